//! A randomized round-trip campaign over every example machine: no silent
//! wrong answers from inverse or forward kinematics.
//!
//! ```text
//! cargo run --release -p pkm --example roundtrip_campaign -- [SAMPLES_PER_MACHINE] [FILE...]
//! ```
//!
//! For each machine file (default: every file of `examples/machines/` and
//! `examples/robots/`), `SAMPLES_PER_MACHINE` (default 1 000 000) of each of:
//!
//! - **IK -> FK**: a pose drawn uniformly around home (driven coordinates only: lengths
//!   +-20 % of the machine's characteristic length, angles +-20 deg), its inverse, then
//!   the forward solution from home and from a start 1e-4 of the span away. A forward
//!   solution must reproduce the actuators within 1e-9 (mm or rad); from the nearby
//!   start it must also be the pose drawn (same assembly mode) within 1e-9 mm / rad
//!   (spatial poses compared as rigid motions), except where the pose's condition
//!   number exceeds 1e3: there the actuators do not determine the pose to 1e-9 and
//!   another assembly mode lies close by (counted apart).
//! - **FK -> IK**: actuator values drawn uniformly (serial robots: over their whole
//!   ranges, at most a turn; other machines: +-30 % of each half stroke around home),
//!   the forward solution from home, then its inverse: the inverse must give the drawn
//!   actuators again, or (serial robots) another posture whose forward pose is the same
//!   within 1e-9.
//!
//! Every failure must be a named error (counted by kind); a panic or a returned value
//! that does not reproduce its input is a silent wrong answer and makes the run exit 1.
//! Poses and actuators are drawn with a fixed seed per chunk: a run is repeatable.

use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

use nalgebra::SVector;
use pkm::machine::Analysable;
use pkm::{Machine, Quantity, Visitor};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;

const TOL: f64 = 1e-9;
const CHUNK: usize = 10_000;

#[derive(Debug, Default, Clone)]
struct Tally {
    ik_fk: u64,
    ik_errors: BTreeMap<String, u64>,
    fk_home_ok: u64,
    fk_home_other_assembly: u64,
    fk_home_errors: BTreeMap<String, u64>,
    fk_near_ok: u64,
    fk_near_ill_conditioned: u64,
    worst_condition_off: f64,
    fk_near_errors: BTreeMap<String, u64>,
    fk_ik: u64,
    fk_errors: BTreeMap<String, u64>,
    ik_after_fk_ok: u64,
    ik_after_fk_other_posture: u64,
    ik_after_fk_errors: BTreeMap<String, u64>,
    silent_wrong: u64,
    panics: u64,
    worst_actuator_error: f64,
    worst_pose_error: f64,
    examples: Vec<String>,
    /// Named failures of IK on poses FK produced (not wrong, but reachable).
    failures: Vec<String>,
}

impl Tally {
    fn merge(mut self, o: Tally) -> Tally {
        let add = |a: &mut BTreeMap<String, u64>, b: BTreeMap<String, u64>| {
            for (k, v) in b {
                *a.entry(k).or_default() += v;
            }
        };
        self.ik_fk += o.ik_fk;
        add(&mut self.ik_errors, o.ik_errors);
        self.fk_home_ok += o.fk_home_ok;
        self.fk_home_other_assembly += o.fk_home_other_assembly;
        add(&mut self.fk_home_errors, o.fk_home_errors);
        self.fk_near_ok += o.fk_near_ok;
        self.fk_near_ill_conditioned += o.fk_near_ill_conditioned;
        self.worst_condition_off = self.worst_condition_off.max(o.worst_condition_off);
        add(&mut self.fk_near_errors, o.fk_near_errors);
        self.fk_ik += o.fk_ik;
        add(&mut self.fk_errors, o.fk_errors);
        self.ik_after_fk_ok += o.ik_after_fk_ok;
        self.ik_after_fk_other_posture += o.ik_after_fk_other_posture;
        add(&mut self.ik_after_fk_errors, o.ik_after_fk_errors);
        self.silent_wrong += o.silent_wrong;
        self.panics += o.panics;
        self.worst_actuator_error = self.worst_actuator_error.max(o.worst_actuator_error);
        self.worst_pose_error = self.worst_pose_error.max(o.worst_pose_error);
        self.examples.extend(o.examples);
        self.examples.truncate(5);
        self.failures.extend(o.failures);
        self.failures.truncate(5);
        self
    }

