//! Limits of a machine and the violations a check reports.
//!
//! A limit check never answers with a bare boolean: it lists every violated limit
//! with its name, the value found and the bound it crossed, in user units, so that a
//! person can see which limit binds and by how much.

use std::fmt;
use std::sync::Arc;

use serde::Serialize;

use crate::units::Quantity;

/// Which side of a bound was crossed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// The value is below its minimum.
    Min,
    /// The value is above its maximum.
    Max,
}

/// The family of a limit, for grouping (workspace maps count points per family).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum LimitKind {
    /// Actuator position (strut length, slider position, joint angle).
    ActuatorPosition,
    /// Actuator speed.
    ActuatorVelocity,
    /// Actuator acceleration.
    ActuatorAcceleration,
    /// Tilt of the spindle / platform relative to the base.
    Tilt,
    /// Collision of a strut with the spindle (seed 000: phi <= lambda).
    StrutSpindleCollision,
    /// Stroke of a passive joint (e.g. the telescopic centre leg of a Tricept).
    PassiveJoint,
    /// Angle of a universal or spherical joint (cone limit).
    JointAngle,
    /// Two struts closer than their diameter.
    StrutInterference,
    /// A pose coordinate outside its travel (a controller's soft limit, LinuxCNC's
    /// `[AXIS_n] MIN_LIMIT / MAX_LIMIT`).
    AxisTravel,
}

/// The name of a limit (`strut 3 length`), as shared text: a mechanism can name its
/// limits once, and a motion that stays beyond a limit for a million samples then
/// clones a pointer per sample instead of formatting and allocating a string (a
/// hexapod program beyond its struts' stroke ran five times slower than one within
/// them). Reads as a `str` (`Deref`), compares equal to strings, prints and
/// serialises as its text.
#[derive(Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LimitName(Arc<str>);

impl LimitName {
    /// The name's text.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

impl std::ops::Deref for LimitName {
    type Target = str;
    fn deref(&self) -> &str {
        &self.0
    }
}

impl std::borrow::Borrow<str> for LimitName {
    fn borrow(&self) -> &str {
        &self.0
    }
}

impl AsRef<str> for LimitName {
    fn as_ref(&self) -> &str {
        &self.0
    }
}

impl fmt::Display for LimitName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl fmt::Debug for LimitName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(&*self.0, f)
    }
}

impl Serialize for LimitName {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.0)
    }
}

impl From<String> for LimitName {
    fn from(s: String) -> Self {
        LimitName(s.into())
    }
}

impl From<&str> for LimitName {
    fn from(s: &str) -> Self {
        LimitName(s.into())
    }
}

impl From<LimitName> for String {
    fn from(n: LimitName) -> Self {
        n.0.to_string()
    }
}

impl PartialEq<str> for LimitName {
    fn eq(&self, other: &str) -> bool {
        &*self.0 == other
    }
}

impl PartialEq<&str> for LimitName {
    fn eq(&self, other: &&str) -> bool {
        &*self.0 == *other
    }
}

impl PartialEq<String> for LimitName {
    fn eq(&self, other: &String) -> bool {
        *self.0 == **other
    }
}

impl PartialEq<LimitName> for String {
    fn eq(&self, other: &LimitName) -> bool {
        **self == *other.0
    }
}

impl PartialEq<LimitName> for &str {
    fn eq(&self, other: &LimitName) -> bool {
        **self == *other.0
    }
}

/// The name of strut `strut`'s length limit, `strut {strut} length`: every strut
/// machine's (the hexapod's limit table and [`PositionLimits::strut_lengths`]).
pub(crate) fn strut_length_name(strut: &str) -> String {
    format!("strut {strut} length")
}

/// The position limits of a machine's actuators, each named once when the machine is
/// built (`joint A1 position`, `slider U position`, `strut 3 length`, ...): checked
/// per pose without formatting a name (a motion beyond one clones it per sample).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PositionLimits(Arc<[LimitName]>);

impl PositionLimits {
    /// The names of `actuators`' position limits: `"{prefix} {actuator} position"`.
    pub(crate) fn new(prefix: &str, actuators: &[crate::mechanism::Actuator]) -> Self {
        Self::from_fn(actuators, |_, a| format!("{prefix} {} position", a.name))
    }

