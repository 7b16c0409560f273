//! The 2-DOF asymmetric P3RP parallel spindle head of seed 004 (Chen Jing) and the
//! 4-axis hybrid machine built on it.
//!
//! Two sliders run on one vertical guide: the lower slider D (actuator `U`) carries the
//! hinge A of the swing platform, the upper slider E (actuator `V`) the hinge C of a rod
//! of fixed length `l2` whose other end is hinged to the platform at B, `|AB| = l1`.
//! The platform carries the spindle; its pose is `(z, theta)`: the height of the
//! output point t (= A) above the table and its deflection, counter-clockwise positive
//! (the spindle turns from vertical, `theta = 0`, towards horizontal).
//!
//! Frames (seed 004 figs. 2-3, restated in `../shared/spec/05-p3rp-spindle-head.md`):
//! O-YZ with Y horizontal and Z along the guide; X (the hinge axes) completes a
//! right-handed frame, so a counter-clockwise deflection is a positive rotation about
//! X. `OA = (0, z1)`, `OC = (e, z2)`, `AB = l1 (-sin psi, cos psi)` with
//! `psi = theta + delta` the angle from Z to AB.
//!
//! The closed loop `OA + AB = OC + CB` gives `|BC| = l2`:
//!
//! ```text
//! (e + l1 sin psi)^2 + (z2 - z1 - l1 cos psi)^2 = l2^2
//! ```
//!
//! so with `z1 = z` (the lower slider carries t) the inverse solution is
//! `z2 = z + g(theta)`, `g(theta) = l1 cos psi + sqrt(l2^2 - (e + l1 sin psi)^2)`, the
//! root with C above B (the paper's `0 <= phi < pi/2`, phi from Z to BC).

mod accuracy;
mod head;
mod hybrid;
pub mod seed004;

pub use head::{Branch, HeadGeometry, HingeOffsets, P3rpHead, Separation};
pub use hybrid::HybridMachine;
