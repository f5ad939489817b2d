//! Voxel traversal (Amanatides & Woo, "A Fast Voxel Traversal Algorithm", 1987). In: a label
//! grid, a ray (origin and unit direction in the ego frame) and a range limit. Out: the first
//! non-free voxel the ray enters, with the distance at which it enters and leaves it and the
//! axis of the face it came through.
//!
//! tMax, the distance to the first boundary crossed on each axis, is measured from the ray's
//! origin: (boundary - origin) / direction. UniScene's CUDA kernel `raycast_kernel_wori` omits
//! the `- origin`, which is only right for an origin at the grid's corner; the off-centre tests
//! below compare against an analytic slab intersection.
//!
//! `Skip` speeds this up for driving scenes, where most of the volume above the ground is empty:
//! a 2D walk over blocks of 8 x 8 columns skips every block whose highest occupied voxel lies
//! below the ray's lowest point over that block, and runs the voxel walk only inside the others.
//! The voxel walk's boundaries are always computed from the ray origin, so the result is the same
//! voxel and distance as `cast`'s (a test compares them on a full scene). `Skip::cast_from`
//! starts the block walk part-way along the ray, where `super::fan` shows it has passed above
//! every block before (a test there compares its hits with `cast`'s).

pub use super::walk::Hit;
use super::walk::{WalkStart, floor_i64, walk, walk_columns};
use crate::backend::layout::{K_GROUND, K_GROUND_TOP, NX, NY, NZ, ORIGIN, UPPER, VOXEL, flat};

/// Where a ray enters and leaves the grid's box, if it meets it at all before `t_max`.
fn clip_to_grid(o: [f64; 3], d: [f64; 3], inv: [f64; 3], t_max: f64) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (0.0f64, t_max);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < ORIGIN[a] || o[a] >= UPPER[a] {
                return None;
            }
        } else {
            let (ta, tb) = ((ORIGIN[a] - o[a]) * inv[a], (UPPER[a] - o[a]) * inv[a]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

/// Bit b set when byte b of `x` (little endian) is not zero.
#[inline]
fn nonzero_bytes(x: u64) -> u32 {
    const LOW7: u64 = 0x7f7f_7f7f_7f7f_7f7f;
    // High bit of each byte: set when any of its bits is (no carry crosses a byte).
    let high = (((x & LOW7) + LOW7) | x) & !LOW7;
    // Gather the eight high bits into the top byte.
    ((high >> 7).wrapping_mul(0x0102_0408_1020_4080) >> 56) as u32
}

/// Bit k set when byte k of the column `col` (`NZ` bytes) is not free.
#[inline]
fn column_mask(col: &[u8]) -> u32 {
    // The column as little-endian words, byte k of the column at bits 8 (k % 8) of word k / 8.
    col.chunks_exact(8)
        .enumerate()
        .map(|(q, b)| nonzero_bytes(u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]])) << (8 * q))
        .fold(0, |m, q| m | q)
}

/// Per axis 1 / d: every boundary distance is a product with it (one division per axis and
/// ray, not one per boundary).
#[inline]
fn inverse(d: [f64; 3]) -> [f64; 3] {
    [1.0 / d[0], 1.0 / d[1], 1.0 / d[2]]
}

/// Walk the ray through `labels` (standard-layout (400, 400, 32)) up to distance `t_max`.
pub fn cast(labels: &[u8], o: [f64; 3], d: [f64; 3], t_max: f64) -> Option<Hit> {
    let inv = inverse(d);
    let (t_in, t_out) = clip_to_grid(o, d, inv, t_max)?;
    let axis = if t_in > 0.0 { entry_axis(o, d, t_in) } else { 3 };
    let occupied = |at: usize| labels[at] != 0;
    walk(labels, occupied, o, d, inv, t_in, t_out, axis, [0, 0, 0], [NX as i64, NY as i64, NZ as i64], |_| {})
}

