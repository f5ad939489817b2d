//! One resampling per route, shared by every agent on it: the grid of samples a `Path` reads
//! up to its cut.

use super::{Path, STEP, run_end, straight_runs};
use crate::geom::wrap_angle;
use glam::DVec2;
use std::rc::Rc;

/// The resampling of one chain of points, kept to share among every agent on that chain: the
/// samples at multiples of `STEP`, with their headings and tangents (the trigonometry, most of a
/// path's cost), are the same bits whatever length an agent keeps, so they are computed once,
/// as far as the farthest-reaching agent needs, and read in place by every path; only each
/// path's last samples, which depend on where it ends, are its own.
#[derive(Clone, Debug, Default)]
pub struct Resampler {
    /// The chain without consecutive duplicates, and the arc length at each of its points.
    pts_in: Vec<DVec2>,
    cum: Vec<f64>,
    total: f64,
    /// Chain segment of the last grid sample (segments are searched forward from it).
    seg: usize,
    /// Shared with the paths made so far; growing it copies it only while one holds it.
    grid: Rc<Grid>,
    /// The straight runs of the grid samples with a tangent, as `straight_runs` splits them,
    /// each ended by a sample that has one (so more samples cannot change it); then the start of
    /// the next run and the last sample known to be on it.
    runs: Vec<(u32, u32)>,
    open: (usize, usize),
}

#[derive(Clone, Debug, Default)]
pub(super) struct Grid {
    /// The sample at `k * STEP` for every `k` computed so far.
    pub(super) pts: Vec<DVec2>,
    /// Heading and unit tangent at grid sample `i`, for every `i` whose central difference reads
    /// grid samples only (`i + 2 < pts.len()`).
    pub(super) heading: Vec<f64>,
    pub(super) tangent: Vec<DVec2>,
    /// Curvature at grid sample `i` for every `i` whose difference reads shared headings only
    /// (`i + HEADING_W < heading.len()`), as `path` computes it.
    pub(super) curvature: Vec<f64>,
}

/// Half-width of the central difference for headings, in samples: polylines from templates have
/// corners at their vertices, and an agent's yaw must not jump there.
const HEADING_W: usize = 2;

impl Resampler {
    pub fn new(points: &[DVec2]) -> Resampler {
        let mut cum = Vec::with_capacity(points.len());
        let mut pts_in: Vec<DVec2> = Vec::with_capacity(points.len());
        let mut acc = 0.0;
        for &p in points {
            if let Some(&last) = pts_in.last() {
                let d = p.distance(last);
                if d < 1e-6 {
                    continue;
                }
                acc += d;
            }
            pts_in.push(p);
            cum.push(acc);
        }
        Resampler { pts_in, cum, total: acc, ..Resampler::default() }
    }

    /// The chain point at arc length `s` on segment `seg`.
    fn point_on(&self, seg: usize, s: f64) -> DVec2 {
        let (a, b) = (self.pts_in[seg], self.pts_in[seg + 1]);
        let len = self.cum[seg + 1] - self.cum[seg];
        let t = if len > 0.0 { ((s - self.cum[seg]) / len).clamp(0.0, 1.0) } else { 0.0 };
        a + (b - a) * t
    }

