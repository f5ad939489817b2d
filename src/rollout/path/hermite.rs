//! The Hermite curve a striker's intercept follows to its contact pose.

use crate::geom::wrap_angle;
use glam::DVec2;

/// A cubic Hermite curve sampled by arc length: the intercept path of an at-fault agent.
pub struct Hermite {
    pts: [DVec2; HN + 1],
    cum: [f64; HN + 1],
}

const HN: usize = 24;

/// The four cubic Hermite basis polynomials at each sample `u = i / HN`, the same for every
/// curve (`plan::choose` builds some 150 per conflict, the intercept one per frame).
const HERMITE_BASIS: [[f64; 4]; HN + 1] = hermite_basis();

const fn hermite_basis() -> [[f64; 4]; HN + 1] {
    let mut b = [[0.0; 4]; HN + 1];
    let mut i = 0;
    while i <= HN {
        let u = i as f64 / HN as f64;
        let (u2, u3) = (u * u, u * u * u);
        b[i] = [2.0 * u3 - 3.0 * u2 + 1.0, u3 - 2.0 * u2 + u, -2.0 * u3 + 3.0 * u2, u3 - u2];
        i += 1;
    }
    b
}

impl Hermite {
    pub fn new(p0: DVec2, yaw0: f64, p1: DVec2, yaw1: f64) -> Hermite {
        Hermite::with_dirs(p0, DVec2::from_angle(yaw0), p1, DVec2::from_angle(yaw1))
    }

    /// `new` given the unit headings `DVec2::from_angle(yaw0)` and `DVec2::from_angle(yaw1)`.
    pub fn with_dirs(p0: DVec2, dir0: DVec2, p1: DVec2, dir1: DVec2) -> Hermite {
        let k = p0.distance(p1).max(0.5);
        let (t0, t1) = (dir0 * k, dir1 * k);
        let mut pts = [DVec2::ZERO; HN + 1];
        let mut cum = [0.0; HN + 1];
        for (q, [b0, b1, b2, b3]) in pts.iter_mut().zip(HERMITE_BASIS) {
            *q = p0 * b0 + t0 * b1 + p1 * b2 + t1 * b3;
        }
        for i in 1..=HN {
            cum[i] = cum[i - 1] + pts[i].distance(pts[i - 1]);
        }
        Hermite { pts, cum }
    }

    pub fn length(&self) -> f64 {
        self.cum[HN]
    }

    /// Position and heading at arc length `s`; beyond the end it continues straight.
    pub fn at(&self, s: f64, end_yaw: f64) -> (DVec2, f64) {
        if s >= self.cum[HN] {
            return (self.pts[HN] + DVec2::from_angle(end_yaw) * (s - self.cum[HN]), end_yaw);
        }
        let i = self.cum.partition_point(|&c| c <= s).clamp(1, HN) - 1;
        let seg = self.cum[i + 1] - self.cum[i];
        let t = if seg > 0.0 { (s - self.cum[i]) / seg } else { 0.0 };
        let d = self.pts[i + 1] - self.pts[i];
        (self.pts[i].lerp(self.pts[i + 1], t), d.y.atan2(d.x))
    }

    /// Largest curvature along the curve (1/m).
    pub fn max_curvature(&self) -> f64 {
        // Each segment's direction and length once: every inner sample reads two segments
        // (`plan::choose` asks this of some 150 curves per conflict).
        let mut dir = [0.0; HN];
        let mut len = [0.0; HN];
        for (i, (d, l)) in dir.iter_mut().zip(&mut len).enumerate() {
            let seg = self.pts[i + 1] - self.pts[i];
            (*d, *l) = (seg.y.atan2(seg.x), seg.length());
        }
        let mut k: f64 = 0.0;
        for i in 1..HN {
            let ds = 0.5 * (len[i - 1] + len[i]);
            if ds > 1e-6 {
                k = k.max(wrap_angle(dir[i] - dir[i - 1]).abs() / ds);
            }
        }
        k
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `max_curvature` computes each segment once; its value must be the bits of the turn
    /// between neighbouring segments over their mean length, taken sample by sample.
    #[test]
    fn hermite_curvature_is_the_per_sample_one() {
        let curves = [
            Hermite::new(DVec2::ZERO, 0.0, DVec2::new(30.0, 3.0), 0.0),
            Hermite::new(DVec2::new(5.0, -2.0), 1.2, DVec2::new(-8.0, 14.0), -2.9),
            Hermite::new(DVec2::new(1.0, 1.0), 0.3, DVec2::new(1.0, 1.0), 0.3),
            Hermite::new(DVec2::ZERO, 3.1, DVec2::new(0.4, 0.1), -3.1),
        ];
        for h in &curves {
            let mut want: f64 = 0.0;
            for i in 1..HN {
                let (a, b) = (h.pts[i] - h.pts[i - 1], h.pts[i + 1] - h.pts[i]);
                let ds = 0.5 * (a.length() + b.length());
                if ds > 1e-6 {
                    want = want.max(wrap_angle(b.y.atan2(b.x) - a.y.atan2(a.x)).abs() / ds);
                }
            }
            assert_eq!(h.max_curvature().to_bits(), want.to_bits());
        }
        assert!(curves[1].max_curvature() > 0.05);
    }

    /// The basis table is evaluated at compile time: it must hold the bits the same formulas give
    /// at run time (what keeps the curves, and so the crashes, bit for bit).
    #[test]
    fn hermite_basis_is_the_run_time_one() {
        for (i, b) in HERMITE_BASIS.iter().enumerate() {
            let u = std::hint::black_box(i as f64) / HN as f64;
            let (u2, u3) = (u * u, u * u * u);
            let want = [2.0 * u3 - 3.0 * u2 + 1.0, u3 - 2.0 * u2 + u, -2.0 * u3 + 3.0 * u2, u3 - u2];
            assert_eq!(b.map(f64::to_bits), want.map(f64::to_bits), "sample {i}");
        }
    }

    #[test]
    fn hermite_ends_where_asked() {
        let h = Hermite::new(DVec2::ZERO, 0.0, DVec2::new(30.0, 3.0), 0.0);
        let (p, _) = h.at(h.length(), 0.0);
        assert!(p.distance(DVec2::new(30.0, 3.0)) < 1e-9);
        assert!(h.max_curvature() < 0.05);
    }
}
