//! Feed profiles: the time law `s(t)` along a segment.
//!
//! Every profile is a sequence of at most seven phases of constant jerk, so position,
//! velocity and acceleration are exact polynomials of time:
//! `s = s0 + v0 t + a0 t^2/2 + j t^3/6`.
//!
//! * constant feed (seed 000): `s = v t`, the velocity jumps at the ends;
//! * trapezoidal ("T-shaped", seed 004): by acceleration limit, or by phase times;
//! * jerk-limited S-curve: seven phases, velocity and acceleration continuous.

use crate::error::{Error, Result};

#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Phase {
    dur: f64,
    a0: f64,
    jerk: f64,
    // state at the phase start
    t0: f64,
    s0: f64,
    v0: f64,
}

/// A time law along a segment of given length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Profile {
    phases: [Phase; 7],
    n: usize,
    /// Total duration (s).
    pub duration: f64,
    /// Length covered (mm or deg).
    pub length: f64,
}

fn invalid(message: String) -> Error {
    Error::InvalidInput {
        what: "feed profile".into(),
        message,
    }
}

impl Profile {
    fn build(length: f64, v_start: f64, parts: &[(f64, f64, f64)]) -> Self {
        let mut phases = [Phase::default(); 7];
        let (mut t, mut s, mut v) = (0.0, 0.0, v_start);
        let mut n = 0;
        for &(dur, a0, jerk) in parts {
            if dur <= 0.0 {
                continue;
            }
            phases[n] = Phase {
                dur,
                a0,
                jerk,
                t0: t,
                s0: s,
                v0: v,
            };
            s += v * dur + a0 * dur * dur / 2.0 + jerk * dur.powi(3) / 6.0;
            v += a0 * dur + jerk * dur * dur / 2.0;
            t += dur;
            n += 1;
        }
        Profile {
            phases,
            n,
            duration: t,
            length,
        }
    }

    /// Standing still for `seconds` (G4 dwell).
    pub fn dwell(seconds: f64) -> Self {
        Self::build(0.0, 0.0, &[(seconds, 0.0, 0.0)])
    }

    /// Constant speed `v` (mm/s) over `length`: the profile of seed 000's study.
    pub fn constant(length: f64, v: f64) -> Result<Self> {
        if !(v > 0.0) {
            return Err(invalid(format!("feed must be > 0, got {v}")));
        }
        Ok(Self::build(length, v, &[(length / v, 0.0, 0.0)]))
    }

    /// Trapezoidal velocity from rest to rest with top speed `v` and acceleration `a`;
    /// triangular when the segment is too short to reach `v`.
    pub fn trapezoid(length: f64, v: f64, a: f64) -> Result<Self> {
        if !(v > 0.0 && a > 0.0) {
            return Err(invalid(format!(
                "speed and acceleration must be > 0, got {v} and {a}"
            )));
        }
        if length <= 0.0 {
            return Ok(Self::build(0.0, 0.0, &[]));
        }
        let (vp, cruise) = if length >= v * v / a {
            (v, (length - v * v / a) / v)
        } else {
            ((length * a).sqrt(), 0.0)
        };
        let ta = vp / a;
        Ok(Self::build(
            length,
            0.0,
            &[(ta, a, 0.0), (cruise, 0.0, 0.0), (ta, -a, 0.0)],
        ))
    }

    /// Trapezoidal velocity given by its phase times (seed 004): accelerate for
    /// `accel_time`, cruise, decelerate for `accel_time`, `duration` in all.
    pub fn trapezoid_timed(length: f64, duration: f64, accel_time: f64) -> Result<Self> {
        if !(duration > 0.0 && accel_time > 0.0 && 2.0 * accel_time <= duration) {
            return Err(invalid(format!(
                "need 0 < 2 x accel time <= duration, got accel time {accel_time} s, duration {duration} s"
            )));
        }
        let v = length / (duration - accel_time);
        let a = v / accel_time;
        Ok(Self::build(
            length,
            0.0,
            &[
                (accel_time, a, 0.0),
                (duration - 2.0 * accel_time, 0.0, 0.0),
                (accel_time, -a, 0.0),
            ],
        ))
    }

    /// Jerk-limited S-curve from rest to rest: speed <= `v`, acceleration <= `a`,
    /// jerk `j`. When the segment is too short the peak speed is lowered (bisection)
    /// so that the profile still starts and ends at rest.
    pub fn scurve(length: f64, v: f64, a: f64, j: f64) -> Result<Self> {
        if !(v > 0.0 && a > 0.0 && j > 0.0) {
            return Err(invalid(format!(
                "speed, acceleration and jerk must be > 0, got {v}, {a}, {j}"
            )));
        }
        if length <= 0.0 {
            return Ok(Self::build(0.0, 0.0, &[]));
        }
        // Acceleration phase to peak speed vp: (ramp time, constant-acceleration time, peak a).
        let accel = |vp: f64| -> (f64, f64, f64) {
            if vp >= a * a / j {
                (a / j, vp / a - a / j, a)
            } else {
                let tj = (vp / j).sqrt();
                (tj, 0.0, j * tj)
            }
        };
        // Distance to reach vp from rest (symmetric ramp): vp * T_acc / 2.
        let dist = |vp: f64| {
            let (tj, tc, _) = accel(vp);
            vp * (2.0 * tj + tc) / 2.0
        };
        let vp = if 2.0 * dist(v) <= length {
            v
        } else {
            let (mut lo, mut hi) = (0.0, v);
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if 2.0 * dist(mid) <= length {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo
        };
        let (tj, tc, ap) = accel(vp);
        let cruise = ((length - 2.0 * dist(vp)) / vp).max(0.0);
        Ok(Self::build(
            length,
            0.0,
            &[
                (tj, 0.0, j),
                (tc, ap, 0.0),
                (tj, ap, -j),
                (cruise, 0.0, 0.0),
                (tj, 0.0, -j),
                (tc, -ap, 0.0),
                (tj, -ap, j),
            ],
        ))
    }

    /// Path parameter, speed and acceleration at time `t` (clamped to the profile).
    #[inline(always)]
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        if self.n == 0 {
            return (self.length, 0.0, 0.0);
        }
        let t = t.clamp(0.0, self.duration);
        let mut k = 0;
        while k + 1 < self.n && t >= self.phases[k + 1].t0 {
            k += 1;
        }
        let p = &self.phases[k];
        let u = t - p.t0;
        let s = p.s0 + p.v0 * u + p.a0 * u * u / 2.0 + p.jerk * u * u * u / 6.0;
        let v = p.v0 + p.a0 * u + p.jerk * u * u / 2.0;
        let a = p.a0 + p.jerk * u;
        (s.min(self.length), v, a)
    }
}
