//! What the identification analyses (`crate::analysis::identification`) need of a
//! machine beyond its equations ([`Identifiable`]): the fixture a simulated campaign
//! measures, the parameters that trade exactly against others, seed 001's procedure
//! where it applies, and its machine file rewritten with identified values. Strut
//! machines (hexapod, translational tripod) get it from [`StrutMachine`]; the pentapod
//! implements it itself (`identify/pentapod.rs`).

use nalgebra::{SVector, Vector3};

use super::hexapod::{seed_procedure, SeedProcedure};
use super::struts::StrutMachine;
use super::{Identifiable, Measurements};
use crate::error::Result;

/// The fixture of a simulated campaign: its points in the platform frame and what it is
/// in words.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Fixture {
    /// Points (platform frame, mm).
    pub points: Vec<Vector3<f64>>,
    /// E.g. "an equilateral triangle of circumradius 200 mm on the platform".
    pub description: String,
}

/// A machine the identification analyses run on (pose X..C, `A` actuators).
pub trait Calibratable<const A: usize>: Identifiable<6, A> {
    /// The fixture of a simulated campaign, of size `size` (mm), in the platform frame:
    /// strut machines measure seed 001's triangle of circumradius `size`; a machine
    /// whose platform spin is free, points on its tool axis `size` apart.
    fn fixture(&self, size: f64) -> Fixture;

    /// Parameters that trade exactly against others for every measurement this
    /// machine can give (indices of [`super::parameter_names`]): a study holds them.
    fn must_hold(&self) -> Vec<usize>;

    /// Seed 001's procedure (one strut's parameters from its own equations), or
    /// [`crate::Error::Unsupported`] where the machine has no such decoupling.
    fn seed_procedure(&self, zero: &SVector<f64, A>, meas: &Measurements) -> Result<SeedProcedure>;

    /// The machine file `text` (named `file`) rewritten with this machine's geometry and
    /// the zero lengths `zero` (`[calibration] zero_lengths`), headed by `comment`.
    fn rewrite_file(
        &self,
        text: &str,
        file: &str,
        zero: Option<&[f64]>,
        comment: &str,
    ) -> Result<String>;
}

impl<M: StrutMachine<A>, const A: usize> Calibratable<A> for M {
    /// Seed 001's triangle ([`super::simulate::triangle`]) in the platform's XY plane.
    fn fixture(&self, size: f64) -> Fixture {
        Fixture {
            points: super::simulate::triangle(size, 0.0),
            description: format!(
                "an equilateral triangle of circumradius {size} mm on the platform"
            ),
        }
    }

    fn must_hold(&self) -> Vec<usize> {
        StrutMachine::must_hold(self)
    }

    fn seed_procedure(&self, zero: &SVector<f64, A>, meas: &Measurements) -> Result<SeedProcedure> {
        seed_procedure(self, zero, meas)
    }

    fn rewrite_file(
        &self,
        text: &str,
        file: &str,
        zero: Option<&[f64]>,
        comment: &str,
    ) -> Result<String> {
        crate::machine::with_strut_geometry(text, file, &self.struts(), zero, comment)
    }
}
