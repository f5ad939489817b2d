//! The `roundabout` template. In: the road (`radius`). Out: the `Map`.
//!
//! A counter-clockwise ring (right-hand traffic) centred on the origin with `lanes` circulating
//! lanes around a central island. `radius` is the radius of the ring's middle; the ring grows when
//! the arms need more room (its outer kerb stays at least 3 m beyond an arm's half width and at
//! least sqrt(2) x the arm's half width with sidewalks, so neighbouring arms never overlap, and the
//! arms' mouths stay 2 m clear of the island). Arms north/east/south/west start at the outer kerb
//! (`J = sqrt(R_out^2 - half_width^2)` from the origin, where an arm's corners touch the ring) with
//! a yield line 1 m out (behind the crosswalk when crosswalks are on). The junction area is the
//! ring (an annulus, as 16 sector polygons); the island is not drivable.
//!
//! Connectors: `ARM.in[k]` enters ring lane k (k = 1 innermost), circulates, and leaves to the
//! out-lane k of the exit arm: `right` = first exit, `straight` = second, `left` = third,
//! `u_turn` = all the way round. A right turn too short to use the ring becomes a direct slip.

use super::arm::{ArmSpec, CROSSWALK, SIDEWALK, add_arm};
use super::junction::ARMS;
use super::map::{Connector, Map};
use super::shape::{arc, cubic, dashes, turn};
use crate::check::scenario::{Road, Turn};
use crate::geom::{Polygon, Polyline};
use glam::DVec2;
use std::f64::consts::{FRAC_PI_2, TAU};

const SECTORS: usize = 16;
/// Extra angle past the point where a lane meets the ring before a connector joins its ring lane,
/// so the entry and exit curves are gentle: at most this many radians, and on large rings about
/// `EASE_M` metres of ring.
const EASE: f64 = 0.35;
const EASE_M: f64 = 12.0;
/// Length of the paved entry between an arm's mouth and the ring (m).
const FLARE: f64 = 8.0;

