//! Agent routes: the lane, connector and out-lane polylines an agent will drive, joined and
//! resampled at a fixed step so that every lookup in the per-frame loop is O(1).

use crate::geom::wrap_angle;
use glam::DVec2;
use std::rc::Rc;

mod hermite;
mod resample;

pub use hermite::Hermite;
use resample::Grid;
pub use resample::Resampler;

/// Sample spacing of a resampled path, m. Fine enough that linear interpolation between samples
/// is indistinguishable from the source polylines at BEV resolution (0.25 m).
pub const STEP: f64 = 0.5;

/// A path's samples: `..cut` read from the grid its route shares with every agent on it (`Grid`,
/// not copied per agent), `cut..` its own (its end, and the differences that reach it).
#[derive(Clone, Debug, Default)]
pub struct Path {
    grid: Rc<Grid>,
    cut: usize,
    pts: Vec<DVec2>,
    heading: Vec<f64>,
    /// Unit tangents (the headings as vectors), so projections need no trigonometry.
    tangent: Vec<DVec2>,
    curvature: Vec<f64>,
    /// Per sample, every one: the highest speed that still lets the agent slow for the curves
    /// ahead.
    cap: Vec<f64>,
    /// Per sample: the first and last sample of the straight run holding it (samples on one
    /// line with one tangent, split greedily from the start), for `Path::straight_run`.
    run: Vec<(u32, u32)>,
}

/// Where a point lies in a path's frame (`Path::frenet` and its kin): the arc length of its foot,
/// its offset to the left, how far beyond either end of the path it lies (0 alongside it), and the
/// path's direction at the foot (`T`: the heading angle, the unit tangent, or nothing).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Foot<T> {
    pub s: f64,
    pub d: f64,
    pub beyond: f64,
    pub dir: T,
}

/// A straight stretch of a path: on it, `Path::frenet_dir` from a guess inside the stretch ends
/// (to float noise) at the point's projection onto the line, so pair checks can bound an agent's
/// path coordinates without running it.
#[derive(Clone, Copy, Debug)]
pub struct Line {
    /// The point of the line at arc length `s0`.
    pub origin: DVec2,
    pub s0: f64,
    /// Unit tangent.
    pub dir: DVec2,
    /// Arc lengths strictly between which the stretch is straight (kept 0.1 m inside its end
    /// samples, so every interpolation there reads samples of the stretch).
    pub lo: f64,
    pub hi: f64,
}

/// How far a sample may lie off its run's line, m, and its tangent differ from the run's, for
/// the run to count as straight: far below the pair checks' 1 mm safety margin.
const RUN_TOL: f64 = 1e-9;

/// The last sample of the straight run starting at `start` (greedy: while the next sample is on
/// the run's line with its tangent), given that samples `start..=end` are on it: `Ok` when the
/// sample after it is not, `Err` (the last sample) when the samples run out first, where more
/// samples could extend it. Reads samples `start..=` the returned one + 1.
/// `at(k)` is sample `k`'s point and tangent, for `k < m`.
fn run_end(at: impl Fn(usize) -> (DVec2, DVec2), m: usize, start: usize, mut end: usize) -> Result<usize, usize> {
    let (p0, t0) = at(start);
    while end + 1 < m {
        let (p, t) = at(end + 1);
        if !((t - t0).abs().max_element() < RUN_TOL && t0.perp_dot(p - p0).abs() < RUN_TOL * (1.0 + (p - p0).length()))
        {
            return Ok(end);
        }
        end += 1;
    }
    Err(end)
}

