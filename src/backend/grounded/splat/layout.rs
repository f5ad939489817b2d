//! The packed Gaussian table the splat operation takes: one row of `COLS` floats per Gaussian,
//! and the plain shape of the region it writes.

use super::Region;
use crate::backend::layout::N_LABELS;

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
    pub region: Region,
    pub batch: usize,
    pub window: usize,
}
