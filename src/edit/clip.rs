//! Edits on a compiled clip directory (`OUT/<scenario>/<ego>/`).
//!
//! The boxes come from `boxes.json`, the static layers from the clip's own `bev/*.npz`; the scene
//! is re-derived from the manifest's input (same bytes, same seed) only for what the later stages
//! need and the clip does not store: the ego's world pose per frame and the procedural background
//! of the occupancy. Re-rasterising unedited boxes reproduces every BEV exactly (a test).

use super::{Edit, kind_info, no_overlap, validate_box};
use crate::backend::grounded::Grounded;
use crate::backend::{Background, Mode};
use crate::check::scenario::Class;
use crate::compile::{OccBackend, Options, Render, Stage, clip_seed, render_clip};
use crate::diag::{Diagnostic, did_you_mean};
use crate::lidar::Rig;
use crate::output::{FrameBoxes, Manifest, bev_frame_path, read_boxes_json, read_npz};
use crate::place::Pose;
use crate::raster::layout::{HALF_EXTENT_M, box_reaches_patch};
use crate::raster::{Bev, Rasterizer, keep_static};
use crate::road::Map;
use crate::view::{EgoBox, EgoFrame};
use crate::visibility::CameraRig;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What `rocc edit` on a clip is told besides the edits.
#[derive(Clone, Debug, Default)]
pub struct ClipEdit {
    /// The scenario the clip was compiled from, when not where the manifest says.
    pub scenario: Option<PathBuf>,
    /// `--frames`: the frames to edit (default: every frame of the clip).
    pub frames: Option<String>,
    /// `--rig`, needed only when the clip was compiled with a rig other than the bundled one.
    pub rig: Option<Rig>,
    /// `--weights`: for a clip of the learned backend, its weights when not where the manifest
    /// says (they must be the same weights: the hash in the backend name is checked).
    pub weights: Option<PathBuf>,
    /// `--grounded-config`: the model config, when not the manifest's (or, with `--weights`, the
    /// `.ron` beside them).
    pub grounded_config: Option<PathBuf>,
}

fn clip_err(dir: &Path, m: String, help: &str) -> Vec<Diagnostic> {
    vec![Diagnostic::error("E0712", format!("clip `{}`: {m}", dir.display())).help(help.to_string())]
}

/// A compiled BEV with its agent, aux and structure layers redrawn from `boxes` and its static
/// and divider layers kept as they are.
pub fn rerasterize(old: &Bev, boxes: &[EgoBox], raster: &mut Rasterizer, out: &mut Bev) {
    // The map is empty: only the boxes are drawn; the old BEV supplies every map layer.
    let ego = Pose { x: 0.0, y: 0.0, yaw: 0.0 };
    raster.rasterize_into(&Map::default(), ego, boxes, out);
    keep_static(old, out);
}

