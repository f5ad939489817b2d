//! The `roundabout` template. In: the road (`radius`). Out: the `Map`.
//!
//! A counter-clockwise ring (right-hand traffic) centred on the origin with `lanes` circulating
//! lanes around a central island. `radius` is the radius of the ring's middle; the ring grows when
//! the arms need more room (its outer kerb stays at least 3 m beyond an arm's half width and at
//! least sqrt(2) x the arm's half width with sidewalks, so neighbouring arms never overlap, and the
//! arms' mouths stay 2 m clear of the island). Arms north/east/south/west start at the outer kerb
//! (`J = sqrt(R_out^2 - half_width^2)` from the origin, where an arm's corners touch the ring) with
//! a yield line 1 m out (behind the crosswalk when crosswalks are on). The junction area is the
//! ring (an annulus, as 16 sector polygons); the island is not drivable. With sidewalks, each
//! corner between two arms is one walkway along the flares' outer kerbs and the ring's
//! (`corner_walkways`), never on paving.
//!
//! Connectors: `ARM.in[k]` enters ring lane k (k = 1 innermost), circulates, and leaves to the
//! out-lane k of the exit arm: `right` = first exit, `straight` = second, `left` = third,
//! `u_turn` = all the way round. A right turn too short to use the ring becomes a direct slip.

use super::arm::{ArmSpec, CROSSWALK, SIDEWALK, add_arm};
use super::junction::ARMS;
use super::map::{Connector, Map};
use super::shape::{arc, area2, cubic, dashes, overlaps_convex, subtract_convex, turn};
use crate::check::scenario::{Road, Turn};
use crate::geom::{Polygon, Polyline};
use glam::DVec2;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, TAU};

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
    let mut flares = Vec::new();
    for &(_, u) in &ARMS {
        let v = u.perp();
        let flare: Polygon = vec![u * j_wide - v * hw, u * j - v * h, u * j + v * h, u * j_wide + v * hw];
        map.intersections.push(flare.clone());
        map.drivable.push(flare.clone());
        map.lane_group_connectors.push(flare.clone());
        flares.push(flare);
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
    }

    let mut slips = Vec::new();
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
                    map.lane_group_connectors.push(hull.clone());
                    slips.push(hull);
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
    if road.sidewalks {
        corner_walkways(&mut map, &flares, &slips, r_out, (j_wide, hw), (j, h));
    }
    map
}

