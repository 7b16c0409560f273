//! The pentapod in the accuracy engine: its geometric parameters (base joint centres,
//! ring radii and heights, the tool length), rebuilt, its base joints as passive joints
//! (for clearances), and analytic sensitivities by the implicit function theorem.

use nalgebra::{DMatrix, SVector, Vector3};

use super::Pentapod;
use crate::accuracy::clearance::PassiveJoint;
use crate::accuracy::rebuild::{
    implicit_sensitivities, parametric_by_rebuild, strut_joints, zero_length_parameter,
};
use crate::accuracy::{Parameter, ParameterKind, Rebuild};
use crate::error::{Error, Result};
use crate::units::Quantity;

/// 15 base joint coordinates, 5 ring radii, 5 ring heights, the tool length.
const GEOMETRY: usize = 26;
const RADIUS: usize = 15;
const HEIGHT: usize = 20;
/// Index of `tool.z` in [`Rebuild::geometry_parameters`] (identification leaves it
/// out: it trades against every ring height).
pub(crate) const TOOL: usize = 25;

impl Pentapod {
    /// `dL/dg` at pose `x` (`5 x 26`, the order of [`Rebuild::geometry_parameters`]):
    /// `dL_i/db_i = -n_i`, `dL_i/dr_i = -(rho - r_i) / L_i`, `dL_i/dz_i = -(s_z - z_i) /
    /// L_i`, `dL_i/dt = (s_z - z_i) / L_i` (the effector origin moves down the axis as
    /// the tool gets longer at a fixed tip).
    pub fn inverse_geometry_jacobian(&self, x: &SVector<f64, 6>) -> Result<DMatrix<f64>> {
        let (o, r) = self.frame(x);
        let mut j = DMatrix::zeros(5, GEOMETRY);
        for i in 0..5 {
            let g = self.strut_at(i, &o, &r);
            let n = -(r * self.gradient(i, &g)?);
            for a in 0..3 {
                j[(i, 3 * i + a)] = -n[a];
            }
            j[(i, RADIUS + i)] = -g.b / g.l;
            j[(i, HEIGHT + i)] = -g.a / g.l;
            j[(i, TOOL)] = g.a / g.l;
        }
        Ok(j)
    }
}

impl Rebuild<6, 5> for Pentapod {
    fn geometry_parameters(&self) -> Vec<Parameter> {
        let base: Vec<&str> = self.struts.iter().map(|s| s.base_name.as_str()).collect();
        let names: Vec<&str> = self
            .struts
            .iter()
            .map(|s| s.actuator.name.as_str())
            .collect();
        // The base joints' x, y, z, made unique per strut where struts share one.
        let mut v: Vec<Parameter> = crate::identify::struts::names(&base, &[], &names)
            .into_iter()
            .map(|n| Parameter::new(n, Quantity::Length, ParameterKind::JointCentre))
            .collect();
        for what in ["radius", "height"] {
            for s in &self.struts {
                v.push(Parameter::new(
                    format!("ring({}).{what}", s.actuator.name),
                    Quantity::Length,
                    ParameterKind::LinkDimension,
                ));
            }
        }
        v.push(Parameter::new(
            "tool.z",
            Quantity::Length,
            ParameterKind::LinkDimension,
        ));
        v
    }

    fn geometry_values(&self) -> Vec<f64> {
        let mut v: Vec<f64> = self
            .struts
            .iter()
            .flat_map(|s| s.base.iter().copied())
            .collect();
        v.extend(self.struts.iter().map(|s| s.ring_radius));
        v.extend(self.struts.iter().map(|s| s.ring_height));
        v.push(self.tool);
        v
    }

    fn with_geometry_values(&self, v: &[f64]) -> Result<Self> {
        let mut m = self.clone();
        self.update_geometry(&mut m, v)?;
        Ok(m)
    }

    /// In place, without allocating.
    fn update_geometry(&self, target: &mut Self, v: &[f64]) -> Result<()> {
        if v.len() != GEOMETRY {
            return Err(Error::InvalidInput {
                what: "pentapod geometry".into(),
                message: format!("expected {GEOMETRY} values, got {}", v.len()),
            });
        }
        for (i, s) in target.struts.iter_mut().enumerate() {
            s.base = Vector3::from_column_slice(&v[3 * i..3 * i + 3]);
            s.ring_radius = v[RADIUS + i];
            s.ring_height = v[HEIGHT + i];
        }
        target.tool = v[TOOL];
        target
            .info
            .set_characteristic_length(super::characteristic_length(&target.struts, target.tool));
        Ok(())
    }

    fn drive_parameter(&self, k: usize) -> Parameter {
        zero_length_parameter(&self.info.actuators()[k].name)
    }

    /// The base joints (a name several struts use is one joint).
    fn passive_joints(&self) -> Vec<PassiveJoint> {
        let base: Vec<&str> = self.struts.iter().map(|s| s.base_name.as_str()).collect();
        strut_joints(&base, &[])
    }
}

parametric_by_rebuild!(Pentapod, 6, 5, |m, x| Some(
    m.inverse_geometry_jacobian(x)
        .and_then(|jg| implicit_sensitivities(m, x, &jg))
));
