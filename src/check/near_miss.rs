//! Near-miss blocks: one agent passing another within a gap at a time, without contact.

use super::scenario::*;
use super::units::Dim;
use super::{Checker, MAX_DURATION_S, word};
use crate::diag::Diagnostic;
use crate::syntax::ast;
use std::collections::BTreeMap;

/// The gaps a near miss may ask for, m: below the least, box tolerances make it a graze (stage a
/// `conflict`); beyond the most, two agents are not near.
pub const GAP_RANGE: (f64, f64) = (0.2, 3.0);

/// Two requests on one pair closer in time than this are the same moment, s (the window a
/// staging may move an impact by, `rollout::staging::plan::WINDOW_S`).
const SAME_TIME_S: f64 = 1.5;

/// The times to collision a near miss may ask for, s: below the least, no braking within a
/// vehicle's limits stops short of contact from a closing speed worth the name; beyond the most,
/// the passer is following, not closing.
pub const TTC_RANGE: (f64, f64) = (0.5, 3.0);

impl Checker {
    pub(super) fn near_miss(
        &mut self,
        c: &ast::Conflict,
        order: &[&str],
        agents: &[Option<Agent>],
        duration: Option<f64>,
    ) -> Option<NearMiss> {
        let (fields, mut ok) = self.fields_once(c, "near_miss");
        let mut missing: Vec<&str> = ["passer", "passed"].into_iter().filter(|k| !fields.contains_key(k)).collect();
        if !fields.contains_key("gap") && !fields.contains_key("ttc") {
            missing.push("gap or ttc");
        }
        if !missing.is_empty() {
            self.err(
                Diagnostic::error("E0106", format!("near_miss has no {}", missing.join(", ")))
                    .label(c.span, "incomplete near miss")
                    .help(
                        "a near miss needs `passer A; passed B; gap DIST` (and optionally `side left|right; at TIME`), \
                         or `passer A; passed B; ttc TIME` (and optionally `at TIME`)",
                    ),
            );
            return None;
        }
        let name = |c: &mut Checker, key: &str| -> Option<&ast::Ident> {
            match &fields.get(key)?.value {
                ast::FieldValue::Ident(i) => Some(i),
                ast::FieldValue::Value(v) => {
                    c.err(
                        Diagnostic::error("E0192", format!("near_miss `{key}` takes a name, not a number"))
                            .label(v.span, "expected a name")
                            .help(format!("e.g. `{key} {}`", if key == "side" { "left" } else { "v2" })),
                    );
                    None
                }
            }
        };
        let number = |c: &mut Checker, key: &str| -> Option<Option<&ast::Value>> {
            match fields.get(key).map(|f| &f.value) {
                None => Some(None),
                Some(ast::FieldValue::Value(v)) => Some(Some(v)),
                Some(ast::FieldValue::Ident(i)) => {
                    c.err(
                        Diagnostic::error("E0192", format!("near_miss `{key}` takes a quantity, not a name"))
                            .label(i.span, "expected a quantity")
                            .help(format!(
                                "e.g. `{key} {}`",
                                match key {
                                    "gap" => "0.5 m",
                                    "ttc" => "0.8 s",
                                    _ => "4 s",
                                }
                            )),
                    );
                    None
                }
            }
        };
        let passer = name(self, "passer").and_then(|i| self.resolve(i, order).map(|x| (x, i.span)));
        let passed = name(self, "passed").and_then(|i| self.resolve(i, order).map(|x| (x, i.span)));
        let side = match fields.get("side") {
            None => Some(None),
            Some(_) => name(self, "side").and_then(|i| {
                let p = word(self, i, &POINTS, "side")?;
                if matches!(p, Point::Left | Point::Right) {
                    return Some(Some(p));
                }
                self.err(
                    Diagnostic::error("E0192", format!("a near miss passes on a side, not at `{}`", i.name))
                        .label(i.span, "not `left` or `right`")
                        .help("`side left` or `side right`: the side of the passed agent the passer goes by"),
                );
                None
            }),
        };
        let gap = number(self, "gap")?.map(|v| {
            let g = self.fixed(v, Dim::Length, "near-miss gap", f64::MIN, f64::MAX, "any length")?;
            if (GAP_RANGE.0..=GAP_RANGE.1).contains(&g) {
                return Some(Some(g));
            }
            let why = if g < GAP_RANGE.0 {
                "closer than that is contact within the boxes' tolerance: stage it as a `conflict`"
            } else {
                "agents that far apart are not a near miss"
            };
            self.err(
                Diagnostic::error("E0190", format!("a near-miss gap of {g} m is out of range"))
                    .label(v.span, format!("must be within {}..{} m", GAP_RANGE.0, GAP_RANGE.1))
                    .help(format!("the gap is the least distance between the two boxes; {why}")),
            );
            None
        });
        let gap = gap.unwrap_or(Some(None));
        let ttc = number(self, "ttc")?;
        let ttc = self.near_ttc(&fields, ttc);
        let at = match number(self, "at")? {
            None => Some(None),
            Some(v) => {
                let max = duration.unwrap_or(MAX_DURATION_S);
                self.fixed(v, Dim::Time, "near-miss time", 0.0, max, &format!("0..{max} s (the clip)")).map(Some)
            }
        };
        let (passer, passed, side, gap, ttc, at) = (passer?, passed?, side?, gap?, ttc?, at?);
        if passer.0 == passed.0 {
            self.err(
                Diagnostic::error("E0191", "a near miss needs two different agents")
                    .label(passed.1, format!("`{}` is also the passer", order[passed.0]))
                    .label(passer.1, "passer")
                    .help("name the agent that is passed, e.g. `passed v2`"),
            );
            return None;
        }
        if let Some(a) = &agents[passer.0]
            && (a.motion == Motion::Static || a.track.is_some())
        {
            let what = if a.track.is_some() { "follows a recorded track" } else { "is static" };
            self.err(
                Diagnostic::error("E0191", format!("`{}` {what} and cannot be the passer", a.name))
                    .label(passer.1, "the passer steers to pass")
                    .help("the passer is a moving agent with a goal; swap `passer` and `passed`, or name another"),
            );
            ok = false;
        }
        ok.then_some(NearMiss { passer: passer.0, passed: passed.0, gap, ttc, side, at, span: c.span })
    }

