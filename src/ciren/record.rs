//! Coded CIREN record -> `Crash`. In: a `CirenCase` (and its file id for spans). Out: the crash
//! description, or the specific reason rocc cannot represent the case.
//!
//! The coded fields decide what they cover (damage areas, configuration, movement, speeds,
//! vehicle types, junction relation, lane counts); the narrative fills what they lack (compass
//! directions, leg count, lane position) by the rules in `narrative.rs`. Every choice is kept
//! as a comment line citing the field or the sentence; a default that is neither coded nor
//! narrated is a warning (E0807), never silent.

use super::case::{CaseVehicle, CirenCase, Coded, Event};
use super::crash::{
    Compass, ConflictDesc, Crash, Face, Manoeuvre, ObjectDesc, RoadDesc, Side, Template, VehicleDesc, approach_arm,
    man_word, t_junction_turn,
};
use super::narrative::{self, Junction, LanePos, Move, Narrative, Side2};
use crate::check::scenario::{Impact, Point};
use crate::diag::Diagnostic;
use crate::source::Span;

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
    fn point(self) -> Option<Point> {
        match self {
            Area::Front => Some(Point::Front),
            Area::Back => Some(Point::Rear),
            Area::Left => Some(Point::Left),
            Area::Right => Some(Point::Right),
            _ => None,
        }
    }
    fn name(self) -> &'static str {
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

/// Result of mapping: the crash and the warnings (defaults taken, events left out).
pub struct Mapped {
    pub crash: Crash,
    pub warnings: Vec<Diagnostic>,
}

struct Ctx<'a> {
    case: &'a CirenCase,
    file: u32,
    warnings: Vec<Diagnostic>,
}

