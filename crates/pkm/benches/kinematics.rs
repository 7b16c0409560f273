//! Kinematics speed (criterion, one thread unless a name says otherwise; the medians and
//! how to rerun them: `docs/performance.md`). Target: tripod IK per pose from a
//! rotation matrix <= 15 ns.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{Matrix3, Vector3, Vector6};
use pkm::accuracy::Parametric;
use pkm::machine::Model;
use pkm::mechanism::abilities;
use pkm::rotation::Convention;
use pkm::{Machine, Mechanism};

fn machine(name: &str) -> Machine {
    Machine::from_path(format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

fn tripod(c: &mut Criterion) {
    let Model::TranslationalTripod(t) = machine("tripod-seed000.toml").model else {
        panic!()
    };
    let p = Vector3::new(-20.0, 45.54, -286.25);
    let r: Matrix3<f64> = Convention::Rpy.to_matrix([15f64.to_radians(), 0.0, 0.0]);
    c.bench_function("tripod IK from rotation matrix", |b| {
        b.iter(|| {
            t.tripod_geometry()
                .strut_lengths(black_box(&p), black_box(&r))
        })
    });
    let x = Vector6::new(-20.0, 45.54, -286.25, 15f64.to_radians(), 0.0, 0.0);
    c.bench_function("tripod IK from X,Y,Z,A,B,C", |b| {
        b.iter(|| Mechanism::<6, 3>::inverse(&t, black_box(&x)).unwrap())
    });
    c.bench_function("tripod jacobian", |b| {
        b.iter(|| Mechanism::<6, 3>::jacobian(&t, black_box(&x)).unwrap())
    });
    let q = Mechanism::<6, 3>::inverse(&t, &x).unwrap();
    c.bench_function("tripod FK closed form", |b| {
        b.iter(|| Mechanism::<6, 3>::forward(&t, black_box(&q), black_box(&x)).unwrap())
    });
    let Model::CentreLegTripod(cl) = machine("tripod-centre-leg.toml").model else {
        panic!()
    };
    let xc = Vector3::new(30.0, -20.0, -300.0);
    let qc = Mechanism::<3, 3>::inverse(&cl, &xc).unwrap();
    c.bench_function("centre-leg tripod IK", |b| {
        b.iter(|| Mechanism::<3, 3>::inverse(&cl, black_box(&xc)).unwrap())
    });
    let home = cl.info().home();
    c.bench_function("centre-leg tripod FK (Newton from home)", |b| {
        b.iter(|| Mechanism::<3, 3>::forward(&cl, black_box(&qc), black_box(&home)).unwrap())
    });
}

fn identification(c: &mut Criterion) {
    use pkm::identify::simulate::{simulate, Experiment};
    use pkm::identify::{identify, MeasurementModel as Measured, Options};
    let Model::Hexapod(h) = machine("hexapod-seed001.toml").model else {
        panic!()
    };
    let zero = pkm::identify::Identifiable::zero_readings(h.as_ref()).unwrap();
    // The command's default campaign with 100 states.
    let e = Experiment {
        states: 100,
        ..Experiment::default()
    };
    let s = simulate(h.as_ref(), &zero, &e).unwrap();
    let mut g = c.benchmark_group("identification");
    g.sample_size(20);
    for (name, model) in [("pose", Measured::Pose), ("points", Measured::Points)] {
        let o = Options {
            model,
            ..Default::default()
        };
        g.bench_function(
            format!("hexapod 42 parameters from 100 states ({name} model, LM + analysis)"),
            |b| b.iter(|| identify(h.as_ref(), &zero, black_box(&s.measurements), &o).unwrap()),
        );
    }
    g.finish();
}

criterion_group!(identification_benches, identification);
criterion_group!(benches, tripod);
criterion_main!(
    accuracy_benches,
    benches,
    motion_benches,
    hexapod_benches,
    workspace_benches,
    serial_benches,
    identification_benches,
    statics_benches
);

fn motion(c: &mut Criterion) {
    use pkm::motion::gcode::Interpreter;
    use pkm::motion::program::{to_move, FeedOptions};
    use pkm::motion::{Runner, Sampling};
    let Model::TranslationalTripod(t) = machine("tripod-seed000.toml").model else {
        panic!()
    };
    let x = Vector6::new(10.0, -5.0, -295.0, 0.0, 0.0, 0.0);
    let xd = Vector6::new(100.0, 50.0, 0.0, 0.0, 0.0, 0.0);
    let xdd = Vector6::new(-300.0, 400.0, 0.0, 0.0, 0.0, 0.0);
    c.bench_function("tripod actuator motion (q, q', q'') per sample", |b| {
        b.iter(|| {
            t.actuator_motion(black_box(&x), black_box(&xd), black_box(&xdd))
                .unwrap()
        })
    });
    // The whole sampler (profile, path, exact actuator motion, statistics, limits) on
    // seed 000's arc at 1 kHz: 10 000 samples per iteration.
    let mut g = Interpreter::new([32.0, -32.0, -290.0, 0.0, 0.0, 0.0]);
    let gm = g.line("G3 X-32 Y32 I-64 J0 F600", 1).unwrap().unwrap();
    let mv = to_move(&t, &gm, &FeedOptions::default()).unwrap();
    let mut group = c.benchmark_group("sampler");
    group.throughput(criterion::Throughput::Elements(10_054));
    group.bench_function("tripod arc at 1 kHz (10 054 samples)", |b| {
        b.iter(|| {
            let mut r = Runner::new(&t, Sampling::Rate(1000.0)).unwrap();
            r.run_move(black_box(&mv), true, &mut |_| Ok(())).unwrap();
            r.finish().samples
        })
    });
    group.finish();
}

/// LinuxCNC's boat program (1 867 lines, 316 s of motion) through MC-300 at 1 kHz with
/// the accuracy along it (the file's 39 tolerances at every sample, a band of 100 machines
/// at every 10th), one thread, within 1 s; and the run alone.
fn five_axis_program(c: &mut Criterion) {
    use pkm::analysis::motion::{
        feed_options, run_motion_with, MotionSource, NoSink, PathAccuracyRequest,
    };
    let m = machine("mc300.toml");
    let text = std::fs::read_to_string(format!(
        "{}/../../tests/fixtures/linuxcnc/xyzbc-trt/boat-xyzbc.ngc",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let run = |acc: Option<&PathAccuracyRequest>| {
        run_motion_with(
            &m,
            MotionSource::Gcode {
                reader: Box::new(std::io::Cursor::new(text.as_bytes())),
                from: None,
                setup: Default::default(),
            },
            &feed_options(&m),
            pkm::motion::Sampling::Rate(1000.0),
            acc,
            &mut NoSink,
        )
        .unwrap()
        .summary
        .samples
    };
    let mut g = c.benchmark_group("five-axis program");
    g.sample_size(10);
    g.bench_function(
        "boat through MC-300 at 1 kHz (316 201 samples), one thread",
        |b| b.iter(|| run(None)),
    );
    let req = PathAccuracyRequest::default();
    g.bench_function(
        "boat through MC-300 at 1 kHz with accuracy (39 tolerances, 100 machines every 10th sample), one thread",
        |b| b.iter(|| run(Some(&req))),
    );
    g.finish();
}

/// Python's `m.ik` batch: `analysis::kinematics::inverse_batch` of 10^6 random hexapod poses
/// (uniform in +-100 mm, +-10 deg about home; the limit check included), rayon on all
/// cores of the machine (2 here) and on one.
fn batch_inverse(c: &mut Criterion) {
    use pkm::analysis::kinematics::inverse_batch;
    use rand::{Rng, SeedableRng};
    let m = machine("hexapod-linuxcnc.toml");
    let home = m.mechanism().home();
    let mut rng = rand::rngs::StdRng::seed_from_u64(1);
    let poses: Vec<f64> = (0..6_000_000)
        .map(|i| {
            let k = i % 6;
            let s = if k < 3 { 100.0 } else { 10f64.to_radians() };
            home[k] + rng.random_range(-s..s)
        })
        .collect();
    let mut g = c.benchmark_group("batch inverse");
    g.sample_size(10);
    g.throughput(criterion::Throughput::Elements(1_000_000));
    g.bench_function(
        format!(
            "hexapod 1e6 random poses with limits (rayon, {} threads)",
            rayon::current_num_threads()
        ),
        |b| {
            b.iter(|| {
                inverse_batch(&m, black_box(&poses))
                    .unwrap()
                    .reachable
                    .len()
            })
        },
    );
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    g.bench_function("hexapod 1e6 random poses with limits (one thread)", |b| {
        b.iter(|| {
            one.install(|| {
                inverse_batch(&m, black_box(&poses))
                    .unwrap()
                    .reachable
                    .len()
            })
        })
    });
    g.finish();
}

/// A wavy 5-axis raster of `lines` G1 moves about `centre` (X, Y, Z, then A about
/// `a0`): +-40 mm in X and Y, +-5 mm in Z, +-3 deg in A and B, 0.1-0.3 mm per line at
/// 800 mm/min (about 18 samples per line at 1 kHz), the shape of a finishing program.
fn wave_program(lines: usize, centre: [f64; 3], a0: f64) -> String {
    let [cx, cy, cz] = centre;
    let mut s = format!(
        "G21 G90 G17\nG0 X{cx:.4} Y{:.4} Z{cz:.4} A{a0:.4} B0 C0\nF800\n",
        cy + 40.0
    );
    for i in 0..lines {
        let t = i as f64 * 0.01;
        s += &format!(
            "G1 X{:.4} Y{:.4} Z{:.4} A{:.4} B{:.4}\n",
            cx + 40.0 * (t * 0.7).sin(),
            cy + 40.0 * (t * 0.53).cos(),
            cz + 5.0 * (t * 1.3).sin(),
            a0 + 3.0 * (t * 0.2).sin(),
            3.0 * (t * 0.17).cos()
        );
    }
    s + "M2\n"
}

/// Programs through a hexapod and a 6R robot at 1 kHz, the whole sampler
/// (G-code, profile, exact actuator q, q', q'', statistics, limits), on one thread and
/// on the global pool (`motion/plan.rs`).
fn program_motion(c: &mut Criterion) {
    use pkm::analysis::motion::{feed_options, run_motion_with, MotionSource, NoSink};
    let run = |m: &Machine, text: &str| {
        run_motion_with(
            m,
            MotionSource::Gcode {
                reader: Box::new(std::io::Cursor::new(text.as_bytes().to_vec())),
                from: None,
                setup: Default::default(),
            },
            &feed_options(m),
            pkm::motion::Sampling::Rate(1000.0),
            None,
            &mut NoSink,
        )
        .unwrap()
        .summary
        .samples
    };
    let mut g = c.benchmark_group("program motion");
    g.sample_size(10);
    // One thread: everything inline, in a pool of one.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for (file, centre, a0) in [
        ("hexapod-linuxcnc.toml", [0.0, 0.0, 508.0], 0.0),
        // A = -180 deg as the KR 30's home pose reads: from A-180, A180 would be a
        // full turn of the tool (every coordinate is interpolated as a number), which
        // the robot's motion follows with A4 to 360 deg, beyond its range.
        ("kr30-dh.toml", [1170.0, 0.0, 1400.0], -180.0),
    ] {
        let m = machine(file);
        let text = wave_program(10_000, centre, a0);
        let samples = run(&m, &text);
        g.throughput(criterion::Throughput::Elements(samples));
        g.bench_function(
            format!("{file}: 10k-line program at 1 kHz ({samples} samples), 1 thread"),
            |b| b.iter(|| one.install(|| run(&m, black_box(&text)))),
        );
        // The global pool: blocks computed on it while this thread records.
        g.bench_function(
            format!(
                "{file}: 10k-line program at 1 kHz ({samples} samples), {} threads",
                rayon::current_num_threads()
            ),
            |b| b.iter(|| run(&m, black_box(&text))),
        );
    }
    // The hexapod's program 400 mm higher: every strut beyond its 1000 mm stroke from
    // the first moves, so every sample reports six violations (a design or a program
    // that does not fit, as a sweep meets them).
    let m = machine("hexapod-linuxcnc.toml");
    let text = wave_program(10_000, [0.0, 0.0, 908.0], 0.0);
    let samples = run(&m, &text);
    g.throughput(criterion::Throughput::Elements(samples));
    g.bench_function(
        format!(
            "hexapod-linuxcnc.toml: the program 400 mm higher, beyond every stroke \
             ({samples} samples), 1 thread"
        ),
        |b| b.iter(|| one.install(|| run(&m, black_box(&text)))),
    );
    g.finish();
}

criterion_group!(
    motion_benches,
    motion,
    five_axis_program,
    batch_inverse,
    program_motion
);

fn hexapod(c: &mut Criterion) {
    let Model::Hexapod(h) = machine("hexapod-linuxcnc.toml").model else {
        panic!()
    };
    let h = *h;
    let x = Vector6::new(20.0, -10.0, 540.0, 0.05, -0.03, 0.1);
    let (p, r) = pkm::legs::split_pose(&x);
    // The fastest kernel of this CPU (AVX-512 when present), and the portable code.
    c.bench_function("hexapod IK from rotation matrix", |b| {
        b.iter(|| h.lengths(black_box(&p), black_box(&r)))
    });
    c.bench_function("hexapod IK from rotation matrix (portable code)", |b| {
        b.iter(|| h.lengths_portable(black_box(&p), black_box(&r)))
    });
    // Batches of 1024 poses (a tool path, a workspace row).
    let n = 1024;
    let ps: Vec<nalgebra::Vector3<f64>> = (0..n)
        .map(|k| p + nalgebra::Vector3::new(0.01 * k as f64, -0.02 * k as f64, 0.005 * k as f64))
        .collect();
    let rs: Vec<nalgebra::Matrix3<f64>> = (0..n)
        .map(|k| pkm::rotation::rpy_matrix(0.05 + 1e-4 * k as f64, -0.03, 0.1))
        .collect();
    let mut out = vec![Vector6::zeros(); n];
    let mut g = c.benchmark_group("hexapod IK batch");
    g.throughput(criterion::Throughput::Elements(n as u64));
    g.bench_function("1024 poses from rotation matrices", |b| {
        b.iter(|| {
            h.lengths_batch(black_box(&ps), black_box(&rs), &mut out);
            out[n - 1][0]
        })
    });
    g.bench_function("1024 poses from rotation matrices (portable code)", |b| {
        b.iter(|| {
            h.soa()
                .lengths_batch(black_box(&ps), black_box(&rs), &mut out);
            out[n - 1][0]
        })
    });
    g.finish();
    random_hexapod_ik(c, &h);
    let q = Mechanism::<6, 6>::inverse(&h, &x).unwrap();
    // Previous pose of a 1 kHz trajectory at 100 mm/s and 0.5 rad/s: 0.1 mm, 0.0005 rad away.
    let prev = Vector6::new(19.9, -10.0, 540.0, 0.0495, -0.03, 0.1);
    c.bench_function("hexapod FK from the previous 1 kHz pose", |b| {
        b.iter(|| Mechanism::<6, 6>::forward(&h, black_box(&q), black_box(&prev)).unwrap())
    });
    // A stream of strut lengths at 1 kHz (circle of radius 40 mm at 100 mm/s with a
    // slow tilt), solved by the tracking FK: start predicted from the last two poses,
    // factorised Jacobian kept across samples.
    let traj: Vec<Vector6<f64>> = (0..1000)
        .map(|k| {
            let t = k as f64 * 1e-3;
            let a = 2.5 * t;
            let hm = h.info().home();
            Vector6::new(
                hm[0] + 40.0 * a.cos() - 40.0,
                hm[1] + 40.0 * a.sin(),
                hm[2] + 10.0 * t,
                0.05 * (3.0 * t).sin(),
                0.04 * t,
                hm[5] + 0.02 * t,
            )
        })
        .collect();
    let qs: Vec<Vector6<f64>> = traj
        .iter()
        .map(|x| Mechanism::<6, 6>::inverse(&h, x).unwrap())
        .collect();
    let mut g = c.benchmark_group("hexapod FK tracking");
    g.throughput(criterion::Throughput::Elements(qs.len() as u64));
    g.bench_function("1 kHz stream of 1000 samples (FkTracker)", |b| {
        b.iter(|| {
            let mut tr = pkm::hexapod::FkTracker::new(&traj[0], Default::default());
            let mut last = 0.0;
            for q in &qs {
                last = tr.track(&h, black_box(q)).unwrap().position.x;
            }
            last
        })
    });
    g.finish();
    let home = h.info().home();
    c.bench_function("hexapod FK from home", |b| {
        b.iter(|| Mechanism::<6, 6>::forward(&h, black_box(&q), black_box(&home)).unwrap())
    });
}

/// The hexapod's IK on random poses (uniform in +-100 mm, +-10 deg about the
/// LinuxCNC hexapod's home, seed 1), one thread: from X, Y, Z, A, B, C one pose per
/// call (what a controller sends), and 200 000 poses as a batch (16 MB of input, so
/// not cache-resident), from X..C by the block kernel and from rotation matrices.
fn random_hexapod_ik(c: &mut Criterion, h: &pkm::hexapod::Hexapod) {
    use rand::{Rng, SeedableRng};
    let home = Mechanism::<6, 6>::info(h).home();
    let mut rng = rand::rngs::StdRng::seed_from_u64(1);
    let mut random = |n: usize| -> Vec<f64> {
        (0..6 * n)
            .map(|i| {
                let k = i % 6;
                let s = if k < 3 { 100.0 } else { 10f64.to_radians() };
                home[k] + rng.random_range(-s..s)
            })
            .collect()
    };
    let few = random(1024);
    let xs: Vec<Vector6<f64>> = few
        .chunks_exact(6)
        .map(Vector6::from_column_slice)
        .collect();
    // The poses one call each, as a controller sends them.
    let one_by_one = |m: &pkm::hexapod::Hexapod| {
        let mut sum = 0.0;
        for x in &xs {
            sum += Mechanism::<6, 6>::inverse(m, black_box(x)).unwrap()[0];
        }
        sum
    };
    let mut g = c.benchmark_group("hexapod IK random poses");
    g.throughput(criterion::Throughput::Elements(xs.len() as u64));
    g.bench_function(
        "from X..C, one pose per call (1024 poses), one thread",
        |b| b.iter(|| one_by_one(h)),
    );
    let n = 200_000;
    let many = random(n);
    let mut qs = vec![0.0; 6 * n];
    let mut clear = vec![false; n];
    g.throughput(criterion::Throughput::Elements(n as u64));
    g.bench_function("batch of 200k from X..C (block kernel), one thread", |b| {
        b.iter(|| {
            let screened =
                abilities::inverse_screened(h, black_box(&many), &mut qs, &mut clear, false);
            (screened, qs[6 * n - 1])
        })
    });
    // The same machine with its tool 100 mm below the platform's plane: its arms are
    // then off that plane, and the kernels take the rotation's third column (the
    // LinuxCNC hexapod's arms lie in it, which the kernels use: `hexapod/simd.rs`).
    let text = std::fs::read_to_string(format!(
        "{}/../../examples/machines/hexapod-linuxcnc.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace("tip = [0.0, 0.0, 0.0]", "tip = [0.0, 0.0, -100.0]");
    let Model::Hexapod(off) = Machine::from_toml_str(&text, "tool-off-plane.toml")
        .unwrap()
        .model
    else {
        panic!()
    };
    let off = *off;
    assert_ne!(off.tool(), h.tool());
    g.throughput(criterion::Throughput::Elements(xs.len() as u64));
    g.bench_function(
        "from X..C, one pose per call (1024 poses), one thread, tool off the platform's plane",
        |b| b.iter(|| one_by_one(&off)),
    );
    g.throughput(criterion::Throughput::Elements(n as u64));
    g.bench_function(
        "batch of 200k from X..C (block kernel), one thread, tool off the platform's plane",
        |b| {
            b.iter(|| {
                let screened =
                    abilities::inverse_screened(&off, black_box(&many), &mut qs, &mut clear, false);
                (screened, qs[6 * n - 1])
            })
        },
    );
    g.bench_function(
        "batch of 200k from X..C with the limit screen (block kernel), one thread",
        |b| {
            b.iter(|| {
                let screened =
                    abilities::inverse_screened(h, black_box(&many), &mut qs, &mut clear, true);
                (screened, clear[n - 1])
            })
        },
    );
    let (ps, rs): (Vec<_>, Vec<_>) = many
        .chunks_exact(6)
        .map(|x| pkm::legs::split_pose(&Vector6::from_column_slice(x)))
        .unzip();
    let mut out = vec![Vector6::zeros(); n];
    g.bench_function("batch of 200k from rotation matrices, one thread", |b| {
        b.iter(|| {
            h.lengths_batch(black_box(&ps), black_box(&rs), &mut out);
            out[n - 1][0]
        })
    });
    // The memory floor under the two batches: the same inputs read and as many values
    // written, with one addition per value instead of the kinematics. A batch cannot
    // run faster than its inputs stream from memory on one core.
    g.bench_function(
        "memory floor: 200k X..C read, 6 values written, one thread",
        |b| {
            b.iter(|| {
                for (o, x) in qs.chunks_exact_mut(6).zip(black_box(&many).chunks_exact(6)) {
                    for k in 0..6 {
                        o[k] = x[k] + 1.0;
                    }
                }
                qs[6 * n - 1]
            })
        },
    );
    g.bench_function(
        "memory floor: 200k positions, matrices read, 6 values written, one thread",
        |b| {
            b.iter(|| {
                for ((o, p), r) in out.iter_mut().zip(black_box(&ps)).zip(black_box(&rs)) {
                    for k in 0..3 {
                        o[k] = p[k] + r[k];
                        o[k + 3] = r[k + 3] + r[k + 6];
                    }
                }
                out[n - 1][0]
            })
        },
    );
    // The same four on the global pool: a batch of a user's (Python's `m.ik`, `pkm ik`)
    // runs on every core; chunks of 8192 poses (the library's batch chunk).
    use rayon::prelude::*;
    let threads = rayon::current_num_threads();
    const CH: usize = 8192;
    g.bench_function(
        format!("batch of 200k from X..C (block kernel), rayon {threads} threads"),
        |b| {
            b.iter(|| {
                black_box(&many)
                    .par_chunks(6 * CH)
                    .zip(qs.par_chunks_mut(6 * CH))
                    .zip(clear.par_chunks_mut(CH))
                    .for_each(|((x, q), c)| {
                        abilities::inverse_screened(h, x, q, c, false);
                    });
                qs[6 * n - 1]
            })
        },
    );
    g.bench_function(
        format!("batch of 200k from rotation matrices, rayon {threads} threads"),
        |b| {
            b.iter(|| {
                black_box(&ps)
                    .par_chunks(CH)
                    .zip(black_box(&rs).par_chunks(CH))
                    .zip(out.par_chunks_mut(CH))
                    .for_each(|((p, r), o)| h.lengths_batch(p, r, o));
                out[n - 1][0]
            })
        },
    );
    g.bench_function(
        format!("memory floor: 200k X..C read, 6 values written, rayon {threads} threads"),
        |b| {
            b.iter(|| {
                qs.par_chunks_mut(6 * CH)
                    .zip(black_box(&many).par_chunks(6 * CH))
                    .for_each(|(q, x)| {
                        for (o, x) in q.chunks_exact_mut(6).zip(x.chunks_exact(6)) {
                            for k in 0..6 {
                                o[k] = x[k] + 1.0;
                            }
                        }
                    });
                qs[6 * n - 1]
            })
        },
    );
    g.bench_function(
        format!(
            "memory floor: 200k positions, matrices read, 6 values written, rayon {threads} threads"
        ),
        |b| {
            b.iter(|| {
                out.par_chunks_mut(CH)
                    .zip(black_box(&ps).par_chunks(CH))
                    .zip(black_box(&rs).par_chunks(CH))
                    .for_each(|((o, p), r)| {
                        for ((o, p), r) in o.iter_mut().zip(p).zip(r) {
                            for k in 0..3 {
                                o[k] = p[k] + r[k];
                                o[k + 3] = r[k + 3] + r[k + 6];
                            }
                        }
                    });
                out[n - 1][0]
            })
        },
    );
    g.finish();
}

criterion_group!(hexapod_benches, hexapod);

fn workspace(c: &mut Criterion) {
    use pkm::workspace::{map, GridAxis};
    let Model::Hexapod(h) = machine("hexapod-linuxcnc.toml").model else {
        panic!()
    };
    let h = *h;
    // 101^3 = 1 030 301 points, all reachable (IK, every limit, condition number).
    let axes = [
        GridAxis {
            coordinate: 0,
            min: -100.0,
            max: 100.0,
            step: 2.0,
        },
        GridAxis {
            coordinate: 1,
            min: -100.0,
            max: 100.0,
            step: 2.0,
        },
        GridAxis {
            coordinate: 2,
            min: 450.0,
            max: 650.0,
            step: 2.0,
        },
    ];
    let mut g = c.benchmark_group("workspace");
    g.sample_size(10);
    g.bench_function(
        format!(
            "hexapod 1.03e6 grid points (rayon, {} threads)",
            rayon::current_num_threads()
        ),
        |b| {
            b.iter(|| {
                map(&h, black_box(&h.info().home()), &axes, &[], &|_| {})
                    .unwrap()
                    .points
                    .len()
            })
        },
    );
    g.finish();
}

criterion_group!(workspace_benches, workspace);

fn serial(c: &mut Criterion) {
    use nalgebra::{Matrix3, Vector3};
    use pkm::serial::{Chain, Joint, JointKind, Link, LinkDeviation, PreparedChain};
    // A 6R arm (KR 30-like proportions) with deviations on every link.
    let links: Vec<Link> = (0..7)
        .map(|i| Link {
            name: format!("{i}"),
            joint: (i > 0).then(|| Joint {
                name: format!("A{i}"),
                kind: JointKind::Revolute,
                range: pkm::Range {
                    min: -3.0,
                    max: 3.0,
                },
                max_velocity: None,
                max_acceleration: None,
                stiffness: None,
            }),
            translation: Vector3::new(35.0 * (i % 2) as f64, 0.0, 150.0 + 50.0 * i as f64),
            rotation: if i % 2 == 0 {
                Matrix3::identity()
            } else {
                Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0)
            },
            inertial: None,
        })
        .collect();
    let chain = Chain {
        name: "arm".into(),
        links,
    };
    let dev: Vec<LinkDeviation> = (0..7)
        .map(|i| LinkDeviation {
            delta: Vector3::new(0.01, -0.02, 0.003 * i as f64),
            alpha: Matrix3::from_fn(|r, k| 1e-4 * ((r + 2 * k + i) % 4) as f64),
            ..Default::default()
        })
        .collect();
    let dq = [1e-3, -2e-3, 5e-4, 0.0, 1e-4, -1e-4];
    let q = [0.3, -0.7, 1.1, 0.2, -0.4, 0.9];
    let prepared = PreparedChain::new(&chain, &dq, &dev);
    c.bench_function("serial 6R FK with deviations (prepared chain)", |b| {
        b.iter(|| prepared.pose(black_box(&q)))
    });
    c.bench_function(
        "serial 6R FK with deviations (general, deviations applied per call)",
        |b| b.iter(|| chain.pose(black_box(&q), &dq, &dev).unwrap()),
    );
    // The same arm with its links' translation deviations only: the walk and each
    // link's bookkeeping without the angular deviations' sines and cosines.
    let dev_delta: Vec<LinkDeviation> = dev
        .iter()
        .map(|d| LinkDeviation {
            delta: d.delta,
            ..Default::default()
        })
        .collect();
    c.bench_function(
        "serial 6R FK with translation deviations only (general, applied per call)",
        |b| b.iter(|| chain.pose(black_box(&q), &dq, &dev_delta).unwrap()),
    );
    c.bench_function(
        "serial 6R pose + geometric Jacobian (prepared chain)",
        |b| b.iter(|| prepared.jacobian(black_box(&q))),
    );
    let serial_m = pkm::serial::machine::SerialMachine {
        name: "arm".into(),
        tool: chain.clone(),
        workpiece: None,
    };
    c.bench_function(
        "serial 6R tool Jacobian (6 x 6, from the sensitivities)",
        |b| b.iter(|| serial_m.tool_jacobian(black_box(&q), &[]).unwrap()),
    );
    let Model::Serial(s) = machine("mc300.toml").model else {
        panic!()
    };
    let m = s.mechanism.machine().clone();
    let (qt, qw) = ([100.0, -50.0, -80.0], [0.52, 0.79]);
    let params = m.all_parameters();
    c.bench_function("MC-300 sensitivities of all 89 deviations", |b| {
        b.iter(|| m.sensitivities(black_box(&qt), &qw, &[], &params).unwrap())
    });
    let pkm::serial::mechanism::SerialAny::Tcp5(mc300) = &s.mechanism else {
        panic!()
    };
    // The TCP pose of those joints.
    let x300 = mc300.coords_of_joints(&nalgebra::SVector::<f64, 5>::from_column_slice(&[
        qt[0], qt[1], qt[2], qw[0], qw[1],
    ]));
    let mut g = c.benchmark_group("serial monte carlo");
    g.sample_size(10);
    g.bench_function(
        format!(
            "MC-300 1e6 machines, its file's 39 tolerances, uncompleted (rayon, {} threads)",
            rayon::current_num_threads()
        ),
        |b| {
            b.iter(|| {
                pkm::accuracy::monte_carlo(mc300, &x300, &s.tolerances, 1_000_000, 1)
                    .unwrap()
                    .mean
            })
        },
    );
    // The same engine on the rows of the file as it was at c008e08 (the paper's
    // 43, aligned-entry angles and installation angles included; evaluated, not
    // completed), so that before/after compare the same work.
    let names = mc300.parameters();
    let by_name = |name: &str, value: f64| pkm::accuracy::Tolerance {
        parameter: names
            .iter()
            .position(|p| p.name == name)
            .unwrap_or_else(|| panic!("{name}")),
        value,
        distribution: pkm::accuracy::Distribution::Uniform,
    };
    let deg = 1f64.to_radians();
    let mut rows_43 = Vec::new();
    for (links, axes, value) in [
        (
            &["1 slide", "2 column", "3 spindle"][..],
            &["xx", "xy", "xz"][..],
            0.002 * deg,
        ),
        (
            &["4 tilting table", "5 face plate"][..],
            &["xz", "yz", "zz"][..],
            0.003 * deg,
        ),
        (&["0 bed"][..], &["xz", "yz", "zz"][..], 0.002 * deg),
    ] {
        for l in links {
            for a in axes {
                rows_43.push(by_name(&format!("alpha_{a}({l})"), value));
            }
        }
    }
    for (links, axes, value) in [
        (
            &["1 slide", "2 column", "3 spindle"][..],
            &["x", "y"][..],
            0.005,
        ),
        (&["1 slide", "2 column", "3 spindle"][..], &["z"][..], 0.01),
        (
            &["4 tilting table", "5 face plate"][..],
            &["x", "y"][..],
            0.005,
        ),
        (&["4 tilting table", "5 face plate"][..], &["z"][..], 0.003),
        (&["0 bed"][..], &["x", "y", "z"][..], 0.01),
    ] {
        for l in links {
            for a in axes {
                rows_43.push(by_name(&format!("delta_{a}({l})"), value));
            }
        }
    }
    for (j, v) in [
        ("X", 0.004),
        ("Y", 0.004),
        ("Z", 0.004),
        ("B", 0.003 * deg),
        ("C", 0.003 * deg),
    ] {
        rows_43.push(by_name(&format!("dq({j})"), v));
    }
    rows_43.push(by_name("theta_x0", 0.01 * deg));
    rows_43.push(by_name("theta_z0", 0.01 * deg));
    assert_eq!(rows_43.len(), 43);
    g.bench_function(
        format!(
            "MC-300 1e6 machines, c008e08's 43 tolerances, uncompleted (rayon, {} threads)",
            rayon::current_num_threads()
        ),
        |b| {
            b.iter(|| {
                pkm::accuracy::monte_carlo(mc300, &x300, &rows_43, 1_000_000, 1)
                    .unwrap()
                    .mean
            })
        },
    );
    // What `pkm errors` runs: the file's angles completed per sample (eq. 3).
    let given: Vec<usize> = s.tolerances.iter().map(|t| t.parameter).collect();
    let completed = mc300
        .with_given(&given)
        .unwrap()
        .expect("angles to complete");
    g.bench_function(
        format!("MC-300 1e6 machines, its file's 39 tolerances, completed per sample (rayon, {} threads)", rayon::current_num_threads()),
        |b| {
            b.iter(|| {
                pkm::accuracy::monte_carlo(&completed, &x300, &s.tolerances, 1_000_000, 1)
                    .unwrap()
                    .mean
            })
        },
    );
    g.finish();
    // The inverse of a robot's 6 x 6 Jacobian (each motion sample takes two): random
    // matrices with rows 3..6 times 1000 (angular rows scaled by a length), as in
    // `SerialArm`.
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(6);
    let jacobians: Vec<nalgebra::Matrix6<f64>> = (0..1024)
        .map(|_| {
            nalgebra::Matrix6::from_fn(|r, _| {
                rng.random_range(-1.0..1.0) * if r >= 3 { 1e3 } else { 1.0 }
            })
        })
        .collect();
    // A robot's inverse kinematics from X..C (what its controller is sent): the KR 30's
    // closed form, the posture nearest the home joints, at poses of random joints
    // within the ranges (clipped to +-3 rad).
    let kr = machine("kr30-dh.toml");
    let Model::Serial(kr) = &kr.model else {
        unreachable!("the KR 30 is a serial machine")
    };
    let pkm::serial::mechanism::SerialAny::Arm(arm) = &kr.mechanism else {
        unreachable!("the KR 30 has tool-pose coordinates")
    };
    let poses: Vec<Vector6<f64>> = (0..1024)
        .map(|_| {
            let q = Vector6::from_fn(|i, _| {
                let r = arm.info().actuators()[i].range;
                rng.random_range(r.min.max(-3.0)..r.max.min(3.0))
            });
            arm.coords_of_joints(&q)
        })
        .collect();
    c.bench_function(
        "KR 30 IK from X..C (closed form, nearest home), 1024 random poses, one thread",
        |b| {
            b.iter(|| {
                poses
                    .iter()
                    .filter_map(|x| arm.inverse(black_box(x)).ok())
                    .map(|q| q[0])
                    .sum::<f64>()
            })
        },
    );
    // The same robot in joint coordinates (a file's `pose = "joints"`, as every serial
    // machine without tool-pose or TCP coordinates): its tool pose is its forward
    // kinematics, what `pkm fk`, the maps and the views ask of it per state.
    let joints =
        pkm::serial::mechanism::SerialMechanism::<6>::new(arm.machine().clone(), arm.home_joints())
            .expect("six joints");
    let states: Vec<Vector6<f64>> = poses.iter().filter_map(|x| arm.inverse(x).ok()).collect();
    c.bench_function(
        "KR 30 in joint coordinates: tool pose (forward kinematics), 1024 random states, one thread",
        |b| {
            b.iter(|| {
                states
                    .iter()
                    .filter_map(|q| joints.tool_pose(black_box(q)).ok())
                    .map(|t| t.translation.vector.x)
                    .sum::<f64>()
            })
        },
    );
    let mut g = c.benchmark_group("6x6 inverse of 1024 random matrices");
    g.bench_function("nalgebra try_inverse", |b| {
        b.iter(|| {
            jacobians
                .iter()
                .map(|m| black_box(m).try_inverse().map_or(0.0, |i| i[(5, 5)]))
                .sum::<f64>()
        })
    });
    g.bench_function("pkm::linalg::inverse_lu (the same bits)", |b| {
        b.iter(|| {
            jacobians
                .iter()
                .map(|m| pkm::linalg::inverse_lu(black_box(m)).map_or(0.0, |i| i[(5, 5)]))
                .sum::<f64>()
        })
    });
    g.finish();
}

criterion_group!(serial_benches, serial);

fn accuracy(c: &mut Criterion) {
    // The generic engine on a parallel machine: seed 001's hexapod at
    // (0, 0, 550, 5 deg, 0, 0), +-10 um on its 36 joint coordinates and 6 zero lengths,
    // every sample rebuilt and solved by forward kinematics.
    let Model::Hexapod(h) = machine("hexapod-seed001.toml").model else {
        panic!()
    };
    let x = Vector6::new(0.0, 0.0, 550.0, 5f64.to_radians(), 0.0, 0.0);
    let tol: Vec<pkm::accuracy::Tolerance> = (0..42)
        .map(|k| pkm::accuracy::Tolerance {
            parameter: k,
            value: 0.01,
            distribution: pkm::accuracy::Distribution::Uniform,
        })
        .collect();
    // Joint clearances (seed 002): the bound along the tool axis with all 12 joints
    // in 0.02 mm balls (first-order states re-solved exactly; 3D length included).
    let joints = h.passive_joints();
    let clearances: Vec<_> = joints
        .iter()
        .map(|j| pkm::accuracy::clearance::JointClearance::spherical(j.name.clone(), 0.02))
        .collect();
    let regions = pkm::accuracy::clearance::regions(&joints, &clearances).unwrap();
    c.bench_function(
        "hexapod clearance bound at one pose, 12 joints (first order + exact)",
        |b| {
            b.iter(|| {
                pkm::accuracy::clearance::bounds(
                    h.as_ref(),
                    black_box(&x),
                    &regions,
                    &Default::default(),
                )
                .unwrap()
                .upper
            })
        },
    );
    // The hemisphere sweep (seed 002's Fig. 4) on the same hexapod: R = 75 mm, pole at
    // the home tool point, 1000 heights (only the cap the hexapod can tilt to is
    // reachable; the others are refused after the inverse kinematics).
    let surface = pkm::accuracy::clearance::surface::Hemisphere {
        radius: 75.0,
        centre: [
            0.0,
            0.0,
            h.tool_pose(&h.info().home()).unwrap().translation.vector.z - 75.0,
        ],
        azimuth: 0.0,
    };
    c.bench_function(
        "hexapod clearance bounds over a hemisphere, 1000 heights (rayon, 2 threads)",
        |b| {
            b.iter(|| {
                pkm::accuracy::clearance::surface::hemisphere_sweep(
                    h.as_ref(),
                    &surface,
                    &regions,
                    &Default::default(),
                    1000,
                )
                .unwrap()
                .len()
            })
        },
    );
    // Seed 002's own machine and part: the whole hemisphere (R = 75 mm on the table) is
    // reachable with the nozzle normal, 8 joints in the file's 0.1 mm balls.
    let Model::HybridAm(am) = machine("hybrid-am-seed002.toml").model else {
        panic!()
    };
    let joints = am.passive_joints();
    let clearances: Vec<_> = joints
        .iter()
        .map(|j| pkm::accuracy::clearance::JointClearance::spherical(j.name.clone(), 0.1))
        .collect();
    let am_regions = pkm::accuracy::clearance::regions(&joints, &clearances).unwrap();
    let part = pkm::accuracy::clearance::surface::Hemisphere {
        radius: 75.0,
        centre: [0.0; 3],
        azimuth: 0.0,
    };
    c.bench_function(
        "seed-002 machine clearance bounds over its hemisphere, 1000 heights, all reachable (rayon, 2 threads)",
        |b| {
            b.iter(|| {
                pkm::accuracy::clearance::surface::hemisphere_sweep(
                    am.as_ref(),
                    &part,
                    &am_regions,
                    &Default::default(),
                    1000,
                )
                .unwrap()
                .len()
            })
        },
    );
    let am_x = Vector6::new(75.0, 0.0, 0.0, 0.0, 90f64.to_radians(), 0.0);
    c.bench_function(
        "seed-002 machine clearance bound at the equator, 8 joints (first order + exact)",
        |b| {
            b.iter(|| {
                pkm::accuracy::clearance::bounds(
                    am.as_ref(),
                    black_box(&am_x),
                    &am_regions,
                    &Default::default(),
                )
                .unwrap()
                .upper
            })
        },
    );
    let mut g = c.benchmark_group("accuracy monte carlo");
    g.sample_size(10);
    let threads = rayon::current_num_threads();
    g.bench_function(
        format!("hexapod 1e6 machines, 42 tolerances (rayon, {threads} threads)"),
        |b| {
            b.iter(|| {
                pkm::accuracy::monte_carlo(h.as_ref(), &x, &tol, 1_000_000, 1)
                    .unwrap()
                    .mean
            })
        },
    );
    // What `pkm errors kr30-dh.toml --pose 1200,100,1400,180,0,0 --length-tolerance
    // 0.01 --joint-tolerance 0.01 --monte-carlo 100000` runs: the budget and 1e5
    // deviated robots (57 tolerances, one per kind; eight links completed per sample,
    // seed 003 eq. 3), on the global pool and on one thread.
    let kr = machine("kr30-dh.toml");
    let opt = pkm::analysis::accuracy::AccuracyOptions {
        pose: Some(vec![1200.0, 100.0, 1400.0, 180f64.to_radians(), 0.0, 0.0]),
        tolerances: pkm::analysis::accuracy::Tolerances::ByKind(Default::default()),
        monte_carlo: Some(100_000),
        ..Default::default()
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let run = || {
        pkm::analysis::accuracy::accuracy(&kr, black_box(&opt))
            .unwrap()
            .monte_carlo
            .map(|m| m.mean)
    };
    // The tolerances the options give (57: one per kind on every toleranced parameter).
    let budget_only = pkm::analysis::accuracy::AccuracyOptions {
        monte_carlo: None,
        ..opt.clone()
    };
    let n = pkm::analysis::accuracy::accuracy(&kr, &budget_only)
        .unwrap()
        .tolerances
        .len();
    g.bench_function(
        format!("KR 30 1e5 robots, {n} tolerances, with the budget (rayon, {threads} threads)"),
        |b| b.iter(run),
    );
    g.bench_function(
        format!("KR 30 1e5 robots, {n} tolerances, with the budget (one thread)"),
        |b| b.iter(|| one.install(run)),
    );
    g.finish();
}

criterion_group!(accuracy_benches, accuracy);

fn statics(c: &mut Criterion) {
    use pkm::statics::{actuator_forces, drive_stiffness, stiffness, Wrench};
    use rand::{Rng, SeedableRng};
    let machine = machine("hexapod-linuxcnc.toml");
    let Model::Hexapod(h) = &machine.model else {
        panic!()
    };
    let h = &**h;
    let k = drive_stiffness(h).unwrap();
    let x = Vector6::new(20.0, -10.0, 540.0, 0.05, -0.03, 0.1);
    let w = Wrench::from_array([200.0, -100.0, -1000.0, 5e3, -2e3, 1e4]);
    c.bench_function("hexapod static forces, one pose", |b| {
        b.iter(|| actuator_forces(h, black_box(&x), black_box(&w)).unwrap())
    });
    c.bench_function("hexapod stiffness unloaded, one pose", |b| {
        b.iter(|| stiffness(h, black_box(&x), &Wrench::default(), &k).unwrap())
    });
    c.bench_function("hexapod stiffness under a wrench, one pose", |b| {
        b.iter(|| stiffness(h, black_box(&x), black_box(&w), &k).unwrap())
    });
    // Random poses as a user's map has them: +-100 mm, +-10 deg about home.
    let mut rng = rand::rngs::StdRng::seed_from_u64(17);
    let home = h.info().home();
    let n = 100_000;
    let poses: Vec<f64> = (0..n)
        .flat_map(|_| {
            let mut p = home;
            for i in 0..6 {
                let r = if i < 3 { 100.0 } else { 10f64.to_radians() };
                p[i] += rng.random_range(-r..r);
            }
            p.iter().copied().collect::<Vec<_>>()
        })
        .collect();
    let mut g = c.benchmark_group("stiffness map");
    g.sample_size(10);
    g.throughput(criterion::Throughput::Elements(n as u64));
    g.bench_function(
        format!(
            "hexapod 1e5 random poses (rayon, {} threads)",
            rayon::current_num_threads()
        ),
        |b| {
            b.iter(|| {
                pkm::analysis::statics::stiffness_map(&machine, black_box(&poses), false)
                    .unwrap()
                    .failed
            })
        },
    );
    g.finish();
}

criterion_group!(statics_benches, statics, dynamics);

fn dynamics(c: &mut Criterion) {
    use nalgebra::Vector3 as V3;
    let robot = Machine::from_path(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/robots/ur5-like.urdf"
    ))
    .unwrap();
    let Model::Serial(s) = &robot.model else {
        panic!()
    };
    let chain = &s.mechanism.machine().tool;
    let q = [0.3, -1.1, 0.7, -0.4, 1.2, 0.5];
    let qd = [0.5, -0.2, 0.9, 1.5, -1.0, 2.0];
    let qdd = [3.0, -2.0, 1.0, 5.0, -4.0, 6.0];
    let mut tau = [0.0; 6];
    let g = pkm::serial::dynamics::GRAVITY;
    c.bench_function("UR5-class 6R inverse dynamics (RNEA), one state", |b| {
        b.iter(|| {
            pkm::serial::dynamics::inverse_dynamics_into(
                chain,
                [black_box(&q), &qd, &qdd],
                &g,
                [&V3::zeros(), &V3::zeros()],
                &mut tau,
            )
            .unwrap();
            tau[1]
        })
    });
}
