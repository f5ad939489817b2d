//! What an impact needs from the file: the masses agents and kinds state (`mass 1500 kg`) and a
//! conflict's `after`, `restitution` and `friction` (rollout::impact).

use super::Checker;
use super::scenario::{AfterImpact, Dist};
use super::units::Dim;
use crate::diag::Diagnostic;
use crate::rollout::impact::MASS_RANGE;
use crate::source::Span;
use crate::syntax::ast;
use std::collections::BTreeMap;

/// `restitution` may be 0 (the bodies stay together) to 1 (no energy lost); `friction` between
/// two bodies 0 to 1.5 (interlocking sheet metal).
const RESTITUTION_RANGE: (f64, f64) = (0.0, 1.0);
const FRICTION_RANGE: (f64, f64) = (0.0, 1.5);

impl Checker {
    /// A stated mass in kg: one value within `MASS_RANGE` (E0124), on something that moves
    /// (E0125: an object or a static kind does not move when struck).
    pub(super) fn mass(&mut self, v: &ast::Value, span: Span, owner: &str, is_static: bool) -> Option<f64> {
        let (lo, hi) = MASS_RANGE;
        let d = self.quantity(v, Dim::Mass, "mass")?;
        if is_static {
            self.err(
                Diagnostic::error("E0125", format!("`{owner}` never moves, so it has no mass to give"))
                    .label(span, "mass on a static thing")
                    .help("an object or a static kind stands when struck (it is immovable); remove `mass`"),
            );
            return None;
        }
        match d {
            Dist::Fixed(m) if (lo..=hi).contains(&m) => Some(m),
            _ => {
                let why = if matches!(d, Dist::Uniform(..)) { "a mass is one value" } else { "out of range" };
                self.err(
                    Diagnostic::error("E0124", format!("the mass of `{owner}` is {why}"))
                        .label(v.span, format!("must be one value within {lo}..{hi} kg"))
                        .help(format!(
                            "a mass is one value within {lo}..{hi} kg (a sedan is about 1500 kg, a bus 12000 kg)"
                        )),
                );
                None
            }
        }
    }

    /// A conflict's `after latch | slide`, `restitution` and `friction` (E0126-E0129).
    pub(super) fn after_impact(&mut self, fields: &BTreeMap<&str, &ast::ConflictField>) -> Option<AfterImpact> {
        let mut ok = true;
        let latch = match fields.get("after").map(|f| &f.value) {
            None => false,
            Some(ast::FieldValue::Ident(i)) if i.name == "latch" || i.name == "slide" => i.name == "latch",
            Some(v) => {
                let (span, written) = match v {
                    ast::FieldValue::Ident(i) => (i.span, i.name.clone()),
                    ast::FieldValue::Value(x) => (x.span, crate::syntax::fmt::val(x)),
                };
                self.err(
                    Diagnostic::error("E0126", format!("`after {written}`: after an impact the pair slides or latches"))
                        .label(span, "expected `slide` or `latch`")
                        .help("`after slide` (the default) lets the bodies move on from the impact; `after latch` holds the pair where it met"),
                );
                ok = false;
                false
            }
        };
        let mut coefficient = |c: &mut Checker, key: &str, code: &'static str, (lo, hi): (f64, f64)| -> Option<f64> {
            let f = fields.get(key)?;
            let value = match &f.value {
                ast::FieldValue::Value(v) if v.unit.is_none() && v.hi.is_none() => Some(v.lo.value),
                _ => None,
            };
            match value {
                Some(x) if (lo..=hi).contains(&x) => Some(x),
                _ => {
                    c.err(
                        Diagnostic::error(code, format!("`{key}` must be a plain number within {lo}..{hi}"))
                            .label(f.span, format!("not a {key} coefficient"))
                            .help(format!("e.g. `{key} {}`", if key == "restitution" { "0.2" } else { "0.5" })),
                    );
                    ok = false;
                    None
                }
            }
        };
        let restitution = coefficient(self, "restitution", "E0127", RESTITUTION_RANGE);
        let friction = coefficient(self, "friction", "E0128", FRICTION_RANGE);
        if latch && let Some(f) = fields.get("restitution").or_else(|| fields.get("friction")) {
            self.err(
                Diagnostic::error("E0129", format!("`after latch` holds the pair, so its `{}` has no effect", f.key))
                    .label(f.span, "a coefficient of an impact that is not resolved")
                    .label(fields["after"].span, "the pair holds here")
                    .help("remove the coefficient, or let the pair move on (`after slide`)"),
            );
            ok = false;
        }
        ok.then_some(AfterImpact { latch, restitution, friction })
    }
}
