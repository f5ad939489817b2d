//! Lamps and doors a box stream gives with a box (`"states"`, as `boxes.json` writes them): kept
//! as the replayed agent's `lights`, `hazards`, `beacons`, `siren` and `door` statements, so a
//! compiled clip imported back carries the same states (docs/output.md, "Vehicle states").

use crate::check::scenario::{Class, DOORS, EMERGENCY_KINDS};
use serde::Deserialize;
use std::collections::BTreeMap;

/// What one recorded box says of its lamps and doors; every field optional. `brake_lights` is
/// read and not kept: the rollout derives it from the replayed track's deceleration.
#[derive(Deserialize, Clone, Debug, Default, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StatesIn {
    #[serde(default)]
    pub headlights: Option<bool>,
    #[serde(default)]
    pub brake_lights: Option<bool>,
    #[serde(default)]
    pub hazards: Option<bool>,
    #[serde(default)]
    pub beacons: Option<bool>,
    #[serde(default)]
    pub siren: Option<bool>,
    /// Each open door's angle, degrees; a door not listed is shut.
    #[serde(default)]
    pub doors: BTreeMap<String, f64>,
}

/// The statements of a replayed agent of `class` and `kind` whose keyframes (clip frame, states
/// where the box gave some) are `keys`. A lamp is on where most boxes that state it say so; a door
/// opens where its angle starts to rise and closes where it starts to fall (then swinging at
/// rocc's rate, 70 degrees a second). Nothing is written for a lamp or a door the kind cannot carry (the checker's rules).
pub fn lines(class: Class, kind: &str, keys: &[(usize, Option<&StatesIn>)], rate: f64) -> Vec<String> {
    let stated: Vec<&StatesIn> = keys.iter().filter_map(|k| k.1).collect();
    if stated.is_empty() {
        return vec![];
    }
    let vote = |get: fn(&StatesIn) -> Option<bool>| {
        let said: Vec<bool> = stated.iter().filter_map(|s| get(s)).collect();
        (!said.is_empty()).then(|| 2 * said.iter().filter(|&&on| on).count() >= said.len())
    };
    let word = |on: bool| if on { "on" } else { "off" };
    let vehicle = class == Class::Vehicle;
    let emergency = EMERGENCY_KINDS.contains(&kind);
    let mut out = vec![];
    for (key, fits, on) in [
        ("lights", vehicle || class == Class::Bicycle, vote(|s| s.headlights)),
        ("hazards", vehicle, vote(|s| s.hazards)),
        ("beacons", emergency, vote(|s| s.beacons)),
        ("siren", emergency, vote(|s| s.siren)),
    ] {
        if let (true, Some(on)) = (fits, on) {
            out.push(format!("{key} {}", word(on)));
        }
    }
    if vehicle && kind != "motorcycle" {
        for (name, _) in DOORS {
            out.extend(door_moves(name, keys, rate));
        }
    }
    out
}

/// `door NAME open at T s` / `door NAME close at T s` from a door's recorded angles.
fn door_moves(name: &str, keys: &[(usize, Option<&StatesIn>)], rate: f64) -> Vec<String> {
    let mut out = vec![];
    // Opening: the last move written was `open`. A move is written where the angle turns.
    let (mut prev, mut opening) = (0.0, false);
    for &(f, s) in keys {
        let deg = s.and_then(|s| s.doors.get(name)).copied().unwrap_or(0.0);
        let t = super::num(f as f64 / rate);
        if !opening && deg > prev {
            out.push(format!("door {name} open at {t} s"));
            opening = true;
        } else if opening && deg < prev {
            out.push(format!("door {name} close at {t} s"));
            opening = false;
        }
        prev = deg;
    }
    out
}
