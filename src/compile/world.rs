//! A clip's world side: per frame the ego's pose and box, each box's motion and instance id
//! (`boxes.json`), and the map as vectors (`scene.json`), from the scenario's tracks and map.

use crate::geom::wrap_angle;
use crate::output::{
    BoxMotion, EgoRecord, FlagShown, FlaggerRecord, FrameWorld, Motion, SceneMap, SignalState, States, ego2global,
    instance_id, yaw_quaternion,
};
use crate::place::Pose;
use crate::raster::layout::class_index;
use crate::road::Map;
use crate::rollout::Tracks;
use crate::view::EgoBox;
use glam::DVec2;

/// What a clip knows of its world: the scenario's name (instance ids), tracks, map and ego, and
/// whether track `i` is in the scene at frame `f` (`Front::present`).
#[derive(Clone, Copy)]
pub struct ClipWorld<'a> {
    pub scenario: &'a str,
    pub tracks: &'a Tracks,
    pub map: &'a Map,
    pub ego: usize,
    pub present: &'a (dyn Fn(usize, usize) -> bool + Sync),
}

impl ClipWorld<'_> {
    /// The world side of frame `f`, whose ego pose and ego-frame boxes are given.
    pub fn frame(&self, f: usize, ego_pose: Pose, boxes: &[EgoBox]) -> FrameWorld {
        let t = self.tracks;
        let a = &t.agents[self.ego];
        let motion = |i: usize| motion(t, &|g| (self.present)(i, g), i, f, ego_pose.yaw);
        let ego = EgoRecord {
            agent: a.name.clone(),
            kind: a.kind.clone(),
            class: class_index(a.class),
            class_name: a.class.name().to_string(),
            track: self.ego as u32,
            instance_id: instance_id(self.scenario, &a.name),
            x: ego_pose.x,
            y: ego_pose.y,
            z: 0.0,
            yaw: ego_pose.yaw,
            l: a.size[0],
            w: a.size[1],
            h: a.size[2],
            ego2global: ego2global(ego_pose),
            ego2global_translation: [ego_pose.x, ego_pose.y, 0.0],
            ego2global_rotation: yaw_quaternion(ego_pose.yaw),
            motion: motion(self.ego),
            states: states(t, self.ego, f),
        };
        let boxes = boxes
            .iter()
            .map(|b| {
                let i = b.track as usize;
                // A box the tracks do not describe (inserted by `rocc edit`) has no motion.
                (t.agents.get(i).is_some_and(|a| a.name == b.agent)).then(|| BoxMotion {
                    instance_id: instance_id(self.scenario, &b.agent),
                    motion: motion(i),
                    flag: flag_shown(t, i, f),
                    states: states(t, i, f),
                })
            })
            .collect();
        let timestamp_us = (f as f64 * 1e6 / t.rate).round() as u64;
        let signals = self.map.signals.as_ref().map_or_else(Vec::new, |plan| {
            let lane = |id: crate::check::scenario::LaneId| format!("{}.in[{}]", id.arm.name(), id.index);
            plan.lights(f as f64 / t.rate).map(|(h, light)| SignalState { lane: lane(h.id), light }).collect()
        });
        FrameWorld { timestamp_us, ego, boxes, signals }
    }

    pub fn scene(&self) -> SceneMap {
        let mut scene = SceneMap::of(self.scenario, self.map);
        scene.flaggers = self
            .tracks
            .flags
            .iter()
            .map(|ft| FlaggerRecord { agent: self.tracks.agents[ft.agent].name.clone(), faces: ft.faces.clone() })
            .collect();
        scene
    }
}

/// What flagger `i` shows at frame `f`; `None` for an agent that is no flagger.
fn flag_shown(t: &Tracks, i: usize, f: usize) -> Option<FlagShown> {
    let ft = t.flags.iter().find(|ft| ft.agent == i)?;
    Some(if *ft.go.get(f)? { FlagShown::Go } else { FlagShown::Stop })
}

