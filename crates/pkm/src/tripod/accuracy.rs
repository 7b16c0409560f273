//! The tripods in the accuracy engine: the translational tripod as a strut machine
//! (every joint centre, the struts' zero lengths, analytic sensitivities), the
//! centre-leg tripod by rebuilding (the struts' joints and the leg's base joint).

use nalgebra::Vector3;

use super::CentreLegTripod;
use crate::accuracy::clearance::PassiveJoint;
use crate::accuracy::rebuild::{parametric_by_rebuild, strut_joints, strut_rebuild};
use crate::accuracy::{Parameter, ParameterKind, Rebuild};
use crate::error::{Error, Result};
use crate::mechanism::Mechanism;
use crate::units::Quantity;

strut_rebuild!(super::TranslationalTripod, 3);

// The centre-leg tripod: strut joints, then the leg's base joint.

impl Rebuild<3, 3> for CentreLegTripod {
    fn geometry_parameters(&self) -> Vec<Parameter> {
        let s = &self.tripod_geometry().struts();
        let b: Vec<&str> = s.iter().map(|s| s.base_name.as_str()).collect();
        let p: Vec<&str> = s.iter().map(|s| s.platform_name.as_str()).collect();
        let n: Vec<&str> = s.iter().map(|s| s.actuator.name.as_str()).collect();
        let mut v: Vec<Parameter> = crate::identify::struts::names(&b, &p, &n)
            .into_iter()
            .chain(["x", "y", "z"].map(|a| format!("leg.{a}")))
            .map(|n| Parameter::new(n, Quantity::Length, ParameterKind::JointCentre))
            .collect();
        v.shrink_to_fit();
        v
    }
    fn geometry_values(&self) -> Vec<f64> {
        let s = &self.tripod_geometry().struts();
        s.iter()
            .flat_map(|s| s.base.iter().copied())
            .chain(s.iter().flat_map(|s| s.platform.iter().copied()))
            .chain(self.leg().base.iter().copied())
            .collect()
    }
    fn with_geometry_values(&self, v: &[f64]) -> Result<Self> {
        if v.len() != 21 {
            return Err(Error::InvalidInput {
                what: "centre-leg tripod geometry".into(),
                message: format!("expected 21 values, got {}", v.len()),
            });
        }
        let old = self.tripod_geometry();
        let mut s = old.struts().clone();
        for (j, st) in s.iter_mut().enumerate() {
            st.base = Vector3::from_column_slice(&v[3 * j..3 * j + 3]);
            st.platform = Vector3::from_column_slice(&v[9 + 3 * j..9 + 3 * j + 3]);
        }
        let geometry = old.with_struts(s);
        let mut leg = self.leg().clone();
        leg.base = Vector3::from_column_slice(&v[18..21]);
        Ok(CentreLegTripod::new(geometry, leg, self.info().home()))
    }
    fn drive_parameter(&self, k: usize) -> Parameter {
        Parameter::new(
            format!("zero({})", self.info().actuators()[k].name),
            Quantity::Length,
            ParameterKind::ZeroLength,
        )
    }
    fn passive_joints(&self) -> Vec<PassiveJoint> {
        let s = &self.tripod_geometry().struts();
        let b: Vec<&str> = s.iter().map(|s| s.base_name.as_str()).collect();
        let p: Vec<&str> = s.iter().map(|s| s.platform_name.as_str()).collect();
        let mut j = strut_joints(&b, &p);
        // The leg's base joint follows the struts' base and platform joints.
        let k = 6 * s.len();
        j.push(PassiveJoint {
            name: "leg".into(),
            body: "base".into(),
            centres: vec![[k, k + 1, k + 2]],
        });
        j
    }
}
parametric_by_rebuild!(CentreLegTripod, 3, 3);
