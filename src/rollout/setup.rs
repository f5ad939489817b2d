//! Set-up: an `Actor` for every placed agent (route, goals, limits) and for background traffic,
//! once, before the first frame.

use crate::check::scenario::{Class, Lateral, Motion};
use crate::check::scenario::{EMERGENCY_KINDS, Side, Stop, Turn};
use crate::diag::Diagnostic;
use crate::place::Pose;
use crate::road::Map;
use crate::road::route::RUN_OUT;
use crate::road::route::{chain, find_lane, side_lane};
use crate::rollout::agent::{Actor, Conf, Drive, Lat, Stage, StopGoal};
use crate::rollout::junction::dry_run::junction_curvature;
use crate::rollout::path::Path;
use crate::rollout::path::Resampler;
use crate::rollout::room::{room_at, single_lane};
use crate::rollout::traffic;
use crate::rollout::{TrackAgent, limits};
use crate::sample::{Concrete, ConcreteAgent};
use glam::DVec2;

/// Pace of a `cross` goal given no speed at all, m/s.
pub(crate) const WALK_SPEED: f64 = 1.4;
/// How much tighter than a vehicle's turning radius a junction path may turn before the turn is
/// refused (E0204). Up to it the vehicle swings wider across the junction area (a sedan's U-turn
/// on a four_way without median: its path turns on 1.7 m, the sedan on 4.0 m); beyond it (a bus
/// on 10.3 m) the arc leaves the road, as the template property test checks.
pub(crate) const TURN_SLACK: f64 = 3.0;
/// Lateral manoeuvre durations, s.
pub(crate) const LANE_CHANGE_S: f64 = 4.0;
pub(crate) const ASIDE_S: f64 = 2.5;

/// A tree or a pole has no front: its yaw is whatever the placement gave it (the lane's heading),
/// so a requested `point front` in that frame could send the striker around the trunk to hit
/// its far face. Turn such a struck object (a static structure, roughly square or under 2 m) to face the
/// striker's start, so the requested side reads from the striker's approach: `front` is the face
/// it drives into, `left` the one on the striker's right as it comes. Walls and buildings keep
/// their yaw: their faces are real.
pub(crate) fn face_the_striker(actors: &mut [Actor], k: &Conf) {
    let (af, st) = (actors[k.af].init, &actors[k.st]);
    // A trunk or a pole: roughly square, or small whatever its sampled aspect (a 0.75 x 0.45 m
    // tree box is still a trunk; a car could not drive around it to a far face in any case).
    let trunk = st.hl.max(st.hw) <= 1.5 * st.hl.min(st.hw) || st.hl.max(st.hw) < 1.0;
    if !matches!(st.drive, Drive::Static) || st.info.class != Class::Structure || !trunk {
        return;
    }
    let to_striker = DVec2::new(af.x - st.init.x, af.y - st.init.y);
    if to_striker.length() > 1e-6 {
        actors[k.st].init.yaw = to_striker.y.atan2(to_striker.x);
    }
}

pub(crate) fn base_actor(info: TrackAgent, pose: Pose, motion: Motion, class: Class, drive: Drive) -> Actor {
    let [l, w, _] = info.size;
    Actor {
        drive,
        doors: vec![],
        vehicle: motion == Motion::Vehicle,
        hl: l / 2.0,
        hw: w / 2.0,
        radius: 0.5 * (l * l + w * w).sqrt(),
        r_min: crate::rollout::min_turn_radius(class, l),
        lim: limits(class, motion),
        path: Path::default(),
        init: pose,
        s0: 0.0,
        d0: 0.0,
        v0: 0.0,
        v_goal: 0.0,
        v_hold: 0.0,
        start: 0.0,
        trigger: None,
        behaviour: Default::default(),
        phases: vec![],
        lateral: Lat::Hold,
        shift_stage: 0,
        stop: StopGoal::None,
        emergency: false,
        junction: None,
        yield_to: vec![],
        span: None,
        turn_goal: None,
        crossings: vec![],
        kerb: None,
        in_conflict: false,
        approach: None,
        bend: None,
        signal: None,
        flag: None,
        flaggers: vec![],
        blocker: false,
        room: None,
        pull: 0.0,
        lane_hw: 1.75,
        single: false,
        reverse: false,
        info,
    }
}

