//! `rocc test`'s library side. In: a checked scenario file. Out: a `Report` — every `expect`
//! line judged on the rollout's tracks (`eval`), and the snapshot body (`snapshot`) to compare
//! with `snapshots/<scenario>.snap` beside the file. Only the boxes are read: contacts are
//! overlapping footprints, gaps are distances between footprints, landmarks are stations along
//! the agent's starting lane.

pub mod compare;
pub mod eval;
pub mod geometry;
pub mod snapshot;

use crate::check;
use crate::compile::front;
use crate::diag::Diagnostic;
use crate::source::SourceMap;
use std::path::Path;

/// One scenario tested.
#[derive(Debug)]
pub struct Report {
    pub scenario: String,
    /// `(line, holds)` per expectation, in the file's order.
    pub verdicts: Vec<(String, bool)>,
    /// Why each failing line failed (E1010-E1015).
    pub failures: Vec<Diagnostic>,
    /// The snapshot body this run produced.
    pub body: String,
}

/// Check, roll out and judge one file. `Err` holds the check or rollout diagnostics.
pub fn run(path: &Path, sources: &mut SourceMap) -> Result<Report, Vec<Diagnostic>> {
    let s = check::check_path(path, sources)?;
    let f = front(s, None)?;
    let contacts = geometry::contacts(&f);
    let mut verdicts = vec![];
    let mut failures = vec![];
    for x in &f.scenario.expects {
        let d = eval::judge(&f, x, &contacts);
        verdicts.push((x.text.clone(), d.is_none()));
        failures.extend(d);
    }
    let body = snapshot::body(&f, &verdicts, &contacts);
    Ok(Report { scenario: f.scenario.name.clone(), verdicts, failures, body })
}
