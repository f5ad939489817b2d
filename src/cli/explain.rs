//! `rocc explain`: the explanation of one diagnostic code, or the list of them all.

use super::Failure;
use rocc::diag::codes;

#[derive(clap::Args)]
pub struct Args {
    code: Option<String>,
}

pub fn run(a: Args) -> Result<(), Failure> {
    let Some(code) = a.code else {
        for c in codes::all() {
            outln!("{}  {}", c.code, c.title)?;
        }
        return Ok(());
    };
    match codes::lookup(&code) {
        Some(c) => outln!("{}: {}\n\n{}", c.code, c.title, c.explanation),
        None => {
            // A usage slip, not a diagnostic of its own: it has no code to explain.
            eprintln!("error: `{code}` is not a rocc diagnostic code; `rocc explain` lists them");
            Err(Failure::shown())
        }
    }
}