/// Apply `edits` to every selected frame's boxes, validating each in every frame.
///
/// Positions and displacements are in the ego frame of `selected[0]` (the reference frame) and
/// stand still in the world: `ego_pose(f)` gives the ego's world pose at frame `f`, through which
/// an inserted box and a move are carried into each frame's own ego frame. `bev_of` gives each
/// frame's compiled BEV (for the surface rule). A box whose footprint cannot reach a frame's grid
/// is left out of that frame, as the compiler leaves such boxes out.
pub fn apply_edits(
    frames: &mut [FrameBoxes],
    selected: &[usize],
    edits: &[Edit],
    bev_of: &dyn Fn(usize) -> Result<Bev, Diagnostic>,
    ego_pose: &dyn Fn(usize) -> Pose,
    ego_size: [f64; 3],
) -> Result<(), Vec<Diagnostic>> {
    let Some(&reference) = selected.first() else { return Ok(()) };
    let ref_pose = ego_pose(reference);
    // The reference ego frame -> world.
    let to_world = |x: f64, y: f64, yaw: f64| {
        let (s, c) = ref_pose.yaw.sin_cos();
        Pose { x: ref_pose.x + c * x - s * y, y: ref_pose.y + s * x + c * y, yaw: ref_pose.yaw + yaw }
    };
    let mut next_track = frames.iter().flat_map(|f| f.boxes.iter().map(|b| b.track + 1)).max().unwrap_or(0);
    let mut names: Vec<String> = {
        let mut n: Vec<String> = frames.iter().flat_map(|f| f.boxes.iter().map(|b| b.agent.clone())).collect();
        n.sort();
        n.dedup();
        n
    };
    let in_ref = |what: &str| {
        Diagnostic::error(
            "E0710",
            format!("{what}: the position is outside the 100 m BEV of frame {reference}, the frame it is given in"),
        )
        .help(format!(
            "coordinates are metres in the ego frame of frame {reference} (x forward, y left), within -50..50"
        ))
    };
    for e in edits {
        let what = e.describe();
        match e {
            Edit::Insert { kind, x, y, yaw } => {
                let k = kind_info(kind).map_err(|d| vec![d])?;
                if x.abs() >= HALF_EXTENT_M || y.abs() >= HALF_EXTENT_M {
                    return Err(vec![in_ref(&what)]);
                }
                let mut idx = 1;
                let name = loop {
                    let n = format!("inserted_{kind}_{idx}");
                    if !names.contains(&n) {
                        break n;
                    }
                    idx += 1;
                };
                names.push(name.clone());
                let world = to_world(*x, *y, *yaw);
                let template = EgoBox {
                    agent: name,
                    kind: kind.clone(),
                    class: k.class,
                    track: next_track,
                    x: 0.0,
                    y: 0.0,
                    z: k.size[2] / 2.0,
                    l: k.size[0],
                    w: k.size[1],
                    h: k.size[2],
                    yaw: 0.0,
                };
                next_track += 1;
                for f in frames.iter_mut().filter(|f| selected.contains(&f.frame)) {
                    let p = EgoFrame::new(ego_pose(f.frame)).pose(world);
                    let b = EgoBox { x: p.x, y: p.y, yaw: p.yaw, ..template.clone() };
                    if !box_reaches_patch(b.x, b.y, b.l, b.w) {
                        continue;
                    }
                    validate_in_frame(&bev_of(f.frame).map_err(|d| vec![d])?, &b, &f.boxes, ego_size, f.frame, &what)
                        .map_err(|d| vec![d])?;
                    f.boxes.push(b);
                }
            }
            Edit::Delete { agent } | Edit::Move { agent, .. } => {
                let mut found = false;
                // The displacement in world axes.
                let shift = match e {
                    Edit::Move { dx, dy, .. } => {
                        let o = to_world(0.0, 0.0, 0.0);
                        let t = to_world(*dx, *dy, 0.0);
                        Some((t.x - o.x, t.y - o.y))
                    }
                    _ => None,
                };
                for f in frames.iter_mut().filter(|f| selected.contains(&f.frame)) {
                    let Some(i) = f.boxes.iter().position(|b| &b.agent == agent) else { continue };
                    found = true;
                    let Some((wx, wy)) = shift else {
                        f.boxes.remove(i);
                        continue;
                    };
                    // World axes -> this frame's ego axes (a rotation by minus the ego's yaw).
                    let (s, c) = ego_pose(f.frame).yaw.sin_cos();
                    let mut b = f.boxes[i].clone();
                    b.x += c * wx + s * wy;
                    b.y += -s * wx + c * wy;
                    if !box_reaches_patch(b.x, b.y, b.l, b.w) {
                        f.boxes.remove(i);
                        continue;
                    }
                    if b.class != Class::Structure {
                        validate_in_frame(
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

/// `validate_box`, except that a box whose centre lies off this frame's grid (its footprint
/// still reaches it) is checked for overlap only: the BEV does not show the surface under it.
fn validate_in_frame(
    bev: &Bev,
    b: &EgoBox,
    others: &[EgoBox],
    ego_size: [f64; 3],
    frame: usize,
    what: &str,
) -> Result<(), Diagnostic> {
    if b.x.abs() < HALF_EXTENT_M && b.y.abs() < HALF_EXTENT_M {
        return validate_box(bev, b, others, ego_size, frame, what);
    }
    no_overlap(b, others, ego_size, frame, what)
}

/// The learned backend a clip was compiled with, loaded again from the files its manifest
/// records (or `--weights` / `--grounded-config`), and checked to be the same weights.
fn grounded_backend(dir: &Path, manifest: &Manifest, o: &ClipEdit) -> Result<Grounded, Vec<Diagnostic>> {
    let (weights, config) = match (&o.weights, &manifest.weights) {
        (Some(w), _) => (w.clone(), o.grounded_config.clone()),
        (None, Some(w)) => (
            PathBuf::from(w),
            o.grounded_config.clone().or_else(|| manifest.grounded_config.as_ref().map(PathBuf::from)),
        ),
        (None, None) => {
            return Err(clip_err(
                dir,
                format!(
                    "its occupancy comes from `{}`, but manifest.json does not record the weights",
                    manifest.backend
                ),
                "pass the weights it was compiled with: `--weights FILE` (and `--grounded-config FILE` if the `.ron` \
                 is not beside them)",
            ));
        }
    };
    if !weights.is_file() {
        return Err(vec![
            Diagnostic::error(
                "E0901",
                format!(
                    "clip `{}` was compiled with the learned backend, and its weights file `{}` does not exist",
                    dir.display(),
                    weights.display()
                ),
            )
            .help("restore that file, or pass the same weights with `--weights FILE` (rocc edit reruns the model)"),
        ]);
    }
    let g = Grounded::load(&weights, config.as_deref()).map_err(|d| vec![d])?;
    let name = crate::backend::OccupancyBackend::name(&g);
    if name != manifest.backend {
        return Err(clip_err(
            dir,
            format!("it was compiled with `{}`, but `{}` loads as `{name}`", manifest.backend, weights.display()),
            "pass the weights (and config) the clip was compiled with; other weights would mix two models in one clip",
        ));
    }
    Ok(g)
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
    if crate::fsio::input_hash(&bytes) != manifest.input_hash {
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
    let ego_pose = |f: usize| front.tracks.poses[ego][f];
    apply_edits(&mut frames, &selected, edits, &bev_of, &ego_pose, ego_size)?;

    let stage = match manifest.stage.as_str() {
        "occ" => Stage::Occ,
        "lidar" => Stage::Lidar,
        _ => Stage::Bev,
    };
    let backend = if manifest.backend.starts_with("grounded") {
        OccBackend::Grounded(Arc::new(grounded_backend(dir, &manifest, o)?))
    } else {
        OccBackend::Procedural
    };
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
    // The masks follow the edited occupancy; only the bundled camera rig can be rebuilt here.
    let visibility = match &manifest.visibility {
        Some(name) if *name != CameraRig::nuplan().name => {
            return Err(clip_err(
                dir,
                format!("its visibility masks were cast with camera rig `{name}`"),
                "recompile the clip with `--visibility --camera-rig FILE` instead of editing it",
            ));
        }
        Some(_) => Some(CameraRig::nuplan()),
        None => None,
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
        backend,
        // Edited boxes have no tracks to take a velocity from.
        flow: false,
        visibility,
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
    if let OccBackend::Grounded(g) = &opts.backend
        && let Some((w, c)) = g.files()
    {
        m.weights = Some(w.display().to_string());
        m.grounded_config = Some(c.display().to_string());
    }
    m.files.clear();
    m.timings.clear();
    // The history says which frame the coordinates were given in and which frames changed.
    let scope = match (&o.frames, selected.first()) {
        (Some(spec), Some(r)) => format!(" (ego frame of frame {r}; frames {spec})"),
        (None, Some(r)) => format!(" (ego frame of frame {r})"),
        _ => String::new(),
    };
    m.edits.extend(edits.iter().map(|e| format!("{}{scope}", e.describe())));
    let render = Render {
        frames: &clip_frames,
        rate: front.tracks.rate,
        background: &background,
        seed: clip_seed(&front, ego),
        manifest: m,
        source: &source,
        world: Some(crate::compile::ClipWorld {
            scenario: &front.concrete.name,
            tracks: &front.tracks,
            map: &front.map,
            ego,
            present: &|i, f| front.present(i, f),
        }),
        velocity: None,
    };
    let report = render_clip(&render, &opts, dir, &|| {}).map_err(|e| {
        vec![
            Diagnostic::error("E0401", format!("cannot write `{}`: {e}", dir.display()))
                .help("check permissions and free space"),
        ]
    })?;
    crate::compile::index::refresh_root_of(dir).map_err(|d| vec![d])?;
    Ok(report.manifest)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::layout::CH_DRIVABLE;
    use std::f64::consts::FRAC_PI_2;

    fn drivable() -> Bev {
        let mut b = Bev::zeros();
        b.masks.index_axis_mut(ndarray::Axis(0), CH_DRIVABLE).fill(1);
        b
    }

    fn two_frames() -> Vec<FrameBoxes> {
        (0..2).map(|f| FrameBoxes { frame: f, t: f as f64 / 10.0, boxes: vec![] }).collect()
    }

    /// Frame 0: ego at the world origin facing +x; frame 1: at (10, 0) facing +y (turned left).
    fn pose(f: usize) -> Pose {
        if f == 0 { Pose { x: 0.0, y: 0.0, yaw: 0.0 } } else { Pose { x: 10.0, y: 0.0, yaw: FRAC_PI_2 } }
    }

    fn close(a: (f64, f64, f64), b: (f64, f64, f64)) -> bool {
        (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9 && (a.2 - b.2).abs() < 1e-9
    }

    #[test]
    fn an_insert_stays_fixed_in_the_world_while_the_ego_turns() {
        let mut frames = two_frames();
        let bev = |_| Ok(drivable());
        let ins = Edit::Insert { kind: "traffic_cone".into(), x: 20.0, y: 5.0, yaw: 0.0 };
        apply_edits(&mut frames, &[0, 1], &[ins], &bev, &pose, [4.5, 1.8, 1.5]).unwrap();
        let at = |frames: &[FrameBoxes], f: usize| {
            let b = &frames[f].boxes[0];
            (b.x, b.y, b.yaw)
        };
        let b = |f: usize| at(&frames, f);
        // World (20, 5) yaw 0. Frame 1: d = (10, 5) rotated by -90 deg = (5, -10); yaw -90 deg.
        assert!(close(b(0), (20.0, 5.0, 0.0)), "{:?}", b(0));
        assert!(close(b(1), (5.0, -10.0, -FRAC_PI_2)), "{:?}", b(1));

        // A world-fixed move: +2 m along frame 0's x (world +x) is -2 m along frame 1's y.
        let mv = Edit::Move { agent: "inserted_traffic_cone_1".into(), dx: 2.0, dy: 0.0 };
        apply_edits(&mut frames, &[0, 1], &[mv], &bev, &pose, [4.5, 1.8, 1.5]).unwrap();
        let b = |f: usize| at(&frames, f);
        assert!(close(b(0), (22.0, 5.0, 0.0)), "{:?}", b(0));
        assert!(close(b(1), (5.0, -12.0, -FRAC_PI_2)), "{:?}", b(1));

        // Given with `--frames 1..2`, the coordinates are in frame 1's ego frame.
        let mut frames = two_frames();
        let ins = Edit::Insert { kind: "traffic_cone".into(), x: 5.0, y: -10.0, yaw: 0.0 };
        apply_edits(&mut frames, &[1], &[ins], &bev, &pose, [4.5, 1.8, 1.5]).unwrap();
        assert!(frames[0].boxes.is_empty());
        let b = &frames[1].boxes[0];
        assert!(close((b.x, b.y, b.yaw), (5.0, -10.0, 0.0)));
    }

    #[test]
    fn every_frame_is_validated_and_the_failing_frame_is_named() {
        // Valid surface in frame 0, none in frame 1: a vehicle is refused there.
        let bev = |f: usize| Ok(if f == 0 { drivable() } else { Bev::zeros() });
        let ins = Edit::Insert { kind: "sedan".into(), x: 20.0, y: 5.0, yaw: 0.0 };
        let e = apply_edits(&mut two_frames(), &[0, 1], &[ins], &bev, &pose, [4.5, 1.8, 1.5]).unwrap_err();
        assert_eq!(e[0].code, "E0710");
        assert!(e[0].message.contains("frame 1"), "{}", e[0].message);
        // Overlap in frame 1 only: the cone lands on the ego, which drove to (10, 0).
        let bev = |_| Ok(drivable());
        let ins = Edit::Insert { kind: "traffic_cone".into(), x: 10.0, y: 0.0, yaw: 0.0 };
        let e = apply_edits(&mut two_frames(), &[0, 1], &[ins], &bev, &pose, [4.5, 1.8, 1.5]).unwrap_err();
        assert_eq!(e[0].code, "E0711");
        assert!(e[0].message.contains("frame 1") && e[0].message.contains("the ego"), "{}", e[0].message);
        // Off the reference frame's grid: refused before any frame is looked at.
        let ins = Edit::Insert { kind: "traffic_cone".into(), x: 60.0, y: 0.0, yaw: 0.0 };
        assert_eq!(
            apply_edits(&mut two_frames(), &[0, 1], &[ins], &bev, &pose, [4.5, 1.8, 1.5]).unwrap_err()[0].code,
            "E0710"
        );
    }

    #[test]
    fn a_box_out_of_reach_of_a_frame_is_left_out_of_it() {
        // World (-45, 0): on frame 0's grid, 55 m behind the ego in frame 1 and out of reach.
        let bev = |_| Ok(drivable());
        let poses = |f: usize| Pose { x: 10.0 * f as f64, y: 0.0, yaw: 0.0 };
        let mut frames = two_frames();
        let ins = Edit::Insert { kind: "traffic_cone".into(), x: -45.0, y: 0.0, yaw: 0.0 };
        apply_edits(&mut frames, &[0, 1], &[ins], &bev, &poses, [4.5, 1.8, 1.5]).unwrap();
        assert_eq!((frames[0].boxes.len(), frames[1].boxes.len()), (1, 0));
        // Centre off the grid but footprint on it (a 4.6 m car 50.5 m behind): kept, surface unchecked.
        let mut frames = two_frames();
        let ins = Edit::Insert { kind: "sedan".into(), x: -40.5, y: 0.0, yaw: 0.0 };
        apply_edits(&mut frames, &[0, 1], &[ins], &bev, &poses, [4.5, 1.8, 1.5]).unwrap();
        assert!((frames[1].boxes[0].x + 50.5).abs() < 1e-9);
    }
}
