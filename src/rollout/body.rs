//! Lamps and doors per frame, read off the finished tracks: headlights, brake lights, hazards,
//! beacons and siren of every vehicle, and the swing of each door a `door` statement moves
//! (scenarios/rare/dooring.scn). The rules are in docs/rollout.md, "Lamps and doors".

use crate::check::scenario::{Class, Door, DoorMove, Motion, Trigger};
use crate::diag::Diagnostic;
use crate::geom::wrap_angle;
use crate::place::{Placed, Pose};
use crate::road::Map;
use crate::rollout::Tracks;
use crate::rollout::setup::is_emergency;
use crate::sample::Concrete;
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// Deceleration beyond which brake lights show, m/s^2: a car in gear slows by up to about this
/// much with the pedal released, so a harder slowdown is braking.
pub const BRAKE_LIGHT_DECEL: f64 = 1.0;
/// Below this speed a vehicle is stopped, m/s.
pub const STOPPED_SPEED: f64 = 0.1;
/// How far a door swings open, degrees.
pub const DOOR_OPEN_DEG: f64 = 70.0;
/// How fast a door swings, degrees per second (fully open in one second).
pub const DOOR_SWING_DEG_S: f64 = 70.0;
/// Thickness of a door's box, m: one BEV cell and one voxel (0.25 m), so that the grids show
/// it at any angle (a real door is about 0.1 m thick; thinner, the rasteriser's rounded corners
/// can leave it no cell at all).
pub const DOOR_THICKNESS_M: f64 = 0.25;

/// One agent's lamps and doors over the clip.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BodyTrack {
    /// Lamps carried at all: vehicles and bicycles (headlights); `states` is written for these.
    pub lamps: bool,
    pub headlights: bool,
    pub hazards: bool,
    pub beacons: bool,
    pub siren: bool,
    /// Per frame.
    pub brake_lights: Vec<bool>,
    /// Each door that moves, with its opening angle (degrees) per frame.
    pub doors: Vec<(Door, Vec<f64>)>,
}

/// The lamps and doors of every track of `t`.
pub fn bodies(c: &Concrete, map: &Map, placed: &Placed, t: &Tracks) -> Vec<BodyTrack> {
    let track_of = |ci: usize| placed.agents.iter().position(|p| p.source == Some(ci));
    t.agents
        .iter()
        .enumerate()
        .map(|(i, info)| {
            let lamps = matches!(info.class, Class::Vehicle | Class::Bicycle);
            if !lamps {
                return BodyTrack::default();
            }
            let ca = placed.agents.get(i).and_then(|p| p.source).and_then(|s| c.agents.get(s));
            let vehicle = info.class == Class::Vehicle;
            // Standing: never meant to move (an object, a static kind, or no goal, track or speed).
            let standing = ca.is_none_or(|a| {
                a.is_object || a.motion == Motion::Static || (a.goal.is_none() && a.track.is_none() && a.speed == 0.0)
            }) && !info.background;
            let body = ca.map(|a| a.body.clone()).unwrap_or_default();
            let siren =
                vehicle && !standing && is_emergency(c, &info.kind) && ca.is_some_and(|a| a.siren != Some(false));
            let p0 = t.poses[i].first().map_or(DVec2::ZERO, |p| DVec2::new(p.x, p.y));
            BodyTrack {
                lamps,
                headlights: body.lights.unwrap_or(false),
                hazards: vehicle && body.hazards.unwrap_or(standing && on_travel_lane(map, p0)),
                beacons: body.beacons.unwrap_or(siren),
                siren,
                brake_lights: (0..t.frames).map(|f| vehicle && !standing && braking(&t.speeds[i], f, t.rate)).collect(),
                doors: doors(&body.doors, i, t, &track_of),
            }
        })
        .collect()
}

