//! Edits on a compiled clip directory (`OUT/<scenario>/<ego>/`).
//!
//! The boxes come from `boxes.json`, the static layers from the clip's own `bev/*.npz`; the scene
//! is re-derived from the manifest's input (same bytes, same seed) only for what the later stages
//! need and the clip does not store: the ego's world pose per frame and the procedural background
//! of the occupancy. Re-rasterising unedited boxes reproduces every BEV exactly (a test).

use super::{Edit, kind_info, validate_box};
use crate::backend::{Background, Mode};
use crate::check::scenario::Class;
use crate::compile::{Options, Render, Stage, clip_seed, render_clip};
use crate::diag::{Diagnostic, did_you_mean};
use crate::lidar::Rig;
use crate::output::{FrameBoxes, Manifest, bev_frame_path, read_npz};
use crate::place::Pose;
use crate::raster::{Bev, Rasterizer, keep_static};
use crate::road::Map;
use crate::view::EgoBox;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What `rocc edit` on a clip is told besides the edits.
#[derive(Clone, Debug, Default)]
pub struct ClipEdit {
    /// The scenario the clip was compiled from, when not where the manifest says.
    pub scenario: Option<PathBuf>,
    /// `--frames`: the frames to edit (default: every frame of the clip).
    pub frames: Option<String>,
    /// `--rig`, needed only when the clip was compiled with a rig other than the bundled one.
    pub rig: Option<Rig>,
}

fn clip_err(dir: &Path, m: String, help: &str) -> Vec<Diagnostic> {
    vec![Diagnostic::error("E0712", format!("clip `{}`: {m}", dir.display())).help(help.to_string())]
}

/// Read `boxes.json` back into frames of ego-frame boxes.
pub fn read_boxes_json(path: &Path) -> Result<Vec<FrameBoxes>, String> {
    #[derive(serde::Deserialize)]
    struct B {
        agent: String,
        kind: String,
        class_name: String,
        track: u32,
        x: f64,
        y: f64,
        z: f64,
        l: f64,
        w: f64,
        h: f64,
        yaw: f64,
    }
    #[derive(serde::Deserialize)]
    struct F {
        frame: usize,
        t: f64,
        boxes: Vec<B>,
    }
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    let frames: Vec<F> = serde_json::from_str(&text).map_err(|e| format!("`{}`: {e}", path.display()))?;
    frames
        .into_iter()
        .map(|f| {
            let boxes = f
                .boxes
                .into_iter()
                .map(|b| {
                    let class = Class::ALL
                        .iter()
                        .find(|(n, _)| *n == b.class_name)
                        .map(|(_, c)| *c)
                        .ok_or_else(|| format!("unknown class `{}` in `{}`", b.class_name, path.display()))?;
                    Ok(EgoBox {
                        agent: b.agent,
                        kind: b.kind,
                        class,
                        track: b.track,
                        x: b.x,
                        y: b.y,
                        z: b.z,
                        l: b.l,
                        w: b.w,
                        h: b.h,
                        yaw: b.yaw,
                    })
                })
                .collect::<Result<Vec<_>, String>>()?;
            Ok(FrameBoxes { frame: f.frame, t: f.t, boxes })
        })
        .collect()
}

/// A compiled BEV with its agent, aux and structure layers redrawn from `boxes` and its static
/// and divider layers kept as they are.
pub fn rerasterize(old: &Bev, boxes: &[EgoBox], raster: &mut Rasterizer, out: &mut Bev) {
    // The map is empty: only the boxes are drawn; the old BEV supplies every map layer.
    let ego = Pose { x: 0.0, y: 0.0, yaw: 0.0 };
    raster.rasterize_into(&Map::default(), ego, boxes, out);
    keep_static(old, out);
}

