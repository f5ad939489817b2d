//! Two-arm roads without a junction (`straight`, and `curve` through `curve.rs`). In: the road
//! and the two arm axes, both starting at the road centre (the origin). Out: the `Map`.
//!
//! `west.in` drives from the west end to the centre and continues (`next`) into `east.out`;
//! `east.in` drives from the east end to the centre and continues into `west.out`. With
//! `crosswalks on`, one mid-block crosswalk is centred on the origin; it serves both
//! `crosswalk(west)` and `crosswalk(east)`, whose walking lines run in opposite directions
//! (each from the right-hand kerb of that arm's in-lanes).

use super::arm::{ArmSpec, CROSSWALK, add_arm};
use super::map::{Crosswalk, Map};
use super::shape::{reversed, strip};
use crate::check::scenario::{Arm, Road};
use crate::geom::Polyline;
use glam::DVec2;

pub(crate) fn build(road: &Road) -> Map {
    let half = road.length / 2.0;
    two_arm(
        road,
        Polyline::new(vec![DVec2::ZERO, DVec2::new(-half, 0.0)]),
        Polyline::new(vec![DVec2::ZERO, DVec2::new(half, 0.0)]),
    )
}

pub(crate) fn two_arm(road: &Road, west: Polyline, east: Polyline) -> Map {
    let mut map = Map::default();
    let clear = if road.crosswalks { CROSSWALK / 2.0 + 1.0 } else { 0.0 };
    let spec = |arm, axis| ArmSpec {
        arm,
        axis,
        n_in: road.lanes,
        n_out: road.lanes,
        lane_width: road.lane_width,
        median: road.median,
        shoulder: road.shoulder,
        speed_limit: road.speed_limit,
        stop_at: None,
        crosswalk_at: None,
        junction: false,
        markings_from: clear,
        sidewalks: road.sidewalks,
        sidewalk_inner: false,
    };
    let (ws, es) = (spec(Arm::West, west), spec(Arm::East, east));
    let (h, _) = ws.half_widths();
    // The full centre line, west end to east end, for the crosswalk across the origin.
    let mut pts = reversed(&ws.axis).points;
    pts.extend(es.axis.points.iter().skip(1));
    let full = Polyline::new(pts);
    let mid = ws.axis.length();
    let w = add_arm(&mut map, &ws);
    let e = add_arm(&mut map, &es);
    for (k, &l) in w.ins.iter().enumerate() {
        map.lanes[l].next = e.outs.get(k).copied();
    }
    for (k, &l) in e.ins.iter().enumerate() {
        map.lanes[l].next = w.outs.get(k).copied();
    }
    if road.crosswalks {
        let polygon = strip(&full, mid - CROSSWALK / 2.0, mid + CROSSWALK / 2.0, -h, h);
        map.crosswalk_polygons.push(polygon.clone());
        // West's in-lanes drive east, right of the full line; east's drive west, left of it.
        let (south, north) = (full.offset_point(mid, -h), full.offset_point(mid, h));
        map.crosswalks.push(Crosswalk {
            arm: Arm::West,
            polygon: polygon.clone(),
            line: Polyline::new(vec![south, north]),
        });
        map.crosswalks.push(Crosswalk { arm: Arm::East, polygon, line: Polyline::new(vec![north, south]) });
    }
    map
}
