//! Crash staging geometry: where the at-fault box must be, relative to the struck box, for its
//! striking face to meet the requested side; the choice of impact and departure times from the
//! first pass; and measurements of a contact (overlap centroid, depth, which side).

use crate::check::scenario::{Impact, Point};
use crate::geom::{Obb, wrap_angle};
use crate::place::Pose;
use crate::rollout::Tracks;
use crate::rollout::agent::{Actor, Conf, Drive, Near};
use crate::rollout::path::Hermite;
use glam::DVec2;

/// Intercepts may accelerate harder than comfortable driving (the driver is at fault), by this
/// factor on the class limits.
pub const STRIKE_ACCEL: f64 = 1.6;
pub const STRIKE_YAW: f64 = 1.5;
/// Heading of a sideswiping agent into the struck one, rad.
const SWIPE_ANGLE: f64 = 0.15;
/// Largest angle off a struck object's face normal that an at-fault agent approaches at, rad.
const OBLIQUE: f64 = 0.6;
/// The same for an `angle` strike: a vehicle at speed that starts alongside its target (a lane
/// change, a merge) cannot turn square onto its side within its turning radius; it meets it at
/// 30 degrees or more, leading with a front corner.
const ANGLE_OBLIQUE: f64 = 1.05;

pub(crate) struct Plan {
    pub struck: usize,
    /// At-fault centre and yaw at the impact frame, in the struck agent's frame.
    pub rel_pos: DVec2,
    pub rel_yaw: f64,
    pub t_depart: f64,
    pub t_impact: f64,
    pub frame: usize,
    /// Planned penetration, m.
    pub delta: f64,
}

/// World pose of a point given in the frame of `base`.
pub(crate) fn compose(base: Pose, rel: DVec2, rel_yaw: f64) -> (DVec2, f64) {
    compose_turned(base, DVec2::from_angle(base.yaw), rel, rel_yaw)
}

/// `compose` given `DVec2::from_angle(base.yaw)` as `rot`.
fn compose_turned(base: Pose, rot: DVec2, rel: DVec2, rel_yaw: f64) -> (DVec2, f64) {
    let p = DVec2::new(base.x, base.y) + rel.rotate(rot);
    (p, wrap_angle(base.yaw + rel_yaw))
}

fn point_signs(p: Point) -> (f64, f64) {
    match p {
        Point::Front => (1.0, 0.0),
        Point::Rear => (-1.0, 0.0),
        Point::Left => (0.0, 1.0),
        Point::Right => (0.0, -1.0),
        Point::FrontLeft => (1.0, 1.0),
        Point::FrontRight => (1.0, -1.0),
        Point::RearLeft => (-1.0, 1.0),
        Point::RearRight => (-1.0, -1.0),
    }
}

