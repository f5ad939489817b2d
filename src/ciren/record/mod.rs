//! Coded CIREN record -> `Crash`. In: a `CirenCase` (and its file id for spans). Out: the crash
//! description, or the specific reason rocc cannot represent the case.
//!
//! The coded fields decide what they cover (damage areas, configuration, movement, speeds,
//! vehicle types, junction relation, lane counts); the narrative fills what they lack (compass
//! directions, leg count, lane position) by the rules in `narrative.rs`. Every choice is kept
//! as a comment line citing the field or the sentence; a default that is neither coded nor
//! narrated is a warning (E0807), never silent.

mod ctx;
mod events;
mod fields;
mod force;
mod object;
mod pair;

use crate::ciren::case::CirenCase;
use crate::ciren::narrative::{self, Narrative};
use crate::diag::Diagnostic;
use crate::source::Span;
use ctx::Ctx;
pub use ctx::Mapped;
pub use fields::{Area, TURN_KMH, area, kind_for};

/// Map a case to a crash.
pub fn map_case(case: &CirenCase, file: u32) -> Result<Mapped, Vec<Diagnostic>> {
    let mut cx = Ctx { case, file, warnings: Vec::new() };
    let text = case.summary.as_ref().map(|s| s.text.clone()).unwrap_or_default();
    let story: Narrative = narrative::read(&text);

    // Rollovers first: the most specific reason there is.
    for v in &case.vehicles {
        if let Some(r) = &v.rollover {
            let t = r.lower();
            if t.contains("rollover") && !t.contains("no rollover")
                || t.contains("overturn") && !t.contains("no overturn")
            {
                return Err(cx.err(
                    "E0804",
                    format!("V{} rolled over ({})", v.number, r.cite("Rollover Type")),
                    Some((cx.span(r), "rollover coded here")),
                    "rocc stages planar contacts between boxes on the ground; a rollover cannot be represented",
                ));
            }
        }
    }
    let Some(config) = &case.configuration else {
        return Err(cx.err(
            "E0802",
            "no CaseSummary/Configuration field".into(),
            None,
            "the crash configuration (Angle/sideswipe, Head-on, Rear end, Object off road, ...) is required",
        ));
    };
    let cfg = config.lower();
    if cfg.contains("rollover") || cfg.contains("non-collision") || cfg.contains("noncollision") {
        return Err(cx.err(
            "E0804",
            format!("{} is not a collision between two boxes", config.cite("Configuration")),
            Some((cx.span(config), "here")),
            "rocc stages collisions between vehicles, or a vehicle and a fixed object",
        ));
    }
    if cfg.contains("pedestrian") {
        return Err(cx.err(
            "E0804",
            format!(
                "{}: pedestrian records carry no coded pedestrian motion rocc could stage",
                config.cite("Configuration")
            ),
            Some((cx.span(config), "here")),
            "write the scenario by hand with `impact pedestrian`",
        ));
    }
    let known_cfg = ["angle", "sideswipe", "head", "rear", "object"];
    if !known_cfg.iter().any(|k| cfg.contains(k)) {
        return Err(cx.unknown(
            "Configuration",
            config,
            "known: Angle/sideswipe, Head-on, Rear end, Object off road / in road (rollovers are refused)",
        ));
    }

    // Every contact in time order; the first-ranked one sets the road.
    let (contacts, primary) = events::contacts(&cx)?;
    let c0 = &contacts[primary];
    let mut header = vec![
        format!("CIREN case {}, imported by `rocc ciren import` from {}.", case.id, case.path),
        format!(
            "{}; {}.",
            case.crash_type.as_ref().map(|c| c.cite("CrashType")).unwrap_or("CrashType missing".into()),
            config.cite("Configuration")
        ),
    ];
    header.push(c0.cite());
    let mut crash = match &c0.other {
        events::Party::Vehicle(other, oa, oc) => {
            pair::two_vehicles(&mut cx, &story, header, (c0.me, c0.own, &c0.own_c), (other, *oa, oc))?
        }
        events::Party::Object => {
            object::single_vehicle(&mut cx, &story, header, c0.me, c0.own, &c0.own_c, &c0.contacted)?
        }
    };
    // The others join in time order around it.
    let mut conflicts = Vec::new();
    for (i, c) in contacts.iter().enumerate() {
        let k = if i == primary {
            crash.conflicts[0].clone()
        } else {
            events::join(&mut cx, &story, &mut crash, c, &conflicts)?
        };
        conflicts.push(k);
    }
    crash.conflicts = conflicts;
    let spans: Vec<(u32, Span)> =
        contacts.iter().map(|c| (c.ev.number, cx.tag_span(&c.ev.range, "EventSum"))).collect();
    events::check_order(&cx, &crash, &spans)?;
    for (i, c) in contacts.iter().enumerate() {
        // The slide sets the force of a strike it brings about; only staged strikes are held to theirs.
        if !crash.on_slide(&crash.conflicts[i]) {
            force::annotate(&cx, &mut crash, i, c.ev.number);
        }
    }
    Ok(Mapped { crash, warnings: cx.warnings })
}
