//! `rocc check`: check scenario files and decide each scene as a compile would; print every
//! diagnostic, or a summary of each file that checks.

use super::{Failure, show};
use clap::ValueEnum;
use rocc::check::summary::Summary;
use rocc::diag::Diagnostic;
use rocc::source::SourceMap;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// `json`: one JSON object per line (diagnostics, then a summary per clean file).
    #[arg(long, value_enum, default_value = "human")]
    message_format: MessageFormat,
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq)]
pub(super) enum MessageFormat {
    Human,
    Json,
}

pub fn run(a: Args) -> Result<(), Failure> {
    let mut failed = 0;
    for f in &a.files {
        let mut sources = SourceMap::default();
        match rocc::check::check_path(f, &mut sources).and_then(|s| rocc::compile::front(s, None)) {
            Ok(front) => {
                let summary = Summary::of(&front.scenario);
                let file = f.display().to_string();
                match a.message_format {
                    MessageFormat::Json => outln!("{}", summary.json(&file))?,
                    MessageFormat::Human => outln!("{}", summary.line(&file))?,
                }
            }
            Err(diags) => {
                failed += 1;
                print(&diags, &sources, a.message_format)?;
            }
        }
    }
    if failed == 0 {
        return Ok(());
    }
    if a.message_format == MessageFormat::Human {
        eprintln!("{failed} of {} file(s) failed to check", a.files.len());
    }
    Err(Failure::shown())
}

/// Diagnostics as `format` asks: reports on stderr, or JSON lines on stdout.
fn print(diags: &[Diagnostic], sources: &SourceMap, format: MessageFormat) -> Result<(), Failure> {
    match format {
        MessageFormat::Human => show(diags, sources),
        MessageFormat::Json => {
            for d in diags {
                let mut v = d.to_json(sources);
                v["type"] = "diagnostic".into();
                outln!("{v}")?;
            }
        }
    }
    Ok(())
}
