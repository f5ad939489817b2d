//! The `merge` template. In: the road. Out: the `Map`.
//!
//! A one-way carriageway of `lanes` lanes driving east (+x), with its left edge (the centre-line
//! side, where `median` is half-paved) at y = -median/2, so lane k sits at
//! y = -(median/2 + (k-0.5) lane_width) exactly like the eastbound lanes of `straight`. `main.in`
//! runs from x = -40 - length to the merge area, `main.out` from the merge area to
//! x = 40 + length; lane k continues as lane k through the merge area (straight connectors).
//!
//! The merge area (`junction`) spans x in [-40, 40]: the ramp's single lane becomes an
//! acceleration lane right of `main[lanes]` up to x = 10, then tapers into it by x = 40 (its
//! connector is tagged `straight`). `ramp.in[1]` (length `length`) comes from the south-west: a
//! straight approach at 10 deg, then a right-hand bend of radius 150 m onto the acceleration
//! lane's line at x = -40. Sidewalks, when on, run along the carriageway's left (north) edge and
//! the ramp's right edge; a merge has no crosswalks.

use super::arm::{ArmSpec, SIDEWALK, add_arm};
use super::map::{Connector, Map};
use super::shape::{DASH, GAP, STEP, dashes, segment};
use crate::check::scenario::{Arm, Road, Turn};
use crate::geom::{Polygon, Polyline};
use glam::DVec2;

/// Half the merge area's length (m).
const HALF: f64 = 40.0;
/// Length of the taper at the merge area's end (m).
const TAPER: f64 = 30.0;
const RAMP_RADIUS: f64 = 150.0;
const RAMP_ANGLE_DEG: f64 = 10.0;

pub(crate) fn build(road: &Road) -> Map {
    let (n, w, m, sh) = (f64::from(road.lanes), road.lane_width, road.median, road.shoulder);
    let mut map = Map::default();
    let spec = |arm, axis, n_in, n_out, median, inner| ArmSpec {
        arm,
        axis,
        n_in,
        n_out,
        lane_width: w,
        median,
        shoulder: sh,
        speed_limit: road.speed_limit,
        stop_at: None,
        crosswalk_at: None,
        junction: true,
        markings_from: 0.0,
        sidewalks: road.sidewalks,
        sidewalk_inner: inner,
    };
    let main_in = add_arm(
        &mut map,
        &spec(
            Arm::Main,
            Polyline::new(vec![DVec2::new(-HALF, 0.0), DVec2::new(-HALF - road.length, 0.0)]),
            road.lanes,
            0,
            m,
            true,
        ),
    );
    let main_out = add_arm(
        &mut map,
        &spec(
            Arm::Main,
            Polyline::new(vec![DVec2::new(HALF, 0.0), DVec2::new(HALF + road.length, 0.0)]),
            0,
            road.lanes,
            m,
            true,
        ),
    );
    let ramp = add_arm(&mut map, &spec(Arm::Ramp, ramp_axis(road, -(m / 2.0 + n * w)), 1, 0, 0.0, false));

    // Merge area: main lanes, the acceleration lane and the shoulder, tapering at the end.
    let edge = -(m / 2.0 + n * w + sh);
    let accel_edge = edge - w;
    let area: Polygon = vec![
        DVec2::new(-HALF, 0.0),
        DVec2::new(-HALF, accel_edge),
        DVec2::new(HALF - TAPER, accel_edge),
        DVec2::new(HALF, edge),
        DVec2::new(HALF, 0.0),
    ];
    map.intersections.push(area.clone());
    map.drivable.push(area.clone());
    map.lane_group_connectors.push(area);
    if road.sidewalks {
        map.walkways.push(vec![
            DVec2::new(-HALF, 0.0),
            DVec2::new(HALF, 0.0),
            DVec2::new(HALF, SIDEWALK),
            DVec2::new(-HALF, SIDEWALK),
        ]);
    }
    let through = Polyline::new(vec![DVec2::new(-HALF, 0.0), DVec2::new(HALF, 0.0)]);
    for k in 1..road.lanes {
        map.dividers.extend(dashes(&through, 0.0, 2.0 * HALF, -(m / 2.0 + f64::from(k) * w)));
    }
    let accel_line = -(m / 2.0 + n * w);
    let mut x = -HALF;
    while x < HALF - TAPER - 0.5 {
        map.dividers.push(vec![DVec2::new(x, accel_line), DVec2::new((x + DASH).min(HALF - TAPER), accel_line)]);
        x += DASH + GAP;
    }
    map.dividers.push(vec![DVec2::new(-HALF, -m / 2.0), DVec2::new(HALF, -m / 2.0)]);

    let end = |l: usize| *map.lanes[l].centre.points.last().expect("lanes have two or more points");
    let start = |l: usize| map.lanes[l].centre.points[0];
    for (&fi, &ti) in main_in.ins.iter().zip(&main_out.outs) {
        let path = Polyline::new(segment(end(fi), start(ti)));
        map.connectors.push(Connector { from: fi, to: ti, turn: Turn::Straight, path });
    }
    if let (Some(&fi), Some(&ti)) = (ramp.ins.first(), main_out.outs.last()) {
        let (p0, p3) = (end(fi), start(ti));
        let mut pts = segment(p0, DVec2::new(HALF - TAPER, p0.y));
        let steps = (TAPER / STEP).ceil() as usize;
        // Smoothstep across the taper: heading is continuous at both ends.
        pts.extend((1..=steps).map(|i| {
            let t = i as f64 / steps as f64;
            let e = t * t * (3.0 - 2.0 * t);
            DVec2::new(HALF - TAPER + TAPER * t, p0.y + (p3.y - p0.y) * e)
        }));
        if let Some(last) = pts.last_mut() {
            *last = p3;
        }
        map.connectors.push(Connector { from: fi, to: ti, turn: Turn::Straight, path: Polyline::new(pts) });
    }
    map
}

/// The ramp's axis from its mouth at (-HALF, y0) outward: heading west, bending left (toward the
/// south-west) by `RAMP_ANGLE_DEG` on `RAMP_RADIUS`, then straight; `length` in all.
fn ramp_axis(road: &Road, y0: f64) -> Polyline {
    let beta = RAMP_ANGLE_DEG.to_radians();
    let arc_len = (RAMP_RADIUS * beta).min(road.length);
    let turned = arc_len / RAMP_RADIUS;
    let start = DVec2::new(-HALF, y0);
    let c = start - DVec2::new(0.0, RAMP_RADIUS);
    let steps = ((arc_len / STEP).ceil() as usize).max(1);
    let at = |psi: f64| c + RAMP_RADIUS * DVec2::new(psi.sin(), -psi.cos());
    let pi = std::f64::consts::PI;
    let mut pts: Vec<DVec2> = (0..=steps).map(|i| at(pi + turned * i as f64 / steps as f64)).collect();
    let rest = road.length - arc_len;
    if rest > 1e-6 {
        let end = at(pi + turned);
        pts.push(end + DVec2::from_angle(pi + turned) * rest);
    }
    Polyline::new(pts)
}