/// Per sample, its straight run (`Path::run`), split greedily from the start. A resampler sharing
/// these samples gives its first runs (`settled`) and how far the next one is known to reach
/// (`known`: its start and a sample up to which it holds), so only the rest is tested.
fn straight_runs(
    at: impl Fn(usize) -> (DVec2, DVec2) + Copy,
    m: usize,
    settled: &[(u32, u32)],
    mut known: Option<(usize, usize)>,
) -> Vec<(u32, u32)> {
    let mut run = vec![(0u32, 0u32); m];
    let mut start = 0;
    for &(a, b) in settled {
        run[a as usize..=b as usize].fill((a, b));
        start = b as usize + 1;
    }
    while start < m {
        let from = match known.take() {
            Some((a, e)) if a == start => e,
            _ => start,
        };
        let (Ok(end) | Err(end)) = run_end(at, m, start, from);
        run[start..=end].fill((start as u32, end as u32));
        start = end + 1;
    }
    run
}

impl Path {
    /// Resample a chain of points (consecutive duplicates allowed) at `STEP`.
    pub fn new(points: &[DVec2]) -> Path {
        Path::new_until(points, f64::INFINITY)
    }

    /// `new`, keeping only the first `until` metres: a route is chained far beyond what an agent
    /// can reach within a clip, and resampling all of it dominated the rollout's set-up.
    pub fn new_until(points: &[DVec2], until: f64) -> Path {
        Resampler::new(points).path(until)
    }

    /// A straight path from `p` along `yaw`.
    pub fn straight(p: DVec2, yaw: f64, length: f64) -> Path {
        Path::new(&[p, p + DVec2::from_angle(yaw) * length.max(1.0)])
    }

    /// Fill the curve speed cap: `lat_acc` bounds v^2 * curvature, `yaw_rate` bounds
    /// v * curvature, and braking at `decel` from any
    /// sample must reach the cap of every sample ahead.
    pub fn set_caps(&mut self, lat_acc: f64, yaw_rate: f64, decel: f64) {
        // Each sample's own cap first: independent of its neighbours, so this loop pipelines;
        // only the braking recursion below is a chain.
        let curvature = self.grid.curvature[..self.cut].iter().chain(&self.curvature);
        for (c, k) in self.cap.iter_mut().zip(curvature) {
            let k = k.abs();
            *c = if k > 1e-4 { (lat_acc / k).sqrt().min(yaw_rate / k) } else { f64::INFINITY };
        }
        let grow = 2.0 * decel * STEP;
        // From the end back to the last curve the braking term is infinite (inf * inf + grow is
        // inf for any grow above -inf, and so is its root): that stretch skips the square root,
        // same bits. (A branch inside the chain loop is compiled to a select that takes the root
        // anyway, hence two loops.)
        let mut next = f64::INFINITY;
        let mut i = self.cap.len();
        while i > 0 && next == f64::INFINITY && grow > f64::NEG_INFINITY {
            i -= 1;
            next = self.cap[i].min(f64::INFINITY);
            self.cap[i] = next;
        }
        for c in self.cap[..i].iter_mut().rev() {
            next = c.min((next * next + grow).sqrt());
            *c = next;
        }
    }

    pub fn length(&self) -> f64 {
        (self.len() - 1) as f64 * STEP
    }

    /// An identity of the samples `at` reads for every arc length up to `hi`, where they are all
    /// the route's shared ones (below `cut`, short of the end, so no clamp differs between
    /// paths): the address of the route's grid. Paths held at the same time giving the same key
    /// give the same `at(s)` for every `s <= hi`, bit for bit (a grid is not changed while a path
    /// holds it: the resampler copies it to grow it).
    pub fn shared_upto(&self, hi: f64) -> Option<usize> {
        (hi / STEP + 2.0 <= self.cut as f64).then_some(Rc::as_ptr(&self.grid) as usize)
    }

    /// Number of samples.
    #[inline]
    fn len(&self) -> usize {
        self.cut + self.pts.len()
    }

    /// Sample `i` of a per-sample array: the route's shared one below `cut`, our own tail above.
    #[inline(always)]
    fn pick<T: Copy>(&self, i: usize, shared: &[T], own: &[T]) -> T {
        if i < self.cut { shared[i] } else { own[i - self.cut] }
    }

