//! The translational tripod's parameters: base joints `A_j` (9), platform joints `B'_j`
//! (9), zero lengths (3). Its platform does not turn, so a base joint and its strut's
//! platform joint can only be identified together (`A_j - B'_j`): hold one of them
//! (`Options::fixed`, `pkm calibrate --fix`); the identified machine is then an
//! equivalent one, exact in every prediction.

use nalgebra::Vector3;

use super::struts::StrutMachine;
use crate::machine::StrutGeometry;
use crate::mechanism::Mechanism;
use crate::tripod::TranslationalTripod;

impl StrutMachine<3> for TranslationalTripod {
    fn struts(&self) -> [StrutGeometry; 3] {
        std::array::from_fn(|j| {
            let s = &self.tripod_geometry().struts()[j];
            StrutGeometry {
                name: s.actuator.name.clone(),
                base_name: s.base_name.clone(),
                platform_name: s.platform_name.clone(),
                base: s.base,
                platform: s.platform,
            }
        })
    }

    fn tool(&self) -> Vector3<f64> {
        self.tripod_geometry().tool()
    }

    fn with_struts(&self, struts: &[StrutGeometry; 3]) -> Self {
        let old = self.tripod_geometry();
        let mut s = old.struts().clone();
        for (st, g) in s.iter_mut().zip(struts) {
            st.base = g.base;
            st.platform = g.platform;
        }
        let geometry = old.with_struts(s);
        TranslationalTripod::new(geometry, self.info().home())
    }

    fn calibrated_zero(&self) -> Option<Vector3<f64>> {
        self.tripod_geometry().zero_lengths
    }

    fn platform_turns(&self) -> bool {
        false
    }

    /// The platform never turns, so each platform joint trades against its strut's
    /// base joint: the platform joints (9..18) are held.
    fn must_hold(&self) -> Vec<usize> {
        (9..18).collect()
    }
}
