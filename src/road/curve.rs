//! The `curve` template. In: the road (`radius`, `angle`, `length` of each straight tangent).
//! Out: the `Map`.
//!
//! The centre line is an arc of `radius` turning left (counter-clockwise) for eastbound traffic,
//! with deflection `angle`; the arc's midpoint sits on the origin heading +x, its centre at
//! (0, radius), and a straight tangent of `length` continues each end. So the road opens toward
//! +y, and with a 180 deg deflection both tangents run north. Lanes on the inside of the bend need
//! `radius` larger than the road's half width (the checker's minimum radius of 20 m covers the
//! usual cross-sections).

use super::shape::STEP;
use crate::check::scenario::Road;
use crate::geom::Polyline;
use glam::DVec2;

pub(crate) fn build(road: &Road) -> super::Map {
    super::straight::two_arm(road, axis(road, -1.0), axis(road, 1.0))
}

/// From the origin along the arc toward one end (`side` -1 west, +1 east), then the tangent.
fn axis(road: &Road, side: f64) -> Polyline {
    let (r, half) = (road.radius, road.angle / 2.0);
    // At most STEP apart along the arc, and at most 1 degree of turn between vertices.
    let dphi = (STEP / r).min(1f64.to_radians());
    let n = ((half / dphi).ceil() as usize).max(1);
    let at = |phi: f64| DVec2::new(r * phi.sin(), r * (1.0 - phi.cos()));
    let mut pts: Vec<DVec2> = (0..=n).map(|i| at(side * half * i as f64 / n as f64)).collect();
    // A first vertex a hair from the origin: offset lines take their first normal from the first
    // segment, and this makes it the true normal at the origin, so both arms (and their crosswalk)
    // meet without a wedge-shaped gap.
    pts.insert(1, at(side * dphi * 1e-6));
    let end = at(side * half);
    pts.push(end + DVec2::from_angle(side * half) * side * road.length);
    Polyline::new(pts)
}