/// The at-fault pose at impact in the struck frame, and the planned penetration.
/// `struck` and `af` are (length, width); `af_rel` is the at-fault's initial position and yaw in
/// the struck frame, which decides what the request leaves open (which face of a corner an
/// object is hit on, which side a sideswipe comes from, same or opposite direction).
/// `drift` (sideswipes only) is how far the leading corner slides along the struck side, in its
/// +x, between first touch and the planned penetration; first touch and the final overlap are
/// centred on the target between them.
pub(crate) fn relative(
    impact: Impact,
    point: Point,
    struck: (f64, f64),
    af: (f64, f64),
    af_rel: (DVec2, f64),
    drift: f64,
) -> (DVec2, f64, f64) {
    let (sx, sy) = (struck.0 / 2.0, struck.1 / 2.0);
    let (al, aw) = (af.0 / 2.0, af.1 / 2.0);
    let (mut px, mut py) = point_signs(point);
    let delta = if struck.0.min(struck.1) < 1.2 { 0.12 } else { 0.25 };
    if impact == Impact::Sideswipe {
        if py == 0.0 {
            py = if af_rel.0.y >= 0.0 { 1.0 } else { -1.0 };
        }
        let same = af_rel.1.cos() >= 0.0;
        let phi = if same { -py * SWIPE_ANGLE } else { std::f64::consts::PI + py * SWIPE_ANGLE };
        // The at-fault side facing the struck box, and its leading corner.
        let sa = if phi.cos() * -py > 0.0 { 1.0 } else { -1.0 };
        let corner_local = DVec2::new(al, sa * aw);
        // The overlap is a sliver running back from that corner; put its centroid on the target.
        let sliver = delta / SWIPE_ANGLE.tan();
        let x_t = px * 0.65 * sx;
        let drift = drift.clamp(-1.5, 1.5);
        let corner = DVec2::new(x_t + 0.5 * (phi.cos() * sliver / 3.0 + drift), py * (sy - delta));
        return (corner - corner_local.rotate(DVec2::from_angle(phi)), phi, delta);
    }
    // Front-face strikes: pick the struck face (outward normal n, half length h along tangent
    // t, depth from the centre) and where along it (sigma: -1, 0, +1 toward a corner).
    match impact {
        Impact::RearEnd => (px, py) = (-1.0, py),
        Impact::HeadOn => (px, py) = (1.0, py),
        _ => {}
    }
    let (n, h, depth, t, sigma) = if px != 0.0 && py != 0.0 {
        let side_face = match impact {
            Impact::RearEnd | Impact::HeadOn => false,
            Impact::Angle => true,
            // Objects and pedestrians: the face the at-fault agent approaches most squarely.
            _ => {
                let dir = DVec2::from_angle(af_rel.1);
                dir.dot(DVec2::new(0.0, -py)) > dir.dot(DVec2::new(-px, 0.0))
            }
        };
        if side_face {
            (DVec2::new(0.0, py), sx, sy, DVec2::X, px)
        } else {
            (DVec2::new(px, 0.0), sy, sx, DVec2::Y, py)
        }
    } else if py != 0.0 {
        (DVec2::new(0.0, py), sx, sy, DVec2::X, 0.0)
    } else {
        (DVec2::new(px, 0.0), sy, sx, DVec2::Y, 0.0)
    };
    let normal_yaw = (-n).y.atan2((-n).x);
    let oblique = if impact == Impact::Angle { ANGLE_OBLIQUE } else { OBLIQUE };
    let beta = wrap_angle(af_rel.1 - normal_yaw).clamp(-oblique, oblique);
    if matches!(impact, Impact::Object | Impact::Pedestrian | Impact::Angle) && beta.abs() > 0.05 {
        // A driver who runs into a thing keeps roughly its own course: approach up to 35 deg off
        // the face normal, leading with the front corner nearest the face.
        let phi = normal_yaw + beta;
        let c_t = sigma * 0.7 * h;
        let target = n * depth + t * c_t - n * delta;
        let rot = DVec2::from_angle(phi);
        let corner = [DVec2::new(al, aw), DVec2::new(al, -aw)]
            .into_iter()
            .min_by(|a, b| a.rotate(rot).dot(n).total_cmp(&b.rotate(rot).dot(n)))
            .unwrap_or(DVec2::new(al, 0.0));
        return (target - corner.rotate(rot), phi, delta);
    }
    let phi = normal_yaw;
    // Toward a corner, overlap only the outer 60% of the half face (or the whole at-fault face
    // when it is narrower), so the overlap's centroid stays in the corner's third.
    let k = 0.6 * h;
    let c = if sigma != 0.0 { sigma * (h - k.min(2.0 * aw) + aw) } else { 0.0 };
    let face = n * depth + t * c;
    (face + n * (al - delta), phi, delta)
}

/// The passer's pose at the pass in the passed frame: level with it, parallel (same direction
/// or the other way, as it starts), its side `gap` from the passed box's `point` side. No
/// penetration is planned (the third value, as `plan::relative` returns it).
pub(crate) fn alongside(
    point: Point,
    passed: (f64, f64),
    passer: (f64, f64),
    start_yaw: f64,
    gap: f64,
) -> (DVec2, f64, f64) {
    let side = if point == Point::Right { -1.0 } else { 1.0 };
    let yaw = if start_yaw.cos() >= 0.0 { 0.0 } else { std::f64::consts::PI };
    (DVec2::new(0.0, side * (passed.1 / 2.0 + gap + passer.1 / 2.0)), yaw, 0.0)
}