    /// Samples `i` and `i + 1` of a per-sample array: one test for where they lie, and one
    /// bounds check, where both are the route's (most reads).
    #[inline(always)]
    fn pick2<T: Copy>(&self, i: usize, shared: &[T], own: &[T]) -> (T, T) {
        if i + 1 < self.cut {
            let w = &shared[i..i + 2];
            (w[0], w[1])
        } else {
            (self.pick(i, shared, own), self.pick(i + 1, shared, own))
        }
    }

    #[inline(always)]
    fn pt(&self, i: usize) -> DVec2 {
        self.pick(i, &self.grid.pts, &self.pts)
    }

    #[inline(always)]
    fn head(&self, i: usize) -> f64 {
        self.pick(i, &self.grid.heading, &self.heading)
    }

    #[inline(always)]
    fn tan(&self, i: usize) -> DVec2 {
        self.pick(i, &self.grid.tangent, &self.tangent)
    }

    #[inline(always)]
    fn curv(&self, i: usize) -> f64 {
        self.pick(i, &self.grid.curvature, &self.curvature)
    }

    #[inline(always)]
    fn locate(&self, s: f64) -> (usize, f64) {
        // Through i64, not usize: the same values (below 2^63), but one instruction each way on
        // x86-64 where unsigned conversions take several, on the projections' dependent chain.
        let last = self.len() - 1;
        let x = (s / STEP).clamp(0.0, last as i64 as f64);
        let i = (x as i64 as usize).min(last - 1);
        (i, x - i as i64 as f64)
    }

    /// Position and heading at arc length `s` (clamped to the ends).
    #[inline]
    pub fn at(&self, s: f64) -> (DVec2, f64) {
        let (i, t) = self.locate(s);
        let p = self.pt(i).lerp(self.pt(i + 1), t);
        let h = self.head(i) + wrap_angle(self.head(i + 1) - self.head(i)) * t;
        (p, h)
    }

    #[inline]
    pub fn cap(&self, s: f64) -> f64 {
        let (i, _) = self.locate(s);
        self.cap[i].min(self.cap[i + 1])
    }

    pub fn curvature(&self, s: f64) -> f64 {
        let (i, t) = self.locate(s);
        self.curv(i) * (1.0 - t) + self.curv(i + 1) * t
    }

    /// Point at `s` shifted `d` metres to the left.
    #[inline]
    pub fn point(&self, s: f64, d: f64) -> (DVec2, f64) {
        let (p, h) = self.at(s);
        (p + DVec2::from_angle(h).perp() * d, h)
    }

    /// `point` without the heading, and without trigonometry (interpolated unit tangents).
    #[inline]
    pub fn point_fast(&self, s: f64, d: f64) -> DVec2 {
        let (p, t) = self.at_vec(s);
        p + t.normalize_or(DVec2::X).perp() * d
    }

    /// `point_fast(s, 0.0)`, bit for bit, without normalising the tangent: scaled by zero, the
    /// unit tangent leaves only zeros whose signs are its components' (a positive finite factor
    /// keeps them), and `normalize_or` takes its fallback exactly where the squared length is
    /// not strictly between zero and infinity.
    #[inline]
    pub fn point_fast_on(&self, s: f64) -> DVec2 {
        let (p, t) = self.at_vec(s);
        let l2 = t.length_squared();
        let n = if l2 > 0.0 && l2 < f64::INFINITY { t } else { DVec2::X };
        p + n.perp() * 0.0
    }

    /// Arc length and left offset of `p`, searched from `guess` by Newton steps along the
    /// tangent (O(1), good near the guess), how far beyond either end `p` lies, and the path
    /// heading there.
    #[inline]
    pub fn frenet(&self, p: DVec2, guess: f64) -> Foot<f64> {
        let Foot { s, d, beyond, .. } = self.frenet_dir(p, guess);
        let (i, u) = self.locate(s);
        let h = self.head(i) + wrap_angle(self.head(i + 1) - self.head(i)) * u;
        Foot { s, d, beyond, dir: h }
    }

    /// `frenet` with the path's unit tangent instead of its heading angle (no trigonometry).
    #[inline]
    pub fn frenet_dir(&self, p: DVec2, guess: f64) -> Foot<DVec2> {
        self.newton(p, guess).0
    }

