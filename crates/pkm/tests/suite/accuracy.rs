#![allow(clippy::needless_range_loop)]
//! The generic accuracy engine on every machine type: analytic sensitivities against an
//! independent exact evaluation, central differences against analytic ones, drive
//! offsets against the inverse Jacobian, Monte Carlo spread against first order.

use nalgebra::{SVector, Vector3, Vector6};
use pkm::accuracy::{
    budget, finite_difference_sensitivities, monte_carlo, sensitivities, Distribution,
    ParameterKind, Parametric, Tolerance,
};
use pkm::identify::Identifiable;
use pkm::machine::{Analysable, Model, Visitor};
use pkm::mechanism::Mechanism;

fn load(name: &str) -> pkm::Machine {
    let dir = if name.ends_with(".urdf") {
        "robots"
    } else {
        "machines"
    };
    pkm::Machine::from_path(format!(
        "{}/../../examples/{dir}/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

fn machine(name: &str) -> Model {
    load(name).model
}

/// Tool-point position and rotation of a strut machine with parameters `theta` at the
/// readings the nominal machine needs for `x`, written from `Identifiable` alone.
fn exact<M: Identifiable<6, A>, const A: usize>(
    m: &M,
    zero: &SVector<f64, A>,
    x: &Vector6<f64>,
    theta: &[f64],
) -> (Vector3<f64>, nalgebra::UnitQuaternion<f64>) {
    let readings = m.inverse(x).unwrap() - zero;
    let ng = theta.len() - A;
    let mm = m.with_geometry(&theta[..ng]).unwrap();
    let z = SVector::<f64, A>::from_column_slice(&theta[ng..]);
    let f = mm.forward(&(z + readings), x).unwrap();
    let p = mm.tool_pose(&f.pose).unwrap();
    (p.translation.vector, p.rotation)
}

fn strut_analytic_vs_exact<M: Identifiable<6, A> + Parametric<6, A>, const A: usize>(
    m: &M,
    x: &Vector6<f64>,
) {
    let zero = m.zero_readings().unwrap();
    let s = sensitivities(m, x).unwrap();
    let mut theta = m.geometry();
    theta.extend(zero.iter());
    assert_eq!(s.len(), theta.len());
    assert_eq!(m.parameters().len(), theta.len());
    for (k, e) in s.iter().enumerate() {
        let h = 1e-5;
        let mut tp = theta.clone();
        let mut tm = theta.clone();
        tp[k] += h;
        tm[k] -= h;
        let (pp, rp) = exact(m, &zero, x, &tp);
        let (pm, rm) = exact(m, &zero, x, &tm);
        let fdp = (pp - pm) / (2.0 * h);
        let fdw = (rp * rm.inverse()).scaled_axis() / (2.0 * h);
        assert!(
            (e.position - fdp).amax() < 1e-6 * fdp.amax().max(1.0),
            "{k}: {} vs {fdp}",
            e.position
        );
        assert!(
            (e.orientation - fdw).amax() < 1e-7,
            "{k}: {} vs {fdw}",
            e.orientation
        );
    }
}

#[test]
fn strut_sensitivities_equal_exact_differences_on_hexapod_and_tripod() {
    let Model::Hexapod(h) = machine("hexapod-seed001.toml") else {
        panic!()
    };
    let x = Vector6::new(30.0, -20.0, h.info().home()[2] + 40.0, 0.1, -0.05, 0.2);
    strut_analytic_vs_exact(h.as_ref(), &x);
    let Model::TranslationalTripod(t) = machine("tripod-seed000.toml") else {
        panic!()
    };
    let mut x = t.info().home();
    x[0] += 20.0;
    x[1] -= 10.0;
    strut_analytic_vs_exact(&t, &x);
}

/// Checks run on every example machine through the visitor.
struct Invariants(&'static str);

impl Visitor for Invariants {
    type Output = ();
    fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
        let x = m.info().home();
        let params = m.parameters();
        assert!(!params.is_empty(), "{}", self.0);
        // Central differences of the exact error against the analytic sensitivities.
        let fd = finite_difference_sensitivities(m, &x).unwrap();
        assert_eq!(fd.len(), params.len());
        if let Some(an) = m.analytic_sensitivities(&x) {
            let an = an.unwrap();
            for (k, (a, f)) in an.iter().zip(&fd).enumerate() {
                assert!(
                    (a.position - f.position).amax() < 1e-5 * a.position.amax().max(1.0),
                    "{} {}: {} vs {}",
                    self.0,
                    params[k].name,
                    a.position,
                    f.position
                );
                assert!(
                    (a.orientation - f.orientation).amax() < 1e-6,
                    "{} {}",
                    self.0,
                    params[k].name
                );
            }
        }
        // The drive offsets (zero lengths, drive positioning: one per actuator, in
        // actuator order) move the tool as the inverse Jacobian says: dx = Jd^-1 e_k,
        // through the tool pose's own derivative.
        let drives: Vec<usize> = (0..params.len())
            .filter(|&k| {
                matches!(
                    params[k].kind,
                    ParameterKind::ZeroLength | ParameterKind::DrivePositioning
                )
            })
            .collect();
        assert_eq!(drives.len(), A, "{}", self.0);
        // (A robot's home may be a singular configuration: no inverse Jacobian there.)
        let d = m.info().driven();
        let jinv = m
            .jacobian(&x)
            .ok()
            .and_then(|j| nalgebra::DMatrix::from_fn(A, A, |r, c| j[(r, d[c])]).try_inverse());
        for k in 0..A {
            let Some(jinv) = &jinv else { break };
            let param = &params[drives[k]];
            let h = 1e-6;
            let mut xp = x;
            let mut xm = x;
            for (c, &dc) in d.iter().enumerate() {
                xp[dc] += h * jinv[(c, k)];
                xm[dc] -= h * jinv[(c, k)];
            }
            let pp = m.tool_pose(&xp).unwrap().translation.vector;
            let pm = m.tool_pose(&xm).unwrap().translation.vector;
            let expect = (pp - pm) / (2.0 * h);
            let got = fd[drives[k]].position;
            assert!(
                (got - expect).amax() < 1e-5 * expect.amax().max(1.0),
                "{} {}: {got} vs {expect}",
                self.0,
                param.name
            );
        }
        // The budget's RSS is the root sum of squares of |sensitivity| x tolerance.
        let tol: Vec<Tolerance> = (0..params.len())
            .map(|k| Tolerance {
                parameter: k,
                value: 0.01,
                distribution: Distribution::Uniform,
            })
            .collect();
        let b = budget(m, &x, &tol).unwrap();
        let s = sensitivities(m, &x).unwrap();
        let rss = s
            .iter()
            .map(|e| (e.position.norm() * 0.01).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!((b.rss - rss).abs() < 1e-12, "{}", self.0);
        assert!(b.worst_case >= b.rss);
    }
}

#[test]
fn every_machine_type_passes_the_engine_invariants() {
    for name in [
        "tripod-seed000.toml",
        "tripod-centre-leg.toml",
        "hexapod-seed001.toml",
        "hexapod-linuxcnc.toml",
        "p3rp-seed004.toml",
        "p3rp-hybrid-seed004.toml",
        "mc300.toml",
        "kr30-dh.toml",
        "ur5-like.urdf",
    ] {
        load(name).visit(Invariants(name));
    }
}

#[test]
fn a_zero_length_error_moves_the_tool_by_the_inverse_jacobian_column() {
    let Model::Hexapod(h) = machine("hexapod-seed001.toml") else {
        panic!()
    };
    let x = h.info().home();
    let s = sensitivities(h.as_ref(), &x).unwrap();
    let jinv = h.jacobian(&x).unwrap().try_inverse().unwrap();
    // zero(L1) longer by 1 mm: the strut is 1 mm longer at the same reading.
    let col = jinv.column(0);
    assert!((s[36].position - Vector3::new(col[0], col[1], col[2])).amax() < 1e-12);
}

/// Per-component Monte Carlo spread against the first-order prediction.
fn monte_carlo_matches_first_order<M: Parametric<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    tol: &[Tolerance],
    n: usize,
    rel: f64,
) {
    let s = sensitivities(m, x).unwrap();
    let predicted: Vec<f64> = (0..3)
        .map(|c| {
            tol.iter()
                .map(|t| (s[t.parameter].position[c] * t.std()).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    let mc = monte_carlo(m, x, tol, n, 3).unwrap();
    assert_eq!(mc.failed, 0);
    assert_eq!(mc.samples, n);
    for c in 0..3 {
        if predicted[c] < 1e-9 {
            assert!(mc.std_vector[c] < 1e-6, "{c}: {}", mc.std_vector[c]);
            continue;
        }
        let r = mc.std_vector[c] / predicted[c];
        assert!(
            (r - 1.0).abs() < rel,
            "component {c}: {} vs {}",
            mc.std_vector[c],
            predicted[c]
        );
        assert!(
            mc.mean_vector[c].abs() < 0.05 * predicted[c] + 1e-6,
            "{:?}",
            mc.mean_vector
        );
    }
    let b = budget(m, x, tol).unwrap();
    assert!(mc.p99 <= b.worst_case, "{} {}", mc.p99, b.worst_case);
    // Same seed, same result (chunks are seeded, whatever the thread count).
    assert_eq!(mc, monte_carlo(m, x, tol, n, 3).unwrap());
}

#[test]
fn monte_carlo_converges_to_the_first_order_prediction_on_parallel_machines() {
    let Model::Hexapod(h) = machine("hexapod-seed001.toml") else {
        panic!()
    };
    let x = Vector6::new(30.0, -20.0, h.info().home()[2] + 40.0, 0.1, -0.05, 0.2);
    let tol: Vec<Tolerance> = (0..42)
        .map(|k| Tolerance {
            parameter: k,
            value: if k < 36 { 0.01 } else { 0.02 },
            distribution: Distribution::Normal,
        })
        .collect();
    monte_carlo_matches_first_order(h.as_ref(), &x, &tol, 40_000, 0.03);
    let Model::P3rpHead(p) = machine("p3rp-seed004.toml") else {
        panic!()
    };
    let x = nalgebra::Vector2::new(p.info().home()[0] + 30.0, 0.5);
    let tol: Vec<Tolerance> = (0..p.parameters().len())
        .map(|k| Tolerance {
            parameter: k,
            value: if k == 3 { 1e-4 } else { 0.02 },
            distribution: Distribution::Uniform,
        })
        .collect();
    monte_carlo_matches_first_order(p.as_ref(), &x, &tol, 40_000, 0.03);
}

#[test]
fn tolerances_from_a_file_by_name() {
    let m = load("p3rp-seed004.toml");
    let params = m.parameters();
    let t = pkm::machine::read_tolerances(
        &params,
        "[[tolerance]]\ndeviation = \"l2\"\nvalue = 0.02\n[[tolerance]]\ndeviation = \"delta\"\nvalue = 0.01\ndistribution = \"normal\"\n",
        "t.toml",
    )
    .unwrap();
    assert_eq!(params[t[0].parameter].name, "l2");
    assert!((t[1].value - 0.01f64.to_radians()).abs() < 1e-15);
    assert_eq!(t[1].distribution, Distribution::Normal);
    let e = pkm::machine::read_tolerances(
        &params,
        "[[tolerance]]\ndeviation = \"l9\"\nvalue = 1\n",
        "t.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("t.toml:2") && e.contains("unknown deviation `l9`"),
        "{e}"
    );
}

/// A tolerance of 1e5 mm was once taken. Tolerances and deviations in files are
/// held to a range per kind of quantity (100 mm, 10 deg), with file, line and field;
/// the largest of each kind is taken.
#[test]
fn tolerances_and_deviations_beyond_their_kinds_range_are_refused() {
    let m = load("p3rp-seed004.toml");
    let params = m.parameters();
    for (text, line, field) in [
        ("[[tolerance]]\ndeviation = \"l2\"\nvalue = 1e5\n", 3, "value"),
        (
            "[[tolerance]]\ndeviation = \"l2\"\nvalue = 1\n\n[[tolerance]]\ndeviation = \"delta\"\nvalue = 10.5\n",
            7,
            "value",
        ),
    ] {
        let e = pkm::machine::read_tolerances(&params, text, "t.toml").unwrap_err();
        let s = e.to_string();
        assert!(s.contains(&format!("t.toml:{line}")), "{s}");
        assert!(s.contains(field) && s.contains("is not a tolerance"), "{s}");
    }
    let ok = pkm::machine::read_tolerances(
        &params,
        "[[tolerance]]\ndeviation = \"l2\"\nvalue = 100\n[[tolerance]]\ndeviation = \"delta\"\nvalue = 10\n",
        "t.toml",
    )
    .unwrap();
    assert_eq!(ok.len(), 2);
    for (text, what) in [("l2 = -250.0\n", "-250 mm"), ("delta = 45\n", "45 deg")] {
        let s = pkm::machine::read_deviations(&params, text, "d.toml")
            .unwrap_err()
            .to_string();
        assert!(s.contains("d.toml:1") && s.contains(what), "{s}");
    }
    let ok = pkm::machine::read_deviations(&params, "l2 = -100.0\ndelta = -10\n", "d.toml");
    assert_eq!(ok.unwrap().len(), 2);
}

/// A tolerance of 1e300 (it once printed a 300-digit budget, exit 0) is refused
/// with its name; the largest sane one is accepted.
#[test]
fn absurd_kind_tolerances_are_refused() {
    use pkm::analysis::KindTolerances;
    let ok = KindTolerances {
        joint: 100.0,
        angle: 10f64.to_radians(),
        ..Default::default()
    };
    assert!(ok.validate().is_ok());
    for t in [
        KindTolerances {
            joint: 1e300,
            ..Default::default()
        },
        KindTolerances {
            length: 2e6,
            ..Default::default()
        },
        // A tolerance of 1e5 mm, once still taken.
        KindTolerances {
            length: 1e5,
            ..Default::default()
        },
        KindTolerances {
            zero: 100.01,
            ..Default::default()
        },
        KindTolerances {
            angle: 11f64.to_radians(),
            ..Default::default()
        },
        KindTolerances {
            angle: f64::NAN,
            ..Default::default()
        },
        KindTolerances {
            zero: -0.01,
            ..Default::default()
        },
    ] {
        let e = t.validate().unwrap_err().to_string();
        assert!(
            e.contains("tolerance") && e.contains("expected a value from 0"),
            "{e}"
        );
    }
}

/// `--monte-carlo 10^14` once grew past 600 MB before anything said no. A count
/// beyond the limit is refused before any sample, with the memory it would need.
#[test]
fn monte_carlo_counts_beyond_the_limit_are_refused_up_front() {
    let Model::Hexapod(h) = machine("hexapod-seed001.toml") else {
        panic!()
    };
    let x = h.info().home();
    let tol = [pkm::accuracy::Tolerance {
        parameter: 0,
        value: 0.01,
        distribution: pkm::accuracy::Distribution::Uniform,
    }];
    let max = pkm::accuracy::monte_carlo::MAX_MONTE_CARLO;
    for n in [0, max + 1, usize::MAX / 2] {
        let e = monte_carlo(h.as_ref(), &x, &tol, n, 1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("expected 1 to 1e9 samples"), "{e}");
    }
}

/// The Monte Carlo streams its statistics (constant memory). The
/// streamed moments equal the stored sample's to rounding, the streamed percentiles
/// are within the sketch's relative 1e-4 of the exact order statistics, the
/// histogram counts every sample.
#[test]
fn streamed_statistics_equal_the_stored_samples() {
    use pkm::accuracy::streamed::{finish, Moments, Sketch, QUANTILE_RESOLUTION};
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    // Errors over four decades, some exactly zero, in two halves merged.
    let errors: Vec<Vector3<f64>> = (0..50_000)
        .map(|i| {
            if i % 1000 == 0 {
                return Vector3::zeros();
            }
            let s = 10f64.powf(rng.random_range(-4.0..0.0));
            Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ) * s
        })
        .collect();
    let exact = pkm::accuracy::statistics(&errors);
    let (mut a, mut b) = (Moments::default(), Moments::default());
    let mut sketch = Sketch::default();
    for (i, e) in errors.iter().enumerate() {
        if i < 20_000 {
            a.push(e)
        } else {
            b.push(e)
        }
        sketch.add(sketch.bucket(e.norm()));
    }
    a.merge(&b);
    let s = finish(&a, &sketch, 3);
    assert_eq!(s.samples, exact.samples);
    assert_eq!(s.failed, 3);
    let close = |x: f64, y: f64, rel: f64| (x - y).abs() <= rel * y.abs() + 1e-300;
    assert!(
        close(s.mean, exact.mean, 1e-12),
        "{} {}",
        s.mean,
        exact.mean
    );
    assert!(close(s.std, exact.std, 1e-10), "{} {}", s.std, exact.std);
    assert_eq!(s.max, exact.max);
    for c in 0..3 {
        assert!((s.mean_vector[c] - exact.mean_vector[c]).abs() < 1e-15);
        assert!(close(s.std_vector[c], exact.std_vector[c], 1e-10));
    }
    assert!(
        close(s.p95, exact.p95, QUANTILE_RESOLUTION),
        "{} {}",
        s.p95,
        exact.p95
    );
    assert!(
        close(s.p99, exact.p99, QUANTILE_RESOLUTION),
        "{} {}",
        s.p99,
        exact.p99
    );
    assert_eq!(s.histogram.iter().map(|h| h.1).sum::<usize>(), errors.len());
    // Bin by bin, only norms within 1e-4 of a bin edge can fall on the other side.
    for (x, y) in s.histogram.iter().zip(&exact.histogram) {
        assert!(x.1.abs_diff(y.1) <= 20, "{x:?} {y:?}");
    }
}

/// The Monte Carlo's result does not depend on the number of threads, and progress
/// is told of every machine.
#[test]
fn monte_carlo_is_the_same_on_one_and_two_threads_and_reports_progress() {
    let Model::Hexapod(h) = machine("hexapod-seed001.toml") else {
        panic!()
    };
    let x = h.info().home();
    let tol: Vec<Tolerance> = (0..12)
        .map(|p| Tolerance {
            parameter: p,
            value: 0.01,
            distribution: if p % 2 == 0 {
                Distribution::Uniform
            } else {
                Distribution::Normal
            },
        })
        .collect();
    let n = 300_000;
    let run = |threads: usize| {
        let done = std::sync::atomic::AtomicU64::new(0);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mc = pool.install(|| {
            pkm::accuracy::monte_carlo_with_progress(h.as_ref(), &x, &tol, n, 9, &|k| {
                done.fetch_add(k, std::sync::atomic::Ordering::Relaxed);
            })
            .unwrap()
        });
        (mc, done.into_inner())
    };
    let (one, done1) = run(1);
    let (two, done2) = run(2);
    assert_eq!(one, two);
    assert_eq!((done1, done2), (n as u64, n as u64));
    assert_eq!(one.samples + one.failed, n);
}

/// The signed sketch of the clearance Monte Carlo: ranks within 1e-4 of the exact
/// order statistics on both sides of zero, every value in the histogram.
#[test]
fn signed_sketch_ranks_equal_the_sorted_values() {
    use pkm::accuracy::streamed::{ScalarMoments, SignedSketch, QUANTILE_RESOLUTION};
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let mut v: Vec<f64> = (0..20_000)
        .map(|_| rng.random_range(-0.3..0.5) * 10f64.powf(rng.random_range(-3.0..0.0)))
        .collect();
    let mut s = SignedSketch::default();
    let mut m = ScalarMoments::default();
    for &x in &v {
        s.add(s.bucket(x));
        m.push(x);
    }
    v.sort_by(f64::total_cmp);
    for f in [0.0, 0.01, 0.2, 0.5, 0.8, 0.99, 1.0] {
        let r = ((v.len() as f64 - 1.0) * f).round() as usize;
        let got = s.rank(r as u64, m.min, m.max);
        assert!(
            (got - v[r]).abs() <= QUANTILE_RESOLUTION * v[r].abs() + 1e-15,
            "{f}: {got} vs {}",
            v[r]
        );
    }
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    assert!((m.mean - mean).abs() < 1e-15);
    let h = s.histogram(40, m.min, m.max);
    assert_eq!(h.iter().map(|b| b.1).sum::<usize>(), v.len());
}
