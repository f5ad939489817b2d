//! `rocc compile`: scenario files (or directories of them) to one output directory per
//! (scenario, ego), spread over the thread pool; a failed input is reported and the batch goes on.

use super::{Failure, show};
use clap::ValueEnum;
use rocc::backend::grounded::DeviceKind;
use rocc::backend::grounded::attention::Precision;
use rocc::compile::{GroundedRun, OccBackend, Options, Stage, StaticBev, batch};
use rocc::diag::Diagnostic;
use rocc::lidar::Rig;
use rocc::visibility::CameraRig;
use std::path::PathBuf;
use std::str::FromStr;

#[derive(clap::Args)]
pub struct Args {
    /// `.scn` files and directories (searched recursively for files that declare a scenario).
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// Output root: one directory per (scenario, ego) below it.
    #[arg(short, long)]
    out: PathBuf,
    /// Stop after this stage.
    #[arg(long, value_enum, default_value = "lidar")]
    stage: StageArg,
    /// Frames to write: `0`, `0..10`, `0..=9`, `50..`, comma-separated (default: all).
    #[arg(long)]
    frames: Option<String>,
    /// Compile the clip of this agent (repeatable); default: the scenario's `egos`.
    #[arg(long)]
    ego: Vec<String>,
    /// Override the scenario's seed.
    #[arg(long)]
    seed: Option<u64>,
    /// Occupancy shapes: `surface` shells (like LiDAR-built ground truth) or `solid` bodies.
    #[arg(long, value_enum, default_value = "surface")]
    occ_mode: OccMode,
    /// LiDAR rig description (RON); default: the bundled nuPlan rig (`rigs/nuplan.ron`).
    #[arg(long)]
    rig: Option<PathBuf>,
    /// Azimuth step in degrees for every sensor of the rig (overrides the rig file).
    #[arg(long)]
    lidar_resolution: Option<f64>,
    /// This job's share of the inputs: K of N (1-based), for job arrays.
    #[arg(long)]
    shard: Option<String>,
    /// Skip the GIFs and the contact sheet (faster at corpus scale).
    #[arg(long)]
    no_previews: bool,
    /// Recompile clips whose manifest says they are already complete.
    #[arg(long)]
    force: bool,
    /// No progress bar or per-clip lines.
    #[arg(short, long)]
    quiet: bool,
    /// A recorded BEV (`.npz`, or a directory of per-frame `NNNNNN.npz`) whose static and
    /// divider layers replace the map's, e.g. for a scene from `rocc import boxes`.
    #[arg(long)]
    static_bev: Option<PathBuf>,
    /// Occupancy backend.
    #[arg(long, value_enum, default_value = "procedural")]
    backend: BackendArg,
    /// `--backend grounded`: generator weights (`.bpk` from `rocc train`, or `.safetensors`).
    #[arg(long)]
    weights: Option<PathBuf>,
    /// `--backend grounded`: the model config (default: the `.ron` beside the weights).
    #[arg(long)]
    grounded_config: Option<PathBuf>,
    /// `--backend grounded`: where the model runs: cpu, wgpu (`--features wgpu`) or cuda
    /// (`--features cuda`).
    #[arg(long, value_parser = DeviceKind::from_str)]
    device: Option<DeviceKind>,
    /// `--backend grounded`: frames per forward pass (default 1 on the cpu, 4 on a GPU).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=256))]
    grounded_batch: Option<u64>,
    /// `--backend grounded`: full (f32 throughout) or mixed (the decoder transformer's products
    /// in f16, for GPUs with tensor cores; docs/learned-backend.md).
    #[arg(long, default_value = "full", value_parser = Precision::from_str)]
    precision: Precision,
    /// Also write `flow/NNNNNN.npz`: each moving agent's velocity on its voxels (docs/output.md).
    #[arg(long)]
    flow: bool,
    /// Also write Occ3D's `gts/NNNNNN/labels.npz`: the labels with LiDAR and camera visibility
    /// masks (docs/output.md).
    #[arg(long)]
    visibility: bool,
    /// `--visibility`: the camera rig (RON; default the bundled nominal nuPlan rig,
    /// rigs/nuplan_cameras.ron).
    #[arg(long)]
    camera_rig: Option<PathBuf>,
}

