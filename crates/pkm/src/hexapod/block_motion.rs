//! The exact motion of many samples eight at a time, with the limit screen (what
//! [`crate::mechanism::BlockKernels::motion_screened`] asks of a hexapod): the motion
//! engine's per-sample work for six struts in one AVX-512 pass over eight samples.
//!
//! The samples' poses, rates and accelerations are transposed into lanes
//! ([`super::block`]'s transposes); then, lane by lane, the operations of the scalar
//! path ([`super::Hexapod::actuator_motion`]) in the same order, written once for both
//! over [`crate::lane::Lane`]:
//!
//! - the sines and cosines of A, B, C ([`crate::trig::avx512::sin_cos`], the scalar
//!   kernel's bits) and the rotation ([`crate::rotation::rpy_entries`]; exactly the
//!   identity where A = B = C = 0, as [`crate::rotation::rpy_matrix`]);
//! - the angular velocity and acceleration ([`crate::rotation::rpy_angular_terms`];
//!   exact zeros where the angles are held, as
//!   [`crate::rotation::rpy_angular_motion`]);
//! - each strut's `L`, `L'`, `L''` ([`crate::legs::strut_motion`]).
//!
//! So a sample's `q`, `q'`, `q''` are the scalar path's bit for bit (tested). The strut
//! vectors and lengths then go through the screen of [`super::block`] (every limit
//! with a relative margin): a lane it clears is within every limit, the others are
//! left to the exact per-sample path, which names the violated limits.

use super::block::{Screen, LANES};

/// The motion of the rows of `x = [poses, rates, accelerations]` (row-major X, Y, Z,
/// A, B, C and their derivatives) into `q = [lengths, rates, accelerations]` (six per
/// row), with `computed[i]` set where row `i`'s motion is the scalar path's (its
/// angles within the sine kernel's range) and `clear[i]` where it is moreover
/// certainly within every limit. The rows of whole blocks of eight are all written,
/// their values meaningful where computed; rows past the last whole block are
/// neither written nor computed. Returns `false` (nothing written) on a CPU without
/// AVX-512F.
pub(crate) fn motion_rows(
    s: &Screen,
    x: [&[f64]; 3],
    q: [&mut [f64]; 3],
    clear: &mut [bool],
    computed: &mut [bool],
) -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        if s.avx512() {
            let n = clear.len();
            let [q0, q1, q2] = q;
            for b in 0..n / LANES {
                let span = 6 * b * LANES..6 * (b + 1) * LANES;
                let rows = x.map(|x| -> &[f64; 6 * LANES] {
                    x[span.clone()].try_into().expect("whole block")
                });
                let out = [
                    (&mut q0[span.clone()]).try_into().expect("whole block"),
                    (&mut q1[span.clone()]).try_into().expect("whole block"),
                    (&mut q2[span.clone()]).try_into().expect("whole block"),
                ];
                // SAFETY: `avx512` is the hexapod's detection of AVX-512F, the one
                // feature the kernel enables.
                let (mask, ok) = unsafe { avx512::block(s, rows, out) };
                let lanes = b * LANES..(b + 1) * LANES;
                for (l, (c, k)) in clear[lanes.clone()]
                    .iter_mut()
                    .zip(&mut computed[lanes])
                    .enumerate()
                {
                    (*c, *k) = (mask & (1 << l) != 0, ok & (1 << l) != 0);
                }
            }
            clear[n / LANES * LANES..].fill(false);
            computed[n / LANES * LANES..].fill(false);
            return true;
        }
    }
    let _ = (s, x, q, clear, computed);
    false
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use super::super::block::avx512::limits;
    use super::super::transpose::{columns, rows};
    use super::{Screen, LANES};
    use crate::lane::Zmm;

    /// One block of eight samples: their motion into `q`; returns the mask of cleared
    /// lanes and that of the lanes computed (angles within the sine kernel's range).
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn block(
        s: &Screen,
        x: [&[f64; 6 * LANES]; 3],
        q: [&mut [f64; 6 * LANES]; 3],
    ) -> (u8, u8) {
        let pose = columns(x[0]);
        let rate = columns(x[1]);
        let acc = columns(x[2]);
        use crate::trig::avx512::sin_cos;
        let ((sa, ca), in_a) = sin_cos(pose[3]);
        let ((sb, cb), in_b) = sin_cos(pose[4]);
        let ((sc, cc), in_c) = sin_cos(pose[5]);
        let ok = in_a & in_b & in_c;
        let zero = _mm512_setzero_pd();
        let is_zero = |v: __m512d| _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(v, zero);
        let mut r =
            crate::rotation::rpy_entries([sa, sb, sc].map(Zmm::of), [ca, cb, cc].map(Zmm::of))
                .map(Zmm::reg);
        let level = is_zero(pose[3]) & is_zero(pose[4]) & is_zero(pose[5]);
        if level != 0 {
            let one = _mm512_set1_pd(1.0);
            for (k, e) in r.iter_mut().enumerate() {
                *e = _mm512_mask_blend_pd(level, *e, if k % 4 == 0 { one } else { zero });
            }
        }
        let [w, al] = crate::rotation::rpy_angular_terms(
            [sb, cb, sc, cc].map(Zmm::of),
            [rate[3], rate[4], rate[5]].map(Zmm::of),
            [acc[3], acc[4], acc[5]].map(Zmm::of),
        )
        .map(|v| v.map(Zmm::reg));
        let held = (3..6).fold(0xff, |m, k| m & is_zero(rate[k]) & is_zero(acc[k]));
        let keep = |v: [__m512d; 3]| v.map(|e| _mm512_mask_blend_pd(held, e, zero));
        let twist = [
            [rate[0], rate[1], rate[2]],
            keep(w),
            [acc[0], acc[1], acc[2]],
            keep(al),
        ]
        .map(|v| v.map(Zmm::of));
        let rz = r.map(Zmm::of);
        let p = [pose[0], pose[1], pose[2]].map(Zmm::of);
        let mut d = [[zero; 3]; 6];
        let mut out = [[zero; 6]; 3];
        for i in 0..6 {
            let m = crate::legs::strut_motion(
                &rz,
                &p,
                [s.arm[0][i], s.arm[1][i], s.arm[2][i]],
                [s.base[0][i], s.base[1][i], s.base[2][i]],
                &twist,
            );
            d[i] = m.d.map(Zmm::reg);
            (out[0][i], out[1][i], out[2][i]) = (m.l.reg(), m.ld.reg(), m.ldd.reg());
        }
        let [q0, q1, q2] = q;
        rows(&out[0], q0);
        rows(&out[1], q1);
        rows(&out[2], q2);
        if ok == 0 {
            return (0, 0);
        }
        (limits(s, &pose, &r, &d, &out[0], ok), ok)
    }
}
