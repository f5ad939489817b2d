//! Which agents the controller looks at for one agent's step: everyone within its look-ahead,
//! less those that provably change nothing (`Sim::candidates`); on a straight run, found through
//! an index along it (`AlongIndex`).

use crate::rollout::agent::{Actor, State};
use crate::rollout::drive::index::{ALONG_FAR, ALONG_MARGIN, ALONG_MIN_AGENTS, AlongIndex, AlongIndexes, LINE_EPS};
use crate::rollout::frame::Sim;
use crate::rollout::path::Line;
use glam::DVec2;

/// What `Sim::candidates` needs of agent `i`'s step in `Sim::drive`.
pub(crate) struct Corridor {
    pub(crate) look: f64,
    /// The lateral band the agent sweeps this step.
    pub(crate) lo: f64,
    pub(crate) hi: f64,
    /// Holding its offset (no lateral move this step).
    pub(crate) holding: bool,
    /// The straight run of its route it is on, when holding.
    pub(crate) line: Option<Line>,
    /// Clearing a junction for an emergency vehicle.
    pub(crate) clearing: bool,
    /// The agent it queues behind.
    pub(crate) named: Option<usize>,
    /// How far behind its centre along a straight run an agent is still kept: its tail may
    /// swing over one beside it in a bend within reach (`Bend::touches`), else 0.
    pub(crate) back: f64,
}

impl Sim<'_, '_> {
    /// The agents `drive`'s pair loop looks at for agent `i`, in the order it visits them: every
    /// agent in index order, and the one queued behind (`named`) once more (every effect there
    /// is a min or an or, so seeing it twice is harmless), less those that provably change
    /// nothing there: itself, its conflict partner, and (except `named`) agents beyond the
    /// look-ahead, well behind, or off its corridor on a straight stretch. It reads the packed
    /// per-frame `near` data. The look-ahead (up to ~240 m at highway speed) spans whole maps,
    /// so a grid finds nearly everyone; but on a straight run the corridor is a thin strip along
    /// it: with many agents, those to test come from `AlongIndex` (`corridor_subset`), in index
    /// order, the same ones the scan of everyone keeps.
    pub(crate) fn candidates(&self, i: usize, c: &Corridor, ix: &mut AlongIndexes, out: &mut Vec<usize>) {
        out.clear();
        let me = (i, &self.actors[i], &self.cur[i], self.facts.dirs[i]);
        if self.facts.near.len() >= ALONG_MIN_AGENTS
            && let Some(ln) = c.line
            && self.corridor_subset(i, c, ln, ix)
        {
            for &j in &ix.subset {
                if self.candidate(me, c, j) {
                    out.push(j);
                }
            }
        } else {
            for j in 0..self.facts.near.len() {
                if self.candidate(me, c, j) {
                    out.push(j);
                }
            }
        }
        if let Some(j) = c.named
            && j != i
            && !self.exempt(i, j)
        {
            out.push(j);
        }
    }

