//! One clip: one ego's frames of one scene, written to `OUT/<scenario>/<ego>/`.
//!
//! Frames are independent (the tracks are already decided, every random draw is keyed by the
//! frame), so they run in parallel with per-thread scratch buffers, and each frame's files are
//! written by the thread that made them. What needs all frames — `boxes.json`, the previews —
//! is written after, and `manifest.json` last: its presence with matching inputs and files is
//! what "this clip is complete" means to a resumed run.

use super::world::{ClipWorld, ground_velocity};
use super::{Front, Options, Stage};
use crate::backend::flow::{Flow, flow_into, to_ego_axes};
use crate::backend::{Background, OccInput, Occupancy, occ_frame_path};
use crate::fsio::To;
use crate::lidar::dda::Skip;
use crate::lidar::{bin_frame_path, pcd_frame_path, scan_with, write_bin, write_pcd};
use crate::output::{
    FrameBoxes, FrameWorld, GifFrame, Manifest, OutputFile, PREVIEW_SIDE, StageTiming, flow_frame_path, gif_frame,
    labels_frame_path, paint_bev, paint_lidar, paint_occ, write_bev_frame, write_boxes_json, write_boxes_json_with,
    write_flow, write_gif, write_labels, write_manifest, write_occ_npy, write_preview_png, write_scene_json,
    write_sheet,
};
use crate::place::Pose;
use crate::raster::layout::{HALF_EXTENT_M, box_reaches_patch};
use crate::raster::{Bev, Rasterizer};
use crate::rollout::body::{DOOR_KIND, open_doors};
use crate::sample::Rng;
use crate::source::SourceMap;
use crate::view::{AgentState, EgoBox, to_ego};
use crate::visibility::{Masks, masks_into};
use rayon::prelude::*;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// GIFs keep at most this many frames (a stride through the clip), bounding preview memory.
const GIF_FRAMES: usize = 60;
/// Columns of the contact sheet.
const SHEET_FRAMES: usize = 4;

/// What one clip is made of.
pub struct ClipInput<'a> {
    /// The input file as named on the command line, and its bytes (hashed into the manifest).
    pub input: &'a str,
    pub input_bytes: &'a [u8],
    /// Every loaded source (prelude, root, imports), as the checker's source map holds them.
    pub sources: &'a SourceMap,
    pub front: &'a Front,
    pub background: &'a Background,
    /// Track index of the ego.
    pub ego: usize,
    pub frames: &'a [usize],
}

#[derive(Clone, Debug)]
pub struct ClipReport {
    pub dir: PathBuf,
    pub frames: usize,
    /// True when a complete earlier run was found and nothing was written.
    pub resumed: bool,
    /// The manifest written (or kept). A batch keeps only its summary: see `summary`.
    pub manifest: Manifest,
    /// Files the clip holds and their total size (set whatever `manifest.files` holds).
    pub files: usize,
    pub bytes: u64,
}

impl ClipReport {
    fn new(dir: &Path, frames: usize, resumed: bool, manifest: Manifest) -> Self {
        let files = manifest.files.len();
        let bytes = manifest.files.iter().map(|f| f.bytes).sum();
        ClipReport { dir: dir.to_path_buf(), frames, resumed, manifest, files, bytes }
    }

    /// Drop the per-file list (kept on disk in manifest.json), so a batch report's memory does not
    /// grow with the number of files per clip; counts and sizes stay in `files` and `bytes`.
    pub fn summary(mut self) -> Self {
        self.manifest.files = Vec::new();
        self
    }
}

#[derive(Default)]
struct Clock {
    bev: AtomicU64,
    occ: AtomicU64,
    lidar: AtomicU64,
    visibility: AtomicU64,
    write: AtomicU64,
    preview: AtomicU64,
}

impl Clock {
    fn add(slot: &AtomicU64, since: Instant) -> Instant {
        let now = Instant::now();
        slot.fetch_add((now - since).as_nanos() as u64, Ordering::Relaxed);
        now
    }
}

