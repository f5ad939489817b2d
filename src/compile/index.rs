//! `index.json` at an output root: every finished clip and its frames (paths relative to the
//! root, timestamps, ego poses). A clip is finished when its `manifest.json` parses and every
//! file it lists exists with the listed size, the test a resumed run applies; a clip being
//! written has no manifest (it is removed first), so it is never listed.
//!
//! The index is rebuilt from the tree, not patched, so batch compiles, resumes and shards all
//! leave it right. Concurrent shards each refresh at their end: `refresh` rewrites until a scan
//! taken after reading the file finds what the file says, so the last write is always followed
//! by a scan that saw every clip finished before it (docs/compile.md, "Dataset index").

use crate::fsio::{input_hash, write_atomic};
use crate::output::{Manifest, read_ego_poses};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::io::{self, Write};
use std::path::Path;

/// The index's file name at the output root.
pub const INDEX_FILE: &str = "index.json";
/// What `format` says.
pub const INDEX_FORMAT: &str = "rocc-index";
/// Rewrites before `refresh` gives up converging with concurrent writers (each one a full scan).
const MAX_ROUNDS: usize = 8;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Index {
    pub format: String,
    pub version: u32,
    /// Sorted by `dir`.
    pub clips: Vec<IndexClip>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IndexClip {
    /// `<scenario>/<ego>`, relative to the root.
    pub dir: String,
    pub scenario: String,
    pub ego: String,
    pub input: String,
    pub seed: u64,
    pub stage: String,
    pub rate_hz: f64,
    /// Frames of the whole clip; `frames` lists those written.
    pub frame_count: usize,
    /// `input_hash` of the clip's manifest without its timings: an unchanged manifest is not
    /// re-read.
    pub manifest_hash: String,
    pub boxes: String,
    /// `scene.json`, when the clip has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<String>,
    pub frames: Vec<IndexFrame>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IndexFrame {
    pub frame: usize,
    /// Seconds since the clip start.
    pub t: f64,
    pub timestamp_us: u64,
    pub bev: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub occ: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lidar: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pcd: Option<String>,
    /// The ego's world pose `[x, y, z, yaw]` and 4x4 ego-to-world matrix (row-major), when
    /// `boxes.json` records them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose: Option<[f64; 4]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ego2global: Option<[[f64; 4]; 4]>,
}

/// Read `root/index.json`.
pub fn read_index(root: &Path) -> Result<Index, String> {
    let path = root.join(INDEX_FILE);
    let text = std::fs::read_to_string(&path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    let idx: Index = serde_json::from_str(&text).map_err(|e| format!("`{}`: {e}", path.display()))?;
    if idx.format != INDEX_FORMAT {
        return Err(format!("`{}` is not a rocc index (format `{}`)", path.display(), idx.format));
    }
    Ok(idx)
}

/// Rebuild `root/index.json` from the clips finished under `root` (see the module comment).
pub fn refresh(root: &Path) -> io::Result<Index> {
    let mut on_disk = read_index(root).ok();
    let mut idx = scan(root, on_disk.as_ref())?;
    for _ in 0..MAX_ROUNDS {
        if on_disk.as_ref() == Some(&idx) {
            break;
        }
        write_index(root, &idx)?;
        on_disk = read_index(root).ok();
        idx = scan(root, on_disk.as_ref())?;
    }
    Ok(idx)
}

fn write_index(root: &Path, idx: &Index) -> io::Result<u64> {
    write_atomic(&root.join(INDEX_FILE), |w| {
        // Compact: a corpus index holds a record per frame.
        serde_json::to_writer(&mut *w, idx).map_err(io::Error::other)?;
        w.write_all(b"\n")
    })
}

/// The index of the clips finished under `root` now; entries of `prev` whose manifest is
/// unchanged are reused without reading `boxes.json` again.
pub fn scan(root: &Path, prev: Option<&Index>) -> io::Result<Index> {
    let reuse: BTreeMap<&str, &IndexClip> =
        prev.map(|p| p.clips.iter().map(|c| (c.dir.as_str(), c)).collect()).unwrap_or_default();
    let mut clips = Vec::new();
    for scenario in sorted_dirs(root)? {
        for ego in sorted_dirs(&root.join(&scenario))? {
            let dir = format!("{scenario}/{ego}");
            if let Some(c) = finished_clip(root, &dir, &scenario, &ego, &reuse) {
                clips.push(c);
            }
        }
    }
    Ok(Index { format: INDEX_FORMAT.to_string(), version: 1, clips })
}

fn sorted_dirs(dir: &Path) -> io::Result<Vec<String>> {
    let mut out = Vec::new();
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(out),
        Err(e) => return Err(e),
    };
    for e in entries {
        let e = e?;
        if e.file_type()?.is_dir()
            && let Ok(name) = e.file_name().into_string()
        {
            out.push(name);
        }
    }
    out.sort();
    Ok(out)
}

/// The entry of the clip in `root/dir` if it is finished; `None` for anything else (no manifest,
/// another program's JSON, a listed file missing or of another size).
fn finished_clip(
    root: &Path,
    dir: &str,
    scenario: &str,
    ego: &str,
    reuse: &BTreeMap<&str, &IndexClip>,
) -> Option<IndexClip> {
    let clip = root.join(dir);
    let bytes = std::fs::read(clip.join("manifest.json")).ok()?;
    let m: Manifest = serde_json::from_slice(&bytes).ok()?;
    let files_ok = m
        .files
        .iter()
        .all(|f| std::fs::metadata(clip.join(&f.path)).is_ok_and(|md| md.is_file() && md.len() == f.bytes));
    if m.compiler != env!("CARGO_PKG_NAME") || !files_ok {
        return None;
    }
    // Timings left out: they are all that differs between two runs of the same input, and
    // the index is as deterministic as the clips.
    let hash = input_hash(&serde_json::to_vec(&Manifest { timings: Vec::new(), ..m.clone() }).ok()?);
    if let Some(c) = reuse.get(dir).filter(|c| c.manifest_hash == hash) {
        return Some((*c).clone());
    }
    let listed: BTreeSet<&str> = m.files.iter().map(|f| f.path.as_str()).collect();
    let has = |p: String| listed.contains(p.as_str()).then(|| format!("{dir}/{p}"));
    let poses: BTreeMap<usize, crate::output::EgoRecord> = if listed.contains("boxes.json") {
        read_ego_poses(&clip.join("boxes.json")).ok()?.into_iter().map(|(f, _, e)| (f, e)).collect()
    } else {
        BTreeMap::new()
    };
    let frames = m
        .frames
        .iter()
        .map(|&f| {
            let ego = poses.get(&f);
            Some(IndexFrame {
                frame: f,
                t: f as f64 / m.rate_hz,
                timestamp_us: (f as f64 * 1e6 / m.rate_hz).round() as u64,
                bev: has(format!("bev/{f:06}.npz"))?,
                occ: has(format!("occ/{f:06}.npy")),
                lidar: has(format!("lidar/{f:06}.bin")),
                pcd: has(format!("lidar/{f:06}.pcd")),
                pose: ego.map(|e| [e.x, e.y, e.z, e.yaw]),
                ego2global: ego.map(|e| e.ego2global),
            })
        })
        .collect::<Option<Vec<_>>>()?;
    Some(IndexClip {
        dir: dir.to_string(),
        scenario: scenario.to_string(),
        ego: ego.to_string(),
        input: m.input.clone(),
        seed: m.seed,
        stage: m.stage.clone(),
        rate_hz: m.rate_hz,
        frame_count: m.frame_count,
        manifest_hash: hash,
        boxes: format!("{dir}/boxes.json"),
        scene: has("scene.json".to_string()),
        frames,
    })
}