    /// Whether `candidates` keeps agent `j` for agent `i`'s pair loop (`me`: `i`, its actor,
    /// state and heading).
    #[inline(always)]
    pub(crate) fn candidate(&self, me: (usize, &Actor, &State, DVec2), c: &Corridor, j: usize) -> bool {
        let (i, a, st, fwd) = me;
        let look = c.look;
        let b = &self.facts.near[j];
        if j == i {
            return false;
        }
        if c.named == Some(j) {
            return !self.exempt(i, j);
        }
        let dp = b.pos - st.pos;
        let r = look + a.radius + b.radius;
        if dp.length_squared() > r * r {
            return false;
        }
        let ahead = dp.dot(fwd);
        // Well behind us and not beside a lateral move: cannot be in our way.
        if ahead < -(a.hl + b.radius + 1.0) && c.holding {
            return false;
        }
        if let Some(ln) = c.line {
            let guess = st.s + ahead;
            let rel = b.pos - ln.origin;
            let s_line = ln.s0 + rel.dot(ln.dir);
            // (Its projection a half length inside the run: `drive` widens the band by our
            // swing, read from the curvature there and a half length behind it.)
            if guess > ln.lo && guess < ln.hi && s_line - a.hl > ln.lo && s_line < ln.hi {
                // `frenet_dir` would give s_line, this offset and this tangent to float
                // noise (1 mm is far above it), hence the extents below too.
                let l_line = ln.dir.perp_dot(rel);
                let (cr, sr) = (b.dir.dot(ln.dir), ln.dir.perp_dot(b.dir));
                let ext_lon = b.hl * cr.abs() + b.hw * sr.abs();
                let ext_lat = b.hl * sr.abs() + b.hw * cr.abs();
                let behind = s_line - st.s < -LINE_EPS - c.back;
                let too_far = s_line - st.s - a.hl - ext_lon > look + LINE_EPS;
                let aside = l_line - ext_lat > c.hi + LINE_EPS || l_line + ext_lat < c.lo - LINE_EPS;
                // Nor would it be predicted to cut across (see `obstacle` in `Sim::respond`).
                let v_lat = b.v * sr;
                let steady =
                    !a.vehicle || v_lat.abs() < 0.3 - LINE_EPS || b.gives_way || (c.clearing && b.cleared_past);
                if behind || too_far || (aside && steady) {
                    return false;
                }
            }
        }
        // Last: a pure test like the others, and the rarest to hold.
        !self.exempt(i, j)
    }

