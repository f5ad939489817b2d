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
        let (p, d) = self.point_dir_at(s);
        (p, d.y.atan2(d.x))
    }

    /// `pose_at`'s position, without the heading's trigonometry.
    pub fn point_at(&self, s: f64) -> DVec2 {
        self.point_dir_at(s).0
    }

    /// Position at arc length `s` (clamped to the ends) and the vector of its segment (zero
    /// with fewer than two points; `pose_at`'s heading is its angle).
    #[inline]
    fn point_dir_at(&self, s: f64) -> (DVec2, DVec2) {
        let n = self.points.len();
        if n == 0 {
            return (DVec2::ZERO, DVec2::ZERO);
        }
        if n == 1 {
            return (self.points[0], DVec2::ZERO);
        }
        let s = s.clamp(0.0, self.length());
        let i = match self.s.binary_search_by(|x| x.total_cmp(&s)) {
            Ok(i) => i.min(n - 2),
            Err(i) => i.saturating_sub(1).min(n - 2),
        };
        self.point_dir_on(i, s)
    }

    /// `point_dir_at`'s answer on segment `i` for a clamped `s`.
    #[inline(always)]
    fn point_dir_on(&self, i: usize, s: f64) -> (DVec2, DVec2) {
        let (a, b) = (self.points[i], self.points[i + 1]);
        let seg = self.s[i + 1] - self.s[i];
        let t = if seg > 0.0 { (s - self.s[i]) / seg } else { 0.0 };
        let d = b - a;
        (a + d * t, d)
    }

    /// `point_at` for arc lengths asked mostly in increasing order (sampling along the line):
    /// where the arc lengths increase strictly (under `total_cmp`), the segment the bisection
    /// finds is the last one starting at or before `s`, found here by walking forward from the
    /// last answer's (`seg`; from the start where `s` lies before it). Else the bisection.
    pub fn point_at_walk(&self, s: f64, seg: &mut Option<usize>, strict: bool) -> DVec2 {
        let n = self.points.len();
        if n < 2 || !strict {
            return self.point_at(s);
        }
        let s = s.clamp(0.0, self.length());
        let mut i = seg.unwrap_or(0).min(n - 1);
        if self.s[i].total_cmp(&s).is_gt() {
            i = 0;
        }
        while i + 1 < n && self.s[i + 1].total_cmp(&s).is_le() {
            i += 1;
        }
        *seg = Some(i);
        self.point_dir_on(i.min(n - 2), s).0
    }

    /// Whether the arc lengths increase strictly (under `total_cmp`), for `point_at_walk`.
    pub fn strictly_increasing(&self) -> bool {
        self.s.windows(2).all(|w| w[0].total_cmp(&w[1]).is_lt())
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
            let seg = self.project_on(i, p);
            if seg.0 < best.0 {
                best = seg;
            }
        }
        (best.1, best.2)
    }

    /// `p` projected onto segment `i`: its distance, the arc length of its foot and its signed
    /// offset (left positive). `project` keeps the first segment of least distance.
    #[inline(always)]
    fn project_on(&self, i: usize, p: DVec2) -> (f64, f64, f64) {
        let foot = self.foot_on(i, p);
        self.finish_on(i, p, foot, foot.0.sqrt())
    }

    /// `project_on`'s first half: the squared distance (`p.distance(q)` is its root), and what
    /// `finish_on` needs (the foot's parameter, the segment's squared length and vector).
    #[inline(always)]
    fn foot_on(&self, i: usize, p: DVec2) -> (f64, f64, f64, DVec2) {
        let (a, b) = (self.points[i], self.points[i + 1]);
        let d = b - a;
        let len2 = d.length_squared();
        let t = if len2 > 0.0 { ((p - a).dot(d) / len2).clamp(0.0, 1.0) } else { 0.0 };
        let q = a + d * t;
        ((p - q).length_squared(), t, len2, d)
    }

    /// `project_on` from `foot_on` and the distance.
    #[inline(always)]
    fn finish_on(&self, i: usize, p: DVec2, (_, t, len2, d): (f64, f64, f64, DVec2), dist: f64) -> (f64, f64, f64) {
        let side = d.perp_dot(p - self.points[i]).signum();
        (dist, self.s[i] + t * len2.sqrt(), side * dist)
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

/// `Polyline::project` for many points onto one long polyline (a roundabout's ring connector
/// against every sample of another path): the same result, bit for bit, from fewer segments.
/// Segments come in chunks with a bounding box; a chunk whose box lies farther from the point
/// than some segment's distance (plus a margin far above rounding) holds no segment of least
/// distance, so it is passed over, and the rest are scanned in order as `project` does.
pub struct Projector<'a> {
    line: &'a Polyline,
    /// Per chunk of `CHUNK` segments, the bounding box of their points.
    boxes: Vec<(DVec2, DVec2)>,
    /// Per run of `GROUP` chunks, the bounding box of their boxes: a point far from a run passes
    /// over its chunks with one test.
    groups: Vec<(DVec2, DVec2)>,
    /// The bounding box of every point.
    whole: (DVec2, DVec2),
    /// Every coordinate finite and within `FAR`, where `MARGIN` bounds the rounding.
    tame: bool,
}