pub(crate) fn build_actor(
    c: &Concrete,
    map: &Map,
    p: &crate::place::PlacedAgent,
    track_of: &[Option<usize>],
    routes: &mut Routes,
    errs: &mut Vec<Diagnostic>,
) -> Actor {
    let info = TrackAgent {
        name: p.name.clone(),
        kind: p.kind.clone(),
        class: p.class,
        motion: p.motion,
        size: p.size,
        background: false,
    };
    let ca = p.source.and_then(|i| c.agents.get(i));
    let doors = ca.map(|ca| ca.door_swing.clone()).unwrap_or_default();
    // A recorded track is what happened: it is replayed even for a kind that never moves by
    // itself (a cone carried on a pickup), so an imported clip reproduces its boxes exactly.
    if let Some(keys) = ca.filter(|_| !p.is_object).and_then(|ca| ca.track.as_ref()).filter(|k| !k.is_empty()) {
        let mut a = base_actor(info, p.pose, p.motion, p.class, Drive::Replay(keys.clone()));
        // `track when ...`: the replay starts when its trigger fires.
        let when = ca.and_then(|ca| ca.goal.as_ref()?.start_when);
        a.trigger = when.and_then(|t| crate::rollout::trigger::on_tracks(t, track_of));
        return a;
    }
    let Some(ca) = ca.filter(|_| !p.is_object && p.motion != Motion::Static) else {
        let mut a = base_actor(info, p.pose, p.motion, p.class, Drive::Static);
        a.blocker = true;
        a.doors = doors;
        a.room = room_at(map, DVec2::new(p.pose.x, p.pose.y));
        return a;
    };
    let mut a = base_actor(info, p.pose, p.motion, p.class, Drive::Mover);
    a.span = Some(p.span);
    a.emergency = a.vehicle && is_emergency(c, &p.kind) && ca.siren != Some(false);
    let pos = DVec2::new(p.pose.x, p.pose.y);
    let goal = ca.goal.as_ref();
    let fail = |errs: &mut Vec<Diagnostic>, msg: String, help: &str| errs.push(goal_error(ca, msg, help));
    a.v0 = p.speed.max(0.0);
    a.v_hold = a.v0;
    a.start = goal.map(|g| g.start_after.max(0.0)).unwrap_or(0.0);
    a.trigger = goal.and_then(|g| g.start_when).and_then(|t| crate::rollout::trigger::on_tracks(t, track_of));
    a.behaviour = ca.behaviour;
    // Each phase keeps the speed, stop and pull-over of the one before unless it states its own.
    let mut prev =
        Stage { v_goal: f64::NAN, start: 0.0, trigger: None, stop_after: None, own_stop: false, pull: false };
    a.phases = ca
        .phases
        .iter()
        .take(u8::MAX as usize)
        .map(|p| {
            let v_goal = p.speed.map_or(prev.v_goal, |v| v.max(0.0));
            prev = Stage {
                v_goal,
                start: p.start_after.max(0.0),
                trigger: p.start_when.and_then(|t| crate::rollout::trigger::on_tracks(t, track_of)),
                stop_after: p.stop_after.or(prev.stop_after),
                own_stop: p.stop_after.is_some(),
                pull: p.pull_over || prev.pull,
            };
            prev
        })
        .collect();
    let (lateral, shift_stage) = route_lateral(ca, a.vehicle);
    a.shift_stage = shift_stage;
    let mut facts = LaneFacts { limit: f64::INFINITY, stop_line: None, lane: None };
    if a.vehicle {
        facts = vehicle_route(c, map, p, ca, &mut a, routes, errs);
    } else if lateral == Lateral::Cross {
        match cross_line(map, pos) {
            Some((yaw, len, kerb)) => {
                // An animal bounds on past the far verge instead of pulling up on it, so that it
                // crosses at its goal speed (scenarios/rare/deer_leaps_onto_rural_road.scn).
                let run_on = match goal.and_then(|g| g.speed) {
                    Some(v) if a.lim == crate::rollout::ANIMAL => v * v / a.lim.brake,
                    _ => 0.0,
                };
                a.path = Path::straight(pos, yaw, len + run_on);
                a.kerb = Some(kerb);
            }
            None => {
                fail(errs, format!("`{}` has no road nearby to cross", ca.name), "place it beside a lane");
                a.path = Path::straight(pos, p.pose.yaw, 1.0);
            }
        }
    } else {
        a.path = Path::straight(pos, p.pose.yaw, RUN_OUT);
    }
    let LaneFacts { limit, stop_line, lane: lane_here } = facts;
    a.path.set_caps(a.lim.lat_acc, a.lim.yaw_rate, a.lim.brake);
    // An explicit goal speed may exceed the lane limit (an ambulance); a kept speed may not.
    // A route goal (a turn, a lane change, a crossing) means to go somewhere: started from rest
    // with no goal speed, it drives at the lane limit, or walks at an ordinary pace.
    let goes = goal.is_some_and(|g| g.turn.is_some() || matches!(g.lateral, Lateral::ChangeLane(_)));
    a.v_goal = match goal.and_then(|g| g.speed) {
        Some(v) => v.max(0.0),
        None if a.vehicle && goes && a.v0 < 0.05 && limit.is_finite() => limit * (1.0 + a.behaviour.speeding),
        // A speeding driver drives over the limit whatever its placed speed.
        None if a.vehicle && a.behaviour.speeding > 0.0 && limit.is_finite() => limit * (1.0 + a.behaviour.speeding),
        None if a.vehicle => a.v0.min(limit),
        None if lateral == Lateral::Cross && a.v0 < 0.05 => WALK_SPEED,
        None => a.v0,
    };
    let mut v = a.v_goal;
    for p in &mut a.phases {
        p.v_goal = if p.v_goal.is_nan() { v } else { p.v_goal };
        v = p.v_goal;
    }
    let lane = lane_here.map(|l| &map.lanes[l]);
    let aside = pull_offset;
    a.lateral = match lateral {
        Lateral::HoldLane | Lateral::Cross => Lat::Hold,
        Lateral::ChangeLane(_) => Lat::Shift { target: 0.0, dur: LANE_CHANGE_S },
        Lateral::PullToShoulder => Lat::Shift { target: aside(lane, a.hw, a.d0), dur: LANE_CHANGE_S },
        Lateral::AwayFrom(k) => match track_of.get(k).copied().flatten() {
            Some(who) => Lat::Away { who, target: aside(lane, a.hw, a.d0), dur: ASIDE_S },
            None => Lat::Hold,
        },
    };
    a.stop = match goal.and_then(|g| g.stop) {
        None => StopGoal::None,
        Some(Stop::AtStopLine) => match stop_line {
            // Stop lines are painted across the lane; the front bumper halts just short of it.
            Some(sl) => StopGoal::Front(sl - 0.3),
            None => {
                fail(
                    errs,
                    format!("`{}` has no stop line ahead on its lane", ca.name),
                    "stop lines exist on the in-lanes of four_way, t_junction and roundabout roads",
                );
                StopGoal::None
            }
        },
        Some(Stop::Behind(k)) => match track_of.get(k).copied().flatten() {
            Some(t) => StopGoal::Behind(t),
            None => StopGoal::None,
        },
        Some(Stop::After(dist)) => StopGoal::Centre(a.s0 + dist.max(0.0)),
    };
    if let Some(r) = goal.and_then(|g| g.reverse).filter(|_| a.vehicle) {
        crate::rollout::drive::reverse::setup(map, &mut a, r, goal.and_then(|g| g.speed), errs);
    }
    if a.vehicle {
        a.pull = pull_offset(lane, a.hw, a.d0);
        a.lane_hw = lane.map_or(1.75, |l| l.width / 2.0);
        a.single = lane_here.is_some_and(|l| single_lane(map, l));
        // Stalled: no speed, and no goal that would set it going.
        a.blocker = a.v0 < 0.05
            && a.v_goal < 0.05
            && matches!((&a.stop, &a.lateral), (StopGoal::None, Lat::Hold))
            && goal.and_then(|g| g.turn).is_none();
        if a.blocker {
            a.room = room_at(map, pos);
            a.doors = doors;
        }
    }
    a
}

