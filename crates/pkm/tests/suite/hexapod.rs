//! Hexapod: FK round trips over the workspace, Jacobian, singularity, limits.

use nalgebra::{Matrix3, Rotation3, Unit, Vector3, Vector6};
use pkm::hexapod::Hexapod;
use pkm::machine::Model;
use pkm::mechanism::{abilities, BlockKernels};
use pkm::rotation::Convention;
use pkm::verify::jacobian_error;
use pkm::{Error, LimitKind, Machine, Mechanism};
use rand::{Rng, SeedableRng};

fn load(name: &str) -> Hexapod {
    match Machine::from_path(format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .model
    {
        Model::Hexapod(h) => *h,
        _ => panic!(),
    }
}

fn within_limits(h: &Hexapod, x: &Vector6<f64>) -> bool {
    let q = h.inverse(x).unwrap();
    let mut v = Vec::new();
    h.check_limits(x, &q, &mut v);
    v.is_empty()
}

/// A random rotation tilting the spindle by at most `max_tilt`, with any spin about Z.
fn random_pose(
    rng: &mut rand::rngs::StdRng,
    centre: &Vector3<f64>,
    half: f64,
    dz: f64,
    max_tilt: f64,
) -> Vector6<f64> {
    let az: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let tilt: f64 = rng.random_range(0.0..max_tilt);
    let spin: f64 = rng.random_range(-0.5..0.5);
    let axis = Unit::new_normalize(Vector3::new(az.cos(), az.sin(), 0.0));
    let r: Matrix3<f64> = *(Rotation3::from_axis_angle(&axis, tilt)
        * Rotation3::from_axis_angle(&Vector3::z_axis(), spin))
    .matrix();
    let a = Convention::Rpy.from_matrix(&r);
    Vector6::new(
        centre.x + rng.random_range(-half..half),
        centre.y + rng.random_range(-half..half),
        centre.z + rng.random_range(-dz..dz),
        a[0],
        a[1],
        a[2],
    )
}

fn pose_error(h: &Hexapod, a: &Vector6<f64>, b: &Vector6<f64>) -> (f64, f64) {
    let pa = h.tool_pose(a).unwrap();
    let pb = h.tool_pose(b).unwrap();
    let dp = (pa.translation.vector - pb.translation.vector).norm();
    let ra = *pa.rotation.to_rotation_matrix().matrix();
    let rb = *pb.rotation.to_rotation_matrix().matrix();
    (dp, pkm::rotation::angle_between(&ra, &rb))
}

/// FK(IK(p)) = p within 1e-9 mm and 1e-9 rad for 10^5 random poses within every limit
/// (tilts up to 30 deg), from a start within 10 mm / 5 deg and from home; every solve
/// converges to the right pose; median linear solves from the nearby start <= 4.
#[test]
fn round_trip_100k_poses() {
    for (file, centre, half, dz) in [
        (
            "hexapod-linuxcnc.toml",
            Vector3::new(0.0, 0.0, 560.0),
            120.0,
            90.0,
        ),
        (
            "hexapod-seed001.toml",
            Vector3::new(0.0, 0.0, 580.0),
            150.0,
            120.0,
        ),
    ] {
        let h = load(file);
        let mut rng = rand::rngs::StdRng::seed_from_u64(1);
        let mut near_iters = Vec::new();
        let mut n = 0;
        let mut worst = (0.0f64, 0.0f64);
        while n < 50_000 {
            let x = random_pose(&mut rng, &centre, half, dz, 30f64.to_radians());
            if !within_limits(&h, &x) {
                continue;
            }
            n += 1;
            let q = h.inverse(&x).unwrap();
            // Nearby start: within 10 mm and 5 deg.
            let dir = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            let dp = dir.normalize() * rng.random_range(0.0..10.0);
            let (p, r) = pkm::legs::split_pose(&x);
            let axis = Unit::new_normalize(Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ));
            let r0 = Rotation3::from_axis_angle(&axis, rng.random_range(0.0..5f64.to_radians()))
                .matrix()
                * r;
            let a0 = Convention::Rpy.from_matrix(&r0);
            let p0 = p + dp;
            let near = Vector6::new(p0.x, p0.y, p0.z, a0[0], a0[1], a0[2]);
            for start in [near, h.info().home()] {
                let f = h
                    .forward(&q, &start)
                    .unwrap_or_else(|e| panic!("{file}: {e} at {x}"));
                let (ep, er) = pose_error(&h, &f.pose, &x);
                worst = (worst.0.max(ep), worst.1.max(er));
                assert!(ep < 1e-9 && er < 1e-9, "{file}: {ep} mm {er} rad at {x}");
                if start == near {
                    near_iters.push(f.iterations);
                }
            }
        }
        near_iters.sort();
        let median = near_iters[near_iters.len() / 2];
        let mean = near_iters.iter().sum::<usize>() as f64 / near_iters.len() as f64;
        eprintln!("{file}: {n} poses, worst {:.2e} mm {:.2e} rad, median {median} solves (mean {mean:.2}) from a nearby start", worst.0, worst.1);
        assert!(median <= 4, "{file}: median {median}");
    }
}

#[test]
fn jacobian_matches_finite_differences() {
    let h = load("hexapod-linuxcnc.toml");
    let mut rng = rand::rngs::StdRng::seed_from_u64(2);
    for _ in 0..200 {
        let x = random_pose(&mut rng, &Vector3::new(0.0, 0.0, 560.0), 100.0, 80.0, 0.5);
        let e = jacobian_error(&h, &x).unwrap();
        assert!(e < 1e-6, "{e}");
    }
}

