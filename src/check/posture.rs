//! `posture standing | kneeling | lying`: how a person or an animal holds its body, which sets
//! its box (a person lying on a lane after a crash: tests/rollout-cases/person-lying-on-lane.scn).

use super::scenario::{Class, Motion};
use super::{Checker, word};
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Posture {
    #[default]
    Standing,
    Kneeling,
    Lying,
}

pub const POSTURES: [(&str, Posture); 3] =
    [("standing", Posture::Standing), ("kneeling", Posture::Kneeling), ("lying", Posture::Lying)];

/// Height of a body lying on the ground, m (a person on their back or side).
pub const LYING_HEIGHT_M: f64 = 0.3;

impl Posture {
    pub fn is_standing(&self) -> bool {
        *self == Posture::Standing
    }

    /// The box (length, width, height, m) of a body whose standing box is `size`. Lying, it
    /// stretches along its heading to its standing height and is at most `LYING_HEIGHT_M` tall
    /// (a 1.8 m adult: 1.8 x 0.6 x 0.3 m); kneeling, it is half as tall and its shins lengthen
    /// its footprint to at least 0.45 of its standing height.
    pub fn apply(self, [l, w, h]: [f64; 3]) -> [f64; 3] {
        match self {
            Posture::Standing => [l, w, h],
            Posture::Kneeling => [l.max(0.45 * h), w, 0.5 * h],
            Posture::Lying => [l.max(h), w, h.min(LYING_HEIGHT_M)],
        }
    }
}

impl Checker {
    /// The posture of an agent of a kind of `class` and `motion` (its kind's, before `object`
    /// makes it static): only people and animals have one (E0130).
    pub(super) fn posture(
        &mut self,
        word_: Option<(&ast::Ident, Span)>,
        class: Option<Class>,
        motion: Option<Motion>,
    ) -> Option<Posture> {
        let Some((w, span)) = word_ else { return Some(Posture::Standing) };
        let p = word(self, w, &POSTURES, "posture")?;
        let (Some(class), Some(motion)) = (class, motion) else { return Some(p) };
        if class != Class::Pedestrian && motion != Motion::Holonomic {
            self.err(
                Diagnostic::error("E0130", format!("a {} has no posture", class.name()))
                    .label(span, "posture of a thing that is not a person or an animal")
                    .help("`posture` is for pedestrians and walking kinds (animals); set a box with `length`, `width`, `height`"),
            );
            return None;
        }
        Some(p)
    }
}
