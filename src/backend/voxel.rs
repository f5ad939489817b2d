//! Column-mask voxeliser. In: an object (primitives in its local frame, an ego-frame pose, the
//! height of its bottom, a label) and a label grid. Out: the object's voxels written into the
//! grid, either solid or as its shell (surface mode).
//!
//! Each ground column of the object's footprint holds its occupied layers as one `u64` bit mask
//! (bit e = layer e - 1, so layers -1 and 32 just outside the grid are kept too). Primitives OR
//! their z intervals into the masks; the shell is then six bit operations per column: a voxel is
//! interior when its neighbours above, below and on the four sides are all solid. Solid means
//! "inside this object, or ground, or beyond the grid": a roof above z = 5 m or a wall cut by the
//! grid's edge is not invented as a surface, and the face an object rests on the ground with is
//! not one LiDAR could ever see.
//!
//! A voxel belongs to a primitive when its centre does (the BEV's rule for pixels, so coverage
//! is measured on the same columns). A primitive too small to contain any column centre still
//! gets the column holding its centre, and an interval too thin to contain a layer centre the
//! layer holding its midpoint: a 0.1 m piece of debris is not silently lost.

use super::layout::{K_GROUND, NX, NY, NZ, ORIGIN, VOXEL, flat};
use super::shape::Prim;

/// How agents and structures are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Only the shell: what accumulated LiDAR sweeps see, as nuPlan-Occ ground truth is built.
    #[default]
    Surface,
    /// Filled solids.
    Solid,
}

/// One object to draw: primitives in the local frame (u forward, v left, z from the bottom).
pub struct Obj<'a> {
    pub prims: &'a [Prim],
    /// Ego-frame centre and heading.
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
    /// Ego-frame height of the local z = 0.
    pub z_bottom: f64,
    pub label: u8,
}

/// Ground layer bit in the extended (shifted by one) layer index.
const GROUND_BIT: u64 = 1 << (K_GROUND + 1);
const EXT_LAYERS: i64 = NZ as i64 + 2;

/// Bits of the extended layers (e = k + 1, e in 0..=33) whose centres lie in [z0, z1] (ego z).
#[inline]
fn bits(z0: f64, z1: f64) -> u64 {
    if z1 < z0 {
        return 0;
    }
    // Centre of extended layer e: ORIGIN_z + VOXEL (e - 1 + 0.5).
    let base = ORIGIN[2] - 0.5 * VOXEL;
    let lo = ((z0 - base) / VOXEL).ceil();
    let hi = ((z1 - base) / VOXEL).floor();
    let (lo, hi) = if lo > hi {
        // No centre inside: take the layer holding the midpoint.
        let m = (((z0 + z1) / 2.0 - (ORIGIN[2] - VOXEL)) / VOXEL).floor();
        (m, m)
    } else {
        (lo, hi)
    };
    let lo = lo.max(0.0);
    let hi = hi.min((EXT_LAYERS - 1) as f64);
    // NaN heights compare false here and draw nothing.
    if lo.partial_cmp(&hi).is_none_or(|o| o == std::cmp::Ordering::Greater) {
        return 0;
    }
    let (lo, hi) = (lo as u32, hi as u32);
    let upto = if hi >= 63 { u64::MAX } else { (1u64 << (hi + 1)) - 1 };
    upto & !((1u64 << lo) - 1)
}

/// Reusable scratch for drawing objects one after another.
#[derive(Debug, Default)]
pub struct Voxelizer {
    cols: Vec<u64>,
}

impl Voxelizer {
    pub fn new() -> Self {
        Self::default()
    }

