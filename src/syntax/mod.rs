//! Parse pass. In: `.scn` text. Out: `ast::File`, every node with its byte span, or one E0001
//! diagnostic. Also the formatter (`fmt`), which prints an AST back in canonical layout.

pub mod ast;
mod error;
pub mod fmt;
mod parse;
mod rules;

pub use parse::parse;

use crate::diag::Diagnostic;

/// Format source text; a file that does not parse is returned as its syntax error.
pub fn format_source(text: &str) -> Result<String, Diagnostic> {
    let file = parse(0, text)?;
    Ok(fmt::format_file(&file, text))
}