/// `cast`, calling `seen` with the flat index (`layout::flat`) of every free voxel the ray
/// passes through before its hit (or before `t_max` or the grid's edge), in order: the free
/// space a sensor observes along the ray (`crate::visibility`).
pub fn traverse(labels: &[u8], o: [f64; 3], d: [f64; 3], t_max: f64, seen: impl FnMut(usize)) -> Option<Hit> {
    let inv = inverse(d);
    let (t_in, t_out) = clip_to_grid(o, d, inv, t_max)?;
    let axis = if t_in > 0.0 { entry_axis(o, d, t_in) } else { 3 };
    let occupied = |at: usize| labels[at] != 0;
    walk(labels, occupied, o, d, inv, t_in, t_out, axis, [0, 0, 0], [NX as i64, NY as i64, NZ as i64], seen)
}

/// Columns per block side in `Skip`.
const B: usize = 8;
/// Blocks along x and y, and their side (m).
pub const NBX: usize = NX / B;
pub const NBY: usize = NY / B;
pub const BLOCK_M: f64 = VOXEL * B as f64;

/// Per-block height of the highest occupied voxel's top face (m), for empty-space skipping.
#[derive(Clone, Debug)]
pub struct Skip {
    top: Vec<f64>,
    /// The highest `top` of all: a ray at or above it that does not descend can hit nothing more.
    max_top: f64,
    /// Blocks whose only occupied voxels are the ground layer (k = K_GROUND) in every column:
    /// a descending ray's hit there is where it crosses z = 0, found without walking voxels.
    ground_only: Vec<bool>,
    /// Per quadrant of travel (x step >= 0, y step >= 0: index 2 sx + sy), per block: the highest
    /// `top` of every block a ray moving that way can still reach from it. A rising ray at or
    /// above it has nothing left to hit (the level-ray test of `max_top`, made local).
    ahead: [Vec<f64>; 4],
    /// Per column (`layout::flat(i, j, 0) / NZ`), bit k set when voxel k is not free: the voxel
    /// walk reads 4 bytes per column from 640 kB instead of the labels' 5 MB, which stay in
    /// memory when the cache does not hold them; only the hit voxel's label is read from there.
    cols: Vec<u32>,
    /// Per ground-only block, the label its ground voxels all share (0 if they differ): the
    /// ground shortcut then reads no voxel at all.
    ground_label: Vec<u8>,
}

/// `Skip` made from the label grid's columns as they come (`Skip::summary`): a writer that
/// passes over the labels anyway feeds them here while they are in the cache, so the scan does
/// not read the 5 MB from memory a second time.
pub struct SkipSummary {
    cols: Vec<u32>,
    /// Per block: the highest occupied layer + 1 (0: none), whether every column holds the
    /// ground voxel and nothing else, and the ground label (u16::MAX: no column yet,
    /// u16::MAX - 1: two labels differ).
    top_k: Vec<u32>,
    ground_only: Vec<bool>,
    ground_label: Vec<u16>,
    /// Columns added so far.
    next: usize,
}

impl SkipSummary {
    /// Add the grid's next columns: `labels` holds whole columns (a multiple of `NZ` bytes),
    /// in the grid's order; bytes past the last whole column are ignored.
    pub fn add(&mut self, labels: &[u8]) {
        let mut cols = labels.chunks_exact(NZ);
        // Runs of B columns share a block (NY is a multiple of B): its entries are updated once
        // per run, not once per column.
        while self.next.is_multiple_of(B) && cols.len() >= B && self.next + B <= NX * NY {
            let c0 = self.next;
            let (mut any, mut ground_only, mut same) = (0u32, true, true);
            let mut first = None;
            for (c, col) in (c0..c0 + B).zip(cols.by_ref()) {
                let m = column_mask(col);
                self.cols[c] = m;
                any |= m;
                ground_only &= m == 1 << K_GROUND;
                let l = u16::from(col[K_GROUND]);
                same &= *first.get_or_insert(l) == l;
            }
            self.next = c0 + B;
            let block = (c0 / NY / B) * NBY + c0 % NY / B;
            self.ground_only[block] &= ground_only;
            self.top_k[block] = self.top_k[block].max(32 - any.leading_zeros());
            // The run's labels folded in as `add_column` folds them one at a time.
            let (g, l) = (&mut self.ground_label[block], first.unwrap_or(0));
            *g = if same && (*g == u16::MAX || *g == l) { l } else { u16::MAX - 1 };
        }
        for col in cols {
            self.add_column(col);
        }
    }