/// Apply `edits` to every selected frame's boxes, validating each; `bevs` gives each frame's
/// compiled BEV (for the surface rule). Returns the edited frames.
pub fn apply_edits(
    frames: &mut [FrameBoxes],
    selected: &[usize],
    edits: &[Edit],
    bev_of: &dyn Fn(usize) -> Result<Bev, Diagnostic>,
    ego_size: [f64; 3],
) -> Result<(), Vec<Diagnostic>> {
    let mut next_track = frames.iter().flat_map(|f| f.boxes.iter().map(|b| b.track + 1)).max().unwrap_or(0);
    let mut names: Vec<String> = {
        let mut n: Vec<String> = frames.iter().flat_map(|f| f.boxes.iter().map(|b| b.agent.clone())).collect();
        n.sort();
        n.dedup();
        n
    };
    for e in edits {
        let what = e.describe();
        match e {
            Edit::Insert { kind, x, y, yaw } => {
                let k = kind_info(kind).map_err(|d| vec![d])?;
                let mut idx = 1;
                let name = loop {
                    let n = format!("inserted_{kind}_{idx}");
                    if !names.contains(&n) {
                        break n;
                    }
                    idx += 1;
                };
                names.push(name.clone());
                let b = EgoBox {
                    agent: name,
                    kind: kind.clone(),
                    class: k.class,
                    track: next_track,
                    x: *x,
                    y: *y,
                    z: k.size[2] / 2.0,
                    l: k.size[0],
                    w: k.size[1],
                    h: k.size[2],
                    yaw: crate::geom::wrap_angle(*yaw),
                };
                next_track += 1;
                for f in frames.iter_mut().filter(|f| selected.contains(&f.frame)) {
                    validate_box(&bev_of(f.frame).map_err(|d| vec![d])?, &b, &f.boxes, ego_size, f.frame, &what)
                        .map_err(|d| vec![d])?;
                    f.boxes.push(b.clone());
                }
            }
            Edit::Delete { agent } | Edit::Move { agent, .. } => {
                let mut found = false;
                for f in frames.iter_mut().filter(|f| selected.contains(&f.frame)) {
                    let Some(i) = f.boxes.iter().position(|b| &b.agent == agent) else { continue };
                    found = true;
                    if let Edit::Move { dx, dy, .. } = e {
                        let mut b = f.boxes[i].clone();
                        b.x += dx;
                        b.y += dy;
                        if b.class != Class::Structure {
                            validate_box(
                                &bev_of(f.frame).map_err(|d| vec![d])?,
                                &b,
                                &f.boxes,
                                ego_size,
                                f.frame,
                                &what,
                            )
                            .map_err(|d| vec![d])?;
                        }
                        f.boxes[i] = b;
                    } else {
                        f.boxes.remove(i);
                    }
                }
                if !found {
                    let cands: Vec<&str> = names.iter().map(String::as_str).collect();
                    return Err(vec![
                        Diagnostic::error("E0709", format!("{what}: no agent `{agent}` in the edited frames"))
                            .help(did_you_mean(agent, &cands, "agent")),
                    ]);
                }
            }
        }
    }
    Ok(())
}