struct Scratch {
    raster: Rasterizer,
    bev: Bev,
    occ: Occupancy,
    /// Allocated on first use: only with `--flow`.
    flow: Flow,
    velocities: Vec<[f64; 2]>,
    /// Allocated on first use: only with `--visibility`.
    masks: Masks,
}

impl Scratch {
    fn new() -> Self {
        Scratch {
            raster: Rasterizer::new(),
            bev: Bev::zeros(),
            occ: Occupancy::empty(),
            flow: Flow::default(),
            velocities: Vec::new(),
            masks: Masks::default(),
        }
    }
}

/// Scratch kept between clips, so a batch's clips reuse it rather than zero and fault in some
/// 13 MB per scratch per clip (`bench clip`). Reuse across clips is reuse across frames: each
/// buffer is rewritten or cleared by what fills it (`rasterize_into` clears what it painted).
static SCRATCH: Mutex<Vec<Scratch>> = Mutex::new(Vec::new());

/// Per-frame results kept for the clip-level files.
struct FrameOut {
    boxes: FrameBoxes,
    files: Vec<OutputFile>,
    /// Ego pose, box motion and timestamp, when the clip knows its world.
    world: Option<FrameWorld>,
    thumbs: Thumbs,
}

/// One frame's preview images per stage (bev, occ, lidar): drawn for the contact sheet, coded for
/// the GIFs.
#[derive(Default)]
struct Thumbs {
    sheet: [Option<Vec<u8>>; 3],
    gif: [Option<GifFrame>; 3],
}

impl Thumbs {
    fn keep(&mut self, stage: usize, img: Vec<u8>, gif_delay: Option<u16>, sheet: bool) {
        self.gif[stage] = gif_delay.map(|d| gif_frame(&img, d));
        self.sheet[stage] = sheet.then_some(img);
    }
}

/// The clip's output directory.
pub fn clip_dir(out: &Path, front: &Front, ego: usize) -> PathBuf {
    out.join(&front.concrete.name).join(&front.tracks.agents[ego].name)
}

/// The seed of one clip's sensor noise: the scene seed, decorrelated per ego so two egos at one
/// spot do not see the same noise.
pub fn clip_seed(front: &Front, ego: usize) -> u64 {
    Rng::stream(front.concrete.seed, &format!("clip:{}", front.tracks.agents[ego].name)).next_u64()
}

/// The manifest this run would write, without files and timings: compared with an existing one
/// to decide whether the clip is already complete.
fn expected_manifest(ci: &ClipInput, opts: &Options, backend: &str) -> Manifest {
    let f = ci.front;
    let mut m = Manifest::new(
        ci.input,
        ci.input_bytes,
        f.concrete.seed,
        &f.tracks.agents[ci.ego].name,
        f.tracks.frames,
        f.tracks.rate,
    );
    m.backend = if opts.stage >= Stage::Occ { backend.to_string() } else { "none".to_string() };
    m.rig = (opts.stage >= Stage::Lidar).then(|| opts.rig.name.clone());
    m.stage = opts.stage.name().to_string();
    m.frames = ci.frames.to_vec();
    m.static_bev = opts.static_bev.as_ref().map(|b| b.source.clone());
    if opts.stage >= Stage::Occ
        && let super::OccBackend::Grounded(g) = &opts.backend
        && let Some((w, c)) = g.files()
    {
        m.weights = Some(w.display().to_string());
        m.grounded_config = Some(c.display().to_string());
        m.device = Some(g.device().name().to_string());
    }
    m.flow = opts.flow && opts.stage >= Stage::Occ;
    let cameras = opts.visibility.as_ref().filter(|_| opts.stage >= Stage::Occ);
    m.visibility = cameras.map(|c| c.name.clone());
    // `mask_lidar` casts the LiDAR rig's rays at stage occ too.
    let rig = (opts.stage >= Stage::Lidar || cameras.is_some()).then_some(&opts.rig);
    m.build_key = build_key(ci.sources, rig, cameras);
    m
}

