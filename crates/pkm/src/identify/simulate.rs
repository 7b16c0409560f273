//! Simulated identification experiments: a "true" machine (nominal + random
//! deviations), measured states with noise on the points and on the readings, written
//! as a real campaign would be; and the validation of a model against the truth.

use nalgebra::{SVector, Vector3};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution as _, Normal};
use serde::Serialize;

mod poses;

use poses::RandomPoses;

use super::{Identifiable, Measurements, State};
use crate::error::Result;
use crate::units::Quantity;

/// How the states are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Design {
    /// Poses drawn uniformly around home (within every limit of the true machine).
    Random,
    /// Seed 001's design: the zero state, then one more actuator changed per state
    /// (cumulative), by `step`; beyond `A + 1` states the cycle repeats with the sign
    /// flipped.
    OneActuator,
}

/// Settings of [`simulate`].
#[derive(Debug, Clone, PartialEq)]
pub struct Experiment {
    /// Size of the deviations: every geometric parameter and zero reading of the true
    /// machine is nominal + uniform in `[-deviation, deviation]` (mm).
    pub deviation: f64,
    /// Standard deviation of the measured points' coordinates (mm).
    pub point_noise: f64,
    /// Standard deviation of the readings (mm or rad).
    pub length_noise: f64,
    /// Number of states.
    pub states: usize,
    /// State design.
    pub design: Design,
    /// Half-width of the random poses' translations around home (mm).
    pub translation: f64,
    /// Half-width of the random poses' angles around home (rad).
    pub rotation: f64,
    /// Largest condition number of a random state ([`crate::Mechanism::condition`]), as
    /// a multiple of the home pose's: states nearer a singularity, where the readings'
    /// noise is amplified in the pose and a model's small error can put the state
    /// beyond its reach, are drawn again ([`CONDITION_RATIO`] by default; infinite:
    /// none refused).
    pub condition_ratio: f64,
    /// Actuator change per state of the one-actuator design (mm or rad).
    pub step: f64,
    /// Fixture points (platform frame, mm).
    pub fixture: Vec<Vector3<f64>>,
    /// Random seed.
    pub seed: u64,
}

impl Default for Experiment {
    /// `pkm simulate-measurements`' defaults: deviations of +-1 mm, point noise 5 um,
    /// reading noise 1 um, 50 random states within +-100 mm and +-10 deg of home and
    /// within 4 times the home pose's condition number, 40 mm per state of the
    /// one-actuator design, a triangular fixture of circumradius 200 mm, seed 1.
    fn default() -> Self {
        Experiment {
            deviation: 1.0,
            point_noise: 0.005,
            length_noise: 0.001,
            states: 50,
            design: Design::Random,
            translation: 100.0,
            rotation: 10f64.to_radians(),
            condition_ratio: CONDITION_RATIO,
            step: 40.0,
            fixture: triangle(DEFAULT_FIXTURE_SIZE, 0.0),
            seed: 1,
        }
    }
}

impl Experiment {
    /// The experiment at another size: the deviations, the translation span and the
    /// one-actuator step times `scale`, the rotation span times `rotation_scale`, the
    /// fixture `fixture` (the caller's, made `scale` times larger for its machine);
    /// the noise (the instrument's) and the rest unchanged ([`sized`]'s factors).
    pub fn scaled(&self, scale: f64, rotation_scale: f64, fixture: Vec<Vector3<f64>>) -> Self {
        Experiment {
            deviation: self.deviation * scale,
            translation: self.translation * scale,
            rotation: self.rotation * rotation_scale,
            step: self.step * scale,
            fixture,
            ..self.clone()
        }
    }
}

/// The fixture size of [`Experiment::default`] (mm): its triangle's circumradius.
pub const DEFAULT_FIXTURE_SIZE: f64 = 200.0;

