//! Motion after an impact: a staged contact (or any contact that follows from the motion it
//! starts) is resolved by the planar impulse-momentum model of crash reconstruction (`model`),
//! and the bodies then slide and spin to rest under tyre friction (`motion`), no longer driven.
//! A conflict that asks for `after latch` holds its pair at the contact instead
//! (`staging::strike`).

pub(crate) mod bodies;
pub(crate) mod model;
pub(crate) mod motion;

pub use crate::check::scenario::AfterImpact;
use crate::check::scenario::{Class, Motion};
use serde::{Deserialize, Serialize};

/// Standard gravity, m/s^2.
pub const G: f64 = 9.81;
/// Coefficient of restitution of an impact that does not state one: crash tests of cars above
/// about 30 km/h rebound with 0.05 to 0.2.
pub const RESTITUTION: f64 = 0.1;
/// Friction between two colliding bodies (sheet metal on sheet metal, bumpers), when unstated.
pub const BODY_FRICTION: f64 = 0.5;
/// Tyre (or, for walkers and riders, body) friction with the road while sliding after an
/// impact: a car sliding sideways or on locked wheels on dry asphalt.
pub const TYRE_FRICTION: f64 = 0.7;
/// How long two bodies may overlap after an impact (their crush) before they are pushed apart,
/// s: the contact's window.
pub const WINDOW_S: f64 = 0.5;
/// Masses a file may state, kg: a child on a scooter to a loaded semi-trailer truck.
pub const MASS_RANGE: (f64, f64) = (10.0, 60_000.0);

/// The mass of a body that does not state one, kg, from its class and box: vehicles at
/// 120 kg per cubic metre of box (a 4.6 m sedan 1,450 kg, a 12 m bus 11.5 t, a motorcycle with
/// its rider 250 kg), walkers and animals at 110 (an adult 70 kg, a child 25 kg), a bicycle or
/// scooter with its rider 90 kg. Objects and structures do not move when struck.
pub fn prior_mass(class: Class, motion: Motion, size: [f64; 3]) -> f64 {
    let volume = size[0] * size[1] * size[2];
    match (class, motion) {
        (_, Motion::Static) => f64::INFINITY,
        (Class::Bicycle, _) => 90.0,
        (Class::Vehicle, _) => (120.0 * volume).clamp(150.0, 40_000.0),
        _ => (110.0 * volume).clamp(5.0, 400.0),
    }
}

/// The yaw moment of inertia of a box of mass `m` (uniform), kg m^2.
pub fn box_inertia(m: f64, length: f64, width: f64) -> f64 {
    m * (length * length + width * width) / 12.0
}

/// One resolved impact, as the tracks record it: a staged conflict's contact or one that
/// followed from the motion after another.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Contact {
    /// The frame whose poses are the bodies at impact: the motion from it on is the rebound.
    pub frame: usize,
    /// Track indices; the normal points from `a` into `b`.
    pub a: usize,
    pub b: usize,
    /// The staged conflict (index into `Concrete::conflicts`), if this is one.
    pub conflict: Option<usize>,
    /// Centroid of the overlap, world frame, m.
    pub point: [f64; 2],
    pub normal: [f64; 2],
    /// The impulse on `b` (the opposite on `a`), N s.
    pub impulse: [f64; 2],
}