    /// `frenet_dir`, and how far `p` still lies along the tangent from the point found (about
    /// zero once the steps have settled).
    #[inline]
    fn newton(&self, p: DVec2, guess: f64) -> (Foot<DVec2>, f64) {
        let len = self.length();
        let mut s = guess.clamp(0.0, len);
        let mut along = 0.0;
        for _ in 0..4 {
            let (q, t) = self.at_vec(s);
            along = (p - q).dot(t);
            let ns = (s + along).clamp(0.0, len);
            let done = (ns - s).abs() < 0.02;
            s = ns;
            if done {
                break;
            }
        }
        let (q, t) = self.at_vec(s);
        let off = p - q;
        let beyond = if s <= 0.0 || s >= len { along.abs().min(off.dot(t).abs()) } else { 0.0 };
        let unit = t.normalize_or(DVec2::X);
        (Foot { s, d: off.dot(t.perp()), beyond, dir: unit }, off.dot(unit))
    }

    /// `frenet_dir`, unless its Newton steps have not settled (`p` still more than a metre
    /// along the tangent from the point found, as near a U-turn's loop, where every point has
    /// several feet on the path and the steps swing between the loop's legs, ending anywhere):
    /// then `p`'s feet on the stretch `[from, to]` are searched, and the first at or past
    /// `ahead` within `reach` to either side is taken, else the first within reach, else the
    /// nearest. A car standing inside our loop lies beside the leg we are on and ahead on the
    /// leg coming back: the one ahead is the one to brake for.
    #[inline]
    pub fn frenet_near(&self, p: DVec2, guess: f64, window: (f64, f64), ahead: f64, reach: f64) -> Foot<DVec2> {
        let (found, rest) = self.newton(p, guess);
        if found.beyond > 0.0 || rest.abs() <= 1.0 {
            return found;
        }
        self.feet(p, found, window, ahead, reach)
    }

    /// `frenet_near`'s search of the feet: rare, kept out of line so that the settled case
    /// stays as lean as `frenet_dir`.
    #[cold]
    #[inline(never)]
    fn feet(&self, p: DVec2, found: Foot<DVec2>, (from, to): (f64, f64), ahead: f64, reach: f64) -> Foot<DVec2> {
        let (from, to) = (from.max(0.0), to.min(self.length()));
        if to - from < STEP {
            return found;
        }
        // The feet: where the component of `p - q` along the tangent turns from ahead to behind
        // between two samples, and the stretch's ends where it points outward.
        let foot = |s: f64| {
            let (q, t) = self.at_vec(s);
            let t = t.normalize_or(DVec2::X);
            let off = p - q;
            (s, off.dot(t.perp()), off.dot(t), t)
        };
        let n = ((to - from) / STEP).ceil() as usize;
        // Feet are (arc length, left offset, along the tangent, unit tangent), taken in order of
        // arc length: the first within reach at or past `ahead`, the first within reach, and
        // the nearest.
        type Cand = (f64, f64, f64, DVec2);
        let (mut first_ahead, mut first, mut nearest): (Option<Cand>, Option<Cand>, Option<Cand>) = (None, None, None);
        let mut take = |cand: Cand| {
            if cand.1.abs() <= reach {
                if cand.0 >= ahead {
                    first_ahead.get_or_insert(cand);
                }
                first.get_or_insert(cand);
            }
            let dist = |c: &Cand| c.1.hypot(c.2);
            if nearest.as_ref().is_none_or(|b| dist(&cand) < dist(b)) {
                nearest = Some(cand);
            }
        };
        let mut prev = foot(from);
        if prev.2 < 0.0 {
            take(prev);
        }
        for k in 1..=n {
            let next = foot((from + k as f64 * STEP).min(to));
            if prev.2 > 0.0 && next.2 <= 0.0 {
                // Linear between the two samples, then one Newton step from there.
                let u = prev.2 / (prev.2 - next.2);
                let s0 = prev.0 + (next.0 - prev.0) * u;
                let f0 = foot(s0);
                take(foot((s0 + f0.2).clamp(prev.0, next.0)));
            }
            prev = next;
        }
        if prev.2 > 0.0 {
            take(prev);
        }
        match first_ahead.or(first).or(nearest) {
            Some((s, lat, along, t)) => {
                // An end of the stretch that is not an end of the path is no foot: `p` lies
                // beyond it as it would beyond the path's.
                let end = (s <= from && along < 0.0) || (s >= to && along > 0.0);
                Foot { s, d: lat, beyond: if end { along.abs() } else { 0.0 }, dir: t }
            }
            None => found,
        }
    }

