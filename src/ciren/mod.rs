//! Crash recreation from NHTSA CIREN cases (`rocc ciren`). In: a CIREN case record
//! (`crash_report.xml`, coded fields plus the `Summary` narrative) or a SAFE-format VLM
//! extraction (`*.json`). Out: `.scn` text with the road, the vehicles, their pre-crash motion and
//! a `conflict` whose struck side and striking face are the coded ones, comments citing the
//! source fields; or a diagnostic saying exactly why the case cannot be represented.
//!
//! `case.rs` reads the XML into a plain `CirenCase`; `narrative.rs` reads the Summary with fixed
//! rules; `record/` maps a case (field decoders, a pair of vehicles, a vehicle and an object),
//! and `safe/` a SAFE extraction (its `point_of_impact` rules in `safe/poi.rs`), to a plain `Crash`
//! (`crash.rs`); `emit.rs` writes the `.scn` and keeps it only once the checker and the rollout
//! agree that the latched contact is on the coded sides; `slide.rs` places a fixed object struck on
//! the slide after an impact where that slide goes. The VLM route (`extract.rs`) sends the sketch and summary to a vision model, checks and
//! repairs the scene like `rocc text`, and merges the conflict of a separate greedy call by span
//! (`descriptor.rs`).

pub mod case;
pub mod crash;
pub mod descriptor;
pub mod emit;
pub mod extract;
pub mod impact;
pub mod narrative;
pub mod record;
pub mod safe;
mod slide;

pub use case::{CirenCase, read_case};
pub use crash::Crash;
pub use emit::{Staged, emit};
pub use slide::stage;

use crate::diag::Diagnostic;
use crate::source::SourceMap;
use std::path::{Path, PathBuf};

/// An imported case: the crash description, the verified `.scn` text and the warnings.
#[derive(Clone, Debug)]
pub struct Imported {
    pub crash: Crash,
    pub staged: Staged,
    pub warnings: Vec<Diagnostic>,
}

impl Imported {
    /// `<id>.scn` for a CIREN record, `safe_<id>.scn` for a SAFE extraction.
    pub fn file_name(&self) -> String {
        format!("{}.scn", self.crash.file_stem())
    }
}

/// Read, map, emit and verify one CIREN case (a case directory or its XML file).
pub fn import_case(path: &Path, sources: &mut SourceMap) -> Result<Imported, Vec<Diagnostic>> {
    let (case, file) = read_case(path, sources)?;
    let mapped = record::map_case(&case, file)?;
    let staged = stage(&mapped.crash)?;
    let mut warnings = mapped.warnings;
    for s in &staged.shortfalls {
        warnings.push(Diagnostic::warning("E0806", format!("case {}: {s}", case.id)).help(
            "the sides and the clock direction are met; the rollout's staging sets the striker's speed in \
                 its last seconds, so the closing speed is the staging's",
        ));
    }
    Ok(Imported { crash: mapped.crash, staged, warnings })
}

/// Read, map, emit and verify one SAFE extraction (`*.json`).
pub fn import_safe(path: &Path, sources: &mut SourceMap) -> Result<Imported, Vec<Diagnostic>> {
    let (crash, warnings) = safe::read_safe(path, sources)?;
    let staged = stage(&crash)?;
    Ok(Imported { crash, staged, warnings })
}

/// The cases named by the command line: a case directory (holding `crash_report.xml`), an XML
/// file, or a directory of case directories (searched one level down, sorted). Inputs that name
/// no case come back as diagnostics.
pub fn case_inputs(inputs: &[PathBuf]) -> (Vec<PathBuf>, Vec<Diagnostic>) {
    let mut out = Vec::new();
    let mut errs = Vec::new();
    for p in inputs {
        if p.is_file() || p.join("crash_report.xml").is_file() {
            out.push(p.clone());
            continue;
        }
        if p.is_dir() {
            let mut sub: Vec<PathBuf> = std::fs::read_dir(p)
                .map(|rd| {
                    rd.filter_map(|e| e.ok().map(|e| e.path()))
                        .filter(|q| q.join("crash_report.xml").is_file())
                        .collect()
                })
                .unwrap_or_default();
            sub.sort();
            if sub.is_empty() {
                errs.push(
                    Diagnostic::error(
                        "E0800",
                        format!(
                            "`{}` holds no CIREN case (no `crash_report.xml` in it or its subdirectories)",
                            p.display()
                        ),
                    )
                    .help("pass case directories (`ciren/100237`), their parent, or XML files"),
                );
            }
            out.extend(sub);
            continue;
        }
        errs.push(
            Diagnostic::error("E0800", format!("cannot read `{}`: no such file or directory", p.display()))
                .help("check the path"),
        );
    }
    (out, errs)
}

/// Write `DIR/<id>.scn` (`DIR/safe_<id>.scn`) atomically (a temporary name, then a rename: never a partial file).
pub fn write_scenario(dir: &Path, imp: &Imported) -> Result<PathBuf, Diagnostic> {
    let path = dir.join(imp.file_name());
    crate::fsio::write_atomic(&path, |w| std::io::Write::write_all(w, imp.staged.text.as_bytes())).map_err(|e| {
        Diagnostic::error("E0809", format!("cannot write `{}`: {e}", path.display()))
            .help("check that the output directory is writable")
    })?;
    Ok(path)
}