/// What, besides the fields compared by name, decides a clip's bytes: the compiler version, the
/// output format (`output::FORMAT`), every loaded source (an edited import or prelude changes the scene) and the effective rig
/// (`--lidar-resolution` changes the rig but not its name) and, with `--visibility`, the camera rig.
fn build_key(
    sources: &SourceMap,
    rig: Option<&crate::lidar::Rig>,
    cameras: Option<&crate::visibility::CameraRig>,
) -> String {
    let mut bytes = Vec::new();
    let mut field = |b: &[u8]| {
        bytes.extend_from_slice(&(b.len() as u64).to_le_bytes());
        bytes.extend_from_slice(b);
    };
    field(env!("CARGO_PKG_VERSION").as_bytes());
    field(&crate::output::FORMAT.to_le_bytes());
    // Texts, not names: the same files named from another directory compile the same.
    for f in &sources.files {
        field(f.text.as_bytes());
    }
    if let Some(r) = rig {
        field(serde_json::to_string(r).unwrap_or_default().as_bytes());
    }
    if let Some(c) = cameras {
        field(serde_json::to_string(c).unwrap_or_default().as_bytes());
    }
    crate::fsio::input_hash(&bytes)
}

/// A complete earlier run of the same clip: same compiler, input (and its imports and prelude),
/// seed, stage, frames, backend, effective rig, and every file it lists present with its recorded size.
fn complete(dir: &Path, want: &Manifest) -> Option<Manifest> {
    let text = std::fs::read_to_string(dir.join("manifest.json")).ok()?;
    let m: Manifest = serde_json::from_str(&text).ok()?;
    let same = m.compiler_version == want.compiler_version
        && m.input_hash == want.input_hash
        && m.build_key == want.build_key
        && m.seed == want.seed
        && m.stage == want.stage
        && m.frames == want.frames
        && m.backend == want.backend
        && m.rig == want.rig
        && m.ego == want.ego
        && m.static_bev == want.static_bev
        && m.flow == want.flow
        && m.visibility == want.visibility
        // An edited clip is not what this input compiles to.
        && m.edits.is_empty();
    let files_ok = m
        .files
        .iter()
        .all(|f| std::fs::metadata(dir.join(&f.path)).is_ok_and(|md| md.is_file() && md.len() == f.bytes));
    (same && files_ok).then_some(m)
}

/// The manifest of a clip in `dir` that `rocc edit` has changed since it was compiled, if any:
/// `rocc compile` does not overwrite it without `--force`.
pub fn edited_clip(dir: &Path) -> Option<Manifest> {
    let text = std::fs::read_to_string(dir.join("manifest.json")).ok()?;
    let m: Manifest = serde_json::from_str(&text).ok()?;
    (!m.edits.is_empty()).then_some(m)
}

