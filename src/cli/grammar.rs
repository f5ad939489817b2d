//! `rocc grammar`: the language grammar for grammar-constrained LLM decoding.

use super::Failure;
use clap::ValueEnum;
use rocc::grammar::{Format, export};

#[derive(clap::Args)]
pub struct Args {
    /// `gbnf`: llama.cpp and vLLM (xgrammar); `lark`: llguidance and vLLM's guidance backend.
    #[arg(long, value_enum, default_value = "gbnf")]
    format: GrammarFormat,
}

#[derive(Clone, Copy, ValueEnum)]
enum GrammarFormat {
    Gbnf,
    Lark,
}

pub fn run(a: Args) -> Result<(), Failure> {
    out!(
        "{}",
        export(match a.format {
            GrammarFormat::Gbnf => Format::Gbnf,
            GrammarFormat::Lark => Format::Lark,
        })
    )
}
