//! From G-code moves to mechanism moves: geometry in the mechanism's coordinates and a
//! feed profile per move.

use serde::Serialize;

use super::gcode::{plane_axes, GMove, Motion};
use super::path::Segment;
use super::profile::Profile;
use super::run::{from_spatial, missing_letters, quantities, Move};
use crate::error::{Error, Result};
use crate::mechanism::{Mechanism, PoseSpace};

/// Shape of the velocity along each move.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ProfileKind {
    /// Constant feed, velocity jumps at the ends (seed 000).
    Constant,
    /// Trapezoidal velocity, rest to rest, acceleration-limited (seed 004).
    Trapezoid,
    /// Jerk-limited S-curve, rest to rest.
    Scurve,
}

/// How moves are timed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FeedOptions {
    /// Velocity shape.
    pub profile: ProfileKind,
    /// Path acceleration for trapezoid and S-curve (mm/s^2).
    pub acceleration: f64,
    /// Path jerk for the S-curve (mm/s^3).
    pub jerk: f64,
    /// G0 rate (mm/s).
    pub rapid: f64,
    /// Replaces every programmed F (mm/s) when given.
    pub feed: Option<f64>,
    /// The run's work limit: at most this many samples
    /// ([`crate::motion::run::DEFAULT_MAX_SAMPLES`] by default). A move that would
    /// cross it is refused before any of its samples is computed.
    pub max_samples: u64,
    /// Threshold (rad) of a passage near the mechanism's singular direction, reported
    /// with the rotary axes' speeds in it ([`crate::motion::singular`]).
    pub singular_angle: f64,
}

impl Default for FeedOptions {
    fn default() -> Self {
        FeedOptions {
            profile: ProfileKind::Constant,
            acceleration: 1000.0,
            jerk: 20_000.0,
            rapid: 10_000.0 / 60.0,
            feed: None,
            max_samples: crate::motion::run::DEFAULT_MAX_SAMPLES,
            singular_angle: crate::motion::singular::DEFAULT_SINGULAR_ANGLE,
        }
    }
}

/// The fastest feed or rapid rate a run takes (mm/s, or deg/s for a machine in its
/// own angles): 1e6 mm/s, 60 km/min, far beyond any machine tool or robot. A faster
/// one is a mistake of units or of typing, and would make velocities and
/// accelerations beyond what the statistics and plots can hold.
pub const MAX_FEED: f64 = 1e6;

/// The shortest duration of a timed move (s): a microsecond, a thousandth of the
/// sampling period of the fastest controller. A shorter one cannot be sampled (its end
/// instant is its start in floating point, or its speed overflows).
pub const MIN_DURATION: f64 = 1e-6;

impl FeedOptions {
    /// Refuses options no run can take, before any sample: a feed or rapid rate not in
    /// (0, [`MAX_FEED`]], an acceleration or jerk that is not positive and finite, a
    /// work limit of no sample.
    ///
    /// # Examples
    ///
    /// ```
    /// use pkm::motion::program::FeedOptions;
    /// assert!(FeedOptions::default().validate().is_ok());
    /// let absurd = FeedOptions { feed: Some(1e300 / 60.0), ..FeedOptions::default() };
    /// let e = absurd.validate().unwrap_err().to_string();
    /// assert!(e.starts_with("feed: expected a feed in (0, 6e7] mm/min"), "{e}");
    /// ```
    pub fn validate(&self) -> Result<()> {
        if let Some(v) = self.feed {
            check_speed("feed", "a feed", v)?;
        }
        check_speed("rapid", "a rapid rate", self.rapid)?;
        for (what, v, unit) in [
            ("acceleration", self.acceleration, "mm/s^2"),
            ("jerk", self.jerk, "mm/s^3"),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(Error::InvalidInput {
                    what: what.into(),
                    message: format!("expected a positive finite {what} ({unit}), got {v}"),
                });
            }
        }
        Ok(())
    }
}

/// Refuses a speed `v` (mm/s) of option `what` outside (0, [`MAX_FEED`]]; the message
/// gives it in mm/min too, the unit of G-code and of `pkm motion --feed`.
pub fn check_speed(what: &str, kind: &str, v: f64) -> Result<()> {
    if v > 0.0 && v <= MAX_FEED {
        return Ok(());
    }
    Err(Error::InvalidInput {
        what: what.into(),
        message: format!(
            "expected {kind} in (0, {}] mm/min ({} mm/s), got {} mm/min ({} mm/s)",
            short(MAX_FEED * 60.0),
            short(MAX_FEED),
            short(v * 60.0),
            short(v)
        ),
    })
}

