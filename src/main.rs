//! The `rocc` command line. Each subcommand is a thin shell over one library entry point.

use clap::{Parser, Subcommand, ValueEnum};
use rocc::compile::{Options, Stage, batch};
use rocc::diag::{Diagnostic, codes};
use rocc::source::SourceMap;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "rocc", version, about = "Compile driving-scenario files (.scn) to BEV, occupancy and LiDAR")]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
enum MessageFormat {
    Human,
    Json,
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

#[derive(Clone, Copy, ValueEnum)]
enum ConventionArg {
    Nuscenes,
    Mmdet3d,
    Nuplan,
}

#[derive(Subcommand)]
enum ImportCmd {
    /// Per-frame 3D boxes (JSON) -> a `.scn` whose agents replay their tracks.
    Boxes {
        file: PathBuf,
        #[arg(long, value_enum)]
        convention: ConventionArg,
        #[arg(short, long)]
        out: PathBuf,
        /// A recorded BEV whose map layers the scene borrows (checked here; pass it to `rocc compile` too).
        #[arg(long)]
        static_bev: Option<PathBuf>,
    },
}

#[derive(Subcommand)]
enum EvalCmd {
    /// Per-class occupancy IoU over a set, mIoU_US, fg-mIoU, occ-IoU.
    Occ {
        #[arg(long)]
        pred: PathBuf,
        #[arg(long)]
        gt: PathBuf,
        /// Print JSON instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// LiDAR MMD and JSD between two sets of clouds.
    Lidar {
        #[arg(long)]
        pred: PathBuf,
        #[arg(long)]
        gt: PathBuf,
        /// Keep only points with 3 < range < 50 m.
        #[arg(long)]
        range_filter: bool,
        #[arg(long)]
        json: bool,
    },
    /// The paper's edit protocol (insert / delete / move) on the procedural backend.
    Edits {
        #[arg(long, default_value_t = 100)]
        scenes: usize,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Scenarios to draw scenes from.
        #[arg(long, default_value = "scenarios")]
        scenarios: PathBuf,
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand)]
enum Cmd {
    /// Parse and check scenario files; print diagnostics.
    Check {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// `json`: one JSON object per line (diagnostics, then a summary per clean file).
        #[arg(long, value_enum, default_value = "human")]
        message_format: MessageFormat,
    },
    /// Rewrite files in canonical layout (comments kept).
    Fmt {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Change nothing; list files that would change and exit 1 if any.
        #[arg(long)]
        check: bool,
    },
    /// Compile scenario files (or directories of them) to BEV, occupancy, LiDAR and previews.
    Compile {
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
    },
    /// Turn recorded boxes into a scenario: `rocc import boxes FILE --convention nuscenes -o scene.scn`.
    Import {
        #[command(subcommand)]
        what: ImportCmd,
    },
    /// Edit the boxes of a compiled clip (OUT/<scenario>/<ego>) or of a `.scn`, and rerun what follows.
    Edit {
        /// A compiled clip directory, or a `.scn` file.
        target: PathBuf,
        /// `KIND at X,Y yaw A` (metres; degrees unless `rad`).
        #[arg(long, num_args = 1.., value_name = "KIND at X,Y yaw A")]
        insert: Vec<String>,
        /// `AGENT`
        #[arg(long, value_name = "AGENT")]
        delete: Vec<String>,
        /// `AGENT by DX,DY` (metres).
        #[arg(long = "move", num_args = 1.., value_name = "AGENT by DX,DY")]
        move_: Vec<String>,
        /// Clips: edit only these frames (`0`, `0..10`, ...); default every frame.
        #[arg(long)]
        frames: Option<String>,
        /// Clips: the scenario the clip was compiled from, if not where its manifest says.
        #[arg(long)]
        scenario: Option<PathBuf>,
        /// Clips: the rig it was compiled with, if not the bundled nuPlan rig.
        #[arg(long)]
        rig: Option<PathBuf>,
        /// `.scn`: write the edited scenario here (default: rewrite the file).
        #[arg(short, long)]
        out: Option<PathBuf>,
    },
    /// Score predictions against ground truth with the shared scorer, or run the edit protocol.
    Eval {
        #[command(subcommand)]
        what: EvalCmd,
    },
    /// Explain a diagnostic code (`rocc explain E0107`); without a code, list them all.
    Explain { code: Option<String> },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.cmd {
        Cmd::Check { files, message_format } => check(&files, message_format),
        Cmd::Fmt { files, check } => fmt(&files, check),
        Cmd::Compile {
            inputs,
            out,
            stage,
            frames,
            ego,
            seed,
            occ_mode,
            rig,
            lidar_resolution,
            shard,
            no_previews,
            force,
            quiet,
            static_bev,
        } => {
            let stage = match stage {
                StageArg::Bev => Stage::Bev,
                StageArg::Occ => Stage::Occ,
                StageArg::Lidar => Stage::Lidar,
            };
            let mode = match occ_mode {
                OccMode::Surface => rocc::backend::Mode::Surface,
                OccMode::Solid => rocc::backend::Mode::Solid,
            };
            let rig = match load_rig(rig.as_deref(), lidar_resolution) {
                Ok(r) => r,
                Err(d) => {
                    print_diags(&[d], &SourceMap::default(), MessageFormat::Human);
                    return ExitCode::FAILURE;
                }
            };
            let static_bev = match static_bev.as_deref().map(rocc::import::StaticBev::load).transpose() {
                Ok(s) => s,
                Err(d) => {
                    print_diags(&[d], &SourceMap::default(), MessageFormat::Human);
                    return ExitCode::FAILURE;
                }
            };
            let opts = Options { stage, frames, egos: ego, seed, mode, rig, previews: !no_previews, force, static_bev };
            compile(&inputs, &out, shard.as_deref(), &opts, quiet)
        }
        Cmd::Import { what: ImportCmd::Boxes { file, convention, out, static_bev } } => {
            import_boxes(&file, convention, &out, static_bev.as_deref())
        }
        Cmd::Edit { target, insert, delete, move_, frames, scenario, rig, out } => {
            edit(&target, &insert, &delete, &move_, frames, scenario, rig.as_deref(), out.as_deref())
        }
        Cmd::Eval { what } => eval(what),
        Cmd::Explain { code } => explain(code.as_deref()),
    }
}

fn print_diags(diags: &[Diagnostic], sources: &SourceMap, format: MessageFormat) {
    for d in diags {
        match format {
            MessageFormat::Json => {
                let mut v = d.to_json(sources);
                v["type"] = "diagnostic".into();
                println!("{v}");
            }
            MessageFormat::Human if std::io::stderr().is_terminal() => eprintln!("{:?}", d.to_report(sources)),
            MessageFormat::Human => eprint!("{}", d.render_plain(sources)),
        }
    }
}

fn check(files: &[PathBuf], format: MessageFormat) -> ExitCode {
    let mut failed = 0;
    for f in files {
        let mut sources = SourceMap::default();
        match rocc::check::check_path(f, &mut sources).and_then(|s| rocc::compile::front(s, None)) {
            Ok(front) => {
                let s = &front.scenario;
                let movers = s
                    .agents
                    .iter()
                    .filter(|a| !a.is_object && a.motion != rocc::check::scenario::Motion::Static)
                    .count();
                let egos: Vec<&str> = s.egos.iter().map(|i| s.agents[*i].name.as_str()).collect();
                match format {
                    MessageFormat::Json => println!(
                        "{}",
                        serde_json::json!({"type": "summary", "file": f.display().to_string(), "ok": true,
                            "scenario": s.name, "road": s.road.template.name(), "agents": s.agents.len(),
                            "movers": movers, "egos": egos, "frames": s.frame_count()})
                    ),
                    MessageFormat::Human => println!(
                        "ok  {}: scenario `{}` on {} road, {} agents ({} moving), egos [{}], {} frames",
                        f.display(),
                        s.name,
                        s.road.template.name(),
                        s.agents.len(),
                        movers,
                        egos.join(", "),
                        s.frame_count()
                    ),
                }
            }
            Err(diags) => {
                failed += 1;
                print_diags(&diags, &sources, format);
            }
        }
    }
    if failed > 0 {
        if format == MessageFormat::Human {
            eprintln!("{failed} of {} file(s) failed to check", files.len());
        }
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

fn fmt(files: &[PathBuf], check_only: bool) -> ExitCode {
    let mut bad = 0;
    for f in files {
        let mut sources = SourceMap::default();
        let text = match rocc::check::load::read_source(f) {
            Ok(t) => t,
            Err(m) => {
                bad += 1;
                print_diags(
                    &[Diagnostic::error("E0002", m).help("pass a readable UTF-8 `.scn` file")],
                    &sources,
                    MessageFormat::Human,
                );
                continue;
            }
        };
        let id = sources.add(f.display().to_string(), text.clone());
        let formatted = match rocc::syntax::parse(id, &text) {
            Ok(ast) => rocc::syntax::fmt::format_file(&ast, &text),
            Err(d) => {
                bad += 1;
                print_diags(&[d], &sources, MessageFormat::Human);
                continue;
            }
        };
        if formatted == text {
            continue;
        }
        if check_only {
            println!("would reformat {}", f.display());
            bad += 1;
        } else if let Err(e) = write_atomic(f, formatted.as_bytes()) {
            eprintln!("error[E0401]: cannot write {}: {e}", f.display());
            bad += 1;
        } else {
            println!("formatted {}", f.display());
        }
    }
    if bad > 0 { ExitCode::FAILURE } else { ExitCode::SUCCESS }
}

fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = path.with_extension("scn.rocc-tmp");
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path)
}

fn load_rig(path: Option<&Path>, resolution: Option<f64>) -> Result<rocc::lidar::Rig, Diagnostic> {
    let mut rig = match path {
        None => rocc::lidar::Rig::nuplan(),
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .map_err(|e| Diagnostic::error("E0304", format!("cannot read rig `{}`: {e}", p.display())))?;
            rocc::lidar::Rig::from_ron(&text).map_err(|e| {
                Diagnostic::error("E0304", format!("rig `{}`: {e}", p.display()))
                    .help("start from rigs/nuplan.ron; `rocc explain E0304` lists the fields")
            })?
        }
    };
    if let Some(r) = resolution {
        rig.horizontal_resolution_deg = r;
        for s in &mut rig.sensors {
            s.horizontal_resolution_deg = None;
        }
        rig.validate().map_err(|e| {
            Diagnostic::error("E0304", format!("--lidar-resolution {r}: {e}")).help("use a step like 0.1 to 2 degrees")
        })?;
    }
    Ok(rig)
}

fn compile(inputs: &[PathBuf], out: &Path, shard: Option<&str>, opts: &Options, quiet: bool) -> ExitCode {
    let shard = match shard.map(batch::parse_shard).transpose() {
        Ok(s) => s,
        Err(m) => {
            eprintln!("error: --shard {m}");
            return ExitCode::FAILURE;
        }
    };
    let files = match batch::collect_inputs(inputs) {
        Ok(f) => batch::shard(f, shard),
        Err(m) => {
            let d = Diagnostic::error("E0002", m).help("pass `.scn` files or directories that hold them");
            print_diags(&[d], &SourceMap::default(), MessageFormat::Human);
            return ExitCode::FAILURE;
        }
    };
    let started = std::time::Instant::now();
    let report = batch::run(&files, out, opts, quiet);
    for f in &report.failures {
        eprintln!("failed: {}", f.input.display());
        print_diags(&f.diags, &f.sources, MessageFormat::Human);
    }
    let frames: usize = report.clips.iter().filter(|c| !c.resumed).map(|c| c.frames).sum();
    let kept = report.clips.iter().filter(|c| c.resumed).count();
    let secs = started.elapsed().as_secs_f64();
    if !quiet {
        eprintln!(
            "{} clip(s) from {} file(s): {frames} frames written in {secs:.1} s ({:.1} frames/s){}; {} failed",
            report.clips.len(),
            files.len(),
            frames as f64 / secs.max(1e-9),
            if kept > 0 { format!(", {kept} complete clip(s) kept") } else { String::new() },
            report.failures.len()
        );
    }
    if report.failures.is_empty() { ExitCode::SUCCESS } else { ExitCode::FAILURE }
}

fn explain(code: Option<&str>) -> ExitCode {
    match code {
        None => {
            for c in codes::CODES {
                println!("{}  {}", c.code, c.title);
            }
            ExitCode::SUCCESS
        }
        Some(code) => match codes::lookup(code) {
            Some(c) => {
                println!("{}: {}\n\n{}", c.code, c.title, c.explanation);
                ExitCode::SUCCESS
            }
            None => {
                eprintln!("error: `{code}` is not a rocc diagnostic code; `rocc explain` lists them");
                ExitCode::FAILURE
            }
        },
    }
}

fn import_boxes(file: &Path, conv: ConventionArg, out: &Path, static_bev: Option<&Path>) -> ExitCode {
    use rocc::import::{Convention, StaticBev, import_boxes, scenario_name};
    let conv = match conv {
        ConventionArg::Nuscenes => Convention::NuScenes,
        ConventionArg::Mmdet3d => Convention::Mmdet3d,
        ConventionArg::Nuplan => Convention::NuPlan,
    };
    let mut sources = SourceMap::default();
    if let Some(p) = static_bev
        && let Err(d) = StaticBev::load(p)
    {
        print_diags(&[d], &sources, MessageFormat::Human);
        return ExitCode::FAILURE;
    }
    match import_boxes(file, conv, &scenario_name(out), &mut sources) {
        Ok(imp) => {
            print_diags(&imp.warnings, &sources, MessageFormat::Human);
            let mut text = imp.text;
            if let Some(p) = static_bev {
                text = format!("// Map layers: compile with `--static-bev {}`.\n{text}", p.display());
            }
            if let Err(e) = rocc::output::write_atomic(out, |w| std::io::Write::write_all(w, text.as_bytes())) {
                let d = Diagnostic::error("E0401", format!("cannot write `{}`: {e}", out.display()))
                    .help("check the directory exists and is writable");
                print_diags(&[d], &sources, MessageFormat::Human);
                return ExitCode::FAILURE;
            }
            eprintln!(
                "imported {} frame(s), {} replayed agent(s) -> {}",
                imp.recorded.frames.len(),
                imp.agents.len(),
                out.display()
            );
            ExitCode::SUCCESS
        }
        Err(d) => {
            print_diags(&d, &sources, MessageFormat::Human);
            ExitCode::FAILURE
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn edit(
    target: &Path,
    insert: &[String],
    delete: &[String],
    move_: &[String],
    frames: Option<String>,
    scenario: Option<PathBuf>,
    rig: Option<&Path>,
    out: Option<&Path>,
) -> ExitCode {
    use rocc::edit::{ClipEdit, Edit, parse_edit};
    let fail = |d: Vec<Diagnostic>, sources: &SourceMap| {
        print_diags(&d, sources, MessageFormat::Human);
        ExitCode::FAILURE
    };
    let mut edits: Vec<Edit> = Vec::new();
    let parsed = (!insert.is_empty())
        .then(|| parse_edit("insert", insert))
        .into_iter()
        .chain(delete.iter().map(|a| parse_edit("delete", std::slice::from_ref(a))))
        .chain((!move_.is_empty()).then(|| parse_edit("move", move_)));
    for p in parsed {
        match p {
            Ok(e) => edits.push(e),
            Err(d) => return fail(vec![d], &SourceMap::default()),
        }
    }
    if edits.is_empty() {
        let d = Diagnostic::error("E0717", "no edit given")
            .help("add `--insert KIND at X,Y yaw A`, `--delete AGENT` or `--move AGENT by DX,DY`");
        return fail(vec![d], &SourceMap::default());
    }
    if target.is_dir() {
        let rig = match rig.map(|r| load_rig(Some(r), None)).transpose() {
            Ok(r) => r,
            Err(d) => return fail(vec![d], &SourceMap::default()),
        };
        match rocc::edit::edit_clip(target, &edits, &ClipEdit { scenario, frames, rig }) {
            Ok(m) => {
                eprintln!("edited {} ({} frames): {}", target.display(), m.frames.len(), m.edits.join("; "));
                ExitCode::SUCCESS
            }
            Err(d) => fail(d, &SourceMap::default()),
        }
    } else {
        let mut sources = SourceMap::default();
        match rocc::edit::edit_scn(target, &edits, &mut sources) {
            Ok(text) => {
                let dest = out.unwrap_or(target);
                match rocc::output::write_atomic(dest, |w| std::io::Write::write_all(w, text.as_bytes())) {
                    Ok(_) => {
                        eprintln!("edited {} -> {}", target.display(), dest.display());
                        ExitCode::SUCCESS
                    }
                    Err(e) => fail(
                        vec![Diagnostic::error("E0401", format!("cannot write `{}`: {e}", dest.display()))],
                        &sources,
                    ),
                }
            }
            Err(d) => fail(d, &sources),
        }
    }
}

fn eval(what: EvalCmd) -> ExitCode {
    let fail = |d: Vec<Diagnostic>| {
        print_diags(&d, &SourceMap::default(), MessageFormat::Human);
        ExitCode::FAILURE
    };
    match what {
        EvalCmd::Occ { pred, gt, json } => match rocc::eval::score_occ_dirs(&pred, &gt) {
            Ok(s) if json => {
                println!("{}", serde_json::to_string_pretty(&s).expect("scores are plain numbers"));
                ExitCode::SUCCESS
            }
            Ok(s) => {
                print!("{}", s.table());
                ExitCode::SUCCESS
            }
            Err(d) => fail(d),
        },
        EvalCmd::Lidar { pred, gt, range_filter, json } => match rocc::eval::score_lidar_dirs(&pred, &gt, range_filter)
        {
            Ok(s) if json => {
                println!("{}", serde_json::to_string_pretty(&s).expect("scores are plain numbers"));
                ExitCode::SUCCESS
            }
            Ok(s) => {
                println!(
                    "MMD {:.4e} ({:.3} x 1e-5)   JSD {:.4}   ({} predicted vs {} ground-truth clouds{})",
                    s.mmd,
                    s.mmd * 1e5,
                    s.jsd,
                    s.pred_clouds,
                    s.gt_clouds,
                    if s.range_filter { ", 3 < r < 50 m" } else { "" }
                );
                ExitCode::SUCCESS
            }
            Err(d) => fail(d),
        },
        EvalCmd::Edits { scenes, seed, scenarios, json } => {
            match rocc::eval::run_edit_protocol(&scenarios, scenes, seed) {
                Ok(s) if json => {
                    println!("{}", serde_json::to_string_pretty(&s).expect("scores are plain numbers"));
                    ExitCode::SUCCESS
                }
                Ok(s) => {
                    print!("{}", s.table());
                    ExitCode::SUCCESS
                }
                Err(d) => fail(d),
            }
        }
    }
}