/// [`Experiment::condition_ratio`] by default. The random states of every example stay
/// within 3 times their home's condition number (the pentapod's largest of 4000 draws:
/// 2.9, the hexapods' 1.3); a translational tripod whose campaign reaches the plane of
/// its base joints, where the three spheres of its forward kinematics meet at a
/// grazing angle, draws states of up to 1000 times (a tenth beyond 13 times): the
/// held-out errors after identification were 7.6-86 um RMS over 20 seeds with them,
/// 5.4-11 um without (`tests/fixtures/micro-tripod.toml` at 1/8 of the default spans;
/// docs/identification.md).
pub const CONDITION_RATIO: f64 = 4.0;

/// A simulated campaign and the truth behind it.
#[derive(Debug, Clone)]
pub struct Simulated<M, const P: usize, const A: usize> {
    /// The true machine.
    pub truth: M,
    /// Its true zero readings.
    pub true_zero: SVector<f64, A>,
    /// The measurements.
    pub measurements: Measurements,
    /// The true poses of the states.
    pub poses: Vec<SVector<f64, P>>,
}

/// Seed 001's fixture: an equilateral triangle of circumradius `r` in the platform's
/// XY plane at height `z`, vertices at 90, 210 and 330 deg.
pub fn triangle(r: f64, z: f64) -> Vec<Vector3<f64>> {
    [90f64, 210.0, 330.0]
        .iter()
        .map(|a| {
            let (s, c) = a.to_radians().sin_cos();
            // Exact zeros where the trigonometry leaves rounding dust.
            let snap = |v: f64| if v.abs() < 1e-9 * r.abs() { 0.0 } else { v };
            Vector3::new(snap(r * c), snap(r * s), z)
        })
        .collect()
}

/// Simulates a campaign on a true machine drawn around `nominal` (zero readings
/// `zero`).
pub fn simulate<M: Identifiable<P, A>, const P: usize, const A: usize>(
    nominal: &M,
    zero: &SVector<f64, A>,
    e: &Experiment,
) -> Result<Simulated<M, P, A>> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(e.seed);
    let dev = e.deviation.abs();
    let mut draw = |v: f64| {
        if dev > 0.0 {
            v + rng.random_range(-dev..=dev)
        } else {
            v
        }
    };
    let g: Vec<f64> = nominal.geometry().iter().map(|v| draw(*v)).collect();
    let true_zero = SVector::<f64, A>::from_fn(|j, _| draw(zero[j]));
    let truth = nominal.with_geometry(&g)?;
    simulate_on(truth, true_zero, e)
}

/// Simulates a campaign on a given true machine (zero readings `true_zero`).
pub fn simulate_on<M: Identifiable<P, A>, const P: usize, const A: usize>(
    truth: M,
    true_zero: SVector<f64, A>,
    e: &Experiment,
) -> Result<Simulated<M, P, A>> {
    truth.check_fixture(&e.fixture)?;
    let mut rng = rand::rngs::StdRng::seed_from_u64(e.seed ^ 0x5EED_0001);
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    let poses = match e.design {
        Design::Random => poses::random(&truth, e, &mut rng)?,
        Design::OneActuator => poses::one_actuator(&truth, &true_zero, e)?,
    };
    let mut states = Vec::with_capacity(poses.len());
    for x in &poses {
        let q = truth.inverse(x)?;
        let readings = (0..A)
            .map(|j| q[j] - true_zero[j] + e.length_noise * unit.sample(&mut rng))
            .collect();
        let points = e
            .fixture
            .iter()
            .map(|s| {
                truth.platform_point(x, s).0
                    + Vector3::from_fn(|_, _| e.point_noise * unit.sample(&mut rng))
            })
            .collect();
        states.push(State { readings, points });
    }
    Ok(Simulated {
        truth,
        true_zero,
        measurements: Measurements {
            fixture: e.fixture.clone(),
            states,
        },
        poses,
    })
}

