//! `rocc text`: a sentence to a checked `.scn` through a language model; the output is written
//! only once it checks, and a failure keeps OUT.rejected.scn.

use super::llm::{Dest, LlmArgs, bad_option};
use super::{Failure, show};
use clap::ValueEnum;
use rocc::diag::Diagnostic;
use rocc::llm::{self, Outcome, Plan};
use rocc::source::SourceMap;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// The scene in words, e.g. "an ambulance through a crowded intersection".
    sentence: String,
    /// The `.scn` file to write (atomically, only once it checks).
    #[arg(short, long)]
    out: PathBuf,
    #[command(flatten)]
    llm: LlmArgs,
    /// Goal stage: one call for all agents, or one per agent with earlier goals in context.
    #[arg(long, value_enum, default_value = "joint", display_order = 15)]
    plan: PlanArg,
    /// Background traffic density 0..1 (overrides the model's choice).
    #[arg(long, display_order = 25)]
    density: Option<f64>,
    /// Background traffic randomness 0..1 (overrides the model's choice).
    #[arg(long, display_order = 26)]
    randomness: Option<f64>,
    /// A sketch (PNG/JPEG/WebP/GIF) sent with the sentence to a vision model (CIREN route).
    #[arg(long, display_order = 45)]
    image: Option<PathBuf>,
}

#[derive(Clone, Copy, ValueEnum)]
enum PlanArg {
    Joint,
    Hierarchical,
}

pub fn run(a: Args) -> Result<(), Failure> {
    let opts = options(&a)?;
    let dest = Dest::new(&a.out);
    let (outcome, run) = llm::text_to_scenario(&a.sentence, &opts, &dest.name(), dest.base());
    show(&run.warnings, &SourceMap::default());
    if a.llm.transcript {
        dest.transcript(&run.transcript(&a.sentence, &opts));
    }
    let repairs = run.attempts.len().saturating_sub(1);
    match outcome {
        Outcome::Accepted { text } => {
            dest.accept(&text)?;
            eprintln!("wrote {} ({} request(s), {repairs} repair round(s))", a.out.display(), run.exchanges.len());
            Ok(())
        }
        Outcome::Rejected { text, diags, sources } => {
            let kept = dest.reject(&text, diags, sources);
            Err(Diagnostic::error(
                "E0613",
                format!(
                    "the generated scenario still fails to check after {repairs} repair round(s); nothing written to {}",
                    a.out.display()
                ),
            )
            .help(format!("{kept}; raise --max-repairs or use a stronger model"))
            .into())
        }
        Outcome::Failed(d) => {
            show(&[d], &SourceMap::default());
            // A failure mid-repair still leaves the last checked attempt to look at.
            dest.keep_last(run.attempts.last());
            Err(Failure::shown())
        }
    }
}

/// The run's options; an option out of range is an E0614.
fn options(a: &Args) -> Result<llm::Options, Diagnostic> {
    for (flag, v) in [("--density", a.density), ("--randomness", a.randomness)] {
        if let Some(v) = v.filter(|v| !(0.0..=1.0).contains(v)) {
            return Err(bad_option(format!("{flag} {v} is outside 0..1"), "a fraction: 0 none, 1 as much as fits"));
        }
    }
    let client = a.llm.client()?;
    let image = a.image.as_deref().map(llm::Image::from_file).transpose()?;
    Ok(llm::Options {
        client,
        plan: match a.plan {
            PlanArg::Joint => Plan::Joint,
            PlanArg::Hierarchical => Plan::Hierarchical,
        },
        max_repairs: a.llm.max_repairs,
        overrides: llm::schema::Overrides { density: a.density, randomness: a.randomness, seed: a.llm.seed },
        constrain: a.llm.constrain(),
        image,
    })
}
