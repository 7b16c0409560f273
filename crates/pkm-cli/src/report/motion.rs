//! The report's motion section: a path through the mechanism (the user's program, the
//! machine file's `[report]` program, or a circle scaled to the machine's reach), at
//! one or several feeds, compared with a serial machine.

use anyhow::Result;
use pkm::analysis::motion::{feed_options, run_motion, study_circle, MotionRun, MotionSource};
use pkm::motion::program::{FeedOptions, ProfileKind};
use pkm::motion::{AxisStats, MotionSummary, Sampling};
use pkm::{DynMechanism, Machine};

use super::html::{esc, Html};
use super::{sig, Context};
use crate::commands::motion::plots;
use crate::poses::Shown;

/// Feed of the circle when no feeds are given (mm/min).
const CIRCLE_FEED: f64 = 1000.0;

/// Fraction of the largest circle within every limit that the study's circle takes.
const CIRCLE_FRACTION: f64 = 0.8;

/// The path the section runs: its program, where it starts, and the sentence saying
/// what it is.
struct StudyPath {
    program: String,
    from: Vec<f64>,
    what: String,
}

/// Runs the report's path at each feed: a table per feed, per-axis statistics and
/// plots of the last.
pub fn section(h: &mut Html, machine: &Machine, ctx: &Context) -> Result<()> {
    let m = machine.mechanism();
    h.h2_id("motion", "Motion along a path");
    let path = study_path(machine, ctx)?;
    let feeds: Vec<Option<f64>> = match (ctx.feeds.is_empty(), ctx.program.is_some()) {
        (false, _) => ctx.feeds.iter().map(|f| Some(*f)).collect(),
        (true, true) => vec![None],
        (true, false) => vec![Some(CIRCLE_FEED)],
    };
    let sampling = match ctx.points {
        Some(n) => Sampling::Points(n),
        None => Sampling::Rate(1000.0),
    };
    h.p(&intro(&path.what, &feeds, sampling));
    let mut rows = Vec::new();
    let mut last = None;
    let mut last_feed = String::new();
    for feed in &feeds {
        let mut frames = super::view3d::Frames::default();
        let out = run_at(machine, &path, *feed, sampling, &mut frames)?;
        last_feed = match feed {
            Some(f) => format!("{f} mm/min"),
            None => "the program's feeds".into(),
        };
        rows.push(feed_row(last_feed.clone(), &out.summary));
        last = Some(out);
        ctx.scene.borrow_mut().frames = frames;
    }
    let unit = actuator_unit(m);
    let (hv, ha) = (
        format!("peak actuator |v| [{unit}/s]"),
        format!("peak actuator |a| [{unit}/s²]"),
    );
    h.table(
        &[
            "feed",
            "duration [s]",
            &hv,
            "peak serial |v| [mm/s]",
            &ha,
            "peak serial |a| [mm/s²]",
            "ratios travel / v / a",
            "limit violations",
        ],
        &rows,
    );
    if let Some(out) = last {
        per_axis(h, m, &out, &last_feed)?;
    }
    Ok(())
}

/// The user's program (from `ctx.from`, else home), else a circle scaled to the
/// machine's reach about the report pose.
fn study_path(machine: &Machine, ctx: &Context) -> Result<StudyPath> {
    let m = machine.mechanism();
    let user = |v: &[f64]| -> String {
        v.iter()
            .zip(m.coordinates())
            .map(|(x, c)| format!("{}{:.3}", c.name, Shown(c.quantity.to_user(*x))))
            .collect::<Vec<_>>()
            .join(" ")
    };
    if let Some(p) = &ctx.program {
        let from = ctx.from.clone().unwrap_or_else(|| m.home());
        let what = format!(
            "The program <code>{}</code> from {}",
            esc(&p.name),
            esc(&user(&from))
        );
        return Ok(StudyPath {
            program: p.text.clone(),
            from,
            what,
        });
    }
    let c = study_circle(machine, &ctx.pose, CIRCLE_FRACTION)?;
    let (r, program, from) = (c.radius, c.program(CIRCLE_FEED), c.start());
    let what = format!(
        "A full circle of radius {r} mm, counter-clockwise in the XY plane about \
         {}{} ({pct:.0} % of the largest circle about that point within every \
         limit, {:.1} mm; <code>pkm report --gcode FILE</code> or the machine \
         file's <code>[report] gcode</code> takes your own path)",
        esc(&user(&c.centre)),
        if c.moved {
            format!(
                " (no circle fits about {}: the centre is the best-conditioned \
                 point of the reach that takes the largest one)",
                ctx.pose_label
            )
        } else {
            String::new()
        },
        c.largest,
        pct = 100.0 * CIRCLE_FRACTION
    );
    Ok(StudyPath {
        program,
        from,
        what,
    })
}

/// The section's first paragraph: the path, its feeds and sampling, what is compared.
fn intro(what: &str, feeds: &[Option<f64>], sampling: Sampling) -> String {
    format!(
        "{what}, at constant feed ({}), sampled {}. Actuator velocity and acceleration come \
         from the Jacobian and its derivative (exact), not from differences of the points. \
         The same path on a serial (Cartesian) machine is the tool tip's X, Y, Z. Ratios are \
         serial over PKM as seed 000 defines them: mean travel over mean travel, largest \
         peak |velocity| over largest, largest peak |acceleration| over largest.",
        feeds
            .iter()
            .map(|f| match f {
                Some(f) => format!("{f} mm/min"),
                None => "the program's F words".into(),
            })
            .collect::<Vec<_>>()
            .join(", "),
        match sampling {
            Sampling::Points(n) => format!("at {n} points per move"),
            Sampling::Rate(r) => format!("at {r} Hz"),
        }
    )
}