/// The passer's pose at a `ttc` pass in the passed frame: in line behind it, same direction,
/// its front `gap` behind the passed box's rear. No penetration is planned.
pub(crate) fn behind(passed: (f64, f64), passer: (f64, f64), gap: f64) -> (DVec2, f64, f64) {
    (DVec2::new(-(passed.0 / 2.0 + gap + passer.0 / 2.0), 0.0), 0.0, 0.0)
}

/// The side of `passed` the passer starts on, where the file leaves it open.
pub(crate) fn start_side(passer: DVec2, passed: DVec2, passed_yaw: f64) -> Point {
    let rel = (passer - passed).rotate(DVec2::from_angle(-passed_yaw));
    if rel.y >= 0.0 { Point::Left } else { Point::Right }
}

/// A latched contact shallower than this is a graze, not the crash asked for, m (a plan aims
/// at 0.12 to 0.25 m): a sideswipe at 23 m/s that latched 2.5 mm of overlap was labelled a crash.
pub const MIN_DEPTH: f64 = 0.05;

/// How far from its requested time a staged impact may land, s.
pub(crate) const WINDOW_S: f64 = 1.5;

/// The impact time a conflict asks for: its `at`, else mid-clip, within the clip's frames.
pub(crate) fn requested_time(c: &crate::check::scenario::Conflict, dt: f64, frames: usize, duration: f64) -> f64 {
    let last = frames.saturating_sub(1);
    c.at.unwrap_or(duration / 2.0).clamp(2.0 * dt, (last as f64 * dt).max(2.0 * dt))
}