#[test]
fn singular_configuration_is_reported() {
    // Platform in the base plane: every strut horizontal, so no strut can resist a
    // vertical force: the Jacobian loses rank (v_z, w_x, w_y columns vanish).
    let h = load("hexapod-linuxcnc.toml");
    let flat = Vector6::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    let q = h.inverse(&flat).unwrap();
    let r = h.forward(&q, &flat);
    assert!(matches!(r, Err(Error::Singular { .. })), "{r:?}");
    // Started slightly off it, the solver does not return a pose either.
    let near = Vector6::new(0.0, 0.0, 1.0, 0.0, 0.0, 0.0);
    let r = h.forward(&q, &near);
    assert!(
        matches!(
            r,
            Err(Error::Singular { .. }) | Err(Error::NotConverged { .. })
        ),
        "{r:?}"
    );
    // Unreachable lengths: not converged, with the residual.
    let r = h.forward(&Vector6::repeat(100.0), &h.info().home());
    assert!(r.is_err(), "{r:?}");
}

#[test]
fn genhexkins_home_lengths() {
    let h = load("hexapod-linuxcnc.toml");
    let q = h.inverse(&h.info().home()).unwrap();
    for l in q.iter() {
        assert!((l - 29.7466 * 25.4).abs() < 0.01, "{l}");
    }
}

#[test]
fn joint_cone_and_interference_limits() {
    let h = load("hexapod-linuxcnc.toml");
    // Far off to the side: the base joints tilt beyond 60 deg.
    let x = Vector6::new(600.0, 0.0, 300.0, 0.0, 0.0, 0.0);
    let q = h.inverse(&x).unwrap();
    let mut v = Vec::new();
    h.check_limits(&x, &q, &mut v);
    assert!(v.iter().any(|v| v.kind == LimitKind::JointAngle), "{v:?}");
    // Strut interference: at a spun pose, a diameter just above the closest approach
    // of two struts that share no joint is violated, just below it is not.
    let mut h = h;
    let x = Vector6::new(0.0, 0.0, 508.0, 0.0, 0.0, 40f64.to_radians());
    let q = h.inverse(&x).unwrap();
    let sk = h.skeleton(&x).unwrap();
    let strut = |i: usize| {
        let l = &sk.links[i];
        (
            Vector3::from(sk.points[l.from].position),
            Vector3::from(sk.points[l.to].position),
        )
    };
    let mut dmin = f64::INFINITY;
    for i in 0..6 {
        for k in i + 1..6 {
            if h.hex_struts()[i].base_name == h.hex_struts()[k].base_name
                || h.hex_struts()[i].platform_name == h.hex_struts()[k].platform_name
            {
                continue;
            }
            let (a0, a1) = strut(i);
            let (b0, b1) = strut(k);
            dmin = dmin.min(pkm::hexapod::segment_distance(&a0, &a1, &b0, &b1));
        }
    }
    let count = |h: &Hexapod| {
        let mut v = Vec::new();
        h.check_limits(&x, &q, &mut v);
        v.iter()
            .filter(|v| v.kind == LimitKind::StrutInterference)
            .count()
    };
    h.set_strut_diameter(Some(dmin + 0.5));
    assert!(count(&h) >= 1, "dmin {dmin}");
    h.set_strut_diameter(Some(dmin - 0.5));
    assert_eq!(count(&h), 0);
}

#[test]
fn segment_distance_by_hand() {
    use pkm::hexapod::segment_distance;
    let d = segment_distance(
        &Vector3::zeros(),
        &Vector3::x(),
        &Vector3::new(0.5, 1.0, -1.0),
        &Vector3::new(0.5, 1.0, 1.0),
    );
    assert!((d - 1.0).abs() < 1e-15);
    let d = segment_distance(
        &Vector3::zeros(),
        &Vector3::x(),
        &Vector3::new(2.0, 1.0, 0.0),
        &Vector3::new(3.0, 1.0, 0.0),
    );
    assert!((d - 2f64.sqrt()).abs() < 1e-15);
}

#[test]
fn assembly_modes_from_several_starts() {
    use pkm::mechanism::{assembly_modes, spread_starts};
    let h = load("hexapod-linuxcnc.toml");
    let x = h.info().home();
    let q = h.inverse(&x).unwrap();
    let starts = spread_starts(&h, 300);
    let modes = assembly_modes(&h, &q, &starts, 1e-6);
    // The home pose comes first; its mirror image through the base plane (all base
    // joints at Z = 0) is another assembly with the same strut lengths.
    assert!(modes.len() >= 2, "{} modes", modes.len());
    assert!((modes[0].pose - x).amax() < 1e-9);
    assert!(modes
        .iter()
        .any(|f| (f.pose[2] + x[2]).abs() < 1e-6 && f.pose[0].abs() < 1e-6));
    for f in &modes {
        assert!((h.inverse(&f.pose).unwrap() - q).amax() < 1e-9);
    }
    eprintln!(
        "LinuxCNC hexapod at home: {} assembly modes from 300 starts",
        modes.len()
    );
}

