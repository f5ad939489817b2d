//! The packed Gaussian table the splat operation takes: one row of `COLS` floats per Gaussian,
//! and the plain shape of the region it writes.

use crate::backend::layout::{N_LABELS, NZ};

/// Mean, continuous voxel coordinates (3).
pub const MEAN: usize = 0;
/// Standard deviations along the local axes, voxels (3).
pub const SCALE: usize = 3;
/// R row-major (9): column j is local axis j in grid coordinates.
pub const ROT: usize = 6;
/// Opacity in (0, 1) (1).
pub const OPACITY: usize = 15;
/// Class features, channel 0 free (9).
pub const FEAT: usize = 16;
/// Batch element, a small whole number stored as a float (1; gets no gradient).
pub const BATCH: usize = FEAT + N_LABELS;
pub const COLS: usize = BATCH + 1;

/// Where the splat writes: `batch` grids of the region's columns (every layer), and the window
/// radius `r` (a Gaussian reaches the (2 r + 1)^3 voxels around the one holding its mean).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SplatShape {
    pub i0: u32,
    pub j0: u32,
    pub ni: u32,
    pub nj: u32,
    pub batch: u32,
    pub window: u32,
}

impl SplatShape {
    pub fn voxels(&self) -> usize {
        self.ni as usize * self.nj as usize * NZ
    }

    /// Flat index of grid voxel (i, j, k) inside one batch element's region, `None` outside.
    #[inline]
    pub fn flat(&self, i: i64, j: i64, k: i64) -> Option<usize> {
        let (li, lj) = (i - self.i0 as i64, j - self.j0 as i64);
        if li < 0 || lj < 0 || k < 0 || li >= self.ni as i64 || lj >= self.nj as i64 || k >= NZ as i64 {
            return None;
        }
        Some((li as usize * self.nj as usize + lj as usize) * NZ + k as usize)
    }
}