/// The plan for conflict `k` from pass 1's tracks: of departure and impact frames within
/// `WINDOW_S` of the requested time, the one of least cost, its impact more than `AVOID_S` from
/// each time in `avoid` (impact times of plans that failed).
pub(crate) fn choose(k: &Conf, actors: &[Actor], p1: &Tracks, dt: f64, duration: f64, avoid: &[f64]) -> Option<Plan> {
    let (af, st) = (&actors[k.af], &actors[k.st]);
    if !matches!(af.drive, Drive::Mover) || p1.frames < 4 {
        return None;
    }
    let pa = &p1.poses[k.af];
    let ps = &p1.poses[k.st];
    let to_struck = |a: Pose, s: Pose| {
        let rel = (DVec2::new(a.x, a.y) - DVec2::new(s.x, s.y)).rotate(DVec2::from_angle(-s.yaw));
        (rel, wrap_angle(a.yaw - s.yaw))
    };
    let sizes = ((2.0 * st.hl, 2.0 * st.hw), (2.0 * af.hl, 2.0 * af.hw));
    let start = to_struck(pa[0], ps[0]);
    let ttc = match k.near {
        Some(Near::Ttc(t)) => Some(t),
        _ => None,
    };
    let (rel_pos0, rel_yaw, delta0) = match k.near {
        Some(Near::Gap(gap)) => alongside(k.c.point, sizes.0, sizes.1, start.1, gap),
        Some(Near::Ttc(_)) => behind(sizes.0, sizes.1, 0.0),
        Some(Near::Across(_)) => return None,
        None => relative(k.c.impact, k.c.point, sizes.0, sizes.1, start, 0.0),
    };
    let swipe = k.c.impact == Impact::Sideswipe && k.near.is_none();
    // First frame pass 1 already has them touching: the intercept must leave before it.
    let natural = (0..p1.frames).find(|&f| {
        let a = Obb { center: DVec2::new(pa[f].x, pa[f].y), yaw: pa[f].yaw, length: 2.0 * af.hl, width: 2.0 * af.hw };
        let b = Obb { center: DVec2::new(ps[f].x, ps[f].y), yaw: ps[f].yaw, length: 2.0 * st.hl, width: 2.0 * st.hw };
        a.overlaps(&b)
    });
    let last = p1.frames - 1;
    let t_req = requested_time(&k.c, dt, p1.frames, duration);
    let lo = ((t_req - WINDOW_S) / dt).round().max(2.0) as usize;
    let hi = (((t_req + WINDOW_S) / dt).round() as usize).min(last);
    let lim = af.lim;
    // Some 150 candidates share a few angles: each sine and cosine is taken once (the same
    // calls on the same arguments, so the same bits), the at-fault heading's per frame.
    let (rel_cos, rel_sin) = (rel_yaw.cos(), rel_yaw.sin());
    let mut af_dirs: Vec<Option<DVec2>> = vec![None; pa.len()];
    let mut per_frame: Vec<Option<(DVec2, DVec2, DVec2)>> = vec![None; ps.len()];
    // The candidates, in the order the cost ranks ties in (by frame of impact, then lead time):
    // those whose departure frame leaves at least three frames to the impact.
    let cands: Vec<(usize, f64)> = (lo..ps.len().min(hi + 1))
        .flat_map(|fi| TAUS.iter().map(move |&tau| (fi, tau)))
        .filter(|&(fi, tau)| ((fi as f64 * dt - tau) / dt).round().max(0.0) as usize + 3 <= fi)
        .filter(|&(fi, _)| avoid.iter().all(|&t| (fi as f64 * dt - t).abs() > AVOID_S))
        .collect();
    // Candidate `c`'s cost and plan, unless `beaten` says its lower bound already loses.
    let mut cost_of = |c: usize, beaten: &dyn Fn(f64) -> bool| -> Option<(f64, Plan)> {
        let (fi, tau) = cands[c];
        let struck_at = ps[fi];
        let t_imp = fi as f64 * dt;
        // Per frame of impact, once for its lead times.
        let (struck_dir, g0, struck_v) = *per_frame[fi].get_or_insert_with(|| {
            let struck_dir = DVec2::from_angle(struck_at.yaw);
            let (g0, _) = compose_turned(struck_at, struck_dir, rel_pos0, rel_yaw);
            (struck_dir, g0, struck_dir * p1.speeds[k.st][fi])
        });
        {
            let fd = ((t_imp - tau) / dt).round().max(0.0) as usize;
            let tau = (fi - fd) as f64 * dt;
            let s = pa[fd];
            let v = p1.speeds[k.af][fd];
            let mut v_end0 = 2.0 * DVec2::new(s.x, s.y).distance(g0) / tau - v;
            // A `ttc` pass: the gap behind is the closing speed times the time, and the closing
            // speed the approach's end speed, which the gap shortens. On a straight approach
            // (distance D to the gap-0 pose) v_end = 2 (D - ttc (v_end - v_st)) / tau - v.
            let mut rel_pos0 = rel_pos0;
            if let Some(ttc) = ttc {
                let v_st = p1.speeds[k.st][fi];
                let v_end =
                    (2.0 * (DVec2::new(s.x, s.y).distance(g0) + ttc * v_st) / tau - v) / (1.0 + 2.0 * ttc / tau);
                rel_pos0 = behind(sizes.0, sizes.1, ttc * (v_end - v_st).max(0.0)).0;
                let (g, _) = compose_turned(struck_at, struck_dir, rel_pos0, rel_yaw);
                v_end0 = 2.0 * DVec2::new(s.x, s.y).distance(g) / tau - v;
            }
            // Sideswipes: where the corner first touches depends on the relative motion.
            let (v_rel, v_lat) = (v_end0 * rel_cos - p1.speeds[k.st][fi], (v_end0 * rel_sin).abs());
            let drift = if swipe { v_rel * delta0 / v_lat.max(0.3) } else { 0.0 };
            // Only a sideswipe's pose depends on the drift: any other is the one at drift 0.
            let (rel_pos, delta) = if swipe {
                let (p, _, d) = relative(k.c.impact, k.c.point, sizes.0, sizes.1, start, drift);
                (p, d)
            } else {
                (rel_pos0, delta0)
            };
            let (g, gyaw) = compose_turned(struck_at, struck_dir, rel_pos, rel_yaw);
            let goal_dir = DVec2::from_angle(gyaw);
            let af_dir = *af_dirs[fd].get_or_insert_with(|| DVec2::from_angle(s.yaw));
            let curve = Hermite::with_dirs(DVec2::new(s.x, s.y), af_dir, g, goal_dir);
            let len = curve.length();
            let acc = 2.0 * (len - v * tau) / (tau * tau);
            let v_end = v + acc * tau;
            // The cost below adds only terms that are not negative to its first two, and float
            // addition is monotone: this sum without the curvature's two terms is a lower bound
            // of the cost, bit for bit, and a candidate it puts at or above the best cannot
            // replace it (`cost < best`). The curvature (24 arctangents) is not computed then.
            if beaten(lower_bound(t_imp, t_req, acc, lim, v_end, drift, natural.is_some_and(|n| n <= fd))) {
                return None;
            }
            let k_curve = curve.max_curvature();
            let lat = v.max(v_end).powi(2) * k_curve;
            // Closing speed along the approach: the at-fault's motion into the struck box.
            let inward = if swipe {
                let side = if rel_pos.y >= 0.0 { -1.0 } else { 1.0 };
                DVec2::new(0.0, side).rotate(struck_dir)
            } else {
                goal_dir
            };
            let closing = (goal_dir * v_end - struck_v).dot(inward);
            let mut cost = 3.0 * (t_imp - t_req).abs() + acc.abs() / lim.accel + 2.0 * (lat - lim.lat_acc).max(0.0);
            if acc > STRIKE_ACCEL * lim.accel || acc < -lim.brake_max {
                cost += 20.0 + acc.abs();
            }
            if v_end < 1.0 {
                cost += 20.0;
            }
            // A curve tighter than the car can steer (turning radius, yaw rate) is followed on a
            // wider arc and misses: prefer departures that leave room to turn.
            let k_max = (1.0 / af.r_min).min(STRIKE_YAW * lim.yaw_rate / v.max(v_end).max(1.0));
            if k_curve > k_max {
                cost += 15.0 + 10.0 * (k_curve / k_max - 1.0);
            }
            if closing < 0.5 {
                cost += 10.0;
            }
            // A long slide along the struck side spreads the contact over more than one sector.
            cost += 3.0 * drift.abs();
            if natural.is_some_and(|n| n <= fd) {
                cost += 50.0;
            }
            let plan =
                Plan { struck: k.st, rel_pos, rel_yaw, t_depart: fd as f64 * dt, t_impact: t_imp, frame: fi, delta };
            Some((cost, plan))
        }
    };
    // The plan is the first candidate of least cost (the first one even at a NaN cost, which
    // nothing after it beats), whatever order they are costed in. Costed nearest the requested
    // time first, the best is soon low, and the lower bound passes over most of the rest
    // without their curvature: one loses where its bound is above the best's cost, or equal to
    // it and it comes later.
    let (mut best, mut best_c) = match cands.first() {
        Some(_) => (cost_of(0, &|_| false)?, 0),
        None => return None,
    };
    if best.0.is_nan() {
        return Some(best.1);
    }
    let mut order: Vec<usize> = (1..cands.len()).collect();
    order.sort_by(|&x, &y| {
        let off = |c: usize| (cands[c].0 as f64 * dt - t_req).abs();
        off(x).total_cmp(&off(y))
    });
    for c in order {
        let (b, bc) = (best.0, best_c);
        let Some((cost, plan)) = cost_of(c, &|lb| lb > b || (lb == b && c > bc)) else { continue };
        if cost < b || (cost == b && c < bc) {
            (best, best_c) = ((cost, plan), c);
        }
    }
    Some(best.1)
}

