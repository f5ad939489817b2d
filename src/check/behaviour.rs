//! `behaviour { ... }`: an agent's attention and compliance (yielding, its stop line, reaction
//! time, speeding), careful by default; settings that contradict the agent are refused.

use super::Checker;
use super::scenario::*;
use super::units::Dim;
use crate::diag::{Diagnostic, did_you_mean};
use crate::syntax::ast;
use std::collections::BTreeMap;

/// The settings, with what each takes.
const SETTINGS: [(&str, &str); 5] = [
    ("yield", "`always` or `never`"),
    ("stop_line", "`obey` or `ignore`"),
    ("reaction", "a time, e.g. `reaction 1.5 s`"),
    ("speeding", "a share over the limit, e.g. `speeding 20 %`"),
    ("signal", "`obey` or `ignore`"),
];

impl Checker {
    pub(super) fn behaviour(
        &mut self,
        b: &ast::Behaviour,
        name: &str,
        motion: Option<Motion>,
        is_static: bool,
        goal: Option<&ast::Goal>,
    ) -> Option<Behaviour> {
        let mut out = Behaviour::default();
        let mut ok = true;
        let mut seen: BTreeMap<&str, crate::source::Span> = BTreeMap::new();
        let walker = motion == Some(Motion::Holonomic);
        for set in &b.sets {
            let key = set.name.name.as_str();
            let Some(&(_, takes)) = SETTINGS.iter().find(|s| s.0 == key) else {
                let names: Vec<&str> = SETTINGS.iter().map(|s| s.0).collect();
                self.err(
                    Diagnostic::error("E0152", format!("unknown behaviour setting `{key}`"))
                        .label(set.name.span, "not a setting")
                        .help(did_you_mean(key, &names, "setting")),
                );
                ok = false;
                continue;
            };
            if let Some(first) = seen.insert(key, set.span) {
                self.dup(&format!("behaviour `{key}`"), first, set.span);
                ok = false;
                continue;
            }
            let bad_value = |c: &mut Checker| {
                c.err(
                    Diagnostic::error("E0152", format!("`{key}` takes {takes}"))
                        .label(set.span, "not a value for this setting")
                        .help(format!("write `{key}` with {takes}")),
                );
            };
            match (key, &set.value) {
                ("yield", ast::FieldValue::Ident(w)) if w.name == "always" || w.name == "never" => {
                    out.yields = w.name == "always"
                }
                ("stop_line", ast::FieldValue::Ident(w)) if w.name == "obey" || w.name == "ignore" => {
                    out.stop_line = w.name == "obey"
                }
                ("signal", ast::FieldValue::Ident(w)) if w.name == "obey" || w.name == "ignore" => {
                    out.signal = w.name == "obey"
                }
                ("reaction", ast::FieldValue::Value(v)) => {
                    match self.fixed(v, Dim::Time, "reaction time", 0.0, 5.0, "0..5 s") {
                        Some(r) => out.reaction = r,
                        None => ok = false,
                    }
                }
                ("speeding", ast::FieldValue::Value(v)) => {
                    match self.fixed(v, Dim::Ratio, "speeding", 0.0, 2.0, "0..200 %") {
                        Some(p) => out.speeding = p,
                        None => ok = false,
                    }
                }
                _ => {
                    bad_value(self);
                    ok = false;
                }
            }
        }
        let stops_at_line = goal
            .is_some_and(|g| g.stmts.iter().any(|s| matches!(s, ast::GoalStmt::Stop { stop: ast::Stop::At(_), .. })));
        let clash = if is_static {
            Some(format!("`{name}` never moves, so it has no behaviour"))
        } else if walker && !out.stop_line {
            Some(format!("`{name}` walks: stop lines are for vehicles"))
        } else if walker && out.speeding > 0.0 {
            Some(format!("`{name}` walks: walkers have no speed limit to exceed"))
        } else if !out.stop_line && stops_at_line {
            Some(format!("`{name}` is told both to stop at its stop line and to ignore it"))
        } else {
            None
        };
        if let Some(msg) = clash {
            self.err(
                Diagnostic::error("E0153", msg)
                    .label(b.span, "contradicts the agent")
                    .help("drop the setting, or the goal it contradicts"),
            );
            ok = false;
        }
        ok.then_some(out)
    }
}
