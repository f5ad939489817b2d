//! A road's traffic signals: `signals on` and the cycle (`signal_green`, `signal_yellow`,
//! `signal_all_red`, `signal_offset`, or greens per approach: `signal_phases`), allowed only
//! where a junction has stop lines to hold at.

use super::Checker;
use super::scenario::{Dist, Signals, Template};
use super::units::Dim;
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast;
use std::collections::BTreeMap;

/// The road parameters this file and `signal_phases` read.
pub const PARAMS: [&str; 10] = [
    "signals",
    "signal_green",
    "signal_yellow",
    "signal_all_red",
    "signal_offset",
    "signal_cycle",
    "signal_north",
    "signal_east",
    "signal_south",
    "signal_west",
];

impl Checker {
    /// The signals of a road of template `template` from its signal parameters; `Err` once
    /// something was reported.
    pub(super) fn signals(&mut self, template: Template, params: &[&ast::Param]) -> Result<Option<Signals>, ()> {
        if params.is_empty() {
            return Ok(None);
        }
        let mut seen: BTreeMap<&str, Span> = BTreeMap::new();
        let mut on: Option<(bool, Span)> = None;
        let mut cycle = Signals::default();
        let mut ok = true;
        let mut green_at = None;
        for p in params {
            let n = p.name.name.as_str();
            if let Some(first) = seen.insert(n, p.span) {
                self.dup(&format!("road parameter `{n}`"), first, p.span);
                ok = false;
                continue;
            }
            if super::signal_phases::PARAMS.contains(&n) {
                // Greens per approach: read once the two-phase timing is known.
                continue;
            }
            match (&p.value, n) {
                (ast::ParamValue::Switch { on: s, .. }, "signals") => on = Some((*s, p.span)),
                (ast::ParamValue::Value(v), "signals") => {
                    self.err(
                        Diagnostic::error("E0101", "`signals` is `on` or `off`")
                            .label(v.span, "expected `on` or `off`")
                            .help("write `signals on`"),
                    );
                    ok = false;
                }
                (ast::ParamValue::Switch { span, .. }, _) => {
                    self.err(
                        Diagnostic::error("E0101", format!("`{n}` takes a time, not on/off"))
                            .label(*span, "expected a time")
                            .help(format!("e.g. `{n} 3 s`")),
                    );
                    ok = false;
                }
                (ast::ParamValue::Value(v), _) => match self.cycle_time(v, n) {
                    Some(x) => match n {
                        "signal_green" => (cycle.green, green_at) = (x, Some(p.span)),
                        "signal_yellow" => cycle.yellow = x,
                        "signal_all_red" => cycle.all_red = x,
                        _ => cycle.offset = x,
                    },
                    None => ok = false,
                },
            }
        }
        if !ok {
            return Err(());
        }
        let first = params[0];
        match on {
            Some((false, _)) | None if params.iter().any(|p| p.name.name != "signals") => {
                let timed = params.iter().find(|p| p.name.name != "signals").unwrap_or(&first);
                self.err(
                    Diagnostic::error("E0232", format!("`{}` without `signals on`", timed.name.name))
                        .label(timed.span, "a cycle for signals the road does not have")
                        .help("add `signals on` to the road, or drop the cycle"),
                );
                Err(())
            }
            Some((true, span)) if !template.has_stop_lines() || template == Template::Roundabout => {
                self.err(
                    Diagnostic::error("E0230", format!("a {} road has no signalled junction", template.name()))
                        .label(span, "no junction with stop lines here")
                        .help("signals stand at a `four_way` or `t_junction`: use one of those, or drop `signals on`"),
                );
                Err(())
            }
            Some((true, span)) if cycle.green <= 0.0 => {
                self.err(
                    Diagnostic::error("E0231", "a green of 0 s leaves every approach red forever")
                        .label(green_at.unwrap_or(span), "these signals never turn green")
                        .help("give `signal_green` a positive time, e.g. `signal_green 20 s`, or drop `signals on`"),
                );
                Err(())
            }
            Some((true, _)) => self.signal_phases(template, cycle, params).map(Some),
            _ => Ok(None),
        }
    }

    /// One cycle time in seconds: a single value, not negative, at most 10 minutes.
    fn cycle_time(&mut self, v: &ast::Value, name: &str) -> Option<f64> {
        let x = match self.quantity(v, Dim::Time, name)? {
            Dist::Fixed(x) => x,
            Dist::Uniform(..) => {
                self.err(
                    Diagnostic::error("E0231", format!("`{name}` cannot be a range"))
                        .label(v.span, "a single time is needed here")
                        .help(format!("e.g. `{name} 3 s`")),
                );
                return None;
            }
        };
        if !(0.0..=600.0).contains(&x) {
            self.err(
                Diagnostic::error("E0231", format!("`{name}` must be within 0..600 s"))
                    .label(v.span, if x < 0.0 { "a negative time" } else { "longer than 10 minutes" })
                    .help(format!("e.g. `{name} 3 s`")),
            );
            return None;
        }
        Some(x)
    }
}