impl<'a> Projector<'a> {
    const CHUNK: usize = 8;
    const GROUP: usize = 8;
    /// Far above the rounding of distances between points within `FAR` (~1e-6 m).
    const MARGIN: f64 = 0.01;
    const FAR: f64 = 1e9;

    pub fn new(line: &'a Polyline) -> Projector<'a> {
        let n = line.points.len();
        let segs = n.saturating_sub(1);
        let bound = |pts: &[DVec2]| {
            pts.iter().fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &q| (lo.min(q), hi.max(q)))
        };
        let boxes: Vec<(DVec2, DVec2)> = (0..segs.div_ceil(Self::CHUNK))
            .map(|c| bound(&line.points[c * Self::CHUNK..((c + 1) * Self::CHUNK + 1).min(n)]))
            .collect();
        let groups = boxes
            .chunks(Self::GROUP)
            .map(|g| g.iter().fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), b| (lo.min(b.0), hi.max(b.1))))
            .collect();
        // Compared one by one: `max_element` would pass over a NaN.
        let tame = line.points.iter().all(|q| q.x.abs() < Self::FAR && q.y.abs() < Self::FAR);
        Projector { line, boxes, groups, whole: bound(&line.points), tame }
    }

    /// `self.line.project(p)`; `hint` is a segment to try first (the last answer's, for points
    /// taken in order along another path), updated.
    pub fn project(&self, p: DVec2, hint: &mut usize) -> (f64, f64) {
        let ((_, s, off), _) = self.nearest(p, hint, f64::INFINITY);
        (s, off)
    }

    /// `Ok(self.line.project(p))`, or `Err` where the point lies farther than `reach` from the
    /// line (by the distance `project` measures, the size of its offset): for asking only
    /// whether points come within some `gap <= reach` of the line, which fails on either. The
    /// error holds a floor under that distance (a point `x` from `p` lies at least the floor
    /// less `x` away). A NaN reach bounds nothing.
    pub fn project_within(&self, p: DVec2, hint: &mut usize, reach: f64) -> Result<(f64, f64), f64> {
        if !self.bounded(p) || reach.is_nan() {
            return Ok(self.line.project(p));
        }
        let ((dist, s, off), floor) = self.nearest(p, hint, reach);
        if dist <= reach { Ok((s, off)) } else { Err(floor) }
    }

    /// Whether the margin bounds the rounding for `p`: it and the line are within `FAR`, and
    /// the line has a segment.
    fn bounded(&self, p: DVec2) -> bool {
        self.tame && self.line.points.len() >= 2 && p.x.abs() < Self::FAR && p.y.abs() < Self::FAR
    }

    /// The first segment of least distance to `p`, as `Polyline::project` finds it, where that
    /// distance is at most `reach` (its distance, arc length and offset); else possibly an
    /// infinite distance. With a floor under that distance (less than it by `MARGIN` at least).
    fn nearest(&self, p: DVec2, hint: &mut usize, reach: f64) -> ((f64, f64, f64), f64) {
        let segs = self.line.points.len().saturating_sub(1);
        let scan_all = || {
            let best = (0..segs)
                .map(|i| self.line.project_on(i, p))
                .fold((f64::INFINITY, 0.0, 0.0), |b, x| if x.0 < b.0 { x } else { b });
            (best, f64::NEG_INFINITY)
        };
        if !self.bounded(p) {
            return scan_all();
        }
        // Some segment's distance (the hint's) bounds the least one; so does `reach` where the
        // least one matters. Chunks beyond the bound hold no segment that could be it.
        let bound = self.line.project_on((*hint).min(segs - 1), p).0.min(reach) + Self::MARGIN;
        if !bound.is_finite() {
            return scan_all();
        }
        let away = |(lo, hi): (DVec2, DVec2)| (lo - p).max(p - hi).max(DVec2::ZERO).length_squared();
        let mut best = (f64::INFINITY, 0.0, 0.0);
        let whole = away(self.whole);
        if whole > bound * bound {
            return (best, whole.sqrt() - Self::MARGIN);
        }
        let mut nearest_box = f64::INFINITY;
        // Once a segment is found, one farther than it by the margin cannot be the first of
        // least distance either (`project` keeps the first under `<`): the bound tightens, and
        // a segment's own box (its two ends) is tested before its projection's division and
        // roots.
        let mut lim = bound;
        let mut best_d2 = f64::INFINITY;
        // A group's box holds its chunks' boxes, so its distance (the same monotone float
        // operations on wider bounds) is no more than theirs: it stands in for them in the
        // floor, and rules them all out when it is beyond the bound.
        for (g, &gb) in self.groups.iter().enumerate() {
            let d2 = away(gb);
            if d2 > lim * lim {
                nearest_box = nearest_box.min(d2);
                continue;
            }
            let first = g * Self::GROUP;
            for (c, &b) in self.boxes[first..(first + Self::GROUP).min(self.boxes.len())].iter().enumerate() {
                let c = first + c;
                let d2 = away(b);
                nearest_box = nearest_box.min(d2);
                if d2 > lim * lim {
                    continue;
                }
                for i in c * Self::CHUNK..((c + 1) * Self::CHUNK).min(segs) {
                    let (a, e) = (self.line.points[i], self.line.points[i + 1]);
                    if away((a.min(e), a.max(e))) > lim * lim {
                        continue;
                    }
                    // A square above the best one has a root no smaller (the root is
                    // monotone): it cannot be less, so neither root nor the rest is taken.
                    let foot = self.line.foot_on(i, p);
                    if foot.0 > best_d2 {
                        continue;
                    }
                    let dist = foot.0.sqrt();
                    if dist < best.0 {
                        best = self.line.finish_on(i, p, foot, dist);
                        best_d2 = foot.0;
                        *hint = i;
                        lim = lim.min(best.0 + Self::MARGIN);
                    }
                }
            }
        }
        (best, nearest_box.sqrt() - Self::MARGIN)
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
        self.corners_along(DVec2::new(self.yaw.cos(), self.yaw.sin()))
    }

    /// `corners` given the unit heading `DVec2::from_angle(self.yaw)` (the same sine and cosine).
    pub fn corners_along(&self, dir: DVec2) -> [DVec2; 4] {
        let f = dir * (self.length / 2.0);
        let l = DVec2::new(-dir.y, dir.x) * (self.width / 2.0);
        [self.center + f + l, self.center - f + l, self.center - f - l, self.center + f - l]
    }

    /// The box grown by `m` all round.
    pub fn grown(&self, m: f64) -> Obb {
        Obb { length: self.length + 2.0 * m, width: self.width + 2.0 * m, ..*self }
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

    /// `Projector` gives the bits of the plain scan over every segment (kept written out here as
    /// `project` was before it shared its segment step): on a ring traced twice (ties between
    /// segments), with repeated points, from any hint, for points on vertices, near and far, and
    /// for coordinates it cannot bound (the plain scan then).
    #[test]
    fn projector_is_the_plain_scan() {
        let plain = |l: &Polyline, p: DVec2| {
            let mut best = (f64::INFINITY, 0.0, 0.0);
            for i in 0..l.points.len().saturating_sub(1) {
                let (a, b) = (l.points[i], l.points[i + 1]);
                let d = b - a;
                let len2 = d.length_squared();
                let t = if len2 > 0.0 { ((p - a).dot(d) / len2).clamp(0.0, 1.0) } else { 0.0 };
                let q = a + d * t;
                let dist = p.distance(q);
                if dist < best.0 {
                    let side = d.perp_dot(p - a).signum();
                    best = (dist, l.s[i] + t * len2.sqrt(), side * dist);
                }
            }
            (best.1, best.2)
        };
        let mut ring: Vec<DVec2> =
            (0..=300).map(|i| DVec2::new(40.0, -12.0) + DVec2::from_angle(i as f64 * 0.042) * 25.0).collect();
        ring.insert(37, ring[37]);
        ring.insert(90, ring[90]);
        let lines = [
            Polyline::new(ring.clone()),
            Polyline::new(vec![DVec2::new(1.0, 2.0), DVec2::new(60.0, 2.0)]),
            Polyline::new(vec![DVec2::new(3.0, 3.0)]),
            Polyline::new(vec![]),
            Polyline::new(vec![DVec2::new(0.0, 0.0), DVec2::new(f64::NAN, 1.0), DVec2::new(5.0, 5.0)]),
            Polyline::new(vec![DVec2::new(0.0, 0.0), DVec2::new(2e9, 1.0)]),
        ];
        let mut points: Vec<DVec2> =
            (0..2500).map(|k| DVec2::new((k % 50) as f64 * 1.7 - 5.0, (k / 50) as f64 * 1.3 - 45.0)).collect();
        points.extend(ring.iter().step_by(7).copied());
        points.extend([
            DVec2::new(40.0, -12.0),
            DVec2::new(1e7, -3e8),
            DVec2::new(2e9, 0.0),
            DVec2::new(f64::NAN, 0.0),
        ]);
        let bits = |(a, b): (f64, f64)| (a.to_bits(), b.to_bits());
        let mut pruned = 0;
        for l in &lines {
            let pr = Projector::new(l);
            let mut hint = 0;
            for (k, &p) in points.iter().enumerate() {
                let want = plain(l, p);
                assert_eq!(bits(l.project(p)), bits(want), "{p}");
                assert_eq!(bits(pr.project(p, &mut hint)), bits(want), "{p}");
                let mut other = k * 37 % 400;
                assert_eq!(bits(pr.project(p, &mut other)), bits(want), "{p} from {}", k * 37 % 400);
                // Within a reach: the same where the point is that near, else `None` only if
                // the distance `project` measures is greater.
                for reach in [0.0, 0.3, 2.0, 7.5, 40.0, f64::INFINITY, -1.0, f64::NAN] {
                    match pr.project_within(p, &mut other, reach) {
                        Ok(got) => assert_eq!(bits(got), bits(want), "{p} within {reach}"),
                        Err(floor) => {
                            assert!(want.1.abs() > reach, "{p} within {reach}: {want:?}");
                            // The floor holds for points near this one (1 m off, any way).
                            for q in [p, p + DVec2::X, p - DVec2::Y, p + DVec2::new(0.6, 0.8)] {
                                assert!(plain(l, q).1.abs() >= floor - p.distance(q), "{q} floor {floor}");
                            }
                            pruned += 1;
                        }
                    }
                    if want.1.abs() <= reach {
                        assert!(pr.project_within(p, &mut hint, reach).is_ok(), "{p} within {reach}");
                    }
                }
            }
        }
        assert!(pruned > 5000, "points far from the line are answered without projecting: {pruned}");
    }

    /// `point_at_walk` gives `point_at`'s bits for arc lengths in order, out of order, at and
    /// beyond the ends, -0 and NaN; and falls back to it where arc lengths repeat.
    #[test]
    fn point_at_walk_is_point_at() {
        let ring: Vec<DVec2> = (0..=120).map(|i| DVec2::from_angle(i as f64 * 0.05) * 18.0).collect();
        let mut repeated = ring.clone();
        repeated.insert(40, repeated[40]);
        let mut asks: Vec<f64> = (0..=300).map(|k| k as f64 * 0.37 - 3.0).collect();
        asks.extend([5.0, 2.5, 200.0, -0.0, 0.0, f64::NAN, -f64::NAN, 40.0, 18.0 * 0.05 * 7.0, 1e300, -1e300]);
        for pts in [ring, repeated, vec![DVec2::ZERO, DVec2::X], vec![DVec2::ONE], vec![]] {
            let l = Polyline::new(pts);
            let strict = l.strictly_increasing();
            let mut seg = None;
            for &s in &asks {
                let (a, b) = (l.point_at(s), l.point_at_walk(s, &mut seg, strict));
                assert_eq!((a.x.to_bits(), a.y.to_bits()), (b.x.to_bits(), b.y.to_bits()), "{s}");
            }
        }
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
