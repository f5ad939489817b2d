//! One SAFE `Conflict` entry -> a `ConflictDesc`: the free-text `point_of_impact` decides the
//! struck side and the striking face; `impact_type` and `struck_vehicle` are checked against it
//! (the damage geometry wins, with a warning E0807); `at_fault_vehicle` keeps its manoeuvre.

use super::poi::*;
use super::{Actor, Ctx, str_of};
use crate::check::scenario::{Impact, Point};
use crate::ciren::crash::{ConflictDesc, Face};
use crate::diag::Diagnostic;
use serde_json::Value;

/// Decode entry `which.0` of `which.1` (time order).
pub(super) fn decode(
    cx: &mut Ctx,
    conflict: &Value,
    actors: &[Actor],
    which: (usize, usize),
) -> Result<ConflictDesc, Vec<Diagnostic>> {
    let get = |k: &str| str_of(conflict, k).map(str::to_string);
    let name_no = |cx: &Ctx, key: &str| -> Result<u32, Vec<Diagnostic>> {
        let s = get(key).ok_or_else(|| {
            cx.err(
                "E0802",
                "Conflict",
                format!("`Conflict.{key}` is missing"),
                "name a listed actor, e.g. \"Vehicle_1\"",
            )
        })?;
        let lower = s.to_ascii_lowercase().replace(' ', "_");
        let n = vehicle_no(&lower, None).filter(|n| actors.iter().any(|a| a.n == *n));
        n.ok_or_else(|| {
            cx.err(
                "E0803",
                key,
                format!("`{key}` \"{s}\" names no listed actor"),
                "name a listed actor, e.g. \"Vehicle_1\"",
            )
        })
    };
    let at_fault_no = name_no(cx, "at_fault_vehicle")?;
    let single = actors.len() == 1;
    let struck_no = if single { None } else { Some(name_no(cx, "struck_vehicle")?) };
    if single {
        return Err(cx.err(
            "E0804",
            "Actors",
            "a single-vehicle extraction: SAFE's format names no struck object rocc could place".into(),
            "import the coded record with `rocc ciren import`, which maps the struck tree or pole",
        ));
    }
    if actors.len() > 2 && which.1 == 1 {
        return Err(cx.err(
            "E0804",
            "Actors",
            format!(
                "{} actors: SAFE's Conflict block describes one pair, and the others' roles are not extracted",
                actors.len()
            ),
            "rocc stages the pairs a `Conflict` list names, one impact per entry in time order",
        ));
    }
    let impact_raw = get("impact_type").ok_or_else(|| {
        cx.err("E0802", "Conflict", "`Conflict.impact_type` is missing".into(), "e.g. \"T-bone\", \"head-on\"")
    })?;
    let it = impact_raw.to_ascii_lowercase().replace(['-', '_'], " ");
    let impact_said =
        if it.contains("t bone") || it.contains("angle") || it.contains("broadside") || it.contains("side impact") {
            Impact::Angle
        } else if it.contains("head on") || it.contains("frontal") {
            Impact::HeadOn
        } else if it.contains("rear") {
            Impact::RearEnd
        } else if it.contains("sideswipe") || it.contains("side swipe") {
            Impact::Sideswipe
        } else {
            return Err(cx.err(
                "E0803",
                "impact_type",
                format!("unknown impact_type \"{impact_raw}\""),
                "known: T-bone, angle, head-on, rear-end, sideswipe",
            ));
        };
    let poi_raw = get("point_of_impact").ok_or_else(|| {
        cx.err(
            "E0802",
            "Conflict",
            "`Conflict.point_of_impact` is missing".into(),
            "e.g. \"front of V2 struck right side of V1\"",
        )
    })?;
    let poi = parse_point_of_impact(&poi_raw);
    let first_other = |n: u32| actors.iter().map(|a| a.n).find(|&m| m != n).unwrap_or(n);
    let struck_field = struck_no.unwrap_or(first_other(at_fault_no));
    // The entry's other party: its named pair first (an extraction may list more than two actors).
    let other_of = |n: u32| match (n == at_fault_no, n == struck_field) {
        (true, false) => struck_field,
        (false, true) => at_fault_no,
        _ => first_other(n),
    };

    let entry = if which.1 > 1 { format!("Conflict {} of {}", which.0 + 1, which.1) } else { "Conflict".into() };
    let mut conflict_notes = vec![format!(
        "{entry}: at_fault_vehicle \"{}\", struck_vehicle \"{}\", impact_type \"{impact_raw}\", point_of_impact \"{poi_raw}\".",
        get("at_fault_vehicle").unwrap_or_default(),
        get("struck_vehicle").unwrap_or_default()
    )];
    let known = |n: &Named| actors.iter().any(|a| a.n == n.vehicle);
    // Decide striker, struck, impact, point and face.
    let (striker, struck, impact, point, face) = match (poi.striker.filter(known), poi.struck.filter(known)) {
        (Some(a), Some(b)) if a.vehicle != b.vehicle => {
            match (a.part, b.part, poi.mutual) {
                // Front to front is symmetric in the text: the at-fault field decides who strikes.
                (Some(Part::Point(pa)), Some(Part::Point(pb)), _) if is_front(pa) && is_front(pb) => {
                    let (af, st) =
                        if b.vehicle == at_fault_no { (b.vehicle, a.vehicle) } else { (a.vehicle, b.vehicle) };
                    (af, st, Impact::HeadOn, Point::Front, Face::Front)
                }
                (Some(Part::Point(pa)), Some(Part::Point(pb)), _) if is_front(pa) && !is_front(pb) => {
                    let imp = if is_rear(pb) { Impact::RearEnd } else { Impact::Angle };
                    (a.vehicle, b.vehicle, imp, pb, Face::Front)
                }
                (Some(Part::Point(pa)), Some(Part::Point(pb)), true) if is_front(pb) && !is_front(pa) => {
                    let imp = if is_rear(pa) { Impact::RearEnd } else { Impact::Angle };
                    (b.vehicle, a.vehicle, imp, pa, Face::Front)
                }
                (Some(Part::Point(pa)), Some(Part::Point(pb)), _) if hand(pa).is_some() && hand(pb).is_some() => {
                    let (af, st, fa, pt) = if a.vehicle == at_fault_no || b.vehicle != at_fault_no {
                        (a.vehicle, b.vehicle, pa, pb)
                    } else {
                        (b.vehicle, a.vehicle, pb, pa)
                    };
                    let f = if hand(fa) == Some(true) { Face::Left } else { Face::Right };
                    (af, st, Impact::Sideswipe, pt, f)
                }
                // One side named, the other party's part a side of unknown hand (a trailer): a
                // side-to-side contact. The at-fault vehicle strikes with its named side; the
                // other's side is the one facing it.
                (pa, pb, _) if side_pair(pa, pb).is_some() => {
                    let (named, other, hand_left) = match side_pair(pa, pb) {
                        Some(true) => (a.vehicle, b.vehicle, hand(part_point(pa)).unwrap_or(true)),
                        _ => (b.vehicle, a.vehicle, hand(part_point(pb)).unwrap_or(true)),
                    };
                    let (af, st) = if other == at_fault_no { (other, named) } else { (named, other) };
                    // Same direction: the at-fault's left meets the other's right.
                    let (face, point) = if af == named {
                        (
                            if hand_left { Face::Left } else { Face::Right },
                            if hand_left { Point::Right } else { Point::Left },
                        )
                    } else {
                        (
                            if hand_left { Face::Right } else { Face::Left },
                            if hand_left { Point::Left } else { Point::Right },
                        )
                    };
                    let msg = format!(
                        "point_of_impact \"{poi_raw}\" names V{}'s {} side and only a side of unknown hand of V{}: staged as a sideswipe, v{af}'s {} against v{st}'s {} side",
                        named,
                        if hand_left { "left" } else { "right" },
                        other,
                        face.name(),
                        point.name()
                    );
                    cx.warn("point_of_impact", msg.clone());
                    conflict_notes.push(format!("Ambiguous: {msg}."));
                    (af, st, Impact::Sideswipe, point, face)
                }
                _ => {
                    return Err(cx.err(
                        "E0808",
                        "point_of_impact",
                        format!("point_of_impact \"{poi_raw}\" names no striking face and struck side rocc can map"),
                        "write it as `PART of V<n> struck PART of V<m>` with PART front, rear, left side, right side or a corner",
                    ));
                }
            }
        }
        (_, Some(b)) if b.part.is_some() => {
            // Only the struck vehicle's part: the other party strikes with its front.
            let Some(Part::Point(pb)) = b.part else {
                return Err(cx.err(
                    "E0808",
                    "point_of_impact",
                    format!("point_of_impact \"{poi_raw}\" names a side of unknown hand"),
                    "name left or right",
                ));
            };
            let af = other_of(b.vehicle);
            let msg = format!("point_of_impact \"{poi_raw}\" names no striking part; v{af}'s front is assumed");
            cx.warn("point_of_impact", msg.clone());
            conflict_notes.push(format!("Ambiguous: {msg}."));
            // Front to (assumed) front is a head-on whatever impact_type says: an angle crash
            // reaches a side or a corner (E0120), and the mismatch is reported below.
            let imp = if pb == Point::Front {
                Impact::HeadOn
            } else if is_rear(pb) {
                Impact::RearEnd
            } else {
                Impact::Angle
            };
            (af, b.vehicle, imp, pb, Face::Front)
        }
        _ => {
            return Err(cx.err(
                "E0808",
                "point_of_impact",
                format!("point_of_impact \"{poi_raw}\" cannot be read: it names no vehicle part rocc can map"),
                "write it as `PART of V<n> struck PART of V<m>` with PART front, rear, left side, right side or a corner",
            ));
        }
    };
    if struck != struck_field {
        let msg = format!(
            "struck_vehicle says Vehicle_{struck_field}, but point_of_impact \"{poi_raw}\" has V{struck} struck; the point_of_impact (the damage geometry) is followed"
        );
        cx.warn("struck_vehicle", msg.clone());
        conflict_notes.push(format!("Contradiction: {msg}."));
    }
    if impact != impact_said {
        let msg = format!(
            "impact_type \"{impact_raw}\" does not fit point_of_impact \"{poi_raw}\"; staged as {}",
            crate::ciren::crash::impact_name(impact)
        );
        cx.warn("impact_type", msg.clone());
        conflict_notes.push(format!("Contradiction: {msg}."));
    }
    if striker != at_fault_no {
        conflict_notes.push(format!(
            "at_fault_vehicle is Vehicle_{at_fault_no}: its manoeuvre is kept as its goal; rocc's `at_fault` is the striking v{striker}, whose {} meets v{struck}'s {} side.",
            face.name(),
            point.name()
        ));
    } else {
        conflict_notes.push(format!("at_fault_vehicle Vehicle_{at_fault_no} strikes with its {}.", face.name()));
    }
    Ok(ConflictDesc {
        at: None,
        clocks: Vec::new(),
        closing: None,
        at_fault: format!("v{striker}"),
        struck: format!("v{struck}"),
        impact,
        point,
        face,
        notes: conflict_notes,
    })
}