    /// Grow the grid to at least `n` samples, with the headings and tangents that those
    /// determine. Paths made before hold the grid: it then grows by half again at least (within
    /// the chain), so that agents asking for a little more each do not copy it each.
    fn extend(&mut self, n: usize) {
        if self.grid.pts.len() >= n {
            return;
        }
        let whole = (self.total / STEP).floor() as usize + 1;
        let n = if Rc::strong_count(&self.grid) > 1 { n.max((self.grid.pts.len() * 3 / 2).min(whole)) } else { n };
        let grid = Rc::make_mut(&mut self.grid);
        if grid.pts.capacity() < n {
            // Later agents on the route may ask for more: room for the whole route (or twice this
            // request on a long one) at once, not a copy per growth.
            let cap = (whole + 1).min(2 * n).max(n);
            grid.pts.reserve_exact(cap - grid.pts.len());
            grid.heading.reserve_exact(cap - grid.heading.len());
            grid.tangent.reserve_exact(cap - grid.tangent.len());
        }
        while grid.pts.len() < n {
            let s = grid.pts.len() as f64 * STEP;
            while self.seg + 2 < self.cum.len() && self.cum[self.seg + 1] < s {
                self.seg += 1;
            }
            let (a, b) = (self.pts_in[self.seg], self.pts_in[self.seg + 1]);
            let len = self.cum[self.seg + 1] - self.cum[self.seg];
            let t = if len > 0.0 { ((s - self.cum[self.seg]) / len).clamp(0.0, 1.0) } else { 0.0 };
            grid.pts.push(a + (b - a) * t);
        }
        let g = grid.pts.len();
        // Straight stretches repeat a few differences and headings bit for bit (a line at an
        // angle alternates between neighbouring floats): the arctangent and the sine and cosine
        // of one seen among the last `RECENT` are reused, the same calls on the same bits.
        let mut seen = Recent::default();
        while grid.heading.len() + HEADING_W < g {
            let i = grid.heading.len();
            let d = grid.pts[i + HEADING_W] - grid.pts[i.saturating_sub(HEADING_W)];
            let (h, t) = seen.heading(d);
            grid.heading.push(h);
            grid.tangent.push(t);
        }
        let w = HEADING_W;
        while grid.curvature.len() + w < grid.heading.len() {
            let i = grid.curvature.len();
            let (a, b) = (i.saturating_sub(w), i + w);
            let k = wrap_angle(grid.heading[b] - grid.heading[a]) / ((b - a) as f64 * STEP);
            grid.curvature.push(k);
        }
        let (mut start, mut end) = self.open;
        let m = grid.pts.len().min(grid.tangent.len());
        while start < grid.tangent.len() {
            match run_end(|k| (grid.pts[k], grid.tangent[k]), m, start, end.max(start)) {
                Ok(e) => {
                    self.runs.push((start as u32, e as u32));
                    (start, end) = (e + 1, e + 1);
                }
                Err(e) => {
                    end = e;
                    break;
                }
            }
        }
        self.open = (start, end);
    }

    /// The path of the chain's first `until` metres (`Path::new_until`).
    pub fn path(&mut self, until: f64) -> Path {
        if self.pts_in.len() < 2 {
            let p = self.pts_in.first().copied().unwrap_or(DVec2::ZERO);
            return Path {
                grid: Rc::default(),
                cut: 0,
                pts: vec![p, p],
                heading: vec![0.0; 2],
                tangent: vec![DVec2::X; 2],
                curvature: vec![0.0; 2],
                cap: vec![f64::INFINITY; 2],
                run: vec![(0, 1); 2],
            };
        }
        let acc = self.total.min(until.max(2.0 * STEP));
        // Samples `..n` lie on the grid (k * STEP <= acc); the last one is the end, at `acc`.
        let n = (acc / STEP).floor() as usize + 1;
        self.extend(n);
        let grid = &*self.grid;
        let seg = self.cum[1..].partition_point(|&c| c < acc).min(self.cum.len() - 2);
        let end = self.point_on(seg, acc);
        let m = n + 1;
        let w = HEADING_W;
        // Headings whose central difference reaches the end sample are this path's own.
        let shared = (m - 1).saturating_sub(w).min(grid.heading.len());
        // Samples `..shared` of this path are the grid's, with its headings and tangents: a
        // curvature reading only those (its difference ends below `shared`), and a straight run
        // whose ending test read only those, are the grid's too. Samples from `cut` on are the
        // path's own copies.
        let own = shared.saturating_sub(w);
        let cut = own;
        let pt = |i: usize| if i < n { grid.pts[i] } else { end };
        let mut heading = Vec::with_capacity(m - cut);
        let mut tangent = Vec::with_capacity(m - cut);
        heading.extend_from_slice(&grid.heading[cut..shared]);
        tangent.extend_from_slice(&grid.tangent[cut..shared]);
        for i in shared..m {
            let d = pt((i + w).min(m - 1)) - pt(i.saturating_sub(w));
            let h = d.y.atan2(d.x);
            let last = if i > 0 {
                Some((head_at(grid, cut, &heading, i - 1), tan_at(grid, cut, &tangent, i - 1)))
            } else {
                None
            };
            let t = match last {
                Some((lh, lt)) if f64::to_bits(lh) == h.to_bits() => lt,
                _ => DVec2::from_angle(h),
            };
            heading.push(h);
            tangent.push(t);
        }
        let curvature: Vec<f64> = (own..m)
            .map(|i| {
                let (a, b) = (i.saturating_sub(w), (i + w).min(m - 1));
                if b > a {
                    wrap_angle(head_at(grid, cut, &heading, b) - head_at(grid, cut, &heading, a))
                        / ((b - a) as f64 * STEP)
                } else {
                    0.0
                }
            })
            .collect();
        let settled = self.runs.partition_point(|&(_, b)| (b as usize + 1) < shared);
        let next = self.runs.get(settled).map_or(self.open, |&(a, b)| (a as usize, b as usize));
        let known = (next.0 < shared).then(|| (next.0, next.1.min(shared - 1)));
        let run = straight_runs(|k| (pt(k), tan_at(grid, cut, &tangent, k)), m, &self.runs[..settled], known);
        let pts = (cut..m).map(pt).collect();
        Path { grid: Rc::clone(&self.grid), cut, pts, heading, tangent, curvature, cap: vec![f64::INFINITY; m], run }
    }
}

