//! Strut lengths with AVX-512, dispatched at run time (the library is built for the
//! baseline x86-64 target; this kernel runs only on CPUs that have AVX-512F).
//!
//! The six lengths of a pose are one 8-lane vector. The square root — the bound of
//! the portable code, six per pose at a few cycles per double — is replaced by the
//! 14-bit reciprocal square-root estimate refined by one Newton step for
//! `1 / sqrt(d2)` and one Heron step for `sqrt(d2)`: relative error within a few
//! units in the last place (tested against the portable code over 10^5 poses: within
//! 1e-15 relative, i.e. 5e-13 mm on a 500 mm strut; the FK tolerance is 1e-11 mm).

use nalgebra::{Matrix3, Vector3, Vector6};

#[cfg(target_arch = "x86_64")]
use crate::lane::{Lane, Zmm};

/// Strut geometry padded to eight lanes (the two spare lanes hold a copy of strut 0,
/// so every lane computes a finite, positive length).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Lanes {
    ax: [f64; 8],
    ay: [f64; 8],
    az: [f64; 8],
    bx: [f64; 8],
    by: [f64; 8],
    bz: [f64; 8],
    /// Every arm's z is exactly 0 (the platform joints in the tool frame's XY plane,
    /// as in LinuxCNC's genhexkins): the rotation's third column is not needed
    /// ([`strut_component`]).
    planar: bool,
    /// The CPU has AVX-512F (checked once, when the machine is built, by
    /// [`crate::simd::level`]).
    pub(crate) available: bool,
    /// The level is AVX2 with FMA (no AVX-512F): the portable lanes' kernel
    /// ([`pose_lengths_avx2`]).
    pub(crate) avx2: bool,
}

impl Lanes {
    pub(crate) fn new(arms: &[Vector3<f64>; 6], base: &[Vector3<f64>; 6]) -> Self {
        let mut lanes = Lanes {
            ax: [0.0; 8],
            ay: [0.0; 8],
            az: [0.0; 8],
            bx: [0.0; 8],
            by: [0.0; 8],
            bz: [0.0; 8],
            planar: false,
            available: detect(),
            avx2: crate::simd::level() == crate::simd::Level::Avx2,
        };
        lanes.set_geometry(arms, base);
        lanes
    }

    /// Sets the strut geometry in place (the CPU check is kept).
    pub(crate) fn set_geometry(&mut self, arms: &[Vector3<f64>; 6], base: &[Vector3<f64>; 6]) {
        for i in 0..8 {
            let k = if i < 6 { i } else { 0 };
            (self.ax[i], self.ay[i], self.az[i]) = (arms[k].x, arms[k].y, arms[k].z);
            (self.bx[i], self.by[i], self.bz[i]) = (base[k].x, base[k].y, base[k].z);
        }
        self.planar = arms.iter().all(|a| a.z == 0.0);
    }

