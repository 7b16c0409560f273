//! The pentapod's identification: base joints (15), ring radii (5) and heights (5), and
//! one zero reading per strut, from the same two
//! measurement models as every machine. The spin about the tool axis is free (the
//! rings turn), so what a fixture can measure is the tool axis: its points lie on the
//! axis, `s = (0, 0, h)` in the effector frame (origin `O`, tool tip at `(0, 0, t)`),
//! and a state's pose comes from a line fit through them (two points or more).
//! The tool length trades against every ring height (a strut sees only `z_i - t`), so
//! it is not identified: the ring heights come out relative to the file's tool length
//! (30 parameters).

use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3, Vector6};

use super::calibratable::{Calibratable, Fixture};
use super::hexapod::SeedProcedure;
use super::{Identifiable, Measurements};
use crate::accuracy::Rebuild;
use crate::error::{Error, Result};
use crate::mechanism::Mechanism;
use crate::pentapod::Pentapod;

use crate::pentapod::TOOL;

impl Pentapod {
    /// The tool tip in the effector frame.
    fn tip(&self) -> Vector3<f64> {
        Vector3::new(0.0, 0.0, self.tool_height())
    }
}

impl Identifiable<6, 5> for Pentapod {
    /// [`Rebuild::geometry_parameters`]' names but `tool.z`: `B0.x` ...,
    /// `ring(0).radius` ..., `ring(0).height` ....
    fn geometry_names(&self) -> Vec<String> {
        let mut v: Vec<String> = self
            .geometry_parameters()
            .into_iter()
            .map(|p| p.name)
            .collect();
        v.truncate(TOOL);
        v
    }

    fn geometry(&self) -> Vec<f64> {
        let mut v = self.geometry_values();
        v.truncate(TOOL);
        v
    }

    /// The ring heights are taken relative to this machine's tool length.
    fn with_geometry(&self, g: &[f64]) -> Result<Self> {
        if g.len() != TOOL {
            return Err(Error::InvalidInput {
                what: "pentapod geometry".into(),
                message: format!("expected {TOOL} values, got {}", g.len()),
            });
        }
        let mut v = g.to_vec();
        v.push(self.tool_height());
        self.with_geometry_values(&v)
    }

    /// [`Pentapod::inverse_geometry_jacobian`] (analytic) but its `tool.z` column.
    fn inverse_with_geometry_jacobian(
        &self,
        x: &Vector6<f64>,
        jac: &mut DMatrix<f64>,
    ) -> Result<SVector<f64, 5>> {
        let q = self.inverse(x)?;
        jac.copy_from(&self.inverse_geometry_jacobian(x)?.columns(0, TOOL));
        Ok(q)
    }

    /// `P = p + R (s - t e_z)`, the tool tip moved along the axis by `s_z - t` for a
    /// point on the axis ([`super::struts::platform_point`]).
    fn platform_point(
        &self,
        x: &Vector6<f64>,
        s: &Vector3<f64>,
    ) -> (Vector3<f64>, SMatrix<f64, 3, 6>) {
        super::struts::platform_point(&self.tip(), x, s)
    }

    /// The tool axis of `r` (its spin about the axis is dropped), through `c + t k`.
    fn coords_from_platform_frame(&self, c: &Vector3<f64>, r: &Matrix3<f64>) -> Vector6<f64> {
        let k = r.column(2).into_owned();
        self.coords_from_axis(&(c + k * self.tool_height()), &k)
    }

    fn pose_points(&self) -> usize {
        2
    }

    /// Every point on the tool axis (`x = y = 0` in the effector frame).
    fn check_fixture(&self, fixture: &[Vector3<f64>]) -> Result<()> {
        for (i, s) in fixture.iter().enumerate() {
            if s.x.hypot(s.y) > 1e-9 * s.norm().max(1.0) {
                return Err(Error::InvalidInput {
                    what: "fixture points".into(),
                    message: format!(
                        "point {} ({}, {}, {}) is off the pentapod's tool axis: the spin about \
                         the axis is free (the rings turn), so only points on it, (0, 0, h) \
                         in the effector frame, have a position",
                        i + 1,
                        s.x,
                        s.y,
                        s.z
                    ),
                });
            }
        }
        Ok(())
    }

    /// The least-squares line through the measured points against their heights `h_k`
    /// on the axis: `d = sum (h_k - h0)(m_k - m0) / sum (h_k - h0)^2`, `k = d / |d|`,
    /// origin `m0 - h0 k`; exact for exact measurements.
    fn measured_pose(
        &self,
        fixture: &[Vector3<f64>],
        points: &[Vector3<f64>],
    ) -> Result<Vector6<f64>> {
        let bad = |message: String| Error::InvalidInput {
            what: "fixture points".into(),
            message,
        };
        self.check_fixture(fixture)?;
        if fixture.len() != points.len() || fixture.len() < 2 {
            return Err(bad(format!(
                "a pentapod's pose needs at least two points on its tool axis and one \
                 measurement of each ({} and {})",
                fixture.len(),
                points.len()
            )));
        }
        let n = fixture.len() as f64;
        let h0 = fixture.iter().map(|s| s.z).sum::<f64>() / n;
        let m0 = points.iter().sum::<Vector3<f64>>() / n;
        let shh: f64 = fixture.iter().map(|s| (s.z - h0).powi(2)).sum();
        let spread = fixture.iter().map(|s| s.z.abs()).fold(1.0, f64::max);
        if !(shh.sqrt() > 1e-9 * spread) {
            return Err(bad(
                "the points on the tool axis are at one height: they give no direction".into(),
            ));
        }
        let d: Vector3<f64> = fixture
            .iter()
            .zip(points)
            .map(|(s, m)| (m - m0) * (s.z - h0))
            .sum::<Vector3<f64>>()
            / shh;
        let len = d.norm();
        if !(len > 0.0) || !len.is_finite() {
            return Err(bad("the measured points give no axis direction".into()));
        }
        let k = d / len;
        let origin = m0 - k * h0;
        Ok(self.coords_from_axis(&(origin + k * self.tool_height()), &k))
    }

    fn zero_readings(&self) -> Result<SVector<f64, 5>> {
        match self.zero_lengths() {
            Some(z) => Ok(z),
            None => self.inverse(&self.info().home()),
        }
    }
}

impl Calibratable<5> for Pentapod {
    /// Two points on the tool axis: the tool tip and `size` above it.
    fn fixture(&self, size: f64) -> Fixture {
        Fixture {
            points: vec![self.tip(), self.tip() + Vector3::new(0.0, 0.0, size)],
            description: format!(
                "two points on the tool axis, the tool tip and {size} mm above it (the \
                 spin about the axis is free)"
            ),
        }
    }

    /// None: the tool length, which trades against every ring height, is not among
    /// the identified parameters.
    fn must_hold(&self) -> Vec<usize> {
        Vec::new()
    }

    fn seed_procedure(
        &self,
        _zero: &SVector<f64, 5>,
        _meas: &Measurements,
    ) -> Result<SeedProcedure> {
        Err(Error::Unsupported {
            machine: self.info().name().to_string(),
            kind: self.info().kind().to_string(),
            analysis: "seed 001's procedure",
            reason: "it solves each strut's two joints from that strut's equations with the \
                     platform pose measured whole; a pentapod's ring joints turn and its pose \
                     is measured on the tool axis only: identify it by least squares"
                .into(),
        })
    }

    fn rewrite_file(
        &self,
        text: &str,
        file: &str,
        zero: Option<&[f64]>,
        comment: &str,
    ) -> Result<String> {
        crate::machine::with_pentapod_geometry(text, file, self, zero, comment)
    }
}