    fn wrong(&mut self, what: String) {
        self.silent_wrong += 1;
        if self.examples.len() < 5 {
            self.examples.push(what);
        }
    }
}

/// The error's kind: its variant name.
fn kind(e: &pkm::Error) -> String {
    let d = format!("{e:?}");
    d.split([' ', '{', '(']).next().unwrap_or("?").to_string()
}

/// Largest difference, angles modulo a whole turn.
fn distance<const N: usize>(a: &SVector<f64, N>, b: &SVector<f64, N>, q: &[Quantity; N]) -> f64 {
    (0..N)
        .map(|i| {
            let d = (a[i] - b[i]).abs();
            if q[i] == Quantity::Angle {
                let d = d.rem_euclid(std::f64::consts::TAU);
                d.min(std::f64::consts::TAU - d)
            } else {
                d
            }
        })
        .fold(0.0, f64::max)
}

struct Campaign {
    samples: usize,
    serial: bool,
}

impl Visitor for Campaign {
    type Output = Tally;

    fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Tally {
        let home = m.info().home();
        let cq: [Quantity; P] = std::array::from_fn(|i| m.info().coordinates()[i].quantity);
        let aq: [Quantity; A] = std::array::from_fn(|i| m.info().actuators()[i].quantity);
        let driven = m.info().driven();
        let lc = m.info().characteristic_length();
        let span: [f64; P] = std::array::from_fn(|i| match cq[i] {
            Quantity::Length => 0.2 * lc,
            _ => 20f64.to_radians(),
        });
        let q_home = m.inverse(&home).expect("home is reachable");
        let ranges: [(f64, f64); A] = std::array::from_fn(|i| {
            let r = m.info().actuators()[i].range;
            if self.serial {
                let (lo, hi) = (
                    r.min.max(-std::f64::consts::PI),
                    r.max.min(std::f64::consts::PI),
                );
                (lo, hi)
            } else {
                let h = 0.3 * 0.5 * (r.max - r.min);
                ((q_home[i] - h).max(r.min), (q_home[i] + h).min(r.max))
            }
        });
        let chunks = self.samples.div_ceil(CHUNK);
        (0..chunks)
            .into_par_iter()
            .map(|c| {
                let mut t = Tally::default();
                let mut rng = StdRng::seed_from_u64(0x9e37_79b9 ^ c as u64);
                let n = CHUNK.min(self.samples - c * CHUNK);
                for _ in 0..n {
                    let r = catch_unwind(AssertUnwindSafe(|| {
                        ik_fk(m, &mut rng, &home, &driven, &span, &cq, &aq, &mut t);
                        fk_ik(m, &mut rng, &home, &ranges, &cq, &aq, &mut t);
                    }));
                    if r.is_err() {
                        t.panics += 1;
                    }
                }
                t
            })
            .reduce(Tally::default, Tally::merge)
    }
}

/// Distance of two poses: for a spatial pose space, of the rigid motions (position in
/// mm, rotation angle in rad: an X..C triple and its twin with B beyond 90 deg are the
/// same pose); else of the coordinates.
fn pose_distance<M: Analysable<P, A>, const P: usize, const A: usize>(
    m: &M,
    a: &SVector<f64, P>,
    b: &SVector<f64, P>,
    cq: &[Quantity; P],
) -> f64 {
    if m.info().pose_space() == pkm::PoseSpace::Spatial {
        if let (Ok(pa), Ok(pb)) = (m.tool_pose(a), m.tool_pose(b)) {
            let dp = (pa.translation.vector - pb.translation.vector).norm();
            let dr = pa.rotation.angle_to(&pb.rotation);
            return dp.max(dr);
        }
    }
    distance(a, b, cq)
}