    /// The six strut lengths `|p + R arm_i - base_i|`; `None` when AVX-512F is not
    /// available (the caller uses the portable code).
    #[inline]
    pub(crate) fn lengths(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> Option<Vector6<f64>> {
        #[cfg(target_arch = "x86_64")]
        {
            if self.available {
                // SAFETY: `available` is true only when the running CPU reported
                // AVX-512F (`detect`), the one feature the kernel is compiled with.
                let l = unsafe { lengths_avx512(self, p, r) };
                return Some(Vector6::new(l[0], l[1], l[2], l[3], l[4], l[5]));
            }
            if self.avx2 {
                // SAFETY: as in `pose_lengths`: the CPU reported AVX2 and FMA.
                let l = unsafe { lengths_avx2(self, p, r) };
                return Some(Vector6::new(l[0], l[1], l[2], l[3], l[4], l[5]));
            }
        }
        let _ = (p, r);
        None
    }
}

impl Lanes {
    /// The six strut lengths of spatial coordinates `x = [X, Y, Z, A, B, C]` in one
    /// AVX-512 pass, written to `out`: the three sines and cosines in one register
    /// ([`crate::trig::avx512::sin_cos`], bit for bit the scalar kernel), the rotation
    /// by [`crate::rotation::rpy_entries`] in registers (each entry in every lane),
    /// then [`Lanes::lengths`]' kernel; so equal bit for bit to
    /// `lengths(split_pose(x))`. `false` (nothing written) without AVX-512F or with an
    /// angle beyond the kernel's range (`|angle| > 1e4` rad, NaN): the caller takes the
    /// portable path, which defers those to libm.
    #[inline]
    pub(crate) fn pose_lengths(&self, x: &Vector6<f64>, out: &mut Vector6<f64>) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            if self.available {
                // SAFETY: as in `lengths`: the CPU reported AVX-512F.
                return unsafe {
                    if self.planar {
                        pose_lengths_avx512::<true>(self, x, out)
                    } else {
                        pose_lengths_avx512::<false>(self, x, out)
                    }
                };
            }
            if self.avx2 {
                // SAFETY: `avx2` is true only when the level is AVX2, which
                // `crate::simd::level` takes only from a CPU reporting AVX2 and FMA.
                return unsafe {
                    if self.planar {
                        pose_lengths_avx2::<true>(self, x, out)
                    } else {
                        pose_lengths_avx2::<false>(self, x, out)
                    }
                };
            }
        }
        let _ = (x, out);
        false
    }

    /// Lengths of many poses; `false` when AVX-512F is not available (nothing
    /// written). The loop runs inside the AVX-512 function, so poses pipeline.
    pub(crate) fn lengths_batch(
        &self,
        p: &[Vector3<f64>],
        r: &[Matrix3<f64>],
        out: &mut [Vector6<f64>],
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            if self.available {
                // SAFETY: as in `lengths`: the CPU reported AVX-512F.
                unsafe { batch_avx512(self, p, r, out) };
                return true;
            }
            if self.avx2 {
                // SAFETY: as in `pose_lengths`: the CPU reported AVX2 and FMA.
                unsafe { batch_avx2(self, p, r, out) };
                return true;
            }
        }
        let _ = (p, r, out);
        false
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn batch_avx512(
    s: &Lanes,
    p: &[Vector3<f64>],
    r: &[Matrix3<f64>],
    out: &mut [Vector6<f64>],
) {
    use std::arch::x86_64::*;
    for ((o, p), r) in out.iter_mut().zip(p).zip(r) {
        // SAFETY: same feature as this function's; the masked store writes lanes 0..6
        // only, the six contiguous f64 of `o`.
        unsafe {
            let l = lengths_zmm(s, p, r);
            _mm512_mask_storeu_pd(o.as_mut_slice().as_mut_ptr(), 0b0011_1111, l);
        }
    }
}

fn detect() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        crate::simd::level() >= crate::simd::Level::Avx512
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn pose_lengths_avx512<const PLANAR: bool>(
    s: &Lanes,
    x: &Vector6<f64>,
    out: &mut Vector6<f64>,
) -> bool {
    use std::arch::x86_64::*;
    let r = if x[3] == 0.0 && x[4] == 0.0 && x[5] == 0.0 {
        // As `rotation::rpy_matrix`: exactly the identity.
        let (one, zero) = (_mm512_set1_pd(1.0), _mm512_setzero_pd());
        [one, zero, zero, zero, one, zero, zero, zero, one]
    } else {
        // SAFETY: the masked load reads lanes 0..3 only, x[3..6] (six contiguous f64
        // in `x`).
        let ang = unsafe { _mm512_maskz_loadu_pd(0b111, x.as_slice().as_ptr().add(3)) };
        let ((sn, cs), in_range) = crate::trig::avx512::sin_cos(ang);
        if in_range != 0xff {
            return false;
        }
        // Lane `j` of `v` in every lane.
        let lane = |v: __m512d, j: i64| _mm512_permutexvar_pd(_mm512_set1_epi64(j), v);
        use crate::lane::Zmm;
        crate::rotation::rpy_entries(
            [lane(sn, 0), lane(sn, 1), lane(sn, 2)].map(Zmm::of),
            [lane(cs, 0), lane(cs, 1), lane(cs, 2)].map(Zmm::of),
        )
        .map(Zmm::reg)
    };
    let p = x.as_slice().first_chunk::<3>().expect("six coordinates");
    let l = lengths_of_entries::<PLANAR>(s, p, &r);
    // Lanes 0..4 and 4..6 by two plain stores, not one masked store: a caller's loads
    // of the result are then forwarded from the stores, where after a masked store they
    // wait for it to retire (which serialised successive calls).
    // SAFETY: the stores write 4 + 2 f64 at offsets 0 and 4 of the six contiguous f64
    // of `out`.
    unsafe {
        let o = out.as_mut_slice().as_mut_ptr();
        _mm256_storeu_pd(o, _mm512_castpd512_pd256(l));
        let high = _mm512_extractf64x4_pd::<1>(l);
        _mm_storeu_pd(o.add(4), _mm256_castpd256_pd128(high));
    }
    true
}

