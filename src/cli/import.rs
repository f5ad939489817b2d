//! `rocc import boxes`: recorded per-frame boxes to a `.scn` whose agents replay their tracks.

use super::{Failure, show, write_file};
use clap::{Subcommand, ValueEnum};
use rocc::compile::StaticBev;
use rocc::diag::Diagnostic;
use rocc::import::{Convention, import_boxes, scenario_name};
use rocc::source::SourceMap;
use std::path::PathBuf;

#[derive(Subcommand)]
pub enum ImportCmd {
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

#[derive(Clone, Copy, ValueEnum)]
pub enum ConventionArg {
    Nuscenes,
    Mmdet3d,
    Nuplan,
}

pub fn run(what: ImportCmd) -> Result<(), Failure> {
    let ImportCmd::Boxes { file, convention, out, static_bev } = what;
    let conv = match convention {
        ConventionArg::Nuscenes => Convention::NuScenes,
        ConventionArg::Mmdet3d => Convention::Mmdet3d,
        ConventionArg::Nuplan => Convention::NuPlan,
    };
    if let Some(p) = &static_bev {
        StaticBev::load(p)?;
    }
    let mut sources = SourceMap::default();
    let imp = match import_boxes(&file, conv, &scenario_name(&out), &mut sources) {
        Ok(imp) => imp,
        Err(d) => return Err(Failure::with_sources(d, sources)),
    };
    show(&imp.warnings, &sources);
    let mut text = imp.text;
    if let Some(p) = &static_bev {
        text = format!("// Map layers: compile with `--static-bev {}`.\n{text}", p.display());
    }
    write_file(&out, text.as_bytes()).map_err(|e| {
        Diagnostic::error("E0401", format!("cannot write `{}`: {e}", out.display()))
            .help("check the directory exists and is writable")
    })?;
    eprintln!(
        "imported {} frame(s), {} replayed agent(s) -> {}",
        imp.recorded.frames.len(),
        imp.agents.len(),
        out.display()
    );
    Ok(())
}
