//! Spatial bucketing for the frame loop's pair checks: a uniform grid over agent positions,
//! stored as one vector of (cell, agent) entries sorted row by row, so that a query is one binary
//! search per grid row it spans and every iteration order is fixed by positions and indices
//! (no hashing). Rebuilt each frame into the same buffer: no allocation once it has grown.

use glam::DVec2;

/// Cell side, m: about the reach of a box-overlap check between two large vehicles, so that
/// those span at most 3 x 3 cells, while a car-following look-ahead (up to ~200 m) spans a few
/// dozen rows.
const CELL: f64 = 24.0;

/// Below this many agents a plain scan of all of them is cheaper than the grid's binary
/// searches (measured with `bench rollout`: at 50 agents the scan wins), and gives the same
/// result: the frame loop's pair effects do not depend on the order candidates come in.
pub(super) const MIN_AGENTS: usize = 96;

#[derive(Default)]
pub(super) struct Grid {
    /// (row, column, agent), sorted.
    entries: Vec<(i32, i32, u32)>,
}

#[inline]
fn cell(x: f64) -> i32 {
    // Far-off or non-finite coordinates saturate into the outermost cells: still correct.
    (x / CELL).floor().clamp(i32::MIN as f64 / 2.0, i32::MAX as f64 / 2.0) as i32
}

impl Grid {
    /// Every agent near `p` (`near`), or simply every agent when there are fewer than
    /// `MIN_AGENTS`; the caller filters by distance either way.
    pub fn cands(&self, p: DVec2, r: f64) -> Cands<'_> {
        if self.entries.len() < MIN_AGENTS { Cands::All(0..self.entries.len()) } else { Cands::Grid(self.near(p, r)) }
    }

    pub fn rebuild(&mut self, positions: impl Iterator<Item = DVec2>) {
        self.entries.clear();
        self.entries.extend(positions.enumerate().map(|(i, p)| (cell(p.y), cell(p.x), i as u32)));
        self.entries.sort_unstable();
    }

    /// Agents whose cell meets the square of half side `r` around `p` (a superset of those
    /// within `r`), in (row, column, index) order.
    pub fn near(&self, p: DVec2, r: f64) -> Near<'_> {
        let (x0, x1) = (cell(p.x - r), cell(p.x + r));
        let (y0, y1) = (cell(p.y - r), cell(p.y + r));
        Near { g: self, row: y0, y1, x0, x1, k: 0, end: 0 }
    }
}

/// Candidates of a query: the grid's, or every agent when there are few.
pub(super) enum Cands<'a> {
    Grid(Near<'a>),
    All(std::ops::Range<usize>),
}

impl Iterator for Cands<'_> {
    type Item = usize;

    #[inline]
    fn next(&mut self) -> Option<usize> {
        match self {
            Cands::Grid(n) => n.next(),
            Cands::All(r) => r.next(),
        }
    }
}

pub(super) struct Near<'a> {
    g: &'a Grid,
    row: i32,
    y1: i32,
    x0: i32,
    x1: i32,
    k: usize,
    end: usize,
}

impl Iterator for Near<'_> {
    type Item = usize;

    #[inline]
    fn next(&mut self) -> Option<usize> {
        loop {
            if self.k < self.end {
                self.k += 1;
                return Some(self.g.entries[self.k - 1].2 as usize);
            }
            if self.row > self.y1 {
                return None;
            }
            let e = &self.g.entries;
            // Skip empty rows at once: jump to the next occupied row at or after `row`.
            let first = e.partition_point(|&(r, _, _)| r < self.row);
            let Some(&(r, _, _)) = e.get(first) else {
                self.row = self.y1 + 1;
                return None;
            };
            if r > self.y1 {
                self.row = self.y1 + 1;
                return None;
            }
            let (x0, x1) = (self.x0, self.x1);
            self.k = first + e[first..].partition_point(|&(rr, c, _)| rr == r && c < x0);
            self.end = first + e[first..].partition_point(|&(rr, c, _)| rr == r && c <= x1);
            self.row = r + 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid finds exactly the brute-force neighbours (after the distance filter), in a fixed
    /// order, over scattered points and radii.
    #[test]
    fn near_matches_brute_force() {
        let mut rng = 12345u64;
        let mut next = || {
            rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((rng >> 11) as f64 / (1u64 << 53) as f64) * 400.0 - 200.0
        };
        let pts: Vec<DVec2> = (0..300).map(|_| DVec2::new(next(), next())).collect();
        let mut g = Grid::default();
        g.rebuild(pts.iter().copied());
        for (qi, &q) in pts.iter().enumerate().take(60) {
            let r = [3.0, 20.0, 75.0, 190.0][qi % 4];
            let mut got: Vec<usize> = g.near(q, r).filter(|&j| pts[j].distance(q) <= r).collect();
            let want: Vec<usize> = (0..pts.len()).filter(|&j| pts[j].distance(q) <= r).collect();
            assert!(got.windows(2).all(|w| w[0] != w[1]), "duplicates");
            got.sort_unstable();
            assert_eq!(got, want, "query {qi} r {r}");
        }
    }
}