/// [`Lanes::pose_lengths`] on the portable lanes, compiled with AVX2 and FMA: each
/// eight-lane operation two 256-bit instructions. The sines and cosines of A, B, C by
/// [`crate::trig::sin_cos_lanes`] (the scalar kernel's operations, so its bits), the
/// rotation by [`crate::rotation::rpy_entries`] once on scalars and broadcast (each
/// lane of the AVX-512 kernel computes the same), the struts by [`lanes_of_entries`].
/// The square roots are the CPU's (`vsqrtpd`, correctly rounded): the lengths are the
/// portable code's within its rounding of the sum, and the AVX-512 kernel's within
/// the refined estimate's few units in the last place.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn pose_lengths_avx2<const PLANAR: bool>(
    s: &Lanes,
    x: &Vector6<f64>,
    out: &mut Vector6<f64>,
) -> bool {
    let r = if x[3] == 0.0 && x[4] == 0.0 && x[5] == 0.0 {
        // As `rotation::rpy_matrix`: exactly the identity.
        [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    } else {
        let Some((sn, cs)) = crate::trig::sin_cos_lanes(&[x[3], x[4], x[5], 0.0]) else {
            return false;
        };
        crate::rotation::rpy_entries([sn[0], sn[1], sn[2]], [cs[0], cs[1], cs[2]])
    };
    let p = x.as_slice().first_chunk::<3>().expect("six coordinates");
    let mut e = [crate::lane::Lanes([0.0; 8]); 9];
    for k in 0..9 {
        e[k] = Zmm::from(r[k]);
    }
    let l = lanes_of_entries::<PLANAR>(s, p, &e);
    out.as_mut_slice().copy_from_slice(&l.0[..6]);
    true
}

/// [`Lanes::lengths`] of a caller's rotation matrix with AVX2 and FMA (every entry in
/// the sum: a caller's matrix may hold NaN in its third column).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn lengths_avx2(s: &Lanes, p: &Vector3<f64>, r: &Matrix3<f64>) -> [f64; 8] {
    let e = entries(r);
    lanes_of_entries::<false>(s, p.as_ref(), &e).0
}

/// [`Lanes::lengths_batch`] with AVX2 and FMA, the loop inside the function.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn batch_avx2(s: &Lanes, p: &[Vector3<f64>], r: &[Matrix3<f64>], out: &mut [Vector6<f64>]) {
    for ((o, p), r) in out.iter_mut().zip(p).zip(r) {
        let e = entries(r);
        let l = lanes_of_entries::<false>(s, p.as_ref(), &e);
        o.as_mut_slice().copy_from_slice(&l.0[..6]);
    }
}

/// The entries of `r` row by row, each in every lane.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn entries(r: &Matrix3<f64>) -> [Zmm; 9] {
    let mut e = [crate::lane::Lanes([0.0; 8]); 9];
    for k in 0..9 {
        e[k] = Zmm::from(r[(k / 3, k % 3)]);
    }
    e
}

