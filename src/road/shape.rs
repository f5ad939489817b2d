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

/// Twice the signed area of `poly` (positive counter-clockwise).
pub(crate) fn area2(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    (0..n).map(|i| poly[i].perp_dot(poly[(i + 1) % n])).sum()
}

/// The part of `poly` on the side of the line `a -> b` where `side * cross(b - a, p - a) >= 0`
/// (Sutherland-Hodgman against one half-plane; a convex polygon stays convex).
fn clip_half_plane(poly: &[DVec2], a: DVec2, b: DVec2, side: f64) -> Polygon {
    let d = b - a;
    let f = |p: DVec2| side * d.perp_dot(p - a);
    let mut out = Vec::with_capacity(poly.len() + 2);
    let n = poly.len();
    for i in 0..n {
        let (p, q) = (poly[(i + n - 1) % n], poly[i]);
        let (fp, fq) = (f(p), f(q));
        if (fp >= 0.0) != (fq >= 0.0) {
            out.push(p + (q - p) * (fp / (fp - fq)));
        }
        if fq >= 0.0 {
            out.push(q);
        }
    }
    out
}

/// Whether `poly` and the convex polygon `convex` share more than an edge (S-H output keeps the
/// area of the intersection even for a concave `poly`).
pub(crate) fn overlaps_convex(poly: &[DVec2], convex: &[DVec2]) -> bool {
    const EPS: f64 = 1e-9;
    let orient = area2(convex).signum();
    if area2(convex).abs() <= EPS {
        return false;
    }
    let n = convex.len();
    let mut rest: Polygon = poly.to_vec();
    for i in 0..n {
        if rest.len() < 3 {
            return false;
        }
        rest = clip_half_plane(&rest, convex[i], convex[(i + 1) % n], orient);
    }
    rest.len() >= 3 && area2(&rest).abs() > EPS
}

/// `poly` minus the convex polygon `hole`, as disjoint pieces: the part beyond the hole's first
/// edge, then the part within the first and beyond the second, and so on. With a convex `poly`
/// every piece is convex. Pieces thinner than rounding are dropped, and `poly` comes back whole
/// when the two only touch.
pub(crate) fn subtract_convex(poly: &[DVec2], hole: &[DVec2]) -> Vec<Polygon> {
    const EPS: f64 = 1e-9;
    if !overlaps_convex(poly, hole) {
        return vec![poly.to_vec()];
    }
    let orient = area2(hole).signum();
    let mut rest: Polygon = poly.to_vec();
    let mut pieces = Vec::new();
    let n = hole.len();
    for i in 0..n {
        let (a, b) = (hole[i], hole[(i + 1) % n]);
        let beyond = clip_half_plane(&rest, a, b, -orient);
        if beyond.len() >= 3 && area2(&beyond).abs() > EPS {
            pieces.push(beyond);
        }
        rest = clip_half_plane(&rest, a, b, orient);
        if rest.len() < 3 {
            break;
        }
    }
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(lo: f64, hi: f64) -> Polygon {
        vec![DVec2::new(lo, lo), DVec2::new(hi, lo), DVec2::new(hi, hi), DVec2::new(lo, hi)]
    }

    #[test]
    fn subtracting_a_convex_hole_keeps_exactly_the_rest() {
        let area = |ps: &[Polygon]| ps.iter().map(|p| area2(p).abs() / 2.0).sum::<f64>();
        // A hole inside: the 16 m2 square loses 4 m2, in pieces that avoid the hole.
        let pieces = subtract_convex(&square(0.0, 4.0), &square(1.0, 3.0));
        assert!((area(&pieces) - 12.0).abs() < 1e-9, "{}", area(&pieces));
        for p in &pieces {
            let c = p.iter().copied().sum::<DVec2>() / p.len() as f64;
            assert!(!(c.x > 1.0 && c.x < 3.0 && c.y > 1.0 && c.y < 3.0), "piece centred in the hole: {p:?}");
        }
        // Clockwise hole over a corner: 1 m2 of 16 goes.
        let mut hole = square(3.0, 5.0);
        hole.reverse();
        assert!((area(&subtract_convex(&square(0.0, 4.0), &hole)) - 15.0).abs() < 1e-9);
        // Touching along an edge only, or apart: unchanged, in one piece.
        assert_eq!(subtract_convex(&square(0.0, 4.0), &square(4.0, 6.0)), vec![square(0.0, 4.0)]);
        assert_eq!(subtract_convex(&square(0.0, 4.0), &square(5.0, 6.0)), vec![square(0.0, 4.0)]);
        // Covered entirely: nothing left.
        assert!(subtract_convex(&square(1.0, 2.0), &square(0.0, 4.0)).is_empty());
    }
}
