//! Coded CIREN record -> `Crash`. In: a `CirenCase` (and its file id for spans). Out: the crash
//! description, or the specific reason rocc cannot represent the case.
//!
//! The coded fields decide what they cover (damage areas, configuration, movement, speeds,
//! vehicle types, junction relation, lane counts); the narrative fills what they lack (compass
//! directions, leg count, lane position) by the rules in `narrative.rs`. Every choice is kept
//! as a comment line citing the field or the sentence; a default that is neither coded nor
//! narrated is a warning (E0807), never silent.

mod ctx;
mod fields;
mod force;
mod object;
mod pair;

use crate::ciren::case::{CirenCase, Coded, Event};
use crate::ciren::narrative::{self, Narrative};
use crate::diag::Diagnostic;
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

    // The first-ranked event is the one staged.
    let mut events: Vec<&Event> = case.events.iter().collect();
    events.sort_by_key(|e| (e.rank.unwrap_or(u32::MAX), e.number, e.vehicle));
    let Some(ev) = events.first().copied() else {
        return Err(cx.err(
            "E0802",
            "no Events/EventSum row: the record codes no collision".into(),
            None,
            "a case needs at least one EventSum with AreaOfDamage, Contacted and ContactedAreaOfDamage",
        ));
    };
    for other in events.iter().skip(1) {
        let d = Diagnostic::warning(
            "E0806",
            format!(
                "case {}: event {} of V{} is not staged; rocc stages the first-ranked event",
                case.id, other.number, other.vehicle
            ),
        )
        .label(cx.tag_span(&other.range, "EventSum"), "left out")
        .help("one conflict per scenario: the later contacts of a multi-event crash are not recreated");
        cx.warnings.push(d);
    }
    let ev_span = cx.tag_span(&ev.range, "EventSum");
    let need = |c: &Option<Coded>, what: &str| {
        c.clone().ok_or_else(|| {
            cx.err(
                "E0802",
                format!("EventSum of V{} has no {what}", ev.vehicle),
                Some((ev_span, "this event")),
                "the event's damage areas and contacted party are required",
            )
        })
    };
    let area_c = need(&ev.area, "AreaOfDamage")?;
    let contacted = need(&ev.contacted, "Contacted")?;
    let own_area =
        area(&area_c).ok_or_else(|| cx.unknown("AreaOfDamage", &area_c, "known CDC areas: F, B, L, R, T, U"))?;
    let vehicle = |n: u32| case.vehicles.iter().find(|v| v.number == n);
    let Some(me) = vehicle(ev.vehicle) else {
        return Err(cx.err(
            "E0802",
            format!("the event names V{} but the record has no GeneralVehicleForm for it", ev.vehicle),
            Some((ev_span, "this event")),
            "each vehicle of the event needs its GeneralVehicleForm (body type, pre-crash data)",
        ));
    };

    let mut header = vec![
        format!("CIREN case {}, imported by `rocc ciren import` from {}.", case.id, case.path),
        format!(
            "{}; {}.",
            case.crash_type.as_ref().map(|c| c.cite("CrashType")).unwrap_or("CrashType missing".into()),
            config.cite("Configuration")
        ),
    ];
    let contacted_t = contacted.lower();
    let other_no: Option<u32> =
        contacted_t.split('#').nth(1).and_then(|n| n.trim().split(|c: char| !c.is_ascii_digit()).next()?.parse().ok());

    if let Some(on) = other_no.filter(|_| contacted_t.contains("vehicle")) {
        let other_area_c = need(&ev.contacted_area, "ContactedAreaOfDamage")?;
        let other_area = area(&other_area_c)
            .ok_or_else(|| cx.unknown("ContactedAreaOfDamage", &other_area_c, "known CDC areas: F, B, L, R, T, U"))?;
        let Some(other) = vehicle(on) else {
            return Err(cx.err(
                "E0802",
                format!("V{} contacted V{on}, which has no GeneralVehicleForm", ev.vehicle),
                Some((cx.span(&contacted), "this vehicle")),
                "each vehicle of the event needs its GeneralVehicleForm (body type, pre-crash data)",
            ));
        };
        header.push(format!(
            "EventSum {}: V{} {}, {}, {}.",
            ev.number,
            ev.vehicle,
            area_c.cite("AreaOfDamage"),
            contacted.cite("Contacted"),
            other_area_c.cite("ContactedAreaOfDamage")
        ));
        pair::two_vehicles(&mut cx, &story, header, (me, own_area, &area_c), (other, other_area, &other_area_c))
    } else {
        header.push(format!(
            "EventSum {}: V{} {}, {}.",
            ev.number,
            ev.vehicle,
            area_c.cite("AreaOfDamage"),
            contacted.cite("Contacted")
        ));
        object::single_vehicle(&mut cx, &story, header, me, own_area, &area_c, &contacted)
    }
    .map(|mut crash| {
        force::annotate(&cx, &mut crash, ev.number);
        Mapped { crash, warnings: cx.warnings }
    })
}
