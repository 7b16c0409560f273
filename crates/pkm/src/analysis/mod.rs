//! The analysis layer: every analysis callable on a loaded machine ([`Machine`]) with a
//! plain options struct, returning a plain result struct (`serde::Serialize`) that a
//! front end prints, writes or converts. Front ends (the `pkm` command, the report,
//! bindings) call these and never dispatch on the machine type themselves.
//!
//! [`Machine`]: crate::Machine

pub mod accuracy;
pub mod batch;
pub mod batch_table;
pub mod clearance;
pub mod clearance_class;
pub mod clearance_path;
mod clearance_study;
pub mod clearance_surface;
pub mod dynamics;
pub mod identification;
pub mod kinematics;
pub mod motion;
pub mod seed004;
pub mod statics;
pub mod workspace;

pub use accuracy::{
    accuracy, accuracy_with_progress, AccuracyOptions, AccuracyReport, KindTolerances, MapRequest,
    ToleranceSource, Tolerances,
};
