//! The `rocc` command line: parses the arguments and hands each subcommand to its module under
//! `cli/`, a thin shell over one library entry point.

mod cli;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "rocc", version, about = "Compile driving-scenario files (.scn) to BEV, occupancy and LiDAR")]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Parse and check scenario files; print diagnostics.
    Check(cli::check::Args),
    /// Rewrite files in canonical layout (comments kept).
    Fmt(cli::fmt::Args),
    /// Compile scenario files (or directories of them) to BEV, occupancy, LiDAR and previews.
    Compile(cli::compile::Args),
    /// Train the grounded occupancy model on compiled clips or nuPlan-Occ-style data.
    Train(cli::train::Args),
    /// Turn recorded boxes into a scenario: `rocc import boxes FILE --convention nuscenes -o scene.scn`.
    Import {
        #[command(subcommand)]
        what: cli::import::ImportCmd,
    },
    /// Recreate NHTSA CIREN crashes as scenarios: `rocc ciren import cases/ -o scn/`.
    Ciren {
        #[command(subcommand)]
        what: cli::ciren::CirenCmd,
    },
    /// Edit the boxes of a compiled clip (OUT/<scenario>/<ego>) or of a `.scn`, and rerun what follows.
    Edit(cli::edit::Args),
    /// Score predictions against ground truth with the shared scorer, or run the edit protocol.
    Eval {
        #[command(subcommand)]
        what: cli::eval::EvalCmd,
    },
    /// Test a scenario library: judge every `expect` block and compare snapshots (`rocc test scenarios/`).
    Test(cli::test::Args),
    /// Write a checked scenario from a sentence with a language model (OpenAI-compatible server).
    Text(cli::text::Args),
    /// Print the language grammar for grammar-constrained LLM decoding (derived from scn.pest).
    Grammar(cli::grammar::Args),
    /// Explain a diagnostic code (`rocc explain E0107`); without a code, list them all.
    Explain(cli::explain::Args),
}

fn main() -> ExitCode {
    let done = match Cli::parse().cmd {
        Cmd::Check(a) => cli::check::run(a),
        Cmd::Fmt(a) => cli::fmt::run(a),
        Cmd::Compile(a) => cli::compile::run(a),
        Cmd::Train(a) => cli::train::run(a),
        Cmd::Import { what } => cli::import::run(what),
        Cmd::Ciren { what } => cli::ciren::run(what),
        Cmd::Edit(a) => cli::edit::run(a),
        Cmd::Eval { what } => cli::eval::run(what),
        Cmd::Test(a) => cli::test::run(a),
        Cmd::Text(a) => cli::text::run(a),
        Cmd::Grammar(a) => cli::grammar::run(a),
        Cmd::Explain(a) => cli::explain::run(a),
    };
    cli::exit(done)
}
