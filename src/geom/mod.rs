//! Plane geometry shared by the passes: polylines with arc length, polygons, oriented boxes.
//! World coordinates are metres, x east, y north, yaw counter-clockwise from +x (radians).

use glam::DVec2;
use serde::{Deserialize, Serialize};

/// A closed polygon (the last point connects back to the first).
pub type Polygon = Vec<DVec2>;

/// A polyline with cumulative arc length at each vertex.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Polyline {
    pub points: Vec<DVec2>,
    /// `s[i]` = arc length from `points[0]` to `points[i]`.
    pub s: Vec<f64>,
}

impl Polyline {
    pub fn new(points: Vec<DVec2>) -> Self {
        let mut s = Vec::with_capacity(points.len());
        let mut acc = 0.0;
        for (i, p) in points.iter().enumerate() {
            if i > 0 {
                acc += p.distance(points[i - 1]);
            }
            s.push(acc);
        }
        Polyline { points, s }
    }

    pub fn length(&self) -> f64 {
        self.s.last().copied().unwrap_or(0.0)
    }

    /// Position and heading (rad) at arc length `s`, clamped to the ends.
    pub fn pose_at(&self, s: f64) -> (DVec2, f64) {
        let n = self.points.len();
        if n == 0 {
            return (DVec2::ZERO, 0.0);
        }
        if n == 1 {
            return (self.points[0], 0.0);
        }
        let s = s.clamp(0.0, self.length());
        let i = match self.s.binary_search_by(|x| x.total_cmp(&s)) {
            Ok(i) => i.min(n - 2),
            Err(i) => i.saturating_sub(1).min(n - 2),
        };
        let (a, b) = (self.points[i], self.points[i + 1]);
        let seg = self.s[i + 1] - self.s[i];
        let t = if seg > 0.0 { (s - self.s[i]) / seg } else { 0.0 };
        let d = b - a;
        (a + d * t, d.y.atan2(d.x))
    }

    /// Point at arc length `s` shifted `offset` metres to the left of the direction of travel.
    pub fn offset_point(&self, s: f64, offset: f64) -> DVec2 {
        let (p, yaw) = self.pose_at(s);
        p + DVec2::new(-yaw.sin(), yaw.cos()) * offset
    }

    /// Arc length and signed lateral offset (left positive) of the closest point to `p`.
    pub fn project(&self, p: DVec2) -> (f64, f64) {
        let mut best = (f64::INFINITY, 0.0, 0.0);
        for i in 0..self.points.len().saturating_sub(1) {
            let (a, b) = (self.points[i], self.points[i + 1]);
            let d = b - a;
            let len2 = d.length_squared();
            let t = if len2 > 0.0 { ((p - a).dot(d) / len2).clamp(0.0, 1.0) } else { 0.0 };
            let q = a + d * t;
            let dist = p.distance(q);
            if dist < best.0 {
                let side = d.perp_dot(p - a).signum();
                best = (dist, self.s[i] + t * len2.sqrt(), side * dist);
            }
        }
        (best.1, best.2)
    }

    /// The polyline shifted sideways by `offset` (left positive), vertex by vertex.
    pub fn shifted(&self, offset: f64) -> Polyline {
        let n = self.points.len();
        let pts = (0..n)
            .map(|i| {
                let a = self.points[i.saturating_sub(1)];
                let b = self.points[(i + 1).min(n - 1)];
                let d = (b - a).normalize_or_zero();
                self.points[i] + DVec2::new(-d.y, d.x) * offset
            })
            .collect();
        Polyline::new(pts)
    }
}

/// An oriented rectangle: the ground footprint of a box.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Obb {
    pub center: DVec2,
    pub yaw: f64,
    pub length: f64,
    pub width: f64,
}

