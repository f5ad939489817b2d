//! The `rocc` command line. Each subcommand is a thin shell over one library entry point.

use clap::{Parser, Subcommand, ValueEnum};
use rocc::compile::{Options, Stage, batch};
use rocc::diag::{Diagnostic, codes};
use rocc::llm;
use rocc::source::SourceMap;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Write to stdout through a locked handle. A reader that has gone away (`rocc explain | head`)
/// ends the command quietly with success, as `cat` would; any other write failure is reported
/// and ends it with failure. `println!` would panic on either.
macro_rules! out {
    ($($arg:tt)*) => {
        stdout_write(format_args!($($arg)*))
    };
}

macro_rules! outln {
    ($($arg:tt)*) => {
        stdout_write(format_args!("{}\n", format_args!($($arg)*)))
    };
}

fn stdout_write(args: std::fmt::Arguments) {
    use std::io::Write;
    let mut lock = std::io::stdout().lock();
    if let Err(e) = lock.write_fmt(args).and_then(|()| lock.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("error[E0401]: cannot write to stdout: {e}");
        std::process::exit(1);
    }
}

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
enum ServerArg {
    Vllm,
    Llamacpp,
    Ollama,
    Openai,
}

#[derive(Clone, Copy, ValueEnum)]
enum PlanArg {
    Joint,
    Hierarchical,
}

