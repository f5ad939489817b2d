//! `stop behind NAME`: the named leader must be ahead of the agent on its route, now or by
//! joining it (E0206). In: the `Concrete` scenario, its `Map`, the placed poses. Out: one
//! diagnostic per goal whose leader can never be ahead (the controller would silently ignore it).
//!
//! The route is the one the rollout drives (`road::route`, one function for both): the lane a
//! vehicle is found in from its pose, continued by its `turn` connector, else the straight one,
//! else the lane's continuation; a walker, an animal or a vehicle off the lanes goes straight
//! along its heading; a `change_lane` agent's route starts in the lane it moves to. The leader
//! qualifies when its centre is ahead of the agent's centre along that route and
//! - within the route's corridor (half the lane width plus half its own width: a cyclist at the
//!   lane edge counts, a car in the next lane does not), or
//! - it will enter the corridor ahead: a walker or animal that `cross`es, a vehicle that changes
//!   lane into it, or a vehicle whose own route merges into it heading the same way (a ramp, a
//!   turn into the agent's exit lane). Crossing traffic that only cuts through is not a leader.

use super::PlacedAgent;
use crate::check::scenario::{Dir, Lateral, Motion, Place, Stop, Turn};
use crate::diag::Diagnostic;
use crate::geom::Polyline;
use crate::road::Map;
use crate::road::route::{chain, find_lane, side_lane};
use crate::sample::{Concrete, ConcreteAgent};
use glam::DVec2;

/// How far an off-lane agent's straight route reaches on either side of it (m).
const RAY_M: f64 = 300.0;
/// Extra lateral room for an off-lane agent's corridor (m): it has no lane to measure.
const RAY_SLACK_M: f64 = 0.5;
/// A merging route must head within this angle of the agent's route where it joins (rad).
const JOIN_ANGLE: f64 = std::f64::consts::FRAC_PI_4;

struct Route {
    line: Polyline,
    /// Half width of the corridor before the leader's own half width is added.
    half: f64,
}

/// The lane a vehicle's route starts with, as the rollout finds it (`road::route::find_lane`:
/// the nearest lane heading its way that holds it; for a `change_lane` goal the lane it moves to,
/// `road::route::side_lane`); walkers and animals have none.
fn lane_of(map: &Map, a: &ConcreteAgent, p: &PlacedAgent) -> Option<usize> {
    if a.motion != Motion::Vehicle {
        return None;
    }
    let l = find_lane(map, centre(p), p.pose.yaw).map(|(l, _, _)| l)?;
    match a.goal.as_ref().map(|g| g.lateral) {
        // No lane on that side is the rollout's E0204; judged on the start lane meanwhile.
        Some(Lateral::ChangeLane(side)) => Some(side_lane(map, l, side).unwrap_or(l)),
        _ => Some(l),
    }
}

/// The rollout's route from lane `l` (`road::route::chain`, the same function that builds the
/// path the agent drives), without its repeated points: a zero-length segment has no direction.
fn chain_of(map: &Map, l: usize, turn: Option<Turn>) -> Vec<DVec2> {
    let (mut pts, _, _) = chain(map, l, turn);
    pts.dedup_by(|a, b| a.distance(*b) < 1e-6);
    pts
}

fn route(map: &Map, a: &ConcreteAgent, p: &PlacedAgent) -> Route {
    let turn = a.goal.as_ref().and_then(|g| g.turn);
    match lane_of(map, a, p) {
        Some(l) => Route { line: Polyline::new(chain_of(map, l, turn)), half: map.lanes[l].width / 2.0 },
        _ => {
            let c = DVec2::new(p.pose.x, p.pose.y);
            let d = DVec2::from_angle(p.pose.yaw);
            Route { line: Polyline::new(vec![c - d * RAY_M, c + d * RAY_M]), half: p.size[1] / 2.0 + RAY_SLACK_M }
        }
    }
}