/// Every box of frame `f` in the ego's frame, the ego itself excluded (nuPlan's annotations never
/// contain the ego), and only boxes whose footprint can reach the 100 m grid.
pub fn frame_boxes(front: &Front, ego: usize, f: usize) -> Vec<EgoBox> {
    let t = &front.tracks;
    let ego_pose = t.poses[ego][f];
    let near = |i: usize| {
        let p = t.poses[i][f];
        let a = &t.agents[i];
        let r = 0.5 * a.size[0].hypot(a.size[1]) + HALF_EXTENT_M;
        // Chebyshev distance bounds the ego-frame coordinates whatever the ego's heading.
        (p.x - ego_pose.x).abs().max((p.y - ego_pose.y).abs()) <= r * std::f64::consts::SQRT_2
    };
    let states =
        t.agents.iter().enumerate().filter(|&(i, _)| i != ego && near(i) && front.present(i, f)).map(|(i, a)| {
            AgentState {
                track: i as u32,
                name: &a.name,
                kind: &a.kind,
                class: a.class,
                size: a.size,
                pose: t.poses[i][f],
            }
        });
    // Open doors: boxes of their vehicle's agent, track and class (`body::DOOR_KIND`).
    let with_doors = t.bodies.iter().enumerate().filter(|(_, b)| !b.doors.is_empty()).map(|(i, _)| i);
    let doors = with_doors.filter(|&i| i != ego && near(i) && front.present(i, f)).flat_map(|i| {
        let a = &t.agents[i];
        open_doors(t, i, f).map(move |(pose, size)| AgentState {
            track: i as u32,
            name: &a.name,
            kind: DOOR_KIND,
            class: a.class,
            size,
            pose,
        })
    });
    let mut boxes = to_ego(ego_pose, states.chain(doors));
    boxes.retain(|b| box_reaches_patch(b.x, b.y, b.l, b.w));
    boxes
}

/// Whether a box of `frame_boxes` is an open door (part of its vehicle's shape, not a box of
/// `boxes.json`).
pub fn is_door(b: &EgoBox) -> bool {
    b.kind == DOOR_KIND
}

/// Indices into `frames` sampled for the GIFs and for the contact sheet.
fn preview_picks(n: usize) -> (Vec<usize>, Vec<usize>) {
    if n == 0 {
        return (vec![], vec![]);
    }
    let stride = n.div_ceil(GIF_FRAMES);
    let gif: Vec<usize> = (0..n).step_by(stride).collect();
    let mut sheet: Vec<usize> = (0..SHEET_FRAMES).map(|c| c * (n - 1) / (SHEET_FRAMES - 1).max(1)).collect();
    sheet.dedup();
    (gif, sheet)
}

/// Where a clip's frames come from: for frame `f`, the ego's world pose and the frame's boxes,
/// with its BEV rendered into the given buffer. `compile_clip` rasterises the scene; `rocc edit`
/// re-rasterises edited boxes over a compiled BEV's static layers.
pub type FrameSource<'a> = dyn Fn(usize, &mut Rasterizer, &mut Bev) -> io::Result<(Pose, Vec<EgoBox>)> + Sync + 'a;

/// A box's velocity over the ground at frame `f`, in that frame's ego axes (m/s), for `--flow`.
pub type BoxVelocity<'a> = dyn Fn(usize, &EgoBox) -> [f64; 2] + Sync + 'a;

/// Everything the stages after the BEV need to render a clip into a directory.
pub struct Render<'a> {
    pub frames: &'a [usize],
    pub rate: f64,
    pub background: &'a Background,
    /// Sensor-noise seed of the clip.
    pub seed: u64,
    /// The manifest to write, without files and timings.
    pub manifest: Manifest,
    pub source: &'a FrameSource<'a>,
    /// The tracks and map behind the frames: the ego pose and motion in `boxes.json`, and
    /// `scene.json`.
    pub world: Option<ClipWorld<'a>>,
    /// Where box velocities come from; `None` writes no flow even with `--flow`.
    pub velocity: Option<&'a BoxVelocity<'a>>,
}