/// Edit a compiled clip in place. Nothing is written unless every edit is valid in every
/// selected frame; then every stage of every frame of the clip is rewritten (atomically per file).
pub fn edit_clip(dir: &Path, edits: &[Edit], o: &ClipEdit) -> Result<Manifest, Vec<Diagnostic>> {
    let mtext = std::fs::read_to_string(dir.join("manifest.json")).map_err(|e| {
        clip_err(
            dir,
            format!("no readable manifest.json ({e})"),
            "pass a directory written by `rocc compile`: OUT/<scenario>/<ego>",
        )
    })?;
    let manifest: Manifest = serde_json::from_str(&mtext)
        .map_err(|e| clip_err(dir, format!("manifest.json: {e}"), "recompile the clip with `rocc compile`"))?;
    let input = o.scenario.clone().unwrap_or_else(|| PathBuf::from(&manifest.input));
    let bytes = std::fs::read(&input).map_err(|e| {
        clip_err(
            dir,
            format!("cannot read its scenario `{}` ({e})", input.display()),
            "pass `--scenario FILE` when the clip was compiled elsewhere",
        )
    })?;
    if crate::output::input_hash(&bytes) != manifest.input_hash {
        return Err(clip_err(
            dir,
            format!("`{}` changed since the clip was compiled", input.display()),
            "recompile the clip first, or pass `--scenario` with the exact file it was compiled from",
        ));
    }
    let mut sources = crate::source::SourceMap::default();
    let scen = crate::check::check_path(&input, &mut sources)?;
    let front = crate::compile::front(scen, Some(manifest.seed))?;
    let ego = front.egos(std::slice::from_ref(&manifest.ego)).map_err(|d| vec![d])?[0];
    let ego_size = front.tracks.agents[ego].size;
    let mut frames = read_boxes_json(&dir.join("boxes.json"))
        .map_err(|m| clip_err(dir, m, "recompile the clip with `rocc compile`"))?;
    let clip_frames: Vec<usize> = frames.iter().map(|f| f.frame).collect();
    if clip_frames != manifest.frames {
        return Err(clip_err(dir, "boxes.json and manifest.json list different frames".into(), "recompile the clip"));
    }
    let selected = match &o.frames {
        None => clip_frames.clone(),
        Some(spec) => {
            let all = crate::compile::parse_frames(Some(spec), front.tracks.frames).map_err(|d| vec![d])?;
            let selected: Vec<usize> = all.into_iter().filter(|f| clip_frames.contains(f)).collect();
            if selected.is_empty() {
                let shown = match (clip_frames.first(), clip_frames.last()) {
                    (Some(a), Some(b)) if a != b => format!("{} frames, {a} to {b}", clip_frames.len()),
                    (Some(a), _) => format!("only frame {a}"),
                    _ => "no frames".to_string(),
                };
                return Err(vec![
                    Diagnostic::error(
                        "E0718",
                        format!("`--frames {spec}` selects no frame compiled into `{}` ({shown})", dir.display()),
                    )
                    .help("pick frames the clip holds (see manifest.json `frames`), or recompile it with those frames"),
                ]);
            }
            selected
        }
    };
    let bev_of = |f: usize| -> Result<Bev, Diagnostic> {
        let p = bev_frame_path(dir, f);
        read_npz(&p).map_err(|e| {
            Diagnostic::error("E0712", format!("cannot read `{}`: {e}", p.display())).help("recompile the clip")
        })
    };
    apply_edits(&mut frames, &selected, edits, &bev_of, ego_size)?;

    let stage = match manifest.stage.as_str() {
        "occ" => Stage::Occ,
        "lidar" => Stage::Lidar,
        _ => Stage::Bev,
    };
    if manifest.backend.starts_with("grounded") {
        return Err(clip_err(
            dir,
            format!(
                "its occupancy comes from the learned backend `{}`, which `rocc edit` cannot rerun",
                manifest.backend
            ),
            "edit the scenario instead (`rocc edit FILE.scn ... -o edited.scn`) and compile it with `--backend grounded --weights W`",
        ));
    }
    let mode = if manifest.backend.ends_with("solid") { Mode::Solid } else { Mode::Surface };
    let rig = match (&o.rig, &manifest.rig) {
        (Some(r), _) => r.clone(),
        (None, Some(name)) if *name != Rig::nuplan().name => {
            return Err(clip_err(
                dir,
                format!("it was compiled with rig `{name}`"),
                "pass the same rig with `--rig FILE` so the LiDAR is re-rendered as before",
            ));
        }
        _ => Rig::nuplan(),
    };
    let previews = manifest.files.iter().any(|f| f.path.starts_with("preview/"));
    let opts = Options {
        stage,
        frames: None,
        egos: vec![],
        seed: None,
        mode,
        rig,
        previews,
        force: true,
        static_bev: None,
        backend: Default::default(),
    };
    let background =
        if stage >= Stage::Occ { Background::generate(&front.map, front.concrete.seed) } else { Background::none() };
    let by_frame: BTreeMap<usize, &FrameBoxes> = frames.iter().map(|f| (f.frame, f)).collect();
    let source = |f: usize, raster: &mut Rasterizer, bev: &mut Bev| -> std::io::Result<(Pose, Vec<EgoBox>)> {
        let old = read_npz(&bev_frame_path(dir, f))?;
        let boxes = by_frame.get(&f).map(|fb| fb.boxes.clone()).unwrap_or_default();
        rerasterize(&old, &boxes, raster, bev);
        Ok((front.tracks.poses[ego][f], boxes))
    };
    let mut m = manifest.clone();
    m.files.clear();
    m.timings.clear();
    m.edits.extend(edits.iter().map(Edit::describe));
    let render = Render {
        frames: &clip_frames,
        rate: front.tracks.rate,
        background: &background,
        seed: clip_seed(&front, ego),
        manifest: m,
        source: &source,
    };
    let report = render_clip(&render, &opts, dir, &|| {}).map_err(|e| {
        vec![
            Diagnostic::error("E0401", format!("cannot write `{}`: {e}", dir.display()))
                .help("check permissions and free space"),
        ]
    })?;
    Ok(report.manifest)
}