/// How far from an impact time that failed another plan's impact must be, s: a few frames on,
/// the same approach meets the same bystander.
pub(crate) const AVOID_S: f64 = 0.35;

/// Lead times between an intercept's departure and its impact that `choose` tries, s.
pub(crate) const TAUS: [f64; 5] = [1.5, 2.0, 2.5, 3.0, 4.0];

/// `choose`'s cost of a candidate without its curvature terms (the lateral acceleration above the
/// limit, the curve tighter than the car can steer) and its closing-speed term, all of them at
/// least 0: the same sums in the same order, so never above the cost.
fn lower_bound(
    t_imp: f64,
    t_req: f64,
    acc: f64,
    lim: crate::rollout::Limits,
    v_end: f64,
    drift: f64,
    natural: bool,
) -> f64 {
    let mut cost = 3.0 * (t_imp - t_req).abs() + acc.abs() / lim.accel + 0.0;
    if acc > STRIKE_ACCEL * lim.accel || acc < -lim.brake_max {
        cost += 20.0 + acc.abs();
    }
    if v_end < 1.0 {
        cost += 20.0;
    }
    cost += 3.0 * drift.abs();
    if natural {
        cost += 50.0;
    }
    cost
}

/// Penetration depth of two overlapping boxes: the smallest overlap over the separating axes.
pub(crate) fn depth(a: &Obb, b: &Obb) -> f64 {
    let (ca, cb) = (a.corners(), b.corners());
    let axes = [
        DVec2::from_angle(a.yaw),
        DVec2::from_angle(a.yaw).perp(),
        DVec2::from_angle(b.yaw),
        DVec2::from_angle(b.yaw).perp(),
    ];
    axes.iter()
        .map(|&ax| {
            let (a0, a1) = span(&ca, ax);
            let (b0, b1) = span(&cb, ax);
            (a1.min(b1) - a0.max(b0)).max(0.0)
        })
        .fold(f64::INFINITY, f64::min)
}