/// Compile one clip into `dir`. `on_frame` is called once per finished frame (progress).
pub fn compile_clip(
    ci: &ClipInput,
    opts: &Options,
    dir: &Path,
    on_frame: &(dyn Fn() + Sync),
) -> io::Result<ClipReport> {
    let backend = opts.occ_backend();
    let want = expected_manifest(ci, opts, backend.name());
    if !opts.force
        && let Some(m) = complete(dir, &want)
    {
        for _ in ci.frames {
            on_frame();
        }
        return Ok(ClipReport::new(dir, ci.frames.len(), true, m));
    }
    let front = ci.front;
    let source = |f: usize, raster: &mut Rasterizer, bev: &mut Bev| -> io::Result<(Pose, Vec<EgoBox>)> {
        let ego_pose = front.tracks.poses[ci.ego][f];
        let boxes = frame_boxes(front, ci.ego, f);
        raster.rasterize_into(&front.map, ego_pose, &boxes, bev);
        if let Some(s) = &opts.static_bev {
            s.apply(f, bev)?;
        }
        Ok((ego_pose, boxes))
    };
    let t = &front.tracks;
    let velocity = |f: usize, b: &EgoBox| -> [f64; 2] {
        let i = b.track as usize;
        let v = ground_velocity(t, &|g| front.present(i, g), i, f);
        to_ego_axes(v, t.poses[ci.ego][f].yaw)
    };
    let render = Render {
        frames: ci.frames,
        rate: front.tracks.rate,
        background: ci.background,
        seed: clip_seed(front, ci.ego),
        manifest: want,
        source: &source,
        world: Some(ClipWorld {
            scenario: &front.concrete.name,
            tracks: &front.tracks,
            map: &front.map,
            ego: ci.ego,
            present: &|i, f| front.present(i, f),
        }),
        velocity: Some(&velocity),
    };
    render_clip(&render, opts, dir, on_frame)
}

type FrameFn<'f> = dyn Fn(&mut Scratch, usize, usize, Option<(Pose, Vec<EgoBox>)>) -> io::Result<FrameOut> + Sync + 'f;

/// The frames of a backend that computes occupancy several frames at a time (the learned one):
/// `per_call` frames at once get their BEV (side by side), then their occupancy in one call,
/// then the rest of their work (side by side). A backend failure is the clip's diagnostic.
fn batched_frames(
    r: &Render,
    backend: &dyn crate::backend::OccupancyBackend,
    per_call: usize,
    clock: &Clock,
    pool: &std::sync::Mutex<Vec<Scratch>>,
    frame: &FrameFn,
) -> io::Result<Vec<FrameOut>> {
    let mut outs = Vec::with_capacity(r.frames.len());
    for (c, chunk) in r.frames.chunks(per_call.max(1)).enumerate() {
        let mut scratch: Vec<Scratch> = {
            let mut p = pool.lock().map_err(|_| io::Error::other("scratch pool poisoned"))?;
            (0..chunk.len()).map(|_| p.pop().unwrap_or_else(Scratch::new)).collect()
        };
        let made: Vec<(Pose, Vec<EgoBox>)> = scratch
            .par_iter_mut()
            .zip(chunk)
            .map(|(s, &f)| {
                let t0 = Instant::now();
                let m = (r.source)(f, &mut s.raster, &mut s.bev);
                Clock::add(&clock.bev, t0);
                m
            })
            .collect::<io::Result<_>>()?;
        let t0 = Instant::now();
        let mut occ: Vec<Occupancy> = scratch.iter_mut().map(|s| std::mem::take(&mut s.occ)).collect();
        let inputs: Vec<OccInput> = scratch
            .iter()
            .zip(&made)
            .zip(chunk)
            .map(|((s, (pose, boxes)), &f)| OccInput {
                boxes,
                bev: &s.bev,
                background: r.background,
                ego: *pose,
                seed: r.seed,
                frame: f,
            })
            .collect();
        let done = backend.occupancy_batch(&inputs, &mut occ);
        drop(inputs);
        for (s, o) in scratch.iter_mut().zip(occ) {
            s.occ = o;
        }
        done.map_err(|d| io::Error::other(crate::backend::BackendFailure(d)))?;
        Clock::add(&clock.occ, t0);
        let base = c * per_call.max(1);
        let part = scratch
            .par_iter_mut()
            .zip(made)
            .enumerate()
            .map(|(i, (s, m))| frame(s, base + i, chunk[i], Some(m)))
            .collect::<io::Result<Vec<_>>>()?;
        outs.extend(part);
        if let Ok(mut p) = pool.lock() {
            p.extend(scratch);
        }
    }
    Ok(outs)
}

