//! Tripods with three variable-length struts (seed 000, Emelyanenko & Ovcharova).
//!
//! Three struts join base joints (fixed, base frame) to platform joints (platform
//! frame); the tool is fixed to the platform. A strut's length is the distance between
//! its two joints (seed 000 eq. 7). Three struts fix only three of the platform's six
//! coordinates; the other three are fixed by the mechanism's motion constraint, which
//! the machine file chooses:
//!
//! * [`TranslationalTripod`]: the mechanism holds the platform orientation constant
//!   (the assumption of seed 000's arc study). Pose coordinates X, Y, Z, A, B, C; the
//!   struts drive X, Y, Z, the orientation is held where it is.
//! * [`CentreLegTripod`]: a Tricept-like tripod whose platform is fixed to the end of a
//!   passive telescopic centre leg hinged to the base by a universal joint, so the
//!   platform tilts and extends with the tool position. Pose coordinates X, Y, Z.
//!
//! Inverse kinematics for any platform pose is [`TripodGeometry::strut_lengths`].

mod accuracy;
mod centre_leg;
mod geometry;
mod translational;

pub use centre_leg::{CentreLeg, CentreLegTripod};
pub use geometry::{Strut, TripodGeometry};
pub use translational::TranslationalTripod;
