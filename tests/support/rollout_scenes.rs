//! Hand-made maps (a straight road, a four-way junction), scenes built on them without the
//! language front end, and the checks every rollout test applies (overlaps, class limits,
//! bicycle kinematics): shared by `tests/rollout*.rs`.
#![allow(dead_code)] // each test crate uses part of it

use crate::contact::obb;
use glam::DVec2;
use rocc::check::scenario::*;
use rocc::geom::{Polyline, wrap_angle};
use rocc::place::{Placed, PlacedAgent, Pose};
use rocc::road::Map;
use rocc::road::map::{Connector, Lane};
use rocc::rollout::{Tracks, limits, min_turn_radius, rollout};
use rocc::sample::{Concrete, ConcreteAgent};

// ------------------------------------------------------------------ hand-made maps

pub const W: f64 = 3.5;

pub fn lane(id: LaneId, pts: Vec<DVec2>, limit: f64, stop: Option<f64>, shoulder: f64) -> Lane {
    let centre = Polyline::new(pts);
    let len = centre.length();
    Lane {
        id,
        centre,
        width: W,
        speed_limit: limit,
        center_s: len / 2.0,
        junction_s: stop.map(|s| s + 1.0),
        stop_line_s: stop,
        shoulder_right: shoulder,
        next: None,
    }
}

pub fn id(arm: Arm, dir: Dir, index: u32) -> LaneId {
    LaneId { arm, dir, index }
}

/// A straight road along x from -150 to 150 m, `n` lanes each way, 2.5 m shoulders. `west.in`
/// lanes drive east (y < 0, index 1 nearest the centre line); `east.in` lanes drive west.
pub fn straight(n: u32) -> Map {
    let mut m = Map::default();
    for k in 1..=n {
        let y = (k as f64 - 0.5) * W;
        let sh = if k == n { 2.5 } else { 0.0 };
        let line =
            |y: f64, x0: f64, x1: f64| (0..=30).map(|i| DVec2::new(x0 + (x1 - x0) * i as f64 / 30.0, y)).collect();
        m.lanes.push(lane(id(Arm::West, Dir::In, k), line(-y, -150.0, 150.0), 14.0, None, sh));
        m.lanes.push(lane(id(Arm::East, Dir::In, k), line(y, 150.0, -150.0), 14.0, None, sh));
    }
    m
}

pub fn arm_dir(arm: Arm) -> DVec2 {
    match arm {
        Arm::North => DVec2::Y,
        Arm::South => -DVec2::Y,
        Arm::East => DVec2::X,
        _ => -DVec2::X,
    }
}

pub const J: f64 = 9.0;
pub const ARM: f64 = 60.0;

/// A four-way junction at the origin, one lane each way on every arm, arms 60 m long, stop
/// lines 1 m before the junction, connectors for every turn (cubic Beziers).
pub fn four_way() -> Map {
    let mut m = Map::default();
    let arms = [Arm::North, Arm::East, Arm::South, Arm::West];
    for arm in arms {
        let u = arm_dir(arm);
        let right_in = DVec2::new(-u.y, u.x); // right of a car driving -u
        // A 4 m median leaves room for a U-turn at a car's turning radius.
        let off = 0.5 * W + 2.0;
        let a = u * (J + ARM) + right_in * off;
        let b = u * J + right_in * off;
        let pts = (0..=20).map(|i| a.lerp(b, i as f64 / 20.0)).collect();
        m.lanes.push(lane(id(arm, Dir::In, 1), pts, 11.0, Some(ARM - 1.0), 0.0));
        let (c, d) = (u * J - right_in * off, u * (J + ARM) - right_in * off);
        let pts = (0..=20).map(|i| c.lerp(d, i as f64 / 20.0)).collect();
        m.lanes.push(lane(id(arm, Dir::Out, 1), pts, 11.0, None, 0.0));
    }
    for (fi, from) in m.lanes.iter().enumerate() {
        if from.id.dir != Dir::In {
            continue;
        }
        for (ti, to) in m.lanes.iter().enumerate() {
            if to.id.dir != Dir::Out {
                continue;
            }
            let din = -arm_dir(from.id.arm);
            let dout = arm_dir(to.id.arm);
            let turn = if from.id.arm == to.id.arm {
                Turn::UTurn
            } else if din.dot(dout) > 0.9 {
                Turn::Straight
            } else if din.perp_dot(dout) > 0.0 {
                Turn::Left
            } else {
                Turn::Right
            };
            let p0 = *from.centre.points.last().expect("lane has points");
            let p3 = to.centre.points[0];
            let k = if turn == Turn::UTurn { 4.0 / 3.0 * 0.5 * p0.distance(p3) } else { 0.55 * p0.distance(p3) };
            let (p1, p2) = (p0 + din * k, p3 - dout * k);
            let pts = (0..=24)
                .map(|i| {
                    let t = i as f64 / 24.0;
                    let s = 1.0 - t;
                    p0 * s * s * s + p1 * 3.0 * s * s * t + p2 * 3.0 * s * t * t + p3 * t * t * t
                })
                .collect();
            m.connectors.push(Connector { from: fi, to: ti, turn, path: Polyline::new(pts) });
        }
    }
    m
}