#[test]
fn transmission_figures_of_the_hexapod() {
    let h = load("hexapod-linuxcnc.toml");
    let x = h.info().home();
    let t = pkm::transmission::transmission(&h, &x).unwrap();
    assert!((t.condition - h.condition(&x).unwrap()).abs() < 1e-6 * t.condition);
    // Independently, by directions over the sphere: the largest strut rate per unit
    // tool speed |J_v u|, and the largest strut force for a unit tool force f with no
    // moment, from the statics J^T tau = (f, 0) (at zero angles the coordinate
    // Jacobian is the twist Jacobian).
    let (p, r) = pkm::legs::split_pose(&x);
    let jt = h.strut_set().twist_jacobian(&p, &r);
    let jt_t = jt.transpose().try_inverse().unwrap();
    let (mut vmax, mut fmax) = (0.0f64, 0.0f64);
    let n = 20_000;
    for k in 0..n {
        // Fibonacci sphere.
        let z = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
        let a = k as f64 * std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let u = Vector3::new(
            (1.0 - z * z).sqrt() * a.cos(),
            (1.0 - z * z).sqrt() * a.sin(),
            z,
        );
        vmax = vmax.max((jt.fixed_view::<6, 3>(0, 0) * u).norm());
        let w = Vector6::new(u.x, u.y, u.z, 0.0, 0.0, 0.0);
        fmax = fmax.max((jt_t * w).norm());
    }
    let (v, f) = (t.velocity.unwrap(), t.force.unwrap());
    assert!(
        vmax <= v * (1.0 + 1e-12) && vmax >= v * 0.999,
        "{vmax} vs {v}"
    );
    assert!(
        fmax <= f * (1.0 + 1e-12) && fmax >= f * 0.999,
        "{fmax} vs {f}"
    );
    // Approaching the flat singular configuration the distance to singularity
    // vanishes.
    let mut prev = t.distance_to_singularity;
    for z in [300.0, 100.0, 30.0, 10.0] {
        let y = Vector6::new(0.0, 0.0, z, 0.0, 0.0, 0.0);
        let d = pkm::transmission::transmission(&h, &y)
            .unwrap()
            .distance_to_singularity;
        assert!(d < prev, "{z}: {d} vs {prev}");
        prev = d;
    }
    assert!(prev < 0.05, "{prev}");
}

#[test]
fn batch_lengths_equal_single_pose_lengths() {
    let h = load("hexapod-seed001.toml");
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let n = 1000 + 5; // not a multiple of the lane count
    let poses: Vec<Vector6<f64>> = (0..n)
        .map(|_| random_pose(&mut rng, &Vector3::new(0.0, 0.0, 580.0), 150.0, 120.0, 0.5))
        .collect();
    let (ps, rs): (Vec<_>, Vec<_>) = poses.iter().map(pkm::legs::split_pose).unzip();
    let mut out = vec![Vector6::zeros(); n];
    h.lengths_batch(&ps, &rs, &mut out);
    for (k, x) in poses.iter().enumerate() {
        let q = h.inverse(x).unwrap();
        assert!((out[k] - q).amax() < 1e-12, "{k}");
    }
}

#[test]
fn per_joint_cone_axes() {
    let path = format!(
        "{}/../../examples/machines/hexapod-seed001.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let with = |extra: &str| {
        let t = text.replacen(
            "strut_diameter = 60.0",
            &format!("strut_diameter = 60.0\n{extra}"),
            1,
        );
        Machine::from_toml_str(&t, "hex.toml")
    };
    let violations = |m: &Machine| {
        let Model::Hexapod(h) = &m.model else {
            panic!()
        };
        let x = h.info().home();
        let q = h.inverse(&x).unwrap();
        let mut v = Vec::new();
        h.check_limits(&x, &q, &mut v);
        v
    };
    assert!(violations(&with("").unwrap()).is_empty());
    // Joint A1's own axis lies horizontal: its strut is far outside its 50 deg cone,
    // the other base joints keep the common vertical axis.
    let m = with("base_joint_axes = { A1 = [1.0, 0.0, 0.0] }").unwrap();
    let v = violations(&m);
    assert!(!v.is_empty());
    assert!(
        v.iter()
            .all(|v| v.kind == LimitKind::JointAngle && v.limit.contains("A1")),
        "{v:?}"
    );
    // Each joint's axis along its strut at home: every angle is zero there.
    let Model::Hexapod(h) = &with("").unwrap().model else {
        panic!()
    };
    let (p, r) = pkm::legs::split_pose(&h.info().home());
    let joints = h.strut_set().platform_joints(&p, &r);
    let axes: Vec<String> = (0..6)
        .map(|i| {
            let d = (joints[i] - h.hex_struts()[i].base).normalize();
            format!(
                "{} = [{}, {}, {}]",
                h.hex_struts()[i].base_name,
                d.x,
                d.y,
                d.z
            )
        })
        .collect();
    // Struts share no base joint in this file, so every joint gets one axis.
    let m = with(&format!(
        "base_joint_max_angle_unused = 0\nbase_joint_axes = {{ {} }}",
        axes.join(", ")
    ));
    assert!(m
        .unwrap_err()
        .to_string()
        .contains("base_joint_max_angle_unused"));
    let t = text.replacen(
        "base_joint_max_angle = 50.0",
        "base_joint_max_angle = 1.0",
        1,
    );
    let t = t.replacen(
        "strut_diameter = 60.0",
        &format!(
            "strut_diameter = 60.0\nbase_joint_axes = {{ {} }}",
            axes.join(", ")
        ),
        1,
    );
    let m = Machine::from_toml_str(&t, "hex.toml").unwrap();
    assert!(violations(&m).is_empty(), "{:?}", violations(&m));
    // Errors name the field.
    let e = with("base_joint_axes = { Z9 = [0.0, 0.0, 1.0] }")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("limits.base_joint_axes.Z9") && e.contains("unknown base joint"),
        "{e}"
    );
    let e = with("platform_joint_axes = { B1 = [0.0, 0.0, 0.0] }")
        .unwrap_err()
        .to_string();
    assert!(e.contains("non-zero"), "{e}");
}