/// Track `i`'s lamps and doors at frame `f`; `None` for what carries no lamps.
fn states(t: &Tracks, i: usize, f: usize) -> Option<States> {
    let b = t.bodies.get(i).filter(|b| b.lamps)?;
    Some(States {
        headlights: b.headlights,
        brake_lights: b.brake_lights.get(f).copied().unwrap_or(false),
        hazards: b.hazards,
        beacons: b.beacons,
        siren: b.siren,
        doors: b
            .doors
            .iter()
            .filter_map(|(d, a)| a.get(f).filter(|&&deg| deg > 0.0).map(|&deg| (d.name().to_string(), deg)))
            .collect(),
    })
}

/// The frames a derivative at frame `f` differences, of a track sampled at frames `0..n` and in
/// the scene where `present` says so: its two neighbours, `f` itself on a side where the
/// neighbour is past the clip or absent (a replayed object entering or leaving), `None` when
/// both are (a single frame).
fn window(n: usize, present: &dyn Fn(usize) -> bool, f: usize) -> Option<(usize, usize)> {
    let ok = |g: usize| g < n && present(g);
    let lo = if f > 0 && ok(f - 1) { f - 1 } else { f };
    let hi = if ok(f + 1) { f + 1 } else { f };
    (hi > lo).then_some((lo, hi))
}

/// The derivative at frame `f` of a quantity sampled every `dt` over `window`'s frames: a
/// central difference, one-sided at a track's ends, zero for a single frame.
fn diff<T>(g: impl Fn(usize) -> T, f: usize, window: &dyn Fn(usize) -> Option<(usize, usize)>, dt: f64) -> T
where
    T: std::ops::Sub<Output = T> + std::ops::Mul<f64, Output = T> + Default,
{
    window(f).map_or_else(T::default, |(lo, hi)| (g(hi) - g(lo)) * (1.0 / ((hi - lo) as f64 * dt)))
}

/// Agent `i`'s velocity over the ground at frame `f`, world axes (m/s): the one derivation
/// behind `boxes.json`'s motion and the occupancy flow, so the two agree at a track's ends.
pub fn ground_velocity(t: &Tracks, present: &dyn Fn(usize) -> bool, i: usize, f: usize) -> [f64; 2] {
    let v = velocity(t, present, i, f);
    [v.x, v.y]
}

fn velocity(t: &Tracks, present: &dyn Fn(usize) -> bool, i: usize, f: usize) -> DVec2 {
    let n = t.frames.min(t.poses[i].len());
    let pos = |k: usize| DVec2::new(t.poses[i][k].x, t.poses[i][k].y);
    diff(pos, f, &|g| window(n, present, g), 1.0 / t.rate)
}

/// Agent `i`'s motion at frame `f`, world and ego axes (the ego's heading `ego_yaw`), where it
/// is in the scene at the frames `present` says.
fn motion(t: &Tracks, present: &dyn Fn(usize) -> bool, i: usize, f: usize, ego_yaw: f64) -> Motion {
    let (n, dt) = (t.frames.min(t.poses[i].len()), 1.0 / t.rate);
    let window = |g: usize| window(n, present, g);
    let vel = |k: usize| velocity(t, present, i, k);
    let v = vel(f);
    let a = diff(vel, f, &window, dt);
    let yaw_rate =
        window(f).map_or(0.0, |(lo, hi)| wrap_angle(t.poses[i][hi].yaw - t.poses[i][lo].yaw) / ((hi - lo) as f64 * dt));
    let to_ego = |w: DVec2| DVec2::from_angle(-ego_yaw).rotate(w);
    let arr = |w: DVec2| [w.x, w.y];
    Motion {
        velocity: arr(to_ego(v)),
        acceleration: arr(to_ego(a)),
        velocity_world: arr(v),
        acceleration_world: arr(a),
        yaw_rate,
    }
}
