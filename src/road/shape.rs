//! Geometry helpers of the road pass. In: axis polylines, offsets, control points. Out: sampled
//! polylines and polygons (strips along an axis, dashes, arcs, Bezier curves, bounds).

use crate::geom::{Polygon, Polyline};
use glam::DVec2;

/// Spacing of sampled curves: fine enough that a lane's polyline never strays more than a few
/// millimetres from the ideal curve at the radii the checker allows.
pub(crate) const STEP: f64 = 0.5;

/// Painted dash and gap lengths of broken lane lines (m).
pub(crate) const DASH: f64 = 3.0;
pub(crate) const GAP: f64 = 6.0;

/// The part of `line` between arc lengths `s0` and `s1` (clamped, `s0 <= s1`), with interpolated
/// end points.
pub(crate) fn slice(line: &Polyline, s0: f64, s1: f64) -> Vec<DVec2> {
    let len = line.length();
    let (s0, s1) = (s0.clamp(0.0, len), s1.clamp(0.0, len));
    let mut out = vec![line.pose_at(s0).0];
    for (p, &s) in line.points.iter().zip(&line.s) {
        if s > s0 + 1e-9 && s < s1 - 1e-9 {
            out.push(*p);
        }
    }
    let end = line.pose_at(s1).0;
    if out.last().is_none_or(|l| l.distance(end) > 1e-9) {
        out.push(end);
    }
    out
}

/// The same line driven the other way.
pub(crate) fn reversed(line: &Polyline) -> Polyline {
    Polyline::new(line.points.iter().rev().copied().collect())
}

/// The band between lateral offsets `a` and `b` (left positive) over arc lengths `s0..s1`.
pub(crate) fn strip(axis: &Polyline, s0: f64, s1: f64, a: f64, b: f64) -> Polygon {
    let part = Polyline::new(slice(axis, s0, s1));
    let mut poly = part.shifted(a).points;
    poly.extend(part.shifted(b).points.into_iter().rev());
    poly
}

/// A line parallel to `axis` at lateral `offset` over `s0..s1`.
pub(crate) fn parallel(axis: &Polyline, s0: f64, s1: f64, offset: f64) -> Vec<DVec2> {
    Polyline::new(slice(axis, s0, s1)).shifted(offset).points
}

/// Broken line parallel to `axis`: one polyline per dash.
pub(crate) fn dashes(axis: &Polyline, s0: f64, s1: f64, offset: f64) -> Vec<Vec<DVec2>> {
    let mut out = Vec::new();
    let mut s = s0;
    while s < s1 - 0.5 {
        out.push(parallel(axis, s, (s + DASH).min(s1), offset));
        s += DASH + GAP;
    }
    out
}

/// Points on a circle from angle `a0` to `a1` (either direction), at most `STEP` apart.
pub(crate) fn arc(center: DVec2, r: f64, a0: f64, a1: f64) -> Vec<DVec2> {
    let n = ((r * (a1 - a0).abs() / STEP).ceil() as usize).clamp(2, 20_000);
    (0..=n).map(|i| center + r * DVec2::from_angle(a0 + (a1 - a0) * i as f64 / n as f64)).collect()
}

/// A cubic Bezier, sampled about `STEP` apart.
pub(crate) fn cubic(p0: DVec2, p1: DVec2, p2: DVec2, p3: DVec2) -> Vec<DVec2> {
    let rough = p0.distance(p1) + p1.distance(p2) + p2.distance(p3);
    let n = ((rough / STEP).ceil() as usize).clamp(8, 4000);
    (0..=n)
        .map(|i| {
            let t = i as f64 / n as f64;
            let u = 1.0 - t;
            p0 * (u * u * u) + p1 * (3.0 * u * u * t) + p2 * (3.0 * u * t * t) + p3 * (t * t * t)
        })
        .collect()
}

/// A straight segment sampled about `STEP` apart (connectors are followed by a controller that
/// reads curvature from neighbouring vertices, so even straight ones are sampled).
pub(crate) fn segment(a: DVec2, b: DVec2) -> Vec<DVec2> {
    let n = ((a.distance(b) / STEP).ceil() as usize).clamp(1, 20_000);
    (0..=n).map(|i| a.lerp(b, i as f64 / n as f64)).collect()
}

/// Where the lines `p + t d` and `q + s e` meet, if they are not parallel.
pub(crate) fn intersect(p: DVec2, d: DVec2, q: DVec2, e: DVec2) -> Option<DVec2> {
    let den = d.perp_dot(e);
    if den.abs() < 1e-9 {
        return None;
    }
    Some(p + d * ((q - p).perp_dot(e) / den))
}

/// A smooth turn from `p0` heading `d0` to `p3` heading `d3`: a cubic whose handles follow the
/// circle-approximation rule (0.5523 of each leg to the corner), or a third of the chord when the
/// headings are parallel.
pub(crate) fn turn(p0: DVec2, d0: DVec2, p3: DVec2, d3: DVec2) -> Vec<DVec2> {
    let chord = p0.distance(p3);
    let (k0, k3) = match intersect(p0, d0, p3, d3) {
        Some(c) if (c - p0).dot(d0) > 0.0 && (p3 - c).dot(d3) > 0.0 => {
            (0.5523 * c.distance(p0), 0.5523 * c.distance(p3))
        }
        _ => (chord / 3.0, chord / 3.0),
    };
    cubic(p0, p0 + d0 * k0, p3 - d3 * k3, p3)
}

/// Stretch the bounds `(min, max)` over `pts`.
pub(crate) fn grow(b: &mut (DVec2, DVec2), pts: &[DVec2]) {
    for p in pts {
        b.0 = b.0.min(*p);
        b.1 = b.1.max(*p);
    }
}
