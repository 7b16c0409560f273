//! What a mechanism is, as data: the descriptive part of [`crate::Mechanism`].

use nalgebra::SVector;

use super::{Actuator, Coordinate, PoseSpace};

/// The descriptive data of a mechanism: its name and type, its pose coordinates and
/// actuators, which coordinates the actuators drive, the pose space, the home pose and
/// the few facts the generic engines ask of every type (how the inverse solves, whether
/// the forward is closed form, the length that scales rotations in conditioning).
///
/// Each machine type builds one when it is built ([`MechanismInfo::new`], then the
/// `with_*` methods for what differs from the defaults) and returns it from
/// [`crate::Mechanism::info`]; a setter of the type that changes what the info says
/// (its home pose, its characteristic length) updates it, so it cannot go stale.
///
/// ```
/// use nalgebra::Vector2;
/// use pkm::mechanism::{Actuator, Coordinate, MechanismInfo};
/// use pkm::{PoseSpace, Quantity, Range};
/// let slide = |n: &str| Actuator {
///     name: n.into(),
///     quantity: Quantity::Length,
///     range: Range { min: 0.0, max: 100.0 },
///     max_velocity: None,
///     max_acceleration: None,
///     stiffness: None,
/// };
/// let info = MechanismInfo::new(
///     "xy table".into(),
///     "example",
///     [Coordinate::length("X"), Coordinate::length("Y")],
///     [slide("U"), slide("V")],
///     PoseSpace::Own,
///     Vector2::new(50.0, 50.0),
/// )
/// .with_forward_closed_form();
/// assert_eq!(info.driven(), [0, 1]);
/// assert_eq!(info.characteristic_length(), 1.0);
/// assert!(info.forward_closed_form());
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct MechanismInfo<const P: usize, const A: usize> {
    name: String,
    kind: &'static str,
    coordinates: [Coordinate; P],
    actuators: [Actuator; A],
    driven: [usize; A],
    pose_space: PoseSpace,
    home: SVector<f64, P>,
    characteristic_length: f64,
    inverse_method: &'static str,
    forward_closed_form: bool,
    free_spin: bool,
}

impl<const P: usize, const A: usize> MechanismInfo<P, A> {
    /// A mechanism's info with the defaults: the actuators drive the first `A`
    /// coordinates in order, the characteristic length is 1 mm, the inverse is closed
    /// form, the forward is iterative and the tool does not spin freely.
    ///
    /// # Panics
    /// When `A > P` (a mechanism drives at most its pose coordinates).
    pub fn new(
        name: String,
        kind: &'static str,
        coordinates: [Coordinate; P],
        actuators: [Actuator; A],
        pose_space: PoseSpace,
        home: SVector<f64, P>,
    ) -> Self {
        assert!(A <= P, "a mechanism drives at most its pose coordinates");
        MechanismInfo {
            name,
            kind,
            coordinates,
            actuators,
            driven: std::array::from_fn(|i| i),
            pose_space,
            home,
            characteristic_length: 1.0,
            inverse_method: "closed form",
            forward_closed_form: false,
            free_spin: false,
        }
    }

    /// The same with the actuators driving the coordinates `driven` (indices, in the
    /// actuators' order).
    pub fn with_driven(mut self, driven: [usize; A]) -> Self {
        self.driven = driven;
        self
    }

    /// The same with the characteristic length `l` (mm).
    pub fn with_characteristic_length(mut self, l: f64) -> Self {
        self.characteristic_length = l;
        self
    }

    /// The same with the inverse's method in words (`pkm check` prints it).
    pub fn with_inverse_method(mut self, method: &'static str) -> Self {
        self.inverse_method = method;
        self
    }

    /// The same with a closed-form forward kinematics.
    pub fn with_forward_closed_form(mut self) -> Self {
        self.forward_closed_form = true;
        self
    }

    /// The same with the tool free to spin about its own axis.
    pub fn with_free_spin(mut self) -> Self {
        self.free_spin = true;
        self
    }

    /// Machine name from its file.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Machine type (`tripod/translational`, ...).
    pub fn kind(&self) -> &'static str {
        self.kind
    }

    /// The pose coordinates, in order.
    pub fn coordinates(&self) -> &[Coordinate; P] {
        &self.coordinates
    }

    /// The actuators, in order.
    pub fn actuators(&self) -> &[Actuator; A] {
        &self.actuators
    }

    /// Indices of the pose coordinates driven by the actuators. The others are held by
    /// the mechanism: forward kinematics takes them from its starting pose.
    pub fn driven(&self) -> [usize; A] {
        self.driven
    }

    /// How the pose coordinates relate to a full tool pose.
    pub fn pose_space(&self) -> PoseSpace {
        self.pose_space
    }

    /// The home pose from the machine file.
    pub fn home(&self) -> SVector<f64, P> {
        self.home
    }

    /// Length (mm) that scales rotations against translations in conditioning: a
    /// rotation of 1 rad counts as a displacement of this many mm.
    pub fn characteristic_length(&self) -> f64 {
        self.characteristic_length
    }

    /// How [`crate::Mechanism::inverse`] solves, in words: `closed form` (every type's
    /// inverse but a robot's of general geometry) or the robot's method.
    pub fn inverse_method(&self) -> &'static str {
        self.inverse_method
    }

    /// Whether [`crate::Mechanism::forward`] is a closed-form solution: then its
    /// [`crate::Forward::iterations`] is 0 by construction, not a count of iterations.
    pub fn forward_closed_form(&self) -> bool {
        self.forward_closed_form
    }

    /// Whether the mechanism leaves the tool free to spin about its own axis (a
    /// pentapod's ring joints turn): a rotation about the tool axis is then no error of
    /// the machine, and the accuracy engine keeps only the tilt of the tool axis
    /// ([`crate::accuracy::PoseError::without_spin`]).
    pub fn free_spin(&self) -> bool {
        self.free_spin
    }

    pub(crate) fn set_home(&mut self, home: SVector<f64, P>) {
        self.home = home;
    }

    pub(crate) fn set_characteristic_length(&mut self, l: f64) {
        self.characteristic_length = l;
    }
}
