//! Training data for the grounded model. In: a directory. Out: `Sample`s (paths and boxes) and,
//! on demand, `Frame`s (BEV masks and aux, ground-truth labels, boxes). Two layouts:
//!
//! 1. What `rocc compile --stage occ` writes: any directory below DIR holding `boxes.json`,
//!    `bev/NNNNNN.npz` and `occ/NNNNNN.npy` is a clip; its frames are those with both files.
//! 2. nuPlan-Occ / UniScene style, one token per frame:
//!    ```text
//!    DIR/bev/<token>.npz     gt_bev_masks (18, 400, 400) int8/uint8/bool, gt_aux_bev (7, 400, 400) int
//!    DIR/occ/<token>.npy     dense (400, 400, 32) labels 0..8 (any integer dtype), or a sparse
//!                            .npz of [i, j, k, label] rows (what `rocc eval occ` reads)
//!    DIR/boxes/<token>.json  {"gt_boxes": [[x, y, z, l, w, h, yaw], ...], "gt_names": ["car", ...]}
//!    ```
//!    ego frame, z the box centre, names as nuPlan/nuScenes/mmdet3d write them (`rocc import`'s
//!    class map; unknown names are generic objects). A token without a boxes file has no boxes.
//!    Every token is its own clip, so pass the validation split explicitly (`--val DIR`).

use crate::backend::grounded::GBox;
use crate::backend::layout::{BACKGROUND, N_LABELS, NZ, class_label};
use crate::raster::layout::{GRID, KEY_AUX, KEY_MASKS, N_AUX, N_MASKS};
use ndarray::{Array3, IxDyn};
use ndarray_npy::NpzReader;
use std::fs::File;
use std::path::{Path, PathBuf};

/// One training frame on disk.
#[derive(Clone, Debug)]
pub struct Sample {
    /// The clip it belongs to.
    pub clip: String,
    /// The scene: held-out splits are by scene, so no view of a held-out scene is trained on
    /// (a scenario's clips for different egos are one scene; a token is its own).
    pub scene: String,
    pub id: String,
    pub bev: PathBuf,
    pub occ: PathBuf,
    pub boxes: Vec<GBox>,
}

/// One frame in memory.
#[derive(Clone, Debug)]
pub struct Frame {
    pub masks: Array3<i8>,
    pub aux: Array3<i32>,
    pub labels: Array3<u8>,
    pub boxes: Vec<GBox>,
}

/// The occupancy label of a box class name (`structure` is rocc's static-scene class).
pub fn label_of(name: &str) -> u8 {
    if name.trim().eq_ignore_ascii_case("structure") {
        BACKGROUND
    } else {
        class_label(crate::check::classes::map_class(name).class)
    }
}

/// Every sample under `dir`, sorted by (clip, id). Errors are messages for E0905.
pub fn scan(dir: &Path) -> Result<Vec<Sample>, String> {
    if !dir.is_dir() {
        return Err(format!("`{}` is not a directory", dir.display()));
    }
    let mut out = if dir.join("bev").is_dir() && dir.join("occ").is_dir() && !dir.join("boxes.json").is_file() {
        scan_tokens(dir)?
    } else {
        let mut clips = Vec::new();
        find_clips(dir, &mut clips, 0);
        clips.sort();
        let mut v = Vec::new();
        for c in clips {
            v.extend(scan_clip(dir, &c)?);
        }
        v
    };
    out.sort_by(|a, b| (&a.clip, &a.id).cmp(&(&b.clip, &b.id)));
    if out.is_empty() {
        return Err(format!(
            "no training frames under `{}`: expected clips as `rocc compile --stage occ` writes them \
             (boxes.json, bev/, occ/) or the nuPlan-Occ layout (bev/, occ/, boxes/ per token)",
            dir.display()
        ));
    }
    Ok(out)
}

fn find_clips(dir: &Path, out: &mut Vec<PathBuf>, depth: usize) {
    if depth > 8 {
        return;
    }
    if dir.join("boxes.json").is_file() && dir.join("occ").is_dir() && dir.join("bev").is_dir() {
        out.push(dir.to_path_buf());
        return;
    }
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut subs: Vec<PathBuf> = rd.filter_map(|e| e.ok()).map(|e| e.path()).filter(|p| p.is_dir()).collect();
    subs.sort();
    for s in subs {
        find_clips(&s, out, depth + 1);
    }
}

