//! The shared scorer. In: directories of predicted and ground-truth occupancy or LiDAR frames, or
//! a number of procedural scenes for the edit protocol. Out: `OccScores` (per-class IoU over the
//! whole set, mIoU_US, fg-mIoU, occ-IoU), `LidarScores` (MMD, JSD) and `EditScores` (box coverage
//! and residue per class, the paper's Table 6 on rocc's own backends), as SPEC.md "Metrics"
//! defines them. Unreadable or mismatched inputs are E07xx diagnostics, never panics.

pub mod edits;
pub mod lidar;
pub mod occ;

pub use edits::{EditScores, run_edit_protocol};
pub use lidar::LidarScores;
pub use occ::{OccScorer, OccScores, read_occ};

use crate::diag::Diagnostic;
use std::path::{Path, PathBuf};

/// Every file under `dir` (recursively) whose extension is one of `exts`, as paths relative to
/// `dir`, sorted so results never depend on directory order.
pub fn list_files(dir: &Path, exts: &[&str]) -> Result<Vec<PathBuf>, Diagnostic> {
    let md = std::fs::metadata(dir).map_err(|e| {
        Diagnostic::error("E0703", format!("cannot read `{}`: {e}", dir.display())).help("pass an existing directory")
    })?;
    if !md.is_dir() {
        return Err(Diagnostic::error("E0703", format!("`{}` is not a directory", dir.display()))
            .help("`--pred` and `--gt` name directories of frames"));
    }
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let rd = std::fs::read_dir(&d)
            .map_err(|e| Diagnostic::error("E0703", format!("cannot list `{}`: {e}", d.display())))?;
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p
                .extension()
                .and_then(|x| x.to_str())
                .is_some_and(|x| exts.iter().any(|w| x.eq_ignore_ascii_case(w)))
                && !p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with('.'))
            {
                out.push(p.strip_prefix(dir).unwrap_or(&p).to_path_buf());
            }
        }
    }
    out.sort();
    Ok(out)
}

/// Score every ground-truth frame under `gt` against the prediction at the same relative path
/// (`.npy` and `.npz` may stand in for each other), in one accumulator.
pub fn score_occ_dirs(pred: &Path, gt: &Path) -> Result<OccScores, Vec<Diagnostic>> {
    let mut gts = list_files(gt, &["npy", "npz"]).map_err(|d| vec![d])?;
    // A clip directory holds `bev/*.npz` next to `occ/*.npy`: keep only occupancy archives.
    gts.retain(|rel| {
        !rel.extension().is_some_and(|x| x.eq_ignore_ascii_case("npz")) || occ::npz_may_hold_occupancy(&gt.join(rel))
    });
    if gts.is_empty() {
        return Err(vec![
            Diagnostic::error("E0703", format!("no `.npy` or `.npz` occupancy frames under `{}`", gt.display()))
                .help("point `--gt` at a directory of frames, e.g. OUT/<scenario>/<ego>/occ"),
        ]);
    }
    let mut pairs = Vec::new();
    let mut missing = Vec::new();
    for rel in &gts {
        let cands = [rel.clone(), rel.with_extension("npy"), rel.with_extension("npz")];
        match cands.iter().map(|c| pred.join(c)).find(|p| p.is_file()) {
            Some(p) => pairs.push((p, gt.join(rel))),
            None => missing.push(rel.display().to_string()),
        }
    }
    if !missing.is_empty() {
        let shown: Vec<&str> = missing.iter().take(5).map(String::as_str).collect();
        return Err(vec![
            Diagnostic::error(
                "E0703",
                format!(
                    "{} ground-truth frame(s) have no prediction under `{}`: {}{}",
                    missing.len(),
                    pred.display(),
                    shown.join(", "),
                    if missing.len() > 5 { ", ..." } else { "" }
                ),
            )
            .help("predictions are matched by relative path; every ground-truth frame needs one"),
        ]);
    }
    let mut scorer = OccScorer::new();
    let mut errs = Vec::new();
    for (p, g) in &pairs {
        let read = |path: &Path| {
            read_occ(path).map_err(|m| {
                Diagnostic::error("E0701", format!("`{}`: {m}", path.display()))
                    .help("occupancy frames are uint8 (400, 400, 32) `.npy` or sparse (N, 4) [i, j, k, label] `.npz`")
            })
        };
        match (read(p), read(g)) {
            (Ok(a), Ok(b)) => scorer.add(&a, &b),
            (a, b) => errs.extend([a.err(), b.err()].into_iter().flatten()),
        }
    }
    if errs.is_empty() { Ok(scorer.scores()) } else { Err(errs) }
}