/// Refuses the duration `d` (s) of a timed move of `length` that is not finite, shorter
/// than [`MIN_DURATION`] or so short that the move would be faster than [`MAX_FEED`].
pub fn check_duration(length: f64, d: f64) -> Result<()> {
    let bad = |message: String| Error::InvalidInput {
        what: "--duration".into(),
        message,
    };
    if !(d.is_finite() && d >= MIN_DURATION) {
        return Err(bad(format!(
            "expected a finite duration of at least {} s, got {} s",
            short(MIN_DURATION),
            short(d)
        )));
    }
    if length / d > MAX_FEED {
        return Err(bad(format!(
            "{} s for a move of {} makes {} mm/s, beyond the fastest accepted ({} mm/s): \
             expected at least {} s",
            short(d),
            short(length),
            short(length / d),
            short(MAX_FEED),
            short(length / MAX_FEED)
        )));
    }
    Ok(())
}

/// `v` to five significant digits, trailing zeros dropped: plain from 1e-3 below 1e6
/// (`0`, `1.5`, `6000`), in scientific notation beyond (`6e7`, `1.6667e298`).
fn short(v: f64) -> String {
    let trim = |s: &str| -> String {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s.to_string()
        }
    };
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if (-3..6).contains(&mag) {
        let decimals = (4 - mag).max(0) as usize;
        return trim(&format!("{v:.decimals$}"));
    }
    let s = format!("{v:.4e}");
    match s.split_once('e') {
        Some((m, e)) => format!("{}e{e}", trim(m)),
        None => s,
    }
}

/// A time law of `kind` along `length` at speed `v`.
pub fn profile(kind: ProfileKind, length: f64, v: f64, o: &FeedOptions) -> Result<Profile> {
    match kind {
        ProfileKind::Constant => Profile::constant(length, v),
        ProfileKind::Trapezoid => Profile::trapezoid(length, v, o.acceleration),
        ProfileKind::Scurve => Profile::scurve(length, v, o.acceleration, o.jerk),
    }
}

/// The mechanism move for one G-code move.
pub fn to_move<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    g: &GMove,
    o: &FeedOptions,
) -> Result<Move<P>> {
    let start = from_spatial(m, &g.start)?;
    let end = from_spatial(m, &g.end)?;
    check_axes(m, g)?;
    let q = quantities(m);
    let segment = match g.motion {
        Motion::Line { .. } | Motion::Dwell { .. } => Segment::line(start, end, &q, true),
        Motion::Arc {
            centre,
            plane,
            sweep,
        } => {
            let (e1, e2) = plane_axes(plane);
            Segment::arc(start, end, centre, e1, e2, sweep).map_err(|e| Error::InvalidInput {
                what: format!("G-code line {}", g.line),
                message: e.to_string(),
            })?
        }
    };
    let profile = move_profile(m, g, &segment, &q, &(end - start), o)?;
    Ok(Move {
        segment,
        profile,
        line: Some(g.line),
        rapid: matches!(g.motion, Motion::Line { rapid: true }),
    })
}

/// Refuses a move of a coordinate the machine does not have: orientation words for a
/// machine whose orientation follows from its position, a rotary letter it lacks.
fn check_axes<M: Mechanism<P, A>, const P: usize, const A: usize>(m: &M, g: &GMove) -> Result<()> {
    let space = m.info().pose_space();
    if space == PoseSpace::Position && (3..6).any(|k| (g.end[k] - g.start[k]).abs() > 1e-12) {
        return Err(Error::InvalidInput {
            what: format!("G-code line {}", g.line),
            message: "A, B, C words: this machine's orientation follows from its position".into(),
        });
    }
    for i in missing_letters(m) {
        if (g.end[i] - g.start[i]).abs() > 1e-12 {
            return Err(Error::InvalidInput {
                what: format!("G-code line {}", g.line),
                message: format!(
                    "{} words: this machine has no {} axis",
                    ["A", "B", "C"][i - 3],
                    ["A", "B", "C"][i - 3]
                ),
            });
        }
    }
    Ok(())
}

/// The time law of move `g` of mechanism `m` along `segment` (coordinates of
/// quantities `q`, moved by `delta` from start to end): a dwell, a rapid
/// ([`rapid_duration`]), inverse time or the feed.
fn move_profile<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    g: &GMove,
    segment: &Segment<P>,
    q: &[crate::units::Quantity; P],
    delta: &nalgebra::SVector<f64, P>,
    o: &FeedOptions,
) -> Result<Profile> {
    Ok(match g.motion {
        Motion::Dwell { seconds } => Profile::dwell(seconds),
        Motion::Line { rapid: true } => {
            let t = rapid_duration(m, q, delta, o.rapid);
            let v = if t > 0.0 && segment.length > 0.0 {
                segment.length / t
            } else {
                o.rapid
            };
            profile(o.profile, segment.length, v, o)?
        }
        // Inverse time (G93): the move takes the programmed time at constant speed.
        _ if o.feed.is_none() && g.duration.is_some() => match g.duration {
            Some(d) if segment.length > 0.0 => {
                let v = segment.length / d;
                check_speed(
                    &format!("G-code line {}", g.line),
                    "an inverse-time speed",
                    v,
                )?;
                Profile::constant(segment.length, v)?
            }
            Some(d) => Profile::dwell(d),
            None => unreachable!("guarded above"),
        },
        _ => {
            let v = o.feed.or(g.feed).ok_or_else(|| Error::InvalidInput {
                what: format!("G-code line {}", g.line),
                message: "no feed".into(),
            })?;
            check_speed(&format!("G-code line {}", g.line), "a feed", v)?;
            profile(o.profile, segment.length, v, o)?
        }
    })
}

