//! Validation of an identified model on held-out states: predicted against measured
//! points, and the tool pose against the best-fit measured pose.

use nalgebra::SVector;
use serde::Serialize;

use super::*;

/// How well a model predicts measured states.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PointErrors {
    /// Largest distance between a predicted and a measured point (mm).
    pub max: f64,
    /// RMS distance (mm).
    pub rms: f64,
    /// With enough fixture points for a pose ([`Identifiable::pose_points`]): the tool
    /// pose predicted against the pose measured ([`Identifiable::measured_pose`]) (position and orientation, max and RMS).
    pub pose: Option<simulate::PoseErrors>,
    /// States whose readings the model cannot reach (forward kinematics failed).
    pub failed: usize,
}

/// Validation on states not used for identification: forward kinematics of the model
/// `m` at `zero + dL` for each state, the fixture's points predicted and compared with
/// the measured ones, and with three or more points the tool pose against the measured
/// pose (the measurement noise is part of the result).
pub fn point_errors<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
    zero: &SVector<f64, A>,
    meas: &Measurements,
) -> PointErrors {
    let mut max: f64 = 0.0;
    let mut sum = 0.0;
    let mut count = 0usize;
    let mut failed = 0;
    let mut start = m.info().home();
    let measured = if meas.fixture.len() >= m.pose_points() {
        measured_poses(m, meas).ok()
    } else {
        None
    };
    let mut stats = simulate::PoseStats::default();
    for (i, st) in meas.states.iter().enumerate() {
        let q =
            SVector::<f64, A>::from_fn(|j, _| zero[j] + st.readings.get(j).copied().unwrap_or(0.0));
        match m.forward(&q, &start) {
            Ok(f) => {
                start = f.pose;
                if let Some(x) = measured.as_ref().map(|v| v[i]) {
                    if let (Ok(a), Ok(b)) = (m.tool_pose(&x), m.tool_pose(&f.pose)) {
                        stats.add(&a, &b, m.info().free_spin());
                    }
                }
                for (s, p) in meas.fixture.iter().zip(&st.points) {
                    let d = (m.platform_point(&f.pose, s).0 - p).norm();
                    max = max.max(d);
                    sum += d * d;
                    count += 1;
                }
            }
            Err(_) => failed += 1,
        }
    }
    PointErrors {
        max,
        rms: (sum / count.max(1) as f64).sqrt(),
        pose: measured.map(|_| stats.finish()),
        failed,
    }
}