    /// The `ttc` form: a positive time within `TTC_RANGE`, instead of `gap` and without `side`
    /// (the passer closes from behind or across a path, on no side). `None`: refused; `Some(None)`: the gap form.
    fn near_ttc(
        &mut self,
        fields: &BTreeMap<&str, &ast::ConflictField>,
        ttc: Option<&ast::Value>,
    ) -> Option<Option<f64>> {
        let Some(v) = ttc else { return Some(None) };
        for other in ["gap", "side"] {
            if let Some(f) = fields.get(other) {
                self.err(
                    Diagnostic::error("E0187", format!("a near miss by `ttc` takes no `{other}`"))
                        .label(f.span, format!("`{other}` belongs to the pass alongside"))
                        .label(v.span, "time to collision")
                        .help("a `ttc` near miss closes on the passed agent from behind or across its path: keep `ttc` or `gap`, not both, and no `side`"),
                );
                return None;
            }
        }
        let t = self.fixed(v, Dim::Time, "near-miss time to collision", f64::MIN, f64::MAX, "any time")?;
        if (TTC_RANGE.0..=TTC_RANGE.1).contains(&t) {
            return Some(Some(t));
        }
        let why = if t <= 0.0 {
            "a time to collision of zero or less is contact: stage it as a `conflict`"
        } else if t < TTC_RANGE.0 {
            "closing that late, no braking within a vehicle's limits stops short of contact"
        } else {
            "that far off, the passer is following, not closing"
        };
        self.err(
            Diagnostic::error("E0188", format!("a near-miss time to collision of {t} s is out of range"))
                .label(v.span, format!("must be within {}..{} s", TTC_RANGE.0, TTC_RANGE.1))
                .help(format!("the time to collision is the gap between the boxes over their closing speed; {why}")),
        );
        None
    }

    /// A near miss is staged like a crash, by one approach of its passer: a pair that also crashes
    /// at about that time is a contradiction, and a passer that already strikes or passes another
    /// cannot follow two approaches.
    pub(super) fn near_misses_apart(
        &mut self,
        near: &[Option<NearMiss>],
        conflicts: &[Option<Conflict>],
        order: &[&str],
        duration: Option<f64>,
    ) {
        let when = |at: Option<f64>| at.unwrap_or(duration.unwrap_or(0.0) / 2.0);
        for (ni, n) in near.iter().enumerate() {
            let Some(n) = n else { continue };
            let (a, b) = (order[n.passer], order[n.passed]);
            let pair = conflicts.iter().flatten().find(|c| {
                ((c.at_fault, c.struck) == (n.passer, n.passed) || (c.at_fault, c.struck) == (n.passed, n.passer))
                    && (when(c.at) - when(n.at)).abs() < SAME_TIME_S
            });
            if let Some(c) = pair {
                self.err(
                    Diagnostic::error("E0193", format!("`{a}` and `{b}` both crash and miss each other at about {:.1} s", when(n.at)))
                        .label(n.span, "near miss")
                        .label(c.span, "crash of the same pair")
                        .help(format!("a near miss has no contact; keep the conflict, or move one of them more than {SAME_TIME_S} s apart in time")),
                );
                continue;
            }
            let other = conflicts
                .iter()
                .flatten()
                .find(|c| c.at_fault == n.passer || c.struck == n.passer)
                .map(|c| (c.span, "a conflict"))
                .or_else(|| {
                    near[..ni].iter().flatten().find(|m| m.passer == n.passer).map(|m| (m.span, "another near miss"))
                });
            if let Some((span, what)) = other {
                self.err(
                    Diagnostic::error("E0194", format!("`{a}` passes `{b}` and is also in {what}"))
                        .label(n.span, "near miss")
                        .label(span, format!("{what} of `{a}`"))
                        .help(format!(
                            "the passer follows one staged approach; stage the near miss with an agent other than `{a}`"
                        )),
                );
            }
        }
    }
}