    fn add_column(&mut self, col: &[u8]) {
        let c = self.next;
        if c >= NX * NY {
            return;
        }
        self.next += 1;
        let m = column_mask(col);
        self.cols[c] = m;
        let block = (c / NY / B) * NBY + c % NY / B;
        self.ground_only[block] &= m == 1 << K_GROUND;
        self.top_k[block] = self.top_k[block].max(32 - m.leading_zeros());
        let g = &mut self.ground_label[block];
        let l = u16::from(col[K_GROUND]);
        *g = if *g == u16::MAX || *g == l { l } else { u16::MAX - 1 };
    }

    /// The `Skip` of the grid, once every column was added (None before).
    pub fn finish(self) -> Option<Skip> {
        (self.next == NX * NY).then(|| Skip::from_summary(self))
    }
}

impl Skip {
    pub fn new(labels: &[u8]) -> Self {
        let mut s = Skip::summary();
        s.add(labels);
        Skip::from_summary(s)
    }

    /// An empty summary to feed the grid's columns to.
    pub fn summary() -> SkipSummary {
        SkipSummary {
            cols: vec![0u32; NX * NY],
            top_k: vec![0u32; NBX * NBY],
            ground_only: vec![true; NBX * NBY],
            ground_label: vec![u16::MAX; NBX * NBY],
            next: 0,
        }
    }

    fn from_summary(s: SkipSummary) -> Self {
        let SkipSummary { cols, top_k, ground_only, ground_label, .. } = s;
        // The top face of the highest occupied voxel (m).
        let top: Vec<f64> =
            top_k.iter().map(|&k| if k == 0 { f64::NEG_INFINITY } else { ORIGIN[2] + VOXEL * f64::from(k) }).collect();
        let max_top = top.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let ahead = [0, 1, 2, 3].map(|q| {
            let (px, py) = (q >> 1 == 1, q & 1 == 1);
            let mut m = vec![f64::NEG_INFINITY; NBX * NBY];
            // Visit blocks from the far corner of the quadrant back towards its origin.
            for a in 0..NBX {
                let i = if px { NBX - 1 - a } else { a };
                for b in 0..NBY {
                    let j = if py { NBY - 1 - b } else { b };
                    let mut v = top[i * NBY + j];
                    let ni = if px { i + 1 } else { i.wrapping_sub(1) };
                    let nj = if py { j + 1 } else { j.wrapping_sub(1) };
                    if ni < NBX {
                        v = v.max(m[ni * NBY + j]);
                    }
                    if nj < NBY {
                        v = v.max(m[i * NBY + nj]);
                    }
                    m[i * NBY + j] = v;
                }
            }
            m
        });
        let ground_label = ground_label.iter().map(|&g| u8::try_from(g).unwrap_or(0)).collect();
        Skip { top, max_top, ground_only, ahead, cols, ground_label }
    }

    /// Same result as `cast`, skipping blocks the ray passes above.
    pub fn cast(&self, labels: &[u8], o: [f64; 3], d: [f64; 3], t_max: f64) -> Option<Hit> {
        self.cast_from(labels, o, d, t_max, 0.0)
    }

    /// Per block (x-major, `NBX` x `NBY`), the top face of its highest occupied voxel (m;
    /// -infinity for an empty block).
    pub fn tops(&self) -> &[f64] {
        &self.top
    }