#[test]
fn tracking_fk_follows_a_trajectory_and_survives_jumps() {
    use pkm::hexapod::{FkOptions, FkTracker};
    for file in ["hexapod-linuxcnc.toml", "hexapod-seed001.toml"] {
        let h = load(file);
        let home = h.info().home();
        // 2 s at 1 kHz: a circle of radius 40 mm at 100 mm/s with a slow tilt.
        let pose = |k: usize| {
            let t = k as f64 * 1e-3;
            let a = 2.5 * t;
            Vector6::new(
                home[0] + 40.0 * a.cos() - 40.0,
                home[1] + 40.0 * a.sin(),
                home[2] + 10.0 * t,
                0.05 * (3.0 * t).sin(),
                0.04 * t,
                home[5] + 0.02 * t,
            )
        };
        let mut tr = FkTracker::new(&pose(0), FkOptions::default());
        let mut solves = 0;
        for k in 0..2000 {
            let x = pose(k);
            let q = h.inverse(&x).unwrap();
            let rep = tr.track(&h, &q).unwrap();
            solves += rep.iterations;
            let (ep, er) = {
                let (p, r) = pkm::legs::split_pose(&x);
                (
                    (rep.position - p).norm(),
                    pkm::rotation::angle_between(&rep.rotation, &r),
                )
            };
            assert!(
                ep < 1e-9 && er < 1e-9,
                "{file} sample {k}: {ep} mm {er} rad"
            );
        }
        let mean = solves as f64 / 2000.0;
        assert!(mean <= 4.0, "{file}: mean {mean} solves");
        // A jump of 60 mm and 10 deg: still the right pose.
        let x = Vector6::new(
            home[0] + 60.0,
            home[1] - 20.0,
            home[2] + 30.0,
            0.17,
            -0.1,
            home[5],
        );
        let rep = tr.track(&h, &h.inverse(&x).unwrap()).unwrap();
        let (p, _) = pkm::legs::split_pose(&x);
        assert!((rep.position - p).norm() < 1e-9);
        eprintln!("{file}: tracking FK, mean {mean:.2} linear solves per sample");
    }
}

#[test]
fn simd_lengths_equal_portable_lengths() {
    // On a CPU with AVX-512F, lengths use the rsqrt14 + Newton kernel: within a few
    // units in the last place of the portable sqrt.
    for file in ["hexapod-linuxcnc.toml", "hexapod-seed001.toml"] {
        let h = load(file);
        eprintln!("{file}: AVX-512 lengths {}", h.simd_lengths());
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let mut worst = 0.0f64;
        for _ in 0..100_000 {
            let x = random_pose(&mut rng, &Vector3::new(0.0, 0.0, 560.0), 400.0, 300.0, 1.0);
            let (p, r) = pkm::legs::split_pose(&x);
            let a = h.lengths(&p, &r);
            let b = h.lengths_portable(&p, &r);
            for i in 0..6 {
                worst = worst.max((a[i] - b[i]).abs() / b[i]);
            }
        }
        assert!(worst <= 1e-15, "{file}: {worst:e}");
    }
}

/// The one-pass lengths from X..C equal the lengths of the split pose bit for bit:
/// random poses, zero angles (the identity), angles beyond the AVX-512 kernel's range
/// and NaN (the portable path).
#[test]
fn pose_lengths_equal_the_lengths_of_the_split_pose() {
    for file in ["hexapod-linuxcnc.toml", "hexapod-seed001.toml"] {
        let h = load(file);
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let mut xs: Vec<Vector6<f64>> = (0..100_000)
            .map(|_| random_pose(&mut rng, &Vector3::new(0.0, 0.0, 560.0), 400.0, 300.0, 1.0))
            .collect();
        xs.extend([
            Vector6::new(10.0, -5.0, 540.0, 0.0, 0.0, 0.0),
            Vector6::new(10.0, -5.0, 540.0, 0.0, -0.0, 0.2),
            Vector6::new(10.0, -5.0, 540.0, 2e4, 0.1, 0.2),
            Vector6::new(10.0, -5.0, 540.0, 0.1, -1e4, 1e4),
            Vector6::new(10.0, -5.0, 540.0, f64::NAN, 0.1, 0.2),
        ]);
        for x in &xs {
            let (p, r) = pkm::legs::split_pose(x);
            let a = h.pose_lengths(x);
            let b = h.lengths(&p, &r);
            let c = Mechanism::<6, 6>::inverse(&h, x).unwrap();
            for i in 0..6 {
                assert!(
                    a[i].to_bits() == b[i].to_bits() && c[i].to_bits() == b[i].to_bits()
                        || a[i].is_nan() && b[i].is_nan() && c[i].is_nan(),
                    "{file} {x:?}: {} {} {}",
                    a[i],
                    b[i],
                    c[i]
                );
            }
        }
    }
}

#[test]
fn joint_centres_moved_in_place_equal_a_rebuilt_machine() {
    use pkm::identify::struts::StrutMachine;
    // The LinuxCNC hexapod's arms lie in the platform's plane (the kernels' planar
    // case), until its joints move; seed 001's tool is 150 mm off that plane.
    for file in ["hexapod-seed001.toml", "hexapod-linuxcnc.toml"] {
        let h = load(file);
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let mut moved = h.clone();
        for _ in 0..3 {
            let mut s = h.struts();
            for st in s.iter_mut() {
                st.base += Vector3::from_fn(|_, _| rng.random_range(-0.5..0.5));
                st.platform += Vector3::from_fn(|_, _| rng.random_range(-0.5..0.5));
            }
            let rebuilt = h.with_struts(&s);
            moved.set_joint_centres(
                &std::array::from_fn(|j| s[j].base),
                &std::array::from_fn(|j| s[j].platform),
            );
            // Every derived field (strut set, SIMD lanes and whether their arms are
            // planar, characteristic length) too.
            assert_eq!(moved, rebuilt, "{file}");
            let x = Vector6::new(12.0, -30.0, 560.0, 0.1, -0.05, 0.3);
            let (p, r) = pkm::legs::split_pose(&x);
            let q = Mechanism::<6, 6>::inverse(&moved, &x).unwrap();
            for j in 0..6 {
                let by_hand = (p + r * (s[j].platform - h.tool()) - s[j].base).norm();
                assert!((q[j] - by_hand).abs() <= 1e-12 * by_hand, "{file} {j}");
            }
        }
        let s = h.struts();
        moved.set_joint_centres(
            &std::array::from_fn(|j| s[j].base),
            &std::array::from_fn(|j| s[j].platform),
        );
        assert_eq!(moved, h, "{file}: moved back");
    }
}