#[derive(Clone, Copy, ValueEnum)]
enum GrammarFormat {
    Gbnf,
    Lark,
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

#[derive(Clone, Copy, ValueEnum)]
enum TrainWhat {
    /// Occupancy -> grounded latents -> decoder (pretrains the shared decoder).
    Autoencoder,
    /// BEV + boxes -> grounded latents -> decoder (warm-started from the autoencoder).
    Generator,
}

#[derive(Clone, Copy, ValueEnum)]
enum DeviceArg {
    /// burn's `flex` backend (pure Rust, every build).
    Cpu,
    /// wgpu (Vulkan/Metal/DX12); needs `--features gpu`.
    Wgpu,
    /// CUDA device 0; needs `--features gpu`.
    Cuda,
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

/// `rocc ciren ...`: crash recreation from NHTSA CIREN cases (one variant per route).
#[derive(Subcommand)]
enum CirenCmd {
    /// Coded CIREN case records -> one checked `.scn` per case (`DIR/<case id>.scn`).
    Import {
        /// Case directories (holding `crash_report.xml`), their parent directories, or XML files.
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
        /// Output directory.
        #[arg(short, long)]
        out: PathBuf,
    },
    /// SAFE-format VLM extractions (`*.json`) -> one checked `.scn` per file.
    ImportSafe {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Output directory.
        #[arg(short, long)]
        out: PathBuf,
    },
    /// Sketch and summary of a case to a checked `.scn` through a vision model (OpenAI-compatible server).
    Extract {
        /// The case folder: sketch.jpeg (or Sketch.jpg) and crash_report.xml (or Summary.txt).
        case: PathBuf,
        /// The `.scn` file to write (atomically, only once it checks with its conflict).
        #[arg(short, long)]
        out: PathBuf,
        /// The server's OpenAI-compatible base URL [env: ROCC_LLM_ENDPOINT; default: the server's usual port on 127.0.0.1].
        #[arg(long)]
        endpoint: Option<String>,
        /// Model name as the server knows it [env: ROCC_LLM_MODEL]; llama.cpp ignores it.
        #[arg(long)]
        model: Option<String>,
        /// Bearer token [env: ROCC_LLM_API_KEY, then OPENAI_API_KEY].
        #[arg(long)]
        api_key: Option<String>,
        /// Server dialect: how grammar and JSON-schema constraints are sent.
        #[arg(long, value_enum, default_value = "vllm")]
        server: ServerArg,
        /// Repair rounds for the scene, and extra conflict calls for the conflict.
        #[arg(long, default_value_t = 3)]
        max_repairs: u32,
        /// Scenario seed (default: the case number); also sent as the sampling seed.
        #[arg(long)]
        seed: Option<u64>,
        /// Worked examples: every `.scn` of this directory instead of the bundled prompts/ciren/.
        #[arg(long)]
        examples: Option<PathBuf>,
        /// Seconds to wait for one reply.
        #[arg(long, default_value_t = 180.0)]
        timeout: f64,
        /// Retries after HTTP 429 or 5xx, with exponential backoff from 1 s.
        #[arg(long, default_value_t = 2)]
        retries: u32,
        #[arg(long, default_value_t = 2048)]
        max_tokens: u32,
        /// Sampling temperature of the scene call; the conflict call is always 0.
        #[arg(long, default_value_t = 0.0)]
        temperature: f64,
        /// Do not send grammar or JSON-schema constraints.
        #[arg(long)]
        no_grammar: bool,
        /// Save every request (images shortened) and reply as OUT.transcript.json.
        #[arg(long)]
        transcript: bool,
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
        /// Compiled clip directories (their lidar/ frames), or directories of .bin / .pcd / .npy clouds.
        #[arg(long)]
        pred: PathBuf,
        /// As `--pred`.
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
        /// Occupancy backend.
        #[arg(long, value_enum, default_value = "procedural")]
        backend: BackendArg,
        /// `--backend grounded`: generator weights (`.bpk` from `rocc train`, or `.safetensors`).
        #[arg(long)]
        weights: Option<PathBuf>,
        /// `--backend grounded`: the model config (default: the `.ron` beside the weights).
        #[arg(long)]
        grounded_config: Option<PathBuf>,
    },
    /// Train the grounded occupancy model on compiled clips or nuPlan-Occ-style data.
    Train {
        #[arg(value_enum)]
        what: TrainWhat,
        /// Training data: `rocc compile --stage occ` output, or bev/ occ/ boxes/ per token.
        #[arg(long)]
        data: PathBuf,
        /// Model and training config (RON), e.g. configs/cpu-small.ron or configs/paper.ron.
        #[arg(long)]
        config: PathBuf,
        /// Output directory: weights, config copy, checkpoints, history.
        #[arg(short, long)]
        out: PathBuf,
        /// Held-out data (default: `val_fraction` of the clips of --data, by the config's seed).
        #[arg(long)]
        val: Option<PathBuf>,
        /// Continue from OUT/checkpoint.
        #[arg(long)]
        resume: bool,
        /// Generator: autoencoder weights to start the decoder from (default OUT/autoencoder.bpk).
        #[arg(long)]
        init: Option<PathBuf>,
        #[arg(long, value_enum, default_value = "cpu")]
        device: DeviceArg,
        /// Override the stage's epoch count.
        #[arg(long)]
        epochs: Option<usize>,
        /// Stop after this many steps in all (weights and a validation line are still written).
        #[arg(long)]
        max_steps: Option<usize>,
        /// Also export the final weights as OUT/<stage>.safetensors.
        #[arg(long)]
        safetensors: bool,
        #[arg(short, long)]
        quiet: bool,
    },
    /// Turn recorded boxes into a scenario: `rocc import boxes FILE --convention nuscenes -o scene.scn`.
    Import {
        #[command(subcommand)]
        what: ImportCmd,
    },
    /// Recreate NHTSA CIREN crashes as scenarios: `rocc ciren import ../shared/ciren -o scn/`.
    Ciren {
        #[command(subcommand)]
        what: CirenCmd,
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
        /// Clips of `--backend grounded`: its weights, if not where the manifest says (same weights).
        #[arg(long)]
        weights: Option<PathBuf>,
        /// Clips of `--backend grounded`: its model config, if not the manifest's.
        #[arg(long)]
        grounded_config: Option<PathBuf>,
        /// `.scn`: write the edited scenario here (default: rewrite the file).
        #[arg(short, long)]
        out: Option<PathBuf>,
    },
    /// Score predictions against ground truth with the shared scorer, or run the edit protocol.
    Eval {
        #[command(subcommand)]
        what: EvalCmd,
    },
    /// Write a checked scenario from a sentence with a language model (OpenAI-compatible server).
    Text {
        /// The scene in words, e.g. "an ambulance through a crowded intersection".
        sentence: String,
        /// The `.scn` file to write (atomically, only once it checks).
        #[arg(short, long)]
        out: PathBuf,
        /// The server's OpenAI-compatible base URL [env: ROCC_LLM_ENDPOINT; default: the server's usual port on 127.0.0.1].
        #[arg(long)]
        endpoint: Option<String>,
        /// Model name as the server knows it [env: ROCC_LLM_MODEL]; llama.cpp ignores it.
        #[arg(long)]
        model: Option<String>,
        /// Bearer token [env: ROCC_LLM_API_KEY, then OPENAI_API_KEY].
        #[arg(long)]
        api_key: Option<String>,
        /// Server dialect: how grammar constraints are sent (ollama and openai take none).
        #[arg(long, value_enum, default_value = "vllm")]
        server: ServerArg,
        /// Goal stage: one call for all agents, or one per agent with earlier goals in context.
        #[arg(long, value_enum, default_value = "joint")]
        plan: PlanArg,
        /// Rounds of sending diagnostics back for a corrected file (and corrections per stage).
        #[arg(long, default_value_t = 3)]
        max_repairs: u32,
        /// Background traffic density 0..1 (overrides the model's choice).
        #[arg(long)]
        density: Option<f64>,
        /// Background traffic randomness 0..1 (overrides the model's choice).
        #[arg(long)]
        randomness: Option<f64>,
        /// Scenario seed (default: a hash of the sentence); also sent as the sampling seed.
        #[arg(long)]
        seed: Option<u64>,
        /// Seconds to wait for one reply.
        #[arg(long, default_value_t = 120.0)]
        timeout: f64,
        /// Retries after HTTP 429 or 5xx, with exponential backoff from 1 s.
        #[arg(long, default_value_t = 2)]
        retries: u32,
        #[arg(long, default_value_t = 2048)]
        max_tokens: u32,
        /// Sampling temperature; 0 (greedy) makes runs repeatable.
        #[arg(long, default_value_t = 0.0)]
        temperature: f64,
        /// A sketch (PNG/JPEG/WebP/GIF) sent with the sentence to a vision model (CIREN route).
        #[arg(long)]
        image: Option<PathBuf>,
        /// Do not send grammar or JSON-schema constraints.
        #[arg(long)]
        no_grammar: bool,
        /// Save every request and reply as OUT.transcript.json (the API key is never written).
        #[arg(long)]
        transcript: bool,
    },
    /// Print the language grammar for grammar-constrained LLM decoding (derived from scn.pest).
    Grammar {
        /// `gbnf`: llama.cpp and vLLM (xgrammar); `lark`: llguidance and vLLM's guidance backend.
        #[arg(long, value_enum, default_value = "gbnf")]
        format: GrammarFormat,
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
            backend,
            weights,
            grounded_config,
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
            let static_bev = match static_bev.as_deref().map(rocc::compile::StaticBev::load).transpose() {
                Ok(s) => s,
                Err(d) => {
                    print_diags(&[d], &SourceMap::default(), MessageFormat::Human);
                    return ExitCode::FAILURE;
                }
            };
            let backend = match occ_backend(backend, weights.as_deref(), grounded_config.as_deref()) {
                Ok(b) => b,
                Err(d) => {
                    print_diags(&[d], &SourceMap::default(), MessageFormat::Human);
                    return ExitCode::FAILURE;
                }
            };
            let opts = Options {
                stage,
                frames,
                egos: ego,
                seed,
                mode,
                rig,
                previews: !no_previews,
                force,
                static_bev,
                backend,
            };
            compile(&inputs, &out, shard.as_deref(), &opts, quiet)
        }
        Cmd::Train { what, data, config, out, val, resume, init, device, epochs, max_steps, safetensors, quiet } => {
            let r =
                train_cmd(what, data, &config, out, val, resume, init, device, epochs, max_steps, safetensors, quiet);
            match r {
                Ok(()) => ExitCode::SUCCESS,
                Err(d) => {
                    print_diags(&[d], &SourceMap::default(), MessageFormat::Human);
                    ExitCode::FAILURE
                }
            }
        }
        Cmd::Import { what: ImportCmd::Boxes { file, convention, out, static_bev } } => {
            import_boxes(&file, convention, &out, static_bev.as_deref())
        }
        Cmd::Edit { target, insert, delete, move_, frames, scenario, rig, weights, grounded_config, out } => {
            let o = ClipEditArgs { frames, scenario, weights, grounded_config };
            edit(&target, &insert, &delete, &move_, o, rig.as_deref(), out.as_deref())
        }
        Cmd::Eval { what } => eval(what),
        Cmd::Ciren { what } => ciren(what),
        Cmd::Text {
            sentence,
            out,
            endpoint,
            model,
            api_key,
            server,
            plan,
            max_repairs,
            density,
            randomness,
            seed,
            timeout,
            retries,
            max_tokens,
            temperature,
            image,
            no_grammar,
            transcript,
        } => {
            let (server, endpoint, model, api_key) = llm_connection(server, endpoint, model, api_key);
            let args = TextArgs {
                endpoint,
                model,
                api_key,
                server,
                plan: match plan {
                    PlanArg::Joint => llm::Plan::Joint,
                    PlanArg::Hierarchical => llm::Plan::Hierarchical,
                },
                max_repairs,
                overrides: llm::schema::Overrides { density, randomness, seed },
                timeout,
                retries,
                max_tokens,
                temperature,
                image,
                constrain: !no_grammar,
                transcript,
            };
            text(&sentence, &out, args)
        }
        Cmd::Grammar { format } => {
            out!(
                "{}",
                rocc::grammar::export(match format {
                    GrammarFormat::Gbnf => rocc::grammar::Format::Gbnf,
                    GrammarFormat::Lark => rocc::grammar::Format::Lark,
                })
            );
            ExitCode::SUCCESS
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
                outln!("{v}");
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
                    MessageFormat::Json => outln!(
                        "{}",
                        serde_json::json!({"type": "summary", "file": f.display().to_string(), "ok": true,
                            "scenario": s.name, "road": s.road.template.name(), "agents": s.agents.len(),
                            "movers": movers, "egos": egos, "frames": s.frame_count()})
                    ),
                    MessageFormat::Human => outln!(
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
            outln!("would reformat {}", f.display());
            bad += 1;
        } else if let Err(e) = write_atomic(f, formatted.as_bytes()) {
            eprintln!("error[E0401]: cannot write {}: {e}", f.display());
            bad += 1;
        } else {
            outln!("formatted {}", f.display());
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

fn occ_backend(
    backend: BackendArg,
    weights: Option<&Path>,
    config: Option<&Path>,
) -> Result<rocc::compile::OccBackend, Diagnostic> {
    use rocc::compile::OccBackend;
    match (backend, weights) {
        (BackendArg::Procedural, None) if config.is_none() => Ok(OccBackend::Procedural),
        (BackendArg::Procedural, _) => {
            Err(Diagnostic::error("E0908", "`--weights` and `--grounded-config` apply to `--backend grounded` only")
                .help("add `--backend grounded`, or drop the weights options for the procedural backend"))
        }
        (BackendArg::Grounded, None) => Err(Diagnostic::error("E0901", "`--backend grounded` needs `--weights FILE`")
            .help("train weights with `rocc train generator ...` (README: \"Training the grounded backend\")")),
        (BackendArg::Grounded, Some(w)) => {
            rocc::backend::grounded::Grounded::load(w, config).map(|g| OccBackend::Grounded(std::sync::Arc::new(g)))
        }
    }
}

fn train_device(d: DeviceArg) -> Result<burn::tensor::Device, Diagnostic> {
    match d {
        DeviceArg::Cpu => Ok(burn::tensor::Device::flex()),
        #[cfg(feature = "gpu")]
        DeviceArg::Wgpu => Ok(burn::tensor::Device::wgpu(Default::default())),
        #[cfg(feature = "gpu")]
        DeviceArg::Cuda => Ok(burn::tensor::Device::cuda(0usize)),
        #[cfg(not(feature = "gpu"))]
        DeviceArg::Wgpu | DeviceArg::Cuda => Err(Diagnostic::error("E0908", "this rocc was built without GPU support")
            .help("rebuild with `cargo build --release --features gpu`, or train with `--device cpu`")),
    }
}

#[allow(clippy::too_many_arguments)]
fn train_cmd(
    what: TrainWhat,
    data: PathBuf,
    config: &Path,
    out: PathBuf,
    val: Option<PathBuf>,
    resume: bool,
    init: Option<PathBuf>,
    device: DeviceArg,
    epochs: Option<usize>,
    max_steps: Option<usize>,
    safetensors: bool,
    quiet: bool,
) -> Result<(), Diagnostic> {
    use rocc::learn::{Stage, TrainOptions};
    let config = rocc::backend::grounded::load_config(config)?;
    let stage = match what {
        TrainWhat::Autoencoder => Stage::Autoencoder,
        TrainWhat::Generator => Stage::Generator,
    };
    if let Some(p) = &init
        && !p.is_file()
    {
        return Err(Diagnostic::error("E0901", format!("`--init {}` does not exist", p.display()))
            .help("pass the autoencoder weights `rocc train autoencoder` wrote (OUT/autoencoder.bpk)"));
    }
    let opts = TrainOptions {
        stage,
        data,
        val,
        config,
        out,
        resume,
        init,
        device: train_device(device)?,
        quiet,
        max_steps,
        epochs,
    };
    let report = rocc::learn::train(&opts)?;
    if safetensors {
        use rocc::backend::grounded::{Autoencoder, Generator, cpu, load_weights, save_safetensors};
        let st = report.weights.with_extension("safetensors");
        let res = match stage {
            Stage::Autoencoder => {
                save_safetensors(&load_weights(Autoencoder::new(&opts.config, &cpu()), &report.weights)?, &st)
            }
            Stage::Generator => {
                save_safetensors(&load_weights(Generator::new(&opts.config, &cpu()), &report.weights)?, &st)
            }
        };
        res.map_err(|e| {
            Diagnostic::error("E0906", format!("cannot write `{}`: {e}", st.display()))
                .help("check the output directory")
        })?;
        if !quiet {
            eprintln!("wrote {}", st.display());
        }
    }
    Ok(())
}

fn compile(inputs: &[PathBuf], out: &Path, shard: Option<&str>, opts: &Options, quiet: bool) -> ExitCode {
    let shard = match shard.map(batch::parse_shard).transpose() {
        Ok(s) => s,
        Err(m) => {
            let d = Diagnostic::error("E0402", format!("--shard {m}"))
                .help("K/N with 1 <= K <= N, e.g. `--shard 3/16` (see `rocc explain E0402`)");
            print_diags(&[d], &SourceMap::default(), MessageFormat::Human);
            return ExitCode::FAILURE;
        }
    };
    let all = match batch::collect_inputs(inputs) {
        Ok(f) => f,
        Err(m) => {
            let d = Diagnostic::error("E0002", m).help("pass `.scn` files or directories that hold them");
            print_diags(&[d], &SourceMap::default(), MessageFormat::Human);
            return ExitCode::FAILURE;
        }
    };
    // Names are checked for duplicates over all inputs, not only this shard's.
    let files = batch::shard(all.clone(), shard);
    let started = std::time::Instant::now();
    let report = batch::run_shard(&all, shard, out, opts, quiet);
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

struct TextArgs {
    endpoint: String,
    model: Option<String>,
    api_key: Option<String>,
    server: llm::client::Server,
    plan: llm::Plan,
    max_repairs: u32,
    overrides: llm::schema::Overrides,
    timeout: f64,
    retries: u32,
    max_tokens: u32,
    temperature: f64,
    image: Option<PathBuf>,
    constrain: bool,
    transcript: bool,
}

fn text_options(a: TextArgs) -> Result<llm::Options, Diagnostic> {
    let bad = |m: String, h: &str| Diagnostic::error("E0614", m).help(h.to_string());
    for (flag, v) in [("--density", a.overrides.density), ("--randomness", a.overrides.randomness)] {
        if let Some(v) = v.filter(|v| !(0.0..=1.0).contains(v)) {
            return Err(bad(format!("{flag} {v} is outside 0..1"), "a fraction: 0 none, 1 as much as fits"));
        }
    }
    if !(a.timeout.is_finite() && a.timeout > 0.0) {
        return Err(bad(format!("--timeout {} is not a positive number of seconds", a.timeout), "e.g. --timeout 120"));
    }
    let model = match (a.model, a.server) {
        (Some(m), _) => m,
        // llama.cpp serves the one model it loaded and ignores the field.
        (None, llm::client::Server::Llamacpp) => "default".to_string(),
        (None, s) => {
            return Err(bad(
                format!("--model is required with --server {}", s.name()),
                "pass the model name the server lists at /v1/models, or set ROCC_LLM_MODEL",
            ));
        }
    };
    let image = a.image.as_deref().map(llm::Image::from_file).transpose()?;
    Ok(llm::Options {
        client: llm::client::ClientConfig {
            endpoint: a.endpoint,
            model,
            api_key: a.api_key,
            server: a.server,
            timeout: std::time::Duration::from_secs_f64(a.timeout),
            retries: a.retries,
            backoff: std::time::Duration::from_secs(1),
            max_tokens: a.max_tokens,
            temperature: a.temperature,
            seed: a.overrides.seed.unwrap_or(0),
        },
        plan: a.plan,
        max_repairs: a.max_repairs,
        overrides: a.overrides,
        constrain: a.constrain,
        image,
    })
}

/// `rocc text`: the output is written only once it checks; a failure keeps OUT.rejected.scn.
fn text(sentence: &str, out: &Path, args: TextArgs) -> ExitCode {
    let human = MessageFormat::Human;
    let write_transcript = args.transcript;
    let opts = match text_options(args) {
        Ok(o) => o,
        Err(d) => {
            print_diags(&[d], &SourceMap::default(), human);
            return ExitCode::FAILURE;
        }
    };
    let name = out.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "scene.scn".into());
    let base = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let (outcome, run) = llm::text_to_scenario(sentence, &opts, &name, base);
    print_diags(&run.warnings, &SourceMap::default(), human);
    let rejected = out.with_extension("rejected.scn");
    if write_transcript {
        let t = out.with_extension("transcript.json");
        let v = run.transcript(sentence, &opts);
        let bytes = serde_json::to_vec_pretty(&v).expect("a JSON value serialises");
        match rocc::files::write_atomic(&t, |w| std::io::Write::write_all(w, &bytes)) {
            Ok(_) => eprintln!("transcript: {}", t.display()),
            Err(e) => eprintln!("error[E0401]: cannot write {}: {e}", t.display()),
        }
    }
    let requests = run.exchanges.len();
    let repairs = run.attempts.len().saturating_sub(1);
    match outcome {
        llm::Outcome::Accepted { text } => {
            if let Err(e) = rocc::files::write_atomic(out, |w| std::io::Write::write_all(w, text.as_bytes())) {
                print_diags(
                    &[Diagnostic::error("E0401", format!("cannot write {}: {e}", out.display()))],
                    &SourceMap::default(),
                    human,
                );
                return ExitCode::FAILURE;
            }
            // A rejected attempt from an earlier run would now be misleading.
            let _ = std::fs::remove_file(&rejected);
            eprintln!("wrote {} ({requests} request(s), {repairs} repair round(s))", out.display());
            ExitCode::SUCCESS
        }
        llm::Outcome::Rejected { text, diags, sources } => {
            let kept = rocc::files::write_atomic(&rejected, |w| std::io::Write::write_all(w, text.as_bytes()));
            // Re-check under the kept file's name so the spans point into it.
            let mut named = SourceMap::default();
            let shown = match &kept {
                Ok(_) => {
                    let rname = rejected.display().to_string();
                    match rocc::check::check_text(&rname, &text, base, &mut named)
                        .and_then(|s| rocc::compile::front(s, None))
                    {
                        Err(d) => (d, named),
                        Ok(_) => (diags, sources),
                    }
                }
                Err(_) => (diags, sources),
            };
            print_diags(&shown.0, &shown.1, human);
            let where_ = match kept {
                Ok(_) => format!("the last attempt is kept in {}", rejected.display()),
                Err(e) => format!("the last attempt could not be kept ({e})"),
            };
            let d = Diagnostic::error(
                "E0613",
                format!("the generated scenario still fails to check after {repairs} repair round(s); nothing written to {}", out.display()),
            )
            .help(format!("{where_}; raise --max-repairs or use a stronger model"));
            print_diags(&[d], &SourceMap::default(), human);
            ExitCode::FAILURE
        }
        llm::Outcome::Failed(d) => {
            print_diags(&[d], &SourceMap::default(), human);
            // A failure mid-repair still leaves the last checked attempt to look at.
            if let Some(last) = run.attempts.last()
                && rocc::files::write_atomic(&rejected, |w| std::io::Write::write_all(w, last.as_bytes())).is_ok()
            {
                eprintln!("the last attempt is kept in {}", rejected.display());
            }
            ExitCode::FAILURE
        }
    }
}

/// The server dialect, endpoint, model and API key of an LLM command: each flag, else its
/// environment variable, else the dialect's usual local endpoint.
fn llm_connection(
    server: ServerArg,
    endpoint: Option<String>,
    model: Option<String>,
    api_key: Option<String>,
) -> (llm::client::Server, String, Option<String>, Option<String>) {
    let server = match server {
        ServerArg::Vllm => llm::client::Server::Vllm,
        ServerArg::Llamacpp => llm::client::Server::Llamacpp,
        ServerArg::Ollama => llm::client::Server::Ollama,
        ServerArg::Openai => llm::client::Server::Openai,
    };
    let env = |k: &str| std::env::var(k).ok().filter(|v| !v.is_empty());
    let endpoint = endpoint.or_else(|| env("ROCC_LLM_ENDPOINT")).unwrap_or_else(|| server.default_endpoint().into());
    let model = model.or_else(|| env("ROCC_LLM_MODEL"));
    let api_key = api_key.or_else(|| env("ROCC_LLM_API_KEY")).or_else(|| env("OPENAI_API_KEY"));
    (server, endpoint, model, api_key)
}

/// `rocc ciren import | import-safe | extract`.
fn ciren(what: CirenCmd) -> ExitCode {
    match what {
        CirenCmd::Import { inputs, out } => {
            let (cases, errs) = rocc::ciren::case_inputs(&inputs);
            print_diags(&errs, &SourceMap::default(), MessageFormat::Human);
            ciren_import(cases.into_iter().map(Ok).chain(errs.into_iter().map(Err)).collect(), &out, false)
        }
        CirenCmd::ImportSafe { files, out } => ciren_import(files.into_iter().map(Ok).collect(), &out, true),
        CirenCmd::Extract {
            case,
            out,
            endpoint,
            model,
            api_key,
            server,
            max_repairs,
            seed,
            examples,
            timeout,
            retries,
            max_tokens,
            temperature,
            no_grammar,
            transcript,
        } => {
            let (server, endpoint, model, api_key) = llm_connection(server, endpoint, model, api_key);
            // The client options are `rocc text`'s, validated the same way.
            let args = TextArgs {
                endpoint,
                model,
                api_key,
                server,
                plan: llm::Plan::Joint,
                max_repairs,
                overrides: llm::schema::Overrides { density: None, randomness: None, seed },
                timeout,
                retries,
                max_tokens,
                temperature,
                image: None,
                constrain: !no_grammar,
                transcript,
            };
            ciren_extract(&case, &out, examples.as_deref(), args)
        }
    }
}

/// `rocc ciren extract`: like `rocc text`, the output is written only once it checks (with its
/// conflict); a failure keeps OUT.rejected.scn.
fn ciren_extract(case_dir: &Path, out: &Path, examples: Option<&Path>, args: TextArgs) -> ExitCode {
    use rocc::ciren::extract::{self, Outcome};
    let human = MessageFormat::Human;
    let fail = |d: Diagnostic, sources: &SourceMap| {
        print_diags(&[d], sources, human);
        ExitCode::FAILURE
    };
    let write_transcript = args.transcript;
    let (seed, max_repairs, constrain) = (args.overrides.seed, args.max_repairs, args.constrain);
    let client = match text_options(args) {
        Ok(o) => o.client,
        Err(d) => return fail(d, &SourceMap::default()),
    };
    let examples = match examples.map(extract::load_examples).transpose() {
        Ok(e) => e.unwrap_or_else(extract::builtin_examples),
        Err(d) => return fail(d, &SourceMap::default()),
    };
    let case = match extract::read_case(case_dir) {
        Ok(c) => c,
        Err(e) => return fail(e.diag, &e.sources),
    };
    let opts = extract::Options { client, max_repairs, constrain, seed, examples };
    let name = out.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "scene.scn".into());
    let base = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let (outcome, run) = extract::extract(&case, &opts, &name, base);
    let rejected = out.with_extension("rejected.scn");
    if write_transcript {
        let t = out.with_extension("transcript.json");
        let v = run.transcript(&case, &opts, seed.unwrap_or_else(|| extract::default_seed(&case.id)));
        let bytes = serde_json::to_vec_pretty(&v).expect("a JSON value serialises");
        match rocc::files::write_atomic(&t, |w| std::io::Write::write_all(w, &bytes)) {
            Ok(_) => eprintln!("transcript: {}", t.display()),
            Err(e) => eprintln!("error[E0401]: cannot write {}: {e}", t.display()),
        }
    }
    let requests = run.exchanges.len();
    let keep = |text: &str, diags: Vec<Diagnostic>, sources: SourceMap| -> Result<(), String> {
        let kept = rocc::files::write_atomic(&rejected, |w| std::io::Write::write_all(w, text.as_bytes()));
        // Re-check under the kept file's name so the spans point into it; a kept file that
        // checks (a scene without a usable conflict) shows the original diagnostics.
        let mut named = SourceMap::default();
        let shown = match &kept {
            // Diagnostics without a file (no scenario in the reply, no usable conflict) are
            // the better explanation.
            Ok(_) if sources.files.is_empty() => (diags, sources),
            Ok(_) => match rocc::check::check_text(&rejected.display().to_string(), text, base, &mut named)
                .and_then(|s| rocc::compile::front(s, None))
            {
                Err(d) => (d, named),
                Ok(_) => (diags, sources),
            },
            Err(_) => (diags, sources),
        };
        print_diags(&shown.0, &shown.1, human);
        kept.map(|_| ()).map_err(|e| e.to_string())
    };
    let where_ = |r: Result<(), String>| match r {
        Ok(()) => format!("the last attempt is kept in {}", rejected.display()),
        Err(e) => format!("the last attempt could not be kept ({e})"),
    };
    match outcome {
        Outcome::Accepted { text } => {
            if let Err(e) = rocc::files::write_atomic(out, |w| std::io::Write::write_all(w, text.as_bytes())) {
                return fail(
                    Diagnostic::error("E0401", format!("cannot write {}: {e}", out.display())),
                    &SourceMap::default(),
                );
            }
            let _ = std::fs::remove_file(&rejected);
            let block = run.descriptor.as_ref().map(|d| d.block()).unwrap_or_default();
            eprintln!(
                "wrote {} ({requests} request(s), {} scene repair round(s), {} conflict call(s)): {block}",
                out.display(),
                run.attempts.len().saturating_sub(1),
                run.conflict_replies.len()
            );
            ExitCode::SUCCESS
        }
        Outcome::SceneRejected { text, diags, sources } => {
            let r = keep(&text, diags, sources);
            let d = Diagnostic::error(
                "E0856",
                format!(
                    "the scene extracted from case {} still fails to check after {} repair round(s); nothing written to {}",
                    case.id,
                    run.attempts.len().saturating_sub(1),
                    out.display()
                ),
            )
            .help(format!("{}; raise --max-repairs or use a stronger model", where_(r)));
            fail(d, &SourceMap::default())
        }
        Outcome::ConflictRejected { text, diags, sources } => {
            let r = keep(&text, diags, sources);
            let d = Diagnostic::error(
                "E0857",
                format!(
                    "no usable conflict for case {} after {} conflict call(s); nothing written to {}",
                    case.id,
                    run.conflict_replies.len(),
                    out.display()
                ),
            )
            .help(format!("{}; the scene checked, only its conflict is missing", where_(r)));
            fail(d, &SourceMap::default())
        }
        Outcome::Failed(d) => {
            print_diags(&[d], &SourceMap::default(), human);
            // A failure mid-way still leaves the last attempt to look at.
            let last = run.merged.last().or(run.scene.as_ref()).or(run.attempts.last());
            if let Some(last) = last
                && rocc::files::write_atomic(&rejected, |w| std::io::Write::write_all(w, last.as_bytes())).is_ok()
            {
                eprintln!("the last attempt is kept in {}", rejected.display());
            }
            ExitCode::FAILURE
        }
    }
}

fn explain(code: Option<&str>) -> ExitCode {
    match code {
        None => {
            for c in codes::CODES {
                outln!("{}  {}", c.code, c.title);
            }
            ExitCode::SUCCESS
        }
        Some(code) => match codes::lookup(code) {
            Some(c) => {
                outln!("{}: {}\n\n{}", c.code, c.title, c.explanation);
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
    use rocc::compile::StaticBev;
    use rocc::import::{Convention, import_boxes, scenario_name};
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
            if let Err(e) = rocc::files::write_atomic(out, |w| std::io::Write::write_all(w, text.as_bytes())) {
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

/// `rocc ciren import | import-safe`: every input is imported on its own; a failure is reported
/// and the batch goes on; the exit status is 1 if any input failed.
fn ciren_import(inputs: Vec<Result<PathBuf, Diagnostic>>, out: &Path, safe: bool) -> ExitCode {
    use rocc::ciren;
    let (mut ok, mut failed) = (0, 0);
    let mut written: Vec<String> = Vec::new();
    for input in inputs {
        let path = match input {
            Ok(p) => p,
            Err(_) => {
                failed += 1;
                continue;
            }
        };
        let mut sources = SourceMap::default();
        let result =
            if safe { ciren::import_safe(&path, &mut sources) } else { ciren::import_case(&path, &mut sources) };
        match result {
            Ok(imp) => {
                print_diags(&imp.warnings, &sources, MessageFormat::Human);
                let name = imp.file_name();
                if written.contains(&name) {
                    let d = Diagnostic::error(
                        "E0809",
                        format!("`{}`: case {} was already imported in this batch", path.display(), imp.crash.id),
                    )
                    .help("two inputs with one case id would write the same file; pass each case once");
                    print_diags(&[d], &sources, MessageFormat::Human);
                    failed += 1;
                    continue;
                }
                match ciren::write_scenario(out, &imp) {
                    Ok(p) => {
                        ok += 1;
                        written.push(name);
                        let k = &imp.crash.conflict;
                        eprintln!(
                            "ok  {} -> {}: {}'s {} into {} ({}{}), latched at {:.1} s",
                            path.display(),
                            p.display(),
                            k.at_fault,
                            k.face.name(),
                            k.struck,
                            rocc::ciren::crash::impact_name(k.impact),
                            if k.impact == rocc::check::scenario::Impact::Object {
                                String::new()
                            } else {
                                format!(", {} side", imp.staged.struck_side.name())
                            },
                            imp.staged.time
                        );
                    }
                    Err(d) => {
                        failed += 1;
                        print_diags(&[d], &sources, MessageFormat::Human);
                    }
                }
            }
            Err(diags) => {
                failed += 1;
                print_diags(&diags, &sources, MessageFormat::Human);
                eprintln!("skip {}: nothing written", path.display());
            }
        }
    }
    eprintln!("{ok} imported, {failed} failed -> {}", out.display());
    if failed > 0 { ExitCode::FAILURE } else { ExitCode::SUCCESS }
}

/// `rocc edit`'s clip options, as given.
struct ClipEditArgs {
    frames: Option<String>,
    scenario: Option<PathBuf>,
    weights: Option<PathBuf>,
    grounded_config: Option<PathBuf>,
}

fn edit(
    target: &Path,
    insert: &[String],
    delete: &[String],
    move_: &[String],
    args: ClipEditArgs,
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
        match rocc::edit::edit_clip(
            target,
            &edits,
            &ClipEdit {
                scenario: args.scenario,
                frames: args.frames,
                rig,
                weights: args.weights,
                grounded_config: args.grounded_config,
            },
        ) {
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
                match rocc::files::write_atomic(dest, |w| std::io::Write::write_all(w, text.as_bytes())) {
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
                outln!("{}", serde_json::to_string_pretty(&s).expect("scores are plain numbers"));
                ExitCode::SUCCESS
            }
            Ok(s) => {
                out!("{}", s.table());
                ExitCode::SUCCESS
            }
            Err(d) => fail(d),
        },
        EvalCmd::Lidar { pred, gt, range_filter, json } => match rocc::eval::score_lidar_dirs(&pred, &gt, range_filter)
        {
            Ok(s) if json => {
                outln!("{}", serde_json::to_string_pretty(&s).expect("scores are plain numbers"));
                ExitCode::SUCCESS
            }
            Ok(s) => {
                outln!(
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
                    outln!("{}", serde_json::to_string_pretty(&s).expect("scores are plain numbers"));
                    ExitCode::SUCCESS
                }
                Ok(s) => {
                    out!("{}", s.table());
                    ExitCode::SUCCESS
                }
                Err(d) => fail(d),
            }
        }
    }
}