    /// The names of `actuators`' position limits, `name(i, actuator)` for actuator
    /// `i` (a machine whose drives are of several kinds, a strut's `length`).
    pub(crate) fn from_fn(
        actuators: &[crate::mechanism::Actuator],
        name: impl Fn(usize, &crate::mechanism::Actuator) -> String,
    ) -> Self {
        PositionLimits(
            actuators
                .iter()
                .enumerate()
                .map(|(i, a)| LimitName::from(name(i, a)))
                .collect(),
        )
    }

    /// The length limits of struts `actuators` ([`strut_length_name`]).
    pub(crate) fn strut_lengths(actuators: &[crate::mechanism::Actuator]) -> Self {
        Self::from_fn(actuators, |_, a| strut_length_name(&a.name))
    }

    /// Pushes a violation when actuator `i`'s `value` is outside its range (a check
    /// interleaved with others per actuator; `actuator` is the one the names were made
    /// for at `i`).
    pub(crate) fn check_one(
        &self,
        i: usize,
        actuator: &crate::mechanism::Actuator,
        value: f64,
        out: &mut Vec<Violation>,
    ) {
        actuator.range.check(
            || self.0[i].clone(),
            LimitKind::ActuatorPosition,
            actuator.quantity,
            value,
            out,
        );
    }

    /// Pushes a violation for every actuator (of those the names were made for)
    /// whose value in `values` is outside its range.
    pub(crate) fn check(
        &self,
        actuators: &[crate::mechanism::Actuator],
        values: &[f64],
        out: &mut Vec<Violation>,
    ) {
        for ((a, name), v) in actuators.iter().zip(self.0.iter()).zip(values) {
            a.range.check(
                || name.clone(),
                LimitKind::ActuatorPosition,
                a.quantity,
                *v,
                out,
            );
        }
    }
}

/// One violated limit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Violation {
    /// Human-readable name of the limit, e.g. `strut e length`.
    pub limit: LimitName,
    /// Family of the limit.
    pub kind: LimitKind,
    /// Minimum or maximum.
    pub side: Side,
    /// Value found, in user units.
    pub value: f64,
    /// The bound it crossed, in user units.
    pub bound: f64,
    /// By how much the bound is crossed (always positive), in user units.
    pub excess: f64,
    /// Unit of `value`, `bound` and `excess`.
    pub unit: &'static str,
}

impl Violation {
    /// Builds a violation from internal values (mm / rad), converting to user units.
    pub fn new(
        limit: impl Into<LimitName>,
        kind: LimitKind,
        side: Side,
        quantity: Quantity,
        value: f64,
        bound: f64,
    ) -> Self {
        let value = quantity.to_user(value);
        let bound = quantity.to_user(bound);
        Violation {
            limit: limit.into(),
            kind,
            side,
            value,
            bound,
            excess: (value - bound).abs(),
            unit: quantity.unit(),
        }
    }
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (verb, word) = match self.side {
            Side::Min => ("below", "minimum"),
            Side::Max => ("above", "maximum"),
        };
        write!(
            f,
            "{} {:.3} {} is {} its {} {:.3} {} by {:.3} {}",
            self.limit,
            self.value,
            self.unit,
            verb,
            word,
            self.bound,
            self.unit,
            self.excess,
            self.unit
        )
    }
}

/// A violated limit as a number in the mechanism's own list of its limits, with the
/// value and bound in internal units (mm, rad): what a batch of a million poses keeps
/// instead of a named [`Violation`] per row
/// ([`crate::mechanism::abilities::inverse_first_limit`]); the mechanism turns it into
/// the violation ([`crate::mechanism::BlockKernels::limit_violation`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LimitCode {
    /// The limit's number (the mechanism's own numbering).
    pub id: u32,
    /// Minimum or maximum.
    pub side: Side,
    /// Quantity of value and bound.
    pub quantity: Quantity,
    /// Value found (internal units).
    pub value: f64,
    /// The bound it crossed (internal units).
    pub bound: f64,
}

/// The first violated limit of a pose: a [`LimitCode`] where the mechanism numbers its
/// limits, otherwise the [`Violation`] itself.
#[derive(Debug, Clone, PartialEq)]
pub enum FirstLimit {
    /// A code of the mechanism's own numbering.
    Code(LimitCode),
    /// The violation.
    Violation(Violation),
}

/// A closed interval `[min, max]` in internal units, with optional rate limits.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Range {
    /// Lower bound (mm or rad).
    pub min: f64,
    /// Upper bound (mm or rad).
    pub max: f64,
}

