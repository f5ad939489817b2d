//! The last safety net: a move that would make two boxes overlap is undone (conflict pairs
//! excepted), so the only overlaps in `Tracks` are staged crashes.

use crate::rollout::agent::{Drive, State};
use crate::rollout::frame::{HardStop, Sim};
use glam::DVec2;

impl Sim<'_, '_> {
    /// Undo moves until no two boxes overlap (conflict pairs excepted). Undoing every move
    /// restores the previous frame, which had no overlap, so this always ends. `f` is the frame
    /// being simulated.
    pub(crate) fn resolve_overlaps(&mut self, f: usize) {
        let n = self.actors.len();
        let pairs = self.overlap_pairs();
        // Each pass undoes at least one turn or move: two per agent at most.
        for _ in 0..=2 * n {
            let mut changed = false;
            // The pairs (i, j > i) in index order (undoing a move changes later pairs'
            // outcome), bounding circles first.
            for &(i, j) in &pairs {
                let (ai, aj) = (&self.actors[i], &self.actors[j]);
                let (si, sj) = (&self.next[i], &self.next[j]);
                let r = ai.radius + aj.radius;
                if si.pos.distance_squared(sj.pos) >= r * r || self.exempt(i, j) {
                    continue;
                }
                if !ai.obb(si).overlaps(&aj.obb(sj)) {
                    continue;
                }
                // A walker turning on the spot sweeps its corners out to its half-diagonal:
                // beside another (two crossing side by side) it keeps its heading and steps on
                // sideways, rather than standing there for good. Turns are undone first, moves
                // only if the pair still overlaps without them.
                let turning = |k: usize| {
                    let (nk, ck) = (self.next[k], self.cur[k]);
                    !self.actors[k].vehicle
                        && matches!(self.actors[k].drive, Drive::Mover)
                        && nk.yaw != ck.yaw
                        && nk.pos != ck.pos
                };
                let turns = [(i, turning(i)), (j, turning(j))];
                if turns.iter().any(|t| t.1) {
                    for (k, _) in turns.into_iter().filter(|t| t.1) {
                        self.next[k].yaw = self.cur[k].yaw;
                    }
                    changed = true;
                    continue;
                }
                for k in [i, j] {
                    let (nk, ck) = (self.next[k], self.cur[k]);
                    let moved = nk.pos != ck.pos || nk.yaw != ck.yaw;
                    if matches!(self.actors[k].drive, Drive::Mover) && moved {
                        if self.cur[k].v > self.actors[k].lim.brake_max * self.dt + 1e-6 {
                            let other = if k == i { j } else { i };
                            self.first_hard.get_or_insert(HardStop { agent: k, other, t: f as f64 * self.dt });
                        }
                        self.next[k] = State { v: 0.0, ..self.cur[k] };
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        self.pairs = pairs;
    }

    /// The pairs (i, j > i), in index order, whose bounding circles may meet in
    /// `resolve_overlaps`: there an agent is at its `next` position or, once its move is undone,
    /// at its `cur` one, so a pair whose boxes around both positions (circle plus `MARGIN`) do
    /// not meet fails the circle test in every pass and changes nothing. A sweep over the boxes
    /// sorted by x, instead of every pair; with a position beyond `FAR` or not finite, where the
    /// margin might not cover float rounding, every pair.
    pub(crate) fn overlap_pairs(&mut self) -> Vec<(usize, usize)> {
        // Far above the rounding of coordinates below `FAR` (~1e-7 m).
        const MARGIN: f64 = 0.01;
        const FAR: f64 = 1e9;
        let n = self.actors.len();
        let mut pairs = std::mem::take(&mut self.pairs);
        pairs.clear();
        self.sweep.clear();
        let mut tame = true;
        for k in 0..n {
            let (p, q, r) = (self.next[k].pos, self.cur[k].pos, self.actors[k].radius);
            // Compared one by one: `max_element` would pass over a NaN.
            tame &= [p.x, p.y, q.x, q.y, r].iter().all(|c| c.abs() < FAR);
            let r = DVec2::splat(r + MARGIN);
            self.sweep.push((p.min(q) - r, p.max(q) + r, k));
        }
        if !tame {
            pairs.extend((0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))));
            return pairs;
        }
        self.sweep.sort_unstable_by(|a, b| a.0.x.total_cmp(&b.0.x));
        for (x, &(lo, hi, k)) in self.sweep.iter().enumerate() {
            for &(lo2, hi2, k2) in &self.sweep[x + 1..] {
                if lo2.x > hi.x {
                    break;
                }
                if lo2.y <= hi.y && hi2.y >= lo.y {
                    pairs.push((k.min(k2), k.max(k2)));
                }
            }
        }
        pairs.sort_unstable();
        pairs
    }
}

#[cfg(test)]
mod tests {
    use crate::rollout::frame::Sim;
    use crate::rollout::setup::test_actors::{lcg, random_boxes};
    use glam::DVec2;

    /// `overlap_pairs` may leave out only pairs whose bounding circles cannot meet at any mix of
    /// the positions `resolve_overlaps` can give them (`next`, or `cur` once undone), and must
    /// list the rest once each in (i, j) order; with a position it cannot bound, every pair.
    #[test]
    fn overlap_pairs_keep_every_pair_that_can_meet() {
        let mut rnd = lcg(7);
        let n = 120;
        let actors = random_boxes(n, 6.0, &mut rnd);
        let mut sim = Sim::new(&actors, &[], &[], None, 0.1);
        for k in 0..n {
            // Clusters of touching and nearly touching boxes, moves up to 4 m, a few far away.
            let base = if k % 10 == 0 { DVec2::new(5e3 * rnd(), -3e3) } else { DVec2::new(60.0 * rnd(), 8.0 * rnd()) };
            sim.cur[k].pos = base;
            sim.next[k].pos = base + DVec2::new(4.0 * rnd() - 2.0, 4.0 * rnd() - 2.0);
        }
        let can_meet = |sim: &Sim, i: usize, j: usize| {
            let r = actors[i].radius + actors[j].radius;
            [sim.next[i].pos, sim.cur[i].pos]
                .iter()
                .any(|p| [sim.next[j].pos, sim.cur[j].pos].iter().any(|q| p.distance_squared(*q) < r * r))
        };
        let pairs = sim.overlap_pairs();
        assert!(pairs.windows(2).all(|w| w[0] < w[1]) && pairs.iter().all(|&(i, j)| i < j && j < n));
        let meeting: Vec<(usize, usize)> =
            (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))).filter(|&(i, j)| can_meet(&sim, i, j)).collect();
        assert!(meeting.len() > 50, "the case must have meeting pairs: {}", meeting.len());
        assert!(meeting.iter().all(|p| pairs.binary_search(p).is_ok()));
        assert!(pairs.len() < n * (n - 1) / 4, "the sweep should leave most pairs out: {}", pairs.len());
        sim.next[3].pos.x = f64::NAN;
        assert_eq!(sim.overlap_pairs().len(), n * (n - 1) / 2);
        sim.next[3].pos.x = 2e9;
        assert_eq!(sim.overlap_pairs().len(), n * (n - 1) / 2);
    }
}