#[allow(clippy::too_many_arguments)]
fn ik_fk<M: Analysable<P, A>, const P: usize, const A: usize>(
    m: &M,
    rng: &mut StdRng,
    home: &SVector<f64, P>,
    driven: &[usize; A],
    span: &[f64; P],
    cq: &[Quantity; P],
    aq: &[Quantity; A],
    t: &mut Tally,
) {
    let mut x = *home;
    for &d in driven {
        x[d] += rng.random_range(-1.0..1.0) * span[d];
    }
    t.ik_fk += 1;
    let q = match m.inverse(&x) {
        Ok(q) => q,
        Err(e) => {
            *t.ik_errors.entry(kind(&e)).or_default() += 1;
            return;
        }
    };
    // From home: any assembly mode reproducing q is right.
    match m.forward(&q, home) {
        Ok(f) => match m.inverse(&f.pose) {
            Ok(q2) => {
                let e = distance(&q2, &q, aq);
                t.worst_actuator_error = t.worst_actuator_error.max(e);
                if e > TOL {
                    t.wrong(format!(
                        "IK->FK(home): x {x:?} q {q:?} FK {:?} off {e:e}",
                        f.pose
                    ));
                } else if pose_distance(m, &f.pose, &x, cq) > 1e-6 {
                    t.fk_home_other_assembly += 1;
                } else {
                    t.fk_home_ok += 1;
                }
            }
            Err(e) => t.wrong(format!("IK->FK(home): FK pose has no inverse ({e})")),
        },
        Err(e) => *t.fk_home_errors.entry(kind(&e)).or_default() += 1,
    }
    // From a nearby start: the pose drawn.
    let mut start = x;
    for &d in driven {
        start[d] += 1e-4 * span[d] * rng.random_range(-1.0..1.0);
    }
    match m.forward(&q, &start) {
        Ok(f) => {
            let e = pose_distance(m, &f.pose, &x, cq);
            t.worst_pose_error = t.worst_pose_error.max(e);
            let eq = m
                .inverse(&f.pose)
                .map(|q2| distance(&q2, &q, aq))
                .unwrap_or(f64::INFINITY);
            t.worst_actuator_error = t.worst_actuator_error.max(eq);
            if eq > TOL {
                t.wrong(format!(
                    "IK->FK(near): x {x:?} FK {:?} actuators off {eq:e}",
                    f.pose
                ));
            } else if e > TOL {
                // Reproduced actuators, another pose: right only where the actuators do
                // not determine the pose to 1e-9 (near a forward singularity: rounding
                // of 1e-13 times a condition number above 1e3 is already 1e-10, and
                // another assembly mode lies close by).
                let cond = m.condition(&x).unwrap_or(f64::INFINITY);
                if cond > pkm::analysis::kinematics::NEAR_SINGULAR_CONDITION {
                    t.fk_near_ill_conditioned += 1;
                    t.worst_condition_off = t.worst_condition_off.max(cond);
                } else {
                    t.wrong(format!(
                        "IK->FK(near): x {x:?} FK {:?} pose off {e:e} (condition {cond:.3e})",
                        f.pose
                    ));
                }
            } else {
                t.fk_near_ok += 1;
            }
        }
        Err(e) => *t.fk_near_errors.entry(kind(&e)).or_default() += 1,
    }
}

fn fk_ik<M: Analysable<P, A>, const P: usize, const A: usize>(
    m: &M,
    rng: &mut StdRng,
    home: &SVector<f64, P>,
    ranges: &[(f64, f64); A],
    cq: &[Quantity; P],
    aq: &[Quantity; A],
    t: &mut Tally,
) {
    let q = SVector::<f64, A>::from_fn(|i, _| rng.random_range(ranges[i].0..=ranges[i].1));
    t.fk_ik += 1;
    let f = match m.forward(&q, home) {
        Ok(f) => f,
        Err(e) => {
            *t.fk_errors.entry(kind(&e)).or_default() += 1;
            return;
        }
    };
    match m.inverse(&f.pose) {
        Ok(q2) => {
            let e = distance(&q2, &q, aq);
            if e <= TOL {
                t.ik_after_fk_ok += 1;
                return;
            }
            // Another posture (serial robots): its forward pose must be the same.
            match m.forward(&q2, &f.pose) {
                Ok(f2) if pose_distance(m, &f2.pose, &f.pose, cq) <= TOL => {
                    t.ik_after_fk_other_posture += 1
                }
                Ok(f2) => t.wrong(format!(
                    "FK->IK: q {q:?} pose {:?} IK {q2:?} whose pose is {:?}",
                    f.pose, f2.pose
                )),
                Err(e) => t.wrong(format!("FK->IK: IK {q2:?} has no forward pose ({e})")),
            }
        }
        Err(e) => {
            *t.ik_after_fk_errors.entry(kind(&e)).or_default() += 1;
            if t.failures.len() < 5 {
                t.failures.push(format!("FK->IK: q {q:?}: {e}"));
            }
        }
    }
}

