//! Box-stream bridge (`rocc import boxes`). In: a JSON file of per-frame 3D boxes of a recorded
//! (or edited) clip in one of three conventions, and the frame's ego pose. Out: `.scn` text whose
//! agents replay their tracks on a road-less map (`road none`) — never tensors: the text goes
//! through `check::check_text` and `compile::front` before it is handed back, so the checker is
//! the gate here as for every front end.
//!
//! Input (`convention` below says how `center`, `size`, `yaw` read):
//!
//! ```json
//! { "rate_hz": 2.0,                        // optional; else 1 / median frame interval
//!   "ego_size": [5.176, 2.297, 1.777],     // optional (l, w, h); default nuPlan's Pacifica
//!   "sensor_to_ego": {"x": 0, "y": 0, "yaw": 0},   // optional, mmdet3d only
//!   "frames": [ { "frame": 0, "time": 0.0,
//!       "ego_pose": {"x": 1.0, "y": 2.0, "yaw": 0.1},   // or {"translation": [x,y,z], "rotation": [w,x,y,z]}
//!       "boxes": [ {"track": "a1", "class": "vehicle.car",
//!                   "center": [x, y, z], "size": [a, b, c], "yaw": 0.3,
//!                   "states": {"hazards": true, "doors": {"front_left": 35.0}}} ] } ] }  // optional
//! ```
//!
//! Conventions, each converted exactly to rocc's world box (centre, l, w, h, yaw CCW from +x):
//! - `nuscenes`: global frame; `size` = (w, l, h) (`Box.wlh`); `yaw` from +x, CCW.
//! - `mmdet3d` (v0.17 LiDAR boxes, as `create_data` writes `gt_boxes`): centre in the sensor frame,
//!   `size` = (w, l, h), `yaw_mm = -yaw_nuscenes - pi/2`, so yaw = -yaw_mm - pi/2; a box may also
//!   be given as `"box": [cx, cy, cz, w, l, h, yaw]`. The sensor frame is mapped to the ego frame
//!   by `sensor_to_ego` (identity when absent), then to the world by the frame's ego pose.
//! - `nuplan`: global frame; `size` = (l, w, h) about the geometric centre; `yaw` from +x, CCW.
//!
//! Boxes stand on the ground in rocc (z = h / 2): the recorded `z` is not kept. The BEV never
//! reads it, so the lossless guarantee — rasterising the imported scene at the recorded frames
//! reproduces the BEV rasterised from the input boxes, IoU 1.0 per channel — is unaffected.

pub use crate::check::classes::{ClassMap, map_class};

mod feasible;

use crate::check::scenario::Class;
use crate::diag::Diagnostic;
use crate::geom::wrap_angle;
use crate::place::Pose;
use crate::source::{SourceMap, Span};
use crate::view::{AgentState, EgoBox, to_ego};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

mod states;
pub use states::StatesIn;

/// nuPlan's ego vehicle (Chrysler Pacifica), l, w, h in metres.
pub const NUPLAN_EGO_SIZE: [f64; 3] = [5.176, 2.297, 1.777];
/// The checker's bound on replayed coordinates (m).
const COORD_LIMIT: f64 = 1000.0;
/// The checker's bounds on a box side (m).
const SIZE_RANGE: (f64, f64) = (0.05, 40.0);

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Convention {
    NuScenes,
    Mmdet3d,
    NuPlan,
}