/// Where a vehicle in `lane` (centre offset `d0`, half width `hw`) pulls over to: onto the
/// shoulder, or as far right in its lane as leaves 0.2 m; never left of where it is.
fn pull_offset(lane: Option<&crate::road::map::Lane>, hw: f64, d0: f64) -> f64 {
    let (w, sh) = lane.map(|l| (l.width, l.shoulder_right)).unwrap_or((3.5, 0.0));
    (-(w / 2.0 + sh - hw - 0.2)).min(d0)
}

/// What set-up needs of the lane a vehicle's route starts on: its speed limit, the stop line
/// ahead, and the lane (none off the lanes).
struct LaneFacts {
    limit: f64,
    stop_line: Option<f64>,
    lane: Option<usize>,
}

/// E0204 on a placed agent's goal.
fn goal_error(ca: &ConcreteAgent, msg: String, help: &str) -> Diagnostic {
    Diagnostic::error("E0204", msg).label(ca.span, "this goal").help(help.to_string())
}

/// The lateral move that sets the route, and the phase it waits for (`Actor::shift_stage`): a
/// lane change in a phase routes on the target lane from the start, the shift towards it
/// waiting for the phase (tests/behaviour-cases/car-changes-lane-on-a-trigger.scn).
fn route_lateral(ca: &ConcreteAgent, vehicle: bool) -> (Lateral, u8) {
    let first = ca.goal.as_ref().map(|g| g.lateral).unwrap_or(Lateral::HoldLane);
    match ca.phases.iter().enumerate().find_map(|(k, p)| Some((k, p.change?))) {
        Some((k, side)) if vehicle && first == Lateral::HoldLane => {
            (Lateral::ChangeLane(side), (k + 1).min(u8::MAX as usize) as u8)
        }
        _ => (first, 0),
    }
}

