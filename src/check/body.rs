//! A vehicle's lamps and doors as stated: `lights on`, `hazards on`, `beacons off` and
//! `door front_left open at 3 s` / `door front_left open when bike within 8 m`
//! (scenarios/rare/dooring.scn). What each lamp shows per frame, and each door's swing, is
//! derived after the rollout (`rollout::body`) and written in `boxes.json`.

use super::scenario::{Class, EMERGENCY_KINDS, Trigger};
use super::units::Dim;
use super::{Checker, MAX_DURATION_S, word};
use crate::diag::Diagnostic;
use crate::syntax::ast;
use serde::{Deserialize, Serialize};

/// The lamps and doors an agent states; everything unstated takes its default (docs/output.md,
/// "Vehicle states").
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Body {
    /// `lights on|off`: headlights; off unless stated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lights: Option<bool>,
    /// `hazards on|off`; unstated, on for a vehicle standing on a travel lane.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hazards: Option<bool>,
    /// `beacons on|off` (emergency vehicles); unstated, on with the siren.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beacons: Option<bool>,
    /// Door movements, in the order written.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub doors: Vec<DoorMove>,
}

impl Body {
    pub fn is_default(&self) -> bool {
        *self == Body::default()
    }
}

/// A side door, named from the driver's seat.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Door {
    FrontLeft,
    FrontRight,
    RearLeft,
    RearRight,
}

pub const DOORS: [(&str, Door); 4] = [
    ("front_left", Door::FrontLeft),
    ("front_right", Door::FrontRight),
    ("rear_left", Door::RearLeft),
    ("rear_right", Door::RearRight),
];

impl Door {
    pub fn name(self) -> &'static str {
        DOORS.iter().find(|d| d.1 == self).map(|d| d.0).expect("every door is listed")
    }
    pub fn is_left(self) -> bool {
        matches!(self, Door::FrontLeft | Door::RearLeft)
    }
    pub fn is_front(self) -> bool {
        matches!(self, Door::FrontLeft | Door::FrontRight)
    }
}

/// `door NAME open|close (at TIME | when ...)`: the door starts to swing at `at` s, or on the
/// first frame its trigger holds (`who` an agent index).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DoorMove {
    pub door: Door,
    pub open: bool,
    pub at: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub when: Option<Trigger>,
}

/// Kinds of the vehicle class that have no doors to open.
const DOORLESS_KINDS: [&str; 1] = ["motorcycle"];

/// The statements of one agent that `body` reads.
#[derive(Default)]
pub(super) struct BodyStmts<'a> {
    pub lamps: Vec<(&'a ast::Ident, &'a ast::Ident, crate::source::Span)>,
    pub doors: Vec<&'a ast::DoorStmt>,
}

impl Checker {
    /// Lamps and doors of an agent of `class` whose kinds are `kinds`: headlights and hazards on
    /// vehicles and bicycles' lights only (E0240), beacons on emergency kinds only (E0241), a
    /// lamp stated twice (E0105), doors on vehicles with doors only (E0242), known door names
    /// and actions (E0116), and door triggers that can be read on the tracks (E0243).
    pub(super) fn body(&mut self, s: &BodyStmts, class: Class, kinds: &[String], order: &[&str]) -> Option<Body> {
        let mut body = Body::default();
        let mut ok = true;
        let mut firsts: Vec<(&str, crate::source::Span)> = vec![];
        for &(key, value, span) in &s.lamps {
            if let Some(&(_, first)) = firsts.iter().find(|f| f.0 == key.name) {
                self.dup(&format!("`{}`", key.name), first, span);
                ok = false;
                continue;
            }
            firsts.push((&key.name, span));
            let Some(on) = word(self, value, &[("on", true), ("off", false)], "lamp setting") else {
                ok = false;
                continue;
            };
            let slot = match key.name.as_str() {
                "lights" => &mut body.lights,
                "hazards" => &mut body.hazards,
                _ => &mut body.beacons,
            };
            *slot = Some(on);
            ok &= self.lamp_fits(key, span, class, kinds);
        }
        for d in &s.doors {
            match self.door_move(d, class, kinds, order) {
                Some(m) => body.doors.push(m),
                None => ok = false,
            }
        }
        ok.then_some(body)
    }

    /// Whether lamp `key` fits the kind (E0240, E0241).
    fn lamp_fits(&mut self, key: &ast::Ident, span: crate::source::Span, class: Class, kinds: &[String]) -> bool {
        let k = kinds.first().map_or("", String::as_str);
        let fits = match key.name.as_str() {
            "lights" => matches!(class, Class::Vehicle | Class::Bicycle),
            "hazards" => class == Class::Vehicle,
            _ => kinds.iter().all(|k| self.is_emergency(k)),
        };
        if !fits {
            let (code, help) = if key.name == "beacons" {
                ("E0241", "only ambulance, fire_truck, police_car and kinds derived from them carry beacons")
            } else if key.name == "hazards" {
                ("E0240", "hazard lights are on vehicles; a bicycle, a person or an object has none")
            } else {
                ("E0240", "headlights are on vehicles and bicycles")
            };
            self.err(
                Diagnostic::error(code, format!("`{k}` has no {}", key.name))
                    .label(span, format!("`{}` on a kind without them", key.name))
                    .help(help),
            );
        }
        fits
    }

    fn is_emergency(&self, k: &str) -> bool {
        EMERGENCY_KINDS.contains(&k) || self.kinds.get(k).is_some_and(|(kind, _)| kind.emergency)
    }

    /// One `door` statement: a vehicle with doors (E0242), a known door and action (E0116), a
    /// time within the clip's limit, or a trigger read on the tracks (E0243).
    fn door_move(&mut self, d: &ast::DoorStmt, class: Class, kinds: &[String], order: &[&str]) -> Option<DoorMove> {
        if class != Class::Vehicle || kinds.iter().any(|k| DOORLESS_KINDS.contains(&k.as_str())) {
            let k = kinds.iter().find(|k| class != Class::Vehicle || DOORLESS_KINDS.contains(&k.as_str()));
            self.err(
                Diagnostic::error("E0242", format!("`{}` has no doors", k.map_or("", String::as_str)))
                    .label(d.span, "door on a kind without doors")
                    .help("doors are on cars, vans, trucks and buses (class vehicle, not motorcycle)"),
            );
            return None;
        }
        let door = word(self, &d.door, &DOORS, "door");
        let open = word(self, &d.action, &[("open", true), ("close", false)], "door action");
        let (at, when) = match (&d.at, &d.when) {
            (Some(v), _) => (self.fixed(v, Dim::Time, "door time", 0.0, MAX_DURATION_S, "0..120 s")?, None),
            (None, Some(w)) => {
                let t = self.trigger(w, order)?;
                if !matches!(t, Trigger::Within { .. } | Trigger::Ttc { .. }) {
                    self.err(
                        Diagnostic::error("E0243", format!("a door opens on `within` or `ttc`, not `{}`", w.cond.name))
                            .label(w.span, "condition a door cannot watch")
                            .help("e.g. `door front_left open when bike within 8 m` or `... when bike ttc under 2 s`"),
                    );
                    return None;
                }
                (0.0, Some(t))
            }
            (None, None) => unreachable!("grammar: a door statement has `at` or `when`"),
        };
        Some(DoorMove { door: door?, open: open?, at, when })
    }
}