fn stems(dir: &Path, ext: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .map(|e| e.path())
                .filter(|p| p.extension().and_then(|e| e.to_str()) == Some(ext))
                .filter_map(|p| p.file_stem().and_then(|s| s.to_str()).map(str::to_string))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

fn num(v: &serde_json::Value, k: &str) -> Option<f64> {
    v.get(k).and_then(|x| x.as_f64())
}

fn scan_clip(root: &Path, clip: &Path) -> Result<Vec<Sample>, String> {
    let name = clip.strip_prefix(root).unwrap_or(clip).to_string_lossy().replace('\\', "/");
    let text = std::fs::read_to_string(clip.join("boxes.json")).map_err(|e| format!("{name}/boxes.json: {e}"))?;
    let json: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{name}/boxes.json: {e}"))?;
    let frames = json.as_array().ok_or_else(|| format!("{name}/boxes.json: expected an array of frames"))?;
    let mut by_frame = std::collections::BTreeMap::new();
    for f in frames {
        let Some(idx) = f.get("frame").and_then(|x| x.as_u64()) else {
            return Err(format!("{name}/boxes.json: a frame without `frame`"));
        };
        let mut boxes = Vec::new();
        for b in f.get("boxes").and_then(|b| b.as_array()).map(Vec::as_slice).unwrap_or(&[]) {
            let cls =
                b.get("class_name").or_else(|| b.get("kind")).and_then(|c| c.as_str()).unwrap_or("generic_object");
            let g = (|| {
                Some(GBox {
                    label: label_of(cls),
                    x: num(b, "x")?,
                    y: num(b, "y")?,
                    z: num(b, "z")?,
                    l: num(b, "l")?,
                    w: num(b, "w")?,
                    h: num(b, "h")?,
                    yaw: num(b, "yaw")?,
                })
            })()
            .ok_or_else(|| format!("{name}/boxes.json: frame {idx}: a box lacks x, y, z, l, w, h or yaw"))?;
            boxes.push(g);
        }
        by_frame.insert(format!("{idx:06}"), boxes);
    }
    let bevs = stems(&clip.join("bev"), "npz");
    let occs = stems(&clip.join("occ"), "npy");
    Ok(bevs
        .into_iter()
        .filter(|s| occs.binary_search(s).is_ok())
        .filter_map(|s| {
            let boxes = by_frame.get(&s)?.clone();
            Some(Sample {
                clip: name.clone(),
                scene: name.split('/').next().unwrap_or(&name).to_string(),
                bev: clip.join("bev").join(format!("{s}.npz")),
                occ: clip.join("occ").join(format!("{s}.npy")),
                id: s,
                boxes,
            })
        })
        .collect())
}

fn scan_tokens(dir: &Path) -> Result<Vec<Sample>, String> {
    let bevs = stems(&dir.join("bev"), "npz");
    let mut occ_files = stems(&dir.join("occ"), "npy");
    let npz = stems(&dir.join("occ"), "npz");
    occ_files.extend(npz.iter().cloned());
    occ_files.sort();
    let mut out = Vec::new();
    for t in bevs {
        if occ_files.binary_search(&t).is_err() {
            continue;
        }
        let occ = if dir.join("occ").join(format!("{t}.npy")).is_file() {
            dir.join("occ").join(format!("{t}.npy"))
        } else {
            dir.join("occ").join(format!("{t}.npz"))
        };
        let bp = dir.join("boxes").join(format!("{t}.json"));
        let boxes = if bp.is_file() { token_boxes(&bp)? } else { Vec::new() };
        out.push(Sample {
            clip: t.clone(),
            scene: t.clone(),
            bev: dir.join("bev").join(format!("{t}.npz")),
            occ,
            id: t,
            boxes,
        });
    }
    Ok(out)
}

fn token_boxes(path: &Path) -> Result<Vec<GBox>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let boxes = v
        .get("gt_boxes")
        .and_then(|b| b.as_array())
        .ok_or_else(|| format!("{}: no `gt_boxes` array", path.display()))?;
    let names = v
        .get("gt_names")
        .and_then(|b| b.as_array())
        .ok_or_else(|| format!("{}: no `gt_names` array", path.display()))?;
    if boxes.len() != names.len() {
        return Err(format!("{}: {} boxes but {} names", path.display(), boxes.len(), names.len()));
    }
    boxes
        .iter()
        .zip(names)
        .enumerate()
        .map(|(i, (b, n))| {
            let r: Vec<f64> = b.as_array().map(|a| a.iter().filter_map(|x| x.as_f64()).collect()).unwrap_or_default();
            if r.len() < 7 {
                return Err(format!("{}: box {i} is not [x, y, z, l, w, h, yaw]", path.display()));
            }
            Ok(GBox {
                label: label_of(n.as_str().unwrap_or("generic_object")),
                x: r[0],
                y: r[1],
                z: r[2],
                l: r[3],
                w: r[4],
                h: r[5],
                yaw: r[6],
            })
        })
        .collect()
}

/// `gt_bev_masks` as int8 0/1, whether stored as int8, uint8 or bool.
fn read_masks(npz: &mut NpzReader<File>) -> Option<ndarray::ArrayD<i8>> {
    if let Ok(a) = npz.by_name::<ndarray::OwnedRepr<i8>, IxDyn>(KEY_MASKS) {
        return Some(a);
    }
    if let Ok(a) = npz.by_name::<ndarray::OwnedRepr<u8>, IxDyn>(KEY_MASKS) {
        return Some(a.mapv(|v| (v != 0) as i8));
    }
    npz.by_name::<ndarray::OwnedRepr<bool>, IxDyn>(KEY_MASKS).ok().map(|a| a.mapv(|v| v as i8))
}