    /// `cast` for a ray that meets no block it could pass below before distance `t_start`
    /// (`fan`): the block walk starts there.
    #[inline(always)]
    pub fn cast_from(&self, labels: &[u8], o: [f64; 3], d: [f64; 3], t_max: f64, t_start: f64) -> Option<Hit> {
        let inv = inverse(d);
        let (t_grid, t_out) = clip_to_grid(o, d, inv, t_max)?;
        let t_in = t_grid.max(t_start);
        if t_in > t_out {
            return None;
        }
        // Level or rising rays above every occupied voxel (most of the upper beams): nothing to hit.
        if d[2] >= 0.0 && o[2] + t_in * d[2] >= self.max_top {
            return None;
        }
        let WalkStart { idx, step, t_next, t_delta } =
            WalkStart::new(o, d, inv, t_in, VOXEL * B as f64, [0, 0], [NBX as i64, NBY as i64]);
        let ray = BlockRay {
            t_out,
            step,
            t_delta,
            // A rising ray only climbs: once it is above every block it can still reach, it is done.
            ahead: (d[2] >= 0.0).then(|| &self.ahead[2 * (d[0] >= 0.0) as usize + (d[1] >= 0.0) as usize][..]),
        };
        // Started inside the grid, the first block has no entry face; it is one the ray passes
        // above (or the sensor's own), so no hit reports it.
        let axis = if t_grid > 0.0 && t_in == t_grid { entry_axis(o, d, t_in) } else { 3 };
        let mut w = BlockWalk { t: t_in, tx: t_next[0], ty: t_next[1], ix: idx[0], iy: idx[1], axis };
        let descending = d[2] < 0.0;
        loop {
            let y_first = w.ty < w.tx;
            let tn = if y_first { w.ty } else { w.tx };
            let t_end = if tn < t_out { tn } else { t_out };
            let block = w.ix as usize * NBY + w.iy as usize;
            let top = self.top[block];
            let z_in = o[2] + w.t * d[2];
            if let Some(m) = ray.ahead
                && z_in >= m[block]
            {
                return None;
            }
            // The lowest point over the block: where it leaves it if descending.
            let z_low = if descending { o[2] + t_end * d[2] } else { z_in };
            if z_low < top {
                if self.ground_only[block] && descending && z_in >= GROUND_Z {
                    // Above the ground on entry and descending: the only thing to hit is the
                    // ground's top face, at the same distance the voxel walk computes for it.
                    let tg = (GROUND_Z - o[2]) * inv[2];
                    if tg <= t_end {
                        return ground_hit(labels, self.ground_label[block], o, d, inv, tg, t_out);
                    }
                } else {
                    let lo = [w.ix * B as i64, w.iy * B as i64, 0];
                    let hi = [lo[0] + B as i64, lo[1] + B as i64, NZ as i64];
                    if let Some(h) = walk_columns(labels, &self.cols, o, d, inv, w.t, t_end, w.axis, lo, hi) {
                        return Some(h);
                    }
                }
            }
            if !w.step(&ray, y_first) {
                return None;
            }
        }
    }
}

/// What `Skip::cast_from` knows of a ray for its block walk.
struct BlockRay<'a> {
    t_out: f64,
    step: [i64; 2],
    t_delta: [f64; 2],
    /// `Skip::ahead` of the ray's quadrant, for a rising ray.
    ahead: Option<&'a [f64]>,
}

/// The block walk's state: the distance at which the ray entered the current block, the next
/// boundary distances, the block and the axis of the face it entered through.
struct BlockWalk {
    t: f64,
    tx: f64,
    ty: f64,
    ix: i64,
    iy: i64,
    axis: usize,
}

impl BlockWalk {
    /// Step to the next block along y (`y` true) or x; false when the ray leaves the grid or
    /// passes `t_out` first.
    #[inline]
    fn step(&mut self, ray: &BlockRay, y: bool) -> bool {
        let tn = if y { self.ty } else { self.tx };
        if tn > ray.t_out {
            return false;
        }
        self.t = tn;
        self.ix = if y { self.ix } else { self.ix + ray.step[0] };
        self.iy = if y { self.iy + ray.step[1] } else { self.iy };
        self.tx = if y { self.tx } else { self.tx + ray.t_delta[0] };
        self.ty = if y { self.ty + ray.t_delta[1] } else { self.ty };
        self.axis = y as usize;
        (self.ix as u64) < NBX as u64 && (self.iy as u64) < NBY as u64
    }
}

/// z of the ground layer's top face (the k = K_GROUND_TOP boundary, 0 m).
const GROUND_Z: f64 = ORIGIN[2] + VOXEL * K_GROUND_TOP as f64;