/// The tolerance of every range, relative to its size (the larger magnitude of its
/// finite bounds): a value within it of a bound is on the bound, inside the range.
/// One rule for every limit in both directions: the pose forward kinematics finds for
/// a strut exactly at its longest length, solved back, gives that length to within
/// rounding (1e-13 mm on a 1000 mm strut), and is as reachable as the strut said. A
/// 1000 mm stroke's tolerance is 1e-6 mm, a 119 deg joint's 2e-9 rad.
pub const RANGE_TOLERANCE: f64 = 1e-9;

impl Range {
    /// The side and bound crossed by `value` beyond [`RANGE_TOLERANCE`], or `None`
    /// inside the range or within the tolerance of a bound.
    #[inline]
    pub fn crossed(&self, value: f64) -> Option<(Side, f64)> {
        // The tolerance is worked out only for a value outside the exact range: the
        // common case, inside, costs two comparisons.
        if value < self.min {
            (value < self.min - self.slack()).then_some((Side::Min, self.min))
        } else if value > self.max {
            (value > self.max + self.slack()).then_some((Side::Max, self.max))
        } else {
            None
        }
    }

    /// [`RANGE_TOLERANCE`] times the range's size: the larger magnitude of its finite
    /// bounds (0 for a range without one).
    fn slack(&self) -> f64 {
        let finite = |v: f64| if v.is_finite() { v.abs() } else { 0.0 };
        RANGE_TOLERANCE * finite(self.min).max(finite(self.max))
    }

    /// Pushes a violation when `value` is outside the range; the name is only built
    /// (allocated) when there is something to report.
    #[inline]
    pub fn check<N: Into<LimitName>>(
        &self,
        name: impl FnOnce() -> N,
        kind: LimitKind,
        quantity: Quantity,
        value: f64,
        out: &mut Vec<Violation>,
    ) {
        if let Some((side, bound)) = self.crossed(value) {
            out.push(Violation::new(name(), kind, side, quantity, value, bound));
        }
    }
}

/// Soft limits of a machine's pose coordinates (LinuxCNC's `[AXIS_n] MIN_LIMIT` and
/// `MAX_LIMIT`): a range per coordinate, in internal units, or none.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct AxisLimits {
    /// `(coordinate index, range)` of every limited coordinate.
    pub ranges: Vec<(usize, Range)>,
}

impl AxisLimits {
    /// Pushes a violation for every coordinate of `x` outside its range.
    pub fn check<const P: usize>(
        &self,
        coordinates: &[crate::mechanism::Coordinate; P],
        x: &nalgebra::SVector<f64, P>,
        out: &mut Vec<Violation>,
    ) {
        for (k, r) in &self.ranges {
            if let Some(c) = coordinates.get(*k) {
                r.check(
                    || format!("axis {} travel", c.name),
                    LimitKind::AxisTravel,
                    c.quantity,
                    x[*k],
                    out,
                );
            }
        }
    }

    /// Whether no coordinate is limited.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::{LimitKind, LimitName, Side, Violation};
    use crate::units::Quantity;

    /// A limit's name reads, compares, prints and serialises as its text, whether it
    /// was formatted for the call or cloned from a machine's table.
    #[test]
    fn a_limit_name_is_its_text() {
        let shared = LimitName::from("strut 3 length");
        let formatted = LimitName::from(format!("strut {} length", 3));
        assert_eq!(shared, formatted);
        assert_eq!(shared.clone(), shared);
        assert_ne!(shared, LimitName::from("strut 4 length"));
        let (text, owned) = ("strut 3 length", String::from("strut 3 length"));
        assert!(shared == text);
        assert!(text == shared);
        assert!(shared == owned);
        assert!(owned == shared);
        assert_eq!(shared.len(), 14);
        assert!(shared.starts_with("strut"));
        assert_eq!(
            format!("{shared} / {shared:?}"),
            "strut 3 length / \"strut 3 length\""
        );
        assert_eq!(String::from(shared.clone()), "strut 3 length");
        let v = Violation::new(
            shared,
            LimitKind::ActuatorPosition,
            Side::Max,
            Quantity::Length,
            1002.0,
            1000.0,
        );
        let json = serde_json::to_value(&v).unwrap();
        assert_eq!(json["limit"], "strut 3 length");
        assert_eq!(json["excess"], 2.0);
        let mut m = std::collections::HashMap::new();
        m.insert(v.limit.clone(), 1);
        assert_eq!(m.get("strut 3 length"), Some(&1));
    }
}
