//! The voxel walks of `dda` (Amanatides & Woo): from where a ray enters a box of voxels to its
//! first occupied voxel. `walk` tests each voxel with a function (`dda::cast` reads the labels,
//! `dda::traverse` also reports the free voxels passed); `walk_columns` reads `dda::Skip`'s
//! per-column bit masks once per column.

use crate::backend::layout::{NY, ORIGIN, VOXEL, flat};

/// The first occupied voxel along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance from the origin to where the ray enters the voxel (0 if it starts inside).
    pub t: f64,
    /// Distance to where it leaves it.
    pub t_exit: f64,
    pub voxel: [usize; 3],
    pub label: u8,
    /// Axis (0 x, 1 y, 2 z) of the entry face; 3 if the ray starts inside the voxel.
    pub axis: usize,
}

/// `x.floor() as i64`, bit for bit (saturating at the ends, 0 for NaN), without the libm call
/// that `f64::floor` compiles to on baseline x86-64: the walks take two or three per block.
#[inline]
pub(super) fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x { t.saturating_sub(1) } else { t }
}

/// The voxel walk from distance `t_in` to `t_out` inside voxel index box [lo, hi); `axis` is
/// the face the ray entered through at `t_in`; `seen` gets each free voxel passed (the LiDAR
/// passes a no-op, which compiles away).
#[allow(clippy::too_many_arguments)]
#[inline]
pub(super) fn walk(
    labels: &[u8],
    occupied: impl Fn(usize) -> bool,
    o: [f64; 3],
    d: [f64; 3],
    inv: [f64; 3],
    t_in: f64,
    t_out: f64,
    axis: usize,
    lo: [i64; 3],
    hi: [i64; 3],
    mut seen: impl FnMut(usize),
) -> Option<Hit> {
    let WalkStart { idx, step, t_next, t_delta } = WalkStart::new(o, d, inv, t_in, VOXEL, lo, hi);
    let axes = Axis::three(step, t_delta, lo, hi);
    // The same additions and comparisons as one loop over [f64; 3] would make, on scalars the
    // compiler keeps in registers (an array indexed by the stepping axis lives on the stack).
    let (mut tx, mut ty, mut tz) = (t_next[0], t_next[1], t_next[2]);
    let (mut i, mut j, mut k) = (idx[0], idx[1], idx[2]);
    let mut t = t_in;
    let mut axis = axis;
    loop {
        let a = if tx <= ty && tx <= tz {
            0
        } else if ty <= tz {
            1
        } else {
            2
        };
        let at = flat(i as usize, j as usize, k as usize);
        if occupied(at) {
            let label = labels[at];
            let tn = [tx, ty, tz][a];
            let voxel = [i as usize, j as usize, k as usize];
            return Some(Hit { t, t_exit: tn.min(t_out.max(t)), voxel, label, axis });
        }
        seen(at);
        let stepped = match a {
            0 => axes[0].advance(&mut t, &mut tx, &mut i, t_out),
            1 => axes[1].advance(&mut t, &mut ty, &mut j, t_out),
            _ => axes[2].advance(&mut t, &mut tz, &mut k, t_out),
        };
        if !stepped {
            return None;
        }
        axis = a;
    }
}

/// Where a grid walk starts: the cell holding the entry point, per axis the step, the distance
/// to the first boundary and between boundaries. The cells are `cell` metres on a side, from
/// `ORIGIN`, over the first `N` axes: voxels (`walk`, `walk_columns`) or `Skip`'s blocks.
pub(super) struct WalkStart<const N: usize> {
    pub idx: [i64; N],
    pub step: [i64; N],
    pub t_next: [f64; N],
    pub t_delta: [f64; N],
}

impl<const N: usize> WalkStart<N> {
    /// Cells inside the index box [lo, hi).
    #[inline(always)]
    pub fn new(o: [f64; 3], d: [f64; 3], inv: [f64; 3], t_in: f64, cell: f64, lo: [i64; N], hi: [i64; N]) -> Self {
        let mut idx = [0i64; N];
        let mut step = [0i64; N];
        let mut t_next = [f64::INFINITY; N];
        let mut t_delta = [f64::INFINITY; N];
        for a in 0..N {
            // The cell holding the entry point; clamped because the entry lies on the box's face.
            let p = o[a] + t_in * d[a];
            idx[a] = floor_i64((p - ORIGIN[a]) / cell).clamp(lo[a], hi[a] - 1);
            if d[a] > 0.0 {
                step[a] = 1;
                t_next[a] = (ORIGIN[a] + (idx[a] + 1) as f64 * cell - o[a]) * inv[a];
                t_delta[a] = cell * inv[a];
            } else if d[a] < 0.0 {
                step[a] = -1;
                t_next[a] = (ORIGIN[a] + idx[a] as f64 * cell - o[a]) * inv[a];
                t_delta[a] = -cell * inv[a];
            }
        }
        WalkStart { idx, step, t_next, t_delta }
    }
}

/// One axis of a voxel walk: its step, the distance between its boundaries and its index range.
#[derive(Clone, Copy)]
struct Axis {
    step: i64,
    delta: f64,
    lo: i64,
    hi: i64,
}

impl Axis {
    #[inline(always)]
    fn three(step: [i64; 3], delta: [f64; 3], lo: [i64; 3], hi: [i64; 3]) -> [Axis; 3] {
        std::array::from_fn(|a| Axis { step: step[a], delta: delta[a], lo: lo[a], hi: hi[a] })
    }