    /// Draw `obj` into `labels` (standard-layout (400, 400, 32)). Columns where `skip` (400 x 400,
    /// row-major [i, j]) is true are left alone. Returns the number of voxels written.
    pub fn draw(&mut self, labels: &mut [u8], obj: &Obj, mode: Mode, skip: Option<&[bool]>) -> usize {
        debug_assert_eq!(labels.len(), NX * NY * NZ);
        let (c, s) = (obj.yaw.cos(), obj.yaw.sin());
        let to_ego = |u: f64, v: f64| (obj.x + u * c - v * s, obj.y + u * s + v * c);
        let col_range = |b: (f64, f64, f64, f64)| {
            let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
            for (u, v) in [(b.0, b.2), (b.0, b.3), (b.1, b.2), (b.1, b.3)] {
                let (x, y) = to_ego(u, v);
                x0 = x0.min(x);
                x1 = x1.max(x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
            let f = |m: f64, a: usize| ((m - ORIGIN[a]) / VOXEL).floor();
            (f(x0, 0), f(x1, 0), f(y0, 1), f(y1, 1))
        };
        // The object's column range plus a one-column halo, clipped to one column beyond the grid.
        let (mut bx0, mut bx1, mut by0, mut by1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for p in obj.prims {
            let (a, b, cc, d) = col_range(p.bounds());
            bx0 = bx0.min(a);
            bx1 = bx1.max(b);
            by0 = by0.min(cc);
            by1 = by1.max(d);
        }
        if !(bx0.is_finite() && bx1.is_finite() && by0.is_finite() && by1.is_finite()) {
            return 0;
        }
        let (gx, gy) = (NX as f64, NY as f64);
        if bx1 < -1.0 || by1 < -1.0 || bx0 > gx || by0 > gy {
            return 0;
        }
        let i0 = (bx0 - 1.0).max(-1.0) as i64;
        let i1 = (bx1 + 1.0).min(gx) as i64;
        let j0 = (by0 - 1.0).max(-1.0) as i64;
        let j1 = (by1 + 1.0).min(gy) as i64;
        let (ni, nj) = ((i1 - i0 + 1) as usize, (j1 - j0 + 1) as usize);
        self.cols.clear();
        self.cols.resize(ni * nj, 0);

        for p in obj.prims {
            let (a, b, cc, d) = col_range(p.bounds());
            let (pi0, pi1) = ((a as i64).max(i0), (b as i64).min(i1));
            let (pj0, pj1) = ((cc as i64).max(j0), (d as i64).min(j1));
            let mut any = false;
            for i in pi0..=pi1 {
                let dx = ORIGIN[0] + VOXEL * (i as f64 + 0.5) - obj.x;
                for j in pj0..=pj1 {
                    let dy = ORIGIN[1] + VOXEL * (j as f64 + 0.5) - obj.y;
                    let (u, v) = (dx * c + dy * s, -dx * s + dy * c);
                    if let Some((z0, z1)) = p.column(u, v) {
                        let m = bits(obj.z_bottom + z0, obj.z_bottom + z1);
                        if m != 0 {
                            self.cols[(i - i0) as usize * nj + (j - j0) as usize] |= m;
                            any = true;
                        }
                    }
                }
            }
            if !any {
                // Too small for any column centre: the column holding the primitive's centre.
                let (u, v) = p.centre();
                let (x, y) = to_ego(u, v);
                let i = ((x - ORIGIN[0]) / VOXEL).floor() as i64;
                let j = ((y - ORIGIN[1]) / VOXEL).floor() as i64;
                if (i0..=i1).contains(&i)
                    && (j0..=j1).contains(&j)
                    && let Some((z0, z1)) = p.column(u, v)
                {
                    self.cols[(i - i0) as usize * nj + (j - j0) as usize] |= bits(obj.z_bottom + z0, obj.z_bottom + z1);
                }
            }
        }

        let mut written = 0;
        let solid = |m: u64| m | GROUND_BIT;
        for li in 0..ni {
            let i = li as i64 + i0;
            if i < 0 || i >= NX as i64 {
                continue;
            }
            for lj in 0..nj {
                let j = lj as i64 + j0;
                if j < 0 || j >= NY as i64 {
                    continue;
                }
                let m = self.cols[li * nj + lj];
                if m == 0 {
                    continue;
                }
                let (i, j) = (i as usize, j as usize);
                if skip.is_some_and(|sk| sk[i * NY + j]) {
                    continue;
                }
                let out = match mode {
                    Mode::Solid => m,
                    Mode::Surface => {
                        // In-grid columns are never on the buffer's edge (halo), so the four
                        // neighbours exist.
                        let cols = &self.cols;
                        let nb = |a: usize, b: usize| cols[a * nj + b];
                        let s = solid(m);
                        let interior = m
                            & (s >> 1)
                            & (s << 1)
                            & solid(nb(li + 1, lj))
                            & solid(nb(li - 1, lj))
                            & solid(nb(li, lj + 1))
                            & solid(nb(li, lj - 1));
                        m & !interior
                    }
                };
                let mut layers = (out >> 1) & ((1u64 << NZ) - 1);
                let base = flat(i, j, 0);
                while layers != 0 {
                    let k = layers.trailing_zeros() as usize;
                    labels[base + k] = obj.label;
                    written += 1;
                    layers &= layers - 1;
                }
            }
        }
        written
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layer_bits_follow_voxel_centres() {
        // Layer 12 (ext 13) has its centre at z = 0.125.
        assert_eq!(bits(0.0, 0.2), 1 << 13);
        // Too thin for a centre: the layer holding the midpoint.
        assert_eq!(bits(0.0, 0.1), 1 << 13);
        assert_eq!(bits(0.0, 0.5), (1 << 13) | (1 << 14));
        // Far above the grid: clipped to the extended top layer 33.
        assert_eq!(bits(4.8, 100.0), (1 << 32) | (1 << 33));
        assert_eq!(bits(200.0, 300.0), 0);
    }
}
