//! `rocc edit`: insert, delete or move boxes of a compiled clip (and rerun the stages after the
//! BEV) or of a `.scn` file.

use super::{Failure, write_file};
use rocc::diag::Diagnostic;
use rocc::edit::{ClipEdit, Edit, parse_edit};
use rocc::lidar::Rig;
use rocc::source::SourceMap;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
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
}

pub fn run(a: Args) -> Result<(), Failure> {
    let edits = edits(&a)?;
    if a.target.is_dir() {
        let rig = a.rig.as_deref().map(|r| Rig::load(Some(r), None)).transpose()?;
        let opts = ClipEdit {
            scenario: a.scenario,
            frames: a.frames,
            rig,
            weights: a.weights,
            grounded_config: a.grounded_config,
        };
        let m = rocc::edit::edit_clip(&a.target, &edits, &opts)?;
        eprintln!("edited {} ({} frames): {}", a.target.display(), m.frames.len(), m.edits.join("; "));
        return Ok(());
    }
    let mut sources = SourceMap::default();
    let text = match rocc::edit::edit_scn(&a.target, &edits, &mut sources) {
        Ok(t) => t,
        Err(d) => return Err(Failure::with_sources(d, sources)),
    };
    let dest = a.out.as_deref().unwrap_or(&a.target);
    write_file(dest, text.as_bytes())
        .map_err(|e| Diagnostic::error("E0401", format!("cannot write `{}`: {e}", dest.display())))?;
    eprintln!("edited {} -> {}", a.target.display(), dest.display());
    Ok(())
}

/// The edits in the order given: inserts, deletes, moves.
fn edits(a: &Args) -> Result<Vec<Edit>, Diagnostic> {
    let parsed = (!a.insert.is_empty())
        .then(|| parse_edit("insert", &a.insert))
        .into_iter()
        .chain(a.delete.iter().map(|d| parse_edit("delete", std::slice::from_ref(d))))
        .chain((!a.move_.is_empty()).then(|| parse_edit("move", &a.move_)));
    let edits = parsed.collect::<Result<Vec<Edit>, Diagnostic>>()?;
    if edits.is_empty() {
        return Err(Diagnostic::error("E0717", "no edit given")
            .help("add `--insert KIND at X,Y yaw A`, `--delete AGENT` or `--move AGENT by DX,DY`"));
    }
    Ok(edits)
}
