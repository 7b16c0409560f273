//! The seed-002 machine in the accuracy engine: its geometric parameters, rebuilt in
//! place, its passive joints (carriage and platform joints, for clearances), and the
//! analytic sensitivities of the tool relative to the part.

use nalgebra::{DMatrix, SVector, Vector3};

use super::HybridAm;
use crate::accuracy::clearance::PassiveJoint;
use crate::accuracy::rebuild::{implicit_sensitivities, parametric_by_rebuild};
use crate::accuracy::{Parameter, ParameterKind, Rebuild};
use crate::error::{Error, Result};
use crate::units::Quantity;

/// Number of geometric parameters: 12 carriage-joint and 12 platform-joint coordinates,
/// 4 strut lengths, the nozzle tip (3) and tilt, the table centre (3).
const GEOMETRY: usize = 35;
/// Offsets of the groups in the parameter vector.
const PLATFORM: usize = 12;
const LENGTHS: usize = 24;
const TOOL: usize = 28;
const TILT: usize = 31;
const TABLE: usize = 32;

impl HybridAm {
    /// Sets the geometry from parameter values `v` (order of
    /// [`Rebuild::geometry_parameters`]) without allocating.
    fn set_geometry(&mut self, v: &[f64]) -> Result<()> {
        if v.len() != GEOMETRY {
            return Err(Error::InvalidInput {
                what: "seed-002 machine geometry".into(),
                message: format!("expected {GEOMETRY} values, got {}", v.len()),
            });
        }
        for (i, leg) in self.legs.iter_mut().enumerate() {
            leg.guide = Vector3::from_column_slice(&v[3 * i..3 * i + 3]);
            leg.platform = Vector3::from_column_slice(&v[PLATFORM + 3 * i..PLATFORM + 3 * i + 3]);
            leg.length = v[LENGTHS + i];
        }
        self.tool = Vector3::from_column_slice(&v[TOOL..TOOL + 3]);
        self.tool_tilt = v[TILT];
        self.table = Vector3::from_column_slice(&v[TABLE..TABLE + 3]);
        self.derive();
        Ok(())
    }

    /// `dq/dg` at pose `x` (`5 x 35`, the table's row zero): with `s = P_i - c_i` and
    /// `s . s = L^2`, `dq_i = (s . (dP_i - dg_i) - L dL) / s_z`, where
    /// `dP_i = Ry(beta) (drho_i - dt) - dgamma e_y x Ry(beta) (rho_i - t) + dc_t`.
    pub fn inverse_geometry_jacobian(&self, x: &SVector<f64, 6>) -> Result<DMatrix<f64>> {
        let (pl, _, s) = self.solve(x)?;
        let k = self.rate_vectors(&s)?;
        let mut j = DMatrix::zeros(5, GEOMETRY);
        for i in 0..4 {
            let kr = k[i].transpose() * pl.rotation;
            let arm = pl.joints[i] - pl.tip;
            for a in 0..3 {
                j[(i, 3 * i + a)] = -k[i][a];
                j[(i, PLATFORM + 3 * i + a)] = kr[a];
                j[(i, TOOL + a)] = -kr[a];
                j[(i, TABLE + a)] = k[i][a];
            }
            j[(i, LENGTHS + i)] = -self.legs[i].length / s[i].z;
            j[(i, TILT)] = -k[i].dot(&Vector3::y().cross(&arm));
        }
        Ok(j)
    }
}

impl Rebuild<6, 5> for HybridAm {
    fn geometry_parameters(&self) -> Vec<Parameter> {
        let xyz = |n: &str, kind| {
            ["x", "y", "z"].map(|a| Parameter::new(format!("{n}.{a}"), Quantity::Length, kind))
        };
        let mut v = Vec::with_capacity(GEOMETRY);
        for leg in &self.legs {
            v.extend(xyz(&leg.carriage_name, ParameterKind::JointCentre));
        }
        for leg in &self.legs {
            v.extend(xyz(&leg.platform_name, ParameterKind::JointCentre));
        }
        for leg in &self.legs {
            v.push(Parameter::new(
                format!("L({})", leg.actuator.name),
                Quantity::Length,
                ParameterKind::LinkDimension,
            ));
        }
        v.extend(xyz("tool", ParameterKind::LinkDimension));
        v.push(Parameter::new(
            "tool.tilt",
            Quantity::Angle,
            ParameterKind::LinkDimension,
        ));
        v.extend(xyz("table", ParameterKind::Installation));
        v
    }

    fn geometry_values(&self) -> Vec<f64> {
        let mut v = Vec::with_capacity(GEOMETRY);
        v.extend(self.legs.iter().flat_map(|l| l.guide.iter().copied()));
        v.extend(self.legs.iter().flat_map(|l| l.platform.iter().copied()));
        v.extend(self.legs.iter().map(|l| l.length));
        v.extend(self.tool.iter().copied());
        v.push(self.tool_tilt);
        v.extend(self.table.iter().copied());
        v
    }

    fn with_geometry_values(&self, v: &[f64]) -> Result<Self> {
        let mut m = self.clone();
        m.set_geometry(v)?;
        Ok(m)
    }

    fn update_geometry(&self, target: &mut Self, v: &[f64]) -> Result<()> {
        target.set_geometry(v)
    }

    /// The carriage joints (their centres in the carriage frame, whose axes are the
    /// base frame's) and the platform joints (platform frame).
    fn passive_joints(&self) -> Vec<PassiveJoint> {
        let mut v = Vec::with_capacity(8);
        for (i, leg) in self.legs.iter().enumerate() {
            v.push(PassiveJoint {
                name: leg.carriage_name.clone(),
                body: "carriage".into(),
                centres: vec![[3 * i, 3 * i + 1, 3 * i + 2]],
            });
        }
        for (i, leg) in self.legs.iter().enumerate() {
            let o = PLATFORM + 3 * i;
            v.push(PassiveJoint {
                name: leg.platform_name.clone(),
                body: "platform".into(),
                centres: vec![[o, o + 1, o + 2]],
            });
        }
        v
    }
}

parametric_by_rebuild!(HybridAm, 6, 5, |m, x| Some(
    m.inverse_geometry_jacobian(x)
        .and_then(|jg| implicit_sensitivities(m, x, &jg))
));
