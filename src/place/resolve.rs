//! From a placement to a world pose. In: a sampled `Place<f64>` and the `Map`. Out: a `Pose`, or
//! a `Miss` saying why the placement names nothing on this map (E0203).
//!
//! Lane and sidewalk placements are measured along a *guide*: the lane's centre line joined with
//! the lanes it continues from and into (`Lane::next`, so `west.in[1], 30 m after center` on a
//! straight road lands on `east.out[1]`), or a sidewalk's centre line joined with the sidewalks
//! that meet its ends.

use super::Pose;
use crate::check::scenario::{Arm, Dir, Keyframe, Landmark, LaneId, Place};
use crate::geom::Polyline;
use crate::road::Map;
use crate::road::map::{KerbRef, Lane};
use glam::DVec2;

/// Float slack at the ends of a guide.
const END: f64 = 1e-6;
/// Sidewalk centre lines closer than this at their ends continue one another.
const JOIN: f64 = 0.5;

/// Why a placement names nothing on this map.
#[derive(Clone, Debug, PartialEq)]
pub enum Miss {
    NoLane(LaneId),
    /// The lane has no such landmark (no stop line on an out-lane, no junction on a straight).
    NoLandmark(LaneId, Landmark),
    /// `dist` from the landmark falls outside the guide, which runs `lo` m before to `hi` m after.
    Beyond {
        what: String,
        landmark: Landmark,
        dist: f64,
        lo: f64,
        hi: f64,
    },
    NoCrosswalk(Arm),
    NoSidewalk(Arm, Dir),
    NoTrack,
    /// A parking slot or driveway the map does not lay out.
    NoKerb,
}

/// A line to measure along, and the station of a landmark on it.
pub struct Guide {
    pub line: Polyline,
    pub what: String,
}

pub fn lane_name(id: LaneId) -> String {
    format!("{}.{}[{}]", id.arm.name(), if id.dir == Dir::In { "in" } else { "out" }, id.index)
}

pub fn landmark_name(l: Landmark) -> &'static str {
    match l {
        Landmark::Center => "center",
        Landmark::Junction => "junction",
        Landmark::StopLine => "stop_line",
    }
}

fn landmark_s(lane: &Lane, l: Landmark) -> Option<f64> {
    match l {
        Landmark::Center => Some(lane.center_s),
        Landmark::Junction => lane.junction_s,
        Landmark::StopLine => lane.stop_line_s,
    }
}

/// Join polylines end to start, dropping the repeated joint.
fn join(parts: impl IntoIterator<Item = Vec<DVec2>>) -> Polyline {
    let mut pts: Vec<DVec2> = Vec::new();
    for part in parts {
        let skip = usize::from(pts.last().zip(part.first()).is_some_and(|(a, b)| a.distance(*b) < 1e-9));
        pts.extend(part.into_iter().skip(skip));
    }
    Polyline::new(pts)
}

/// The lane `id` with its predecessors and successors, and the station of `id`'s start on it.
fn lane_guide(map: &Map, id: LaneId) -> Result<(Guide, usize, f64), Miss> {
    let l = map.lanes.iter().position(|x| x.id == id).ok_or(Miss::NoLane(id))?;
    let mut order = vec![l];
    // `next` links form simple chains; the length bound also guards against a malformed cycle.
    while let Some(p) = map.lanes.iter().position(|x| x.next == Some(order[0])) {
        if order.contains(&p) || order.len() > map.lanes.len() {
            break;
        }
        order.insert(0, p);
    }
    while let Some(n) = order.last().and_then(|&i| map.lanes[i].next) {
        if order.contains(&n) || n >= map.lanes.len() {
            break;
        }
        order.push(n);
    }
    let start: f64 = order.iter().take_while(|&&i| i != l).map(|&i| map.lanes[i].centre.length()).sum();
    let line = join(order.iter().map(|&i| map.lanes[i].centre.points.clone()));
    Ok((Guide { line, what: lane_name(id) }, l, start))
}

/// Station on the lane guide of `dist` from `landmark` on lane `id`.
pub fn on_lane(map: &Map, id: LaneId, landmark: Landmark, dist: f64) -> Result<(Guide, f64), Miss> {
    let (g, l, start) = lane_guide(map, id)?;
    let at = start + landmark_s(&map.lanes[l], landmark).ok_or(Miss::NoLandmark(id, landmark))?;
    check_range(g, at, landmark, dist)
}

fn check_range(g: Guide, at: f64, landmark: Landmark, dist: f64) -> Result<(Guide, f64), Miss> {
    let s = at + dist;
    let len = g.line.length();
    if s < -END || s > len + END {
        return Err(Miss::Beyond { what: g.what, landmark, dist, lo: at, hi: len - at });
    }
    Ok((g, s.clamp(0.0, len)))
}