/// Units of the actuators (a robot's joints turn: deg; ratios to a Cartesian machine
/// then compare unlike quantities and are not given).
fn actuator_unit(m: &dyn DynMechanism) -> &'static str {
    let angular = |a: &pkm::mechanism::Actuator| a.quantity == pkm::Quantity::Angle;
    if m.actuators().iter().all(angular) {
        "deg"
    } else if m.actuators().iter().any(angular) {
        "mm or deg"
    } else {
        "mm"
    }
}

/// The path run at constant `feed` (mm/min; `None`: the program's), its frames for
/// the 3D view.
fn run_at(
    machine: &Machine,
    path: &StudyPath,
    feed: Option<f64>,
    sampling: Sampling,
    frames: &mut super::view3d::Frames,
) -> Result<MotionRun> {
    let out = run_motion(
        machine,
        MotionSource::Gcode {
            reader: Box::new(std::io::Cursor::new(path.program.clone().into_bytes())),
            from: Some(path.from.clone()),
            setup: Default::default(),
        },
        &FeedOptions {
            profile: ProfileKind::Constant,
            feed: feed.map(|f| f / 60.0),
            ..feed_options(machine)
        },
        sampling,
        frames,
    );
    match out {
        Ok(o) => Ok(o),
        Err(e) => anyhow::bail!("the path cannot be run through the machine: {e}"),
    }
}

/// The row of one feed: duration, peaks, ratios, limit violations.
fn feed_row(feed: String, s: &MotionSummary) -> Vec<String> {
    let peak = |v: &[(String, AxisStats)], f: fn(&AxisStats) -> f64| {
        v.iter().map(|(_, x)| f(x)).fold(0.0, f64::max)
    };
    vec![
        feed,
        sig(s.duration_s),
        sig(peak(&s.actuators, |x| x.peak_velocity)),
        sig(peak(&s.serial, |x| x.peak_velocity)),
        sig(peak(&s.actuators, |x| x.peak_acceleration)),
        sig(peak(&s.serial, |x| x.peak_acceleration)),
        match &s.ratios {
            Some(r) => format!(
                "{:.3} / {} / {}",
                r.travel,
                r.velocity
                    .map_or("n/a (no sample in motion)".to_string(), |v| format!(
                        "{v:.3}"
                    )),
                match (r.velocity, r.acceleration) {
                    (_, Some(a)) => format!("{a:.3}"),
                    (None, None) => "n/a".into(),
                    // The report's run has the constant profile.
                    (Some(_), None) => "n/a (constant profile)".into(),
                }
            ),
            None => "n/a (revolute drives, or no serial axis moved)".into(),
        },
        if s.violations.is_empty() {
            "<span class=\"ok\">none</span>".into()
        } else {
            format!(
                "<span class=\"bad\">{} (first: {} {:.3} {} beyond {:.3})</span>",
                s.violations.len(),
                esc(&s.violations[0].limit),
                s.violations[0].worst,
                s.violations[0].unit,
                s.violations[0].bound
            )
        },
    ]
}

/// The last feed's statistics per axis, its feed override and its plots.
fn per_axis(h: &mut Html, m: &dyn DynMechanism, out: &MotionRun, last_feed: &str) -> Result<()> {
    let s = &out.summary;
    let mut axes = Vec::new();
    let units: Vec<&str> = m.actuators().iter().map(|a| a.quantity.unit()).collect();
    for (kind, list) in [("actuator", &s.actuators), ("serial", &s.serial)] {
        for (k, (n, st)) in list.iter().enumerate() {
            let u = if kind == "actuator" {
                units.get(k).copied().unwrap_or("mm")
            } else {
                "mm"
            };
            axes.push(vec![
                format!("{kind} {}", esc(n)),
                u.to_string(),
                format!("{:.3}", st.travel),
                format!("{:.3}", st.peak_velocity),
                format!("{:.3}", st.mean_abs_velocity),
                format!("{:.3}", st.peak_acceleration),
                format!("{:.3}", st.mean_abs_acceleration),
            ]);
        }
    }
    h.p(&format!("Per axis at {last_feed} (at constant feed, velocities scale with the feed and accelerations with its square; travel does not change):"));
    h.table(
        &[
            "axis",
            "unit",
            "travel",
            "peak |v| [/s]",
            "mean |v|",
            "peak |a| [/s²]",
            "mean |a|",
        ],
        &axes,
    );
    match s.feed_override_max {
        Some(k) => h.p(&format!(
            "Largest feed override within the actuators' velocity and acceleration limits at {last_feed}: <b>{k:.3}</b>."
        )),
        None => h.p("The machine file gives no actuator rate limits, so no feed override is computed."),
    }
    if let Some(k) = s.rapid_override_max {
        h.p(&format!(
            "Largest rapid override within the same limits (the rapids alone: a feed override does not scale them): <b>{k:.3}</b>."
        ));
    }
    let (a, b) = plots(m, out, last_feed)?;
    h.raw(&format!("<div class=\"views\">{a}{b}</div>"));
    Ok(())
}
