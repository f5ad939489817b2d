//! Visibility pass (`rocc compile --visibility`). In: one frame's occupancy, the LiDAR `Rig` and
//! a `CameraRig`. Out: Occ3D's two observation masks over the (400, 400, 32) grid, one byte per
//! voxel (1 observed, 0 not), written with the labels as `gts/NNNNNN/labels.npz`
//! (`output::write_labels`).
//!
//! Both masks walk rays through the grid with the LiDAR's voxel walk (`lidar::dda::traverse`)
//! and mark every free voxel a ray passes through and the first occupied voxel it reaches:
//!
//! - `mask_lidar`: every ray the rig fires (`lidar::scan`'s rays), up to `max_range`. The
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
use crate::lidar::{Rig, dda, ray_dir};
use rayon::prelude::*;

/// Voxels in a mask, C order over (NX, NY, NZ) like the labels.
pub const N: usize = NX * NY * NZ;

/// The two masks of one frame, 0 or 1 per voxel.
#[derive(Clone, Debug, Default)]
pub struct Masks {
    pub lidar: Vec<u8>,
    pub camera: Vec<u8>,
}

/// A share of a frame's rays: one LiDAR beam's sweep, or one row of a camera's rays.
#[derive(Clone, Copy)]
enum Unit {
    Beam { sensor: usize, beam: usize },
    Row { camera: usize, row: u32 },
}

/// Fill `m` for `occ` (all zeros for a grid of another size, which rocc never makes). The rays
/// are shared among rayon's threads (a frame is 130 ms of work, and `--visibility` on a short
/// clip has fewer frames than cores); each share marks its own masks, which are OR-ed together,
/// so the result does not depend on the split.
pub fn masks_into(occ: &Occupancy, lidar: &Rig, cameras: &CameraRig, m: &mut Masks) {
    for v in [&mut m.lidar, &mut m.camera] {
        v.clear();
        v.resize(N, 0);
    }
    let Some(labels) = occ.labels.as_slice().filter(|_| occ.labels.dim() == (NX, NY, NZ)) else { return };
    let trig = lidar.azimuth_trig();
    let beams = lidar
        .sensors
        .iter()
        .enumerate()
        .flat_map(|(sensor, s)| (0..s.elevations_deg.len()).map(move |beam| Unit::Beam { sensor, beam }));
    let stride = cameras.ray_stride_px;
    let rows = cameras
        .cameras
        .iter()
        .enumerate()
        .flat_map(|(camera, c)| (0..c.height / stride).map(move |row| Unit::Row { camera, row }));
    let units: Vec<Unit> = beams.chain(rows).collect();
    let run = |unit: Unit, m: &mut Masks| match unit {
        Unit::Beam { sensor, beam } => {
            let s = &lidar.sensors[sensor];
            let (rot, o) = (s.rotation(), lidar.sensor_origin(s));
            let el = s.elevations_deg[beam].to_radians();
            for &a in &trig[sensor] {
                mark(labels, o, ray_dir(&rot, (el.cos(), el.sin()), a), lidar.max_range, &mut m.lidar);
            }
        }
        Unit::Row { camera, row } => {
            let c = &cameras.cameras[camera];
            let (o, s) = ([c.origin.0, c.origin.1, c.origin.2], stride as f64);
            for a in 0..c.width / stride {
                let d = c.ray((a as f64 + 0.5) * s, (row as f64 + 0.5) * s);
                mark(labels, o, d, f64::INFINITY, &mut m.camera);
            }
        }
    };
    // Share k takes every parts-th unit from k on: neighbouring beams and rows cost alike.
    let parts = rayon::current_num_threads().clamp(1, units.len().max(1));
    let share = |k: usize, m: &mut Masks| units.iter().skip(k).step_by(parts).for_each(|&u| run(u, m));
    let (_, others) = rayon::join(
        || share(0, m),
        || {
            (1..parts)
                .into_par_iter()
                .map(|k| {
                    let mut own = Masks { lidar: vec![0; N], camera: vec![0; N] };
                    share(k, &mut own);
                    own
                })
                .collect::<Vec<_>>()
        },
    );
    for o in others {
        for (mine, theirs) in [(&mut m.lidar, &o.lidar), (&mut m.camera, &o.camera)] {
            mine.iter_mut().zip(theirs).for_each(|(a, b)| *a |= b);
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
