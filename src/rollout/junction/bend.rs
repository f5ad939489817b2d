//! A vehicle's sweep through its first junction, as its dry run found it (`Bend`), and the
//! questions asked of it every frame: how far its box reaches beyond its lane band, whether its
//! boxes meet another box.

use crate::geom::{Obb, wrap_angle};
use glam::DVec2;

/// How far a vehicle's box reaches beyond the band its path's centre sweeps through its first
/// junction, metre by metre along its route (`assign_bends`): a U-turn driven wide on an
/// ambulance's turning radius loops out 10 m and more at its apex, far beyond what the path's
/// curvature says, and not at all past it.
#[derive(Clone, Debug)]
pub(crate) struct Bend {
    /// Route arc length of the first metre.
    pub from: f64,
    /// Per metre from `from`: the reach to the right and to the left.
    pub reach: Vec<(f64, f64)>,
    /// The widest reach to either side anywhere, at least the corners' swing in the tightest
    /// bend (`sweep`).
    pub widest: f64,
    /// The box stretched over its reach, a metre of path each, where it reaches beyond the band
    /// (`sweep_entry`), and their bounding box (lower and upper corners).
    pub slices: Vec<(f64, Obb)>,
    pub bounds: (DVec2, DVec2),
    /// `reach`'s widest over every run of `2^k` metres from each metre, for `k` from 1
    /// (`index`): `within` is asked per agent per frame over up to the look-ahead.
    pub spans: Vec<Vec<(f64, f64)>>,
    /// The run's box centre, step by step: route arc length, position, heading (`Bend::pose`).
    pub poses: Vec<(f64, DVec2, f64)>,
    /// The bounding box of the run's boxes (lower and upper corners; `touches`).
    pub run_bounds: (DVec2, DVec2),
}

impl Bend {
    /// The widest reach to the right and to the left between route arc lengths `lo` and `hi`.
    pub(crate) fn within(&self, lo: f64, hi: f64) -> (f64, f64) {
        let Some((a, b)) = self.metres(lo, hi) else { return (0.0, 0.0) };
        // The widest of a set of reaches is the same number whatever the order it is taken in
        // (each is 0 or above, never NaN): two overlapping spans cover the range.
        let k = (b - a + 1).ilog2() as usize;
        if k == 0 || k > self.spans.len() {
            return self.reach[a..=b].iter().fold((0.0, 0.0), |(r, l), &(x, y)| (f64::max(r, x), f64::max(l, y)));
        }
        let t = &self.spans[k - 1];
        let ((r0, l0), (r1, l1)) = (t[a], t[b + 1 - (1 << k)]);
        let widest = (f64::max(f64::max(0.0, r0), r1), f64::max(f64::max(0.0, l0), l1));
        debug_assert_eq!(
            widest,
            self.reach[a..=b].iter().fold((0.0, 0.0), |(r, l), &(x, y)| (f64::max(r, x), f64::max(l, y)))
        );
        widest
    }

    /// The indices into `reach` of the metres covering route arc lengths `lo` to `hi`, if any.
    pub(crate) fn metres(&self, lo: f64, hi: f64) -> Option<(usize, usize)> {
        let last = self.reach.len() as f64 - 1.0;
        // `max` and `min` take the number over a NaN: a and b are never NaN.
        let (a, b) = ((lo - self.from).floor().max(0.0), (hi - self.from).ceil().min(last));
        (a <= b).then_some((a as usize, b as usize))
    }

    /// Fill `spans` from `reach`.
    pub(crate) fn index(&mut self) {
        self.spans.clear();
        let mut h = 1;
        while 2 * h <= self.reach.len() {
            let prev = self.spans.last().unwrap_or(&self.reach);
            let next: Vec<(f64, f64)> = (0..=prev.len() - 1 - h)
                .map(|i| (f64::max(prev[i].0, prev[i + h].0), f64::max(prev[i].1, prev[i + h].1)))
                .collect();
            self.spans.push(next);
            h *= 2;
        }
    }

    /// The box centre's pose in the run where its centre is at route arc length `s`, `None`
    /// outside the run.
    pub(crate) fn pose(&self, s: f64) -> Option<(DVec2, f64)> {
        let k = self.poses.partition_point(|q| q.0 <= s);
        let (p, q) = (self.poses.get(k.checked_sub(1)?)?, self.poses.get(k)?);
        let t = (s - p.0) / (q.0 - p.0);
        Some((p.1.lerp(q.1, t), p.2 + wrap_angle(q.2 - p.2) * t))
    }

    /// The first route arc length from `lo` to `hi` at which the run's box (half length `hl`,
    /// half width `hw`: the vehicle whose run it is) meets `theirs`, at the run's steps.
    pub(crate) fn touches(&self, (hl, hw): (f64, f64), theirs: &Obb, lo: f64, hi: f64) -> Option<f64> {
        if clear_of(self.run_bounds, theirs) {
            return None;
        }
        let k = self.poses.partition_point(|q| q.0 < lo);
        let (length, width) = (2.0 * hl, 2.0 * hw);
        let reach = 0.5 * (length.hypot(width) + theirs.length.hypot(theirs.width));
        self.poses[k..]
            .iter()
            .take_while(|q| q.0 <= hi)
            .filter(|q| q.1.distance_squared(theirs.center) < reach * reach)
            .find(|q| Obb { center: q.1, yaw: q.2, length, width }.overlaps(theirs))
            .map(|q| q.0)
    }

    /// The route arc length of the first metre from `lo` to `hi` whose slice meets `theirs`.
    pub(crate) fn meets(&self, theirs: &Obb, lo: f64, hi: f64) -> Option<f64> {
        if clear_of(self.bounds, theirs) {
            return None;
        }
        let (c, r) = (theirs.center, 0.5 * theirs.length.hypot(theirs.width));
        let near = |q: &Obb| {
            let rq = r + 0.5 * q.length.hypot(q.width);
            q.center.distance_squared(c) < rq * rq
        };
        let (at, _) = self.slices.iter().find(|(s, q)| *s + 1.0 > lo && *s < hi && near(q) && q.overlaps(theirs))?;
        Some(*at)
    }
}

/// Whether box `theirs`, within its circumscribed circle, lies wholly outside the axis-aligned
/// `(lower, upper)` corners `bounds`: then nothing inside them can meet it.
pub(crate) fn clear_of((min, max): (DVec2, DVec2), theirs: &Obb) -> bool {
    let (c, r) = (theirs.center, 0.5 * theirs.length.hypot(theirs.width));
    c.x + r < min.x || c.x - r > max.x || c.y + r < min.y || c.y - r > max.y
}

/// How far a box is grown all round where it is tested against a dry run's boxes
/// (`first_contact`, `Bend::touches`): a vehicle driven at other speeds than its dry run's
/// steers a few centimetres off it, and a bus's tail, clearing a car standing beside its turn by
/// a centimetre in the run, met it in the drive.
pub(crate) const SWEEP_MARGIN: f64 = 0.3;

/// `SWEEP_MARGIN` for the sweep's slices (`Bend::slices`), which already stretch each metre's
/// box over the widest reach there.
pub(crate) const SLICE_MARGIN: f64 = 0.1;