/// Vehicle `a`'s route from its lane (the target lane of a lane change), its turn checked against
/// its turning radius.
fn vehicle_route(
    c: &Concrete,
    map: &Map,
    p: &crate::place::PlacedAgent,
    ca: &ConcreteAgent,
    a: &mut Actor,
    routes: &mut Routes,
    errs: &mut Vec<Diagnostic>,
) -> LaneFacts {
    let pos = DVec2::new(p.pose.x, p.pose.y);
    let goal = ca.goal.as_ref();
    let lateral = route_lateral(ca, true).0;
    let fail = |errs: &mut Vec<Diagnostic>, msg: String, help: &str| errs.push(goal_error(ca, msg, help));
    let mut facts = LaneFacts { limit: f64::INFINITY, stop_line: None, lane: None };
    let found = find_lane(map, pos, p.pose.yaw);
    let mut base = found.map(|(l, _, _)| l);
    if let Lateral::ChangeLane(side) = lateral {
        match base.and_then(|l| side_lane(map, l, side)) {
            Some(t) => base = Some(t),
            None => fail(
                errs,
                format!("`{}` cannot change lane {}: there is no lane on that side", ca.name, side_name(side)),
                "lane 1 is nearest the centre line: `left` moves to index-1, `right` to index+1",
            ),
        }
    }
    match base {
        Some(l) => {
            let lane = &map.lanes[l];
            let turn = goal.and_then(|g| g.turn);
            let (pts, ok, junction) = chain(map, l, turn);
            a.junction = junction;
            if !ok {
                fail(
                    errs,
                    format!(
                        "`{}` cannot turn {}: no junction connector of that kind leaves its lane",
                        ca.name,
                        turn.map(turn_name).unwrap_or("")
                    ),
                    "place the agent on an in-lane of a junction that offers this turn",
                );
            }
            let (s, d) = lane.centre.project(pos);
            (a.s0, a.d0) = (s, d);
            let v_top = a.v0.max(goal.and_then(|g| g.speed).unwrap_or(0.0)).max(lane.speed_limit);
            a.path = route_path(routes, (l, turn), &pts, s.max(0.0) + reach(v_top, c.duration));
            // A turn tighter than the kind can steer (a bus's U-turn on a narrow junction)
            // would leave the road: refused, not driven wide.
            if let (Some(t), Some(j)) = (turn, a.junction) {
                a.turn_goal = Some(t);
                let k = junction_curvature(map, &a.path, j);
                if k * a.r_min > TURN_SLACK {
                    fail(
                        errs,
                        format!(
                            "`{}` ({}, turning radius {:.1} m) cannot turn {} here: the junction's path turns on {:.1} m",
                            ca.name,
                            p.kind,
                            a.r_min,
                            turn_name(t),
                            1.0 / k
                        ),
                        "a wider road (lane_width, median) or a smaller kind; rocc derives the turning radius \
                         from the kind's length (see docs/rollout.md)",
                    );
                }
            }
            facts = LaneFacts {
                limit: lane.speed_limit,
                stop_line: lane.stop_line_s.filter(|&sl| sl > a.s0),
                lane: Some(l),
            };
        }
        None => {
            a.path = Path::straight(pos, p.pose.yaw, RUN_OUT * 2.0);
            if goal.is_some_and(|g| g.turn.is_some()) {
                fail(errs, format!("`{}` is not on a lane, so it cannot turn", ca.name), "start it on a lane");
            }
        }
    }
    facts
}

