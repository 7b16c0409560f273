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

    /// The factor of [`Quantity::to_user`]: `to_user(v) == v * user_scale()` bit for
    /// bit (1, or `180 / pi` as in `f64::to_degrees`).
    pub fn user_scale(self) -> f64 {
        match self {
            Quantity::Length => 1.0,
            Quantity::Angle => 180.0f64 / std::f64::consts::PI,
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

#[cfg(test)]
mod tests {
    use super::Quantity;

    /// The motion statistics multiply by `user_scale` instead of calling `to_user`:
    /// the bits must agree on every value, specials included.
    #[test]
    fn user_scale_is_to_user_bit_for_bit() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut values = vec![0.0, -0.0, 1.0, f64::MIN_POSITIVE, f64::MAX, f64::INFINITY];
        values.extend([f64::NEG_INFINITY, f64::NAN, 5e-324]);
        for _ in 0..100_000 {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            values.push(f64::from_bits(state));
            values.push((state >> 11) as f64 / (1u64 << 53) as f64 * 20.0 - 10.0);
        }
        for q in [Quantity::Length, Quantity::Angle] {
            for &v in &values {
                let (a, b) = (q.to_user(v), v * q.user_scale());
                assert!(
                    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                    "{v:e}"
                );
            }
        }
    }
}
