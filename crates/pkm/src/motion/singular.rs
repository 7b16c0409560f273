//! Passages of a path near a mechanism's singular direction
//! ([`crate::mechanism::ToolAxis::singular_distance`]): on a 5-axis machine, where the
//! tool axis comes close to the rotary axis nearer the part (a trt table's C axis at
//! B = 0), a small change of the tool axis needs a large turn of that axis, and the
//! rotary axes speed up. Each passage within the threshold angle is reported with its
//! G-code lines, its closest approach, and every rotary axis' peak speed in it against
//! its limit and against its peak everywhere else on the path. Rapids are left out:
//! they run every axis at its own rate whatever the direction (and a rapid through
//! the singular direction is a repositioning, not a cut); what a passage costs is the
//! programmed feed moves'.

use serde::Serialize;

use crate::error::{Error, Result};
use crate::mechanism::Actuator;
use crate::units::Quantity;

/// Default threshold of a passage: 2 deg between the tool axis and the singular
/// direction.
pub const DEFAULT_SINGULAR_ANGLE: f64 = 2.0 * std::f64::consts::PI / 180.0;

/// The most passages listed (those beyond are counted).
pub const MAX_PASSAGES: usize = 10_000;

/// One rotary axis' peak speed in a passage.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RotaryPeak {
    /// Axis (actuator) name.
    pub axis: String,
    /// Largest |speed| (deg/s).
    pub peak: f64,
    /// When (s).
    pub t_s: f64,
    /// G-code line there.
    pub line: Option<u64>,
    /// The axis' speed limit (deg/s), when the machine file gives one.
    pub limit: Option<f64>,
}

/// A stretch of the path within the threshold of the singular direction.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SingularPassage {
    /// First sample within the threshold (s).
    pub start_s: f64,
    /// Last sample within it (s).
    pub end_s: f64,
    /// G-code line of the first sample.
    pub start_line: Option<u64>,
    /// G-code line of the last sample.
    pub end_line: Option<u64>,
    /// Smallest angle between the tool axis and the singular direction (deg).
    pub closest_deg: f64,
    /// When (s).
    pub closest_s: f64,
    /// G-code line there.
    pub closest_line: Option<u64>,
    /// Per rotary axis, its peak speed in the passage.
    pub rotary: Vec<RotaryPeak>,
    /// Largest peak over limit among the rotary axes (`> 1`: a limit is exceeded; the
    /// feed override the passage needs is its inverse); `None` without limits.
    pub limit_ratio: Option<f64>,
}

/// The passages of a run near the singular direction.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SingularReport {
    /// Threshold of a passage (deg).
    pub threshold_deg: f64,
    /// Smallest angle to the singular direction on the whole path (deg), its time (s)
    /// and G-code line.
    pub closest: (f64, f64, Option<u64>),
    /// The passages, in order (the first [`MAX_PASSAGES`]).
    pub passages: Vec<SingularPassage>,
    /// Passages beyond those listed.
    pub passages_not_listed: u64,
    /// Per rotary axis, its peak |speed| outside every passage (deg/s): what a passage's
    /// peak is a speed-up against.
    pub peak_outside: Vec<(String, f64)>,
}

impl SingularReport {
    /// The listed passages, largest speed-up first: by limit ratio where the machine
    /// gives limits, else by the largest peak over the peak outside.
    pub fn worst(&self) -> Vec<&SingularPassage> {
        let key = |p: &SingularPassage| match p.limit_ratio {
            Some(r) => r,
            None => p
                .rotary
                .iter()
                .zip(&self.peak_outside)
                .map(|(r, o)| if o.1 > 0.0 { r.peak / o.1 } else { r.peak })
                .fold(0.0, f64::max),
        };
        let mut v: Vec<&SingularPassage> = self.passages.iter().collect();
        v.sort_by(|a, b| key(b).total_cmp(&key(a)));
        v
    }
}

