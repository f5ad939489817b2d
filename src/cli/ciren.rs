//! `rocc ciren import | import-safe | extract`: NHTSA CIREN crashes to checked scenarios, from
//! coded case records, from SAFE-format extractions, or from a case's sketch and summary through
//! a vision model.

use super::llm::{Dest, LlmArgs};
use super::{Failure, show};
use clap::Subcommand;
use rocc::check::scenario::Impact;
use rocc::ciren::extract::{self, Outcome};
use rocc::ciren::{self, Imported};
use rocc::diag::Diagnostic;
use rocc::source::SourceMap;
use std::path::{Path, PathBuf};

/// `rocc ciren ...`: crash recreation from NHTSA CIREN cases (one variant per route).
#[derive(Subcommand)]
pub enum CirenCmd {
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
    #[command(
        mut_arg("server", |a| a.help("Server dialect: how grammar and JSON-schema constraints are sent")),
        mut_arg("max_repairs", |a| a.help("Repair rounds for the scene, and extra conflict calls for the conflict")),
        mut_arg("seed", |a| a.help("Scenario seed (default: the case number); also sent as the sampling seed")),
        mut_arg("timeout", |a| a.default_value("180")),
        mut_arg("temperature", |a| a.help("Sampling temperature of the scene call; the conflict call is always 0")),
        mut_arg("transcript", |a| a.help("Save every request (images shortened) and reply as OUT.transcript.json")),
    )]
    Extract {
        /// The case folder: sketch.jpeg (or Sketch.jpg) and crash_report.xml (or Summary.txt).
        case: PathBuf,
        /// The `.scn` file to write (atomically, only once it checks with its conflict).
        #[arg(short, long)]
        out: PathBuf,
        #[command(flatten)]
        llm: LlmArgs,
        /// Worked examples: every `.scn` of this directory instead of the bundled prompts/ciren/.
        #[arg(long, display_order = 35)]
        examples: Option<PathBuf>,
    },
}

pub fn run(what: CirenCmd) -> Result<(), Failure> {
    match what {
        CirenCmd::Import { inputs, out } => {
            let (cases, errs) = ciren::case_inputs(&inputs);
            show(&errs, &SourceMap::default());
            import_all(&cases, &out, ciren::import_case, errs.len())
        }
        CirenCmd::ImportSafe { files, out } => import_all(&files, &out, ciren::import_safe, 0),
        CirenCmd::Extract { case, out, llm, examples } => extract_case(&case, &out, &llm, examples.as_deref()),
    }
}

type Importer = fn(&Path, &mut SourceMap) -> Result<Imported, Vec<Diagnostic>>;

/// Import every input on its own: a failure is reported and the batch goes on, failing at the
/// end if any input (or any of the `failed` that never became an input) failed.
fn import_all(inputs: &[PathBuf], out: &Path, import: Importer, mut failed: usize) -> Result<(), Failure> {
    let mut ok = 0;
    let mut written: Vec<String> = Vec::new();
    for path in inputs {
        let mut sources = SourceMap::default();
        let imp = match import(path, &mut sources) {
            Ok(imp) => imp,
            Err(diags) => {
                failed += 1;
                show(&diags, &sources);
                eprintln!("skip {}: nothing written", path.display());
                continue;
            }
        };
        show(&imp.warnings, &sources);
        let name = imp.file_name();
        if written.contains(&name) {
            let d = Diagnostic::error(
                "E0809",
                format!("`{}`: case {} was already imported in this batch", path.display(), imp.crash.id),
            )
            .help("two inputs with one case id would write the same file; pass each case once");
            show(&[d], &sources);
            failed += 1;
            continue;
        }
        match ciren::write_scenario(out, &imp) {
            Ok(p) => {
                ok += 1;
                written.push(name);
                eprintln!("ok  {} -> {}: {}", path.display(), p.display(), what_happened(&imp));
            }
            Err(d) => {
                failed += 1;
                show(&[d], &sources);
            }
        }
    }
    eprintln!("{ok} imported, {failed} failed -> {}", out.display());
    if failed > 0 { Err(Failure::shown()) } else { Ok(()) }
}

/// Who struck whom with what, and when the crash latches.
fn what_happened(imp: &Imported) -> String {
    let k = &imp.crash.conflicts[0];
    let more = match imp.crash.conflicts.len() {
        1 => String::new(),
        n => format!(", then {} more", n - 1),
    };
    format!(
        "{}'s {} into {} ({}{}), impact at {:.1} s{more}",
        k.at_fault,
        k.face.name(),
        k.struck,
        ciren::crash::impact_name(k.impact),
        if k.impact == Impact::Object { String::new() } else { format!(", {} side", imp.staged.struck_side.name()) },
        imp.staged.time
    )
}

/// `rocc ciren extract`: like `rocc text`, the output is written only once it checks (with its
/// conflict); a failure keeps OUT.rejected.scn.
fn extract_case(case_dir: &Path, out: &Path, llm: &LlmArgs, examples: Option<&Path>) -> Result<(), Failure> {
    let client = llm.client()?;
    let examples = examples.map(extract::load_examples).transpose()?.unwrap_or_else(extract::builtin_examples);
    let case = extract::read_case(case_dir).map_err(|e| Failure::with_sources(vec![e.diag], e.sources))?;
    let seed = llm.seed;
    let opts = extract::Options { client, max_repairs: llm.max_repairs, constrain: llm.constrain(), seed, examples };
    let dest = Dest::new(out);
    let (outcome, run) = extract::extract(&case, &opts, &dest.name(), dest.base());
    if llm.transcript {
        dest.transcript(&run.transcript(&case, &opts, seed.unwrap_or_else(|| extract::default_seed(&case.id))));
    }
    let scene_repairs = run.attempts.len().saturating_sub(1);
    match outcome {
        Outcome::Accepted { text } => {
            dest.accept(&text)?;
            let block = run.descriptor.as_ref().map(|d| d.block()).unwrap_or_default();
            eprintln!(
                "wrote {} ({} request(s), {scene_repairs} scene repair round(s), {} conflict call(s)): {block}",
                out.display(),
                run.exchanges.len(),
                run.conflict_replies.len()
            );
            Ok(())
        }
        Outcome::SceneRejected { text, diags, sources } => {
            let kept = dest.reject(&text, diags, sources);
            Err(Diagnostic::error(
                "E0856",
                format!(
                    "the scene extracted from case {} still fails to check after {scene_repairs} repair round(s); nothing written to {}",
                    case.id,
                    out.display()
                ),
            )
            .help(format!("{kept}; raise --max-repairs or use a stronger model"))
            .into())
        }
        Outcome::ConflictRejected { text, diags, sources } => {
            let kept = dest.reject(&text, diags, sources);
            Err(Diagnostic::error(
                "E0857",
                format!(
                    "no usable conflict for case {} after {} conflict call(s); nothing written to {}",
                    case.id,
                    run.conflict_replies.len(),
                    out.display()
                ),
            )
            .help(format!("{kept}; the scene checked, only its conflict is missing"))
            .into())
        }
        Outcome::Failed(d) => {
            show(&[d], &SourceMap::default());
            // A failure mid-way still leaves the last attempt to look at.
            dest.keep_last(run.merged.last().or(run.scene.as_ref()).or(run.attempts.last()));
            Err(Failure::shown())
        }
    }
}
