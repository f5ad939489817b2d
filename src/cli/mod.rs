//! The subcommands of `rocc`, one module each: a module parses its command's options, calls the
//! library and says what it did. What they share lives here: stdout that a closed pipe ends
//! quietly, how diagnostics are shown, and the one way a command fails (`Failure`, `exit`).

use rocc::diag::Diagnostic;
use rocc::source::SourceMap;
use std::io::IsTerminal;
use std::path::Path;
use std::process::ExitCode;

/// Write to stdout through a locked handle; evaluates to `Result<(), Failure>`. A reader that has
/// gone away (`rocc explain | head`) ends the command quietly with success, as `cat` would; any
/// other write failure fails the command. `println!` would panic on either.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::cli::stdout_write(format_args!($($arg)*))
    };
}

macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::cli::stdout_write(format_args!("{}\n", format_args!($($arg)*)))
    };
}

pub mod check;
pub mod ciren;
pub mod compile;
pub mod edit;
pub mod eval;
pub mod explain;
pub mod fmt;
pub mod grammar;
pub mod import;
mod llm;
pub mod test;
mod test_junit;
pub mod text;
pub mod train;

/// Why a command failed: the diagnostics still to show, with the sources their spans point
/// into. Empty when every diagnostic was shown as the command went (a batch reports each input
/// and fails at the end if any failed).
pub struct Failure {
    diags: Vec<Diagnostic>,
    sources: SourceMap,
}

impl Failure {
    /// A failure whose diagnostics have all been shown.
    pub fn shown() -> Self {
        Failure { diags: Vec::new(), sources: SourceMap::default() }
    }

    pub fn with_sources(diags: Vec<Diagnostic>, sources: SourceMap) -> Self {
        Failure { diags, sources }
    }
}

impl From<Diagnostic> for Failure {
    fn from(d: Diagnostic) -> Self {
        Failure::from(vec![d])
    }
}

impl From<Vec<Diagnostic>> for Failure {
    fn from(diags: Vec<Diagnostic>) -> Self {
        Failure::with_sources(diags, SourceMap::default())
    }
}

/// The one way every command ends: success, or its failure shown as miette reports on stderr
/// and exit status 1.
pub fn exit(done: Result<(), Failure>) -> ExitCode {
    match done {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            show(&f.diags, &f.sources);
            ExitCode::FAILURE
        }
    }
}

/// Diagnostics on stderr: miette's graphical report on a terminal, its plain rendering otherwise
/// (what the tests read).
pub fn show(diags: &[Diagnostic], sources: &SourceMap) {
    for d in diags {
        if std::io::stderr().is_terminal() {
            eprintln!("{:?}", d.to_report(sources));
        } else {
            eprint!("{}", d.render_plain(sources));
        }
    }
}

pub fn stdout_write(args: std::fmt::Arguments) -> Result<(), Failure> {
    use std::io::Write;
    let mut lock = std::io::stdout().lock();
    match lock.write_fmt(args).and_then(|()| lock.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(0),
        Err(e) => Err(Diagnostic::error("E0401", format!("cannot write to stdout: {e}")).into()),
    }
}

/// Write `bytes` to `path` atomically (`rocc::fsio::write_atomic`).
pub fn write_file(path: &Path, bytes: &[u8]) -> std::io::Result<u64> {
    rocc::fsio::write_atomic(path, |w| std::io::Write::write_all(w, bytes))
}