/// Roll `c` out again with its doors swinging as `t` has them, until they swing the same way
/// twice: the rollout sees an open door as an obstacle (`drive/doors.rs`), and a door's moves
/// may watch agents that react to it. Each run settles the next move in time (before it, the
/// runs agree), so a scene with `n` door moves takes at most `n` more runs; one without doors
/// none.
pub(crate) fn with_doors(c: &Concrete, map: &Map, placed: &Placed, mut t: Tracks) -> Result<Tracks, Vec<Diagnostic>> {
    let moves: usize = c.agents.iter().map(|a| a.body.doors.len()).sum();
    if moves == 0 {
        return Ok(t);
    }
    let mut c = c.clone();
    for _ in 0..moves {
        let mut changed = false;
        for (ci, a) in c.agents.iter_mut().enumerate() {
            let swing = placed
                .agents
                .iter()
                .position(|p| p.source == Some(ci))
                .and_then(|i| t.bodies.get(i))
                .map_or_else(Vec::new, |b| b.doors.clone());
            changed |= swing != a.door_swing;
            a.door_swing = swing;
        }
        if !changed {
            break;
        }
        t = super::staging::passes::run(&c, map, placed)?;
        t.bodies = bodies(&c, map, placed, &t);
    }
    Ok(t)
}

/// Brake lights at frame `f`: slowing beyond `BRAKE_LIGHT_DECEL` (central difference of the
/// speeds' size, one-sided at the ends; forwards or reversing), or stopped.
fn braking(v: &[f64], f: usize, rate: f64) -> bool {
    let n = v.len();
    if n == 0 {
        return false;
    }
    let (lo, hi) = (f.saturating_sub(1), (f + 1).min(n - 1));
    // Slowing is the speed's size falling: a reversing car's speed is negative.
    let a = if hi > lo { (v[hi].abs() - v[lo].abs()) * rate / (hi - lo) as f64 } else { 0.0 };
    a < -BRAKE_LIGHT_DECEL || v[f.min(n - 1)].abs() < STOPPED_SPEED
}

/// Whether `p` lies on a travel lane or a junction path: within half a lane width of its centre
/// line (a shoulder or a parking strip is not).
fn on_travel_lane(map: &Map, p: DVec2) -> bool {
    let on = |line: &crate::geom::Polyline, width: f64| {
        let (s, d) = line.project(p);
        (0.0..=line.length()).contains(&s) && d.abs() <= width / 2.0
    };
    map.lanes.iter().any(|l| on(&l.centre, l.width))
        || map.connectors.iter().any(|c| on(&c.path, map.lanes[c.from].width))
}

/// The angle of each door of track `i` that moves, per frame: it swings toward open or shut
/// from the first frame its latest move's time or trigger holds.
fn doors(moves: &[DoorMove], i: usize, t: &Tracks, track_of: &dyn Fn(usize) -> Option<usize>) -> Vec<(Door, Vec<f64>)> {
    let dt = 1.0 / t.rate;
    // When each move starts: its time, or the first frame its trigger holds (never: no start).
    let starts: Vec<Option<usize>> = moves
        .iter()
        .map(|m| match m.when {
            None => Some((m.at * t.rate - 1e-9).ceil().max(0.0) as usize),
            Some(tr) => (0..t.frames).find(|&f| holds(t, i, tr, f, track_of)),
        })
        .collect();
    let mut names: Vec<Door> = moves.iter().map(|m| m.door).collect();
    names.sort();
    names.dedup();
    names
        .into_iter()
        .map(|door| {
            let mut angle = 0.0;
            let series = (0..t.frames)
                .map(|f| {
                    // The move in force: the one started last by this frame (ties: written last).
                    let open = moves
                        .iter()
                        .zip(&starts)
                        .filter(|(m, s)| m.door == door && s.is_some_and(|s| s <= f))
                        .max_by_key(|(_, s)| s.unwrap_or(0))
                        .is_some_and(|(m, _)| m.open);
                    let target = if open { DOOR_OPEN_DEG } else { 0.0 };
                    if f > 0 {
                        let step = DOOR_SWING_DEG_S * dt;
                        angle = if target > angle { (angle + step).min(target) } else { (angle - step).max(target) };
                    }
                    angle
                })
                .collect();
            (door, series)
        })
        .collect()
}