#[test]
fn axis_travel_is_checked_and_kept_by_a_rebuilt_hexapod() {
    use pkm::identify::struts::StrutMachine;
    let text = std::fs::read_to_string(format!(
        "{}/../../examples/machines/hexapod-linuxcnc.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace(
        "strut_diameter = 25.0",
        "strut_diameter = 25.0\naxes = { Z = [400, 700], A = [-20, 20] }",
    );
    let h = match Machine::from_toml_str(&text, "axes.toml").unwrap().model {
        Model::Hexapod(h) => *h,
        _ => panic!(),
    };
    let x = Vector6::new(0.0, 0.0, 720.0, 25f64.to_radians(), 0.0, 0.0);
    for m in [h.clone(), h.with_struts(&h.struts())] {
        let mut v = Vec::new();
        m.check_limits(&x, &m.inverse(&x).unwrap(), &mut v);
        let axes: Vec<String> = v
            .iter()
            .filter(|v| v.kind == LimitKind::AxisTravel)
            .map(|v| v.to_string())
            .collect();
        assert_eq!(
            axes,
            [
                "axis Z travel 720.000 mm is above its maximum 700.000 mm by 20.000 mm",
                "axis A travel 25.000 deg is above its maximum 20.000 deg by 5.000 deg"
            ]
        );
    }
}

/// Limits that random poses hit in every family: with `open`, nothing but thick struts
/// (interference comes first); else travel on two axes besides the file's limits.
fn limits_to_hit(h: &mut Hexapod, open: bool) {
    use pkm::limits::Range;
    if open {
        let mut struts = h.hex_struts().clone();
        for s in &mut struts {
            s.actuator.range = Range { min: 0.0, max: 1e5 };
            s.base_cone = None;
            s.platform_cone = None;
        }
        h.set_struts(struts);
        h.set_strut_diameter(Some(150.0));
    } else {
        let mut axes = h.axes().clone();
        axes.ranges.push((
            0,
            Range {
                min: -60.0,
                max: 60.0,
            },
        ));
        axes.ranges.push((
            4,
            Range {
                min: -0.3,
                max: 0.3,
            },
        ));
        h.set_axes(axes);
    }
}

/// The batch's first violated limit comes as a code, named once per distinct limit
/// (for the batch's speed): code and name must be the first violation `check_limits`
/// reports, for every family of limit (axis travel, strut lengths, both cones,
/// interference), over poses that hit each of them.
#[test]
fn coded_first_limits_are_the_first_checked_violation() {
    use pkm::limits::FirstLimit;
    let mut hits = std::collections::BTreeMap::new();
    for (name, open) in [
        ("hexapod-linuxcnc.toml", false),
        ("hexapod-seed001.toml", false),
        ("hexapod-seed001.toml", true),
    ] {
        let mut h = load(name);
        limits_to_hit(&mut h, open);
        let home = h.info().home();
        let centre = Vector3::new(home[0], home[1], home[2]);
        let mut rng = rand::rngs::StdRng::seed_from_u64(21);
        let mut buf = Vec::new();
        for _ in 0..40_000 {
            let x = random_pose(&mut rng, &centre, 200.0, 200.0, 0.9);
            let q = h.inverse(&x).unwrap();
            let mut all = Vec::new();
            h.check_limits(&x, &q, &mut all);
            let (q2, first) = abilities::inverse_first_limit(&h, &x, &mut buf).unwrap();
            assert_eq!(q, q2);
            let coded = first.map(|f| match f {
                FirstLimit::Code(c) => BlockKernels::limit_violation(&h, &c),
                FirstLimit::Violation(_) => panic!("the hexapod codes its limits"),
            });
            assert_eq!(coded.as_ref(), all.first(), "{name} {x:?}");
            assert_eq!(
                abilities::inverse_first_violation(&h, &x, &mut buf)
                    .unwrap()
                    .1,
                coded
            );
            if let Some(v) = coded {
                *hits.entry(format!("{:?}", v.kind)).or_insert(0) += 1;
            }
        }
    }
    for family in [
        "AxisTravel",
        "ActuatorPosition",
        "JointAngle",
        "StrutInterference",
    ] {
        assert!(
            hits.get(family).copied().unwrap_or(0) > 10,
            "{family}: {hits:?}"
        );
    }
}

/// The block kernel's screen changes no result (it is there for speed): over random poses,
/// poses bisected onto the boundary of the limits to 1e-13 of the step (whichever
/// limit binds), exact axis bounds, NaN and angles beyond the fast sine's range, a
/// cleared row is one the exact scan finds within every limit, its lengths are the
/// single call's bit for bit, and the batch equals the single calls row by row.
/// The screen must also clear most rows that are within limits (else it is no
/// faster).
#[test]
fn screened_batch_equals_the_exact_path_on_and_near_every_limit() {
    use pkm::limits::FirstLimit;
    for (name, open) in [
        ("hexapod-linuxcnc.toml", false),
        ("hexapod-seed001.toml", false),
        ("hexapod-seed001.toml", true),
    ] {
        let mut machine = Machine::from_path(format!(
            "{}/../../examples/machines/{name}",
            env!("CARGO_MANIFEST_DIR")
        ))
        .unwrap();
        let Model::Hexapod(h) = &mut machine.model else {
            panic!()
        };
        limits_to_hit(h, open);
        let Model::Hexapod(h) = &machine.model else {
            panic!()
        };
        let h: &Hexapod = h;
        let home = h.info().home();
        let centre = Vector3::new(home[0], home[1], home[2]);
        let mut rng = rand::rngs::StdRng::seed_from_u64(33);
        let mut buf = Vec::new();
        let fine = |x: &Vector6<f64>, buf: &mut Vec<_>| {
            abilities::inverse_first_limit(h, x, buf)
                .unwrap()
                .1
                .is_none()
        };
        let mut poses: Vec<Vector6<f64>> = Vec::new();
        // Rows drawn at random (not on a boundary by construction).
        let mut random = Vec::new();
        for k in 0..6000 {
            let x = random_pose(&mut rng, &centre, 200.0, 200.0, 0.9);
            if k % 2 == 0 || !fine(&home, &mut buf) {
                random.push(poses.len());
                poses.push(x);
                continue;
            }
            // Bisect home -> x onto the first limit met, and keep both sides.
            let (mut lo, mut hi) = (0.0, 1.0);
            if fine(&x, &mut buf) {
                poses.push(x);
                continue;
            }
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if fine(&(home + (x - home) * mid), &mut buf) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            poses.push(home + (x - home) * lo);
            poses.push(home + (x - home) * hi);
        }
        // Exactly on an axis bound, NaN, angles beyond 1e4 rad.
        let mut on = home;
        on[0] = 60.0;
        poses.push(on);
        on[4] = -0.3;
        poses.push(on);
        let mut nan = home;
        nan[3] = f64::NAN;
        poses.push(nan);
        let mut far = home;
        far[5] = 2e4 * std::f64::consts::TAU;
        poses.push(far);
        let n = poses.len() - poses.len() % 8 + 8;
        while poses.len() < n {
            poses.push(home);
        }
        let flat: Vec<f64> = poses.iter().flat_map(|x| x.iter().copied()).collect();
        let mut qs = vec![0.0; 6 * n];
        let mut clear = vec![false; n];
        let kernel = abilities::inverse_screened(h, &flat, &mut qs, &mut clear, true);
        if !kernel {
            eprintln!("no block kernel at this SIMD level: the per-pose path only");
            clear.fill(false);
            qs.clear();
        }
        let batch = pkm::analysis::batch::inverse_batch(&machine, &flat).unwrap();
        let (mut within, mut cleared) = (0, 0);
        for (r, x) in poses.iter().enumerate() {
            let (q, first) = abilities::inverse_first_limit(h, x, &mut buf).unwrap();
            let ok = first.is_none();
            if x.iter().all(|v| v.is_finite()) && !qs.is_empty() {
                // The kernel's lengths are the single call's, bit for bit.
                for i in 0..6 {
                    assert_eq!(qs[6 * r + i].to_bits(), q[i].to_bits(), "{name} row {r}");
                    assert_eq!(batch.actuators[6 * r + i].to_bits(), q[i].to_bits());
                }
            }
            assert!(!clear[r] || ok, "{name} row {r}: cleared but {first:?}");
            assert_eq!(batch.reachable[r], ok, "{name} row {r}");
            let v = first.map(|f| match f {
                FirstLimit::Code(c) => BlockKernels::limit_violation(h, &c),
                FirstLimit::Violation(v) => v,
            });
            assert_eq!(batch.causes.violation(r), v, "{name} row {r}");
        }
        for &r in &random {
            let ok = batch.reachable[r];
            within += usize::from(ok);
            cleared += usize::from(clear[r] && ok);
        }
        // Without a block kernel nothing is cleared: the per-pose path settles all.
        assert!(
            within >= 100 && (!kernel || cleared as f64 > 0.99 * within as f64),
            "{name}: {within} of {} random rows within limits, {cleared} cleared",
            random.len()
        );
        let within: Vec<bool> = random.iter().map(|&r| batch.reachable[r]).collect();
        motion_kernel_equals_the_exact_path(name, h, &poses, &random, &within);
        // Without the check the screen settles every row but the NaN one and the one
        // with an angle beyond the fast sine's range (on a CPU with AVX-512; without
        // it there is no block kernel).
        if abilities::inverse_screened(h, &flat, &mut qs, &mut clear, false) {
            for (r, x) in poses.iter().enumerate() {
                let fast = x.iter().all(|v| v.abs() <= 1e4);
                assert_eq!(clear[r], fast, "{name} row {r}");
            }
            // Blocks go two per call and the odd one alone: an even and an odd number
            // of blocks, and rows past the last whole block, give the single call's
            // lengths bit for bit.
            for rows in [n, n - 8, n - 3] {
                let (mut q, mut c) = (vec![f64::NAN; 6 * rows], vec![true; rows]);
                assert!(abilities::inverse_screened(
                    h,
                    &flat[..6 * rows],
                    &mut q,
                    &mut c,
                    false
                ));
                for (r, x) in poses[..rows].iter().enumerate() {
                    let whole = r < rows / 8 * 8;
                    let fast = x.iter().all(|v| v.abs() <= 1e4);
                    assert_eq!(c[r], whole && fast, "{name} {rows} rows, row {r}");
                    if c[r] {
                        let single = h.pose_lengths(x);
                        for i in 0..6 {
                            assert_eq!(q[6 * r + i].to_bits(), single[i].to_bits());
                        }
                    }
                }
            }
            let b = pkm::analysis::batch::inverse_batch_with(&machine, &flat, false).unwrap();
            assert!(b.reachable.iter().all(|r| *r));
            // The same lengths with and without the check.
            for (u, v) in b.actuators.iter().zip(&batch.actuators) {
                assert!(u.to_bits() == v.to_bits() || (u.is_nan() && v.is_nan()));
            }
        }
    }
}

/// The motion kernel (`BlockKernels::motion_screened`, eight samples per AVX-512
/// register) on `poses` with random rates and accelerations: a cleared row's `q`,
/// `q'`, `q''` are `actuator_motion`'s bit for bit and `actuator_motion_checked` finds
/// no violation on it; rows with held angles (no angular rate), level poses
/// (A = B = C = 0) and rows at rest take the scalar path's shortcuts alike; and the
/// kernel clears at least 99 % of the random rows (`random`) that are `within` limits.
fn motion_kernel_equals_the_exact_path(
    name: &str,
    h: &Hexapod,
    poses: &[Vector6<f64>],
    random: &[usize],
    within: &[bool],
) {
    let mut rng = rand::rngs::StdRng::seed_from_u64(34);
    let n = poses.len();
    let mut x = poses.to_vec();
    let (mut xd, mut xdd) = (Vec::new(), Vec::new());
    for (r, x) in x.iter_mut().enumerate() {
        let mut v = Vector6::from_fn(|_, _| rng.random_range(-80.0..80.0));
        let mut a = Vector6::from_fn(|_, _| rng.random_range(-900.0..900.0));
        match r % 7 {
            // Held angles: exact zeros for the angular motion.
            0 => (3..6).for_each(|k| (v[k], a[k]) = (0.0, 0.0)),
            // A level pose (the exact identity) moving.
            1 if r % 2 == 1 => (3..6).for_each(|k| x[k] = 0.0),
            // At rest.
            2 => (v, a) = (Vector6::zeros(), Vector6::zeros()),
            // Only an angular acceleration.
            3 => (3..6).for_each(|k| v[k] = 0.0),
            _ => {
                v.fixed_rows_mut::<3>(3).scale_mut(1e-3);
                a.fixed_rows_mut::<3>(3).scale_mut(1e-3);
            }
        }
        xd.push(v);
        xdd.push(a);
    }
    let flat =
        |v: &[Vector6<f64>]| -> Vec<f64> { v.iter().flat_map(|x| x.iter().copied()).collect() };
    let rows = [flat(&x), flat(&xd), flat(&xdd)];
    let mut q = [
        vec![f64::NAN; 6 * n],
        vec![f64::NAN; 6 * n],
        vec![f64::NAN; 6 * n],
    ];
    let mut clear = vec![false; n];
    let mut computed = vec![false; n];
    let [q0, q1, q2] = &mut q;
    if !abilities::motion_screened(
        h,
        [&rows[0], &rows[1], &rows[2]],
        [q0, q1, q2],
        &mut clear,
        &mut computed,
    ) {
        eprintln!("no AVX-512 on this CPU: the per-sample path only");
        return;
    }
    let mut buf = Vec::new();
    let mut level = 0;
    let mut beyond = 0;
    for r in 0..n {
        assert!(
            computed[r] || !clear[r],
            "{name} row {r}: cleared, not computed"
        );
        // Computed wherever the angles are within the fast sine's range (a row past
        // the last whole block of eight is left to the per-sample path).
        let fast = x[r].fixed_rows::<3>(3).iter().all(|v| v.abs() <= 1e4);
        assert_eq!(computed[r], fast && r < n / 8 * 8, "{name} row {r}");
        if !computed[r] {
            continue;
        }
        // Every computed row's motion is the per-sample path's, cleared or not.
        let want = h.actuator_motion(&x[r], &xd[r], &xdd[r]).unwrap();
        for i in 0..6 {
            for (k, w) in [want.q[i], want.qd[i], want.qdd[i]].into_iter().enumerate() {
                let u = q[k][6 * r + i];
                assert!(
                    u.to_bits() == w.to_bits() || (u.is_nan() && w.is_nan()),
                    "{name} row {r} strut {i} order {k}: {u} against {w}"
                );
            }
        }
        if !clear[r] {
            buf.clear();
            h.actuator_motion_checked(&x[r], &xd[r], &xdd[r], &mut buf)
                .unwrap();
            beyond += usize::from(!buf.is_empty());
            continue;
        }
        buf.clear();
        h.actuator_motion_checked(&x[r], &xd[r], &xdd[r], &mut buf)
            .unwrap();
        assert!(buf.is_empty(), "{name} row {r}: cleared but {buf:?}");
        level += usize::from(x[r].fixed_rows::<3>(3) == Vector3::zeros());
    }
    let (ok, cleared) = random.iter().zip(within).fold((0, 0), |(o, c), (&r, &w)| {
        (o + usize::from(w), c + usize::from(w && clear[r]))
    });
    assert!(
        ok >= 100 && cleared as f64 > 0.99 * ok as f64,
        "{name}: {ok} random rows within limits, {cleared} cleared by the motion kernel"
    );
    assert!(level > 0, "{name}: no level pose was cleared");
    assert!(
        beyond > 0,
        "{name}: no computed row beyond a limit (the motion engine checks those rows' limits \
         with the kernel's motion)"
    );
}

/// The motion engine's per-sample call shares the pose's rotation between the motion
/// and the limits: the same actuator motion and the same violations, bit for bit, as
/// the two calls apart, on poses within and beyond the limits.
#[test]
fn checked_actuator_motion_equals_motion_then_limits() {
    for file in ["hexapod-linuxcnc.toml", "hexapod-seed001.toml"] {
        let h = load(file);
        let home = h.info().home();
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let mut violated = 0;
        for _ in 0..5000 {
            let x = Vector6::from_fn(|k, _| {
                let s = if k < 3 { 150.0 } else { 0.3 };
                home[k] + rng.random_range(-s..s)
            });
            let xd = Vector6::from_fn(|_, _| rng.random_range(-50.0..50.0));
            let xdd = Vector6::from_fn(|_, _| rng.random_range(-500.0..500.0));
            let (mut a, mut b) = (Vec::new(), Vec::new());
            let got = h.actuator_motion_checked(&x, &xd, &xdd, &mut a).unwrap();
            let want = h.actuator_motion(&x, &xd, &xdd).unwrap();
            h.check_limits(&x, &want.q, &mut b);
            assert_eq!(got, want, "{file}: {x:?}");
            assert_eq!(a, b, "{file}: {x:?}");
            violated += usize::from(!a.is_empty());
        }
        assert!(violated > 500 && violated < 4500, "{file}: {violated}");
    }
}

/// The accuracy engine's forward call returns the solver's rotation as it is: the same
/// tool pose as forward kinematics through X..C, to 1e-12 mm and rad.
#[test]
fn forward_tool_pose_equals_forward_then_tool_pose() {
    let h = load("hexapod-linuxcnc.toml");
    let home = h.info().home();
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    for _ in 0..2000 {
        let x = Vector6::from_fn(|k, _| {
            let s = if k < 3 { 80.0 } else { 0.15 };
            home[k] + rng.random_range(-s..s)
        });
        let q = h.inverse(&x).unwrap();
        let a = h.forward_tool_pose(&q, &home).unwrap();
        let b = h.tool_pose(&h.forward(&q, &home).unwrap().pose).unwrap();
        assert!((a.translation.vector - b.translation.vector).norm() < 1e-12);
        assert!(a.rotation.angle_to(&b.rotation) < 1e-12);
        // And both are the pose the actuators came from.
        let t = h.tool_pose(&x).unwrap();
        assert!((a.translation.vector - t.translation.vector).norm() < 1e-9);
    }
}

/// `Hexapod::motion_at` (struts across SIMD lanes, AVX-512 where the CPU has it) and
/// the portable `StrutSoa::motion` give the bits of `StrutSet::coords_motion_at` (the
/// 3-vector form): lengths, rates and accelerations, on random poses and rates, held
/// orientations (no angular motion), zero rates, and NaN (as NaN).
#[test]
fn strut_motion_across_lanes_is_the_three_vector_form_bit_for_bit() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(19);
    for file in ["hexapod-linuxcnc.toml", "hexapod-seed001.toml"] {
        let h = load(file);
        let home = h.info().home();
        // The bits, every NaN as one (the sign of a NaN follows operand order, which
        // an unoptimised build may swap; every NaN prints alike).
        let bits = |a: &pkm::ActuatorMotion<6>| {
            [a.q, a.qd, a.qdd].map(|v| v.map(|x| if x.is_nan() { 0 } else { x.to_bits() }))
        };
        for k in 0..20_000 {
            let mut x = home;
            let mut xd = Vector6::zeros();
            let mut xdd = Vector6::zeros();
            for i in 0..6 {
                let (span, rate) = if i < 3 { (100.0, 200.0) } else { (0.3, 2.0) };
                x[i] += rng.random_range(-span..span);
                xd[i] = rng.random_range(-rate..rate);
                xdd[i] = rng.random_range(-10.0 * rate..10.0 * rate);
            }
            match k % 4 {
                // Orientation held: the zero angular motion shortcut.
                1 => xd.fixed_rows_mut::<3>(3).fill(0.0),
                2 => {
                    xd.fill(0.0);
                    xdd.fill(0.0);
                }
                3 if k % 400 == 3 => x[k % 6] = f64::NAN,
                _ => {}
            }
            let (p, r) = pkm::legs::split_pose(&x);
            let want = h.strut_set().coords_motion_at(&x, &xd, &xdd, &p, &r);
            let [v, w, a, al] = pkm::legs::coords_twist(&x, &xd, &xdd);
            let portable = h.soa().motion(&p, &r, &v, &w, &a, &al);
            let lanes = h.motion_at(&x, &xd, &xdd, &p, &r);
            assert_eq!(bits(&portable), bits(&want), "{file} {k}");
            assert_eq!(bits(&lanes), bits(&want), "{file} {k}");
        }
    }
}