/// How many of the last distinct differences `Recent` remembers.
const RECENT: usize = 8;

/// The last `RECENT` distinct sample differences met (by their bits), with the heading and unit
/// tangent of each: `d.y.atan2(d.x)` and `DVec2::from_angle` of it.
#[derive(Default)]
struct Recent {
    keys: [(u64, u64); RECENT],
    vals: [(f64, DVec2); RECENT],
    len: usize,
    next: usize,
}

impl Recent {
    #[inline]
    fn heading(&mut self, d: DVec2) -> (f64, DVec2) {
        let key = (d.x.to_bits(), d.y.to_bits());
        if let Some(k) = self.keys[..self.len].iter().position(|&x| x == key) {
            return self.vals[k];
        }
        let h = d.y.atan2(d.x);
        // A new difference may still give a heading met before (its sine and cosine too).
        let t = match self.vals[..self.len].iter().find(|v| v.0.to_bits() == h.to_bits()) {
            Some(v) => v.1,
            None => DVec2::from_angle(h),
        };
        self.keys[self.next] = key;
        self.vals[self.next] = (h, t);
        self.next = (self.next + 1) % RECENT;
        self.len = (self.len + 1).min(RECENT);
        (h, t)
    }
}

/// Heading of sample `i` of a path being made: the grid's below `cut`, else its own (`own[i - cut]`).
#[inline(always)]
fn head_at(grid: &Grid, cut: usize, own: &[f64], i: usize) -> f64 {
    if i < cut { grid.heading[i] } else { own[i - cut] }
}

#[inline(always)]
fn tan_at(grid: &Grid, cut: usize, own: &[DVec2], i: usize) -> DVec2 {
    if i < cut { grid.tangent[i] } else { own[i - cut] }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rollout::path::tests::{bits, full};

    #[test]
    fn shared_resampling_is_bitwise_the_own_one() {
        let mut pts = vec![DVec2::new(-40.0, 2.0), DVec2::new(0.0, 2.0)];
        pts.extend((1..=30).map(|i| DVec2::new(0.0, 32.0) + DVec2::from_angle(-1.4 + i as f64 * 0.05) * 30.0));
        pts.push(*pts.last().unwrap() + DVec2::new(-25.0, 60.0));
        let untils = [55.3, 0.2, 12.0, 150.0, 1e9, 55.3, 3.7, 90.25, 1.0, 60.0, 61.0, 62.5, 140.0];
        let sorted = {
            let mut u = untils.to_vec();
            u.sort_by(f64::total_cmp);
            u
        };
        for order in [untils.to_vec(), untils.iter().rev().copied().collect(), sorted] {
            let mut shared = Resampler::new(&pts);
            // Paths kept while later ones grow the grid they read (copied then, and grown ahead).
            let mut kept = vec![];
            for &u in &order {
                let (a, b) = (shared.path(u), Resampler::new(&pts).path(u));
                assert_eq!(bits(&a), bits(&b), "until {u}");
                kept.push((u, a.clone()));
                assert!(a.length() > 0.0);
                // The curvature and runs taken from the grid are those of the path's own samples.
                let (pts, heading, tangent, curv) = full(&a);
                let m = pts.len();
                let curvature: Vec<u64> = (0..m)
                    .map(|i| {
                        let (lo, hi) = (i.saturating_sub(HEADING_W), (i + HEADING_W).min(m - 1));
                        let k = if hi > lo {
                            wrap_angle(heading[hi] - heading[lo]) / ((hi - lo) as f64 * STEP)
                        } else {
                            0.0
                        };
                        k.to_bits()
                    })
                    .collect();
                assert_eq!(curv.iter().map(|k| k.to_bits()).collect::<Vec<_>>(), curvature, "until {u}");
                assert_eq!(a.run, straight_runs(|k| (pts[k], tangent[k]), m, &[], None), "until {u}");
            }
            for (u, a) in &kept {
                assert_eq!(bits(a), bits(&Resampler::new(&pts).path(*u)), "kept, until {u}");
            }
        }
    }
}