/// Whether door trigger `tr` of track `i` holds at frame `f` (the checker admits `within` and
/// `ttc`, read as `start when` reads them).
fn holds(t: &Tracks, i: usize, tr: Trigger, f: usize, track_of: &dyn Fn(usize) -> Option<usize>) -> bool {
    let Some(j) = track_of(tr.who()) else { return false };
    let (me, o) = (t.poses[i][f], t.poses[j][f]);
    let d = DVec2::new(me.x - o.x, me.y - o.y);
    let dist = d.length();
    match tr {
        Trigger::Within { m, .. } => dist <= m,
        Trigger::Ttc { s, .. } => {
            let radius = |k: usize| 0.5 * t.agents[k].size[0].hypot(t.agents[k].size[1]);
            let gap = (dist - radius(i) - radius(j)).max(0.0);
            let vel = |p: Pose, v: f64| DVec2::from_angle(p.yaw) * v;
            let rel = vel(o, t.speeds[j][f]) - vel(me, t.speeds[i][f]);
            let closing = if dist > 1e-9 { rel.dot(d) / dist } else { 0.0 };
            closing > 1e-6 && gap <= s * closing
        }
        _ => false,
    }
}

/// The `kind` of a door's box among a frame's boxes: the backends see it as part of its
/// vehicle's shape (same agent, track and class); `boxes.json` lists it as the vehicle's
/// `states.doors` instead.
pub const DOOR_KIND: &str = "door";

/// Every open door of track `i` at frame `f`: its world pose and box (length, width, height).
pub fn open_doors(t: &Tracks, i: usize, f: usize) -> impl Iterator<Item = (Pose, [f64; 3])> + '_ {
    let (size, pose) = (t.agents[i].size, t.poses[i][f]);
    t.bodies.get(i).into_iter().flat_map(move |b| {
        b.doors.iter().filter_map(move |(d, a)| a.get(f).and_then(|&deg| door_box(*d, deg, size, pose)))
    })
}

/// The box of `door` open `deg` degrees on a vehicle of `size` at `pose`, world frame: a thin box
/// hinged at the side of the body, swinging outward about its front edge. Sedan proportions: the
/// front door's hinge at 0.2 of the length ahead of the centre (at most 1.4 m behind the nose),
/// the rear door's behind the front door. `None` while it is shut.
pub fn door_box(door: Door, deg: f64, size: [f64; 3], pose: Pose) -> Option<(Pose, [f64; 3])> {
    if deg <= 0.5 {
        return None;
    }
    let [l, w, h] = size;
    let front_hinge = 0.5 * l - (0.3 * l).min(1.4);
    let front_len = (0.23 * l).min(1.1);
    let (hinge_x, len) =
        if door.is_front() { (front_hinge, front_len) } else { (front_hinge - front_len - 0.05, (0.19 * l).min(0.95)) };
    let side = if door.is_left() { 1.0 } else { -1.0 };
    let a = deg.to_radians();
    // In the vehicle's frame: hinge on the body's side, the door pointing back and outward.
    let dir = DVec2::new(-a.cos(), side * a.sin());
    let centre = DVec2::new(hinge_x, side * 0.5 * w) + dir * (0.5 * len) + dir.perp() * (side * 0.5 * DOOR_THICKNESS_M);
    let world = DVec2::new(pose.x, pose.y) + DVec2::from_angle(pose.yaw).rotate(centre);
    let yaw = wrap_angle(pose.yaw + dir.to_angle());
    Some((Pose { x: world.x, y: world.y, yaw }, [len, DOOR_THICKNESS_M, 0.85 * h]))
}