// ------------------------------------------------------------------ scenes

pub struct Spec {
    pub name: &'static str,
    pub class: Class,
    pub motion: Motion,
    pub size: [f64; 3],
    pub pose: Pose,
    pub speed: f64,
    pub goal: Option<Goal<f64>>,
    pub object: bool,
    pub track: Option<Vec<Keyframe>>,
}

pub const CAR: [f64; 3] = [4.6, 1.85, 1.5];

pub fn goal() -> Goal<f64> {
    Goal::default()
}

pub fn car(name: &'static str, pose: Pose, speed: f64, g: Option<Goal<f64>>) -> Spec {
    Spec {
        name,
        class: Class::Vehicle,
        motion: Motion::Vehicle,
        size: CAR,
        pose,
        speed,
        goal: g,
        object: false,
        track: None,
    }
}

/// Pose on a lane of `m`, `s` metres from its start, `off` to the left.
pub fn on(m: &Map, l: LaneId, s: f64, off: f64) -> Pose {
    let lane = m.lane(l).expect("lane exists");
    let (p, yaw) = lane.centre.pose_at(s);
    let p = p + DVec2::from_angle(yaw).perp() * off;
    Pose { x: p.x, y: p.y, yaw }
}

pub fn scene(
    specs: Vec<Spec>,
    conflicts: Vec<Conflict>,
    traffic: Option<Traffic>,
    duration: f64,
) -> (Concrete, Placed) {
    let road = Road {
        template: Template::Straight,
        lanes: 2,
        lane_width: W,
        speed_limit: 14.0,
        shoulder: 2.5,
        median: 0.0,
        crosswalks: false,
        sidewalks: false,
        length: 300.0,
        radius: 0.0,
        angle: 0.0,
        signals: None,
        kerb: Default::default(),
    };
    let agents: Vec<ConcreteAgent> = specs
        .iter()
        .map(|s| ConcreteAgent {
            name: s.name.to_string(),
            kind: s.name.to_string(),
            class: s.class,
            motion: s.motion,
            is_object: s.object,
            size: s.size,
            place: Place::World { x: s.pose.x, y: s.pose.y, heading: Some(s.pose.yaw) },
            speed: s.speed,
            goal: s.goal.clone(),
            track: s.track.clone(),
            behaviour: Default::default(),
            phases: vec![],
            siren: None,
            body: Default::default(),
            door_swing: vec![],
            mass: None,
            span: Default::default(),
            place_span: Default::default(),
        })
        .collect();
    let placed = Placed {
        agents: specs
            .iter()
            .enumerate()
            .map(|(i, s)| PlacedAgent {
                name: s.name.to_string(),
                kind: s.name.to_string(),
                class: s.class,
                motion: s.motion,
                is_object: s.object,
                size: s.size,
                pose: s.pose,
                speed: s.speed,
                source: Some(i),
                span: Default::default(),
            })
            .collect(),
    };
    let c = Concrete {
        name: "t".into(),
        seed: 7,
        duration,
        rate: 10.0,
        egos: vec![0],
        road,
        agents,
        rows: vec![],
        conflicts,
        near_misses: vec![],
        flaggers: vec![],
        traffic,
        kinds: Default::default(),
    };
    (c, placed)
}

/// Pairs whose boxes overlap in some frame, other than the listed conflict pairs.
pub fn overlaps(t: &Tracks, allowed: &[(usize, usize)]) -> Vec<(usize, usize, usize)> {
    let mut bad = vec![];
    for f in 0..t.frames {
        for i in 0..t.agents.len() {
            for j in i + 1..t.agents.len() {
                if allowed.iter().any(|&(a, b)| (a, b) == (i, j) || (a, b) == (j, i)) {
                    continue;
                }
                if obb(t, i, f).overlaps(&obb(t, j, f)) {
                    bad.push((f, i, j));
                }
            }
        }
    }
    bad
}

