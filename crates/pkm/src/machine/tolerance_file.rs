//! Tolerances and deviations by parameter name, for any machine: `[[tolerance]]`
//! entries (in a serial machine file or a tolerances file) and deviations files
//! (`"A1.x" = 0.01`). Values in the parameter's user unit (mm; deg for angles).

use serde::Deserialize;

use super::source::{Seg, Source};
use crate::accuracy::{Distribution, Parameter, Tolerance};
use crate::error::{Error, Result};

/// One `[[tolerance]]` entry.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ToleranceFile {
    deviation: String,
    value: f64,
    #[serde(default)]
    distribution: Option<String>,
}

fn key(k: &str) -> Seg {
    Seg::Key(k.into())
}

/// The parameter named `name`, or a message saying what names look like.
fn lookup(params: &[Parameter], name: &str) -> std::result::Result<usize, String> {
    params.iter().position(|p| p.name == name).ok_or_else(|| {
        let examples: Vec<&str> = params.iter().take(6).map(|p| p.name.as_str()).collect();
        format!(
            "unknown deviation `{name}`: this machine's {} parameters are named like {} \
             (`pkm errors MACHINE --json` lists them all)",
            params.len(),
            examples.join(", ")
        )
    })
}

/// `[[tolerance]]` entries by name, in the parameter's user unit.
pub(crate) fn tolerances(
    src: &Source,
    params: &[Parameter],
    entries: &[ToleranceFile],
) -> Result<Vec<Tolerance>> {
    let mut out: Vec<Tolerance> = Vec::new();
    for (i, t) in entries.iter().enumerate() {
        let at = |k: &str| vec![key("tolerance"), Seg::Index(i), key(k)];
        let k = lookup(params, &t.deviation).map_err(|m| src.error(&at("deviation"), m))?;
        if out.iter().any(|o| o.parameter == k) {
            return Err(src.error(
                &at("deviation"),
                format!("`{}` has a tolerance already", t.deviation),
            ));
        }
        if !(t.value > 0.0) {
            return Err(src.error(
                &at("value"),
                format!("expected a tolerance > 0, found {}", t.value),
            ));
        }
        let value = params[k].quantity.from_user(t.value);
        crate::accuracy::check_tolerance_magnitude(params[k].quantity, value)
            .map_err(|m| src.error(&at("value"), m))?;
        let distribution = match t.distribution.as_deref() {
            None => Distribution::Uniform,
            Some(d) => d
                .parse::<Distribution>()
                .map_err(|e| src.error(&at("distribution"), e.to_string()))?,
        };
        out.push(Tolerance {
            parameter: k,
            value,
            distribution,
        });
    }
    Ok(out)
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TolerancesOnly {
    tolerance: Vec<ToleranceFile>,
}

/// Reads a tolerances file (`[[tolerance]]` entries with `deviation`, `value`,
/// optional `distribution`) for a machine with parameters `params`; errors name the
/// file, line and field.
pub fn read_tolerances(params: &[Parameter], text: &str, file: &str) -> Result<Vec<Tolerance>> {
    let src = Source::parse(file, text)?;
    src.check_numbers()?;
    let f: TolerancesOnly = src.deserialize()?;
    tolerances(&src, params, &f.tolerance)
}

/// Reads a deviations file (`"A1.x" = 0.01`, one value per named parameter; mm, deg
/// for angles) for a machine with parameters `params`: `(index, value)` in internal
/// units; errors name the file, line and parameter.
pub fn read_deviations(params: &[Parameter], text: &str, file: &str) -> Result<Vec<(usize, f64)>> {
    let src = Source::parse(file, text)?;
    src.check_numbers()?;
    let values: std::collections::BTreeMap<String, f64> = src.deserialize()?;
    values
        .iter()
        .map(|(name, v)| {
            let k = lookup(params, name).map_err(|m| src.error(&[key(name)], m))?;
            let v = params[k].quantity.from_user(*v);
            crate::accuracy::check_tolerance_magnitude(params[k].quantity, v)
                .map_err(|m| src.error(&[key(name)], m))?;
            Ok((k, v))
        })
        .collect::<Result<Vec<_>, Error>>()
}
