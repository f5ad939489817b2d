//! `gts/NNNNNN/labels.npz` (`rocc compile --visibility`), Occ3D's per-frame file: `semantics`,
//! `mask_lidar` and `mask_camera`, each uint8 (400, 400, 32) like the occupancy, the masks 0 or
//! 1 (`visibility` fills them). Occ3D writes all three as uint8 and its loaders
//! (CVPR2023-occupancy's `LoadOccGTFromFile`) cast the masks with `.astype(bool)`.

use super::Npz;
use crate::backend::Occupancy;
use crate::backend::layout::{NX, NY, NZ};
use crate::visibility::Masks;
use std::io;
use std::path::{Path, PathBuf};

/// The npz keys, as Occ3D names them.
pub const SEMANTICS_KEY: &str = "semantics";
pub const MASK_LIDAR_KEY: &str = "mask_lidar";
pub const MASK_CAMERA_KEY: &str = "mask_camera";

/// `dir/gts/NNNNNN/labels.npz` for frame `frame`: Occ3D's `gts/<scene>/<token>/labels.npz`
/// with the clip as the scene and the frame number as the token.
pub fn labels_frame_path(dir: &Path, frame: usize) -> PathBuf {
    dir.join("gts").join(format!("{frame:06}")).join("labels.npz")
}

/// Write the labels and both masks, atomically.
pub fn write_labels(path: &Path, occ: &Occupancy, masks: &Masks) -> io::Result<u64> {
    let shape = [NX, NY, NZ];
    let labels = occ.labels.as_standard_layout();
    let semantics = labels.as_slice().ok_or_else(|| io::Error::other("labels: occupancy not contiguous"))?;
    let mut npz = Npz::default();
    npz.add(SEMANTICS_KEY, &shape, semantics)?;
    npz.add(MASK_LIDAR_KEY, &shape, &masks.lidar)?;
    npz.add(MASK_CAMERA_KEY, &shape, &masks.camera)?;
    crate::fsio::write_atomic(path, |w| npz.finish(w))
}
