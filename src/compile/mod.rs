//! Compile driver. In: scenario files and `Options`. Out: the SPEC.md output layout, one
//! directory per (scenario, ego): `OUT/<scenario>/<ego>/{manifest.json, boxes.json, bev/, occ/,
//! lidar/, preview/}`.
//!
//! `front` runs the passes that decide the scene (check's output -> sample -> road -> place ->
//! rollout); `rocc check` runs it too, so every error a compile could hit before writing a byte
//! is a check error. `clip::compile_clip` then renders one ego's frames in parallel (view ->
//! raster -> backend -> lidar, each frame independent, every random draw keyed by frame), and
//! `batch::run` spreads files and clips over the rayon pool.

pub mod batch;
mod clip;
pub mod index;
mod static_bev;
mod world;

pub use clip::{
    BoxVelocity, ClipInput, ClipReport, FrameSource, Render, clip_dir, clip_seed, compile_clip, edited_clip,
    frame_boxes, is_door, render_clip,
};
pub use static_bev::StaticBev;
pub use world::ClipWorld;

use crate::backend::Mode;
use crate::check::scenario::Scenario;
use crate::diag::{Diagnostic, did_you_mean};
use crate::lidar::Rig;
use crate::place::{Placed, place};
use crate::road::{self, Map};
use crate::rollout::{Tracks, rollout};
use crate::sample::{Concrete, sample};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// How far `rocc compile` goes. Each stage includes the ones before it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Stage {
    Bev,
    Occ,
    Lidar,
}

impl Stage {
    pub fn name(self) -> &'static str {
        match self {
            Stage::Bev => "bev",
            Stage::Occ => "occ",
            Stage::Lidar => "lidar",
        }
    }
}

/// Everything `rocc compile` can be told, besides its inputs and output directory.
#[derive(Clone, Debug)]
pub struct Options {
    pub stage: Stage,
    /// `--frames` as written; `None` = every frame.
    pub frames: Option<String>,
    /// `--ego` names; empty = the scenario's own `egos`.
    pub egos: Vec<String>,
    /// `--seed`; `None` = the scenario's `seed`.
    pub seed: Option<u64>,
    pub mode: Mode,
    pub rig: Rig,
    pub previews: bool,
    /// Recompile clips whose manifest says they are complete.
    pub force: bool,
    /// A recorded BEV whose static and divider layers replace the map's (`--static-bev`).
    pub static_bev: Option<StaticBev>,
    /// Which occupancy backend runs (`--backend`).
    pub backend: OccBackend,
    /// Per-voxel velocity of moving agents, `flow/NNNNNN.npz` (`--flow`, stage occ and up).
    pub flow: bool,
    /// Occ3D's `gts/NNNNNN/labels.npz` with LiDAR and camera visibility masks, the cameras
    /// from this rig (`--visibility`, `--camera-rig`; stage occ and up).
    pub visibility: Option<crate::visibility::CameraRig>,
}

/// `--backend`: the procedural default (shapes by `mode`), or loaded grounded weights.
#[derive(Clone, Default)]
pub enum OccBackend {
    #[default]
    Procedural,
    Grounded(std::sync::Arc<crate::backend::grounded::Grounded>),
}

impl OccBackend {
    /// The backend `--backend` names: `grounded` loads `weights` (with `config`, by default the
    /// `.ron` beside them); the procedural one takes neither (E0908 if given them).
    pub fn select(grounded: bool, weights: Option<&Path>, config: Option<&Path>) -> Result<OccBackend, Diagnostic> {
        Self::select_on(grounded, weights, config, &GroundedRun::default())
    }

    /// `select` with where and how the learned backend runs (`--device`, `--grounded-batch`;
    /// E0908 when given to the procedural backend).
    pub fn select_on(
        grounded: bool,
        weights: Option<&Path>,
        config: Option<&Path>,
        run: &GroundedRun,
    ) -> Result<OccBackend, Diagnostic> {
        if !grounded && *run != GroundedRun::default() {
            return Err(Diagnostic::error(
                "E0908",
                "`--device`, `--grounded-batch` and `--precision` apply to `--backend grounded` only",
            )
            .help("add `--backend grounded --weights FILE`, or drop them for the procedural backend"));
        }
        match (grounded, weights) {
            (false, None) if config.is_none() => Ok(OccBackend::Procedural),
            (false, _) => Err(Diagnostic::error(
                "E0908",
                "`--weights` and `--grounded-config` apply to `--backend grounded` only",
            )
            .help("add `--backend grounded`, or drop the weights options for the procedural backend")),
            (true, None) => Err(Diagnostic::error("E0901", "`--backend grounded` needs `--weights FILE`")
                .help("train weights with `rocc train generator ...` (docs/learned-backend.md, \"Training\")")),
            (true, Some(w)) => crate::backend::grounded::Grounded::load_on(
                w,
                config,
                run.device.unwrap_or_default(),
                run.batch,
                run.mixed,
            )
            .map(|g| OccBackend::Grounded(std::sync::Arc::new(g))),
        }
    }
}

/// Where the learned backend runs (`--device`) and how many frames one forward pass takes
/// (`--grounded-batch`; `None`: the device's default).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GroundedRun {
    /// `None`: the CPU.
    pub device: Option<crate::backend::grounded::DeviceKind>,
    pub batch: Option<usize>,
    /// `--precision mixed`: the decoder transformer's matrix products in f16.
    pub mixed: bool,
}

impl std::fmt::Debug for OccBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OccBackend::Procedural => write!(f, "Procedural"),
            OccBackend::Grounded(g) => write!(f, "Grounded({})", crate::backend::OccupancyBackend::name(&**g)),
        }
    }
}

