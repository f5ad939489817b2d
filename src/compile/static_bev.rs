//! `--static-bev`: a recorded BEV whose static and divider layers replace the map's in every
//! frame. In: one `.npz` used for every frame, or a directory of per-frame `NNNNNN.npz` (a
//! compiled clip's `bev/`). Out: the frame's BEV with those layers swapped in.

use crate::diag::Diagnostic;
use crate::raster::{Bev, keep_static};
use std::path::{Path, PathBuf};

/// A loaded `--static-bev`.
#[derive(Clone, Debug)]
pub struct StaticBev {
    /// As given on the command line (recorded in the manifest).
    pub source: String,
    one: Option<Box<Bev>>,
    dir: Option<PathBuf>,
}

impl StaticBev {
    pub fn load(path: &Path) -> Result<StaticBev, Diagnostic> {
        let bad = |m: String| {
            Diagnostic::error("E0708", format!("static BEV `{}`: {m}", path.display()))
                .help("pass a nuPlan-Occ BEV `.npz` (gt_bev_masks int8 (18, 400, 400)) or a directory of NNNNNN.npz")
        };
        if path.is_dir() {
            return Ok(StaticBev { source: path.display().to_string(), one: None, dir: Some(path.to_path_buf()) });
        }
        let bev = crate::output::read_npz(path).map_err(|e| bad(e.to_string()))?;
        check_shape(&bev).map_err(bad)?;
        Ok(StaticBev { source: path.display().to_string(), one: Some(Box::new(bev)), dir: None })
    }

    /// Replace the static and divider layers of frame `f`'s BEV.
    pub fn apply(&self, f: usize, bev: &mut Bev) -> std::io::Result<()> {
        if let Some(one) = &self.one {
            keep_static(one, bev);
        } else if let Some(dir) = &self.dir {
            let p = dir.join(format!("{f:06}.npz"));
            let rec = crate::output::read_npz(&p)
                .map_err(|e| std::io::Error::other(format!("static BEV `{}`: {e}", p.display())))?;
            check_shape(&rec).map_err(|m| std::io::Error::other(format!("static BEV `{}`: {m}", p.display())))?;
            keep_static(&rec, bev);
        }
        Ok(())
    }
}

fn check_shape(b: &Bev) -> Result<(), String> {
    use crate::raster::layout::{GRID, N_MASKS};
    if b.masks.dim() != (N_MASKS, GRID, GRID) {
        return Err(format!("gt_bev_masks has shape {:?}, expected (18, 400, 400)", b.masks.dim()));
    }
    Ok(())
}