#[derive(Clone, Copy, ValueEnum)]
enum StageArg {
    Bev,
    Occ,
    Lidar,
}

#[derive(Clone, Copy, ValueEnum)]
enum OccMode {
    Surface,
    Solid,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
enum BackendArg {
    /// Shapes drawn from each box (no weights).
    Procedural,
    /// The learned entity-grounded model (needs `--weights`).
    Grounded,
}

pub fn run(a: Args) -> Result<(), Failure> {
    if a.flow && matches!(a.stage, StageArg::Bev) {
        return Err(Diagnostic::error("E0430", "`--flow` needs the occupancy, which `--stage bev` leaves out")
            .help("drop `--stage bev` or use `--stage occ` (see `rocc explain E0430`)")
            .into());
    }
    if a.visibility && matches!(a.stage, StageArg::Bev) {
        return Err(Diagnostic::error("E0432", "`--visibility` needs the occupancy, which `--stage bev` leaves out")
            .help("drop `--stage bev` or use `--stage occ` (see `rocc explain E0432`)")
            .into());
    }
    if a.camera_rig.is_some() && !a.visibility {
        return Err(Diagnostic::error("E0433", "`--camera-rig` is only used by `--visibility`")
            .help("add `--visibility`, or drop `--camera-rig` (see `rocc explain E0433`)")
            .into());
    }
    let visibility = a.visibility.then(|| CameraRig::load(a.camera_rig.as_deref())).transpose()?;
    let opts = Options {
        stage: match a.stage {
            StageArg::Bev => Stage::Bev,
            StageArg::Occ => Stage::Occ,
            StageArg::Lidar => Stage::Lidar,
        },
        frames: a.frames,
        egos: a.ego,
        seed: a.seed,
        mode: match a.occ_mode {
            OccMode::Surface => rocc::backend::Mode::Surface,
            OccMode::Solid => rocc::backend::Mode::Solid,
        },
        rig: Rig::load(a.rig.as_deref(), a.lidar_resolution)?,
        previews: !a.no_previews,
        force: a.force,
        static_bev: a.static_bev.as_deref().map(StaticBev::load).transpose()?,
        backend: OccBackend::select_on(
            a.backend == BackendArg::Grounded,
            a.weights.as_deref(),
            a.grounded_config.as_deref(),
            &GroundedRun {
                device: a.device,
                batch: a.grounded_batch.map(|b| b as usize),
                mixed: matches!(a.precision, Precision::Mixed(_)),
            },
        )?,
        flow: a.flow,
        visibility,
    };
    let shard = a.shard.as_deref().map(batch::parse_shard).transpose().map_err(|m| {
        Diagnostic::error("E0402", format!("--shard {m}"))
            .help("K/N with 1 <= K <= N, e.g. `--shard 3/16` (see `rocc explain E0402`)")
    })?;
    let all = batch::collect_inputs(&a.inputs)
        .map_err(|m| Diagnostic::error("E0002", m).help("pass `.scn` files or directories that hold them"))?;
    // Names are checked for duplicates over all inputs, not only this shard's.
    let files = batch::shard(all.clone(), shard);
    let started = std::time::Instant::now();
    let report = batch::run_shard(&all, shard, &a.out, &opts, a.quiet);
    for f in &report.failures {
        eprintln!("failed: {}", f.input.display());
        show(&f.diags, &f.sources);
    }
    let frames: usize = report.clips.iter().filter(|c| !c.resumed).map(|c| c.frames).sum();
    let kept = report.clips.iter().filter(|c| c.resumed).count();
    let secs = started.elapsed().as_secs_f64();
    if !a.quiet {
        eprintln!(
            "{} clip(s) from {} file(s): {frames} frames written in {secs:.1} s ({:.1} frames/s){}; {} failed",
            report.clips.len(),
            files.len(),
            frames as f64 / secs.max(1e-9),
            if kept > 0 { format!(", {kept} complete clip(s) kept") } else { String::new() },
            report.failures.len()
        );
    }
    if report.failures.is_empty() { Ok(()) } else { Err(Failure::shown()) }
}
