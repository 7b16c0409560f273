//! What `pkm motion` prints: the run's statistics per axis, the serial/PKM ratios,
//! the feed override, the singular passages, the notes, and the first limit violation.

use pkm::analysis::motion::MotionRun;
use pkm::motion::MotionSummary;
use pkm::DynMechanism;

use super::ProfileArg;
use crate::out::{outln, Printed};
use crate::EXIT_UNREACHABLE;

/// Notes printed; the others are in summary.json.
const NOTES_SHOWN: usize = 20;

/// The run as text (without the closing `wrote DIR`).
pub(super) fn print_text(
    m: &dyn DynMechanism,
    outcome: &MotionRun,
    profile: ProfileArg,
) -> Printed {
    let s = &outcome.summary;
    outln!(
        "{} ({}): {} samples over {:.4} s",
        m.name(),
        m.kind(),
        s.samples,
        s.duration_s
    )?;
    print_axes(s)?;
    print_ratios(s, profile)?;
    match s.feed_override_max {
        Some(k) => outln!(
            "largest feed override within the actuator rate limits: {:.4}",
            k
        )?,
        None if s.rapid_override_max.is_some() => outln!("largest feed override: no feed move")?,
        None => outln!("largest feed override: no rate limits in the machine file")?,
    }
    if let Some(k) = s.rapid_override_max {
        outln!("largest rapid override within the actuator rate limits: {k:.4}")?;
    }
    if let Some(sg) = &s.singular {
        print_singular(sg)?;
    }
    if let Some(acc) = &outcome.accuracy {
        super::super::motion_accuracy::print(acc)?;
    }
    print_notes(outcome)?;
    Ok(())
}

/// The table of travel, velocity and acceleration per actuator and serial axis.
fn print_axes(s: &MotionSummary) -> Printed {
    // The first column as wide as the longest axis label (a machine's own
    // actuator names, `actuator north-west`, keep the columns aligned).
    let lists = [("actuator", &s.actuators), ("serial", &s.serial)];
    let w = lists
        .iter()
        .flat_map(|(kind, list)| {
            list.iter()
                .map(move |(n, _)| kind.len() + 1 + n.chars().count())
        })
        .fold(10, usize::max);
    outln!(
        "{:<w$} {:>12} {:>14} {:>14} {:>16} {:>16}",
        "axis",
        "travel",
        "peak |v|",
        "mean |v|",
        "peak |a|",
        "mean |a|"
    )?;
    for (kind, list) in lists {
        for (n, st) in list.iter() {
            outln!(
                "{:<w$} {:>12.4} {:>14.4} {:>14.4} {:>16.4} {:>16.4}",
                format!("{kind} {n}"),
                st.travel,
                st.peak_velocity,
                st.mean_abs_velocity,
                st.peak_acceleration,
                st.mean_abs_acceleration
            )?;
        }
    }
    Ok(())
}

/// Seed 000's serial/PKM ratios, and why one is not available.
fn print_ratios(s: &MotionSummary, profile: ProfileArg) -> Printed {
    let ratio = |r: Option<f64>| r.map_or("n/a".to_string(), |r| format!("{r:.3}"));
    let Some(r) = &s.ratios else {
        outln!(
            "ratios serial/PKM: none (no serial axis moved, or an actuator or axis turns: \
             mm over deg means nothing)"
        )?;
        return Ok(());
    };
    outln!(
        "ratios serial/PKM (seed 000's): travel {:.3} (mean over mean), peak \
         velocity {}, peak acceleration {} (largest over largest); of mean \
         peaks: velocity {}, acceleration {}",
        r.travel,
        ratio(r.velocity),
        ratio(r.acceleration),
        ratio(r.velocity_of_mean_peaks),
        ratio(r.acceleration_of_mean_peaks)
    )?;
    if r.velocity.is_none() {
        outln!(
            "  (n/a: no sample caught the machine moving: every move is shorter \
             than the sampling period, so its samples are its ends, at rest; \
             a higher --rate samples it)"
        )?;
    } else if r.acceleration.is_none() {
        outln!(
            "  (acceleration n/a: no sample caught a serial axis accelerating{})",
            match profile {
                ProfileArg::Constant =>
                    ": under `--profile constant` the serial axes keep their \
                     speed along each straight move, and the speed steps at the \
                     corners are not samples; `--profile trapezoid` or `scurve` \
                     gives the ramps",
                _ => "",
            }
        )?;
    }
    Ok(())
}

/// The program's first notes, and how many more summary.json lists.
fn print_notes(outcome: &MotionRun) -> Printed {
    for (l, t) in outcome.notes.iter().take(NOTES_SHOWN) {
        outln!("note: line {l}: {t}")?;
    }
    let more = outcome.notes.len().saturating_sub(NOTES_SHOWN) as u64 + outcome.notes_dropped;
    if more > 0 {
        outln!("note: {more} more in summary.json")?;
    }
    Ok(())
}

/// 0, or [`EXIT_UNREACHABLE`] with the first limit violation on stderr.
pub(super) fn exit_code(s: &MotionSummary) -> u8 {
    if s.violations.is_empty() {
        return 0;
    }
    // The first stretch: where it starts, and the worst value in it (not the
    // value at its start).
    let v = &s.violations[0];
    let n = s.violations.len() as u64 + s.violations_not_listed;
    eprintln!(
        "error: {n} limit violation{} along the path; first: {} beyond {:.3} {} from t = {:.4} s{}, worst {:.3} {}",
        if n == 1 { "" } else { "s" },
        v.limit,
        v.bound,
        v.unit,
        v.start_s,
        v.line.map(|l| format!(" (G-code line {l})")).unwrap_or_default(),
        v.worst,
        v.unit,
    );
    EXIT_UNREACHABLE
}

/// The closest approach to the singular direction and the worst passages near it.
fn print_singular(sg: &pkm::motion::singular::SingularReport) -> Printed {
    let line = |l: Option<u64>| l.map(|l| format!("line {l}")).unwrap_or("-".into());
    let (deg, t, l) = sg.closest;
    outln!(
        "singular direction (tool axis along the rotary axis nearer the part), feed moves: \
         closest {deg:.4} deg at t = {t:.3} s ({}); {} passage(s) within {:.3} deg{}",
        line(l),
        sg.passages.len() as u64 + sg.passages_not_listed,
        sg.threshold_deg,
        if sg.passages.is_empty() {
            ""
        } else {
            ", largest speed-ups:"
        }
    )?;
    for p in sg.worst().into_iter().take(5) {
        let peaks: Vec<String> = p
            .rotary
            .iter()
            .zip(&sg.peak_outside)
            .map(|(r, o)| {
                format!(
                    "{} {:.2} deg/s ({}{}; {:.2} elsewhere)",
                    r.axis,
                    r.peak,
                    line(r.line),
                    r.limit
                        .map(|lim| format!(", limit {lim:.2}"))
                        .unwrap_or_default(),
                    o.1
                )
            })
            .collect();
        outln!(
            "  {} to {} (t {:.3}-{:.3} s), closest {:.4} deg: {}",
            line(p.start_line),
            line(p.end_line),
            p.start_s,
            p.end_s,
            p.closest_deg,
            peaks.join(", ")
        )?;
    }
    Ok(())
}
