//! Decoders of single coded fields and narrative findings: damage areas, body types, speeds,
//! lanes, movements, directions. Each returns rocc's value and the citation it came from.

use super::ctx::Ctx;
use crate::check::scenario::Point;
use crate::ciren::case::{CaseVehicle, CirenCase, Coded};
use crate::ciren::crash::{Compass, Manoeuvre, Template, t_junction_turn};
use crate::ciren::narrative::{self, LanePos, Move, Narrative};
use crate::diag::Diagnostic;

/// A coded damage area (CDC general area).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Area {
    Front,
    Back,
    Left,
    Right,
    Top,
    Under,
    NotVehicle,
}

impl Area {
    pub fn point(self) -> Option<Point> {
        match self {
            Area::Front => Some(Point::Front),
            Area::Back => Some(Point::Rear),
            Area::Left => Some(Point::Left),
            Area::Right => Some(Point::Right),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Area::Front => "front",
            Area::Back => "back",
            Area::Left => "left side",
            Area::Right => "right side",
            Area::Top => "top",
            Area::Under => "undercarriage",
            Area::NotVehicle => "(not a vehicle)",
        }
    }
}

/// Decode a damage area: the CDC letter in `sasCode`, else the text.
pub fn area(c: &Coded) -> Option<Area> {
    match c.sas.as_str() {
        "F" => return Some(Area::Front),
        "B" => return Some(Area::Back),
        "L" => return Some(Area::Left),
        "R" => return Some(Area::Right),
        "T" => return Some(Area::Top),
        "U" => return Some(Area::Under),
        _ => {}
    }
    let t = c.lower();
    if t.contains("not a motor vehicle") {
        Some(Area::NotVehicle)
    } else if t.starts_with("front") {
        Some(Area::Front)
    } else if t.starts_with("back") || t.starts_with("rear") {
        Some(Area::Back)
    } else if t.starts_with("left") {
        Some(Area::Left)
    } else if t.starts_with("right") {
        Some(Area::Right)
    } else if t.starts_with("top") {
        Some(Area::Top)
    } else if t.starts_with("undercarriage") {
        Some(Area::Under)
    } else {
        None
    }
}

/// A rocc kind for a body type or vehicle class text; `None` when nothing fits.
pub fn kind_for(text: &str) -> Option<&'static str> {
    let t = text.to_ascii_lowercase();
    let has = |w: &str| t.contains(w);
    let k = if has("motorcycle") || has("moped") || has("motor scooter") {
        "motorcycle"
    } else if has("truck-tractor") || has("tractor-trailer") || has("tractor pulling") || has("semi") {
        "semi_truck"
    } else if has("ambulance") {
        "ambulance"
    } else if has("fire truck") {
        "fire_truck"
    } else if has("police") {
        "police_car"
    } else if has("bus") {
        "bus"
    } else if has("van") {
        "van"
    } else if has("pickup") {
        "pickup_truck"
    } else if has("utility") || has("suv") {
        "suv"
    } else if has("truck") {
        "truck"
    } else if has("hatchback") {
        "hatchback"
    } else if has("sedan")
        || has("coupe")
        || has("hardtop")
        || has("convertible")
        || has("station wagon")
        || has("compact")
        || has("intermediate")
        || has("full size")
        || has("largest")
        || has("passenger car")
    {
        "sedan"
    } else {
        return None;
    };
    Some(k)
}

pub(super) fn quote(s: &str) -> String {
    const MAX: usize = 110;
    if s.chars().count() <= MAX {
        format!("\"{s}\"")
    } else {
        let cut: String = s.chars().take(MAX).collect();
        format!("\"{}...\"", cut.trim_end())
    }
}

/// Whether a vehicle's own critical pre-crash event puts it at the origin of the conflict
/// ("Over the lane line ...", "Turning left at junction") rather than the other party
/// ("From crossing street ...", "From adjacent lane ...").
pub(super) fn own_event(v: &CaseVehicle) -> Option<bool> {
    let t = v.critical_event.as_ref()?.lower();
    if t.contains("unknown") { None } else { Some(!(t.starts_with("from") || t.starts_with("other"))) }
}

pub(super) fn speed_kmh(c: &Coded) -> Option<f64> {
    let v: f64 = c.value.parse().ok()?;
    if v <= 0.0 || v > 250.0 {
        return None;
    }
    Some(if c.unit.eq_ignore_ascii_case("mph") { v * 1.609_344 } else { v })
}