    /// Step across this axis' next boundary (`*boundary`, which moves on by `delta`) into the
    /// next cell: `false` when the boundary lies beyond `t_out` or the cell outside the range.
    /// The walks keep `t`, the boundaries and the indices as scalars (registers, once inlined).
    #[inline(always)]
    fn advance(&self, t: &mut f64, boundary: &mut f64, index: &mut i64, t_out: f64) -> bool {
        *t = *boundary;
        if *t > t_out {
            return false;
        }
        *index += self.step;
        if *index < self.lo || *index >= self.hi {
            return false;
        }
        *boundary += self.delta;
        true
    }
}

/// `walk` for `Skip`, with `cols` (`Skip::cols`) for the occupancy: the same voxels in the same
/// order, the same comparisons and sums, so the same hit. A column's mask is read once when the
/// walk enters it, and the steps along z inside it form their own loop: z is stepped exactly
/// when `walk` would pick it (tz below both tx and ty; no distance is NaN), and between x and y
/// the tie goes to x as there.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn walk_columns(
    labels: &[u8],
    cols: &[u32],
    o: [f64; 3],
    d: [f64; 3],
    inv: [f64; 3],
    t_in: f64,
    t_out: f64,
    axis: usize,
    lo: [i64; 3],
    hi: [i64; 3],
) -> Option<Hit> {
    let WalkStart { idx, step, t_next, t_delta } = WalkStart::new(o, d, inv, t_in, VOXEL, lo, hi);
    let axes = Axis::three(step, t_delta, lo, hi);
    let (mut tx, mut ty, mut tz) = (t_next[0], t_next[1], t_next[2]);
    let (mut i, mut j, mut k) = (idx[0], idx[1], idx[2]);
    let mut t = t_in;
    let mut axis = axis;
    loop {
        let mask = cols[i as usize * NY + j as usize];
        loop {
            if mask >> k & 1 != 0 {
                let voxel = [i as usize, j as usize, k as usize];
                let label = labels[flat(voxel[0], voxel[1], voxel[2])];
                // `walk`'s next boundary: the least of the three.
                let tn = tx.min(ty).min(tz);
                return Some(Hit { t, t_exit: tn.min(t_out.max(t)), voxel, label, axis });
            }
            if !(tz < tx && tz < ty) {
                break;
            }
            if !axes[2].advance(&mut t, &mut tz, &mut k, t_out) {
                return None;
            }
            axis = 2;
        }
        if tx <= ty {
            if !axes[0].advance(&mut t, &mut tx, &mut i, t_out) {
                return None;
            }
            axis = 0;
        } else {
            if !axes[1].advance(&mut t, &mut ty, &mut j, t_out) {
                return None;
            }
            axis = 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::layout::{NX, NZ};
    use crate::sample::Rng;

    #[test]
    fn the_column_walk_gives_the_voxel_walks_hit_bit_for_bit() {
        // Scattered boxes and single voxels, rays from inside whole grid and inside one block.
        let mut rng = Rng::new(8);
        let mut g = vec![0u8; NX * NY * NZ];
        for _ in 0..3000 {
            let (i, j, k) = (rng.index(NX - 3), rng.index(NY - 3), rng.index(NZ - 3));
            for n in 0..rng.index(27) + 1 {
                g[flat(i + n % 3, j + n / 3 % 3, k + n / 9)] = 1 + rng.index(8) as u8;
            }
        }
        let cols: Vec<u32> =
            g.chunks_exact(NZ).map(|c| (0..NZ).fold(0, |m, k| m | u32::from(c[k] != 0) << k)).collect();
        let occupied = |at: usize| cols[at / NZ] >> (at % NZ) & 1 != 0;
        let (mut hits, mut misses) = (0, 0);
        for n in 0..40_000 {
            let (lo, hi) = if n % 2 == 0 {
                ([0, 0, 0], [NX as i64, NY as i64, NZ as i64])
            } else {
                let (bi, bj) = (rng.index(NX / 8) as i64 * 8, rng.index(NY / 8) as i64 * 8);
                ([bi, bj, 0], [bi + 8, bj + 8, NZ as i64])
            };
            let o: [f64; 3] = std::array::from_fn(|a| {
                ORIGIN[a] + VOXEL * (lo[a] as f64 + rng.range(0.0, 1.0) * (hi[a] - lo[a]) as f64)
            });
            // Level, axis-aligned and diagonal directions too, where ties between axes happen.
            let raw = match n % 5 {
                0 => [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.0],
                1 => [1.0, 1.0, -1.0],
                2 => [-1.0, 0.0, 0.0],
                _ => [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-0.5, 0.5)],
            };
            let len = (raw[0] * raw[0] + raw[1] * raw[1] + raw[2] * raw[2]).sqrt();
            let d = raw.map(|x| x / len);
            let inv = [1.0 / d[0], 1.0 / d[1], 1.0 / d[2]];
            let t_out = rng.range(1.0, 150.0);
            let a = walk(&g, occupied, o, d, inv, 0.0, t_out, 3, lo, hi, |_| {});
            let b = walk_columns(&g, &cols, o, d, inv, 0.0, t_out, 3, lo, hi);
            assert_eq!(a, b, "from {o:?} along {d:?} in {lo:?}..{hi:?}");
            if a.is_some() { hits += 1 } else { misses += 1 }
        }
        assert!(hits > 5000 && misses > 5000, "{hits} hits, {misses} misses");
    }
}