    /// Fill `subset` with, in index order, every agent that `candidate` can keep for agent `i`
    /// on the straight run `ln` (and maybe others): those whose place along the run lies in
    /// the corridor ahead and across it near our band, those moving across the run, and
    /// `named`. `false` (subset unset) where that cannot be bounded: the run ending within
    /// reach ahead or close behind (there `candidate` does not use the run), a lateral move, or
    /// coordinates beyond `ALONG_FAR`.
    pub(crate) fn corridor_subset(&self, i: usize, c: &Corridor, ln: Line, ixs: &mut AlongIndexes) -> bool {
        const FAR: f64 = ALONG_FAR;
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let rmax = self.max_radius;
        // Everyone `candidate` keeps lies within `reach` of us (its circle test), and (holding
        // our offset) no farther behind than `back` along our heading, so along the run too
        // but for the turn `g` of our heading from it: then its guess and its place along the
        // run are inside the run, where `candidate` uses it. The margin covers rounding (below
        // 1e-8 m within `FAR`) and a unit vector's length.
        let m = ALONG_MARGIN;
        let reach = c.look + a.radius + rmax;
        let back = a.hl + rmax + 1.0;
        let g = reach * (self.facts.dirs[i] - ln.dir).length();
        let s_here = ln.s0 + (st.pos - ln.origin).dot(ln.dir);
        let inside = st.s - back - m > ln.lo
            && s_here - back - g - a.hl - m > ln.lo
            && st.s + reach + m < ln.hi
            && s_here + reach + m < ln.hi;
        let sizes = [reach, g, s_here, st.s, ln.s0, ln.origin.x, ln.origin.y, st.pos.x, st.pos.y, c.lo, c.hi, a.hl];
        if !c.holding || !inside || !sizes.iter().all(|x| x.abs() < FAR) {
            return false;
        }
        let along = &mut ixs.along;
        let key = (ln.dir.x.to_bits(), ln.dir.y.to_bits());
        let k = match along.iter().position(|x| x.key == key) {
            Some(k) => k,
            None => {
                along.push(AlongIndex::new(&self.facts.near, ln.dir));
                along.len() - 1
            }
        };
        let ix = &along[k];
        if !ix.tame {
            return false;
        }
        // Inside the run `candidate` keeps an agent only where it is not behind, not beyond the
        // look-ahead (its extents are within `rmax`), and beside our band, or moving across.
        let (o_along, o_across) = (ln.origin.dot(ln.dir), ln.dir.perp_dot(ln.origin));
        let lo = st.s - ln.s0 + o_along - LINE_EPS - m - c.back;
        let hi = st.s - ln.s0 + o_along + a.hl + rmax + c.look + LINE_EPS + m;
        let (l_lo, l_hi) = (c.lo - rmax - LINE_EPS - m + o_across, c.hi + rmax + LINE_EPS + m + o_across);
        let sub = &mut ixs.subset;
        sub.clear();
        ix.collect(lo, hi, l_lo, l_hi, sub);
        if a.vehicle {
            // Clearing the junction for an emergency vehicle, we predict walkers only.
            sub.extend(ix.crossing.iter().filter(|&&j| !c.clearing || !self.facts.near[j].cleared_past));
        }
        sub.extend(c.named.filter(|&j| j < self.facts.near.len()));
        sub.sort_unstable();
        sub.dedup();
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rollout::agent::State;
    use crate::rollout::drive::index::Near;
    use crate::rollout::path::Path;
    use crate::rollout::setup::test_actors::{lcg, random_boxes};

    /// `candidates` through the along index must give exactly the agents (and order) of the scan
    /// of everyone, for agents on a straight run among others ahead, behind, beside, far off,
    /// crossing it, walking, holding at a line, with and without a named leader; and the index
    /// must answer most asks, or the test proves nothing.
    #[test]
    fn along_index_keeps_every_candidate() {
        let mut rnd = lcg(11);
        let n = 160;
        let mut actors = random_boxes(n, 11.0, &mut rnd);
        for a in actors.iter_mut().step_by(9) {
            a.vehicle = false;
        }
        let road = Path::straight(DVec2::new(-300.0, 40.0), 0.37, 3000.0);
        let mut sim = Sim::new(&actors, &[], &[], None, 0.1);
        let mut ix = AlongIndexes { along: vec![], subset: vec![] };
        for k in 0..n {
            let s = 500.0 + 700.0 * rnd();
            let lat = (rnd() - 0.5) * 40.0;
            let (p, h) = road.point(s, lat);
            let turn = match k % 7 {
                0 => 1.2,
                1 => std::f64::consts::PI,
                _ => (rnd() - 0.5) * 0.03,
            };
            sim.cur[k] = State { pos: p, yaw: h + turn, v: 35.0 * rnd(), s, d: lat, off: lat, ..sim.cur[k] };
        }
        sim.facts.dirs = sim.cur.iter().map(|s| DVec2::from_angle(s.yaw)).collect();
        sim.facts.near = (0..n).map(|k| Near::new(&sim.cur[k], &actors[k], sim.facts.dirs[k], k % 11 == 0)).collect();
        let (mut asked, mut indexed) = (0, 0);
        for (i, ai) in actors.iter().enumerate() {
            let st = sim.cur[i];
            let Some(line) = road.straight_run(st.s) else { continue };
            for (k, look) in [15.0, 60.0, 240.0].into_iter().enumerate() {
                let wide = 2.0 * rnd();
                let c = Corridor {
                    look,
                    lo: st.d - ai.hw - wide,
                    hi: st.d + ai.hw + 0.1,
                    holding: true,
                    line: Some(line),
                    clearing: k == 1 && i % 2 == 0,
                    named: (k == 2).then_some((i * 7 + 3) % n),
                    back: if k == 1 { 8.0 } else { 0.0 },
                };
                let mut got = vec![];
                sim.candidates(i, &c, &mut ix, &mut got);
                let me = (i, ai, &sim.cur[i], sim.facts.dirs[i]);
                let mut want: Vec<usize> = (0..n).filter(|&j| sim.candidate(me, &c, j)).collect();
                want.extend(c.named.filter(|&j| j != i));
                assert_eq!(got, want, "agent {i}, look {look}");
                asked += 1;
                indexed += usize::from(sim.corridor_subset(i, &c, line, &mut ix));
            }
        }
        assert!(indexed * 10 > asked * 9, "the index answered {indexed} of {asked}");
    }
}
