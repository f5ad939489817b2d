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
            let opts = Options { stage, frames, egos: ego, seed, mode, rig, previews: !no_previews, force };
            compile(&inputs, &out, shard.as_deref(), &opts, quiet)
        }
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
