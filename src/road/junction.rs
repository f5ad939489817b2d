//! The `four_way` and `t_junction` templates. In: the road. Out: the `Map`.
//!
//! Arms leave the origin north (+y), east (+x), south (-y), west (-x); the T has no north arm
//! (its stem is south). Each arm's mouth is `J = half_width + CORNER` from the origin, where
//! `half_width` counts median/2, lanes and shoulder. The junction area is the square |x|, |y| <= J
//! with its corners between two arms rounded to kerb arcs of radius `CORNER`; on the T the north
//! side is the straight kerb of the through road. Along each arm from the mouth: a 1 m gap, the
//! crosswalk (4 m, when on), 1 m, then the stop line; `length` of approach lies beyond the stop
//! line, so `N m before stop_line` is on the lane for every N up to `length`.

use super::arm::{ArmSpec, CROSSWALK, SIDEWALK, add_arm};
use super::map::{Connector, Map};
use super::shape::{arc, segment, turn};
use crate::check::scenario::{Arm, Road, Template, Turn};
use crate::geom::{Polygon, Polyline};
use glam::DVec2;
use std::f64::consts::FRAC_PI_2;

/// Kerb radius at the junction corners (m): room for a right turn from the outermost lane.
const CORNER: f64 = 6.0;

/// Arms counter-clockwise from east, with their outward unit vectors (exact, so that the map is
/// exactly symmetric under quarter turns).
pub(crate) const ARMS: [(Arm, DVec2); 4] = [
    (Arm::East, DVec2::new(1.0, 0.0)),
    (Arm::North, DVec2::new(0.0, 1.0)),
    (Arm::West, DVec2::new(-1.0, 0.0)),
    (Arm::South, DVec2::new(0.0, -1.0)),
];

pub(crate) fn build(road: &Road) -> Map {
    let present: Vec<(Arm, DVec2)> =
        ARMS.iter().copied().filter(|(a, _)| road.template != Template::TJunction || *a != Arm::North).collect();
    let h = road.median / 2.0 + f64::from(road.lanes) * road.lane_width + road.shoulder;
    let j = h + CORNER;
    let stop = if road.crosswalks { 2.0 + CROSSWALK } else { 1.0 };
    let mut map = Map::default();
    let mut built = Vec::new();
    for &(arm, u) in &present {
        let spec = ArmSpec {
            arm,
            axis: Polyline::new(vec![u * j, u * (j + stop + road.length)]),
            n_in: road.lanes,
            n_out: road.lanes,
            lane_width: road.lane_width,
            median: road.median,
            shoulder: road.shoulder,
            speed_limit: road.speed_limit,
            stop_at: Some(stop),
            crosswalk_at: road.crosswalks.then_some(1.0),
            junction: true,
            markings_from: stop,
            sidewalks: road.sidewalks,
            sidewalk_inner: false,
        };
        built.push((arm, u, add_arm(&mut map, &spec)));
    }

    // Junction outline, counter-clockwise; corner arcs only between two present arms.
    let has = |u: DVec2| present.iter().any(|(_, v)| *v == u);
    let mut area: Polygon = Vec::new();
    for &(_, u) in &present {
        let v = u.perp();
        area.push(u * j - v * h);
        area.push(u * j + v * h);
        if has(v) {
            let c = (u + v) * j;
            let a0 = (-v).to_angle();
            let mut pts = arc(c, CORNER, a0, a0 - FRAC_PI_2);
            pts.pop();
            pts.remove(0);
            area.extend(pts);
        }
    }
    map.intersections.push(area.clone());
    map.drivable.push(area);

    if road.sidewalks {
        for &(_, u) in &present {
            let v = u.perp();
            if has(v) {
                // Kerb corner: a quarter ring around the kerb arc's centre.
                let c = (u + v) * j;
                let a0 = (-v).to_angle();
                let mut ring = arc(c, CORNER, a0, a0 - FRAC_PI_2);
                ring.extend(arc(c, CORNER - SIDEWALK, a0 - FRAC_PI_2, a0));
                map.walkways.push(ring);
            } else if has(-u) {
                // The T's far side: a straight walk along the through road's kerb.
                map.walkways.push(vec![
                    u * j + v * h,
                    u * j + v * (h + SIDEWALK),
                    -u * j + v * (h + SIDEWALK),
                    -u * j + v * h,
                ]);
            }
        }
    }

    // Connectors (driving toward the centre along -u, the right-hand exit is u.perp()): from each in-lane, every turn whose exit arm exists, to the out-lane of the same
    // index (lane counts are equal on every arm).
    for &(_, u, ref from) in &built {
        for (turn_kind, exit) in
            [(Turn::Right, u.perp()), (Turn::Straight, -u), (Turn::Left, -u.perp()), (Turn::UTurn, u)]
        {
            let Some((_, _, to)) = built.iter().find(|(_, v, _)| *v == exit) else { continue };
            for (k, &fi) in from.ins.iter().enumerate() {
                let Some(&ti) = to.outs.get(k).or(to.outs.last()) else { continue };
                let p0 = *map.lanes[fi].centre.points.last().expect("lanes have two or more points");
                let p3 = map.lanes[ti].centre.points[0];
                let pts =
                    if turn_kind == Turn::UTurn { u_turn(p0, -u, p3, CORNER / 2.0) } else { turn(p0, -u, p3, exit) };
                let path = Polyline::new(pts);
                if turn_kind != Turn::UTurn {
                    map.lane_group_connectors.push(corridor(&path, road.lane_width));
                }
                map.connectors.push(Connector { from: fi, to: ti, turn: turn_kind, path });
            }
        }
    }
    map
}

/// Drive `lead` metres into the junction, sweep a half circle to the left onto the parallel
/// out-lane, and drive back out. The radius is half the gap between the two lanes: tight for
/// lanes either side of a bare centre line, as a U-turn across a junction is.
pub(crate) fn u_turn(p0: DVec2, d: DVec2, p3: DVec2, lead: f64) -> Vec<DVec2> {
    let (a, b) = (p0 + d * lead, p3 + d * lead);
    let c = (a + b) / 2.0;
    let r = a.distance(b) / 2.0;
    let a0 = (a - c).to_angle();
    let mut pts = segment(p0, a);
    pts.pop();
    pts.extend(arc(c, r, a0, a0 + std::f64::consts::PI));
    pts.pop();
    pts.extend(segment(b, p3));
    pts
}

/// A band one lane wide around a connector path.
pub(crate) fn corridor(path: &Polyline, width: f64) -> Polygon {
    let mut poly = path.shifted(width / 2.0).points;
    poly.extend(path.shifted(-width / 2.0).points.into_iter().rev());
    poly
}
