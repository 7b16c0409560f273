//! Motion analysis: tool paths through any mechanism, with exact actuator position,
//! velocity and acceleration, a serial-machine comparison (seed 000) and limits along
//! the path.

mod block;
pub mod decimated;
mod follow;
pub mod gcode;
pub mod path;
pub mod plan;
pub mod profile;
pub mod program;
mod recorder;
pub mod run;
pub mod singular;
pub mod stats;
pub mod tools;
mod words;

pub use path::{Segment, Shape, MIN_MOVE};
pub use plan::Step;
pub use profile::Profile;
pub(crate) use recorder::RunSink;
pub use run::{MotionSummary, Move, Runner, Sample, Sampling, ViolationRun};
pub use stats::{AxisStats, Ratios};