pub(crate) fn build(road: &Road) -> Map {
    let (n, w) = (f64::from(road.lanes), road.lane_width);
    let h = road.median / 2.0 + n * w + road.shoulder;
    // Neighbouring arms are a quarter turn apart: they stay apart (sidewalks included) only if
    // each arm's mouth, where its corners touch the ring, lies at least the arm's outer half
    // width from the centre, which takes a ring of radius sqrt(2) x that half width. A narrower
    // ring let the arms overlap, and one arm's lane dividers ran across the next arm's lanes.
    let h_walk = h + if road.sidewalks { SIDEWALK } else { 0.0 };
    let mut r_out = (road.radius + n * w / 2.0).max(h + 3.0).max(std::f64::consts::SQRT_2 * h_walk);
    while (r_out * r_out - h * h).sqrt() < r_out - n * w + 2.0 {
        r_out += 0.5;
    }
    let r_in = r_out - n * w;
    // Where an arm's corners touch the ring; the arm's lanes stop FLARE further out so that
    // entering traffic has room to swing onto the ring.
    let j0 = (r_out * r_out - h * h).sqrt();
    let j = j0 + FLARE;
    let stop = if road.crosswalks { 2.0 + CROSSWALK } else { 1.0 };
    let mut map = Map::default();
    let mut built = Vec::new();
    for &(arm, u) in &ARMS {
        let spec = ArmSpec {
            arm,
            axis: Polyline::new(vec![u * j, u * (j + stop + road.length)]),
            n_in: road.lanes,
            n_out: road.lanes,
            lane_width: w,
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
        built.push((u, add_arm(&mut map, &spec)));
    }

    // Entries widen toward the ring (half width `hw` where they meet it) so that the curves onto
    // and off the ring stay on paving; they never reach into the island.
    let mut hw = (h + FLARE).min(0.95 * r_out);
    while hw > h && (r_out * r_out - hw * hw).sqrt() < r_in + 0.5 {
        hw = (hw - 0.25).max(h);
    }
    let j_wide = (r_out * r_out - hw * hw).sqrt();
    for &(_, u) in &ARMS {
        let v = u.perp();
        let flare: Polygon = vec![u * j_wide - v * hw, u * j - v * h, u * j + v * h, u * j_wide + v * hw];
        map.intersections.push(flare.clone());
        map.drivable.push(flare.clone());
        map.lane_group_connectors.push(flare);
        if road.sidewalks {
            for side in [-1.0, 1.0] {
                let (a, b) = (v * side * h, v * side * (h + SIDEWALK));
                map.walkways.push(vec![u * j0 + a, u * j + a, u * j + b, u * j0 + b]);
            }
        }
    }
    for i in 0..SECTORS {
        let (a0, a1) = (TAU * i as f64 / SECTORS as f64, TAU * (i + 1) as f64 / SECTORS as f64);
        let mut sector: Polygon = arc(DVec2::ZERO, r_out, a0, a1);
        sector.extend(arc(DVec2::ZERO, r_in, a1, a0));
        map.intersections.push(sector.clone());
        map.drivable.push(sector.clone());
        map.lane_group_connectors.push(sector);
    }

    // Ring lane lines, broken where the arms come in.
    let gap = (h / r_out).min(1.0).asin() + 0.1;
    for q in 0..4 {
        let (a0, a1) = (q as f64 * FRAC_PI_2 + gap, (q + 1) as f64 * FRAC_PI_2 - gap);
        if a1 <= a0 {
            continue;
        }
        for k in 1..road.lanes {
            let r = r_in + f64::from(k) * w;
            let line = Polyline::new(arc(DVec2::ZERO, r, a0, a1));
            map.dividers.extend(dashes(&line, 0.0, line.length(), 0.0));
        }
        if road.sidewalks {
            let g = ((h + SIDEWALK) / (r_out + SIDEWALK)).min(1.0).asin();
            let (b0, b1) = (q as f64 * FRAC_PI_2 + g.min(gap), (q + 1) as f64 * FRAC_PI_2 - g.min(gap));
            let mut walk = arc(DVec2::ZERO, r_out + SIDEWALK, b0, b1);
            walk.extend(arc(DVec2::ZERO, r_out, b1, b0));
            map.walkways.push(walk);
        }
    }

    let ease = EASE.min(EASE_M / (r_out - n * w / 2.0));
    for (q, (u, from)) in built.iter().enumerate() {
        let phi = u.to_angle();
        for (quarters, turn_kind) in [(1, Turn::Right), (2, Turn::Straight), (3, Turn::Left), (4, Turn::UTurn)] {
            let (v, to) = &built[(q + quarters) % 4];
            for (k, &fi) in from.ins.iter().enumerate() {
                let Some(&ti) = to.outs.get(k).or(to.outs.last()) else { continue };
                let r = r_in + (k as f64 + 0.5) * w;
                let p0 = *map.lanes[fi].centre.points.last().expect("lanes have two or more points");
                let p3 = map.lanes[ti].centre.points[0];
                let th_in = phi + p0.perp_dot(*u).abs().atan2(j) + ease;
                let th_out = phi + quarters as f64 * FRAC_PI_2 - p3.perp_dot(*v).abs().atan2(j) - ease;
                let pts = if th_out - th_in < 0.1 {
                    let k = p0.distance(p3) / 3.0;
                    let hull = vec![p0, p0 - *u * k, p3 - *v * k, p3];
                    // A slip cuts the corner between two arms, which a ring large enough to keep
                    // the arms apart leaves unpaved: pave the Bezier's control hull, which holds
                    // the whole curve.
                    map.intersections.push(hull.clone());
                    map.drivable.push(hull.clone());
                    map.lane_group_connectors.push(hull);
                    cubic(p0, p0 - *u * k, p3 - *v * k, p3)
                } else {
                    let (q_in, q_out) = (DVec2::from_angle(th_in) * r, DVec2::from_angle(th_out) * r);
                    let (t_in, t_out) = (DVec2::from_angle(th_in).perp(), DVec2::from_angle(th_out).perp());
                    // Corner-based handles keep each easing curve inside the triangle of its two
                    // tangents, so it never cuts into the island.
                    let mut pts = turn(p0, -*u, q_in, t_in);
                    pts.pop();
                    pts.extend(arc(DVec2::ZERO, r, th_in, th_out));
                    pts.pop();
                    pts.extend(turn(q_out, t_out, p3, *v));
                    pts
                };
                let path = Polyline::new(pts);
                map.connectors.push(Connector { from: fi, to: ti, turn: turn_kind, path });
            }
        }
    }
    map
}