/// Station on the sidewalk guide of `dist` from the point abreast of `landmark` on the
/// sidewalk's adjacent (outermost) lane.
pub fn on_sidewalk(map: &Map, arm: Arm, dir: Dir, landmark: Landmark, dist: f64) -> Result<(Guide, f64), Miss> {
    let first = map.sidewalks.iter().position(|w| w.arm == arm && w.dir == dir).ok_or(Miss::NoSidewalk(arm, dir))?;
    let ends = |i: usize| {
        let c = &map.sidewalks[i].centre.points;
        (c.first().copied().unwrap_or_default(), c.last().copied().unwrap_or_default())
    };
    let mut order = vec![first];
    while let Some(p) =
        (0..map.sidewalks.len()).find(|&i| !order.contains(&i) && ends(i).1.distance(ends(order[0]).0) < JOIN)
    {
        order.insert(0, p);
    }
    while let Some(n) = (0..map.sidewalks.len())
        .find(|&i| !order.contains(&i) && ends(order[order.len() - 1]).1.distance(ends(i).0) < JOIN)
    {
        order.push(n);
    }
    let line = join(order.iter().map(|&i| map.sidewalks[i].centre.points.clone()));
    let lane = map
        .lanes
        .iter()
        .filter(|l| l.id.arm == arm && l.id.dir == dir)
        .max_by_key(|l| l.id.index)
        .ok_or(Miss::NoSidewalk(arm, dir))?;
    let ls = landmark_s(lane, landmark).ok_or(Miss::NoLandmark(lane.id, landmark))?;
    let at = line.project(lane.centre.pose_at(ls).0).0;
    let what = format!("sidewalk({}.{})", arm.name(), if dir == Dir::In { "in" } else { "out" });
    check_range(Guide { line, what }, at, landmark, dist)
}

/// Pose `offset` m left of station `s` on a guide, facing along it unless `heading` is given.
pub fn along(g: &Guide, s: f64, offset: f64, heading: Option<f64>) -> Pose {
    let (p, yaw) = g.line.pose_at(s);
    let p = p + DVec2::from_angle(yaw).perp() * offset;
    Pose { x: p.x, y: p.y, yaw: heading.unwrap_or(yaw) }
}

/// The world pose of a placement.
pub fn pose(map: &Map, place: &Place<f64>, track: Option<&[Keyframe]>) -> Result<Pose, Miss> {
    match place {
        Place::Lane { lane, along: a, offset, heading } => {
            let (g, s) = on_lane(map, *lane, a.landmark, a.dist)?;
            Ok(along(&g, s, *offset, *heading))
        }
        Place::World { x, y, heading } => Ok(Pose { x: *x, y: *y, yaw: heading.unwrap_or(0.0) }),
        Place::Crosswalk { arm, fraction } => {
            let cw = map.crosswalks.iter().find(|c| c.arm == *arm).ok_or(Miss::NoCrosswalk(*arm))?;
            let (p, yaw) = cw.line.pose_at(fraction.clamp(0.0, 1.0) * cw.line.length());
            Ok(Pose { x: p.x, y: p.y, yaw })
        }
        Place::Sidewalk { arm, dir, along: a, offset, heading } => {
            let (g, s) = on_sidewalk(map, *arm, *dir, a.landmark, a.dist)?;
            Ok(along(&g, s, *offset, *heading))
        }
        Place::Parking { arm, dir, slot } => kerb(map, KerbRef::Slot { arm: *arm, dir: *dir, slot: *slot }),
        Place::Driveway { index } => kerb(map, KerbRef::Driveway(*index)),
        Place::Track => {
            let k = track.and_then(|t| t.first()).ok_or(Miss::NoTrack)?;
            Ok(Pose { x: k.x, y: k.y, yaw: k.yaw })
        }
    }
}

/// A parking slot's or a driveway's standing place (`road/parking.rs`).
fn kerb(map: &Map, at: KerbRef) -> Result<Pose, Miss> {
    let k = map.kerb_place(at).ok_or(Miss::NoKerb)?;
    Ok(Pose { x: k.centre.x, y: k.centre.y, yaw: k.yaw })
}

impl Miss {
    pub fn message(&self, who: &str) -> (String, String) {
        match self {
            Miss::NoLane(id) => (
                format!("`{who}` is placed on {}, which this road does not have", lane_name(*id)),
                "check the lane index against `lanes`".into(),
            ),
            Miss::NoLandmark(id, l) => (
                format!("{} has no `{}` to measure from", lane_name(*id), landmark_name(*l)),
                "measure from `center`, or from `junction` / `stop_line` on a junction's in-lane".into(),
            ),
            Miss::Beyond { what, landmark, dist, lo, hi } => {
                let name = landmark_name(*landmark);
                let side = if *dist < 0.0 { "before" } else { "after" };
                (
                    format!(
                        "`{who}` would start {:.1} m {side} {name}, beyond the end of {what}, which runs from {lo:.1} m before to {hi:.1} m after {name}",
                        dist.abs()
                    ),
                    format!(
                        "place it between {lo:.0} m before and {hi:.0} m after {name}, or lengthen the road with `length`"
                    ),
                )
            }
            Miss::NoCrosswalk(arm) => (
                format!("this road has no crosswalk on the {} arm", arm.name()),
                "crosswalks exist with `crosswalks on` on straight, curve, four_way, t_junction and roundabout roads"
                    .into(),
            ),
            Miss::NoSidewalk(arm, dir) => (
                format!(
                    "this road has no sidewalk along {}.{}",
                    arm.name(),
                    if *dir == Dir::In { "in" } else { "out" }
                ),
                "add `sidewalks on` to the road block".into(),
            ),
            Miss::NoKerb => (
                format!("`{who}` is placed in a parking slot or driveway this road does not lay out"),
                "parking lanes and driveways are laid along straight roads".into(),
            ),
            Miss::NoTrack => {
                (format!("`{who}` replays a track with no keyframes"), "give the track at least one keyframe".into())
            }
        }
    }
}
