//! `rocc fmt`: rewrite scenario files in canonical layout, comments kept; `--check` only lists
//! the files that would change.

use super::{Failure, show, write_file};
use rocc::diag::Diagnostic;
use rocc::source::SourceMap;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct Args {
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// Change nothing; list files that would change and exit 1 if any.
    #[arg(long)]
    check: bool,
}

pub fn run(a: Args) -> Result<(), Failure> {
    let mut bad = 0;
    for f in &a.files {
        let mut sources = SourceMap::default();
        let formatted = match canonical(f, &mut sources) {
            Ok(Some(t)) => t,
            Ok(None) => continue,
            Err(d) => {
                bad += 1;
                show(&[d], &sources);
                continue;
            }
        };
        if a.check {
            outln!("would reformat {}", f.display())?;
            bad += 1;
        } else if let Err(e) = write_file(f, formatted.as_bytes()) {
            show(&[Diagnostic::error("E0401", format!("cannot write {}: {e}", f.display()))], &sources);
            bad += 1;
        } else {
            outln!("formatted {}", f.display())?;
        }
    }
    if bad > 0 { Err(Failure::shown()) } else { Ok(()) }
}

/// The canonical text of `f`, or `None` when it is canonical already.
fn canonical(f: &Path, sources: &mut SourceMap) -> Result<Option<String>, Diagnostic> {
    let text = rocc::check::load::read_source(f)
        .map_err(|m| Diagnostic::error("E0002", m).help("pass a readable UTF-8 `.scn` file"))?;
    let id = sources.add(f.display().to_string(), text.clone());
    let formatted = rocc::syntax::fmt::format_file(&rocc::syntax::parse(id, &text)?, &text);
    Ok((formatted != text).then_some(formatted))
}