/// [`lengths_of_entries`] on the portable lanes ([`crate::lane::Zmm`]), for a caller
/// compiled with the instructions it is to use; `|d|` by the lanes' square root.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn lanes_of_entries<const PLANAR: bool>(s: &Lanes, p: &[f64; 3], r: &[Zmm; 9]) -> Zmm {
    let (ax, ay, az) = (
        crate::lane::Lanes(s.ax),
        crate::lane::Lanes(s.ay),
        crate::lane::Lanes(s.az),
    );
    let base = [&s.bx, &s.by, &s.bz];
    let mut d = [crate::lane::Lanes([0.0; 8]); 3];
    for i in 0..3 {
        let offset = Zmm::from(p[i]).sub(crate::lane::Lanes(*base[i]));
        let t = if PLANAR {
            offset
        } else {
            r[3 * i + 2].mul_add(az, offset)
        };
        let t = r[3 * i + 1].mul_add(ay, t);
        d[i] = r[3 * i].mul_add(ax, t);
    }
    let [dx, dy, dz] = d;
    super::block_lanes::strut_length(dx, dy, dz)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn lengths_avx512(s: &Lanes, p: &Vector3<f64>, r: &Matrix3<f64>) -> [f64; 8] {
    let mut out = [0.0; 8];
    // SAFETY: same feature; the store writes the 8 f64 of `out`.
    unsafe {
        std::arch::x86_64::_mm512_storeu_pd(out.as_mut_ptr(), lengths_zmm(s, p, r));
    }
    out
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
fn lengths_zmm(s: &Lanes, p: &Vector3<f64>, r: &Matrix3<f64>) -> std::arch::x86_64::__m512d {
    use std::arch::x86_64::_mm512_set1_pd;
    let e = std::array::from_fn(|k| _mm512_set1_pd(r[(k / 3, k % 3)]));
    // A matrix from a caller may hold NaN in its third column, which the full sum
    // carries into the lengths: no shortcut here.
    lengths_of_entries::<false>(s, p.as_ref(), &e)
}

/// The lengths of the struts in the lanes of one pose: tool tip `p` (by reference, so
/// each coordinate is broadcast from memory, not from a copy on the stack), rotation
/// entries `r` row by row, each in every lane; `PLANAR` as in [`strut_component`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
fn lengths_of_entries<const PLANAR: bool>(
    s: &Lanes,
    p: &[f64; 3],
    r: &[std::arch::x86_64::__m512d; 9],
) -> std::arch::x86_64::__m512d {
    use std::arch::x86_64::*;
    // SAFETY (whole body): the loads read 8 f64 from arrays of exactly 8 f64
    // (unaligned forms); everything else is register arithmetic.
    unsafe {
        let ld = |a: &[f64; 8]| _mm512_loadu_pd(a.as_ptr());
        let (ax, ay, az) = (ld(&s.ax), ld(&s.ay), ld(&s.az));
        let row = |i: usize, base: &[f64; 8]| {
            let offset = _mm512_sub_pd(_mm512_set1_pd(p[i]), ld(base));
            strut_component::<PLANAR>([r[3 * i], r[3 * i + 1], r[3 * i + 2]], [ax, ay, az], offset)
        };
        strut_length([row(0, &s.bx), row(1, &s.by), row(2, &s.bz)])
    }
}

/// One component of a strut vector, `r_0 a_x + r_1 a_y + r_2 a_z + (p - base)`, by
/// fused multiply-adds from the last term (`offset = p - base`): the one sequence of
/// operations of the single pose's kernel (lanes: struts) and the block kernel's
/// (lanes: poses), so both give the same bits.
///
/// With `PLANAR` (every arm's `a_z` exactly 0) the first term is left out:
/// `r_2 * 0 + offset` is `offset` exactly for a finite `r_2` (the sign of a zero
/// aside, which no length or limit test sees), so the same bits, and the rotation's
/// third column is then not computed at all by a caller that needs it for nothing
/// else. Callers pass `PLANAR` only where the entries come from the kernels' own
/// sines and cosines: a lane whose angles are beyond their range or NaN (entries
/// not finite) is refused or not cleared, and its lengths are not used; a caller's
/// matrix, which may hold NaN there, takes the full sum.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
pub(crate) fn strut_component<const PLANAR: bool>(
    r: [std::arch::x86_64::__m512d; 3],
    arm: [std::arch::x86_64::__m512d; 3],
    offset: std::arch::x86_64::__m512d,
) -> std::arch::x86_64::__m512d {
    use std::arch::x86_64::*;
    let t = if PLANAR {
        offset
    } else {
        _mm512_fmadd_pd(r[2], arm[2], offset)
    };
    let t = _mm512_fmadd_pd(r[1], arm[1], t);
    _mm512_fmadd_pd(r[0], arm[0], t)
}

/// `|d|` by lane without the square-root unit: `d2 = |d|^2`, then
/// [`crate::lane::sqrt_refined`] (56 bits).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
pub(crate) fn strut_length(d: [std::arch::x86_64::__m512d; 3]) -> std::arch::x86_64::__m512d {
    use std::arch::x86_64::*;
    let [dx, dy, dz] = d;
    let d2 = _mm512_fmadd_pd(dz, dz, _mm512_fmadd_pd(dy, dy, _mm512_mul_pd(dx, dx)));
    crate::lane::sqrt_refined(d2)
}

/// [`crate::legs::StrutSoa::motion`] compiled with the instructions of a level (the
/// same operations, so the same bits, in wider vectors).
macro_rules! motion_with {
    ($($(#[doc = $doc:literal])* $name:ident: $features:literal;)*) => {$(
        $(#[doc = $doc])*
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        #[allow(clippy::too_many_arguments)]
        pub(crate) unsafe fn $name(
            soa: &crate::legs::StrutSoa<6>,
            p: &nalgebra::Vector3<f64>,
            r: &nalgebra::Matrix3<f64>,
            v: &nalgebra::Vector3<f64>,
            w: &nalgebra::Vector3<f64>,
            a: &nalgebra::Vector3<f64>,
            al: &nalgebra::Vector3<f64>,
        ) -> crate::mechanism::ActuatorMotion<6> {
            soa.motion(p, r, v, w, a, al)
        }
    )*};
}

motion_with! {
    /// The motion with AVX-512F.
    ///
    /// # Safety
    /// The CPU must have AVX-512F.
    motion: "avx512f";
    /// The motion with AVX2 and FMA.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    motion_avx2: "avx2,fma";
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use nalgebra::{Vector3, Vector6};
    use rand::{Rng, SeedableRng};

    use super::{pose_lengths_avx512, Lanes};

    /// An example hexapod's arms and base joints: the LinuxCNC one's arms lie in the
    /// platform's plane, seed 001's tool is 150 mm below it.
    fn geometry(file: &str) -> ([Vector3<f64>; 6], [Vector3<f64>; 6]) {
        let path = format!(
            "{}/../../examples/machines/{file}",
            env!("CARGO_MANIFEST_DIR")
        );
        match crate::Machine::from_path(path).unwrap().model {
            crate::machine::Model::Hexapod(h) => (h.set.arms, h.set.base),
            _ => panic!("{file} is not a hexapod"),
        }
    }

    #[test]
    fn planar_arms_are_recognised_and_moved_joints_unset_it() {
        let (arms, base) = geometry("hexapod-linuxcnc.toml");
        let mut lanes = Lanes::new(&arms, &base);
        assert!(lanes.planar);
        let mut lifted = arms;
        lifted[3].z = 1e-300;
        lanes.set_geometry(&lifted, &base);
        assert!(!lanes.planar, "one arm off the plane by 1e-300 mm");
        lanes.set_geometry(&arms, &base);
        assert!(lanes.planar);
        let (arms, base) = geometry("hexapod-seed001.toml");
        assert!(!Lanes::new(&arms, &base).planar);
    }

    /// The AVX2 kernel: the planar and full sums give the same bits, the one pass from
    /// the angles equals the rotation matrix's lengths bit for bit (the same sines, the
    /// same rotation), the batch equals the single calls, and every length is the
    /// portable code's within 1e-15 relative; angles beyond the fast sine's range and
    /// NaN are refused.
    #[test]
    fn avx2_kernel_equals_the_matrix_path_and_the_portable_code() {
        if !(std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma"))
        {
            eprintln!("no AVX2 with FMA on this CPU: the kernel is not run");
            return;
        }
        let (arms, base) = geometry("hexapod-linuxcnc.toml");
        let lanes = Lanes::new(&arms, &base);
        let path = format!(
            "{}/../../examples/machines/hexapod-linuxcnc.toml",
            env!("CARGO_MANIFEST_DIR")
        );
        let crate::machine::Model::Hexapod(h) = crate::Machine::from_path(path).unwrap().model
        else {
            panic!("not a hexapod")
        };
        let mut rng = rand::rngs::StdRng::seed_from_u64(12);
        let xs: Vec<Vector6<f64>> = (0..100_000)
            .map(|k| {
                let a = if k % 7 == 0 { 0.0 } else { 0.6 };
                Vector6::new(
                    rng.random_range(-300.0..300.0),
                    rng.random_range(-300.0..300.0),
                    rng.random_range(300.0..800.0),
                    rng.random_range(-a..=a),
                    rng.random_range(-a..=a),
                    rng.random_range(-3.2 * a..=3.2 * a),
                )
            })
            .collect();
        let (mut planar, mut full) = (Vector6::zeros(), Vector6::zeros());
        let (ps, rs): (Vec<_>, Vec<_>) = xs.iter().map(crate::legs::split_pose).unzip();
        let mut batch = vec![Vector6::zeros(); xs.len()];
        // SAFETY: the CPU has AVX2 and FMA (checked above).
        unsafe { super::batch_avx2(&lanes, &ps, &rs, &mut batch) };
        for (k, x) in xs.iter().enumerate() {
            // SAFETY: as above.
            let ok = unsafe {
                (
                    super::pose_lengths_avx2::<true>(&lanes, x, &mut planar),
                    super::pose_lengths_avx2::<false>(&lanes, x, &mut full),
                )
            };
            assert!(ok.0 && ok.1, "{x:?}");
            // SAFETY: as above.
            let matrix = unsafe { super::lengths_avx2(&lanes, &ps[k], &rs[k]) };
            let portable = h.lengths_portable(&ps[k], &rs[k]);
            for i in 0..6 {
                assert_eq!(planar[i].to_bits(), full[i].to_bits(), "{x:?} strut {i}");
                assert_eq!(matrix[i].to_bits(), full[i].to_bits(), "{x:?} strut {i}");
                assert_eq!(batch[k][i].to_bits(), full[i].to_bits(), "{x:?} strut {i}");
                let e = (full[i] - portable[i]).abs() / portable[i];
                assert!(e <= 1e-15, "{x:?} strut {i}: {e:e}");
            }
        }
        for bad in [1e5, f64::NAN, f64::INFINITY] {
            let x = Vector6::new(0.0, 0.0, 500.0, 0.1, bad, 0.2);
            // SAFETY: as above.
            assert!(!unsafe { super::pose_lengths_avx2::<true>(&lanes, &x, &mut full) });
        }
    }

    /// The kernel without the `R_k2 a_z` terms gives the lengths of the full sum bit for
    /// bit on planar arms, over random poses and poses with exact zeros (signed zeros
    /// in the strut vectors: `p = base` in a coordinate); and the dispatch takes it.
    #[test]
    fn planar_kernel_equals_the_full_sum_bit_for_bit() {
        let (arms, base) = geometry("hexapod-linuxcnc.toml");
        let lanes = Lanes::new(&arms, &base);
        assert!(lanes.planar, "the example's arms left the platform's plane");
        if !lanes.available {
            eprintln!("no AVX-512F on this CPU: the kernels are not run");
            return;
        }
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let mut xs: Vec<Vector6<f64>> = (0..200_000)
            .map(|_| {
                Vector6::new(
                    rng.random_range(-300.0..300.0),
                    rng.random_range(-300.0..300.0),
                    rng.random_range(300.0..800.0),
                    rng.random_range(-0.6..0.6),
                    rng.random_range(-0.6..0.6),
                    rng.random_range(-3.2..3.2),
                )
            })
            .collect();
        xs.extend([
            // The tool tip at a base joint's coordinates: zero offsets.
            Vector6::new(base[0].x, base[0].y, base[0].z, 0.0, 0.0, 0.0),
            Vector6::new(base[3].x, base[3].y, -0.0, 0.0, -0.0, 0.0),
            Vector6::new(-0.0, 0.0, 508.0, 0.3, -0.0, 1.0),
            Vector6::new(10.0, 20.0, 500.0, 1e3, -2.0, 7.0),
        ]);
        let (mut planar, mut full, mut dispatched) =
            (Vector6::zeros(), Vector6::zeros(), Vector6::zeros());
        for x in &xs {
            // SAFETY: `available` says the CPU has AVX-512F.
            let ok = unsafe {
                (
                    pose_lengths_avx512::<true>(&lanes, x, &mut planar),
                    pose_lengths_avx512::<false>(&lanes, x, &mut full),
                )
            };
            assert!(ok.0 && ok.1, "{x:?}");
            assert!(lanes.pose_lengths(x, &mut dispatched));
            for i in 0..6 {
                assert_eq!(planar[i].to_bits(), full[i].to_bits(), "{x:?} strut {i}");
                assert_eq!(
                    dispatched[i].to_bits(),
                    full[i].to_bits(),
                    "{x:?} strut {i}"
                );
            }
        }
    }
}
