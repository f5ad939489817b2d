//! Output writers. In: a `Bev`, per-frame `EgoBox`es, run metadata and a destination directory
//! (`OUT/<scenario>/<ego>/`). Out: `bev/NNNNNN.npz`, `preview/bev.png`, `boxes.json` and
//! `manifest.json` laid out as SPEC.md "Output layout of `rocc compile`" says, each written
//! through `fsio::write_atomic`. The readers of these files (`read_npz`, `read_boxes_json`) sit
//! beside their writers, so each format is defined once.

mod anim;
mod ego;
mod flow;
mod labels;
mod npy;
mod npz;
mod paint;
mod preview;
mod runs;
mod vector_map;

pub use anim::{GifFrame, gif_frame, write_gif, write_sheet};
pub use flow::{FLOW_KEY, flow_frame_path, write_flow};
pub use labels::{MASK_CAMERA_KEY, MASK_LIDAR_KEY, SEMANTICS_KEY, labels_frame_path, write_labels};
pub use npy::{write_npy_u8, write_occ_npy};
pub use npz::{DEFLATE, Deflate, NpyElem, Npz};
pub use paint::{CHANNEL_COLOURS, SIDE as PREVIEW_SIDE, STRUCTURE_COLOUR, paint_bev, paint_lidar, paint_occ, palette};
pub use preview::{render_preview, write_preview_png};

pub use ego::{
    BoxMotion, EgoRecord, FlagShown, FrameWorld, Motion, SignalState, States, ego2global, instance_id, yaw_quaternion,
};
pub use vector_map::{FlaggerRecord, Points, SceneMap, read_scene_json, write_scene_json};

/// A temporary of an interrupted write, as found in an output directory.
pub use crate::fsio::is_atomic_tmp;

use crate::fsio::{input_hash, write_atomic};

use crate::check::scenario::Class;
use crate::raster::Bev;
use crate::raster::layout::{KEY_AUX, KEY_MASKS, KEY_STRUCTURE, class_index};
use crate::view::EgoBox;
use ndarray_npy::NpzReader;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// One file written into the output directory: path relative to it, and size in bytes.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct OutputFile {
    pub path: String,
    pub bytes: u64,
}

fn npz_err(e: impl std::fmt::Display) -> io::Error {
    io::Error::other(format!("npz: {e}"))
}

/// Write one BEV as a compressed `.npz` with keys `gt_bev_masks` (int8, 18x400x400),
/// `gt_aux_bev` (int32, 7x400x400) and `structure` (int8, 400x400). Returns the size in bytes.
pub fn write_npz(path: &Path, bev: &Bev) -> io::Result<u64> {
    write_npz_with(path, bev, DEFLATE)
}

/// `write_npz` with the members deflated by `how` (`bench npz` compares them).
pub fn write_npz_with(path: &Path, bev: &Bev, how: Deflate) -> io::Result<u64> {
    let mut npz = Npz::with_deflate(how);
    npz.add(KEY_MASKS, bev.masks.shape(), std_slice(&bev.masks)?)?;
    npz.add(KEY_AUX, bev.aux.shape(), std_slice(&bev.aux)?)?;
    npz.add(KEY_STRUCTURE, bev.structure.shape(), std_slice(&bev.structure)?)?;
    write_atomic(path, |w| npz.finish(w))
}

/// The elements of a standard-layout array (every array rocc makes is one).
fn std_slice<T, D: ndarray::Dimension>(a: &ndarray::Array<T, D>) -> io::Result<&[T]> {
    a.as_slice().ok_or_else(|| npz_err("array not in standard layout"))
}

/// Read back a `.npz` written by `write_npz` (or any nuPlan-Occ BEV; a missing `structure` key
/// reads as zeros).
pub fn read_npz(path: &Path) -> io::Result<Bev> {
    let mut npz = NpzReader::new(File::open(path)?).map_err(npz_err)?;
    let masks = npz.by_name(KEY_MASKS).map_err(npz_err)?;
    let aux = npz.by_name(KEY_AUX).map_err(npz_err)?;
    let structure = match npz.by_name(KEY_STRUCTURE) {
        Ok(s) => s,
        Err(_) => Bev::zeros().structure,
    };
    Ok(Bev::from_arrays(masks, aux, structure))
}

/// `dir/bev/NNNNNN.npz` for frame `frame` (SPEC output layout).
pub fn bev_frame_path(dir: &Path, frame: usize) -> PathBuf {
    dir.join("bev").join(format!("{frame:06}.npz"))
}

/// Write frame `frame` of the clip in `dir` (`OUT/<scenario>/<ego>/`) as `bev/NNNNNN.npz`.
pub fn write_bev_frame(dir: &Path, frame: usize, bev: &Bev) -> io::Result<OutputFile> {
    let bytes = write_npz(&bev_frame_path(dir, frame), bev)?;
    Ok(OutputFile { path: format!("bev/{frame:06}.npz"), bytes })
}

