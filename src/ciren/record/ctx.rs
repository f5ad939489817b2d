//! The mapping's context: the case, its file id for spans, and the warnings collected on the way.

use crate::ciren::case::{CirenCase, Coded};
use crate::ciren::crash::Crash;
use crate::diag::Diagnostic;
use crate::source::Span;

/// Result of mapping: the crash and the warnings (defaults taken, events left out).
pub struct Mapped {
    pub crash: Crash,
    pub warnings: Vec<Diagnostic>,
}

pub(super) struct Ctx<'a> {
    pub case: &'a CirenCase,
    pub file: u32,
    pub warnings: Vec<Diagnostic>,
}

impl Ctx<'_> {
    pub(super) fn span(&self, c: &Coded) -> Span {
        Span::new(self.file, c.range.start, c.range.end)
    }
    /// The start tag of an element (whole elements can span kilobytes).
    pub(super) fn tag_span(&self, r: &std::ops::Range<usize>, tag: &str) -> Span {
        Span::new(self.file, r.start, (r.start + tag.len() + 1).min(r.end))
    }
    pub(super) fn err(&self, code: &'static str, msg: String, at: Option<(Span, &str)>, help: &str) -> Vec<Diagnostic> {
        let mut d = Diagnostic::error(code, format!("case {}: {msg}", self.case.id)).help(help.to_string());
        if let Some((s, t)) = at {
            d = d.label(s, t);
        }
        vec![d]
    }
    pub(super) fn warn(&mut self, msg: String, at: Option<Span>) {
        let mut d = Diagnostic::warning("E0807", format!("case {}: {msg}", self.case.id))
            .help("the choice is written as a comment in the generated file; check it against the case");
        if let Some(s) = at {
            d = d.label(s, "here");
        }
        self.warnings.push(d);
    }
    pub(super) fn unknown(&self, what: &str, c: &Coded, help: &str) -> Vec<Diagnostic> {
        self.err(
            "E0803",
            format!("unknown {what} \"{}\" (value {}, sasCode {})", c.text, c.value, c.sas),
            Some((self.span(c), "not a code rocc maps")),
            help,
        )
    }
}
