//! Units at the user-facing boundary.
//!
//! Internally pkm computes in millimetres and radians; files, command lines and reports
//! use millimetres and degrees (mm/min for feeds, as on CNC machines). [`Quantity`]
//! says which a number is and converts it.

use serde::Serialize;

/// The physical kind of a scalar coordinate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Quantity {
    /// A length: mm internally and at the boundary.
    Length,
    /// An angle: radians internally, degrees at the boundary.
    Angle,
}

impl Quantity {
    /// Unit symbol shown to users.
    pub fn unit(self) -> &'static str {
        match self {
            Quantity::Length => "mm",
            Quantity::Angle => "deg",
        }
    }

    /// Unit of the `order`-th time derivative (`mm/s`, `deg/s^2`, ...).
    pub fn rate_unit(self, order: u8) -> &'static str {
        match (self, order) {
            (Quantity::Length, 0) => "mm",
            (Quantity::Length, 1) => "mm/s",
            (Quantity::Length, _) => "mm/s^2",
            (Quantity::Angle, 0) => "deg",
            (Quantity::Angle, 1) => "deg/s",
            (Quantity::Angle, _) => "deg/s^2",
        }
    }

    /// Converts an internal value (mm or rad) to the user unit (mm or deg).
    pub fn to_user(self, v: f64) -> f64 {
        match self {
            Quantity::Length => v,
            Quantity::Angle => v.to_degrees(),
        }
    }

    /// Converts a user value (mm or deg) to the internal unit (mm or rad).
    pub fn from_user(self, v: f64) -> f64 {
        match self {
            Quantity::Length => v,
            Quantity::Angle => v.to_radians(),
        }
    }
}
