//! Tolerances and the first-order error budget (seed 003): each toleranced parameter's
//! tool-point error at its tolerance, `|dp/dp_k| t_k`, their sum (every deviation at
//! its worst) and root sum of squares.

use nalgebra::SVector;
use serde::Serialize;

use super::{sensitivities, Parameter, ParameterKind, Parametric, PoseError};
use crate::error::{Error, Result};

/// How a deviation is distributed within its tolerance `t`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Distribution {
    /// Uniform in `[-t, t]` (standard deviation `t / sqrt 3`).
    Uniform,
    /// Normal with `t` as three standard deviations.
    Normal,
}

impl std::str::FromStr for Distribution {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "uniform" => Ok(Distribution::Uniform),
            "normal" => Ok(Distribution::Normal),
            other => Err(Error::InvalidInput {
                what: "distribution".into(),
                message: format!("unknown distribution `{other}`, expected `uniform` or `normal`"),
            }),
        }
    }
}

/// A tolerance on one parameter of a machine.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Tolerance {
    /// Index into the machine's [`Parametric::parameters`].
    pub parameter: usize,
    /// Its tolerance (mm or rad): the bound of a uniform distribution, three standard
    /// deviations of a normal one.
    pub value: f64,
    /// Distribution in Monte Carlo.
    pub distribution: Distribution,
}

impl Tolerance {
    /// Standard deviation of the deviation.
    pub fn std(&self) -> f64 {
        match self.distribution {
            Distribution::Uniform => self.value / 3f64.sqrt(),
            Distribution::Normal => self.value / 3.0,
        }
    }
}

/// The same tolerance on every parameter of the given kinds (`value` in internal units).
pub fn tolerances_of_kind(
    params: &[Parameter],
    kinds: &[ParameterKind],
    value: f64,
    distribution: Distribution,
) -> Vec<Tolerance> {
    params
        .iter()
        .enumerate()
        .filter(|(_, p)| kinds.contains(&p.kind))
        .map(|(k, _)| Tolerance {
            parameter: k,
            value,
            distribution,
        })
        .collect()
}

/// One line of an error budget.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BudgetItem {
    /// The parameter's name.
    pub name: String,
    /// What kind of parameter it is.
    pub kind: ParameterKind,
    /// Tolerance (mm or rad).
    pub tolerance: f64,
    /// Tool-point error at the tolerance, first order (mm): `|dp/dd| t`.
    pub position: f64,
    /// Tool-frame rotation at the tolerance, first order (rad).
    pub orientation: f64,
}

/// An error budget at one machine state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Budget {
    /// Items, largest position contribution first.
    pub items: Vec<BudgetItem>,
    /// Sum of the position contributions (mm): every deviation at its worst.
    pub worst_case: f64,
    /// Root sum of squares of the position contributions (mm).
    pub rss: f64,
}

impl Budget {
    /// A budget of these items: sorted, largest position contribution first, with their
    /// worst-case sum and root sum of squares.
    pub fn from_items(mut items: Vec<BudgetItem>) -> Self {
        items.sort_by(|a, b| b.position.total_cmp(&a.position));
        let worst_case = items.iter().map(|i| i.position).sum();
        let rss = items
            .iter()
            .map(|i| i.position * i.position)
            .sum::<f64>()
            .sqrt();
        Budget {
            items,
            worst_case,
            rss,
        }
    }

    /// The budget of tolerances `tol` from sensitivities `sens` to `params`.
    pub fn from_sensitivities(
        params: &[Parameter],
        sens: &[PoseError],
        tol: &[Tolerance],
    ) -> Result<Self> {
        let items = tol
            .iter()
            .map(|t| {
                let (p, s) = params
                    .get(t.parameter)
                    .zip(sens.get(t.parameter))
                    .ok_or_else(|| Error::InvalidInput {
                        what: "tolerance".into(),
                        message: format!(
                            "parameter index {} beyond the machine's {} parameters",
                            t.parameter,
                            params.len()
                        ),
                    })?;
                Ok(BudgetItem {
                    name: p.name.clone(),
                    kind: p.kind,
                    tolerance: t.value,
                    position: s.position.norm() * t.value,
                    orientation: s.orientation.norm() * t.value,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Budget::from_items(items))
    }
}

/// The error budget of tolerances `tol` at pose `x`.
pub fn budget<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    tol: &[Tolerance],
) -> Result<Budget>
where
    M: Parametric<P, A>,
{
    Budget::from_sensitivities(&m.parameters(), &sensitivities(m, x)?, tol)
}
