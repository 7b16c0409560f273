//! The hexapod's strut lengths and their motion, by the widest kernel the level
//! ([`crate::simd::level`]) allows: the AVX-512 or AVX2 lanes of `simd.rs`, else the
//! portable structure of arrays ([`crate::legs::StrutSoa`]). The motion is the same
//! bits on every level; the lengths within a few units in the last place (tested).

use nalgebra::{Matrix3, Vector3, Vector6};

use super::{simd, Hexapod};
use crate::legs::split_pose;
use crate::mechanism::ActuatorMotion;

impl Hexapod {
    /// Strut lengths from a tool tip and a rotation matrix (allocation-free).
    #[inline]
    pub fn lengths(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> Vector6<f64> {
        match self.lanes.lengths(p, r) {
            Some(l) => l,
            None => self.soa.lengths(p, r),
        }
    }

    /// Strut lengths `|p + R(A, B, C) arm_i - base_i|` of spatial coordinates
    /// `x = [X, Y, Z, A, B, C]` (seed 001's inverse kinematics; `R` is
    /// [`crate::rotation::rpy_matrix`]): on a CPU with AVX-512F one pass from the
    /// angles to the lengths, equal bit for bit to [`Hexapod::lengths`] of
    /// [`crate::legs::split_pose`] (tested).
    #[inline]
    pub fn pose_lengths(&self, x: &Vector6<f64>) -> Vector6<f64> {
        let mut q = Vector6::zeros();
        if self.lanes.pose_lengths(x, &mut q) {
            return q;
        }
        let (p, r) = split_pose(x);
        self.lengths(&p, &r)
    }

    /// Strut lengths by the portable code only (the reference the AVX-512 kernel is
    /// tested against).
    pub fn lengths_portable(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> Vector6<f64> {
        self.soa.lengths(p, r)
    }

    /// [`crate::legs::StrutSet::coords_motion_at`] bit for bit, strut by strut across SIMD lanes
    /// ([`crate::legs::StrutSoa::motion`], compiled for AVX-512 where the CPU has it).
    pub fn motion_at(
        &self,
        x: &Vector6<f64>,
        xd: &Vector6<f64>,
        xdd: &Vector6<f64>,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
    ) -> ActuatorMotion<6> {
        let [v, w, a, al] = crate::legs::coords_twist(x, xd, xdd);
        #[cfg(target_arch = "x86_64")]
        if self.simd_lengths() {
            // SAFETY: `simd_lengths` is the detection of AVX-512F, the one feature the
            // function enables.
            return unsafe { simd::motion(&self.soa, p, r, &v, &w, &a, &al) };
        }
        #[cfg(target_arch = "x86_64")]
        if self.lanes.avx2 {
            // SAFETY: `avx2` is set only at the AVX2 level, which a CPU with AVX2 and
            // FMA alone reaches (`crate::simd::level`).
            return unsafe { simd::motion_avx2(&self.soa, p, r, &v, &w, &a, &al) };
        }
        self.soa.motion(p, r, &v, &w, &a, &al)
    }

    /// Whether [`Hexapod::lengths`] runs the AVX-512 kernel on this CPU.
    pub fn simd_lengths(&self) -> bool {
        self.lanes.available
    }

    /// Strut lengths of many poses into `out` (the fastest kernel this CPU has).
    ///
    /// # Panics
    /// When the slices differ in length.
    pub fn lengths_batch(&self, p: &[Vector3<f64>], r: &[Matrix3<f64>], out: &mut [Vector6<f64>]) {
        assert!(
            p.len() == r.len() && p.len() == out.len(),
            "batch slices differ in length"
        );
        if !self.lanes.lengths_batch(p, r, out) {
            self.soa.lengths_batch(p, r, out);
        }
    }
}