fn files(args: &[String]) -> Vec<PathBuf> {
    if !args.is_empty() {
        return args.iter().map(PathBuf::from).collect();
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut out = Vec::new();
    for dir in ["machines", "robots"] {
        let mut v: Vec<PathBuf> = std::fs::read_dir(root.join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| {
                matches!(
                    p.extension().and_then(|e| e.to_str()),
                    Some("toml" | "urdf")
                )
            })
            .collect();
        v.sort();
        out.extend(v);
    }
    out
}

fn show(map: &BTreeMap<String, u64>) -> String {
    if map.is_empty() {
        return "none".into();
    }
    map.iter()
        .map(|(k, v)| format!("{k} {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (samples, rest) = match args.first().map(|a| a.replace('_', "").parse::<usize>()) {
        Some(Ok(n)) => (n, &args[1..]),
        _ => (1_000_000, &args[..]),
    };
    println!(
        "round-trip campaign: {samples} IK->FK and {samples} FK->IK samples per machine, \
         {} threads",
        rayon::current_num_threads()
    );
    let mut total = Tally::default();
    let t0 = std::time::Instant::now();
    for f in files(rest) {
        let machine = match Machine::from_path(&f) {
            Ok(m) => m,
            Err(e) => {
                println!("{}: not loaded: {e}", f.display());
                continue;
            }
        };
        let t1 = std::time::Instant::now();
        let t = machine.visit(Campaign {
            samples,
            serial: machine.kind() == "serial"
                && machine.mechanism().pose_space() != pkm::PoseSpace::Own,
        });
        println!(
            "\n{} ({}, {:.1} s)\n  IK->FK {}: IK errors [{}]; FK from home: {} same pose, {} \
             other assembly, errors [{}]; FK from nearby start: {} same pose, {} another pose at a condition number above \
             1e3 (largest {:.2e}), errors [{}]\n  \
             FK->IK {}: FK errors [{}]; IK: {} same actuators, {} other posture, errors [{}]\n  \
             worst actuator error {:.2e}, worst pose error from nearby start {:.2e}; \
             silent wrong {}, panics {}",
            f.display(),
            machine.kind(),
            t1.elapsed().as_secs_f64(),
            t.ik_fk,
            show(&t.ik_errors),
            t.fk_home_ok,
            t.fk_home_other_assembly,
            show(&t.fk_home_errors),
            t.fk_near_ok,
            t.fk_near_ill_conditioned,
            t.worst_condition_off,
            show(&t.fk_near_errors),
            t.fk_ik,
            show(&t.fk_errors),
            t.ik_after_fk_ok,
            t.ik_after_fk_other_posture,
            show(&t.ik_after_fk_errors),
            t.worst_actuator_error,
            t.worst_pose_error,
            t.silent_wrong,
            t.panics
        );
        for e in &t.examples {
            println!("  e.g. {e}");
        }
        for e in &t.failures {
            println!("  failed: {e}");
        }
        total = total.merge(t);
    }
    println!(
        "\nall machines: {} round trips in {:.1} s; silent wrong {}, panics {}, IK failures \
         after FK {}",
        total.ik_fk + total.fk_ik,
        t0.elapsed().as_secs_f64(),
        total.silent_wrong,
        total.panics,
        total.ik_after_fk_errors.values().sum::<u64>()
    );
    if total.silent_wrong > 0 || total.panics > 0 {
        std::process::exit(1);
    }
}