/// Render every frame of `r` (BEV, then occupancy and LiDAR as `opts.stage` asks), the clip-level
/// files and the manifest, into `dir`.
pub fn render_clip(r: &Render, opts: &Options, dir: &Path, on_frame: &(dyn Fn() + Sync)) -> io::Result<ClipReport> {
    let backend = opts.occ_backend();
    std::fs::create_dir_all(dir)?;
    // A stale manifest must not vouch for a half-rewritten directory if this run is interrupted.
    match std::fs::remove_file(dir.join("manifest.json")) {
        Err(e) if e.kind() != io::ErrorKind::NotFound => return Err(e),
        _ => {}
    }
    // Temporaries of an interrupted earlier run of this clip (never another clip's: one dir each).
    crate::fsio::sweep_stale_tmp(dir)?;

    let seed = r.seed;
    let (gif_picks, sheet_picks) = if opts.previews { preview_picks(r.frames.len()) } else { (vec![], vec![]) };
    let clock = Clock::default();
    // The frames' occupancy and LiDAR files reach the disk while later frames compute.
    let behind = crate::fsio::Behind::new();
    let rate = r.rate;
    // GIF frames play at the clip's real speed.
    let stride = gif_picks.get(1).copied().unwrap_or(1);
    let delay_cs = ((100.0 * stride as f64 / rate).round() as u16).max(2);

    // `made`: the frame's pose and boxes when its BEV and occupancy are already in `s`
    // (`batched_frames`).
    let frame = |s: &mut Scratch, n: usize, f: usize, made: Option<(Pose, Vec<EgoBox>)>| -> io::Result<FrameOut> {
        let t0 = Instant::now();
        let occ_ready = made.is_some();
        let (ego_pose, boxes) = match made {
            Some(m) => m,
            None => (r.source)(f, &mut s.raster, &mut s.bev)?,
        };
        let listed: Vec<EgoBox> = boxes.iter().filter(|b| !is_door(b)).cloned().collect();
        let world = r.world.map(|w| w.frame(f, ego_pose, &listed));
        let t2 = Clock::add(&clock.bev, t0);
        let mut files = vec![write_bev_frame(dir, f, &s.bev)?];
        let mut t3 = Clock::add(&clock.write, t2);
        let (gif_delay, in_sheet) = (gif_picks.contains(&n).then_some(delay_cs), sheet_picks.contains(&n));
        let preview = gif_delay.is_some() || in_sheet;
        let mut thumbs = Thumbs::default();
        // The LiDAR's block summary, made while the occupancy is written.
        let mut skip = None;
        if preview {
            let mut img = vec![0u8; PREVIEW_SIDE * PREVIEW_SIDE];
            paint_bev(&s.bev, &mut img);
            thumbs.keep(0, img, gif_delay, in_sheet);
            // The full BEV preview (with legend) shows the first frame, written while
            // the other frames render.
            if n == 0 {
                files.push(write_preview_png(dir, &s.bev)?);
            }
            t3 = Clock::add(&clock.preview, t3);
        }
        if opts.stage >= Stage::Occ {
            let input =
                OccInput { boxes: &boxes, bev: &s.bev, background: r.background, ego: ego_pose, seed, frame: f };
            if !occ_ready {
                backend.occupancy_into(&input, &mut s.occ);
            }
            let t4 = Clock::add(&clock.occ, t3);
            let path = occ_frame_path(dir, f);
            let (bytes, made) = write_occ(To::Behind(&behind), &path, &s.occ, opts.stage >= Stage::Lidar)?;
            skip = made;
            files.push(OutputFile { path: rel(dir, &path), bytes });
            if opts.flow
                && let Some(velocity) = r.velocity
            {
                s.velocities.clear();
                s.velocities.extend(boxes.iter().map(|b| velocity(f, b)));
                flow_into(&s.occ, &boxes, &s.velocities, &mut s.flow);
                let path = flow_frame_path(dir, f);
                files.push(OutputFile { path: rel(dir, &path), bytes: write_flow(&path, &s.flow)? });
            }
            t3 = Clock::add(&clock.write, t4);
            if let Some(cameras) = &opts.visibility {
                masks_into(&s.occ, &opts.rig, cameras, &mut s.masks);
                let t5 = Clock::add(&clock.visibility, t3);
                let path = labels_frame_path(dir, f);
                files.push(OutputFile { path: rel(dir, &path), bytes: write_labels(&path, &s.occ, &s.masks)? });
                t3 = Clock::add(&clock.write, t5);
            }
            if preview {
                let mut img = vec![0u8; PREVIEW_SIDE * PREVIEW_SIDE];
                paint_occ(&s.occ, &mut img);
                thumbs.keep(1, img, gif_delay, in_sheet);
                t3 = Clock::add(&clock.preview, t3);
            }
        }
        if opts.stage >= Stage::Lidar {
            let pc = scan_with(&s.occ, skip.as_ref(), &opts.rig, seed, f);
            let t5 = Clock::add(&clock.lidar, t3);
            let (bin, pcd) = (bin_frame_path(dir, f), pcd_frame_path(dir, f));
            files.push(OutputFile { path: rel(dir, &bin), bytes: write_bin(To::Behind(&behind), &bin, &pc)? });
            files.push(OutputFile { path: rel(dir, &pcd), bytes: write_pcd(To::Behind(&behind), &pcd, &pc)? });
            t3 = Clock::add(&clock.write, t5);
            if preview {
                let mut img = vec![0u8; PREVIEW_SIDE * PREVIEW_SIDE];
                paint_lidar(&pc, &mut img);
                thumbs.keep(2, img, gif_delay, in_sheet);
                Clock::add(&clock.preview, t3);
            }
        }
        on_frame();
        Ok(FrameOut { boxes: FrameBoxes { frame: f, t: f as f64 / rate, boxes: listed }, world, files, thumbs })
    };
    let pool: &Mutex<Vec<Scratch>> = &SCRATCH;
    let batch = backend.batch().filter(|_| opts.stage >= Stage::Occ);
    let outs: Vec<FrameOut> = match batch {
        Some(per_call) => batched_frames(r, &*backend, per_call, &clock, pool, &frame)?,
        None => r
            .frames
            .par_iter()
            .enumerate()
            .map(|(n, &f)| {
                // Taken from the pool, not per thread: a frame's own parallel work may run another
                // frame on the same thread, which then takes (or makes) a scratch of its own.
                let mut s = pool.lock().ok().and_then(|mut p| p.pop()).unwrap_or_else(Scratch::new);
                let out = frame(&mut s, n, f, None);
                if let Ok(mut p) = pool.lock()
                    && p.len() < 2 * rayon::current_num_threads()
                {
                    p.push(s);
                }
                out
            })
            .collect::<io::Result<Vec<_>>>()?,
    };

    let t0 = Instant::now();
    let mut files: Vec<OutputFile> = outs.iter().flat_map(|o| o.files.iter().cloned()).collect();
    let frame_boxes: Vec<FrameBoxes> = outs.iter().map(|o| o.boxes.clone()).collect();
    let worlds: Option<Vec<FrameWorld>> = outs.iter().map(|o| o.world.clone()).collect();
    match (&worlds, &r.world) {
        (Some(w), Some(cw)) => {
            files.push(write_boxes_json_with(dir, &frame_boxes, w)?);
            files.push(write_scene_json(dir, &cw.scene())?);
        }
        _ => files.push(write_boxes_json(dir, &frame_boxes)?),
    }
    let t1 = Clock::add(&clock.write, t0);

    if opts.previews {
        let names = ["bev", "occ", "lidar"];
        let stages = 1 + (opts.stage >= Stage::Occ) as usize + (opts.stage >= Stage::Lidar) as usize;
        let sheet = |s: usize| -> Vec<Vec<u8>> {
            sheet_picks.iter().filter_map(|&n| outs[n].thumbs.sheet[s].clone()).collect()
        };
        let gif =
            |s: usize| -> Vec<&GifFrame> { gif_picks.iter().filter_map(|&n| outs[n].thumbs.gif[s].as_ref()).collect() };
        let rows: Vec<(&str, Vec<Vec<u8>>)> = (0..stages).map(|s| (names[s], sheet(s))).collect();
        let sheet_frames: Vec<usize> = sheet_picks.iter().map(|&n| r.frames[n]).collect();
        // The GIFs' frames are coded already; the sheet is coded beside them.
        let (gifs, sheet) = rayon::join(
            || {
                (0..stages)
                    .map(|s| write_gif(dir, &format!("{}.gif", names[s]), &gif(s)))
                    .collect::<io::Result<Vec<_>>>()
            },
            || write_sheet(dir, &sheet_frames, &rows),
        );
        files.extend(gifs?);
        files.push(sheet?);
        Clock::add(&clock.preview, t1);
    }
    files.sort_by(|a, b| a.path.cmp(&b.path));

    let mut manifest = r.manifest.clone();
    let secs = |a: &AtomicU64| a.load(Ordering::Relaxed) as f64 * 1e-9;
    // View and BEV are one step of the frame source now; "bev" holds both.
    let mut timings = vec![("bev", &clock.bev)];
    if opts.stage >= Stage::Occ {
        timings.push(("occ", &clock.occ));
    }
    if opts.stage >= Stage::Lidar {
        timings.push(("lidar", &clock.lidar));
    }
    if opts.stage >= Stage::Occ && opts.visibility.is_some() {
        timings.push(("visibility", &clock.visibility));
    }
    timings.extend([("write", &clock.write), ("preview", &clock.preview)]);
    manifest.timings =
        timings.into_iter().map(|(n, a)| StageTiming { stage: n.to_string(), seconds: secs(a) }).collect();
    manifest.files = files;
    let t2 = Instant::now();
    behind.finish()?;
    Clock::add(&clock.write, t2);
    write_manifest(dir, &manifest)?;
    Ok(ClipReport::new(dir, r.frames.len(), false, manifest))
}

