//! The one error type of the `pkm` library.

use crate::limits::Violation;

/// Everything that can go wrong in `pkm`.
///
/// Every variant carries structured fields so that a caller (the CLI, a Python binding,
/// a sweep) can report the problem precisely or react to it programmatically.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A machine file could not be read or does not describe a valid machine.
    #[error("{}", format_file_error(.file, .line, .column, .field, .message))]
    MachineFile {
        /// File name (or `<string>` for in-memory sources).
        file: String,
        /// 1-based line, when known.
        line: Option<usize>,
        /// 1-based column, when known.
        column: Option<usize>,
        /// Dotted path of the offending field (`struts[1].length`), empty when the
        /// problem is in the syntax itself.
        field: String,
        /// What was wrong and what was expected.
        message: String,
    },
    /// A value given by the user is not acceptable (wrong count, not finite, ...).
    #[error("{what}: {message}")]
    InvalidInput {
        /// The input concerned (`--pose`, `actuators`, a CSV column, ...).
        what: String,
        /// What was wrong and what was expected.
        message: String,
    },
    /// The requested pose or actuator set violates one or more limits of the machine.
    #[error("unreachable: {}", join_violations(.violations))]
    Unreachable {
        /// Every violated limit, with its value and bound.
        violations: Vec<Violation>,
    },
    /// The pose cannot be produced by this mechanism at all (its motion constraint
    /// forbids it), independent of any stroke limit.
    #[error("pose not attainable by the mechanism: {reason}")]
    NotAttainable {
        /// Why, with the numbers involved (words when displayed).
        reason: Unattainable,
    },
    /// An iterative solver did not converge.
    #[error("{solver} did not converge after {iterations} iterations (residual {residual:.3e})")]
    NotConverged {
        /// Which solver (`forward kinematics`, ...).
        solver: &'static str,
        /// Iterations performed.
        iterations: usize,
        /// Final residual norm in the solver's units (mm for strut lengths).
        residual: f64,
    },
    /// An identification problem whose data cannot determine a combination of the free
    /// parameters.
    #[error(
        "not identifiable: {combination} (relative singular value {relative_singular_value:.2e})"
    )]
    NotIdentifiable {
        /// The combination, named, with advice.
        combination: String,
        /// Its singular value relative to the largest.
        relative_singular_value: f64,
    },
    /// The configuration is singular (or too close to it) for the requested operation.
    #[error("singular configuration: {what} (reciprocal condition number {rcond:.3e})")]
    Singular {
        /// What is singular (`Jacobian`, ...).
        what: String,
        /// Reciprocal condition number found (0 = exactly singular).
        rcond: f64,
    },
    /// The machine cannot run this analysis; `reason` says why (what it lacks).
    #[error("{machine}: {analysis} is not available for a {kind} machine: {reason}")]
    Unsupported {
        /// Machine name.
        machine: String,
        /// Machine type (`p3rp/head`, ...).
        kind: String,
        /// The analysis asked for (`identification`, `--all-solutions`, ...).
        analysis: &'static str,
        /// Why the machine cannot do it.
        reason: String,
    },
}

/// [`Error::category`] of [`Error::NotAttainable`].
pub(crate) const NO_SOLUTION: &str = "no solution";

impl Error {
    /// The failure without its numbers: one key per kind of failure, for tables that
    /// count failures over many poses (a workspace map's binding limits, a batch's
    /// causes). `no solution` for a pose the mechanism cannot attain, `no solution
    /// found (<solver> did not converge)`, `singular`, `unreachable`; other errors are
    /// their message.
    pub fn category(&self) -> String {
        match self {
            Error::NotAttainable { .. } => NO_SOLUTION.into(),
            Error::NotConverged { solver, .. } => {
                format!("no solution found ({solver} did not converge)")
            }
            Error::Singular { .. } => "singular".into(),
            Error::Unreachable { .. } => "unreachable".into(),
            other => other.to_string(),
        }
    }
}