/// The walkway round each corner between two neighbouring arms, from one arm's sidewalk to the
/// next one's: along the outer kerb of the first arm's flare, round the ring's outer kerb, and
/// back along the second arm's flare. A walkway at the arm's kerb would lie on the flare, which
/// widens toward the ring beneath it.
///
/// Each flare kerb runs from the arm's kerb corner `B` (station `j`, half width `h`) to the ring
/// at `A` (station `j_wide`, half width `hw`); its walkway is the band `SIDEWALK` wide beyond it,
/// from `B` to `A*`, the last point where the kerb leaves the ring's disk. A band beyond a line
/// that leaves a disk never reaches into the disk, and the bends at `B` (into the arm's kerb) and
/// at `A*` (onto the ring) turn away from the walkway side, so neighbouring bands overlap
/// there and leave no gap. The ring's sidewalk covers the angles between the two `A*`, where no
/// flare reaches (a flare's polar angles peak at `A*`). On a ring too small for that range the
/// two flares meet beyond the ring, and each band loses what lies on the other flare.
///
/// A paved right-turn slip (`slips`: its Bezier hull, whose last edge is the chord facing away
/// from the ring) can reach beyond the ring's kerb in the corner: the walkway then also runs in a
/// band beyond that chord, and every band and the ring's sidewalk lose what lies on paving
/// (flares, slips, the arms' roads).
fn corner_walkways(
    map: &mut Map,
    flares: &[Polygon],
    slips: &[Polygon],
    r_out: f64,
    (j_wide, hw): (f64, f64),
    (j, h): (f64, f64),
) {
    let first = map.walkways.len();
    // In a corner's own frame: the first arm along x, the next along y.
    let (a, b) = (DVec2::new(j_wide, hw), DVec2::new(j, h));
    let d = b - a;
    // The larger root of |a + t d| = r_out (t = 0 is `a` itself, on the ring).
    let t_exit = (-2.0 * a.dot(d) / d.length_squared()).clamp(0.0, 1.0);
    let a_exit = a + d * t_exit;
    // Away from the first arm's axis.
    let n = DVec2::new(-d.y, d.x).normalize();
    let band = [b, a_exit, a_exit + n * SIDEWALK, b + n * SIDEWALK];
    let theta = a_exit.y.atan2(a_exit.x);
    let bevel = [a_exit, a_exit + n * SIDEWALK, a_exit * ((r_out + SIDEWALK) / a_exit.length())];
    let mirror = |p: DVec2| DVec2::new(p.y, p.x);
    // The arms' own paving too: a slip's band starts on its arm.
    let arms = map.road_segments.clone();
    let paving: Vec<&Polygon> = flares.iter().chain(slips).chain(&arms).collect();
    let minus = |pieces: Vec<Polygon>, holes: &[&Polygon]| {
        holes.iter().fold(pieces, |pieces, hole| pieces.iter().flat_map(|p| subtract_convex(p, hole)).collect())
    };
    for &(_, u) in &ARMS {
        let v = u.perp();
        let world = |p: DVec2| u * p.x + v * p.y;
        let mut bands = vec![band.map(world).to_vec(), band.map(|p| world(mirror(p))).to_vec()];
        if theta < FRAC_PI_4 {
            // Bevel the notch between a band's end and the ring's sidewalk: both leave `A*`
            // outward (the band along `n`, the ring radially), and so does every direction between.
            bands.push(bevel.map(world).to_vec());
            bands.push(bevel.map(|p| world(mirror(p))).to_vec());
        }
        map.walkways.extend(minus(bands, &paving));
        // The ring's sidewalk between the flares, unless they (nearly) meet on the ring: a wedge
        // a few centimetres wide would be cut to slivers, and a zero-area one would survive every
        // cut (it overlaps nothing) yet be drawn as a 1-px line across the paving.
        if (FRAC_PI_2 - 2.0 * theta) * (r_out + SIDEWALK) > 0.05 {
            let phi = u.to_angle();
            let (a0, a1) = (phi + theta, phi + FRAC_PI_2 - theta);
            let mut ring = arc(DVec2::ZERO, r_out + SIDEWALK, a0, a1);
            ring.extend(arc(DVec2::ZERO, r_out, a1, a0));
            if !slips.iter().any(|s| overlaps_convex(&ring, s)) {
                map.walkways.push(ring);
            } else {
                // Convex pieces, so that a slip can be cut out of them.
                let outer = arc(DVec2::ZERO, r_out + SIDEWALK, a0, a1);
                let inner = |p: DVec2| p * (r_out / (r_out + SIDEWALK));
                let quads = outer.windows(2).map(|w| vec![inner(w[0]), inner(w[1]), w[1], w[0]]).collect();
                map.walkways.extend(minus(quads, &paving));
            }
        }
    }
    if !slips.is_empty() {
        // The ring's disk as a circumscribed polygon (it may shave a centimetre off a band).
        const SIDES: usize = 128;
        let step = TAU / SIDES as f64;
        let disk: Polygon =
            (0..SIDES).map(|i| DVec2::from_angle(step * i as f64) * (r_out / (step / 2.0).cos())).collect();
        let mut holes = paving.clone();
        holes.push(&disk);
        for slip in slips {
            let (p3, p0) = (slip[3], slip[0]);
            let mut n = (p0 - p3).perp().normalize();
            if n.dot(p0 + p3) < 0.0 {
                n = -n;
            }
            map.walkways.extend(minus(vec![vec![p3, p0, p0 + n * SIDEWALK, p3 + n * SIDEWALK]], &holes));
        }
    }
    // Cuts leave pieces of any shape; one without area is drawn as a line (fillPoly) over paving.
    let mut added = map.walkways.split_off(first);
    added.retain(|p| area2(p).abs() >= 2e-4);
    map.walkways.extend(added);
}
