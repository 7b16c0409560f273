//! The tolerance options `pkm errors` and `pkm motion --accuracy` share.

use anyhow::{bail, Context, Result};
use clap::Args;
use pkm::analysis::accuracy::{KindTolerances, Tolerances};
use std::path::PathBuf;

/// Which tolerances: a file, one per kind of parameter, or the machine file's.
#[derive(Args, Debug, Clone, Default)]
pub struct ToleranceArgs {
    /// Tolerance of every joint-centre coordinate (mm).
    #[arg(long, allow_negative_numbers = true)]
    pub joint_tolerance: Option<f64>,
    /// Tolerance of every zero length and linear drive positioning (mm).
    #[arg(long, allow_negative_numbers = true)]
    pub length_tolerance: Option<f64>,
    /// Tolerance of every link dimension and linear link deviation (mm).
    #[arg(long, allow_negative_numbers = true)]
    pub link_tolerance: Option<f64>,
    /// Tolerance of every angular parameter, revolute drives included (deg).
    #[arg(long, allow_negative_numbers = true)]
    pub angle_tolerance: Option<f64>,
    /// With the per-kind tolerances: `uniform` (in +-tolerance, the default) or `normal`
    /// (tolerance = 3 sigma).
    #[arg(long)]
    pub distribution: Option<String>,
    /// Tolerances file (`[[tolerance]]` entries with `deviation`, `value`, optional
    /// `distribution`) instead of the machine file's or the per-kind ones.
    #[arg(long)]
    pub tolerances: Option<PathBuf>,
}

impl ToleranceArgs {
    /// Whether any was given.
    pub fn given(&self) -> bool {
        self.tolerances.is_some()
            || self.distribution.is_some()
            || [
                self.joint_tolerance,
                self.length_tolerance,
                self.link_tolerance,
                self.angle_tolerance,
            ]
            .iter()
            .any(Option::is_some)
    }

    /// The tolerances asked for on a machine with parameters `params`.
    pub fn tolerances(&self, params: &[pkm::accuracy::Parameter]) -> Result<Tolerances> {
        let read = |p: &std::path::Path| {
            std::fs::read_to_string(p).with_context(|| format!("cannot read {}", p.display()))
        };
        let by_kind = [
            self.joint_tolerance,
            self.length_tolerance,
            self.link_tolerance,
            self.angle_tolerance,
        ];
        Ok(match &self.tolerances {
            Some(p) => {
                if by_kind.iter().any(Option::is_some) {
                    bail!(
                    "--tolerances and --joint/length/link/angle-tolerance: give one or the other"
                );
                }
                Tolerances::Given(pkm::machine::read_tolerances(
                    params,
                    &read(p)?,
                    &p.display().to_string(),
                )?)
            }
            None if by_kind.iter().any(Option::is_some) || self.distribution.is_some() => {
                let d = KindTolerances::default();
                Tolerances::ByKind(KindTolerances {
                    joint: self.joint_tolerance.unwrap_or(d.joint),
                    zero: self.length_tolerance.unwrap_or(d.zero),
                    length: self.link_tolerance.unwrap_or(d.length),
                    angle: self.angle_tolerance.map(f64::to_radians).unwrap_or(d.angle),
                    distribution: match &self.distribution {
                        Some(t) => t.parse()?,
                        None => d.distribution,
                    },
                })
            }
            None => Tolerances::Default,
        })
    }
}
