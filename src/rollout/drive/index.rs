//! What the neighbour search reads of everyone, packed once per frame (`Near`), and the index
//! of everyone along a straight run's direction (`AlongIndex`): the agents near a stretch of the
//! run are a few ranges of it.

use crate::rollout::agent::{Actor, State};
use glam::DVec2;

/// Agent `j` as `Sim::candidates` sees it this frame: copies of its state's and actor's fields
/// (same bits), packed so that scanning everyone reads 72 contiguous bytes per agent, not its
/// whole state and actor.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Near {
    pub(crate) pos: DVec2,
    /// Unit heading (`Sim::dirs`).
    pub(crate) dir: DVec2,
    pub(crate) v: f64,
    pub(crate) radius: f64,
    pub(crate) hl: f64,
    pub(crate) hw: f64,
    /// Holding at its stop line for an emergency vehicle (`Sim::yield_state`).
    pub(crate) gives_way: bool,
    /// A vehicle that one clearing a junction for an emergency vehicle does not wait for
    /// (`Actor::cleared_past`).
    pub(crate) cleared_past: bool,
}

impl Near {
    pub(crate) fn new(st: &State, a: &Actor, dir: DVec2, gives_way: bool) -> Near {
        Near {
            pos: st.pos,
            dir,
            v: st.v,
            radius: a.radius,
            hl: a.hl,
            hw: a.hw,
            gives_way,
            cleared_past: a.cleared_past(st),
        }
    }
}

/// How far inside the look-ahead's bounds `candidate` counts an agent on a straight run, m.
pub(crate) const LINE_EPS: f64 = 1e-3;
/// From this many agents on, `candidates` asks `AlongIndex` for the agents near a straight run
/// instead of testing everyone (below, building it costs more than it saves: measured slower
/// at 42 agents on `highway_merge`, with its many lane directions, faster at 50 on one road).
pub(crate) const ALONG_MIN_AGENTS: usize = 48;
/// Coordinates up to which `ALONG_MARGIN` bounds the rounding of the index's bounds.
pub(crate) const ALONG_FAR: f64 = 1e6;
pub(crate) const ALONG_MARGIN: f64 = 0.01;
/// Width of `AlongIndex`'s lanes across the direction, m.
pub(crate) const ALONG_BIN: f64 = 2.0;

/// Every agent's place along (`pos . dir`) and across (`dir x pos`) one direction, in bins
/// across it, each sorted along: the agents near a stretch of a straight run are a few ranges.
/// This frame's along indexes, one per straight-run direction `candidates` asked about, built on
/// the first ask; and the agents one ask yields (`Sim::corridor_subset`).
pub(crate) struct AlongIndexes {
    pub(crate) along: Vec<AlongIndex>,
    pub(crate) subset: Vec<usize>,
}

pub(crate) struct AlongIndex {
    pub(crate) key: (u64, u64),
    /// The first bin across, and where each bin's agents start in `along` / `agent`.
    pub(crate) min_bin: i64,
    pub(crate) starts: Vec<usize>,
    pub(crate) along: Vec<f64>,
    pub(crate) agent: Vec<usize>,
    /// Agents whose speed across the direction `candidate` counts as moving across it (or
    /// that it cannot tell), not holding at a line.
    pub(crate) crossing: Vec<usize>,
    /// Every coordinate finite and within `ALONG_FAR`, and not too many bins.
    pub(crate) tame: bool,
}

impl AlongIndex {
    pub(crate) fn new(near: &[Near], dir: DVec2) -> AlongIndex {
        let mut ix = AlongIndex {
            key: (dir.x.to_bits(), dir.y.to_bits()),
            min_bin: 0,
            starts: vec![],
            along: vec![],
            agent: vec![],
            crossing: vec![],
            tame: near.iter().all(|b| b.pos.x.abs() < ALONG_FAR && b.pos.y.abs() < ALONG_FAR),
        };
        if !ix.tame {
            return ix;
        }
        let bin = |b: &Near| (dir.perp_dot(b.pos) / ALONG_BIN).floor() as i64;
        let (lo, hi) = near.iter().fold((i64::MAX, i64::MIN), |(l, h), b| (l.min(bin(b)), h.max(bin(b))));
        if near.is_empty() || hi - lo > 4 * near.len() as i64 + 64 {
            ix.tame = false;
            return ix;
        }
        // A counting sort by bin, then each bin along.
        ix.min_bin = lo;
        let mut starts = vec![0usize; (hi - lo + 2) as usize];
        for b in near {
            starts[(bin(b) - lo + 1) as usize] += 1;
        }
        for k in 1..starts.len() {
            starts[k] += starts[k - 1];
        }
        let mut fill = starts.clone();
        let mut items = vec![(0.0, 0usize); near.len()];
        for (j, b) in near.iter().enumerate() {
            let k = &mut fill[(bin(b) - lo) as usize];
            items[*k] = (b.pos.dot(dir), j);
            *k += 1;
            // As `candidate` takes it, with room for rounding.
            let v_lat = b.v * dir.perp_dot(b.dir);
            let steady = v_lat.abs() < 0.3 - LINE_EPS - 1e-6;
            if !steady && !b.gives_way {
                ix.crossing.push(j);
            }
        }
        for w in starts.windows(2) {
            items[w[0]..w[1]].sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
        }
        (ix.along, ix.agent) = items.into_iter().unzip();
        ix.starts = starts;
        ix
    }

    /// Append the agents placed along within `lo..=hi` in the bins holding `l_lo..=l_hi` across.
    pub(crate) fn collect(&self, lo: f64, hi: f64, l_lo: f64, l_hi: f64, out: &mut Vec<usize>) {
        let nbins = self.starts.len() as i64 - 1;
        let b_lo = ((l_lo / ALONG_BIN).floor() as i64 - self.min_bin).max(0);
        let b_hi = ((l_hi / ALONG_BIN).floor() as i64 - self.min_bin).min(nbins - 1);
        for b in b_lo..=b_hi {
            let (s, e) = (self.starts[b as usize], self.starts[b as usize + 1]);
            let first = s + self.along[s..e].partition_point(|&x| x < lo);
            let last = first + self.along[first..e].partition_point(|&x| x <= hi);
            out.extend_from_slice(&self.agent[first..last]);
        }
    }
}