/// Share of [`SIZING_DRAWS`] random poses within `translation` (mm) and `rotation`
/// (rad) of home that `m` reaches within every limit and within `condition_ratio`
/// times the home pose's condition number (a fixed seed: the same answer for the same
/// machine).
pub fn reachable_share<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
    translation: f64,
    rotation: f64,
    condition_ratio: f64,
) -> f64 {
    let mut rng = rand::rngs::StdRng::seed_from_u64(0x512E);
    let mut draw = RandomPoses::new(m, translation, rotation, condition_ratio);
    let hits = (0..SIZING_DRAWS)
        .filter(|_| draw.next(m, &mut rng).is_some())
        .count();
    hits as f64 / SIZING_DRAWS as f64
}

/// Draws per [`reachable_share`]: the share's standard error is about 0.013 at
/// [`SIZING_SHARE`] (0.025 with 256 draws, too coarse: a micro tripod whose share at
/// 1/8 of the default spans is 0.155 of 20 000 draws was found 0.21 in the first 256
/// and given that campaign).
pub const SIZING_DRAWS: usize = 1024;

/// Smallest share of random poses within the limits [`sized`] accepts.
pub const SIZING_SHARE: f64 = 0.2;

/// Largest translation span [`sized`] grows to, as a fraction of the mean length of
/// the linear actuators at home: [`Experiment::default`]'s +-100 mm is an eighth of
/// the examples' struts (0.75 m at home), a micro-hexapod's fitted campaign a fifth of
/// its struts; spans of more than a fifth of the struts are not sought.
pub const SIZING_FRACTION: f64 = 0.2;

/// Mean length (mm) of the linear actuators at their zero readings
/// ([`Identifiable::zero_readings`]: at home unless the file gives calibrated ones; 0
/// where there are none).
fn home_stroke_length<M: Identifiable<P, A>, const P: usize, const A: usize>(m: &M) -> f64 {
    let Ok(q) = m.zero_readings() else {
        return 0.0;
    };
    let (sum, n) = (0..A)
        .filter(|&j| m.info().actuators()[j].quantity == Quantity::Length)
        .fold((0.0, 0), |(s, n), j| (s + q[j].abs(), n + 1));
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// How [`sized`] fitted an experiment.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sizing {
    /// Factor on the translation span, the fixture, the one-actuator step and the
    /// deviations (a power of 2; 1 where the experiment fits as it is).
    pub scale: f64,
    /// Factor on the rotation span (a power of 1/2).
    pub rotation_scale: f64,
    /// Share of random poses within the limits at the chosen spans.
    pub share: f64,
    /// Mean length of the linear actuators at home (mm; 0 where there are none).
    pub home_length: f64,
}

/// The spans of `e` fitted to `nominal`. Smaller: where fewer than [`SIZING_SHARE`]
/// of the random poses within them are reachable within
/// [`Experiment::condition_ratio`] (a machine much smaller than
/// [`Experiment::default`]'s +-100 mm, or with tight joint limits), halves the
/// translation or the rotation span, whichever raises the share more, until the share
/// is reached or both have been halved ten times. Larger: where the translation span
/// is below [`SIZING_FRACTION`] of the mean length of the linear actuators at home (a
/// machine with struts of metres, whose struts would hardly turn over +-100 mm), doubles
/// it while twice the span stays within that fraction and the share stays reached.
/// The caller scales the fixture, step and deviations by [`Sizing::scale`] (see
/// [`crate::analysis::identification::sized_experiment`]).
pub fn sized<M: Identifiable<P, A>, const P: usize, const A: usize>(
    nominal: &M,
    e: &Experiment,
) -> Sizing {
    const FLOOR: f64 = 1.0 / 1024.0;
    let share = |s: f64, r: f64| {
        reachable_share(
            nominal,
            s * e.translation,
            r * e.rotation,
            e.condition_ratio,
        )
    };
    let (mut s, mut r) = (1.0, 1.0);
    let mut now = share(s, r);
    let home_length = home_stroke_length(nominal);
    if now >= SIZING_SHARE {
        while 2.0 * s * e.translation <= SIZING_FRACTION * home_length && s < 1024.0 {
            let wider = share(2.0 * s, r);
            if wider < SIZING_SHARE {
                break;
            }
            s *= 2.0;
            now = wider;
        }
        return Sizing {
            scale: s,
            rotation_scale: r,
            share: now,
            home_length,
        };
    }
    while now < SIZING_SHARE && (s > FLOOR || r > FLOOR) {
        let by_t = if s > FLOOR { share(s / 2.0, r) } else { -1.0 };
        let by_r = if r > FLOOR { share(s, r / 2.0) } else { -1.0 };
        if by_t >= by_r {
            s /= 2.0;
            now = by_t;
        } else {
            r /= 2.0;
            now = by_r;
        }
    }
    Sizing {
        scale: s,
        rotation_scale: r,
        share: now,
        home_length,
    }
}