impl Obb {
    /// Corners counter-clockwise: front-left, rear-left, rear-right, front-right.
    pub fn corners(&self) -> [DVec2; 4] {
        let f = DVec2::new(self.yaw.cos(), self.yaw.sin()) * (self.length / 2.0);
        let l = DVec2::new(-self.yaw.sin(), self.yaw.cos()) * (self.width / 2.0);
        [self.center + f + l, self.center - f + l, self.center - f - l, self.center + f - l]
    }

    /// Separating-axis test; boxes that only touch do not overlap.
    pub fn overlaps(&self, o: &Obb) -> bool {
        let (a, b) = (self.corners(), o.corners());
        let axes = [
            DVec2::from_angle(self.yaw),
            DVec2::from_angle(self.yaw).perp(),
            DVec2::from_angle(o.yaw),
            DVec2::from_angle(o.yaw).perp(),
        ];
        axes.iter().all(|ax| {
            let (amin, amax) = proj(&a, *ax);
            let (bmin, bmax) = proj(&b, *ax);
            amin < bmax - 1e-9 && bmin < amax - 1e-9
        })
    }
}

fn proj(c: &[DVec2; 4], ax: DVec2) -> (f64, f64) {
    c.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
        let d = p.dot(ax);
        (lo.min(d), hi.max(d))
    })
}

/// Even-odd point-in-polygon test.
pub fn point_in_polygon(p: DVec2, poly: &[DVec2]) -> bool {
    let mut inside = false;
    let n = poly.len();
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// Wrap an angle to (-pi, pi].
pub fn wrap_angle(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let y = a + std::f64::consts::PI;
    // `rem_euclid` returns its argument unchanged on [0, TAU) (fmod is exact): skip the libm call
    // there, the common case, with a bit-identical result.
    let r = if (0.0..t).contains(&y) { y } else { y.rem_euclid(t) };
    let mut x = r - std::f64::consts::PI;
    if x <= -std::f64::consts::PI {
        x += t;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast path of `wrap_angle` is bit-identical to the plain `rem_euclid` formula.
    #[test]
    fn wrap_angle_fast_path_is_exact() {
        let slow = |a: f64| {
            let t = std::f64::consts::TAU;
            let mut x = (a + std::f64::consts::PI).rem_euclid(t) - std::f64::consts::PI;
            if x <= -std::f64::consts::PI {
                x += t;
            }
            x
        };
        let pi = std::f64::consts::PI;
        let mut cases = vec![0.0, -0.0, pi, -pi, 2.0 * pi, -2.0 * pi, 1e-300, -1e-300, 7.5, -7.5, 1e6, f64::NAN];
        cases.extend((0..20000).map(|i| (i as f64 - 10000.0) * 0.00123 * pi));
        cases.extend([pi.next_up(), (-pi).next_down(), (-pi).next_up(), pi.next_down()]);
        for a in cases {
            assert_eq!(wrap_angle(a).to_bits(), slow(a).to_bits(), "{a}");
        }
    }

    #[test]
    fn polyline_pose_and_projection_agree() {
        let l = Polyline::new(vec![DVec2::new(0.0, 0.0), DVec2::new(10.0, 0.0), DVec2::new(10.0, 10.0)]);
        assert_eq!(l.length(), 20.0);
        let (p, yaw) = l.pose_at(15.0);
        assert!((p - DVec2::new(10.0, 5.0)).length() < 1e-12);
        assert!((yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let (s, lat) = l.project(DVec2::new(5.0, 1.0));
        assert!((s - 5.0).abs() < 1e-12 && (lat - 1.0).abs() < 1e-12);
    }

    #[test]
    fn boxes_overlap_only_when_they_intersect() {
        let a = Obb { center: DVec2::ZERO, yaw: 0.0, length: 4.0, width: 2.0 };
        let touching = Obb { center: DVec2::new(4.0, 0.0), ..a };
        let overlapping = Obb { center: DVec2::new(3.9, 0.5), yaw: 0.3, ..a };
        assert!(!a.overlaps(&touching));
        assert!(a.overlaps(&overlapping));
        assert!(point_in_polygon(DVec2::new(0.5, 0.5), &a.corners()));
    }
}