fn span(c: &[DVec2; 4], ax: DVec2) -> (f64, f64) {
    c.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.dot(ax)), hi.max(p.dot(ax))))
}

/// Centroid of the overlap of two boxes (world frame), `None` when they do not overlap.
pub fn contact_centroid(a: &Obb, b: &Obb) -> Option<DVec2> {
    // Sutherland-Hodgman: clip a's corners by each edge of b (both counter-clockwise).
    let mut poly: Vec<DVec2> = a.corners().to_vec();
    let cb = b.corners();
    for e in 0..4 {
        let (p, q) = (cb[e], cb[(e + 1) % 4]);
        let inside = |x: DVec2| (q - p).perp_dot(x - p) >= 0.0;
        let mut outp = Vec::with_capacity(poly.len() + 2);
        for i in 0..poly.len() {
            let (cur, prev) = (poly[i], poly[(i + poly.len() - 1) % poly.len()]);
            let (ic, ip) = (inside(cur), inside(prev));
            if ic != ip {
                let d = cur - prev;
                let den = (q - p).perp_dot(d);
                if den.abs() > 1e-12 {
                    let u = (q - p).perp_dot(p - prev) / den;
                    outp.push(prev + d * u);
                }
            }
            if ic {
                outp.push(cur);
            }
        }
        poly = outp;
        if poly.is_empty() {
            return None;
        }
    }
    let (mut area, mut c) = (0.0, DVec2::ZERO);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let cr = p.perp_dot(q);
        area += cr;
        c += (p + q) * cr;
    }
    if area.abs() < 1e-12 {
        return Some(poly.iter().copied().sum::<DVec2>() / poly.len() as f64);
    }
    Some(c / (3.0 * area))
}

/// Which side of a box (length, width) a point in its frame lies on: each face is cut in thirds;
/// the outer thirds of the faces are corners.
/// Why a latched contact is not on the side the conflict asked for, if it is not ("front, not
/// its rear_left"): the struck box's side (thirds of each face, `side_of`) must be `point`,
/// except for a struck object, which is turned to face the striker and has no side of its own.
pub fn wrong_struck_side(impact: Impact, point: Point, struck_side: Point) -> Option<String> {
    (impact != Impact::Object && struck_side != point)
        .then(|| format!("{}, not its {}", struck_side.name(), point.name()))
}

