//! Road pass. In: the checked `Road` (template + parameters). Out: a `Map` in the world frame.
//!
//! Conventions every template keeps: x east, y north, metres, right-hand traffic; junction
//! templates are centred on the origin with arms north (+y), east (+x), south (-y), west (-x);
//! `ARM.in[k]` drives toward the centre, `ARM.out[k]` away, k = 1 nearest the centre line.
//! Each template's own module documents its layout.

mod arm;
mod curve;
mod junction;
pub mod map;
mod merge;
pub(crate) mod parking;
mod roundabout;
pub mod route;
pub(crate) mod shape;
pub mod signals;
mod straight;

pub use map::Map;

use crate::check::scenario::{Road, Template};

/// Synthesise the map of `road`.
pub fn build(road: &Road) -> Map {
    let mut map = match road.template {
        Template::Straight => straight::build(road),
        Template::Curve => curve::build(road),
        Template::FourWay | Template::TJunction => junction::build(road),
        Template::Merge => merge::build(road),
        Template::Roundabout => roundabout::build(road),
        // Replayed recorded tracks carry no map of their own.
        Template::None => Map::default(),
    };
    if !road.kerb.is_empty() {
        parking::lay(road, &mut map);
    }
    map.bounds = bounds(&map);
    map.signals = road.signals.map(|c| signals::plan(c, &map));
    map
}

fn bounds(m: &Map) -> (glam::DVec2, glam::DVec2) {
    let mut b = (glam::DVec2::splat(f64::INFINITY), glam::DVec2::splat(f64::NEG_INFINITY));
    let polys = [
        &m.intersections,
        &m.drivable,
        &m.walkways,
        &m.carparks,
        &m.crosswalk_polygons,
        &m.lane_group_connectors,
        &m.lane_groups,
        &m.road_segments,
        &m.dividers,
    ];
    for p in polys.into_iter().flatten() {
        shape::grow(&mut b, p);
    }
    for l in &m.lanes {
        shape::grow(&mut b, &l.centre.points);
    }
    for c in &m.connectors {
        shape::grow(&mut b, &c.path.points);
    }
    if b.0.x > b.1.x {
        return (glam::DVec2::ZERO, glam::DVec2::ZERO);
    }
    b
}