impl Options {
    /// The occupancy backend these options select.
    pub fn occ_backend(&self) -> Box<dyn crate::backend::OccupancyBackend + '_> {
        match &self.backend {
            OccBackend::Procedural => Box::new(crate::backend::Procedural::new(self.mode)),
            OccBackend::Grounded(g) => Box::new(&**g),
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Options {
            stage: Stage::Lidar,
            frames: None,
            egos: Vec::new(),
            seed: None,
            mode: Mode::Surface,
            rig: Rig::nuplan(),
            previews: true,
            force: false,
            static_bev: None,
            backend: OccBackend::Procedural,
            flow: false,
            visibility: None,
        }
    }
}

/// A scene decided down to every agent's track: what all of a scenario's clips share.
#[derive(Clone, Debug)]
pub struct Front {
    pub scenario: Scenario,
    pub concrete: Concrete,
    pub map: Map,
    pub placed: Placed,
    pub tracks: Tracks,
}

/// Sample, build the road, place and roll out a checked scenario.
pub fn front(scenario: Scenario, seed: Option<u64>) -> Result<Front, Vec<Diagnostic>> {
    let mut concrete = sample(&scenario, seed.unwrap_or(scenario.seed));
    let map = road::build(&concrete.road);
    crate::place::resolve_keys(&mut concrete, &map)?;
    let placed = place(&concrete, &map)?;
    let tracks = rollout(&concrete, &map, &placed)?;
    Ok(Front { scenario, concrete, map, placed, tracks })
}

impl Front {
    /// Track indices of the clips to compile: `names`, or the scenario's egos when empty.
    pub fn egos(&self, names: &[String]) -> Result<Vec<usize>, Diagnostic> {
        if names.is_empty() {
            return Ok(self.concrete.egos.clone());
        }
        // Declared, non-object agents may carry sensors; their track index is their declaration index.
        let eligible: Vec<&str> =
            self.concrete.agents.iter().filter(|a| !a.is_object).map(|a| a.name.as_str()).collect();
        let mut out = Vec::new();
        for n in names {
            match self.concrete.agents.iter().position(|a| &a.name == n && !a.is_object) {
                Some(i) if !out.contains(&i) => out.push(i),
                Some(_) => {}
                None => {
                    return Err(Diagnostic::error(
                        "E0301",
                        format!("`{n}` is not an agent of scenario `{}` that can be an ego", self.concrete.name),
                    )
                    .help(did_you_mean(n, &eligible, "agent")));
                }
            }
        }
        Ok(out)
    }

    /// Whether track `i` is in the scene at frame `f`. A replayed track exists from its first to
    /// its last keyframe (a recorded object enters and leaves the clip); everything else, and a
    /// track on a trigger (at its first keyframe till then, at its last after), always.
    pub fn present(&self, i: usize, f: usize) -> bool {
        let agent = self.placed.agents.get(i).and_then(|p| p.source).and_then(|s| self.concrete.agents.get(s));
        if agent.and_then(|a| a.goal.as_ref()?.start_when).is_some() {
            return true;
        }
        let keys = agent.and_then(|a| a.track.as_ref());
        let (Some(first), Some(last)) = (keys.and_then(|k| k.first()), keys.and_then(|k| k.last())) else {
            return true;
        };
        let t = f as f64 / self.tracks.rate;
        t >= first.t - crate::rollout::KEY_SNAP_S && t <= last.t + crate::rollout::KEY_SNAP_S
    }

    /// The frame indices `spec` selects (all when `None`), sorted and de-duplicated.
    pub fn frames(&self, spec: Option<&str>) -> Result<Vec<usize>, Diagnostic> {
        parse_frames(spec, self.tracks.frames)
    }
}

/// Parse `--frames`: comma-separated `N`, `A..B`, `A..=B`, `A..`.
pub fn parse_frames(spec: Option<&str>, count: usize) -> Result<Vec<usize>, Diagnostic> {
    let Some(spec) = spec else { return Ok((0..count).collect()) };
    let bad = |why: String| {
        Diagnostic::error("E0302", format!("`--frames {spec}`: {why}"))
            .help(format!("the clip has {count} frames (0..{count}); write e.g. `0`, `0..10`, `0..=9`, `50..`"))
    };
    let num = |s: &str| s.trim().parse::<usize>().map_err(|_| bad(format!("`{}` is not a frame index", s.trim())));
    let mut out = Vec::new();
    for part in spec.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (a, b) = if let Some((a, b)) = part.split_once("..=") {
            (num(a)?, num(b)? + 1)
        } else if let Some((a, b)) = part.split_once("..") {
            (num(a)?, if b.trim().is_empty() { count } else { num(b)? })
        } else {
            let n = num(part)?;
            (n, n + 1)
        };
        if a >= b {
            return Err(bad(format!("`{part}` selects no frame")));
        }
        if b > count {
            return Err(bad(format!("`{part}` goes past the last frame ({})", count.saturating_sub(1))));
        }
        out.extend(a..b);
    }
    if out.is_empty() {
        return Err(bad("selects no frame".to_string()));
    }
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_selections() {
        assert_eq!(parse_frames(None, 3).unwrap(), vec![0, 1, 2]);
        assert_eq!(parse_frames(Some("0,2..4, 8..=9"), 10).unwrap(), vec![0, 2, 3, 8, 9]);
        assert_eq!(parse_frames(Some("7.."), 10).unwrap(), vec![7, 8, 9]);
        assert_eq!(parse_frames(Some("1,1,0"), 10).unwrap(), vec![0, 1]);
        for bad in ["10", "3..3", "x", "0..11", "", "5..2"] {
            let e = parse_frames(Some(bad), 10).unwrap_err();
            assert_eq!(e.code, "E0302", "{bad}");
        }
    }
}
