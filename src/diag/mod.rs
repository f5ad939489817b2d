//! Diagnostics as plain data. Every pass returns `Diagnostic`s; the CLI renders them with miette
//! (terminal) or as JSON lines (the LLM repair loop). In: pass errors. Out: text for people and
//! machines.

pub mod codes;

use crate::source::{SourceMap, Span};
use serde::Serialize;
use std::fmt;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Error,
    Warning,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Label {
    pub span: Span,
    pub text: String,
    /// The primary label is the place the error is; secondary ones give context.
    pub primary: bool,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    pub code: &'static str,
    pub severity: Severity,
    pub message: String,
    pub labels: Vec<Label>,
    /// What to do about it: one hint a line, the main one first (`and_help` adds a line). Kept
    /// as one string so that a `Diagnostic` stays small enough to return by value.
    pub help: Option<String>,
}

impl Diagnostic {
    pub fn error(code: &'static str, message: impl Into<String>) -> Self {
        debug_assert!(codes::lookup(code).is_some(), "unregistered diagnostic code {code}");
        Diagnostic { code, severity: Severity::Error, message: message.into(), labels: vec![], help: None }
    }
    pub fn warning(code: &'static str, message: impl Into<String>) -> Self {
        Diagnostic { severity: Severity::Warning, ..Self::error(code, message) }
    }
    pub fn label(mut self, span: Span, text: impl Into<String>) -> Self {
        let primary = self.labels.is_empty();
        self.labels.push(Label { span, text: text.into(), primary });
        self
    }
    pub fn help(mut self, text: impl Into<String>) -> Self {
        self.help = Some(text.into());
        self
    }
    /// A further hint, rendered on a line of its own after the others: where two things are
    /// worth saying (close the block; and where the statement after it begins).
    pub fn and_help(mut self, text: impl Into<String>) -> Self {
        let text = text.into();
        self.help = Some(match self.help.take() {
            Some(help) => format!("{help}\n{text}"),
            None => text,
        });
        self
    }
    /// Every hint, the main one first.
    pub fn hints(&self) -> impl Iterator<Item = &str> {
        self.help.iter().flat_map(|h| h.lines())
    }
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
    /// The span of the primary label, if any.
    pub fn span(&self) -> Option<Span> {
        self.labels.first().map(|l| l.span)
    }

    /// A miette report carrying the source of the primary label's file.
    pub fn to_report(&self, sources: &SourceMap) -> miette::Report {
        let file = self.span().map(|s| s.file).unwrap_or(0);
        let src = sources.files.get(file as usize);
        let rendered = Rendered {
            code: self.code,
            severity: self.severity,
            message: self.message.clone(),
            help: self.help.clone(),
            labels: self
                .labels
                .iter()
                .filter(|l| l.span.file == file)
                .map(|l| {
                    let text = if l.text.is_empty() { None } else { Some(l.text.clone()) };
                    if l.primary {
                        miette::LabeledSpan::new_primary_with_span(text, l.span.range())
                    } else {
                        miette::LabeledSpan::new_with_span(text, l.span.range())
                    }
                })
                .collect(),
            // Labels in other files (an imported kind file) are named in the help instead.
            foreign: self
                .labels
                .iter()
                .filter(|l| l.span.file != file)
                .map(|l| {
                    let (line, col) = sources.line_col(l.span.file, l.span.start as usize);
                    format!("{} at {}:{line}:{col}", l.text, sources.get(l.span.file).name)
                })
                .collect(),
            source: src.map(|s| miette::NamedSource::new(s.name.clone(), s.text.clone())),
        };
        miette::Report::new(rendered)
    }

    /// One JSON object: what the LLM repair loop sends back to a model.
    pub fn to_json(&self, sources: &SourceMap) -> serde_json::Value {
        let loc = |span: &Span| {
            let (line, col) = sources.line_col(span.file, span.start as usize);
            let (end_line, end_col) = sources.line_col(span.file, span.end as usize);
            serde_json::json!({
                "file": sources.files.get(span.file as usize).map(|f| f.name.as_str()),
                "start": span.start, "end": span.end,
                "line": line, "col": col, "end_line": end_line, "end_col": end_col,
            })
        };
        let primary = self.span();
        serde_json::json!({
            "code": self.code,
            "severity": self.severity,
            "message": self.message,
            "file": primary.and_then(|s| sources.files.get(s.file as usize)).map(|f| f.name.as_str()),
            "span": primary.map(|s| loc(&s)),
            "labels": self.labels.iter().map(|l| serde_json::json!({
                "text": l.text, "primary": l.primary, "span": loc(&l.span)
            })).collect::<Vec<_>>(),
            "help": self.help,
        })
    }

    /// Plain text with no colours or box drawing: used by snapshot tests and non-tty output.
    pub fn render_plain(&self, sources: &SourceMap) -> String {
        let handler = miette::GraphicalReportHandler::new_themed(miette::GraphicalTheme::unicode_nocolor())
            .with_width(100)
            .with_links(false);
        let mut out = String::new();
        let report = self.to_report(sources);
        handler.render_report(&mut out, report.as_ref()).expect("writing to a String cannot fail");
        out
    }
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}[{}]: {}", if self.is_error() { "error" } else { "warning" }, self.code, self.message)
    }
}

#[derive(Debug)]
struct Rendered {
    code: &'static str,
    severity: Severity,
    message: String,
    help: Option<String>,
    labels: Vec<miette::LabeledSpan>,
    foreign: Vec<String>,
    source: Option<miette::NamedSource<String>>,
}