/// Coded movement, refined by the critical event and then by the narrative.
pub(super) fn manoeuvre(v: &CaseVehicle, text: Option<&narrative::VehicleText>) -> (Manoeuvre, String) {
    let pre = v.preevent_movement.as_ref().map(Coded::lower).unwrap_or_default();
    let crit = v.critical_event.as_ref().map(Coded::lower).unwrap_or_default();
    let cite_pre =
        v.preevent_movement.as_ref().map(|c| c.cite("PreeventMovement")).unwrap_or("PreeventMovement missing".into());
    let cite_crit = v.critical_event.as_ref().map(|c| c.cite("CriticalPrecrashEvent")).unwrap_or_default();
    if pre.contains("stopped") || pre.contains("parked") {
        return (Manoeuvre::Stopped, cite_pre);
    }
    if pre.contains("turning left") {
        return (Manoeuvre::TurnLeft, cite_pre);
    }
    if pre.contains("turning right") {
        return (Manoeuvre::TurnRight, cite_pre);
    }
    if pre.contains("merging") {
        return (Manoeuvre::Merge, cite_pre);
    }
    let own = !(crit.starts_with("from") || crit.starts_with("other"));
    if own && crit.contains("turning left") {
        return (Manoeuvre::TurnLeft, cite_crit);
    }
    if own && crit.contains("turning right") {
        return (Manoeuvre::TurnRight, cite_crit);
    }
    if own && crit.contains("lane line") && crit.contains("left") {
        return (Manoeuvre::ChangeLaneLeft, format!("{cite_pre}, {cite_crit}"));
    }
    if own && crit.contains("lane line") && crit.contains("right") {
        return (Manoeuvre::ChangeLaneRight, format!("{cite_pre}, {cite_crit}"));
    }
    if let Some(m) = text.and_then(|t| t.movement.as_ref()) {
        let man = match m.value {
            Move::TurnLeft => Manoeuvre::TurnLeft,
            Move::TurnRight => Manoeuvre::TurnRight,
            Move::VeerLeft => Manoeuvre::ChangeLaneLeft,
            Move::VeerRight => Manoeuvre::ChangeLaneRight,
        };
        if !pre.contains("going straight") || matches!(man, Manoeuvre::ChangeLaneLeft | Manoeuvre::ChangeLaneRight) {
            return (man, format!("Summary {}", quote(&m.quote)));
        }
    }
    if pre.contains("unknown") || pre.is_empty() {
        if crit.contains("crossing over") || crit.contains("passing through") {
            return (Manoeuvre::Straight, cite_crit);
        }
        return (Manoeuvre::Straight, format!("{cite_pre}: straight on"));
    }
    (Manoeuvre::Straight, cite_pre)
}

/// Lanes per direction of a vehicle's road, with the centre lane (if any) and the reason.
pub(super) fn lanes_of(v: &CaseVehicle, t: Option<&narrative::VehicleText>) -> Option<(u32, bool, String)> {
    if let Some(l) = t.and_then(|t| t.lanes.as_ref()) {
        let x = l.value;
        let (per, centre) = if let Some(p) = x.per_direction {
            (p, x.centre_lane || (!x.divided && x.total > 2 * p))
        } else if x.one_way {
            (x.total, false)
        } else {
            ((x.total / 2).max(1), x.total % 2 == 1 && x.total > 1)
        };
        return Some((per, centre, format!("Summary {}", quote(&l.quote))));
    }
    let c = v.travel_lanes.as_ref()?;
    let n: u32 = c.value.parse().ok().filter(|n| (1..=12).contains(n))?;
    let divided = v.relation_to_flow.as_ref().is_some_and(|f| f.lower().starts_with("divided"));
    let cite = format!(
        "{}{}",
        c.cite("TravelLanes"),
        v.relation_to_flow.as_ref().map(|f| format!(", {}", f.cite("RelationToFlow"))).unwrap_or_default()
    );
    Some(if divided { (n, false, cite) } else { ((n / 2).max(1), n % 2 == 1 && n > 1, cite) })
}

pub(super) fn travel_of(
    cx: &mut Ctx,
    story: &Narrative,
    v: &CaseVehicle,
    fallback: Compass,
    why: &str,
) -> (Compass, String) {
    match story.vehicle(v.number).and_then(|t| t.travel.as_ref()) {
        Some(f) => (f.value, format!("Summary {}", quote(&f.quote))),
        None => {
            let sp = cx.case.summary.as_ref().map(|s| cx.span(s));
            cx.warn(format!("the narrative gives no direction of travel for V{}; {why}", v.number), sp);
            (fallback, format!("direction not narrated: {why}"))
        }
    }
}

pub(super) fn vehicle_kind(
    cx: &mut Ctx,
    v: &CaseVehicle,
    class: Option<&Coded>,
) -> Result<(String, String), Vec<Diagnostic>> {
    let what = [v.year.as_deref(), v.make.as_deref(), v.model.as_deref()]
        .iter()
        .flatten()
        .copied()
        .collect::<Vec<_>>()
        .join(" ");
    if let Some(b) = &v.body_type {
        if let Some(k) = kind_for(&b.text) {
            return Ok((k.into(), format!("{what}; {} -> {k}", b.cite("BodyType"))));
        }
        if !b.lower().contains("unknown") {
            return Err(cx.unknown("BodyType", b, "body types rocc maps: cars, utility vehicles, vans, pickups, trucks, tractor-trailers, buses, motorcycles"));
        }
    }
    if let Some(c) = class
        && let Some(k) = kind_for(&c.text)
    {
        return Ok((k.into(), format!("{what}; BodyType unknown, {} -> {k}", c.cite("Class"))));
    }
    let at = v.body_type.as_ref().map(|b| cx.span(b));
    cx.warn(format!("V{} has no usable body type or class; a sedan is assumed", v.number), at);
    Ok(("sedan".into(), format!("{what}; body type unknown: sedan assumed")))
}