impl Convention {
    pub fn name(self) -> &'static str {
        match self {
            Convention::NuScenes => "nuscenes",
            Convention::Mmdet3d => "mmdet3d",
            Convention::NuPlan => "nuplan",
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileIn {
    #[serde(default)]
    rate_hz: Option<f64>,
    #[serde(default)]
    ego_size: Option<[f64; 3]>,
    #[serde(default)]
    sensor_to_ego: Option<PoseIn>,
    #[serde(default)]
    convention: Option<String>,
    frames: Vec<FrameIn>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FrameIn {
    frame: i64,
    time: f64,
    ego_pose: PoseIn,
    #[serde(default)]
    boxes: Vec<BoxIn>,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(untagged)]
enum PoseIn {
    Planar { x: f64, y: f64, yaw: f64 },
    Quat { translation: [f64; 3], rotation: [f64; 4] },
}

impl PoseIn {
    fn pose(self) -> Pose {
        match self {
            PoseIn::Planar { x, y, yaw } => Pose { x, y, yaw },
            PoseIn::Quat { translation: t, rotation: [w, x, y, z] } => {
                Pose { x: t[0], y: t[1], yaw: (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z)) }
            }
        }
    }
}

#[derive(Deserialize, Clone)]
#[serde(untagged)]
enum TrackId {
    Text(String),
    Number(i64),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxIn {
    track: TrackId,
    class: String,
    #[serde(default)]
    center: Option<[f64; 3]>,
    #[serde(default)]
    size: Option<[f64; 3]>,
    #[serde(default)]
    yaw: Option<f64>,
    #[serde(default, rename = "box")]
    packed: Option<[f64; 7]>,
    /// Lamps and doors (`states.rs`).
    #[serde(default)]
    states: Option<StatesIn>,
}

/// One recorded box in rocc's world frame.
#[derive(Clone, Debug, PartialEq)]
pub struct RecBox {
    /// The recording's track id.
    pub track: String,
    /// The recording's class name and what it maps to.
    pub class_name: String,
    pub class: Class,
    pub kind: &'static str,
    /// l, w, h (m).
    pub size: [f64; 3],
    pub pose: Pose,
    /// Lamps and doors, where the box gave them.
    pub states: Option<StatesIn>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct RecFrame {
    /// The recording's frame index and time.
    pub frame: i64,
    pub time: f64,
    pub ego: Pose,
    pub boxes: Vec<RecBox>,
}

/// A box stream converted to rocc's conventions (world origin already shifted by `origin`).
#[derive(Clone, Debug, PartialEq)]
pub struct Recorded {
    pub convention: Convention,
    pub rate: f64,
    pub ego_size: [f64; 3],
    /// Subtracted from every recorded world coordinate (multiples of 1 km, so the subtraction is
    /// exact for coordinates of the same magnitude); (0, 0) when none was needed.
    pub origin: (f64, f64),
    pub frames: Vec<RecFrame>,
}

/// The result of an import: the `.scn` text, the converted stream and any warnings.
#[derive(Clone, Debug)]
pub struct Imported {
    pub text: String,
    pub recorded: Recorded,
    pub warnings: Vec<Diagnostic>,
    /// Declaration order of the replayed agents (after `ego`): (agent name, track id, first
    /// clip frame, last clip frame).
    pub agents: Vec<AgentSpan>,
}

/// (agent name, recorded track id, first clip frame, last clip frame).
pub type AgentSpan = (String, String, usize, usize);

/// Byte offset of a 1-based (line, column) in `text`.
fn offset(text: &str, line: usize, col: usize) -> usize {
    let mut off = 0;
    for (i, l) in text.split_inclusive('\n').enumerate() {
        if i + 1 == line {
            return (off + col.saturating_sub(1)).min(text.len());
        }
        off += l.len();
    }
    text.len()
}

/// Read and convert a box-stream file. The JSON text is added to `sources` so errors point into it.
pub fn read_stream(
    path: &Path,
    conv: Convention,
    sources: &mut SourceMap,
) -> Result<(Recorded, Vec<Diagnostic>), Vec<Diagnostic>> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        vec![
            Diagnostic::error("E0705", format!("cannot read box stream `{}`: {e}", path.display()))
                .help("pass a readable UTF-8 JSON file"),
        ]
    })?;
    let id = sources.add(path.display().to_string(), text.clone());
    let span_at = |line: usize, col: usize| {
        let o = offset(&text, line, col) as u32;
        Span { file: id, start: o, end: (o + 1).min(text.len() as u32).max(o) }
    };
    let file: FileIn = serde_json::from_str(&text).map_err(|e| {
        vec![
            Diagnostic::error("E0705", format!("box stream `{}`: {e}", path.display()))
                .label(span_at(e.line(), e.column()), "here")
                .help("see `rocc explain E0705` for the expected JSON layout"),
        ]
    })?;
    let whole = Span { file: id, start: 0, end: text.len().min(1) as u32 };
    convert(file, conv, whole)
}

fn convert(file: FileIn, conv: Convention, whole: Span) -> Result<(Recorded, Vec<Diagnostic>), Vec<Diagnostic>> {
    let bad =
        |m: String, help: &str| vec![Diagnostic::error("E0706", m).label(whole, "in this file").help(help.to_string())];
    if let Some(c) = &file.convention
        && !c.eq_ignore_ascii_case(conv.name())
    {
        return Err(bad(
            format!("the file says its convention is `{c}` but `--convention {}` was given", conv.name()),
            "pass the convention the boxes were written in",
        ));
    }
    if file.frames.is_empty() {
        return Err(bad("the box stream has no frames".into(), "give at least one frame with its ego pose"));
    }
    let mut frames_in = file.frames;
    frames_in.sort_by_key(|f| f.frame);
    if let Some(w) = frames_in.windows(2).find(|w| w[0].frame == w[1].frame) {
        return Err(bad(format!("frame {} appears twice", w[0].frame), "give each frame once"));
    }
    if let Some(w) = frames_in.windows(2).find(|w| w[1].time <= w[0].time || !w[1].time.is_finite()) {
        return Err(bad(
            format!(
                "frame {} (t = {} s) is not after frame {} (t = {} s)",
                w[1].frame, w[1].time, w[0].frame, w[0].time
            ),
            "frame times must increase with the frame index",
        ));
    }
    let rate = match file.rate_hz {
        Some(r) if r.is_finite() && r > 0.0 => r,
        Some(r) => return Err(bad(format!("rate_hz {r} is not a positive number"), "e.g. `\"rate_hz\": 2.0`")),
        None if frames_in.len() < 2 => 10.0,
        None => {
            let mut dts: Vec<f64> = frames_in.windows(2).map(|w| w[1].time - w[0].time).collect();
            dts.sort_by(f64::total_cmp);
            // Rounded so the `.scn` says `2 Hz`, not `1.99996 Hz`; recorded times are kept in comments.
            ((1.0 / dts[dts.len() / 2]) * 1000.0).round() / 1000.0
        }
    };
    if !(0.5..=100.0).contains(&rate) {
        return Err(bad(format!("frame rate {rate} Hz is outside 0.5..100 Hz"), "set `rate_hz` in the file"));
    }
    if frames_in.len() as f64 / rate > 120.0 {
        return Err(bad(
            format!("{} frames at {rate} Hz last longer than the 120 s a scenario may", frames_in.len()),
            "split the clip into parts of at most 120 s",
        ));
    }
    let sensor = file.sensor_to_ego.map(PoseIn::pose).unwrap_or(Pose { x: 0.0, y: 0.0, yaw: 0.0 });
    let mut warnings = Vec::new();
    let mut frames = Vec::new();
    for f in &frames_in {
        let ego = f.ego_pose.pose();
        let mut boxes = Vec::new();
        for (n, b) in f.boxes.iter().enumerate() {
            let where_ = format!("frame {}, box {n}", f.frame);
            let (c, size, yaw) = match (b.packed, b.center, b.size, b.yaw) {
                (Some(p), None, None, None) if conv == Convention::Mmdet3d => {
                    ([p[0], p[1], p[2]], [p[3], p[4], p[5]], p[6])
                }
                (None, Some(c), Some(s), Some(y)) => (c, s, y),
                _ => {
                    return Err(bad(
                        format!(
                            "{where_}: give `center`, `size` and `yaw`{}",
                            if conv == Convention::Mmdet3d { ", or `box` [cx, cy, cz, w, l, h, yaw]" } else { "" }
                        ),
                        "each box needs a centre, a size and a yaw",
                    ));
                }
            };
            if !c.iter().chain(&size).chain([&yaw]).all(|v| v.is_finite()) {
                return Err(bad(format!("{where_}: a value is not a finite number"), "check the box"));
            }
            let (lwh, pose) = match conv {
                Convention::NuScenes => ([size[1], size[0], size[2]], Pose { x: c[0], y: c[1], yaw }),
                Convention::NuPlan => (size, Pose { x: c[0], y: c[1], yaw }),
                Convention::Mmdet3d => {
                    // v0.17: yaw_mm = -yaw_ns - pi/2 in the sensor frame; dims (w, l, h).
                    let s = Pose { x: c[0], y: c[1], yaw: -yaw - FRAC_PI_2 };
                    ([size[1], size[0], size[2]], compose(ego, compose(sensor, s)))
                }
            };
            let track = match &b.track {
                TrackId::Text(t) => t.clone(),
                TrackId::Number(n) => n.to_string(),
            };
            let m = map_class(&b.class);
            if !m.known {
                warnings.push(
                    Diagnostic::warning(
                        "E0715",
                        format!("unknown class `{}` ({where_}, track `{track}`) imported as generic_object", b.class),
                    )
                    .label(whole, "in this file")
                    .help("known: the nuPlan, nuScenes and mmdet3d class names; `rocc explain E0715` lists them"),
                );
            }
            let mut lwh = lwh;
            if lwh.iter().any(|v| !(SIZE_RANGE.0..=SIZE_RANGE.1).contains(v)) {
                warnings.push(
                    Diagnostic::warning(
                        "E0716",
                        format!("{where_} (track `{track}`): size {lwh:?} m clamped to 0.05..40 m"),
                    )
                    .label(whole, "in this file")
                    .help("this box's BEV footprint will differ from the recording's"),
                );
                lwh = lwh.map(|v| v.clamp(SIZE_RANGE.0, SIZE_RANGE.1));
            }
            boxes.push(RecBox {
                track,
                class_name: b.class.clone(),
                class: m.class,
                kind: m.kind,
                size: lwh,
                pose: Pose { yaw: keep_or_wrap(pose.yaw), ..pose },
                states: b.states.clone(),
            });
        }
        frames.push(RecFrame { frame: f.frame, time: f.time, ego: Pose { yaw: keep_or_wrap(ego.yaw), ..ego }, boxes });
    }
    // Shift the origin when the recording's coordinates exceed what a `.scn` may hold (nuPlan's
    // UTM metres): by whole kilometres, so the subtraction is exact for nearby coordinates.
    let max = frames
        .iter()
        .flat_map(|f| std::iter::once(f.ego).chain(f.boxes.iter().map(|b| b.pose)))
        .map(|p| p.x.abs().max(p.y.abs()))
        .fold(0.0, f64::max);
    let origin = if max > COORD_LIMIT - 1.0 {
        let e = frames[0].ego;
        ((e.x / 1000.0).round() * 1000.0, (e.y / 1000.0).round() * 1000.0)
    } else {
        (0.0, 0.0)
    };
    if origin != (0.0, 0.0) {
        for f in &mut frames {
            for p in std::iter::once(&mut f.ego).chain(f.boxes.iter_mut().map(|b| &mut b.pose)) {
                p.x -= origin.0;
                p.y -= origin.1;
                if p.x.abs() >= COORD_LIMIT || p.y.abs() >= COORD_LIMIT {
                    return Err(vec![
                        Diagnostic::error(
                            "E0707",
                            format!("frame {}: a box lies more than 1 km from the clip's start", f.frame),
                        )
                        .label(whole, "in this file")
                        .help("split the clip: a scenario's replayed coordinates stay within 1 km of its origin"),
                    ]);
                }
            }
        }
    }
    let ego_size = file.ego_size.unwrap_or(NUPLAN_EGO_SIZE);
    Ok((Recorded { convention: conv, rate, ego_size, origin, frames }, warnings))
}

/// `b` (in the frame of `a`) in the frame `a` is expressed in.
fn compose(a: Pose, b: Pose) -> Pose {
    let (s, c) = a.yaw.sin_cos();
    Pose { x: a.x + c * b.x - s * b.y, y: a.y + s * b.x + c * b.y, yaw: a.yaw + b.yaw }
}

/// Wrap a yaw into (-pi, pi] only when it is outside: values already there stay bit-exact.
fn keep_or_wrap(y: f64) -> f64 {
    if y > -PI && y <= PI { y } else { wrap_angle(y) }
}

/// A recorded id as a `.scn` identifier: `t_` + the id with every other character as `_`.
fn ident(track: &str) -> String {
    let body: String = track.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    format!("t_{body}")
}

/// One replayed agent: a maximal run of consecutive frames of one track.
#[derive(Clone)]
struct Segment {
    name: String,
    track: String,
    class_name: String,
    class: Class,
    kind: &'static str,
    size: [f64; 3],
    /// (clip frame, pose)
    keys: Vec<(usize, Pose)>,
    /// Per key, the box's lamps and doors.
    states: Vec<Option<StatesIn>>,
}

fn segments(rec: &Recorded, warnings: &mut Vec<Diagnostic>, whole: Span) -> Vec<Segment> {
    let mut out: Vec<Segment> = Vec::new();
    // Track id -> index of its open segment and the clip frame it was last seen in.
    let mut open: BTreeMap<String, (usize, usize)> = BTreeMap::new();
    let mut used: BTreeMap<String, usize> = BTreeMap::new();
    for (n, f) in rec.frames.iter().enumerate() {
        for b in &f.boxes {
            let cont = open.get(&b.track).filter(|(_, last)| *last + 1 == n).map(|(s, _)| *s);
            let s = match cont {
                Some(s) if out[s].kind == b.kind => s,
                _ => {
                    // A gap (or a class change) starts a new agent: a replayed agent exists only
                    // between its first and last keyframe.
                    let base = ident(&b.track);
                    let k = used.entry(base.clone()).or_insert(0);
                    *k += 1;
                    let name = if *k == 1 { base } else { format!("{base}_{k}") };
                    out.push(Segment {
                        name,
                        track: b.track.clone(),
                        class_name: b.class_name.clone(),
                        class: b.class,
                        kind: b.kind,
                        size: b.size,
                        keys: vec![],
                        states: vec![],
                    });
                    out.len() - 1
                }
            };
            if out[s].keys.last().is_some_and(|(fr, _)| *fr == n) {
                warnings.push(
                    Diagnostic::warning(
                        "E0716",
                        format!("track `{}` has two boxes in frame {}; the second is dropped", b.track, f.frame),
                    )
                    .label(whole, "in this file")
                    .help("give each track one box per frame"),
                );
                continue;
            }
            if out[s].size != b.size {
                warnings.push(
                    Diagnostic::warning(
                        "E0716",
                        format!(
                            "track `{}` changes size in frame {} ({:?} -> {:?} m); its first size is kept",
                            b.track, f.frame, out[s].size, b.size
                        ),
                    )
                    .label(whole, "in this file")
                    .help("a replayed agent has one box size; this frame's footprint will differ from the recording's"),
                );
            }
            out[s].keys.push((n, b.pose));
            out[s].states.push(b.states.clone());
            open.insert(b.track.clone(), (s, n));
        }
    }
    out
}

/// A number as `.scn` text that parses back to the same `f64` (Rust's shortest round-trip form).
fn num(v: f64) -> String {
    let s = format!("{v}");
    if s == "-0" { "0".into() } else { s }
}

fn track_text(keys: &[(usize, Pose)], rate: f64) -> String {
    let mut s = String::from("        track {\n");
    for (f, p) in keys {
        s += &format!(
            "            {} s: ({} m, {} m) yaw {} rad\n",
            num(*f as f64 / rate),
            num(p.x),
            num(p.y),
            num(p.yaw)
        );
    }
    s + "        }\n"
}

/// Write the `.scn` text of a converted stream and gate it through the checker and the front end.
pub fn to_scn(
    rec: &Recorded,
    scenario: &str,
    source_name: &str,
    warnings: &mut Vec<Diagnostic>,
    whole: Span,
) -> Result<(String, Vec<AgentSpan>), Vec<Diagnostic>> {
    let segs = feasible::drop_infeasible(segments(rec, warnings, whole), rec.rate, warnings, whole);
    let n = rec.frames.len();
    let mut t = format!(
        "// Imported by `rocc import boxes` from {source_name} (convention {}): {n} frame(s) at {} Hz, {} replayed agent(s).\n",
        rec.convention.name(),
        num(rec.rate),
        segs.len()
    );
    if rec.origin != (0.0, 0.0) {
        t += &format!("// World origin: the recording's ({}, {}) m.\n", num(rec.origin.0), num(rec.origin.1));
    }
    t += "// Recorded frame -> clip frame (time):";
    for (i, f) in rec.frames.iter().enumerate() {
        if i % 6 == 0 {
            t += "\n//  ";
        }
        t += &format!(" {} -> {i} ({} s)", f.frame, num(f.time));
    }
    t += "\n";
    t += &format!(
        "scenario {scenario} {{\n    seed 0\n    duration {} s\n    rate {} Hz\n    egos [ego]\n    road none\n\n",
        num(n as f64 / rec.rate),
        num(rec.rate)
    );
    let [l, w, h] = rec.ego_size;
    t += &format!(
        "    agent ego: sedan {{\n        length {} m\n        width {} m\n        height {} m\n",
        num(l),
        num(w),
        num(h)
    );
    let ego_keys: Vec<(usize, Pose)> = rec.frames.iter().enumerate().map(|(i, f)| (i, f.ego)).collect();
    t += &track_text(&ego_keys, rec.rate);
    t += "    }\n";
    let mut agents = Vec::new();
    for s in &segs {
        let [l, w, h] = s.size;
        t += &format!(
            "\n    // track `{}`, recorded class `{}`\n    agent {}: {} {{\n        length {} m\n        width {} m\n        height {} m\n",
            s.track.replace('\n', " "),
            s.class_name.replace('\n', " "),
            s.name,
            s.kind,
            num(l),
            num(w),
            num(h)
        );
        t += &track_text(&s.keys, rec.rate);
        let keyed: Vec<(usize, Option<&StatesIn>)> =
            s.keys.iter().zip(&s.states).map(|(k, st)| (k.0, st.as_ref())).collect();
        for line in states::lines(s.class, s.kind, &keyed, rec.rate) {
            t += &format!("        {line}\n");
        }
        t += "    }\n";
        agents.push((s.name.clone(), s.track.clone(), s.keys[0].0, s.keys[s.keys.len() - 1].0));
    }
    t += "}\n";
    // The gate: what we hand back must check and place like any hand-written scenario.
    let mut sources = SourceMap::default();
    let scen = crate::check::check_text(&format!("{scenario}.scn"), &t, Path::new("."), &mut sources)?;
    crate::compile::front(scen, None)?;
    Ok((t, agents))
}

/// `rocc import boxes`: read, convert, write the `.scn` text, and gate it.
pub fn import_boxes(
    path: &Path,
    conv: Convention,
    scenario: &str,
    sources: &mut SourceMap,
) -> Result<Imported, Vec<Diagnostic>> {
    let (recorded, mut warnings) = read_stream(path, conv, sources)?;
    let file = sources.files.len().saturating_sub(1) as u32;
    let whole = Span { file, start: 0, end: 1 };
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("input");
    let (text, agents) = to_scn(&recorded, scenario, name, &mut warnings, whole)?;
    Ok(Imported { text, recorded, warnings, agents })
}

/// The scenario name for an output file: its stem as an identifier.
pub fn scenario_name(out: &Path) -> String {
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("imported");
    let s: String = stem.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    if s.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') { s } else { format!("s_{s}") }
}

/// The reference the lossless test compares with: for each recorded frame, the ego pose and the
/// ego-frame boxes computed straight from the converted input boxes (no `.scn` involved), in the
/// order the imported scene declares them (the rasteriser's draw order).
pub fn reference_frames(imp: &Imported) -> Vec<(Pose, Vec<EgoBox>)> {
    let order: BTreeMap<(&str, usize), usize> = imp
        .agents
        .iter()
        .enumerate()
        .flat_map(|(i, (_, tr, a, b))| (*a..=*b).map(move |f| ((tr.as_str(), f), i)))
        .collect();
    imp.recorded
        .frames
        .iter()
        .enumerate()
        .map(|(n, f)| {
            let mut bs: Vec<(usize, &RecBox)> =
                f.boxes.iter().map(|b| (order.get(&(b.track.as_str(), n)).copied().unwrap_or(usize::MAX), b)).collect();
            bs.sort_by_key(|(i, _)| *i);
            let states = bs.iter().map(|(i, b)| AgentState {
                track: (*i + 1) as u32,
                name: imp.agents.get(*i).map(|a| a.0.as_str()).unwrap_or(""),
                kind: b.kind,
                class: b.class,
                size: b.size,
                pose: b.pose,
            });
            (f.ego, to_ego(f.ego, states.collect::<Vec<_>>()))
        })
        .collect()
}