/// The point clouds under `dir`, as paths relative to it: in a compiled clip (a directory with a
/// `manifest.json`, at any depth) only its `lidar/` folder counts, so `occ/*.npy` and `bev/*.npz`
/// are never read as clouds; elsewhere `.bin`, `.pcd` and `.npy` files. A frame written as both
/// `.bin` and `.pcd` (as `rocc compile` writes it) counts once, from the `.bin`. E0703 when none.
pub fn lidar_files(dir: &Path) -> Result<Vec<PathBuf>, Diagnostic> {
    let files = list_files(dir, &["bin", "pcd", "npy"])?;
    let rank = |p: &Path| match p.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("bin") => 0,
        Some("pcd") => 1,
        _ => 2,
    };
    let mut best: std::collections::BTreeMap<PathBuf, PathBuf> = std::collections::BTreeMap::new();
    let mut clips = 0;
    for rel in files {
        // The innermost clip directory above the file, if any.
        let clip = rel.ancestors().skip(1).find(|a| dir.join(a).join("manifest.json").is_file());
        if let Some(c) = clip {
            clips += 1;
            if !rel.strip_prefix(c).is_ok_and(|r| r.starts_with("lidar")) {
                continue;
            }
        }
        let stem = rel.with_extension("");
        match best.get(&stem) {
            Some(have) if rank(have) <= rank(&rel) => {}
            _ => {
                best.insert(stem, rel);
            }
        }
    }
    if best.is_empty() {
        let what = if clips > 0 || dir.join("manifest.json").is_file() {
            "no LiDAR frames in the compiled clip(s) under"
        } else {
            "no `.bin`, `.pcd` or `.npy` point clouds under"
        };
        return Err(Diagnostic::error("E0703", format!("{what} `{}`", dir.display())).help(
            "compile the clip with `--stage lidar` (the default), or point at a directory of `.bin` / `.pcd` / \
             (N, >= 3) `.npy` clouds",
        ));
    }
    Ok(best.into_values().collect())
}

/// MMD and JSD between the LiDAR sets under `pred` and `gt` (clip directories, or directories
/// of `.bin`, `.pcd` or `.npy` clouds; see `lidar_files`).
pub fn score_lidar_dirs(pred: &Path, gt: &Path, range_filter: bool) -> Result<LidarScores, Vec<Diagnostic>> {
    let mut errs = Vec::new();
    let mut maps = |dir: &Path| -> Vec<Vec<f64>> {
        let files = match lidar_files(dir) {
            Ok(f) => f,
            Err(d) => {
                errs.push(d);
                return vec![];
            }
        };
        let mut out = Vec::new();
        for rel in files {
            let p = dir.join(&rel);
            match lidar::read_points(&p) {
                Ok(pts) => out.push(lidar::bev_map(&pts, range_filter)),
                Err(m) => errs.push(Diagnostic::error("E0704", format!("`{}`: {m}", p.display())).help(
                    "clouds are KITTI `.bin` (float32 x, y, z, intensity), PCD (fields x y z; ascii or binary) \
                     or (N, >= 3) float `.npy`",
                )),
            }
        }
        out
    };
    let (p, g) = (maps(pred), maps(gt));
    if !errs.is_empty() {
        return Err(errs);
    }
    Ok(LidarScores {
        pred_clouds: p.len(),
        gt_clouds: g.len(),
        mmd: lidar::mmd(&p, &g),
        jsd: lidar::jsd(&p, &g),
        range_filter,
    })
}