/// Pose errors of a model against the truth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PoseErrors {
    /// Largest tool-point position error (mm).
    pub position_max: f64,
    /// RMS tool-point position error (mm).
    pub position_rms: f64,
    /// Largest orientation error (rad; the angle between tool axes where the spin is
    /// free, [`crate::mechanism::MechanismInfo::free_spin`]).
    pub orientation_max: f64,
    /// RMS orientation error (rad).
    pub orientation_rms: f64,
}

/// Running maxima and sums of squares of pose differences.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct PoseStats {
    pm: f64,
    ps: f64,
    om: f64,
    os: f64,
    n: usize,
}

impl PoseStats {
    /// Adds the difference between two tool poses; `free_spin`: the tool's spin about
    /// its axis is free ([`crate::mechanism::MechanismInfo::free_spin`]), so the orientation
    /// error is the angle between the tool axes.
    pub(crate) fn add(&mut self, a: &crate::pose::Pose, b: &crate::pose::Pose, free_spin: bool) {
        let dp = (a.translation.vector - b.translation.vector).norm();
        let dw = if free_spin {
            let z = nalgebra::Vector3::z();
            (a.rotation * z).angle(&(b.rotation * z))
        } else {
            a.rotation.angle_to(&b.rotation)
        };
        self.pm = self.pm.max(dp);
        self.om = self.om.max(dw);
        self.ps += dp * dp;
        self.os += dw * dw;
        self.n += 1;
    }

    /// Maxima and RMS values.
    pub(crate) fn finish(&self) -> PoseErrors {
        let n = self.n.max(1) as f64;
        PoseErrors {
            position_max: self.pm,
            position_rms: (self.ps / n).sqrt(),
            orientation_max: self.om,
            orientation_rms: (self.os / n).sqrt(),
        }
    }
}

/// How far a model (`m`, zero readings `zero`) puts the tool from the true poses
/// `poses` when given the readings `readings` the control would have: forward
/// kinematics of the model at `zero + dL`, against the truth; and how many states'
/// readings the model cannot reach (its forward kinematics finds no pose: a state at
/// the edge of the true machine's workspace can lie beyond the model's), which are
/// left out of the statistics. Fails only when no state is reached.
pub fn pose_errors<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
    zero: &SVector<f64, A>,
    readings: &[Vec<f64>],
    poses: &[SVector<f64, P>],
) -> Result<(PoseErrors, usize)> {
    let mut stats = PoseStats::default();
    let mut failed = 0;
    let mut first = None;
    for (r, x) in readings.iter().zip(poses) {
        let q = SVector::<f64, A>::from_fn(|j, _| zero[j] + r[j]);
        match m.forward(&q, x) {
            Ok(f) => stats.add(
                &m.tool_pose(x)?,
                &m.tool_pose(&f.pose)?,
                m.info().free_spin(),
            ),
            Err(e) => {
                failed += 1;
                first.get_or_insert(e);
            }
        }
    }
    match first {
        Some(e) if stats.n == 0 => Err(e),
        _ => Ok((stats.finish(), failed)),
    }
}