fn format_file_error(
    file: &str,
    line: &Option<usize>,
    column: &Option<usize>,
    field: &str,
    message: &str,
) -> String {
    let mut s = file.to_string();
    if let Some(l) = line {
        s.push_str(&format!(":{l}"));
        if let Some(c) = column {
            s.push_str(&format!(":{c}"));
        }
    }
    s.push_str(": ");
    if !field.is_empty() {
        s.push_str(&format!("field `{field}`: "));
    }
    s.push_str(message);
    s
}

fn join_violations(v: &[Violation]) -> String {
    v.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join("; ")
}

/// Result type of the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Why a pose is not attainable, with the numbers involved. The common reasons of a
/// robot's inverse are kept as numbers and put in words only when displayed: a
/// workspace map meets millions of poses out of reach and shows none of the messages
/// (formatting them was an eighth of a 6R robot's map).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Unattainable {
    /// In words.
    Text(std::borrow::Cow<'static, str>),
    /// The tool point is beyond the links' reach from the robot's base (mm).
    BeyondReach {
        /// Distance of the tool point from the base (mm).
        distance: f64,
        /// The longest reach of the links (mm).
        reach: f64,
    },
    /// A point of the wrist (`what`: "the wrist centre would be", "axes 5 and 6 would
    /// meet") would be nearer axis 1 than the arm's plane is offset from it (mm).
    ShoulderOffset {
        /// The point, as a sentence's start.
        what: &'static str,
        /// Its distance from axis 1 (mm).
        distance: f64,
        /// The offset of the arm's plane from axis 1 (mm).
        offset: f64,
    },
    /// A point (`what`: "the wrist centre", "axis 4") would be outside the ring the
    /// elbow's two links span around axis 2 (mm).
    ElbowSpan {
        /// The point.
        what: &'static str,
        /// Its distance from axis 2 (mm).
        distance: f64,
        /// The nearest the elbow reaches (mm).
        min: f64,
        /// The farthest (mm).
        max: f64,
    },
    /// A strut of fixed length whose carriage runs on a vertical guide cannot reach its
    /// platform joint: the joint is farther from the guide's axis than the strut is
    /// long (mm). A hybrid machine's map meets it at every point beyond its struts'
    /// reach (formatting its three numbers was a third of such a map's time).
    StrutReach {
        /// The strut's actuator.
        strut: String,
        /// The platform joint.
        joint: String,
        /// The strut's length `L` (mm).
        length: f64,
        /// The joint's distance from the guide's axis (mm).
        distance: f64,
    },
}

impl std::fmt::Display for Unattainable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unattainable::Text(t) => f.write_str(t),
            Unattainable::BeyondReach { distance, reach } => write!(
                f,
                "the tool point is {distance:.3} mm from the robot's base, beyond the \
                 {reach:.3} mm the links can reach"
            ),
            Unattainable::ShoulderOffset {
                what,
                distance,
                offset,
            } => write!(
                f,
                "{what} {distance:.3} mm from axis 1, closer than the {offset:.3} mm the \
                 arm's plane is offset from it"
            ),
            Unattainable::ElbowSpan {
                what,
                distance,
                min,
                max,
            } => write!(
                f,
                "{what} would be {distance:.3} mm from axis 2, outside the {min:.3} to \
                 {max:.3} mm the elbow spans"
            ),
            Unattainable::StrutReach {
                strut,
                joint,
                length,
                distance,
            } => write!(
                f,
                "strut {strut} (L = {length:.3} mm) cannot reach platform joint {joint}: the \
                 joint is {distance:.3} mm from its guide, {:.3} mm beyond the strut's length",
                distance - length
            ),
        }
    }
}

impl From<String> for Unattainable {
    fn from(s: String) -> Self {
        Unattainable::Text(s.into())
    }
}

impl From<&'static str> for Unattainable {
    fn from(s: &'static str) -> Self {
        Unattainable::Text(s.into())
    }
}
