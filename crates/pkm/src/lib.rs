//! # pkm — kinematics and accuracy of parallel, hybrid and serial machine tools
//!
//! The library behind the `pkm` command. It describes a machine by a text file
//! ([`Machine`]), solves its inverse and forward kinematics with every design limit
//! checked ([`Mechanism`], [`Violation`]), and provides the rotation conventions and
//! pose algebra the analyses share ([`rotation`], [`pose`]).
//!
//! Units: millimetres and radians inside, millimetres and degrees at the user boundary
//! ([`Quantity`]).
//!
//! ```
//! use pkm::{Machine, Mechanism, machine::Model};
//! let text = std::fs::read_to_string(concat!(
//!     env!("CARGO_MANIFEST_DIR"),
//!     "/../../examples/machines/tripod-seed000.toml"
//! )).unwrap();
//! let machine = Machine::from_toml_str(&text, "tripod-seed000.toml").unwrap();
//! let Model::TranslationalTripod(tripod) = &machine.model else { panic!() };
//! let lengths = tripod.inverse(&tripod.info().home()).unwrap();
//! assert!(lengths.iter().all(|l| *l > 0.0));
//! ```

#![warn(missing_docs)]
// `!(x > 0.0)` is used on purpose: it is also true for NaN, which must fail validation.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accuracy;
pub mod analysis;
pub mod dynamic;
pub mod error;
pub mod hexapod;
pub mod hybrid_am;
pub mod identify;
mod lane;
pub mod legs;
pub mod limits;
pub mod linalg;
pub mod linuxcnc;
pub mod machine;
pub mod mechanism;
pub mod motion;
pub mod p3rp;
pub mod pentapod;
pub mod pose;
pub mod rotation;
pub mod serial;
pub mod simd;
pub mod statics;
pub mod transmission;
pub mod trig;
pub mod tripod;
pub mod units;
pub mod verify;
pub mod workspace;

pub use dynamic::DynMechanism;
pub use error::{Error, Result, Unattainable};
pub use limits::{LimitKind, LimitName, Range, Side, Violation};
pub use machine::{Machine, Visitor};
pub use mechanism::{
    inverse_checked, newton_forward, Actuator, ActuatorMotion, Coordinate, Forward, Mechanism,
    NewtonOptions, PoseSpace, Skeleton,
};
pub use pose::{Pose, SmallDisplacement};
pub use rotation::Convention;
pub use units::Quantity;