/// Resampled routes by start lane and turn (`chain`'s arguments, so one key is one chain).
pub(crate) type Routes = std::collections::HashMap<(usize, Option<Turn>), Resampler>;

/// `Path::new_until(pts, until)` for the chain `key`, reusing the resampling of agents before.
pub(crate) fn route_path(routes: &mut Routes, key: (usize, Option<Turn>), pts: &[DVec2], until: f64) -> Path {
    routes.entry(key).or_insert_with(|| Resampler::new(pts)).path(until)
}

/// Whether a kind drives with lights and siren: the checker resolved it through the kind's
/// ancestry (`kind my_amb: ambulance`); the stdlib names count even where the scenario's kind
/// table lacks them (a hand-built `Concrete`).
pub(crate) fn is_emergency(c: &Concrete, kind: &str) -> bool {
    EMERGENCY_KINDS.contains(&kind) || c.kinds.get(kind).is_some_and(|k| k.emergency)
}

/// How much of its route an agent can use within a clip of `duration` s: driving at up to 1.25
/// times `v` (at least 15 m/s) all the way, plus the longest look-ahead of the car-following
/// law at that speed and a margin. Nothing beyond can affect the clip.
pub(crate) fn reach(v: f64, duration: f64) -> f64 {
    let v = if v.is_finite() { v.max(15.0) * 1.25 } else { 40.0 };
    v * duration + v * v / (2.0 * 2.0) + 2.5 * v + 60.0
}

pub(crate) fn background_actor(map: &Map, s: traffic::Spawn, duration: f64, routes: &mut Routes) -> Actor {
    let lane = &map.lanes[s.lane];
    let (p, yaw) = lane.centre.pose_at(s.s);
    let info = TrackAgent {
        name: s.name,
        kind: s.kind.to_string(),
        class: Class::Vehicle,
        motion: Motion::Vehicle,
        size: s.size,
        background: true,
    };
    let mut a = base_actor(info, Pose { x: p.x, y: p.y, yaw }, Motion::Vehicle, Class::Vehicle, Drive::Mover);
    let (pts, _, junction) = chain(map, s.lane, None);
    a.junction = junction;
    a.path = route_path(routes, (s.lane, None), &pts, s.s.max(0.0) + reach(s.speed.max(s.target), duration));
    a.path.set_caps(a.lim.lat_acc, a.lim.yaw_rate, a.lim.brake);
    a.s0 = s.s;
    a.v0 = s.speed;
    a.v_hold = s.speed;
    a.v_goal = s.target;
    a.pull = pull_offset(Some(lane), a.hw, 0.0);
    a.lane_hw = lane.width / 2.0;
    a.single = single_lane(map, s.lane);
    a
}

