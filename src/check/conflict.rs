//! Conflict blocks: the crash a scenario asks for, its impact type and point of contact.

use super::scenario::*;
use super::units::Dim;
use super::{Checker, MAX_DURATION_S, word};
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast;
use std::collections::BTreeMap;

impl Checker {
    /// A crash latches its pair from the impact on, so an agent takes part in one conflict only:
    /// a second block naming it (as at_fault or struck) is rejected, pointing at both.
    pub(super) fn one_conflict_each(
        &mut self,
        conflicts: &[Option<Conflict>],
        asts: &[&ast::Conflict],
        order: &[&str],
    ) {
        // Agent index -> the block of its first conflict.
        let mut first: BTreeMap<usize, Span> = BTreeMap::new();
        for (c, ca) in conflicts.iter().zip(asts) {
            let Some(c) = c else { continue };
            for (who, key) in [(c.at_fault, "at_fault"), (c.struck, "struck")] {
                let field = ca.fields.iter().find(|f| f.key == key).map_or(ca.span, |f| f.span);
                match first.get(&who) {
                    None => {
                        first.insert(who, ca.span);
                    }
                    Some(&block) => {
                        let name = order[who];
                        self.err(
                            Diagnostic::error("E0121", format!("`{name}` is in two conflicts"))
                                .label(field, format!("`{name}` named again here, as {key}"))
                                .label(block, format!("first conflict of `{name}`"))
                                .help(format!(
                                    "a crash holds its pair from the impact on; keep one conflict for `{name}`, or stage the second crash with another agent"
                                )),
                        );
                    }
                }
            }
        }
    }