/// Follows a run sample by sample and collects its passages (flat memory: one open
/// passage, at most [`MAX_PASSAGES`] closed ones).
#[derive(Debug, Clone)]
pub struct SingularTracker {
    threshold: f64,
    /// Actuator indices of the rotary axes, names and limits (rad/s).
    rotary: Vec<(usize, String, Option<f64>)>,
    open: Option<SingularPassage>,
    passages: Vec<SingularPassage>,
    dropped: u64,
    closest: Option<(f64, f64, Option<u64>)>,
    outside: Vec<f64>,
}

impl SingularTracker {
    /// A tracker for a mechanism with `actuators` (its angle actuators are the rotary
    /// axes), passages within `threshold` rad (0 to pi/2) of the singular direction.
    pub fn new(actuators: &[Actuator], threshold: f64) -> Result<Self> {
        if !(threshold > 0.0 && threshold <= std::f64::consts::FRAC_PI_2) {
            return Err(Error::InvalidInput {
                what: "singular angle".into(),
                message: format!(
                    "expected an angle above 0 and up to 90 deg, got {} deg",
                    threshold.to_degrees()
                ),
            });
        }
        let rotary: Vec<(usize, String, Option<f64>)> = actuators
            .iter()
            .enumerate()
            .filter(|(_, a)| a.quantity == Quantity::Angle)
            .map(|(i, a)| (i, a.name.clone(), a.max_velocity))
            .collect();
        Ok(SingularTracker {
            threshold,
            outside: vec![0.0; rotary.len()],
            rotary,
            open: None,
            passages: Vec::new(),
            dropped: 0,
            closest: None,
        })
    }

    /// One sample: time `t`, G-code line, the angle to the singular direction (rad) and
    /// the actuator velocities (internal units).
    pub fn add(&mut self, t: f64, line: Option<u64>, distance: f64, qd: &[f64]) {
        let deg = distance.to_degrees();
        if self.closest.is_none_or(|c| deg < c.0) {
            self.closest = Some((deg, t, line));
        }
        if distance >= self.threshold {
            for (k, (i, _, _)) in self.rotary.iter().enumerate() {
                self.outside[k] = self.outside[k].max(qd[*i].abs().to_degrees());
            }
            self.close();
            return;
        }
        let p = self.open.get_or_insert_with(|| SingularPassage {
            start_s: t,
            end_s: t,
            start_line: line,
            end_line: line,
            closest_deg: deg,
            closest_s: t,
            closest_line: line,
            rotary: self
                .rotary
                .iter()
                .map(|(_, name, limit)| RotaryPeak {
                    axis: name.clone(),
                    peak: 0.0,
                    t_s: t,
                    line,
                    limit: limit.map(f64::to_degrees),
                })
                .collect(),
            limit_ratio: None,
        });
        p.end_s = t;
        p.end_line = line;
        if deg < p.closest_deg {
            p.closest_deg = deg;
            p.closest_s = t;
            p.closest_line = line;
        }
        for (r, (i, _, _)) in p.rotary.iter_mut().zip(&self.rotary) {
            let v = qd[*i].abs().to_degrees();
            if v > r.peak {
                r.peak = v;
                r.t_s = t;
                r.line = line;
            }
        }
    }

    fn close(&mut self) {
        let Some(mut p) = self.open.take() else {
            return;
        };
        p.limit_ratio = p
            .rotary
            .iter()
            .filter_map(|r| r.limit.map(|l| r.peak / l))
            .reduce(f64::max);
        if self.passages.len() < MAX_PASSAGES {
            self.passages.push(p);
        } else {
            self.dropped += 1;
        }
    }

    /// The report; `None` when no sample was tracked (the mechanism has no singular
    /// direction).
    pub fn finish(mut self) -> Option<SingularReport> {
        self.close();
        let closest = self.closest?;
        Some(SingularReport {
            threshold_deg: self.threshold.to_degrees(),
            closest,
            passages: self.passages,
            passages_not_listed: self.dropped,
            peak_outside: self
                .rotary
                .into_iter()
                .map(|(_, n, _)| n)
                .zip(self.outside)
                .collect(),
        })
    }
}