    /// `frenet_dir` of each point from its guess, without the tangent: the searches run side by
    /// side, a Newton step of each per round, so that their dependent chains overlap. Each
    /// takes the steps `frenet_dir` takes on the same values (one that has converged waits,
    /// its step's result dropped), so each result is `frenet_dir`'s, bit for bit.
    #[inline]
    pub fn frenet_many<const N: usize>(&self, ps: [DVec2; N], guesses: [f64; N]) -> [Foot<()>; N] {
        let len = self.length();
        let mut s = guesses.map(|g| g.clamp(0.0, len));
        let mut along = [0.0; N];
        let mut live = [true; N];
        for _ in 0..4 {
            if !live.contains(&true) {
                break;
            }
            for k in 0..N {
                let (q, t) = self.at_vec(s[k]);
                let a = (ps[k] - q).dot(t);
                let ns = (s[k] + a).clamp(0.0, len);
                let done = (ns - s[k]).abs() < 0.02;
                if live[k] {
                    (along[k], s[k], live[k]) = (a, ns, !done);
                }
            }
        }
        std::array::from_fn(|k| {
            let (q, t) = self.at_vec(s[k]);
            let off = ps[k] - q;
            let beyond = if s[k] <= 0.0 || s[k] >= len { along[k].abs().min(off.dot(t).abs()) } else { 0.0 };
            Foot { s: s[k], d: off.dot(t.perp()), beyond, dir: () }
        })
    }

    /// The straight run of the path around arc length `s`, if `s` lies inside one at least a metre
    /// long.
    pub fn straight_run(&self, s: f64) -> Option<Line> {
        if self.run.len() < 2 {
            return None;
        }
        let (i, _) = self.locate(s);
        let (a, b) = self.run[i];
        let (lo, hi) = (a as f64 * STEP + 0.1, b as f64 * STEP - 0.1);
        if hi - lo < 1.0 || s <= lo || s >= hi {
            return None;
        }
        let a = a as usize;
        Some(Line { origin: self.pt(a), s0: a as f64 * STEP, dir: self.tan(a), lo, hi })
    }