    pub(super) fn conflict(
        &mut self,
        c: &ast::Conflict,
        order: &[&str],
        agents: &[Option<Agent>],
        duration: Option<f64>,
    ) -> Option<Conflict> {
        let mut fields: BTreeMap<&str, &ast::ConflictField> = BTreeMap::new();
        let mut ok = true;
        for f in &c.fields {
            if let Some(first) = fields.get(f.key.as_str()) {
                let first = first.span;
                self.dup(&format!("conflict field `{}`", f.key), first, f.span);
                ok = false;
                continue;
            }
            fields.insert(&f.key, f);
        }
        let ident = |c: &mut Checker, key: &str| -> Option<&ast::Ident> {
            let f = fields.get(key)?;
            match &f.value {
                ast::FieldValue::Ident(i) => Some(i),
                ast::FieldValue::Value(v) => {
                    c.err(
                        Diagnostic::error("E0114", format!("`{key}` takes a name, not a number"))
                            .label(v.span, "expected a name")
                            .help(format!(
                                "e.g. `{key} {}`",
                                match key {
                                    "impact" => "rear_end",
                                    "point" => "rear",
                                    _ => "ego",
                                }
                            )),
                    );
                    None
                }
            }
        };
        let missing: Vec<&str> =
            ["at_fault", "struck", "impact", "point"].into_iter().filter(|k| !fields.contains_key(k)).collect();
        if !missing.is_empty() {
            self.err(
                Diagnostic::error("E0106", format!("conflict has no {}", missing.join(", ")))
                    .label(c.span, "incomplete conflict")
                    .help(
                        "a conflict needs `at_fault A; struck B; impact TYPE; point SIDE` (and optionally `at TIME`)",
                    ),
            );
            return None;
        }
        let at_fault = ident(self, "at_fault").and_then(|i| self.resolve(i, order).map(|x| (x, i.span)));
        let struck = ident(self, "struck").and_then(|i| self.resolve(i, order).map(|x| (x, i.span)));
        let impact_i = ident(self, "impact");
        let point_i = ident(self, "point");
        let impact = impact_i.and_then(|i| word(self, i, &IMPACTS, "impact type"));
        let point = point_i.and_then(|i| word(self, i, &POINTS, "impact point"));
        if let (Some(imp), Some(pt), Some(ii), Some(pi)) = (impact, point, impact_i, point_i) {
            let fits = points_for(imp);
            if !fits.contains(&pt) {
                let names: Vec<&str> = POINTS.iter().filter(|(_, p)| fits.contains(p)).map(|(n, _)| *n).collect();
                let why = match imp {
                    Impact::RearEnd => "a rear-end strikes the struck agent's rear",
                    Impact::HeadOn => "a head-on meets the struck agent's front",
                    _ => "an angle or sideswipe strikes the struck agent's side or a corner",
                };
                self.err(
                    Diagnostic::error("E0120", format!("`impact {}` cannot have `point {}`: {why}", ii.name, pi.name))
                        .label(pi.span, format!("not a side a {} strikes", ii.name.replace('_', "-")))
                        .label(ii.span, "impact type")
                        .help(format!(
                            "with `impact {}` use `point {}`; `point {}` fits `impact {}`",
                            ii.name,
                            names.join("`, `"),
                            pi.name,
                            IMPACTS
                                .iter()
                                .filter(|(_, i)| !matches!(i, Impact::Pedestrian | Impact::Object))
                                .filter(|(_, i)| points_for(*i).contains(&pt))
                                .map(|(n, _)| *n)
                                .collect::<Vec<_>>()
                                .join("` or `impact ")
                        )),
                );
                ok = false;
            }
        }
        let at = match fields.get("at").map(|f| &f.value) {
            None => Some(None),
            Some(ast::FieldValue::Value(v)) => {
                let max = duration.unwrap_or(MAX_DURATION_S);
                self.fixed(v, Dim::Time, "impact time", 0.0, max, &format!("0..{max} s (the clip)")).map(Some)
            }
            Some(ast::FieldValue::Ident(i)) => {
                self.err(
                    Diagnostic::error("E0101", "`at` takes a time")
                        .label(i.span, "expected a time")
                        .help("e.g. `at 4 s`"),
                );
                None
            }
        };
        let (at_fault, struck, impact, point, at) = (at_fault?, struck?, impact?, point?, at?);
        if at_fault.0 == struck.0 {
            self.err(
                Diagnostic::error("E0114", "a conflict needs two different agents")
                    .label(struck.1, format!("`{}` is also the at-fault agent", order[struck.0]))
                    .label(at_fault.1, "at-fault agent")
                    .help("name the agent that is struck, e.g. `struck v2`"),
            );
            return None;
        }
        if let (Some(f), Some(s)) = (&agents[at_fault.0], &agents[struck.0]) {
            let bad = if f.motion == Motion::Static {
                Some((at_fault.1, format!("`{}` is static and cannot be at fault", f.name)))
            } else if impact == Impact::Pedestrian && s.class != Class::Pedestrian {
                Some((struck.1, format!("`impact pedestrian` but `{}` is a {}", s.name, s.class.name())))
            } else if impact == Impact::Object && s.motion != Motion::Static {
                Some((struck.1, format!("`impact object` but `{}` moves", s.name)))
            } else if impact != Impact::Object && impact != Impact::Pedestrian && s.motion == Motion::Static {
                Some((struck.1, format!("`{}` is a static {}: use `impact object`", s.name, s.class.name())))
            } else {
                None
            };
            if let Some((span, msg)) = bad {
                self.err(
                    Diagnostic::error("E0114", msg)
                        .label(span, "here")
                        .help("see `rocc explain E0114` for the impact types"),
                );
                ok = false;
            }
        }
        ok.then_some(Conflict { at_fault: at_fault.0, struck: struck.0, impact, point, at, span: c.span })
    }
}

/// The points (sides of the struck agent) an impact type can hit: a rear-end strikes the rear
/// face or a rear corner, a head-on the front face or a front corner, an angle (front into side)
/// or a sideswipe (side along side) a side or a corner. A pedestrian or an object may be hit
/// anywhere. `rocc explain E0120` prints this table; keep the two in step.
pub fn points_for(impact: Impact) -> &'static [Point] {
    use Point::*;
    match impact {
        Impact::RearEnd => &[Rear, RearLeft, RearRight],
        Impact::HeadOn => &[Front, FrontLeft, FrontRight],
        Impact::Angle | Impact::Sideswipe => &[Left, Right, FrontLeft, FrontRight, RearLeft, RearRight],
        Impact::Pedestrian | Impact::Object => &[Front, Rear, Left, Right, FrontLeft, FrontRight, RearLeft, RearRight],
    }
}
