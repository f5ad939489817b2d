//! How bodies move: the kinematic bicycle (pure pursuit, arcs bounded by the turning radius and
//! the yaw rate), holonomic turns, lateral profiles, stopping distances, keyframe replay, and
//! the band a box sweeps along a path.

use crate::check::scenario::Keyframe;
use crate::geom::{Obb, wrap_angle};
use crate::rollout::agent::Actor;
use glam::DVec2;

/// Whether one at speed `v`, `rem` metres short of a mark (up to 5 cm past it counts as at it),
/// can stop there braking at `brake`.
pub(crate) fn can_stop(v: f64, rem: f64, brake: f64) -> bool {
    rem > -0.05 && v * v / (2.0 * rem.max(1e-3)) <= brake
}

/// Largest angle between a vehicle's heading and its lane while it moves sideways (rad).
pub(crate) const MAX_SLIP: f64 = 0.25;
/// How far a long vehicle's ends may swing out of its lane while it moves sideways (m): its
/// box turns about its centre, so at `MAX_SLIP` a bus's tail swung 0.9 m the other way.
pub(crate) const END_SWING: f64 = 0.65;

/// The tangent of the largest angle between vehicle `a`'s heading and its lane while it moves
/// sideways: `MAX_SLIP`, or less where its ends would swing out further than `END_SWING`.
pub(crate) fn slip_tan(a: &Actor) -> f64 {
    MAX_SLIP.tan().min(END_SWING / a.hl)
}

/// The first centre arc length from `from` (to within a quarter metre, never past the
/// true one) at which the box of `a`, stretched across its path to the offsets `band`,
/// meets `theirs`, following its path up to `to`.
pub(crate) fn band_meets(a: &Actor, from: f64, to: f64, band: (f64, f64), theirs: &Obb) -> Option<f64> {
    let (mid, width) = (0.5 * (band.0 + band.1), band.1 - band.0);
    // The box for every centre position in [s, s + step].
    let meets = |s: f64, step: f64| {
        let (p, h) = a.path.point(s + 0.5 * step, mid);
        Obb { center: p, yaw: h, length: 2.0 * a.hl + step, width }.overlaps(theirs)
    };
    let mut s = from;
    while s < to {
        if meets(s, 1.0) {
            return (0..4).map(|k| s + 0.25 * k as f64).find(|&q| meets(q, 0.25)).or(Some(s + 0.75));
        }
        s += 1.0;
    }
    None
}

/// The nearest longitudinal point, relative to its centre, of the part of a box lying inside the
/// lateral band `lo..hi` of a path frame (the box centred at lateral offset `lat`, its heading at
/// cosine `cr` and sine `sr` to the path's, half sizes `hl`, `hw`); `None` when no part does.
pub(crate) fn band_front(lat: f64, cr: f64, sr: f64, hl: f64, hw: f64, lo: f64, hi: f64) -> Option<f64> {
    let (ax, ay) = (DVec2::new(cr, sr), DVec2::new(-sr, cr));
    let c = DVec2::new(0.0, lat);
    let mut poly = vec![c + ax * hl + ay * hw, c - ax * hl + ay * hw, c - ax * hl - ay * hw, c + ax * hl - ay * hw];
    // Sutherland-Hodgman against y >= lo, then y <= hi.
    for (bound, keep_above) in [(lo, true), (hi, false)] {
        let inside = |p: DVec2| if keep_above { p.y >= bound } else { p.y <= bound };
        let mut out = Vec::with_capacity(poly.len() + 2);
        for k in 0..poly.len() {
            let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
            if inside(p) {
                out.push(p);
            }
            if inside(p) != inside(q) {
                let u = (bound - p.y) / (q.y - p.y);
                out.push(p + (q - p) * u);
            }
        }
        poly = out;
        if poly.is_empty() {
            return None;
        }
    }
    poly.iter().map(|p| p.x).reduce(f64::min)
}

/// Smooth 0..1 profile with zero velocity and acceleration at both ends.
pub(crate) fn quintic(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)
}

/// Rotate `from` toward `to`, bounded by a yaw rate (holonomic agents turn on the spot).
pub(crate) fn turn_toward(from: f64, to: f64, rate: f64, dt: f64) -> f64 {
    let step = wrap_angle(to - from).clamp(-rate * dt, rate * dt);
    wrap_angle(from + step)
}

/// Pure pursuit: the curvature of the circle through `p`, tangent to the unit heading `fwd`
/// there, and through `aim` (0 when `aim` is on the heading line or at `p`).
pub(crate) fn pursuit(p: DVec2, fwd: DVec2, aim: DVec2) -> f64 {
    let rel = aim - p;
    let l2 = rel.length_squared();
    if l2 < 1e-12 { 0.0 } else { 2.0 * fwd.perp_dot(rel) / l2 }
}

/// `Sim::advance` from a bare pose (the dry run of `assign_bends` steers as the rollout does).
pub(crate) fn steer(a: &Actor, pos: DVec2, yaw: f64, k: f64, dist: f64, dt: f64, yaw_scale: f64) -> (DVec2, f64) {
    if dist <= 0.0 {
        return (pos, yaw);
    }
    let k_max = (1.0 / a.r_min).min(yaw_scale * a.lim.yaw_rate * dt / dist);
    arc(pos, yaw, k.clamp(-k_max, k_max), dist)
}

/// Pure pursuit's look-ahead distance for vehicle `a` at speed `v`, m.
pub(crate) fn look_ahead(a: &Actor, v: f64) -> f64 {
    (0.8 * v).max(2.0 + 0.25 * a.r_min).min(20.0)
}

/// Exact integration of the kinematic bicycle over a step of length `dist` at curvature `k`:
/// the box moves along a circular arc tangent to its heading (no sideways slip).
pub(crate) fn arc(p: DVec2, yaw: f64, k: f64, dist: f64) -> (DVec2, f64) {
    let dyaw = k * dist;
    let chord = if dyaw.abs() < 1e-9 { dist } else { 2.0 * (0.5 * dyaw).sin() / k };
    (p + DVec2::from_angle(yaw + 0.5 * dyaw) * chord, wrap_angle(yaw + dyaw))
}

/// Keyframe time tolerance (s) of `replay`; see there.
pub const KEY_SNAP_S: f64 = 1e-6;

/// Keyframe interpolation: linear in position, shortest arc in yaw, held beyond either end.
/// At a keyframe's own time (within `KEY_SNAP_S`, the float noise of `f * dt`) the keyframe is
/// returned exactly, so recorded frames replay bit for bit (the importer's lossless guarantee).
pub(crate) fn replay(keys: &[Keyframe], t: f64) -> (DVec2, f64) {
    if let Some(k) = keys.iter().find(|k| (k.t - t).abs() <= KEY_SNAP_S) {
        return (DVec2::new(k.x, k.y), k.yaw);
    }
    let k = keys.partition_point(|k| k.t <= t);
    if k == 0 {
        let f = &keys[0];
        return (DVec2::new(f.x, f.y), f.yaw);
    }
    if k >= keys.len() {
        let l = &keys[keys.len() - 1];
        return (DVec2::new(l.x, l.y), l.yaw);
    }
    let (a, b) = (&keys[k - 1], &keys[k]);
    let u = if b.t > a.t { (t - a.t) / (b.t - a.t) } else { 1.0 };
    let p = DVec2::new(a.x, a.y).lerp(DVec2::new(b.x, b.y), u);
    (p, wrap_angle(a.yaw + wrap_angle(b.yaw - a.yaw) * u))
}
