//! Greens stated per approach (`signal_north 0..20 s`, ... and `signal_cycle`): each approach's
//! green within a cycle of its own length, in place of the two-phase cycle, so that one approach
//! may lead or lag the one opposite (a protected left). Two approaches whose traffic crosses
//! may not show green or yellow at once (E0236).

use super::Checker;
use super::scenario::{Arm, Dist, Signals, Template};
use super::units::Dim;
use crate::diag::Diagnostic;
use crate::road::signals::crossing;
use crate::source::Span;
use crate::syntax::ast;

/// The road parameters read here, each approach's with its arm.
pub const PARAMS: [&str; 5] = ["signal_cycle", "signal_north", "signal_east", "signal_south", "signal_west"];
const APPROACHES: [(&str, Arm); 4] = [
    ("signal_north", Arm::North),
    ("signal_east", Arm::East),
    ("signal_south", Arm::South),
    ("signal_west", Arm::West),
];

impl Checker {
    /// `cycle` with the greens per approach among `params` (the road's signal parameters, each
    /// name once); unchanged where none is stated. `Err` once something was reported.
    pub(super) fn signal_phases(
        &mut self,
        template: Template,
        mut cycle: Signals,
        params: &[&ast::Param],
    ) -> Result<Signals, ()> {
        let named = |n: &str| params.iter().find(|p| p.name.name == n).copied();
        let stated: Vec<(&ast::Param, Arm)> =
            APPROACHES.iter().filter_map(|(n, arm)| named(n).map(|p| (p, *arm))).collect();
        let Some(&(first, _)) = stated.first() else {
            return match named("signal_cycle") {
                Some(p) => self.mixed(
                    p.span,
                    "`signal_cycle` times greens stated per approach",
                    "state each approach's green, e.g. `signal_north 0..20 s`, or drop `signal_cycle`",
                ),
                None => Ok(cycle),
            };
        };
        if let Some(p) = named("signal_green").or(named("signal_all_red")) {
            let help = "per-approach greens replace the two-phase cycle: drop it, or the per-approach greens";
            return self.mixed(p.span, &format!("`{}` with greens stated per approach", p.name.name), help);
        }
        let mut ok = true;
        for &(p, arm) in &stated {
            match self.green_window(p, template, arm) {
                Some(w) => cycle.windows[slot(arm)] = Some(w),
                None => ok = false,
            }
        }
        for &arm in template.arms() {
            if !stated.iter().any(|s| s.1 == arm) {
                self.err(
                    Diagnostic::error("E0234", format!("the `{}` approach has no green", arm.name()))
                        .label(first.span, "greens are stated per approach here")
                        .help(format!("state every approach's green: add `signal_{} A..B s`", arm.name())),
                );
                ok = false;
            }
        }
        if !ok {
            return Err(());
        }
        let ends = stated.iter().map(|&(_, arm)| cycle.windows[slot(arm)].map_or(0.0, |w| w[1]) + cycle.yellow);
        let least = ends.fold(0.0, f64::max);
        cycle.period = match named("signal_cycle") {
            None => least,
            Some(p) => {
                let ast::ParamValue::Value(v) = &p.value else { return self.not_a_time(p) };
                let t = self.fixed(v, Dim::Time, "signal_cycle", 0.1, 600.0, "0.1..600 s").ok_or(())?;
                if t < least - 1e-9 {
                    self.err(
                        Diagnostic::error(
                            "E0233",
                            format!("a {t} s cycle ends before a green and its yellow do ({least} s)"),
                        )
                        .label(p.span, "too short")
                        .help(format!("make `signal_cycle` at least {least} s, or end the greens sooner")),
                    );
                    return Err(());
                }
                t
            }
        };
        self.crossing_greens(&cycle, &stated)?;
        Ok(cycle)
    }

    /// One approach's green, `A..B s`: a range of times within 0..600 s, starting before it
    /// ends, on an arm the template has (E0233).
    fn green_window(&mut self, p: &ast::Param, template: Template, arm: Arm) -> Option<[f64; 2]> {
        let bad = |msg: String, label: &str| {
            Diagnostic::error("E0233", msg)
                .label(p.span, label.to_string())
                .help(format!("e.g. `{} 0..20 s`: green from 0 s to 20 s into the cycle", p.name.name))
        };
        if !template.arms().contains(&arm) {
            self.err(bad(format!("a {} road has no `{}` approach", template.name(), arm.name()), "no such approach"));
            return None;
        }
        let ast::ParamValue::Value(v) = &p.value else {
            return self.not_a_time(p).ok();
        };
        match self.quantity(v, Dim::Time, &p.name.name)? {
            Dist::Uniform(a, b) if a >= 0.0 && b <= 600.0 && b > a => Some([a, b]),
            Dist::Uniform(..) => {
                self.err(bad(format!("`{}` must start before it ends, within 0..600 s", p.name.name), "not a green"));
                None
            }
            Dist::Fixed(_) => {
                self.err(bad(format!("`{}` is a green's start and end, not one time", p.name.name), "one time"));
                None
            }
        }
    }

    /// E0236 for two approaches whose traffic crosses, green or yellow at once.
    fn crossing_greens(&mut self, c: &Signals, stated: &[(&ast::Param, Arm)]) -> Result<(), ()> {
        for (k, &(p, arm)) in stated.iter().enumerate() {
            for &(q, other) in &stated[..k] {
                if !crossing(arm).contains(&other) {
                    continue;
                }
                let (Some(a), Some(b)) = (c.windows[slot(arm)], c.windows[slot(other)]) else { continue };
                let (lo, hi) = (a[0].max(b[0]), (a[1] + c.yellow).min(b[1] + c.yellow));
                if lo < hi {
                    self.err(
                        Diagnostic::error(
                            "E0236",
                            format!(
                                "`{}` and `{}` show green or yellow at once, from {lo} s to {hi} s",
                                other.name(),
                                arm.name()
                            ),
                        )
                        .label(p.span, "this green, with its yellow")
                        .label(q.span, "overlaps this one, whose traffic it crosses")
                        .help("crossing approaches take turns: end one green (and its yellow) before the other starts"),
                    );
                    return Err(());
                }
            }
        }
        Ok(())
    }

    /// E0235 at `span`; always `Err`.
    fn mixed<T>(&mut self, span: Span, msg: &str, help: &str) -> Result<T, ()> {
        self.err(Diagnostic::error("E0235", msg.to_string()).label(span, "here").help(help.to_string()));
        Err(())
    }

    /// E0101 for an on/off where times belong; always `Err`.
    fn not_a_time<T>(&mut self, p: &ast::Param) -> Result<T, ()> {
        self.err(
            Diagnostic::error("E0101", format!("`{}` takes times, not on/off", p.name.name))
                .label(p.span, "expected times")
                .help(format!("e.g. `{} 0..20 s`", p.name.name)),
        );
        Err(())
    }
}

/// The index of approach `arm` in `Signals::windows`.
fn slot(arm: Arm) -> usize {
    APPROACHES.iter().position(|a| a.1 == arm).unwrap_or(0)
}