    #[inline(always)]
    fn at_vec(&self, s: f64) -> (DVec2, DVec2) {
        let (i, u) = self.locate(s);
        let (p0, p1) = self.pick2(i, &self.grid.pts, &self.pts);
        let (t0, t1) = self.pick2(i, &self.grid.tangent, &self.tangent);
        (p0.lerp(p1, u), t0.lerp(t1, u))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path's samples, wherever they are kept: points, headings, tangents, curvature.
    pub(super) fn full(p: &Path) -> (Vec<DVec2>, Vec<f64>, Vec<DVec2>, Vec<f64>) {
        let m = p.len();
        (
            (0..m).map(|i| p.pt(i)).collect(),
            (0..m).map(|i| p.head(i)).collect(),
            (0..m).map(|i| p.tan(i)).collect(),
            (0..m).map(|i| p.curv(i)).collect(),
        )
    }

    /// Every field of a path as bits, for exact comparison.
    pub(super) fn bits(p: &Path) -> Vec<u64> {
        let v2 = |v: &[DVec2]| v.iter().flat_map(|q| [q.x.to_bits(), q.y.to_bits()]).collect::<Vec<_>>();
        let f = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let runs = p.run.iter().flat_map(|&(a, b)| [a as u64, b as u64]);
        let (pts, heading, tangent, curvature) = full(p);
        [v2(&pts), f(&heading), v2(&tangent), f(&curvature), f(&p.cap)].concat().into_iter().chain(runs).collect()
    }

    /// A resampler shared by agents reaching different distances, asked in any order, gives each
    /// the bits of a path resampled for it alone (what makes sharing invisible in the tracks).

    #[test]
    fn resampled_arc_keeps_length_heading_and_curvature() {
        let r = 20.0;
        let pts: Vec<DVec2> =
            (0..=90).map(|i| DVec2::from_angle(i as f64 / 90.0 * std::f64::consts::FRAC_PI_2) * r).collect();
        let p = Path::new(&pts);
        assert!((p.length() - r * std::f64::consts::FRAC_PI_2).abs() < 0.6);
        let (q, h) = p.at(10.0);
        assert!((q.length() - r).abs() < 0.05);
        assert!((wrap_angle(h - (q.y.atan2(q.x) + std::f64::consts::FRAC_PI_2))).abs() < 0.02);
        assert!((p.curvature(10.0) - 1.0 / r).abs() < 0.005);
        let Foot { s, d, beyond, .. } = p.frenet(q + DVec2::from_angle(h).perp() * 1.5, 6.0);
        assert!((s - 10.0).abs() < 0.05 && (d - 1.5).abs() < 0.05 && beyond == 0.0, "{s} {d}");
    }

    /// Near a U-turn's loop the Newton search may end anywhere, a point 18 m off reported a quarter
    /// metre off (tests/rollout-cases/ambulance-u-turn-crossing-car-off-loop.scn): `frenet_near`
    /// then finds the point's true feet, and of a point between the loop's legs it takes the foot
    /// ahead.
    #[test]
    fn frenet_near_settles_what_newton_does_not() {
        let r = 2.5;
        let mut pts: Vec<DVec2> = (0..=40).map(|k| DVec2::new(r, -40.0 + k as f64)).collect();
        pts.extend((1..36).map(|k| DVec2::from_angle(k as f64 * std::f64::consts::PI / 36.0) * r));
        pts.extend((0..=40).map(|k| DVec2::new(-r, -k as f64)));
        let p = Path::new(&pts);
        let len = p.length();
        let resid = |q: DVec2, f: Foot<DVec2>| (q - p.at_vec(f.s).0).dot(f.dir).abs();
        let far = DVec2::new(0.5, 20.0);
        let mut unsettled = 0;
        for k in 0..80 {
            let guess = 30.0 + k as f64 * 0.2;
            let newton = p.frenet_dir(far, guess);
            unsettled += usize::from(newton.beyond == 0.0 && resid(far, newton) > 1.0);
            let near = p.frenet_near(far, guess, (guess - 20.0, guess + 40.0), guess, 8.0);
            assert!(resid(far, near) < 0.05, "from {guess}: {near:?}");
            // None within reach: the nearest foot, the loop's apex 17.5 m below.
            assert!(near.beyond == 0.0 && (near.d.abs() - 17.5).abs() < 0.2, "from {guess}: {near:?}");
        }
        assert!(unsettled > 0, "no guess leaves Newton unsettled: the fallback is not exercised");
        // Between the legs, 5 m below the loop, seen from 2 m further up the leg coming in: the
        // foot on the leg going back out, not the one behind.
        let mid = DVec2::new(0.0, -5.0);
        let at = 38.0;
        let out_leg = 40.0 + std::f64::consts::PI * r;
        let mut unsettled = 0;
        for k in 0..80 {
            let guess = at + k as f64 * 0.1;
            let newton = p.frenet_dir(mid, guess);
            if resid(mid, newton) <= 1.0 {
                continue;
            }
            unsettled += 1;
            let foot = p.frenet_near(mid, guess, (at - 10.0, at + 30.0), at, 8.0);
            assert!(foot.s > out_leg && foot.s < len && (foot.d.abs() - r).abs() < 0.05, "from {guess}: {foot:?}");
        }
        assert!(unsettled > 0, "no guess leaves Newton unsettled between the legs");
    }

    /// `frenet_many` is `frenet_dir` for each point, bit for bit: points on, beside and beyond
    /// the path (both ends, where the search clamps), from near and far guesses, on a path that
    /// reads its route's shared samples and its own.
    #[test]
    fn frenet_many_is_frenet_dir_each() {
        let mut pts = vec![DVec2::new(-40.0, 2.0), DVec2::new(0.0, 2.0)];
        pts.extend((1..=30).map(|i| DVec2::new(0.0, 32.0) + DVec2::from_angle(-1.4 + i as f64 * 0.05) * 30.0));
        let mut shared = Resampler::new(&pts);
        let _longer = shared.path(1e9);
        let p = shared.path(70.0);
        assert!(p.cut > 0 && p.cut < p.len(), "reads shared and own samples");
        let bits = |f: Foot<()>| [f.s.to_bits(), f.d.to_bits(), f.beyond.to_bits()];
        let mut n = 0;
        for k in 0..600 {
            let along = k as f64 * 0.137 - 8.0;
            let (q, h) = p.at(along);
            let ps: [DVec2; 4] = std::array::from_fn(|c| {
                q + DVec2::from_angle(h + c as f64 * 1.3) * (0.3 + (k % 9) as f64 * (1.0 + c as f64))
            });
            let guesses: [f64; 4] = std::array::from_fn(|c| along + ((k * 5 + c * 3) % 17) as f64 - 8.0);
            let many = p.frenet_many(ps, guesses);
            for c in 0..4 {
                let Foot { s, d, beyond, .. } = p.frenet_dir(ps[c], guesses[c]);
                assert_eq!(bits(many[c]), bits(Foot { s, d, beyond, dir: () }), "{:?} from {}", ps[c], guesses[c]);
                n += usize::from(beyond > 0.0);
            }
        }
        assert!(n > 50, "points beyond the ends are covered: {n}");
    }

    /// `point_fast_on` is `point_fast(s, 0.0)` bit for bit, zeros' signs included: on paths
    /// through the origin along both axes, and on ones whose tangents cannot be normalised.
    #[test]
    fn point_fast_on_is_point_fast_at_zero() {
        let paths = [
            Path::new(&[DVec2::new(-0.0, -20.0), DVec2::new(-0.0, 0.0), DVec2::new(20.0, 0.0), DVec2::new(20.0, 30.0)]),
            Path::new(&[DVec2::new(-5.0, 5.0), DVec2::new(5.0, -5.0), DVec2::new(0.0, -0.0)]),
            Path::new(&[DVec2::ONE]),
            Path::new(&[DVec2::ZERO, DVec2::new(1e-160, 0.0), DVec2::new(0.0, 1e-170), DVec2::new(3.0, -0.0)]),
        ];
        let bits = |q: DVec2| (q.x.to_bits(), q.y.to_bits());
        for p in &paths {
            for k in -10..800 {
                let s = k as f64 * 0.0625;
                assert_eq!(bits(p.point_fast_on(s)), bits(p.point_fast(s, 0.0)), "{s}");
            }
        }
    }

    /// Paths on one route that give the same `shared_upto` key read the same points and headings
    /// up to it, bit for bit (a grown grid is a copy, with a key of its own); a key is given only
    /// as far as the shared samples reach, and paths resampled apart never share one.
    #[test]
    fn shared_upto_keys_equal_points() {
        let mut pts = vec![DVec2::new(-40.0, 2.0), DVec2::new(0.0, 2.0)];
        pts.extend((1..=30).map(|i| DVec2::new(0.0, 32.0) + DVec2::from_angle(-1.4 + i as f64 * 0.05) * 30.0));
        let mut shared = Resampler::new(&pts);
        let paths: Vec<Path> = [80.0, 30.0, 55.5, 1e9].iter().map(|&u| shared.path(u)).collect();
        let alone = Resampler::new(&pts).path(80.0);
        let bits = |(p, h): (DVec2, f64)| (p.x.to_bits(), p.y.to_bits(), h.to_bits());
        let mut compared = 0;
        for a in &paths {
            assert!(a.shared_upto(a.length() + 1.0).is_none());
            assert_ne!(a.shared_upto(-5.0), alone.shared_upto(-5.0));
            for b in &paths {
                for hi in [-3.0, 0.0, 10.0, 25.0, 26.3, 50.0, 77.0, 200.0] {
                    if let (Some(x), Some(y)) = (a.shared_upto(hi), b.shared_upto(hi))
                        && x == y
                    {
                        for k in 0..=200 {
                            let s = hi - k as f64 * 0.37;
                            assert_eq!(bits(a.at(s)), bits(b.at(s)), "{s} up to {hi}");
                            compared += 1;
                        }
                    }
                }
            }
        }
        assert!(compared > 5000, "{compared}");
    }

    /// On a straight run, `frenet_dir` from any guess inside the run lands on the point's
    /// projection onto the run's line (what the pair loop's early reject relies on, 1 mm margin);
    /// a bend ends the run.
    #[test]
    fn straight_runs_agree_with_frenet() {
        let (a, b) = (DVec2::new(3.0, -7.0), DVec2::new(3.0, -7.0) + DVec2::from_angle(0.7) * 80.0);
        let c = b + DVec2::from_angle(1.9) * 40.0;
        let p = Path::new(&[a, b, c]);
        let ln = p.straight_run(10.0).expect("straight start");
        assert!(ln.hi > 70.0 && ln.hi < 80.0, "run ends before the bend: {}", ln.hi);
        assert!(p.straight_run(80.0).is_none(), "no run across the bend");
        let mut worst: f64 = 0.0;
        for k in 0..400 {
            let q = a
                + DVec2::from_angle(0.7) * (1.0 + (k % 70) as f64)
                + DVec2::from_angle(0.7).perp() * (k as f64 * 0.37 - 70.0);
            let guess = 1.0 + ((k * 7) % 68) as f64;
            let rel = q - ln.origin;
            let (s_line, l_line) = (ln.s0 + rel.dot(ln.dir), ln.dir.perp_dot(rel));
            if s_line <= ln.lo || s_line >= ln.hi {
                continue;
            }
            let Foot { s, d: l, beyond, dir: t } = p.frenet_dir(q, guess);
            assert_eq!(beyond, 0.0);
            worst = worst.max((s - s_line).abs()).max((l - l_line).abs()).max((t - ln.dir).length());
        }
        assert!(worst < 1e-6, "{worst}");
    }

    /// `set_caps` skips the square roots behind the last curve: the caps must be the bits of the
    /// plain recursion, on paths ending straight (a skipped tail) and ending in a curve (none).
    #[test]
    fn caps_are_the_plain_recursion() {
        let mut pts = vec![DVec2::new(-40.0, 2.0), DVec2::new(0.0, 2.0)];
        pts.extend((1..=30).map(|i| DVec2::new(0.0, 32.0) + DVec2::from_angle(-1.4 + i as f64 * 0.05) * 30.0));
        let curved_end = pts.clone();
        pts.push(*pts.last().unwrap() + DVec2::new(-25.0, 60.0));
        for (pts, decel) in [(&pts, 3.5), (&curved_end, 3.5), (&pts, f64::NEG_INFINITY), (&pts, f64::NAN)] {
            let mut p = Path::new(pts);
            p.set_caps(2.5, 0.6, decel);
            let mut next = f64::INFINITY;
            let curvature = full(&p).3;
            let mut want = vec![0.0; curvature.len()];
            for i in (0..want.len()).rev() {
                let k = curvature[i].abs();
                let local = if k > 1e-4 { (2.5 / k).sqrt().min(0.6 / k) } else { f64::INFINITY };
                next = local.min((next * next + 2.0 * decel * STEP).sqrt());
                want[i] = next;
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&p.cap), bits(&want), "decel {decel}");
            assert!(p.cap.iter().any(|c| c.is_finite()));
        }
    }
}
