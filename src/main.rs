//! The `rocc` command line. Each subcommand is a thin shell over one library entry point.

use clap::{Parser, Subcommand, ValueEnum};
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
    /// Explain a diagnostic code (`rocc explain E0107`); without a code, list them all.
    Explain { code: Option<String> },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.cmd {
        Cmd::Check { files, message_format } => check(&files, message_format),
        Cmd::Fmt { files, check } => fmt(&files, check),
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
        match rocc::check::check_path(f, &mut sources) {
            Ok(s) => {
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