/// Write the occupancy's `.npy`; with `summarise`, also the LiDAR's block summary of it, fed each
/// piece of the labels as it is written: one read of the 5 MB from memory instead of two (the
/// copy into the file's buffer then finds the piece in the cache). Returns the file's size.
fn write_occ(to: To, path: &Path, occ: &Occupancy, summarise: bool) -> io::Result<(u64, Option<Skip>)> {
    use crate::backend::layout::{NX, NY, NZ};
    // The summary covers the grid's shape only.
    let mut summary = (summarise && occ.labels.dim() == (NX, NY, NZ)).then(Skip::summary);
    let bytes = write_occ_npy(to, path, occ, |piece| {
        if let Some(s) = &mut summary {
            s.add(piece);
        }
    })?;
    Ok((bytes, summary.and_then(|s| s.finish())))
}

fn rel(dir: &Path, p: &Path) -> String {
    p.strip_prefix(dir).unwrap_or(p).to_string_lossy().replace('\\', "/")
}

#[cfg(test)]
mod tests {
    use super::preview_picks;

    #[test]
    fn previews_sample_the_whole_clip() {
        let (gif, sheet) = preview_picks(200);
        assert!(gif.len() <= super::GIF_FRAMES && gif[0] == 0 && *gif.last().unwrap() >= 190);
        assert_eq!(sheet, vec![0, 66, 132, 199]);
        assert_eq!(preview_picks(1), (vec![0], vec![0]));
        assert_eq!(preview_picks(2).1, vec![0, 1]);
    }
}
