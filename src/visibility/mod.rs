//! Visibility pass (`rocc compile --visibility`). In: one frame's occupancy, the LiDAR `Rig` and
//! a `CameraRig`. Out: Occ3D's two observation masks over the (400, 400, 32) grid, one byte per
//! voxel (1 observed, 0 not), written with the labels as `gts/NNNNNN/labels.npz`
//! (`output::write_labels`).
//!
//! Both masks walk rays through the grid with the LiDAR's voxel walk (`lidar::dda::traverse`)
//! and mark every free voxel a ray passes through and the first occupied voxel it reaches:
//!
//! - `mask_lidar`: every ray the rig fires (`lidar::for_each_ray`), up to `max_range`. The
//!   drop model and range noise do not apply: the mask says what the rays reach, as Occ3D's
//!   says what its accumulated sweeps reach.
//! - `mask_camera`: one ray per `ray_stride_px` pixels of each camera (Occ3D casts from the
//!   camera centres too), as far as the grid reaches. A voxel behind the first occupied voxel
//!   of every ray is not in it; neither is one outside every frustum.
//!
//! Marks are set, never cleared, so ray order does not change the masks.

pub mod camera;

pub use camera::{Camera, CameraRig};

use crate::backend::Occupancy;
use crate::backend::layout::{NX, NY, NZ, flat};
use crate::lidar::{Rig, dda, for_each_ray};

/// Voxels in a mask, C order over (NX, NY, NZ) like the labels.
pub const N: usize = NX * NY * NZ;

/// The two masks of one frame, 0 or 1 per voxel.
#[derive(Clone, Debug, Default)]
pub struct Masks {
    pub lidar: Vec<u8>,
    pub camera: Vec<u8>,
}

/// Fill `m` for `occ` (all zeros for a grid of another size, which rocc never makes).
pub fn masks_into(occ: &Occupancy, lidar: &Rig, cameras: &CameraRig, m: &mut Masks) {
    for v in [&mut m.lidar, &mut m.camera] {
        v.clear();
        v.resize(N, 0);
    }
    let Some(labels) = occ.labels.as_slice().filter(|_| occ.labels.dim() == (NX, NY, NZ)) else { return };
    for_each_ray(lidar, |o, d| mark(labels, o, d, lidar.max_range, &mut m.lidar));
    for c in &cameras.cameras {
        let o = [c.origin.0, c.origin.1, c.origin.2];
        for d in c.rays(cameras.ray_stride_px) {
            mark(labels, o, d, f64::INFINITY, &mut m.camera);
        }
    }
}

/// Mark the free voxels along one ray and the occupied voxel that ends it.
fn mark(labels: &[u8], o: [f64; 3], d: [f64; 3], t_max: f64, mask: &mut [u8]) {
    let hit = dda::traverse(labels, o, d, t_max, |at| mask[at] = 1);
    if let Some(h) = hit {
        mask[flat(h.voxel[0], h.voxel[1], h.voxel[2])] = 1;
    }
}