pub(super) fn speed_of(cx: &mut Ctx, v: &CaseVehicle, road_limit: f64, man: Manoeuvre) -> (f64, String) {
    if let Some(s) = v.travel_speed.as_ref().and_then(speed_kmh) {
        return (s, format!("TravelSpeed {} km/h", crate::ciren::emit::num(s)));
    }
    let posted = v.posted_speed.as_ref().and_then(speed_kmh);
    let (base, cite) = match posted {
        Some(p) => (p, format!("TravelSpeed unknown; PostedSpeedLimit {} km/h", crate::ciren::emit::num(p))),
        None => {
            let at = v.posted_speed.as_ref().map(|c| cx.span(c));
            cx.warn(
                format!(
                    "V{} has neither travel speed nor posted limit; the road's {} km/h is used",
                    v.number,
                    crate::ciren::emit::num(road_limit)
                ),
                at,
            );
            (
                road_limit,
                format!("no TravelSpeed or PostedSpeedLimit: road limit {} km/h", crate::ciren::emit::num(road_limit)),
            )
        }
    };
    if matches!(man, Manoeuvre::TurnLeft | Manoeuvre::TurnRight) && base > TURN_KMH {
        return (TURN_KMH, format!("{cite}; turning: {TURN_KMH} km/h"));
    }
    (base, cite)
}

/// Speed of a vehicle turning at a junction when no travel speed is coded, km/h.
pub const TURN_KMH: f64 = 25.0;

pub(super) fn road_limit(cx: &mut Ctx, vs: &[&CaseVehicle]) -> (f64, String) {
    let limits: Vec<f64> = vs.iter().filter_map(|v| v.posted_speed.as_ref().and_then(speed_kmh)).collect();
    match limits.iter().copied().reduce(f64::max) {
        Some(l) => {
            (l, format!("PostedSpeedLimit {} km/h (the highest of the vehicles' roads)", crate::ciren::emit::num(l)))
        }
        None => {
            cx.warn("no posted speed limit is coded; 50 km/h is assumed".into(), None);
            (50.0, "no PostedSpeedLimit coded: 50 km/h assumed".into())
        }
    }
}

pub(super) fn lane_index(pos: Option<&narrative::Found<LanePos>>, lanes: u32) -> (u32, String) {
    match pos {
        Some(p) => match p.value {
            LanePos::Left => (1, "left lane -> in[1]".into()),
            LanePos::Right => (lanes, format!("right lane -> in[{lanes}]")),
            LanePos::Center => (1, "centre lane -> in[1] (next to the centre line)".into()),
        },
        None => (1, "lane position not narrated -> in[1]".into()),
    }
}

/// The EventSum class of a vehicle (a size class, used when the body type is unknown).
pub(super) fn cx_class(case: &CirenCase, n: u32) -> Option<Coded> {
    case.events.iter().find(|e| e.vehicle == n).and_then(|e| e.class.clone()).or_else(|| {
        case.events
            .iter()
            .find(|e| e.contacted.as_ref().is_some_and(|c| c.text.ends_with(&format!("#{n}"))))
            .and_then(|e| e.contacted_class.clone())
    })
}

/// The manoeuvre a template can hold for a vehicle starting on `arm.in[lane]`: turns off a road
/// without a junction, lane changes with no lane to go to and merges off a merge are driven
/// straight on, and a T's missing leg is avoided; each fallback said in `notes`.
pub(super) fn fit_manoeuvre(
    template: Template,
    arm: &str,
    lane: u32,
    lanes: u32,
    man: Manoeuvre,
    notes: &mut Vec<String>,
) -> Manoeuvre {
    let junction = template.has_junction();
    let man = match man {
        Manoeuvre::TurnLeft | Manoeuvre::TurnRight if !junction => {
            notes.push("a turn off a road without a junction is driven straight on".into());
            Manoeuvre::Straight
        }
        Manoeuvre::ChangeLaneLeft if lane <= 1 => {
            notes.push("no lane to its left: straight on; the staging moves it into the conflict".into());
            Manoeuvre::Straight
        }
        Manoeuvre::ChangeLaneRight if lane >= lanes => {
            notes.push("no lane to its right: straight on; the staging moves it into the conflict".into());
            Manoeuvre::Straight
        }
        Manoeuvre::Merge if template != Template::Merge => Manoeuvre::Straight,
        m => m,
    };
    t_junction_turn(template, arm, man, notes)
}
