//! Rollout pass. In: a `Concrete` scenario, its `Map` and the `Placed` initial poses. Out:
//! `Tracks` — a world pose and speed for every agent at every frame (`rate` Hz over `duration`),
//! seeded background traffic appended after the placed agents, and one record per staged crash —
//! or E0204 diagnostics when a goal asks for geometry the map does not have.
//!
//! One controller drives every agent; nothing in here knows a scenario by name:
//! - longitudinal: IDM toward the goal speed (capped by the lane limit unless the goal names a
//!   speed, and by the curvature ahead), against every agent found in the agent's own corridor
//!   along its path — now, or predicted to cut into it within a few seconds — plus a stopping law
//!   that lands exactly on stop targets (stop line, queue gap, distance);
//! - lateral: offsets from the route's centre line, moved along quintic profiles that pause while
//!   the target side is occupied; vehicles steer toward that reference by pure pursuit and move
//!   as kinematic bicycles (along their heading, curvature bounded by `min_turn_radius` and the
//!   yaw rate); walkers and animals step onto it holonomically;
//! - junctions: vehicles whose junction path crosses an approaching emergency vehicle's hold at
//!   their stop line, and those already committed clear the junction first; any other two whose
//!   junction paths share a zone go in a strict order (inside it, too close to stop, earlier to
//!   arrive, then those stopped or queued for something else; names break ties), the other
//!   holding short of it; a walker about to cross waits at the kerb while a vehicle could not
//!   stop comfortably for it;
//! - signals (`signals on`): a vehicle holds at its stop line on a red, or a yellow it can stop
//!   for comfortably, and a walker on a crosswalk waits at the kerb for the walk signal; a
//!   flagger's stop holds the vehicles it faces short of it as a red does;
//! - car-following keeps Gipps's safe speed: able to stop, at emergency braking, behind where the
//!   leader could stop (within its clearance to its partner, for a conflict agent that the crash
//!   latch may stop dead); a striker keeps out of bystanders' stopping envelopes;
//! - a last safety net: a move that would make two boxes overlap is undone (the agent holds its
//!   previous pose), so the only overlaps in `Tracks` are conflict pairs from their impact on.
//!
//! Conflicts are staged in two passes: pass 1 predicts every agent's natural motion; the at-fault
//! agent's departure and impact time are chosen from it; pass 2 replays with the at-fault agent
//! following a Hermite intercept, re-planned each frame, to a pose that puts its striking face
//! on the requested side of the struck box at the impact frame.

mod agent;
pub mod body;
mod drive;
mod flagger;
mod frame;
pub mod impact;
mod junction;
mod kinematics;
mod path;
mod room;
mod safety;
mod setup;
mod staging;
mod traffic;
mod trigger;
mod turn_check;

pub use kinematics::KEY_SNAP_S;
pub use staging::plan::{MIN_DEPTH, contact_centroid, off_striking_face, side_of, wrong_struck_side};

use crate::check::scenario::{Class, Motion, Point};
use crate::diag::Diagnostic;
use crate::place::{Placed, Pose};
use crate::road::Map;
use crate::sample::Concrete;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Tracks {
    pub rate: f64,
    pub frames: usize,
    /// Placed agents first, in `Placed` order (indices match), then background traffic.
    pub agents: Vec<TrackAgent>,
    /// `[agent][frame]`, world frame.
    pub poses: Vec<Vec<Pose>>,
    /// `[agent][frame]`, m/s along the heading.
    pub speeds: Vec<Vec<f64>>,
    pub impacts: Vec<ImpactRecord>,
    /// `[agent]`: lamps and doors per frame (`body.rs`), read off the tracks above.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<body::BodyTrack>,
    /// Every impact resolved by the impact model, in order: staged contacts and those that
    /// follow from the motion after them (`rollout::impact`).
    #[serde(default)]
    pub contacts: Vec<impact::Contact>,
    /// Each flagger's state per frame (`flag { ... }`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub flags: Vec<FlagTrack>,
}

/// What one flagger shows over the clip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlagTrack {
    /// Track index (into `Tracks::agents`).
    pub agent: usize,
    /// The lanes it faces, as a placement names them (`west.in[1]`).
    pub faces: Vec<String>,
    /// Per frame: `go` (true) or `stop`.
    pub go: Vec<bool>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrackAgent {
    pub name: String,
    pub kind: String,
    pub class: Class,
    pub motion: Motion,
    /// Box length, width, height (m).
    pub size: [f64; 3],
    /// Seeded background traffic rather than a declared agent.
    pub background: bool,
}

