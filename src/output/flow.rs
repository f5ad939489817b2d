//! `flow/NNNNNN.npz` (`rocc compile --flow`): one key, `flow`, float32 (400, 400, 32, 3), the
//! grid `backend::flow` fills.

use super::Npz;
use crate::backend::flow::{C, Flow};
use crate::backend::layout::{NX, NY, NZ};
use std::io;
use std::path::{Path, PathBuf};

/// The npz key of the flow array.
pub const FLOW_KEY: &str = "flow";

/// `dir/flow/NNNNNN.npz` for frame `frame`.
pub fn flow_frame_path(dir: &Path, frame: usize) -> PathBuf {
    dir.join("flow").join(format!("{frame:06}.npz"))
}

/// Write `flow` under `FLOW_KEY`, atomically (all zeros if it was never filled).
pub fn write_flow(path: &Path, flow: &Flow) -> io::Result<u64> {
    let zeros;
    let v = if flow.values().is_empty() {
        zeros = vec![0.0f32; NX * NY * NZ * C];
        &zeros
    } else {
        flow.values()
    };
    let mut npz = Npz::default();
    npz.add(FLOW_KEY, &[NX, NY, NZ, C], v)?;
    crate::fsio::write_atomic(path, |w| npz.finish(w))
}