impl fmt::Display for Rendered {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Rendered {}

impl miette::Diagnostic for Rendered {
    fn code<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        Some(Box::new(self.code))
    }
    fn severity(&self) -> Option<miette::Severity> {
        Some(match self.severity {
            Severity::Error => miette::Severity::Error,
            Severity::Warning => miette::Severity::Warning,
        })
    }
    fn help<'a>(&'a self) -> Option<Box<dyn fmt::Display + 'a>> {
        let mut parts: Vec<String> = self.help.iter().cloned().collect();
        parts.extend(self.foreign.iter().cloned());
        parts.push(format!("`rocc explain {}` explains this error", self.code));
        Some(Box::new(parts.join("\n")))
    }
    fn source_code(&self) -> Option<&dyn miette::SourceCode> {
        self.source.as_ref().map(|s| s as &dyn miette::SourceCode)
    }
    fn labels(&self) -> Option<Box<dyn Iterator<Item = miette::LabeledSpan> + '_>> {
        if self.labels.is_empty() { None } else { Some(Box::new(self.labels.iter().cloned())) }
    }
}

/// The result of a pass that can fail with several diagnostics at once.
pub type Result<T> = std::result::Result<T, Vec<Diagnostic>>;

/// Edit distance for "did you mean" suggestions.
pub fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut cur = vec![0; b.len() + 1];
    for (i, ca) in a.chars().enumerate() {
        cur[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    prev[b.len()]
}

/// Optimal-string-alignment distance: Levenshtein plus the swap of two adjacent characters as
/// one edit, the commonest typing slip (`agnet` for `agent`).
pub fn osa_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    // Three rows: i-2, i-1 and i.
    let mut before: Vec<usize> = vec![0; b.len() + 1];
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut cur = vec![0; b.len() + 1];
    for i in 0..a.len() {
        cur[0] = i + 1;
        for j in 0..b.len() {
            let mut d = (prev[j] + usize::from(a[i] != b[j])).min(prev[j + 1] + 1).min(cur[j] + 1);
            if i > 0 && j > 0 && a[i] == b[j - 1] && a[i - 1] == b[j] {
                d = d.min(before[j - 1] + 1);
            }
            cur[j + 1] = d;
        }
        std::mem::swap(&mut before, &mut prev);
        std::mem::swap(&mut prev, &mut cur);
    }
    prev[b.len()]
}

/// The closest candidate within an edit distance of a third of the word's length (at least
/// one): a slip of a letter or two, never a word that merely shares some letters (`lights` is
/// three edits from `height`, half the word, and gets no suggestion).
pub fn suggest<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let limit = (word.chars().count() / 3).max(1);
    candidates
        .into_iter()
        .filter(|c| *c != word)
        .map(|c| (osa_distance(word, c), c))
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, c)| (*d, *c))
        .map(|(_, c)| c)
}

/// `help` text for an unknown name: "did you mean `x`?" or the list of what is allowed.
pub fn did_you_mean(word: &str, candidates: &[&str], what: &str) -> String {
    match suggest(word, candidates.iter().copied()) {
        Some(s) => format!("did you mean `{s}`?"),
        None if candidates.is_empty() => format!("no {what} is defined here"),
        None if candidates.len() <= 12 => {
            format!("expected one of {}", candidates.iter().map(|c| format!("`{c}`")).collect::<Vec<_>>().join(", "))
        }
        None => format!("see `rocc explain` for the list of {what}s"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggestions_find_close_words_only() {
        assert_eq!(suggest("frnt", ["front", "ego", "rear"]), Some("front"));
        assert_eq!(suggest("sidewlk", ["sidewalks", "crosswalks"]), Some("sidewalks"));
        assert_eq!(suggest("xyz", ["front", "ego"]), None);
        assert_eq!(levenshtein("kitten", "sitting"), 3);
        // A transposition is one edit, so short words get their suggestion too.
        assert_eq!(osa_distance("agnet", "agent"), 1);
        assert_eq!(osa_distance("ca", "abc"), 3);
        assert_eq!(osa_distance("kitten", "sitting"), 3);
        assert_eq!(osa_distance("", "abc"), 3);
        assert_eq!(suggest("agnet", ["agent", "object", "row"]), Some("agent"));
        assert_eq!(suggest("laens", ["lanes", "length"]), Some("lanes"));
    }

    #[test]
    fn unrelated_words_get_no_suggestion() {
        assert_eq!(osa_distance("lights", "height"), 3);
        assert_eq!(suggest("lights", ["at", "speed", "length", "width", "height", "goal", "track"]), None);
        assert_eq!(suggest("colour", ["color", "motion"]), Some("color"));
        assert_eq!(suggest("speeed", ["speed", "seed"]), Some("speed"));
    }

    #[test]
    fn further_hints_render_one_a_line_after_the_first() {
        let mut sources = SourceMap::default();
        let file = sources.add("t.scn", "scenario s {}\n");
        let d = Diagnostic::error("E0001", "m").label(Span::new(file, 0, 8), "here").help("first").and_help("second");
        assert_eq!(d.hints().collect::<Vec<_>>(), ["first", "second"]);
        let text = d.render_plain(&sources);
        let (first, second) = (text.find("help: first").expect("first"), text.find("second").expect("second"));
        assert!(first < second && text[first..second].matches('\n').count() == 1, "{text}");
        assert_eq!(d.to_json(&sources)["help"], "first\nsecond");
    }
}