/// The hit on the ground voxel a descending ray enters through its top face at distance `tg`.
/// `label`: the label of every ground voxel there, or 0 to read it from `labels`.
#[inline]
fn ground_hit(labels: &[u8], label: u8, o: [f64; 3], d: [f64; 3], inv: [f64; 3], tg: f64, t_out: f64) -> Option<Hit> {
    let n = [NX, NY];
    let mut voxel = [0usize, 0, K_GROUND];
    let mut t_exit = (GROUND_Z - VOXEL - o[2]) * inv[2];
    for a in 0..2 {
        let p = o[a] + tg * d[a];
        let i = floor_i64((p - ORIGIN[a]) / VOXEL).clamp(0, n[a] as i64 - 1) as usize;
        voxel[a] = i;
        if d[a] > 0.0 {
            t_exit = t_exit.min((ORIGIN[a] + (i + 1) as f64 * VOXEL - o[a]) * inv[a]);
        } else if d[a] < 0.0 {
            t_exit = t_exit.min((ORIGIN[a] + i as f64 * VOXEL - o[a]) * inv[a]);
        }
    }
    let label = if label != 0 { label } else { labels[flat(voxel[0], voxel[1], voxel[2])] };
    Some(Hit { t: tg, t_exit: t_exit.min(t_out.max(tg)), voxel, label, axis: 2 })
}

