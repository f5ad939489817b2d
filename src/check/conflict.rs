//! Conflict blocks: the crash a scenario asks for, its impact type and point of contact.

use super::scenario::*;
use super::units::Dim;
use super::{Checker, MAX_DURATION_S, word};
use crate::diag::Diagnostic;
use crate::syntax::ast;
use std::collections::BTreeMap;

impl Checker {
    /// A crash ends both agents' driving (they slide to rest, or hold `after latch`), and the
    /// motion after it may carry either into a later contact, so an agent may strike several
    /// times and strike after it was struck. Refused are the orders that cannot happen: two
    /// strikes at once (E0121), strikes written out of time order (E0196), a strike after a
    /// latch holds the agent (E0122), a latched strike that follows an impact (E0197), and a
    /// pair staged twice (E0123).
    pub(super) fn conflicts_in_order(
        &mut self,
        conflicts: &[Option<Conflict>],
        asts: &[&ast::Conflict],
        order: &[&str],
        duration: Option<f64>,
    ) {
        let when = |c: &Conflict| c.at.unwrap_or(duration.unwrap_or(0.0) / 2.0);
        let field = |ca: &ast::Conflict, key: &str| ca.fields.iter().find(|f| f.key == key).map_or(ca.span, |f| f.span);
        let all: Vec<(&Conflict, &ast::Conflict)> =
            conflicts.iter().zip(asts).filter_map(|(c, a)| c.as_ref().map(|c| (c, *a))).collect();
        for (i, &(c, ca)) in all.iter().enumerate() {
            let name = order[c.at_fault];
            let earlier = &all[..i];
            if let Some((e, first)) = earlier.iter().find(|(e, _)| e.at_fault == c.at_fault && when(e) >= when(c)) {
                let same = when(e) == when(c);
                let d = if same {
                    Diagnostic::error("E0121", format!("`{name}` strikes twice at {:.1} s", when(c))).help(format!(
                        "one body makes one contact at a time: give the strikes of `{name}` different `at` times"
                    ))
                } else {
                    Diagnostic::error(
                        "E0196",
                        format!(
                            "the strike of `{name}` at {:.1} s is written after its strike at {:.1} s",
                            when(c),
                            when(e)
                        ),
                    )
                    .help(format!("write the strikes of `{name}` in the order they happen, or swap their `at` times"))
                };
                self.err(
                    d.label(field(ca, "at"), format!("`{name}` strikes at {:.1} s here", when(c)))
                        .label(first.span, format!("strike of `{name}` at {:.1} s", when(e))),
                );
                continue;
            }
            let same_pair = |e: &Conflict| {
                (e.at_fault, e.struck) == (c.at_fault, c.struck) || (e.at_fault, e.struck) == (c.struck, c.at_fault)
            };
            if let Some((_, first)) = earlier.iter().find(|(e, _)| same_pair(e)) {
                let other = order[c.struck];
                self.err(
                    Diagnostic::error("E0123", format!("`{name}` and `{other}` crash twice"))
                        .label(ca.span, "second crash of the pair")
                        .label(first.span, "first crash of the pair")
                        .help(
                            "a crash ends the pair's driving, so a pair is staged to crash once; keep one of the two",
                        ),
                );
                continue;
            }
            // An earlier crash of the striker: latched, it holds it; otherwise the motion after
            // it must bring the striker here, and a latch cannot be asked of that contact.
            let before = |e: &Conflict| (e.struck == c.at_fault || e.at_fault == c.at_fault) && when(e) < when(c);
            let held =
                all.iter().filter(|(e, _)| before(e) && e.after.latch).min_by(|a, b| when(a.0).total_cmp(&when(b.0)));
            if let Some((e, ea)) = held {
                let role = if e.struck == c.at_fault { "is struck" } else { "strikes" };
                self.err(
                    Diagnostic::error(
                        "E0122",
                        format!(
                            "`{name}` cannot strike `{}` at {:.1} s: it {role} at {:.1} s `after latch`, which holds it there",
                            order[c.struck],
                            when(c),
                            when(e)
                        ),
                    )
                    .label(field(ca, "at_fault"), format!("`{name}` strikes here"))
                    .label(field(ea, "after"), format!("`{name}` is held from {:.1} s", when(e)))
                    .help(format!(
                        "drop `after latch` so `{name}` moves on from that crash, or move this strike to {:.1} s or before",
                        when(e)
                    )),
                );
                continue;
            }
            if c.after.latch && all.iter().any(|(e, _)| before(e)) {
                self.err(
                    Diagnostic::error(
                        "E0197",
                        format!("`{name}` cannot latch a strike that follows its earlier crash"),
                    )
                    .label(field(ca, "after"), "a latch here")
                    .help(format!(
                        "`{name}` is not driven after its earlier crash and its next contact is resolved as an \
                             impact: drop `after latch`"
                    )),
                );
            }
        }
    }

    /// The fields of a `conflict` or `near_miss` block by key; a key given twice is E0105 (the
    /// second value is ignored) and the block is not ok.
    pub(super) fn fields_once<'a>(
        &mut self,
        c: &'a ast::Conflict,
        block: &str,
    ) -> (BTreeMap<&'a str, &'a ast::ConflictField>, bool) {
        let mut fields: BTreeMap<&str, &ast::ConflictField> = BTreeMap::new();
        let mut ok = true;
        for f in &c.fields {
            if let Some(first) = fields.get(f.key.as_str()) {
                let first = first.span;
                self.dup(&format!("{block} field `{}`", f.key), first, f.span);
                ok = false;
                continue;
            }
            fields.insert(&f.key, f);
        }
        (fields, ok)
    }

    pub(super) fn conflict(
        &mut self,
        c: &ast::Conflict,
        order: &[&str],
        agents: &[Option<Agent>],
        duration: Option<f64>,
    ) -> Option<Conflict> {
        let (fields, mut ok) = self.fields_once(c, "conflict");
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
        let after = self.after_impact(&fields);
        let (at_fault, struck, impact, point, at, after) = (at_fault?, struck?, impact?, point?, at?, after?);
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
        ok.then_some(Conflict { at_fault: at_fault.0, struck: struck.0, impact, point, at, after, span: c.span })
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