/// The latched frame of one staged conflict.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImpactRecord {
    /// Index into `Concrete::conflicts`.
    pub conflict: usize,
    pub frame: usize,
    /// Track indices (into `Tracks::agents`).
    pub at_fault: usize,
    pub struck: usize,
    /// Centroid of the overlap of the two boxes, world frame.
    pub point_world: [f64; 2],
    /// The same point in each box's frame (x forward, y left, m).
    pub at_fault_local: [f64; 2],
    pub struck_local: [f64; 2],
    /// Which side of the struck box the contact lies on (thirds of each face; see `side_of`).
    pub struck_side: Point,
    /// Penetration depth at the latched frame, m.
    pub depth: f64,
}

/// Motion limits of a class; the controller never plans beyond them (the overlap safety net may:
/// it stops an agent in one frame, which only an unavoidable situation triggers).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Comfortable acceleration, m/s^2.
    pub accel: f64,
    /// Comfortable braking, m/s^2.
    pub brake: f64,
    /// Emergency braking, m/s^2.
    pub brake_max: f64,
    /// Yaw rate, rad/s.
    pub yaw_rate: f64,
    /// Lateral acceleration in curves, m/s^2.
    pub lat_acc: f64,
    /// Time headway of the car-following law, s.
    pub headway: f64,
    /// Standstill gap to a leader, m.
    pub min_gap: f64,
}

pub fn limits(class: Class, motion: Motion) -> Limits {
    match (motion, class) {
        (Motion::Vehicle, Class::Bicycle) => {
            Limits { accel: 1.5, brake: 2.5, brake_max: 5.0, yaw_rate: 1.5, lat_acc: 2.5, headway: 1.0, min_gap: 1.5 }
        }
        (Motion::Vehicle, _) => {
            Limits { accel: 2.5, brake: 3.0, brake_max: 8.0, yaw_rate: 1.2, lat_acc: 3.0, headway: 1.2, min_gap: 2.0 }
        }
        (Motion::Holonomic, Class::Pedestrian) | (Motion::Static, _) => {
            Limits { accel: 1.5, brake: 2.0, brake_max: 4.0, yaw_rate: 3.0, lat_acc: 4.0, headway: 0.8, min_gap: 0.8 }
        }
        (Motion::Holonomic, _) => ANIMAL,
    }
}

/// Animals (walking kinds that are not pedestrians: `animal`, `dog`, a `deer` derived from
/// them; a `stroller` shares their class and motion, hence their limits) bound off: a deer reaches 8 m/s in about a second and stops or turns as sharply
/// (scenarios/rare/deer_leaps_onto_rural_road.scn).
pub const ANIMAL: Limits =
    Limits { accel: 8.0, brake: 5.0, brake_max: 10.0, yaw_rate: 4.0, lat_acc: 6.0, headway: 0.8, min_gap: 0.8 };

impl Tracks {
    /// The first frame at which agent `i` is in an impact the impact model resolved.
    pub fn first_contact(&self, i: usize) -> Option<usize> {
        self.contacts.iter().filter(|c| c.a == i || c.b == i).map(|c| c.frame).min()
    }

    /// Feed every pose, speed and impact (frame and depth) to `h`, bit for bit: the digest that
    /// pins the rollout (`bench rollout`, the pin test), which a change that claims to change
    /// nothing must leave as it is.
    pub fn digest(&self, h: &mut crate::fsio::Fnv1a) {
        for (poses, speeds) in self.poses.iter().zip(&self.speeds) {
            for (p, v) in poses.iter().zip(speeds) {
                for x in [p.x, p.y, p.yaw, *v] {
                    h.write_u64(x.to_bits());
                }
            }
        }
        for r in &self.impacts {
            h.write_u64(r.frame as u64).write_u64(r.depth.to_bits());
        }
    }
}

/// Smallest turning radius of a vehicle's box centre, m, from its kind's box length (the stdlib
/// priors carry no wheelbase): a kinematic bicycle with wheelbase `0.6 * length` (a sedan's
/// 2.8 m at 4.65 m, a city bus's 7.2 m at 12 m) and a largest steering angle of 35 degrees
/// (45 for bicycles), referenced at the box centre so that the box moves along its heading.
/// A sedan turns on 4.0 m, an ambulance on 5.6 m, a bus on 10.3 m; at least 1 m for anything.
pub fn min_turn_radius(class: Class, length: f64) -> f64 {
    let steer: f64 = if class == Class::Bicycle { 45.0 } else { 35.0 };
    (WHEELBASE_SHARE * length / steer.to_radians().tan()).max(1.0)
}

/// A vehicle's wheelbase as a share of its box length, axles placed symmetrically about the box
/// centre (see `min_turn_radius`).
pub const WHEELBASE_SHARE: f64 = 0.6;

/// Roll the placed scenario out over its frames.
pub fn rollout(c: &Concrete, map: &Map, placed: &Placed) -> Result<Tracks, Vec<Diagnostic>> {
    let mut t = staging::passes::run(c, map, placed)?;
    t.bodies = body::bodies(c, map, placed, &t);
    body::with_doors(c, map, placed, t)
}