pub(crate) fn side_name(s: Side) -> &'static str {
    match s {
        Side::Left => "left",
        Side::Right => "right",
    }
}

pub(crate) fn turn_name(t: Turn) -> &'static str {
    match t {
        Turn::Left => "left",
        Turn::Right => "right",
        Turn::Straight => "straight",
        Turn::UTurn => "u_turn",
    }
}

/// Heading and length of a walk straight across the nearest road from `p`: perpendicular to
/// the nearest lane, toward it, ending 2 m past the last lane or shoulder met; and how far along
/// it the road begins.
pub(crate) fn cross_line(map: &Map, p: DVec2) -> Option<(f64, f64, f64)> {
    let mut near: Option<(usize, f64, f64)> = None;
    for (i, l) in map.lanes.iter().enumerate() {
        if l.centre.points.len() < 2 {
            continue;
        }
        let (s, d) = l.centre.project(p);
        if near.is_none_or(|b| d.abs() < b.2.abs()) {
            near = Some((i, s, d));
        }
    }
    let (i, s, d) = near?;
    let (_, h) = map.lanes[i].centre.pose_at(s);
    let dir = DVec2::from_angle(h).perp() * if d > 0.0 { -1.0 } else { 1.0 };
    // A lane holds q only within its half width and shoulder of its centre line: where the box
    // of that line, grown by as much and a millimetre (far above rounding), does not hold q,
    // the projection (this loop's cost) would say no, so it is not made.
    let boxes: Vec<(DVec2, DVec2)> = map
        .lanes
        .iter()
        .map(|l| {
            let grow = DVec2::splat(l.width / 2.0 + l.shoulder_right.max(0.0) + 1e-3);
            let (lo, hi) = l
                .centre
                .points
                .iter()
                .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &q| (lo.min(q), hi.max(q)));
            (lo - grow, hi + grow)
        })
        .collect();
    let on_road = |q: DVec2| {
        map.lanes.iter().zip(&boxes).any(|(l, (lo, hi))| {
            if q.x < lo.x || q.x > hi.x || q.y < lo.y || q.y > hi.y {
                return false;
            }
            let (s, d) = l.centre.project(q);
            s > 0.0 && s < l.centre.length() && d.abs() <= l.width / 2.0 + if d < 0.0 { l.shoulder_right } else { 0.0 }
        })
    };
    let (mut first, mut last) = (None, None);
    for k in 0..=160 {
        let dist = k as f64 * 0.5;
        if on_road(p + dir * dist) {
            first = first.or(Some(dist));
            last = Some(dist);
        } else if last.is_some_and(|l| dist - l > 4.0) {
            break;
        }
    }
    Some((dir.y.atan2(dir.x), last? + 2.0, (first? - 0.5).max(0.0)))
}

/// Random actors for the unit tests of the frame loop's parts.
#[cfg(test)]
pub(crate) mod test_actors {
    use super::base_actor;
    use crate::check::scenario::{Class, Motion};
    use crate::place::Pose;
    use crate::rollout::TrackAgent;
    use crate::rollout::agent::{Actor, Drive};

    /// A reproducible stream of numbers in [0, 1) (a 64-bit LCG's top 53 bits).
    pub(crate) fn lcg(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// `n` vehicle actors of random size (1 m to `1 + extra` m long) at the origin.
    pub(crate) fn random_boxes(n: usize, extra: f64, rnd: &mut impl FnMut() -> f64) -> Vec<Actor> {
        (0..n)
            .map(|k| {
                let info = TrackAgent {
                    name: format!("a{k}"),
                    kind: "sedan".into(),
                    class: Class::Vehicle,
                    motion: Motion::Vehicle,
                    size: [1.0 + extra * rnd(), 0.5 + 2.0 * rnd(), 1.5],
                    background: false,
                };
                base_actor(info, Pose { x: 0.0, y: 0.0, yaw: 0.0 }, Motion::Vehicle, Class::Vehicle, Drive::Mover)
            })
            .collect()
    }
}
