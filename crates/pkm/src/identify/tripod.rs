//! The translational tripod's parameters: base joints `A_j` (9), platform joints `B'_j`
//! (9), zero lengths (3). Its platform does not turn, so a base joint and its strut's
//! platform joint can only be identified together (`A_j - B'_j`): hold one of them
//! (`Options::fixed`, `pkm calibrate --fix`); the identified machine is then an
//! equivalent one, exact in every prediction.

use nalgebra::{DMatrix, Matrix3, SMatrix, Vector3, Vector6};

use super::{struts, Identifiable};
use crate::error::Result;
use crate::mechanism::Mechanism;
use crate::tripod::{TranslationalTripod, TripodGeometry};

impl Identifiable<6, 3> for TranslationalTripod {
    fn geometry_names(&self) -> Vec<String> {
        let s = &self.geometry.struts;
        let b: Vec<&str> = s.iter().map(|s| s.base_name.as_str()).collect();
        let p: Vec<&str> = s.iter().map(|s| s.platform_name.as_str()).collect();
        let n: Vec<&str> = s.iter().map(|s| s.actuator.name.as_str()).collect();
        struts::names(&b, &p, &n)
    }

    fn geometry(&self) -> Vec<f64> {
        let s = &self.geometry.struts;
        let a = s.iter().flat_map(|s| s.base.iter().copied());
        let b = s.iter().flat_map(|s| s.platform.iter().copied());
        a.chain(b).collect()
    }

    fn with_geometry(&self, g: &[f64]) -> Result<Self> {
        let (base, platform) = struts::split::<3>(g)?;
        let old = &self.geometry;
        let mut s = old.struts.clone();
        for (j, st) in s.iter_mut().enumerate() {
            st.base = base[j];
            st.platform = platform[j];
        }
        let mut geometry = TripodGeometry::new(
            old.name.clone(),
            s,
            old.tool,
            old.max_tilt,
            old.min_strut_spindle_angle,
        );
        geometry.zero_lengths = old.zero_lengths;
        Ok(TranslationalTripod::new(geometry, self.home))
    }

    fn inverse_with_geometry_jacobian(
        &self,
        x: &Vector6<f64>,
        jac: &mut DMatrix<f64>,
    ) -> Result<Vector3<f64>> {
        let s = &self.geometry.struts;
        struts::lengths_with_jacobian(
            &std::array::from_fn(|j| s[j].base),
            &std::array::from_fn(|j| s[j].platform),
            &self.geometry.tool,
            x,
            jac,
        )
    }

    fn platform_point(
        &self,
        x: &Vector6<f64>,
        s: &Vector3<f64>,
    ) -> (Vector3<f64>, SMatrix<f64, 3, 6>) {
        struts::platform_point(&self.geometry.tool, x, s)
    }

    fn coords_from_platform_frame(&self, c: &Vector3<f64>, r: &Matrix3<f64>) -> Vector6<f64> {
        struts::coords_from_platform_frame(&self.geometry.tool, c, r)
    }

    fn explain(&self, terms: &[(usize, f64)]) -> Option<String> {
        let (p, r) = crate::legs::split_pose(&self.home());
        let s = &self.geometry.struts;
        let dirs: [Vector3<f64>; 3] = std::array::from_fn(|j| {
            (p + r * (s[j].platform - self.geometry.tool) - s[j].base).normalize()
        });
        struts::explain(terms, &super::parameter_names(self), &dirs, &r)
    }
}

/// A translational tripod's zero readings: calibrated ones from its file, else its
/// strut lengths at home.
pub fn zero_lengths(t: &TranslationalTripod) -> Result<Vector3<f64>> {
    match t.geometry.zero_lengths {
        Some(z) => Ok(z),
        None => t.inverse(&t.home()),
    }
}