/// Why the striker did not touch with its natural striking face, if it did not: its front
/// (the front third of its box, a front corner included, as `side_of` divides a box), or
/// for a sideswipe one of its sides (the left or right third).
pub fn off_striking_face(impact: Impact, af_local: [f64; 2], af_size: [f64; 3]) -> Option<String> {
    let sector = side_of(DVec2::new(af_local[0], af_local[1]), af_size[0], af_size[1]);
    let (on, face) = match impact {
        Impact::Sideswipe => (!matches!(sector, Point::Front | Point::Rear), "side"),
        _ => (matches!(sector, Point::Front | Point::FrontLeft | Point::FrontRight), "front"),
    };
    let (x, y) = (af_local[0], af_local[1]);
    (!on).then(|| format!("the striker touches at ({x:.2}, {y:.2}) m of its box, not with its {face}"))
}

pub fn side_of(local: DVec2, length: f64, width: f64) -> Point {
    let u = local.x / (length / 2.0);
    let v = local.y / (width / 2.0);
    let lon = if u > 1.0 / 3.0 {
        1
    } else if u < -1.0 / 3.0 {
        -1
    } else {
        0
    };
    let lat = if v > 1.0 / 3.0 {
        1
    } else if v < -1.0 / 3.0 {
        -1
    } else {
        0
    };
    match (lon, lat) {
        (1, 0) => Point::Front,
        (-1, 0) => Point::Rear,
        (0, 1) => Point::Left,
        (0, -1) => Point::Right,
        (1, 1) => Point::FrontLeft,
        (1, -1) => Point::FrontRight,
        (-1, 1) => Point::RearLeft,
        (-1, -1) => Point::RearRight,
        // Deep in the middle: the nearer face.
        _ if u.abs() * length >= v.abs() * width => {
            if u >= 0.0 {
                Point::Front
            } else {
                Point::Rear
            }
        }
        _ if v >= 0.0 => Point::Left,
        _ => Point::Right,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::scenario::POINTS;

    /// Every static staging lands the overlap centroid in the requested sector.
    #[test]
    fn staged_poses_touch_the_requested_side() {
        let struck = (4.6, 1.85);
        let af = (4.8, 1.9);
        let cases: &[(Impact, &[Point])] = &[
            (Impact::RearEnd, &[Point::Rear, Point::RearLeft, Point::RearRight]),
            (Impact::HeadOn, &[Point::Front, Point::FrontLeft, Point::FrontRight]),
            (Impact::Angle, &[Point::Left, Point::Right, Point::FrontLeft, Point::RearRight]),
            (Impact::Sideswipe, &[Point::Left, Point::Right, Point::FrontRight, Point::RearLeft]),
            (Impact::Object, &[Point::Front, Point::Rear, Point::Left, Point::FrontLeft, Point::RearRight]),
        ];
        for &(impact, points) in cases {
            for &p in points {
                for same in [0.0, std::f64::consts::PI] {
                    let (c, yaw, delta) = relative(impact, p, struck, af, (DVec2::new(-10.0, -3.0), same), 0.0);
                    let a = Obb { center: c, yaw, length: af.0, width: af.1 };
                    let b = Obb { center: DVec2::ZERO, yaw: 0.0, length: struck.0, width: struck.1 };
                    assert!(a.overlaps(&b), "{impact:?} {p:?}");
                    let d = depth(&a, &b);
                    assert!(d > 0.5 * delta && d < 2.0 * delta, "{impact:?} {p:?} depth {d}");
                    let q = contact_centroid(&a, &b).expect("overlap");
                    let name = POINTS.iter().find(|x| x.1 == p).map(|x| x.0);
                    assert_eq!(side_of(q, struck.0, struck.1), p, "{impact:?} {name:?} {q}");
                }
            }
        }
    }

    #[test]
    fn centroid_of_a_corner_overlap() {
        let a = Obb { center: DVec2::ZERO, yaw: 0.0, length: 2.0, width: 2.0 };
        let b = Obb { center: DVec2::new(1.5, 1.5), yaw: 0.0, length: 2.0, width: 2.0 };
        let c = contact_centroid(&a, &b).expect("overlap");
        assert!(c.distance(DVec2::new(0.75, 0.75)) < 1e-9, "{c}");
        assert!((depth(&a, &b) - 0.5).abs() < 1e-9);
    }
}