impl Ctx<'_> {
    fn span(&self, c: &Coded) -> Span {
        Span::new(self.file, c.range.start, c.range.end)
    }
    /// The start tag of an element (whole elements can span kilobytes).
    fn tag_span(&self, r: &std::ops::Range<usize>, tag: &str) -> Span {
        Span::new(self.file, r.start, (r.start + tag.len() + 1).min(r.end))
    }
    fn err(&self, code: &'static str, msg: String, at: Option<(Span, &str)>, help: &str) -> Vec<Diagnostic> {
        let mut d = Diagnostic::error(code, format!("case {}: {msg}", self.case.id)).help(help.to_string());
        if let Some((s, t)) = at {
            d = d.label(s, t);
        }
        vec![d]
    }
    fn warn(&mut self, msg: String, at: Option<Span>) {
        let mut d = Diagnostic::warning("E0807", format!("case {}: {msg}", self.case.id))
            .help("the choice is written as a comment in the generated file; check it against the case");
        if let Some(s) = at {
            d = d.label(s, "here");
        }
        self.warnings.push(d);
    }
    fn unknown(&self, what: &str, c: &Coded, help: &str) -> Vec<Diagnostic> {
        self.err(
            "E0803",
            format!("unknown {what} \"{}\" (value {}, sasCode {})", c.text, c.value, c.sas),
            Some((self.span(c), "not a code rocc maps")),
            help,
        )
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

fn quote(s: &str) -> String {
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
fn own_event(v: &CaseVehicle) -> Option<bool> {
    let t = v.critical_event.as_ref()?.lower();
    if t.contains("unknown") { None } else { Some(!(t.starts_with("from") || t.starts_with("other"))) }
}

fn speed_kmh(c: &Coded) -> Option<f64> {
    let v: f64 = c.value.parse().ok()?;
    if v <= 0.0 || v > 250.0 {
        return None;
    }
    Some(if c.unit.eq_ignore_ascii_case("mph") { v * 1.609_344 } else { v })
}

/// Coded movement, refined by the critical event and then by the narrative.
fn manoeuvre(v: &CaseVehicle, text: Option<&narrative::VehicleText>) -> (Manoeuvre, String) {
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
        two_vehicles(&mut cx, &story, header, (me, own_area, &area_c), (other, other_area, &other_area_c))
    } else {
        header.push(format!(
            "EventSum {}: V{} {}, {}.",
            ev.number,
            ev.vehicle,
            area_c.cite("AreaOfDamage"),
            contacted.cite("Contacted")
        ));
        single_vehicle(&mut cx, &story, header, me, own_area, &area_c, &contacted)
    }
    .map(|crash| Mapped { crash, warnings: cx.warnings })
}

/// Striker and struck vehicle numbers, impact, struck point, striking face, and why.
type PairConflict = (u32, u32, Impact, Point, Face, String);

/// Pick the rocc conflict from two coded damage areas.
fn pair_conflict(
    cx: &Ctx,
    a: (&CaseVehicle, Area, &Coded),
    b: (&CaseVehicle, Area, &Coded),
) -> Result<PairConflict, Vec<Diagnostic>> {
    let (va, aa, ca) = a;
    let (vb, ab, cb) = b;
    let cite = format!("V{}'s {} met V{}'s {}", va.number, aa.name(), vb.number, ab.name());
    let side = |x: Area| matches!(x, Area::Left | Area::Right);
    let by_event = || match (own_event(va), own_event(vb)) {
        (Some(true), Some(false)) | (Some(true), None) => {
            (va.number, vb.number, "its own CriticalPrecrashEvent starts the conflict")
        }
        (Some(false), Some(true)) | (None, Some(true)) => {
            (vb.number, va.number, "its own CriticalPrecrashEvent starts the conflict")
        }
        _ => (va.number, vb.number, "the critical events do not single one out; the event's own vehicle is taken"),
    };
    let face_of = |x: Area| if x == Area::Left { Face::Left } else { Face::Right };
    Ok(match (aa, ab) {
        (Area::Front, x) if side(x) => (
            va.number,
            vb.number,
            Impact::Angle,
            x.point().unwrap_or(Point::Left),
            Face::Front,
            format!("{cite}: V{} strikes", va.number),
        ),
        (x, Area::Front) if side(x) => (
            vb.number,
            va.number,
            Impact::Angle,
            x.point().unwrap_or(Point::Left),
            Face::Front,
            format!("{cite}: V{} strikes", vb.number),
        ),
        (Area::Front, Area::Back) => (va.number, vb.number, Impact::RearEnd, Point::Rear, Face::Front, cite),
        (Area::Back, Area::Front) => (vb.number, va.number, Impact::RearEnd, Point::Rear, Face::Front, cite),
        (Area::Front, Area::Front) => {
            let (af, st, why) = by_event();
            (af, st, Impact::HeadOn, Point::Front, Face::Front, format!("{cite}; V{af} is at_fault: {why}"))
        }
        (x, y) if side(x) && side(y) => {
            let (af, st, why) = by_event();
            let (af_area, st_area) = if af == va.number { (x, y) } else { (y, x) };
            (
                af,
                st,
                Impact::Sideswipe,
                st_area.point().unwrap_or(Point::Left),
                face_of(af_area),
                format!("{cite}; V{af} is at_fault: {why}"),
            )
        }
        _ => {
            let (c, what) = if matches!(aa, Area::Top | Area::Under | Area::Back) { (ca, aa) } else { (cb, ab) };
            return Err(cx.err(
                "E0804",
                format!("{cite}: rocc stages a vehicle's front or side striking, and no {} strike", what.name()),
                Some((cx.span(c), "coded here")),
                "rocc can stage front-to-side (angle), front-to-back (rear end), front-to-front (head-on) and side-to-side (sideswipe) contacts",
            ));
        }
    })
}

/// Lanes per direction of a vehicle's road, with the centre lane (if any) and the reason.
fn lanes_of(v: &CaseVehicle, t: Option<&narrative::VehicleText>) -> Option<(u32, bool, String)> {
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

fn travel_of(cx: &mut Ctx, story: &Narrative, v: &CaseVehicle, fallback: Compass, why: &str) -> (Compass, String) {
    match story.vehicle(v.number).and_then(|t| t.travel.as_ref()) {
        Some(f) => (f.value, format!("Summary {}", quote(&f.quote))),
        None => {
            let sp = cx.case.summary.as_ref().map(|s| cx.span(s));
            cx.warn(format!("the narrative gives no direction of travel for V{}; {why}", v.number), sp);
            (fallback, format!("direction not narrated: {why}"))
        }
    }
}

fn vehicle_kind(cx: &mut Ctx, v: &CaseVehicle, class: Option<&Coded>) -> Result<(String, String), Vec<Diagnostic>> {
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

fn speed_of(cx: &mut Ctx, v: &CaseVehicle, road_limit: f64, man: Manoeuvre) -> (f64, String) {
    if let Some(s) = v.travel_speed.as_ref().and_then(speed_kmh) {
        return (s, format!("TravelSpeed {} km/h", super::emit::num(s)));
    }
    let posted = v.posted_speed.as_ref().and_then(speed_kmh);
    let (base, cite) = match posted {
        Some(p) => (p, format!("TravelSpeed unknown; PostedSpeedLimit {} km/h", super::emit::num(p))),
        None => {
            let at = v.posted_speed.as_ref().map(|c| cx.span(c));
            cx.warn(
                format!(
                    "V{} has neither travel speed nor posted limit; the road's {} km/h is used",
                    v.number,
                    super::emit::num(road_limit)
                ),
                at,
            );
            (
                road_limit,
                format!("no TravelSpeed or PostedSpeedLimit: road limit {} km/h", super::emit::num(road_limit)),
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

fn road_limit(cx: &mut Ctx, vs: &[&CaseVehicle]) -> (f64, String) {
    let limits: Vec<f64> = vs.iter().filter_map(|v| v.posted_speed.as_ref().and_then(speed_kmh)).collect();
    match limits.iter().copied().reduce(f64::max) {
        Some(l) => (l, format!("PostedSpeedLimit {} km/h (the highest of the vehicles' roads)", super::emit::num(l))),
        None => {
            cx.warn("no posted speed limit is coded; 50 km/h is assumed".into(), None);
            (50.0, "no PostedSpeedLimit coded: 50 km/h assumed".into())
        }
    }
}

fn lane_index(pos: Option<&narrative::Found<LanePos>>, lanes: u32) -> (u32, String) {
    match pos {
        Some(p) => match p.value {
            LanePos::Left => (1, "left lane -> in[1]".into()),
            LanePos::Right => (lanes, format!("right lane -> in[{lanes}]")),
            LanePos::Center => (1, "centre lane -> in[1] (next to the centre line)".into()),
        },
        None => (1, "lane position not narrated -> in[1]".into()),
    }
}

fn two_vehicles(
    cx: &mut Ctx,
    story: &Narrative,
    mut header: Vec<String>,
    a: (&CaseVehicle, Area, &Coded),
    b: (&CaseVehicle, Area, &Coded),
) -> Result<Crash, Vec<Diagnostic>> {
    let (af_no, st_no, impact, point, face, why) = pair_conflict(cx, a, b)?;
    let vs = [a.0, b.0];
    let pick = |n: u32| if a.0.number == n { a.0 } else { b.0 };
    let (af, st) = (pick(af_no), pick(st_no));
    let (limit, limit_cite) = road_limit(cx, &vs);

    // Manoeuvres (coded first).
    let mut mans: Vec<(Manoeuvre, String)> = vs.iter().map(|v| manoeuvre(v, story.vehicle(v.number))).collect();

    // Template.
    let rel: Vec<String> = vs.iter().filter_map(|v| v.relation_to_junction.as_ref().map(Coded::lower)).collect();
    let at_junction = rel.iter().any(|r| r.contains("intersection") && !r.contains("non-junction"));
    let interchange = rel.iter().any(|r| r.contains("interchange area related") || r.contains("ramp"));
    let merging = mans.iter().any(|m| m.0 == Manoeuvre::Merge)
        || story.junction.as_ref().is_some_and(|j| j.value == Junction::Ramp)
        || vs.iter().any(|v| story.vehicle(v.number).is_some_and(|t| t.ramp.is_some()));
    let rel_cite = vs[0]
        .relation_to_junction
        .as_ref()
        .map(|r| r.cite("RelationToJunction"))
        .unwrap_or("RelationToJunction missing".into());
    let (template, mut road_notes) = if merging && (interchange || !at_junction) {
        (Template::Merge, vec![format!("road merge: {rel_cite}; a vehicle merges from an entrance ramp")])
    } else if at_junction {
        match story.junction.as_ref().map(|j| (j.value, j.quote.clone())) {
            Some((Junction::T, q)) => {
                (Template::TJunction, vec![format!("road t_junction: {rel_cite}; Summary {}", quote(&q))])
            }
            Some((Junction::FourLeg, q)) => {
                (Template::FourWay, vec![format!("road four_way: {rel_cite}; Summary {}", quote(&q))])
            }
            _ => {
                let sp = cx.case.summary.as_ref().map(|s| cx.span(s));
                cx.warn("the intersection's leg count is not narrated; a four-leg intersection is assumed".into(), sp);
                (
                    Template::FourWay,
                    vec![format!("road four_way: {rel_cite}; leg count not narrated, four legs assumed")],
                )
            }
        }
    } else {
        let al = st.alignment.as_ref();
        match al.map(Coded::lower) {
            Some(t) if t.contains("curve") => (
                Template::Curve { right: t.contains("right") },
                vec![format!("road curve: {rel_cite}; {}", al.map(|c| c.cite("Alignment")).unwrap_or_default())],
            ),
            _ => (
                Template::Straight,
                vec![format!(
                    "road straight: {rel_cite}; {}",
                    al.map(|c| c.cite("Alignment")).unwrap_or("Alignment missing".into())
                )],
            ),
        }
    };

    // Directions in the record's frame.
    let fallback_other = |d: Compass| match impact {
        Impact::HeadOn => d.opposite(),
        Impact::Angle if template.has_junction() => d.rotate(1),
        _ => d,
    };
    let (d_st, st_dir_cite) = travel_of(cx, story, st, Compass::East, "east assumed");
    let (d_af, af_dir_cite) = {
        let fb = fallback_other(d_st);
        travel_of(cx, story, af, fb, &format!("{} assumed from the configuration", fb.name()))
    };
    let dir_of = |n: u32| if n == af_no { (d_af, af_dir_cite.clone()) } else { (d_st, st_dir_cite.clone()) };

    // Rotation into rocc's template frame.
    let idx = |n: u32| if vs[0].number == n { 0 } else { 1 };
    let q = match template {
        Template::FourWay | Template::Merge => 0,
        // Straight roads only need the axis east-west: a quarter turn at most, so a road that
        // runs north-south becomes west-east and left and right keep their sense.
        Template::Straight | Template::Curve { .. } => match d_st {
            Compass::North => -1,
            Compass::South => 1,
            _ => 0,
        },
        Template::TJunction => {
            // The stem is the leg of the turning vehicle, else of the vehicle with fewer lanes.
            let turning =
                vs.iter().find(|v| matches!(mans[idx(v.number)].0, Manoeuvre::TurnLeft | Manoeuvre::TurnRight));
            let stem_v = turning.copied().unwrap_or(vs[1]);
            let stem_from = dir_of(stem_v.number).0.opposite();
            stem_from.turns_to(Compass::South)
        }
    };
    if q.rem_euclid(4) != 0 {
        let from = Compass::North;
        header.push(format!(
            "Rotated into the template: the record's {} is rocc's {}.",
            from.name(),
            from.rotate(q).name()
        ));
    }

    // Lanes: one count for every arm (rocc's templates share it); the larger road's.
    let mut lane_info: Vec<Option<(u32, bool, String)>> =
        vs.iter().map(|v| lanes_of(v, story.vehicle(v.number))).collect();
    // "the same roadway": share the first vehicle's road.
    for i in 1..vs.len() {
        if lane_info[i].is_none() || story.vehicle(vs[i].number).is_some_and(|t| t.same_road && t.lanes.is_none()) {
            lane_info[i] = lane_info[0].clone();
        }
    }
    let main = if template == Template::Merge {
        // The main road's vehicle is the one not on the ramp.
        let ramp_i = vs.iter().position(|v| {
            mans[idx(v.number)].0 == Manoeuvre::Merge || story.vehicle(v.number).is_some_and(|t| t.ramp.is_some())
        });
        let ramp_i = ramp_i.unwrap_or(0);
        let main_i = 1 - ramp_i;
        // The ramp vehicle's narrative often describes the freeway it enters: use it when the
        // main vehicle's own road is not narrated.
        if story.vehicle(vs[main_i].number).is_none_or(|t| t.lanes.is_none())
            && story.vehicle(vs[ramp_i].number).is_some_and(|t| t.lanes.is_some())
        {
            lane_info[main_i] = lanes_of(vs[ramp_i], story.vehicle(vs[ramp_i].number));
        }
        lane_info[main_i].clone()
    } else {
        lane_info.iter().flatten().max_by_key(|l| (l.0, l.1)).cloned()
    };
    let (lanes, centre, lanes_cite) = match main {
        Some(l) => l,
        None => {
            cx.warn("no lane count is coded or narrated; one lane per direction is assumed".into(), None);
            (1, false, "no lane count: one per direction assumed".into())
        }
    };
    let lanes = lanes.clamp(1, 6);
    road_notes.push(format!("lanes {lanes} per direction: {lanes_cite}"));
    let mut median = 0.0;
    if centre && template != Template::Merge {
        median = 3.5;
        road_notes.push("the centre (turn) lane is a 3.5 m median: rocc has no centre lane".into());
    } else if template != Template::Merge
        && vs.iter().any(|v| v.relation_to_flow.as_ref().is_some_and(|f| f.lower().starts_with("divided")))
    {
        median = 4.0;
        road_notes.push(format!(
            "{}: a 4 m median",
            vs.iter().find_map(|v| v.relation_to_flow.as_ref()).map(|f| f.cite("RelationToFlow")).unwrap_or_default()
        ));
    }
    road_notes.push(format!("speed_limit: {limit_cite}"));

    // Vehicles.
    let mut vehicles = Vec::new();
    for v in vs {
        let i = idx(v.number);
        let (dir, dir_cite) = dir_of(v.number);
        let rdir = dir.rotate(q);
        let text = story.vehicle(v.number);
        let (mut man, man_cite) = mans[i].clone();
        let mut notes = Vec::new();
        let (kind, kind_cite) = vehicle_kind(cx, v, cx_class(cx.case, v.number).as_ref())?;
        notes.push(format!("v{}: {kind_cite}", v.number));
        let (arm, lane, lane_cite): (&'static str, u32, String) = match template {
            Template::Merge => {
                if man == Manoeuvre::Merge || text.is_some_and(|t| t.ramp.is_some()) {
                    man = Manoeuvre::Merge;
                    ("ramp", 1, "on the entrance ramp -> ramp.in[1]".into())
                } else {
                    let (l, c) = lane_index(text.and_then(|t| t.lane.as_ref()), lanes);
                    ("main", l, format!("on the main road: {c}"))
                }
            }
            _ => {
                let (l, c) = lane_index(text.and_then(|t| t.lane.as_ref()), lanes);
                (approach_arm(rdir), l, c)
            }
        };
        if template == Template::TJunction && arm == "north" {
            return Err(cx.err(
                "E0804",
                format!("V{} would approach the T-junction from its missing leg (travelling {})", v.number, dir.name()),
                None,
                "the narrated directions do not fit a T-junction; check the case's Summary",
            ));
        }
        // A road without a junction runs west-east in rocc's frame (rotated by the struck
        // vehicle's travel): a vehicle travelling across it has no lane to start in.
        if matches!(template, Template::Straight | Template::Curve { .. })
            && matches!(rdir, Compass::North | Compass::South)
        {
            return Err(cx.err(
                "E0804",
                format!(
                    "V{} travels {} ({dir_cite}), across the road V{} travels {} on, and the record codes no \
                     junction: rocc's roads without a junction hold traffic along them only",
                    v.number,
                    dir.name(),
                    st.number,
                    d_st.name()
                ),
                cx.case.summary.as_ref().map(|s| (cx.span(s), "the directions are narrated here")),
                "a vehicle coming out of a driveway or crossing away from a junction is written by hand on a \
                 `t_junction` (its stem as the driveway); check the case's Summary and RelationToJunction",
            ));
        }
        notes.push(format!("travels {} ({dir_cite}) -> {arm}.in[{lane}]: {lane_cite}", dir.name()));
        // Manoeuvres the template cannot hold fall back to straight on, said so.
        let junction = template.has_junction();
        man = match man {
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
        man = t_junction_turn(template, arm, man, &mut notes);
        notes.push(format!("manoeuvre {}: {man_cite}", man_word(man)));
        let (speed, speed_cite) = speed_of(cx, v, limit, man);
        notes.push(format!("speed: {speed_cite}"));
        vehicles.push(VehicleDesc {
            name: format!("v{}", v.number),
            kind,
            arm,
            lane,
            speed_kmh: speed,
            manoeuvre: man,
            notes,
        });
        mans[i].0 = man;
    }
    let conflict = ConflictDesc {
        at_fault: format!("v{af_no}"),
        struck: format!("v{st_no}"),
        impact,
        point,
        face,
        notes: vec![
            format!("{why} (EventSum damage areas)."),
            "rocc's at_fault is the striking vehicle (its coded face meets the struck side); the record codes damage, not fault.".into(),
        ],
    };
    Ok(Crash {
        id: cx.case.id.clone(),
        source: super::crash::Source::Record,
        header,
        road: RoadDesc {
            template,
            lanes,
            lane_width: 3.5,
            speed_limit_kmh: limit,
            median,
            shoulder: 0.0,
            notes: road_notes,
        },
        vehicles,
        objects: Vec::new(),
        conflict,
    })
}

/// The EventSum class of a vehicle (a size class, used when the body type is unknown).
fn cx_class(case: &CirenCase, n: u32) -> Option<Coded> {
    case.events.iter().find(|e| e.vehicle == n).and_then(|e| e.class.clone()).or_else(|| {
        case.events
            .iter()
            .find(|e| e.contacted.as_ref().is_some_and(|c| c.text.ends_with(&format!("#{n}"))))
            .and_then(|e| e.contacted_class.clone())
    })
}

fn single_vehicle(
    cx: &mut Ctx,
    story: &Narrative,
    header: Vec<String>,
    me: &CaseVehicle,
    own: Area,
    own_c: &Coded,
    contacted: &Coded,
) -> Result<Crash, Vec<Diagnostic>> {
    let t = contacted.lower();
    let kind = if t.contains("tree") {
        "tree"
    } else if t.contains("pole") || t.contains("post") {
        "pole"
    } else if t.contains("wall") {
        "wall"
    } else if t.contains("building") {
        "building"
    } else if t.contains("barrier") || t.contains("guardrail") || t.contains("guard rail") {
        "jersey_barrier"
    } else {
        return Err(cx.err(
            "E0804",
            format!("V{} struck {}: rocc has no kind for it", me.number, contacted.cite("Contacted")),
            Some((cx.span(contacted), "coded here")),
            "rocc's fixed objects: tree, pole, wall, building and barriers; ditches, embankments, curbs and culverts are terrain it does not model",
        ));
    };
    if own != Area::Front {
        return Err(cx.err(
            "E0804",
            format!(
                "V{}'s {} struck a {kind}: rocc stages fixed objects struck by a vehicle's front",
                me.number,
                own.name()
            ),
            Some((cx.span(own_c), "coded here")),
            "a side impact with a tree or pole comes from a slide rocc's rollout does not model",
        ));
    }
    let (limit, limit_cite) = road_limit(cx, &[me]);
    let (_, man_cite) = manoeuvre(me, story.vehicle(me.number));
    let (dir, dir_cite) = travel_of(cx, story, me, Compass::East, "east assumed");
    let (lanes, _centre, lanes_cite) =
        lanes_of(me, story.vehicle(me.number)).unwrap_or((1, false, "one lane assumed".into()));
    let lanes = lanes.clamp(1, 6);
    let al = me.alignment.as_ref();
    let template = match al.map(Coded::lower) {
        Some(x) if x.contains("curve") => Template::Curve { right: x.contains("right") },
        _ => Template::Straight,
    };
    let (side, side_cite) = match story.departure.as_ref() {
        Some(d) => {
            (if d.value == Side2::Left { Side::Left } else { Side::Right }, format!("Summary {}", quote(&d.quote)))
        }
        None => {
            let sp = cx.case.summary.as_ref().map(|s| cx.span(s));
            cx.warn("the narrative does not say which side the vehicle left the road; the right is assumed".into(), sp);
            (Side::Right, "side not narrated: right assumed".into())
        }
    };
    let (kind_v, kind_cite) = vehicle_kind(cx, me, cx_class(cx.case, me.number).as_ref())?;
    let mut header = header;
    if dir != Compass::East {
        header.push(format!(
            "Rotated into the template: V{} travels {} in the record, east in rocc.",
            me.number,
            dir.name()
        ));
    }
    let (speed, speed_cite) = speed_of(cx, me, limit, Manoeuvre::Straight);
    let rel = me.relation_to_junction.as_ref().map(|r| r.cite("RelationToJunction")).unwrap_or_default();
    let v = VehicleDesc {
        name: format!("v{}", me.number),
        kind: kind_v,
        arm: "west",
        lane: 1,
        speed_kmh: speed,
        manoeuvre: Manoeuvre::Straight,
        notes: vec![
            format!("v{}: {kind_cite}", me.number),
            format!("travels {} ({dir_cite}) -> west.in[1]", dir.name()),
            format!("manoeuvre straight on ({man_cite}); the staging steers it off the road into the {kind}"),
            format!("speed: {speed_cite}"),
        ],
    };
    let obj = ObjectDesc {
        name: "obj1".into(),
        kind: kind.into(),
        side,
        notes: vec![format!(
            "obj1: {} -> {kind} (a structure), off the {} side ({side_cite})",
            contacted.cite("Contacted"),
            if side == Side::Left { "left" } else { "right" }
        )],
    };
    Ok(Crash {
        id: cx.case.id.clone(),
        source: super::crash::Source::Record,
        header,
        road: RoadDesc {
            template,
            lanes,
            lane_width: 3.5,
            speed_limit_kmh: limit,
            median: 0.0,
            shoulder: 1.0,
            notes: vec![
                format!(
                    "road {}: {rel}; {}",
                    template.name(),
                    al.map(|c| c.cite("Alignment")).unwrap_or("Alignment missing".into())
                ),
                format!("lanes {lanes} per direction: {lanes_cite}"),
                format!("speed_limit: {limit_cite}"),
            ],
        },
        vehicles: vec![v],
        objects: vec![obj],
        conflict: ConflictDesc {
            at_fault: format!("v{}", me.number),
            struck: "obj1".into(),
            impact: Impact::Object,
            point: Point::Front,
            face: Face::Front,
            notes: vec![format!(
                "V{}'s {} struck the {kind} (EventSum); `point front` is the face it drives into.",
                me.number,
                own_c.cite("AreaOfDamage")
            )],
        },
    })
}