/// `gt_aux_bev` as int32, whether stored as int32, int64 or float32.
fn read_aux(npz: &mut NpzReader<File>) -> Option<ndarray::ArrayD<i32>> {
    if let Ok(a) = npz.by_name::<ndarray::OwnedRepr<i32>, IxDyn>(KEY_AUX) {
        return Some(a);
    }
    if let Ok(a) = npz.by_name::<ndarray::OwnedRepr<i64>, IxDyn>(KEY_AUX) {
        return Some(a.mapv(|v| v as i32));
    }
    npz.by_name::<ndarray::OwnedRepr<f32>, IxDyn>(KEY_AUX).ok().map(|a| a.mapv(|v| v as i32))
}

/// Load one sample. Errors name the file.
pub fn load(s: &Sample) -> Result<Frame, String> {
    let f = File::open(&s.bev).map_err(|e| format!("{}: {e}", s.bev.display()))?;
    let mut npz = NpzReader::new(f).map_err(|e| format!("{}: not a .npz: {e}", s.bev.display()))?;
    let masks = read_masks(&mut npz).ok_or_else(|| format!("{}: no readable `{KEY_MASKS}`", s.bev.display()))?;
    let aux = read_aux(&mut npz).ok_or_else(|| format!("{}: no readable `{KEY_AUX}`", s.bev.display()))?;
    let masks = masks
        .into_dimensionality::<ndarray::Ix3>()
        .ok()
        .filter(|m| m.dim() == (N_MASKS, GRID, GRID))
        .ok_or_else(|| format!("{}: `{KEY_MASKS}` is not ({N_MASKS}, {GRID}, {GRID})", s.bev.display()))?;
    let aux = aux
        .into_dimensionality::<ndarray::Ix3>()
        .ok()
        .filter(|m| m.dim() == (N_AUX, GRID, GRID))
        .ok_or_else(|| format!("{}: `{KEY_AUX}` is not ({N_AUX}, {GRID}, {GRID})", s.bev.display()))?;
    let labels = read_labels(&s.occ)?;
    Ok(Frame { masks: standard(masks), aux: standard(aux), labels: standard(labels), boxes: s.boxes.clone() })
}

/// `a` in standard layout: itself when it is (what `.npy` files hold), else a copy.
fn standard<T: Clone>(a: Array3<T>) -> Array3<T> {
    if a.is_standard_layout() { a } else { a.as_standard_layout().into_owned() }
}

/// Occupancy labels: rocc's own uint8 `.npy` directly, anything else through the scorer's reader
/// (every integer dtype, sparse `.npz`).
fn read_labels(path: &Path) -> Result<Array3<u8>, String> {
    use ndarray_npy::ReadNpyExt;
    if path.extension().and_then(|e| e.to_str()) == Some("npy")
        && let Ok(f) = File::open(path)
        && let Ok(a) = Array3::<u8>::read_npy(std::io::BufReader::new(f))
        && a.dim() == (crate::backend::layout::NX, crate::backend::layout::NY, NZ)
        && a.iter().all(|&l| (l as usize) < N_LABELS)
    {
        return Ok(a);
    }
    crate::eval::occ::read_occ(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// Label counts per height layer over a set of frames: class weights and the baseline.
pub fn layer_counts(labels: &Array3<u8>, out: &mut [[u64; N_LABELS]; NZ]) {
    for ((_, _, k), &l) in labels.indexed_iter() {
        out[k][(l as usize).min(N_LABELS - 1)] += 1;
    }
}

/// Split samples into (train, val) by whole scenes: a scene is held out when the hash of (seed,
/// scene name) falls under `fraction`; at least one scene on each side when there are two.
pub fn split(samples: Vec<Sample>, fraction: f64, seed: u64) -> (Vec<Sample>, Vec<Sample>) {
    let mut clips: Vec<String> = samples.iter().map(|s| s.scene.clone()).collect();
    clips.sort();
    clips.dedup();
    let score = |c: &str| crate::sample::Rng::stream(seed, &format!("split:{c}")).unit();
    let mut held: Vec<&String> = clips.iter().filter(|c| score(c) < fraction).collect();
    if fraction > 0.0 && clips.len() >= 2 {
        if held.is_empty() {
            held.push(clips.iter().min_by(|a, b| score(a).total_cmp(&score(b))).expect("two clips"));
        }
        if held.len() == clips.len() {
            let keep = clips.iter().max_by(|a, b| score(a).total_cmp(&score(b))).expect("two clips");
            held.retain(|c| *c != keep);
        }
    }
    let held: std::collections::BTreeSet<String> = held.into_iter().cloned().collect();
    samples.into_iter().partition(|s| !held.contains(&s.scene))
}
