//! Kind declarations and the references agents and rows make to them.

use super::scenario::*;
use super::units::Dim;
use super::{Checker, word};
use crate::diag::{Diagnostic, did_you_mean};
use crate::syntax::ast;
use std::collections::BTreeMap;

impl Checker {
    pub(super) fn kinds(&mut self, decls: &[ast::KindDecl]) {
        for k in decls {
            if let Some((_, first)) = self.kinds.get(&k.name.name) {
                let first = *first;
                self.dup(&format!("kind `{}`", k.name.name), first, k.name.span);
                continue;
            }
            // After the colon, a class; else an earlier kind, whose class, motion, box priors and
            // emergency status the new kind inherits (its own statements override them).
            let is_class = Class::ALL.iter().any(|(n, _)| *n == k.class.name);
            let parent = self.kinds.get(&k.class.name).filter(|_| !is_class).map(|(p, _)| p.clone());
            let class = match &parent {
                Some(p) => p.class,
                None => {
                    let Some(class) = word(self, &k.class, &Class::ALL, "class") else { continue };
                    class
                }
            };
            let mut motion = parent.as_ref().map_or(class.default_motion(), |p| p.motion);
            let mut size: [Option<Dist>; 3] =
                parent.as_ref().map_or([None; 3], |p| [Some(p.length), Some(p.width), Some(p.height)]);
            let mut mass = parent.as_ref().and_then(|p| p.mass);
            let emergency = EMERGENCY_KINDS.contains(&k.name.name.as_str()) || parent.is_some_and(|p| p.emergency);
            for s in &k.stmts {
                match s {
                    ast::KindStmt::Motion { motion: m, .. } => {
                        if let Some(m) = word(self, m, &MOTIONS, "motion") {
                            motion = m;
                        }
                    }
                    ast::KindStmt::Size(s) => {
                        let what = format!("kind {}", s.key.as_str());
                        size[s.key as usize] = self.bounded(&s.value, Dim::Length, &what, 0.01, 40.0, "0.01..40 m");
                    }
                    ast::KindStmt::Mass { .. } => {}
                }
            }
            // After the motion statements: a static kind has no mass.
            for s in &k.stmts {
                if let ast::KindStmt::Mass { value, span } = s {
                    mass = self.mass(value, *span, &k.name.name, motion == Motion::Static);
                }
            }
            let missing: Vec<&str> =
                ["length", "width", "height"].iter().zip(size).filter(|(_, s)| s.is_none()).map(|(n, _)| *n).collect();
            if !missing.is_empty() {
                if !self.diags.iter().any(|d| {
                    d.span().is_some_and(|s| s.file == k.span.file && s.start >= k.span.start && s.end <= k.span.end)
                }) {
                    self.err(
                        Diagnostic::error("E0106", format!("kind `{}` has no {}", k.name.name, missing.join(", ")))
                            .label(k.name.span, "incomplete kind")
                            .help("a kind gives length, width and height priors, e.g. `length 4.2..4.8 m`"),
                    );
                }
                continue;
            }
            let [length, width, height] = size.map(|s| s.expect("checked above"));
            self.kinds.insert(
                k.name.name.clone(),
                (
                    Kind { name: k.name.name.clone(), class, motion, length, width, height, emergency, mass },
                    k.name.span,
                ),
            );
        }
    }

    /// Resolve a kind reference; `one_of` choices must share class and motion.
    pub(super) fn kind_ref(
        &mut self,
        r: &ast::KindRef,
        used: &mut BTreeMap<String, Kind>,
    ) -> Option<(Vec<String>, Class, Motion)> {
        let idents: Vec<&ast::Ident> = match r {
            ast::KindRef::Named(i) => vec![i],
            ast::KindRef::OneOf { kinds, .. } => kinds.iter().collect(),
        };
        let mut found: Vec<Kind> = vec![];
        for i in &idents {
            match self.kinds.get(&i.name) {
                Some((k, _)) => found.push(k.clone()),
                None => {
                    let names: Vec<&str> = self.kinds.keys().map(String::as_str).collect();
                    let help = did_you_mean(&i.name, &names, "kind");
                    self.err(
                        Diagnostic::error("E0108", format!("unknown kind `{}`", i.name))
                            .label(i.span, "no kind of this name")
                            .help(format!("{help} (kinds come from stdlib/kinds.scn or a `use`d file)")),
                    );
                }
            }
        }
        if found.len() != idents.len() {
            return None;
        }
        let first = &found[0];
        if let Some(other) = found.iter().find(|k| k.class != first.class || k.motion != first.motion) {
            self.err(
                Diagnostic::error("E0119", "the kinds of `one_of` differ in class or motion")
                    .label(
                        r.span(),
                        format!(
                            "`{}` is a {} but `{}` is a {}",
                            first.name,
                            first.class.name(),
                            other.name,
                            other.class.name()
                        ),
                    )
                    .help("list kinds of one class, e.g. `one_of [sedan, suv, pickup_truck]`"),
            );
            return None;
        }
        let (class, motion) = (first.class, first.motion);
        for k in found.iter() {
            used.insert(k.name.clone(), k.clone());
        }
        Some((found.into_iter().map(|k| k.name).collect(), class, motion))
    }
}