/// Entering from outside the grid: the entry face is the axis whose slab bound set t_in.
fn entry_axis(o: [f64; 3], d: [f64; 3], t_in: f64) -> usize {
    (0..3)
        .filter(|&a| d[a] != 0.0)
        .map(|a| {
            let tb = if d[a] > 0.0 { (ORIGIN[a] - o[a]) / d[a] } else { (UPPER[a] - o[a]) / d[a] };
            (a, (tb - t_in).abs())
        })
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .map_or(3, |(a, _)| a)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::Rng;

    fn grid_with(v: [usize; 3]) -> Vec<u8> {
        let mut g = vec![0u8; NX * NY * NZ];
        g[flat(v[0], v[1], v[2])] = 2;
        g
    }

    /// Entry distance of a ray into one voxel's box, by the slab method.
    fn slab(o: [f64; 3], d: [f64; 3], v: [usize; 3]) -> Option<f64> {
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            let lo = ORIGIN[a] + VOXEL * v[a] as f64;
            let hi = lo + VOXEL;
            if d[a] == 0.0 {
                if o[a] < lo || o[a] >= hi {
                    return None;
                }
            } else {
                let (ta, tb) = ((lo - o[a]) / d[a], (hi - o[a]) / d[a]);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
        }
        (t0 <= t1).then_some(t0)
    }

    fn unit(v: [f64; 3]) -> [f64; 3] {
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / n, v[1] / n, v[2] / n]
    }

    #[test]
    fn off_centre_origin_hits_the_voxel_where_the_slab_test_says() {
        // Origins nowhere near a voxel corner, rays aimed at random points of one voxel.
        let mut rng = Rng::new(11);
        for _ in 0..2000 {
            let o = [rng.range(-20.0, 20.0) + 0.137, rng.range(-20.0, 20.0) - 0.061, rng.range(-2.0, 4.0) + 0.033];
            let v = [rng.index(NX), rng.index(NY), rng.index(NZ)];
            let target = [
                ORIGIN[0] + VOXEL * (v[0] as f64 + rng.range(0.05, 0.95)),
                ORIGIN[1] + VOXEL * (v[1] as f64 + rng.range(0.05, 0.95)),
                ORIGIN[2] + VOXEL * (v[2] as f64 + rng.range(0.05, 0.95)),
            ];
            let d = unit([target[0] - o[0], target[1] - o[1], target[2] - o[2]]);
            let g = grid_with(v);
            let h = cast(&g, o, d, 1e3).expect("aimed at the voxel");
            assert_eq!(h.voxel, v);
            let t = slab(o, d, v).expect("slab agrees it is hit");
            assert!((h.t - t).abs() < 1e-9, "dda {} slab {t}", h.t);
            // The entry point lies on the voxel's boundary.
            let p = [o[0] + h.t * d[0], o[1] + h.t * d[1], o[2] + h.t * d[2]];
            if h.axis < 3 {
                let face = ORIGIN[h.axis] + VOXEL * (v[h.axis] as f64 + if d[h.axis] > 0.0 { 0.0 } else { 1.0 });
                assert!((p[h.axis] - face).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn rays_that_miss_a_lone_voxel_see_nothing() {
        let mut rng = Rng::new(5);
        let v = [203, 198, 14];
        let g = grid_with(v);
        for _ in 0..2000 {
            let o = [rng.range(-3.0, 3.0) + 0.01, rng.range(-3.0, 3.0) + 0.02, rng.range(-1.0, 2.0)];
            let d = unit([rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-0.5, 0.5)]);
            let dda = cast(&g, o, d, 1e3).map(|h| h.t);
            let brute = slab(o, d, v);
            match (dda, brute) {
                (Some(a), Some(b)) => assert!((a - b).abs() < 1e-9),
                (None, None) => {}
                other => panic!("dda and slab disagree: {other:?} from {o:?} along {d:?}"),
            }
        }
    }

    #[test]
    fn the_uniscene_tmax_bug_would_be_caught() {
        // With tMax measured from the grid corner instead of the origin, the first crossing of an
        // off-centre ray lands on the wrong boundary; ours crosses x = 0.25 exactly at 0.25 - 0.1.
        let g = grid_with([201, 200, 12]);
        let h = cast(&g, [0.1, 0.1, 0.1], [1.0, 0.0, 0.0], 10.0).expect("hit");
        assert_eq!(h.voxel, [201, 200, 12]);
        assert!((h.t - 0.15).abs() < 1e-12 && h.axis == 0);
        assert!((h.t_exit - 0.4).abs() < 1e-12);
    }

    #[test]
    fn block_skipping_finds_the_same_hits_as_the_plain_walk() {
        // Ground at k = 11 plus scattered blocks and floating voxels.
        let mut g = vec![0u8; NX * NY * NZ];
        for c in g.chunks_exact_mut(NZ) {
            c[11] = 1;
        }
        let mut rng = Rng::new(3);
        for _ in 0..400 {
            let (i, j, k) = (rng.index(NX - 4), rng.index(NY - 4), 12 + rng.index(NZ - 16));
            for di in 0..rng.index(4) + 1 {
                for dj in 0..rng.index(4) + 1 {
                    g[flat(i + di, j + dj, k)] = 2 + rng.index(7) as u8;
                }
            }
        }
        let skip = Skip::new(&g);
        let mut hits = 0;
        for n in 0..20_000 {
            let o = if n % 2 == 0 {
                [rng.range(-45.0, 45.0), rng.range(-45.0, 45.0), rng.range(0.0, 4.0)]
            } else {
                [rng.range(-80.0, 80.0), rng.range(-80.0, 80.0), rng.range(-5.0, 8.0)]
            };
            let d = unit([rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-0.3, 0.3)]);
            let a = cast(&g, o, d, 150.0);
            let b = skip.cast(&g, o, d, 150.0);
            match (a, b) {
                (Some(x), Some(y)) => {
                    assert_eq!((x.voxel, x.label, x.axis), (y.voxel, y.label, y.axis));
                    assert!((x.t - y.t).abs() < 1e-9 && (x.t_exit - y.t_exit).abs() < 1e-9, "{x:?} {y:?}");
                    hits += 1;
                }
                (None, None) => {}
                other => panic!("plain and skipping walks disagree: {other:?} from {o:?} along {d:?}"),
            }
        }
        assert!(hits > 5000);
    }

    #[test]
    fn floor_i64_is_floor_then_cast() {
        let mut rng = Rng::new(9);
        let mut xs = vec![0.0, -0.0, 0.5, -0.5, 1.0, -1.0, -1e-300, 1e-300, f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
        xs.extend([1e300, -1e300, 9.3e18, -9.3e18, -9.223372036854775e18, 4503599627370495.5, -4503599627370495.5]);
        xs.extend((0..10_000).map(|_| rng.range(-500.0, 500.0)));
        xs.extend((0..1000).map(|n| n as f64 * 0.25 - 100.0));
        for x in xs {
            assert_eq!(floor_i64(x), x.floor() as i64, "{x}");
        }
    }

    #[test]
    fn skip_summary_matches_a_plain_column_scan() {
        let mut g = vec![0u8; NX * NY * NZ];
        let mut rng = Rng::new(21);
        for c in g.chunks_exact_mut(NZ) {
            if rng.unit() < 0.9 {
                c[K_GROUND] = 1;
            }
            if rng.unit() < 0.01 {
                c[rng.index(NZ)] = 2;
            }
            if rng.unit() < 0.001 {
                c[K_GROUND] = 3;
            }
        }
        let skip = Skip::new(&g);
        for bi in 0..NBX {
            for bj in 0..NBY {
                let cols = || (0..B).flat_map(move |di| (0..B).map(move |dj| (bi * B + di, bj * B + dj)));
                let ground_only = cols().all(|(i, j)| (0..NZ).all(|k| (g[flat(i, j, k)] != 0) == (k == K_GROUND)));
                let top = cols()
                    .filter_map(|(i, j)| (0..NZ).rev().find(|&k| g[flat(i, j, k)] != 0))
                    .map(|k| ORIGIN[2] + VOXEL * (k + 1) as f64)
                    .fold(f64::NEG_INFINITY, f64::max);
                assert_eq!(skip.ground_only[bi * NBY + bj], ground_only);
                assert_eq!(skip.top[bi * NBY + bj], top);
                let grounds: Vec<u8> = cols().map(|(i, j)| g[flat(i, j, K_GROUND)]).collect();
                let same = grounds.iter().all(|&l| l == grounds[0]);
                assert_eq!(skip.ground_label[bi * NBY + bj], if same { grounds[0] } else { 0 });
                for (i, j) in cols() {
                    let bits = (0..NZ).filter(|&k| g[flat(i, j, k)] != 0).fold(0u32, |m, k| m | 1 << k);
                    assert_eq!(skip.cols[i * NY + j], bits);
                }
            }
        }
        // `ahead`: the highest top over every block a ray of each quadrant can still reach.
        for _ in 0..300 {
            let (bi, bj, q) = (rng.index(NBX), rng.index(NBY), rng.index(4));
            let xs: Vec<usize> = if q >> 1 == 1 { (bi..NBX).collect() } else { (0..=bi).collect() };
            let ys: Vec<usize> = if q & 1 == 1 { (bj..NBY).collect() } else { (0..=bj).collect() };
            let want = xs
                .iter()
                .flat_map(|&i| ys.iter().map(move |&j| (i, j)))
                .map(|(i, j)| skip.top[i * NBY + j])
                .fold(f64::NEG_INFINITY, f64::max);
            assert_eq!(skip.ahead[q][bi * NBY + bj], want, "block ({bi}, {bj}) quadrant {q}");
        }
        // Fed in pieces that split the runs of B columns (as a writer's pieces might), the same.
        let mut s = Skip::summary();
        for piece in g.chunks(NZ * 13) {
            s.add(piece);
        }
        let pieced = s.finish().expect("every column was added");
        assert_eq!((&pieced.cols, &pieced.top, &pieced.ground_only), (&skip.cols, &skip.top, &skip.ground_only));
        assert_eq!((&pieced.ground_label, pieced.ahead.clone()), (&skip.ground_label, skip.ahead.clone()));
        let mut short = Skip::summary();
        short.add(&g[..NZ * 100]);
        assert!(short.finish().is_none());
    }

    #[test]
    fn rays_from_outside_enter_through_the_grid_face() {
        let g = grid_with([0, 200, 12]);
        let h = cast(&g, [-60.0, 0.1, 0.1], [1.0, 0.0, 0.0], 100.0).expect("hit");
        assert!((h.t - 10.0).abs() < 1e-12 && h.axis == 0);
        assert!(cast(&g, [-60.0, 0.1, 0.1], [-1.0, 0.0, 0.0], 100.0).is_none());
    }
}