/// How long a rapid (G0) moving the pose coordinates of `m` by `delta` (of quantities
/// `q`, internal units) takes as a controller runs it: every coordinate at most at its
/// own rate, all of them arriving together on the straight line (LinuxCNC's planner
/// in world mode: the trajectory's linear rate and each axis's `MAX_VELOCITY`). The
/// rates: the tool tip's distance at `rapid` (mm/s; the machine file's `[motion]
/// rapid`); a coordinate that is one of the machine's axes (the same name and
/// quantity as an actuator with a `max_velocity`: the slides and rotary axes of a
/// 5-axis machine tool) at that axis's rate; any other rotary coordinate at `rapid`
/// read as deg/s. The move takes as long as its slowest part.
///
/// Actuators that are not pose coordinates (a hexapod's struts) do not slow a rapid:
/// a controller in world mode does not know their limits, and a run reports where a
/// rapid exceeds them.
pub fn rapid_duration<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    q: &[crate::units::Quantity; P],
    delta: &nalgebra::SVector<f64, P>,
    rapid: f64,
) -> f64 {
    use crate::units::Quantity;
    let tip = (0..P.min(3))
        .filter(|&k| q[k] == Quantity::Length)
        .map(|k| delta[k] * delta[k])
        .sum::<f64>()
        .sqrt();
    let info = m.info();
    let mut t = tip / rapid;
    for (k, c) in info.coordinates().iter().enumerate().take(P) {
        let change = q[k].to_user(delta[k]).abs();
        if change == 0.0 {
            continue;
        }
        let own = info
            .actuators()
            .iter()
            .find(|a| a.name == c.name && a.quantity == c.quantity)
            .and_then(|a| a.max_velocity)
            .map(|v| c.quantity.to_user(v));
        let rate = match (own, c.quantity) {
            (Some(r), _) => r,
            (None, Quantity::Angle) => rapid,
            (None, Quantity::Length) => continue,
        };
        t = t.max(change / rate);
    }
    t
}

/// A note on move `g` of mechanism `m` turning an orientation angle by half a turn or
/// more: on a machine whose A, B, C are the tool's orientation (a robot's, a
/// hexapod's: [`PoseSpace::Spatial`]) an angle and that angle plus a whole turn name
/// the same orientation, so `A-180` to `A180` is no change of orientation, yet the
/// move interpolates A, B, C linearly, as LinuxCNC does, and turns the tool through a
/// whole turn (a robot controller interpolating orientations would take the short
/// way). The note names the angle, its turn and the nearer angle that names the same
/// end orientation. `None` for other machines (the rotary axes of a machine tool turn
/// as far as they are told) and for moves of less than half a turn.
///
/// ```
/// use pkm::motion::gcode::Interpreter;
/// use pkm::motion::program::wrap_note;
///
/// let m = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))?;
/// let pkm::machine::Model::Hexapod(h) = &m.model else { unreachable!() };
/// let mut g = Interpreter::new([0.0, 0.0, 508.0, -std::f64::consts::PI, 0.0, 0.0]);
/// let mv = g.line("G1 A180 F100", 3)?.unwrap();
/// let note = wrap_note(h.as_ref(), &mv).unwrap();
/// assert!(note.starts_with("A turns 360.000 deg"), "{note}");
/// # Ok::<(), pkm::Error>(())
/// ```
pub fn wrap_note<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    g: &GMove,
) -> Option<String> {
    if m.info().pose_space() != PoseSpace::Spatial || matches!(g.motion, Motion::Dwell { .. }) {
        return None;
    }
    // Half a turn, less a rounding margin (1e-9 deg).
    let half = std::f64::consts::PI - 1e-9f64.to_radians();
    let k = (3..6).find(|&k| (g.end[k] - g.start[k]).abs() >= half)?;
    let (start, end) = (g.start[k].to_degrees(), g.end[k].to_degrees());
    let nearer = end - 360.0 * ((end - start) / 360.0).round();
    let letter = ["A", "B", "C"][k - 3];
    Some(format!(
        "{letter} turns {turn:.3} deg, from {start:.3} to {end:.3} deg: {letter}{nearer:.3} \
         names the same orientation {off:.3} deg from the start; pkm moves A, B, C \
         linearly, as LinuxCNC does, so the tool turns all the way (write the nearer \
         angle for the short way)",
        turn = (end - start).abs(),
        off = (nearer - start).abs(),
    ))
}