/// The boxes of one frame, in that frame's ego frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameBoxes {
    pub frame: usize,
    /// Seconds since the clip start.
    pub t: f64,
    pub boxes: Vec<EgoBox>,
}

/// One box of `boxes.json`, as written and as read back.
#[derive(Serialize, Deserialize)]
struct BoxRecord {
    agent: String,
    kind: String,
    /// Index in UniScene's `object_classes` (vehicle 0 .. generic_object 6; structure 7), as
    /// SPEC.md "Boxes" asks for a class index. Reading takes the class from `class_name`.
    #[serde(default)]
    class: u8,
    class_name: String,
    track: u32,
    x: f64,
    y: f64,
    z: f64,
    l: f64,
    w: f64,
    h: f64,
    yaw: f64,
    /// Instance id and motion (`ego.rs`); absent for a box no track describes (an inserted one).
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    world: Option<BoxMotion>,
}

/// One frame of `boxes.json`.
#[derive(Serialize, Deserialize)]
struct FrameRecord {
    frame: usize,
    t: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    timestamp_us: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    ego: Option<EgoRecord>,
    boxes: Vec<BoxRecord>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    signals: Vec<SignalState>,
}

impl BoxRecord {
    fn of(b: &EgoBox) -> Self {
        BoxRecord {
            agent: b.agent.clone(),
            kind: b.kind.clone(),
            class: class_index(b.class),
            class_name: b.class.name().to_string(),
            track: b.track,
            x: b.x,
            y: b.y,
            z: b.z,
            l: b.l,
            w: b.w,
            h: b.h,
            yaw: b.yaw,
            world: None,
        }
    }

    /// The box again; `Err` names a `class_name` that is no class.
    fn into_box(self) -> Result<EgoBox, String> {
        let class = Class::ALL
            .iter()
            .find(|(n, _)| *n == self.class_name)
            .map(|(_, c)| *c)
            .ok_or_else(|| format!("unknown class `{}`", self.class_name))?;
        Ok(EgoBox {
            agent: self.agent,
            kind: self.kind,
            class,
            track: self.track,
            x: self.x,
            y: self.y,
            z: self.z,
            l: self.l,
            w: self.w,
            h: self.h,
            yaw: self.yaw,
        })
    }
}

/// `boxes.json`: `[{"frame", "t", "boxes": [{"agent", "kind", "class", "class_name", "track",
/// "x", "y", "z", "l", "w", "h", "yaw"}]}]` (SPEC output layout; `class_name` is an addition).
pub fn boxes_json(frames: &[FrameBoxes]) -> serde_json::Value {
    boxes_json_with(frames, None)
}

/// `boxes_json` with each frame's world side (`worlds[i]` belongs to `frames[i]`): the frame
/// gains `timestamp_us` and `ego`, each box its `instance_id` and motion.
pub fn boxes_json_with(frames: &[FrameBoxes], worlds: Option<&[FrameWorld]>) -> serde_json::Value {
    let recs: Vec<FrameRecord> = frames
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let w = worlds.and_then(|w| w.get(i));
            let boxes = f
                .boxes
                .iter()
                .enumerate()
                .map(|(k, b)| BoxRecord {
                    world: w.and_then(|w| w.boxes.get(k).cloned().flatten()),
                    ..BoxRecord::of(b)
                })
                .collect();
            FrameRecord {
                frame: f.frame,
                t: f.t,
                timestamp_us: w.map(|w| w.timestamp_us),
                ego: w.map(|w| w.ego.clone()),
                boxes,
                signals: w.map(|w| w.signals.clone()).unwrap_or_default(),
            }
        })
        .collect();
    serde_json::to_value(recs).expect("box records hold only strings and numbers")
}

/// Read `boxes.json` back into frames of ego-frame boxes; `class` is taken from `class_name`.
pub fn read_boxes_json(path: &Path) -> Result<Vec<FrameBoxes>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    let frames: Vec<FrameRecord> = serde_json::from_str(&text).map_err(|e| format!("`{}`: {e}", path.display()))?;
    frames
        .into_iter()
        .map(|f| {
            let boxes = f
                .boxes
                .into_iter()
                .map(|b| b.into_box().map_err(|m| format!("{m} in `{}`", path.display())))
                .collect::<Result<Vec<_>, String>>()?;
            Ok(FrameBoxes { frame: f.frame, t: f.t, boxes })
        })
        .collect()
}

/// Write `dir/boxes.json`.
pub fn write_boxes_json(dir: &Path, frames: &[FrameBoxes]) -> io::Result<OutputFile> {
    write_json(dir, "boxes.json", &boxes_json(frames))
}