pub fn run(specs: Vec<Spec>, conflicts: Vec<Conflict>, map: &Map, duration: f64) -> Tracks {
    let (c, p) = scene(specs, conflicts, None, duration);
    rollout(&c, map, &p).expect("rollout succeeds")
}

pub fn front_gap(t: &Tracks, back: usize, front: usize, f: usize) -> f64 {
    let (a, b) = (t.poses[back][f], t.poses[front][f]);
    DVec2::new(b.x - a.x, b.y - a.y).length() - t.agents[back].size[0] / 2.0 - t.agents[front].size[0] / 2.0
}

// ------------------------------------------------------------------ checks

/// Speeds are non-negative; accelerations and yaw rates within class limits; moving vehicles
/// move along their heading (no sideways sliding beyond a lane change's slip).
pub fn check_limits(t: &Tracks) {
    let dt = 1.0 / t.rate;
    for (i, a) in t.agents.iter().enumerate() {
        let lim = limits(a.class, a.motion);
        for f in 1..t.frames {
            let v = t.speeds[i][f];
            assert!(v >= 0.0);
            let acc = (v - t.speeds[i][f - 1]) / dt;
            assert!(acc <= lim.accel + 1e-6 && acc >= -lim.brake_max - 1e-6, "{}: accel {acc} at {f}", a.name);
            let (p, q) = (t.poses[i][f - 1], t.poses[i][f]);
            let rate = wrap_angle(q.yaw - p.yaw).abs() / dt;
            assert!(rate <= lim.yaw_rate + 1e-6, "{}: yaw rate {rate} at {f}", a.name);
            let step = DVec2::new(q.x - p.x, q.y - p.y);
            if a.motion == Motion::Vehicle && step.length() > 0.3 {
                let slip = wrap_angle(step.y.atan2(step.x) - q.yaw).abs();
                assert!(slip < 0.35, "{}: slip {slip} at {f}", a.name);
            }
        }
    }
}

/// Kinematic bicycle checks on consecutive poses of every vehicle: heading change per metre
/// travelled within its kind's turning radius, displacement along the step's mean heading (no
/// sideways slip) while moving over 0.5 m/s, and speed within `v_max` (m/s, per agent). Agents
/// listed in `strikers` may use the staging's harder acceleration and yaw rate (1.6 x, 1.5 x);
/// everyone is checked up to its first impact (from it on the impact model moves it).
pub fn check_kinematics(t: &Tracks, v_max: &[f64], strikers: &[usize]) {
    let dt = 1.0 / t.rate;
    for (i, a) in t.agents.iter().enumerate() {
        let last = t.impacts.iter().filter(|r| r.at_fault == i || r.struck == i).map(|r| r.frame).min();
        let last = last.into_iter().chain(t.first_contact(i)).min();
        let lim = limits(a.class, a.motion);
        let (fa, fy) = if strikers.contains(&i) { (1.6, 1.5) } else { (1.0, 1.0) };
        let r_min = min_turn_radius(a.class, a.size[0]);
        for f in 1..last.unwrap_or(t.frames) {
            let v = t.speeds[i][f];
            assert!(v >= 0.0 && v <= v_max[i] + 0.5, "{}: speed {v:.2} at {f} (max {:.2})", a.name, v_max[i]);
            let acc = (v - t.speeds[i][f - 1]) / dt;
            let (p, q) = (t.poses[i][f - 1], t.poses[i][f]);
            assert!(acc >= -lim.brake_max - 1e-6, "{}: braking {acc} at {f}", a.name);
            assert!(acc <= fa * lim.accel + 1e-6, "{}: accel {acc} at {f}", a.name);
            let dyaw = wrap_angle(q.yaw - p.yaw);
            assert!(dyaw.abs() / dt <= fy * lim.yaw_rate + 1e-6, "{}: yaw rate {} at {f}", a.name, dyaw.abs() / dt);
            if a.motion != Motion::Vehicle {
                continue;
            }
            let step = DVec2::new(q.x - p.x, q.y - p.y);
            let ds = step.length();
            if ds > 1e-3 {
                let k = dyaw.abs() / ds;
                assert!(k <= 1.0 / r_min + 1e-3, "{}: curvature {k:.4} > 1/{r_min:.2} at {f}", a.name);
            }
            if ds > 0.5 * dt {
                let mean = p.yaw + 0.5 * dyaw;
                let slip = wrap_angle(step.y.atan2(step.x) - mean).abs();
                assert!(slip < 0.02, "{}: slip {slip:.4} rad at {f}", a.name);
            }
        }
    }
}
