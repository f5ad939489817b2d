//! Check pass. In: the AST of one scenario plus every kind in scope (stdlib, `use`d files).
//! Out: `scenario::Scenario` — names resolved, units converted to SI, domain rules enforced —
//! or every diagnostic found (the checker keeps going after an error to report them all).
//!
//! `Checker`'s methods sit in one file per part of the language (kinds, scene, road, placement,
//! agent, goal, conflict); this file holds the entry points and the value helpers they share.

mod agent;
mod behaviour;
mod body;
pub mod classes;
mod conflict;
mod expect;
mod flagger;
mod goal;
mod impact;
pub mod kerb;
mod kinds;
pub mod load;
mod near_miss;
mod placement;
mod posture;
mod road;
pub mod scenario;
mod scene;
mod signal_phases;
mod signals;
pub mod summary;
pub mod track;
mod trigger;
pub mod units;

pub use conflict::points_for;
pub use near_miss::GAP_RANGE;
pub use road::{CURVE_MARGIN_M, ISLAND_MIN_M, SIDEWALK_WIDTH_M, lane_count, min_radius};

use crate::diag::{Diagnostic, did_you_mean};
use crate::source::{SourceMap, Span};
use crate::syntax::ast;
use scenario::*;
use std::collections::BTreeMap;
use std::path::Path;
use units::Dim;

/// Caps that keep a typo from asking for a week of compute.
pub const MAX_DURATION_S: f64 = 120.0;
pub const MAX_RATE_HZ: f64 = 100.0;
pub const MAX_SPEED_MS: f64 = 90.0;
pub const MAX_LANES: u32 = 6;
pub const MAX_ROW_OBJECTS: usize = 500;

/// Load, parse and check a scenario file.
pub fn check_path(path: &Path, sources: &mut SourceMap) -> Result<Scenario, Vec<Diagnostic>> {
    let program = load::load_path(path, sources)?;
    check_program(&program)
}

/// Parse and check scenario text (imports resolve against `base`).
pub fn check_text(name: &str, text: &str, base: &Path, sources: &mut SourceMap) -> Result<Scenario, Vec<Diagnostic>> {
    let program = load::load_text(name, text, base, sources)?;
    check_program(&program)
}

pub fn check_program(p: &load::Program) -> Result<Scenario, Vec<Diagnostic>> {
    let mut c = Checker { diags: vec![], kinds: BTreeMap::new() };
    c.kinds(&p.kinds);
    let s = c.scenario(&p.scenario);
    if c.diags.iter().any(Diagnostic::is_error) {
        c.diags.sort_by_key(|d| d.span().map(|s| (s.file, s.start)));
        Err(c.diags)
    } else {
        Ok(s.expect("a scenario is built whenever no error was reported"))
    }
}

/// Every road parameter of any template, in the order the decoding grammar offers them
/// (the scenario library's order).
pub const ROAD_PARAMS: [&str; 10] = [
    "lanes",
    "lane_width",
    "radius",
    "angle",
    "speed_limit",
    "shoulder",
    "median",
    "crosswalks",
    "sidewalks",
    "length",
];

struct Checker {
    diags: Vec<Diagnostic>,
    kinds: BTreeMap<String, (Kind, Span)>,
}

/// Look a word up in a closed vocabulary, reporting E0116 with a suggestion.
fn word<T: Copy>(c: &mut Checker, ident: &ast::Ident, table: &[(&str, T)], what: &str) -> Option<T> {
    if let Some((_, v)) = table.iter().find(|(n, _)| *n == ident.name) {
        return Some(*v);
    }
    let names: Vec<&str> = table.iter().map(|(n, _)| *n).collect();
    c.diags.push(
        Diagnostic::error("E0116", format!("unknown {what} `{}`", ident.name))
            .label(ident.span, format!("not a {what}"))
            .help(did_you_mean(&ident.name, &names, what)),
    );
    None
}

impl Checker {
    fn err(&mut self, d: Diagnostic) {
        self.diags.push(d);
    }

    /// Convert a value to SI, checking its dimension. Ranges become uniform distributions.
    fn quantity(&mut self, v: &ast::Value, dim: Dim, what: &str) -> Option<Dist> {
        let (got, factor) = match &v.unit {
            Some(u) => units::unit(&u.text),
            None => (Dim::Count, 1.0),
        };
        let got = if dim == Dim::Ratio && got == Dim::Count { Dim::Ratio } else { got };
        if got != dim {
            let d = if got == Dim::Count {
                Diagnostic::error("E0102", format!("{what} needs a unit"))
                    .label(v.span, format!("expected {}", dim.name()))
                    .help(format!("write the unit: {}", dim.units()))
            } else {
                let written = crate::syntax::fmt::val(v);
                Diagnostic::error("E0101", format!("{what} needs {}, but `{written}` is {}", dim.units(), got.name()))
                    .label(
                        v.span,
                        format!(
                            "{} here, expected {}",
                            got.name().trim_start_matches("a ").trim_start_matches("an "),
                            dim.name()
                        ),
                    )
                    .help(format!("{what} needs {}{}", dim.units(), units::hint(dim, got, v)))
            };
            self.err(d);
            return None;
        }
        let lo = v.lo.value * factor;
        match &v.hi {
            None => Some(Dist::Fixed(lo)),
            Some(hi) => {
                let hi = hi.value * factor;
                if hi < lo {
                    self.err(
                        Diagnostic::error("E0104", format!("range of {what} is reversed"))
                            .label(v.span, "lower bound is larger than upper bound")
                            .help(format!(
                                "write it as {}..{}",
                                v.hi.as_ref().map_or("", |h| &h.literal),
                                v.lo.literal
                            )),
                    );
                    return None;
                }
                Some(if hi == lo { Dist::Fixed(lo) } else { Dist::Uniform(lo, hi) })
            }
        }
    }

    /// A quantity that must lie within [min, max] (SI).
    fn bounded(&mut self, v: &ast::Value, dim: Dim, what: &str, min: f64, max: f64, shown: &str) -> Option<Dist> {
        let d = self.quantity(v, dim, what)?;
        if d.lo() < min || d.hi() > max {
            let mut e = Diagnostic::error("E0103", format!("{what} is out of range"))
                .label(v.span, format!("must be within {shown}"))
                .help(format!("{what} must be within {shown}"));
            if dim == Dim::Speed && d.lo() < 0.0 {
                e = e.and_help("to drive backwards, give the vehicle a reverse goal: `goal { reverse 8 m }`");
            }
            if let Some(meant) = units::slip(v, dim, min, max, shown) {
                let written = crate::syntax::fmt::val(v);
                e = e.and_help(format!(
                    "did you mean `{meant}`? `{written}` is far outside, so the unit looks like a slip"
                ));
            }
            self.err(e);
            return None;
        }
        Some(d)
    }

    fn fixed(&mut self, v: &ast::Value, dim: Dim, what: &str, min: f64, max: f64, shown: &str) -> Option<f64> {
        let d = self.bounded(v, dim, what, min, max, shown)?;
        match d {
            Dist::Fixed(x) => Some(x),
            Dist::Uniform(..) => {
                self.err(
                    Diagnostic::error("E0103", format!("{what} cannot be a range"))
                        .label(v.span, "a single value is needed here")
                        .help("ranges are allowed for sizes, speeds, distances and headings"),
                );
                None
            }
        }
    }

    fn dup(&mut self, what: &str, first: Span, second: Span) {
        self.err(
            Diagnostic::error("E0105", format!("{what} is given twice"))
                .label(second, "second one here")
                .label(first, "first one here")
                .help("keep one of them"),
        );
    }
}