/// Write `dir/boxes.json` with each frame's world side.
pub fn write_boxes_json_with(dir: &Path, frames: &[FrameBoxes], worlds: &[FrameWorld]) -> io::Result<OutputFile> {
    write_json(dir, "boxes.json", &boxes_json_with(frames, Some(worlds)))
}

/// The ego record of every frame of `boxes.json`, by frame index; frames written without one
/// are left out.
pub fn read_ego_poses(path: &Path) -> Result<Vec<(usize, f64, EgoRecord)>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    let frames: Vec<FrameRecord> = serde_json::from_str(&text).map_err(|e| format!("`{}`: {e}", path.display()))?;
    Ok(frames.into_iter().filter_map(|f| f.ego.map(|e| (f.frame, f.t, e))).collect())
}

/// Wall time of one pipeline stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageTiming {
    pub stage: String,
    pub seconds: f64,
}

/// The version of the files a clip holds, part of every clip's build key: a clip written with
/// another format is recompiled by a resumed run, never kept. Raised whenever a file or field
/// is added, removed or changes meaning.
pub const FORMAT: u32 = 2;

/// `manifest.json` (SPEC output layout).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub compiler: String,
    pub compiler_version: String,
    /// The scenario file as given on the command line.
    pub input: String,
    /// `input_hash(bytes of the input)`.
    pub input_hash: String,
    /// `input_hash` of everything else the output depends on: the compiler version, every
    /// loaded source (prelude, root, imports) and, with LiDAR, the effective rig (after
    /// `--lidar-resolution`). A resumed run keeps a clip only when this matches too.
    #[serde(default)]
    pub build_key: String,
    pub seed: u64,
    pub backend: String,
    /// Sensor rig name or description; `None` when no LiDAR was produced.
    pub rig: Option<String>,
    pub frame_count: usize,
    pub rate_hz: f64,
    pub ego: String,
    /// The last stage written: `bev`, `occ` or `lidar`.
    #[serde(default)]
    pub stage: String,
    /// The frame indices written (all of the clip unless `--frames` chose).
    #[serde(default)]
    pub frames: Vec<usize>,
    /// In pipeline order. Wall seconds summed over worker threads, so they add up to CPU time;
    /// the only part of an output directory that differs between two runs of the same input.
    pub timings: Vec<StageTiming>,
    pub files: Vec<OutputFile>,
    /// The recorded BEV whose static layers replaced the map's (`--static-bev`), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub static_bev: Option<String>,
    /// With `--backend grounded`: the weights and config files as given, so `rocc edit` can
    /// rerun the same model (the weights' hash is in `backend`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weights: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grounded_config: Option<String>,
    /// With `--backend grounded`: the device the model ran on (`cpu`, `wgpu`, `cuda`). Not
    /// compared when a run resumes: a clip made on one device stands for the same model's output.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub device: Option<String>,
    /// Whether `flow/` was written (`--flow`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub flow: bool,
    /// With `--visibility`: the camera rig's name (`gts/` holds the labels and masks).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub visibility: Option<String>,
    /// Box edits applied by `rocc edit` after compilation, in order (`insert sedan at 10,-3.5 yaw 0`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub edits: Vec<String>,
}

impl Manifest {
    /// A manifest with this build's compiler name and version filled in.
    pub fn new(input: &str, input_bytes: &[u8], seed: u64, ego: &str, frame_count: usize, rate_hz: f64) -> Self {
        Manifest {
            compiler: env!("CARGO_PKG_NAME").to_string(),
            compiler_version: env!("CARGO_PKG_VERSION").to_string(),
            input: input.to_string(),
            input_hash: input_hash(input_bytes),
            build_key: String::new(),
            seed,
            backend: "procedural".to_string(),
            rig: None,
            frame_count,
            rate_hz,
            ego: ego.to_string(),
            stage: "bev".to_string(),
            frames: Vec::new(),
            timings: Vec::new(),
            files: Vec::new(),
            static_bev: None,
            weights: None,
            grounded_config: None,
            device: None,
            flow: false,
            visibility: None,
            edits: Vec::new(),
        }
    }
}

/// Write `dir/manifest.json`. The manifest does not list itself.
pub fn write_manifest(dir: &Path, m: &Manifest) -> io::Result<OutputFile> {
    let v = serde_json::to_value(m).map_err(io::Error::other)?;
    write_json(dir, "manifest.json", &v)
}

fn write_json(dir: &Path, name: &str, v: &serde_json::Value) -> io::Result<OutputFile> {
    let bytes = write_atomic(&dir.join(name), |w| {
        serde_json::to_writer_pretty(&mut *w, v).map_err(io::Error::other)?;
        w.write_all(b"\n")
    })?;
    Ok(OutputFile { path: name.to_string(), bytes })
}