fn centre(p: &PlacedAgent) -> DVec2 {
    DVec2::new(p.pose.x, p.pose.y)
}

/// Why `leader` can never be ahead of `me` on its route, or `None` when it can.
fn not_ahead(map: &Map, me: (&ConcreteAgent, &PlacedAgent), leader: (&ConcreteAgent, &PlacedAgent)) -> Option<String> {
    let r = route(map, me.0, me.1);
    let (s_me, _) = r.line.project(centre(me.1));
    let (s_x, d_x) = r.line.project(centre(leader.1));
    let corridor = r.half + leader.1.size[1] / 2.0;
    let ahead = s_x > s_me;
    let inside = d_x.abs() <= corridor;
    let name = &leader.0.name;
    if inside {
        return (!ahead).then(|| format!("`{name}` starts behind `{}` on its lane", me.0.name));
    }
    let goal = leader.0.goal.as_ref();
    let moves = leader.0.motion != Motion::Static && !leader.0.is_object;
    if moves && ahead {
        match goal.map(|g| g.lateral) {
            Some(Lateral::Cross) => return None,
            Some(Lateral::ChangeLane(_)) if d_x.abs() <= corridor + 2.0 * r.half => return None,
            _ => {}
        }
        if let Some(l) = lane_of(map, leader.0, leader.1) {
            // Its own route, from where it stands: a point of it inside our corridor, ahead of us
            // and heading our way is where it joins in front.
            let own = Polyline::new(chain_of(map, l, goal.and_then(|g| g.turn)));
            let (from, _) = own.project(centre(leader.1));
            let joins = own.points.windows(2).zip(own.s.windows(2)).any(|(w, s)| {
                let (sa, d) = r.line.project(w[1]);
                let dir = (w[1] - w[0]).normalize_or_zero();
                let (_, yaw) = r.line.pose_at(sa);
                s[1] >= from && sa > s_me && d.abs() <= corridor && dir.dot(DVec2::from_angle(yaw)) > JOIN_ANGLE.cos()
            });
            if joins {
                return None;
            }
        }
    }
    Some(if !ahead {
        format!("`{name}` starts behind `{}` and is not on its way", me.0.name)
    } else {
        format!("`{name}` is not on the route of `{}` and never joins it", me.0.name)
    })
}

/// E0206 for every `stop behind NAME` whose leader is not ahead on the agent's route.
pub fn check(c: &Concrete, map: &Map, placed: &[PlacedAgent]) -> Vec<Diagnostic> {
    let by_source = |i: usize| placed.iter().find(|p| p.source == Some(i));
    let mut errs = vec![];
    for (i, a) in c.agents.iter().enumerate() {
        let Some(g) = &a.goal else { continue };
        let Some(Stop::Behind(j)) = g.stop else { continue };
        let (Some(me), Some(x), Some(xa)) = (by_source(i), by_source(j), c.agents.get(j)) else { continue };
        if matches!(xa.place, Place::Track) {
            // A replayed track may enter anywhere later; its first keyframe says nothing.
            continue;
        }
        if let Some(why) = not_ahead(map, (a, me), (xa, x)) {
            let dir = match &a.place {
                Place::Lane { lane, .. } => {
                    format!(
                        " on {}.{}[{}]",
                        lane.arm.name(),
                        if lane.dir == Dir::In { "in" } else { "out" },
                        lane.index
                    )
                }
                _ => String::new(),
            };
            errs.push(
                Diagnostic::error("E0206", format!("`{}` cannot stop behind `{}`: {why}", a.name, xa.name))
                    .label(g.stop_span, format!("`{}` is not ahead of `{}`", xa.name, a.name))
                    .label(xa.place_span, format!("`{}` starts here", xa.name))
                    .help(format!(
                        "place `{}` ahead of `{}`{dir} (further along its lane), name the agent that is ahead, or use `stop after DIST`",
                        xa.name, a.name
                    )),
            );
        }
    }
    errs
}
