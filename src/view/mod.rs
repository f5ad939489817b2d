//! View pass. In: the ego's world `Pose` and world-frame agent states (one frame). Out: `EgoBox`es
//! in the ego frame, and `EgoFrame`, the world -> ego transform the rasteriser applies to map
//! geometry.
//!
//! Ego frame: x forward, y left, z up, metres; the origin is the ego box's centre projected to the
//! ground (z = 0 is the road surface, the top of the occupancy's ground layer). Every output is in
//! this frame: boxes, BEV, occupancy and LiDAR points. nuPlan puts the origin on the rear axle
//! (SPEC.md, "Frames"); rocc's kinds carry no axle position, and the box centre keeps the ego's
//! own footprint symmetric about pixel 200 in the BEV, so we use the centre for every kind. The
//! sensor poses of SPEC.md's LiDAR table (headed "origin in ego frame") are nuPlan's rear-axle
//! values at axle height, not this frame: the rig file keeps them as published and its
//! `mount.frame_origin` moves them here (`lidar::rig::Mount`; docs/output.md, "Frames").

use crate::check::scenario::Class;
use crate::geom::wrap_angle;
use crate::place::{PlacedAgent, Pose};
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// One agent's box in the ego frame of one frame: `[x, y, z, l, w, h, yaw]` plus identity.
/// `z` is the height of the box centre (the box stands on the ground, so z = h / 2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EgoBox {
    pub agent: String,
    pub kind: String,
    pub class: Class,
    pub track: u32,
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub l: f64,
    pub w: f64,
    pub h: f64,
    /// Counter-clockwise from the ego's +x, wrapped to (-pi, pi].
    pub yaw: f64,
}

/// What `to_ego` needs of one agent at one frame: borrowed identity plus a world pose, so the
/// rollout pass can feed per-frame poses without cloning names.
#[derive(Clone, Copy, Debug)]
pub struct AgentState<'a> {
    pub track: u32,
    pub name: &'a str,
    pub kind: &'a str,
    pub class: Class,
    /// Length, width, height (m).
    pub size: [f64; 3],
    pub pose: Pose,
}

impl<'a> AgentState<'a> {
    /// The state of a placed agent at its initial pose.
    pub fn placed(track: u32, a: &'a PlacedAgent) -> Self {
        Self::at(track, a, a.pose)
    }

    /// The same agent at another pose (a rollout frame).
    pub fn at(track: u32, a: &'a PlacedAgent, pose: Pose) -> Self {
        AgentState { track, name: &a.name, kind: &a.kind, class: a.class, size: a.size, pose }
    }
}

/// World -> ego transform of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EgoFrame {
    origin: DVec2,
    yaw: f64,
    cos: f64,
    sin: f64,
}

impl EgoFrame {
    pub fn new(ego: Pose) -> Self {
        EgoFrame { origin: DVec2::new(ego.x, ego.y), yaw: ego.yaw, cos: ego.yaw.cos(), sin: ego.yaw.sin() }
    }

    /// A world point in the ego frame (metres).
    #[inline]
    pub fn point(&self, world: DVec2) -> DVec2 {
        let d = world - self.origin;
        // Rotation by -yaw.
        DVec2::new(self.cos * d.x + self.sin * d.y, -self.sin * d.x + self.cos * d.y)
    }

    /// A world heading in the ego frame, wrapped to (-pi, pi].
    #[inline]
    pub fn heading(&self, world_yaw: f64) -> f64 {
        wrap_angle(world_yaw - self.yaw)
    }

    /// A world pose in the ego frame.
    pub fn pose(&self, p: Pose) -> Pose {
        let q = self.point(DVec2::new(p.x, p.y));
        Pose { x: q.x, y: q.y, yaw: self.heading(p.yaw) }
    }
}

/// Every agent's box in the frame of `ego`, in input order (which the rasteriser keeps: later
/// boxes win the aux channels where footprints overlap). Whether the ego's own box is included is
/// the caller's choice: nuPlan's annotations never contain the ego vehicle, so pass it only when a
/// consumer wants it drawn.
pub fn to_ego<'a>(ego: Pose, agents: impl IntoIterator<Item = AgentState<'a>>) -> Vec<EgoBox> {
    let f = EgoFrame::new(ego);
    agents
        .into_iter()
        .map(|a| {
            let p = f.pose(a.pose);
            let [l, w, h] = a.size;
            EgoBox {
                agent: a.name.to_string(),
                kind: a.kind.to_string(),
                class: a.class,
                track: a.track,
                x: p.x,
                y: p.y,
                z: h / 2.0,
                l,
                w,
                h,
                yaw: p.yaw,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn state(pose: Pose) -> AgentState<'static> {
        AgentState { track: 3, name: "a", kind: "sedan", class: Class::Vehicle, size: [4.0, 2.0, 1.5], pose }
    }

    #[test]
    fn agent_ahead_of_a_north_facing_ego_is_on_plus_x() {
        let ego = Pose { x: 10.0, y: 5.0, yaw: FRAC_PI_2 };
        let b = &to_ego(ego, [state(Pose { x: 10.0, y: 15.0, yaw: FRAC_PI_2 })])[0];
        assert!((b.x - 10.0).abs() < 1e-12 && b.y.abs() < 1e-12 && b.yaw.abs() < 1e-12);
        assert_eq!((b.z, b.track, b.l), (0.75, 3, 4.0));
        // East of a north-facing ego is on its right (-y).
        let r = &to_ego(ego, [state(Pose { x: 13.0, y: 5.0, yaw: 0.0 })])[0];
        assert!((r.y + 3.0).abs() < 1e-12 && (r.yaw + FRAC_PI_2).abs() < 1e-12);
    }
}