/// The LinuxCNC hexapod scaled by `k` (joints, strokes, home, strut diameter; its
/// published reference left out).
fn scaled_linuxcnc(k: f64) -> pkm::Machine {
    crate::common::scaled_example(
        "hexapod-linuxcnc.toml",
        k,
        &[
            "B1",
            "B2",
            "B3",
            "P1",
            "P2",
            "P3",
            "P4",
            "P5",
            "P6",
            "length",
            "position",
            "strut_diameter",
            "tip",
        ],
    )
}

/// Forward kinematics converges on a hexapod of any size: the LinuxCNC hexapod scaled
/// by 100 (struts of 50 to 100 m) solves every pose its inverse reaches, where a fixed
/// 1e-11 mm residual tolerance (1e-16 of its struts, below rounding) refused 405 of
/// 1 000 ("did not converge, residual 1.455e-11"); and by 1/100 (struts of 5 to 10 mm)
/// the poses come back as exactly, relative to the machine.
#[test]
fn forward_kinematics_converges_at_every_size() {
    use rand::{Rng, SeedableRng};
    for k in [100.0, 0.01] {
        let m = scaled_linuxcnc(k);
        let home = m.mechanism().home();
        let mut rng = rand::rngs::StdRng::seed_from_u64(8);
        let mut solved = 0;
        for _ in 0..1000 {
            let x: Vec<f64> = (0..6)
                .map(|i| {
                    if i < 3 {
                        home[i] + k * rng.random_range(-50.0..50.0)
                    } else {
                        rng.random_range(-0.08..0.08)
                    }
                })
                .collect();
            let inv = pkm::analysis::kinematics::inverse(&m, &x).unwrap();
            if !inv.violations.is_empty() {
                continue;
            }
            let f = pkm::analysis::kinematics::forward(&m, &inv.actuators, &home)
                .unwrap_or_else(|e| panic!("x{k}: {x:?}: {e}"));
            for i in 0..6 {
                let scale = if i < 3 { k * 1000.0 } else { 1.0 };
                assert!(
                    (f.pose[i] - x[i]).abs() < 1e-11 * scale,
                    "x{k}: {x:?} -> {:?}",
                    f.pose
                );
            }
            solved += 1;
        }
        assert!(solved > 500, "x{k}: {solved} poses within the limits");
    }
}
