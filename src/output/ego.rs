//! The world side of `boxes.json`: per frame the ego's pose in the world (x, y, z, yaw, the 4x4
//! ego-to-world matrix and the nuScenes-style translation and quaternion that Occ3D and UniScene
//! infos carry), its box and kind, a timestamp in microseconds (nuPlan's unit); per box its
//! motion and a stable instance id. Plain records, serialised into `boxes.json` beside the
//! fields SPEC.md defines (docs/output.md, "boxes.json").

use crate::place::Pose;
use serde::{Deserialize, Serialize};

/// The ego of one frame, world frame (x east, y north, z up; yaw counter-clockwise from +x).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EgoRecord {
    pub agent: String,
    pub kind: String,
    /// UniScene object-class index and name, as for the other boxes.
    pub class: u8,
    pub class_name: String,
    pub track: u32,
    pub instance_id: String,
    /// The ego frame's origin in the world: the box centre on the ground (z = 0).
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub yaw: f64,
    pub l: f64,
    pub w: f64,
    pub h: f64,
    /// Row-major 4x4: world point = ego2global * (ego point, 1).
    pub ego2global: [[f64; 4]; 4],
    /// nuScenes convention: translation (m) and rotation quaternion [w, x, y, z].
    pub ego2global_translation: [f64; 3],
    pub ego2global_rotation: [f64; 4],
    #[serde(flatten)]
    pub motion: Motion,
    /// Lamps and doors (vehicles and bicycles).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub states: Option<States>,
}

/// A flagger's state: traffic it faces stops or goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FlagShown {
    Stop,
    Go,
}

/// How one agent moves at one frame (central differences over the clip's frames, one-sided at
/// its ends, as nuScenes derives box velocities from annotations).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Motion {
    /// m/s, the world velocity expressed in the frame's ego axes (not relative to the ego).
    pub velocity: [f64; 2],
    /// m/s^2, likewise.
    pub acceleration: [f64; 2],
    /// m/s and m/s^2 in the world frame.
    pub velocity_world: [f64; 2],
    pub acceleration_world: [f64; 2],
    /// rad/s, counter-clockwise (the same in both frames).
    pub yaw_rate: f64,
}

/// What a box of `boxes.json` gains beyond SPEC.md's fields.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoxMotion {
    /// Stable across the frames and the egos of a scenario.
    pub instance_id: String,
    #[serde(flatten)]
    pub motion: Motion,
    /// What a flagger shows at this frame (`flag { ... }`); absent for everyone else.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flag: Option<FlagShown>,
    /// Lamps and doors (vehicles and bicycles).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub states: Option<States>,
}

/// What a vehicle's (or a bicycle's) lamps show and how far each door is open, at one frame
/// (docs/output.md, "Vehicle states").
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct States {
    pub headlights: bool,
    pub brake_lights: bool,
    pub hazards: bool,
    pub beacons: bool,
    pub siren: bool,
    /// Each door not shut, by name (`front_left`), with its opening angle in degrees.
    #[serde(default)]
    pub doors: std::collections::BTreeMap<String, f64>,
}

/// The world side of one frame: timestamp, ego, and per box (in `FrameBoxes::boxes` order) its
/// motion where the agent is known to the clip's tracks.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameWorld {
    pub timestamp_us: u64,
    pub ego: EgoRecord,
    pub boxes: Vec<Option<BoxMotion>>,
    /// Each approach lane's signal (`signals on`), in `SignalPlan::heads` order.
    pub signals: Vec<SignalState>,
}

/// What one approach lane's signal shows at one frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SignalState {
    /// The lane, as a placement names it: `south.in[1]`.
    pub lane: String,
    pub light: crate::road::signals::Light,
}

/// The instance id of agent `agent` of scenario `scenario`: FNV-1a of both names, hex.
pub fn instance_id(scenario: &str, agent: &str) -> String {
    let mut h = crate::fsio::Fnv1a::new();
    h.write(scenario.as_bytes()).write(&[0]).write(agent.as_bytes());
    format!("{:016x}", h.finish())
}

/// The ego-to-world matrix of an ego pose (its origin on the ground, z = 0).
pub fn ego2global(p: Pose) -> [[f64; 4]; 4] {
    let (s, c) = p.yaw.sin_cos();
    [[c, -s, 0.0, p.x], [s, c, 0.0, p.y], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
}

/// The quaternion [w, x, y, z] of a rotation by `yaw` about +z.
pub fn yaw_quaternion(yaw: f64) -> [f64; 4] {
    let (s, c) = (0.5 * yaw).sin_cos();
    [c, 0.0, 0.0, s]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrix_and_quaternion_rotate_alike() {
        let p = Pose { x: 3.0, y: -2.0, yaw: 0.7 };
        let m = ego2global(p);
        let [w, _, _, z] = yaw_quaternion(p.yaw);
        // Rotation matrix of the quaternion about z: cos = w^2 - z^2, sin = 2wz.
        assert!((m[0][0] - (w * w - z * z)).abs() < 1e-12 && (m[1][0] - 2.0 * w * z).abs() < 1e-12);
        // The ego point (1, 0) lies 1 m ahead of the pose.
        let fwd = [m[0][0] + m[0][3], m[1][0] + m[1][3]];
        assert!((fwd[0] - (3.0 + 0.7f64.cos())).abs() < 1e-12 && (fwd[1] - (-2.0 + 0.7f64.sin())).abs() < 1e-12);
        assert_ne!(instance_id("a", "bc"), instance_id("ab", "c"));
    }
}
