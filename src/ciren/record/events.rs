//! Every contact of a case: the `EventSum` rows decoded, one per contact (a contact coded from
//! both vehicles' rows counts once), in time order (the event number). The first-ranked contact
//! sets the road and its pair; each other one joins the crash as a further conflict, its new
//! vehicle placed on the same road; a fixed object or a stopped vehicle struck after its
//! striker's earlier contact is placed on that slide (`ciren::slide`); what the importer cannot
//! stage (a vehicle striking one already in the crash twice or after it was struck, a moving
//! vehicle struck on a slide, a pair meeting twice, an object struck before any other contact
//! of its striker) refuses the case with the reason.

use super::ctx::Ctx;
use super::fields::{Area, area};
use super::fields::{cx_class, manoeuvre, vehicle_kind};
use super::pair::{extra_vehicle, pair_conflict};
use crate::check::scenario::{Impact, Point};
use crate::ciren::case::{CaseVehicle, Coded, Event};
use crate::ciren::crash::{ConflictDesc, Crash, Face, Manoeuvre, ObjectDesc, Side, VehicleDesc};
use crate::diag::Diagnostic;
use crate::source::Span;

/// What an event's vehicle met.
pub(super) enum Party<'a> {
    Vehicle(&'a CaseVehicle, Area, Coded),
    Object,
}

/// One decoded contact.
pub(super) struct Contact<'a> {
    pub ev: &'a Event,
    pub me: &'a CaseVehicle,
    pub own: Area,
    pub own_c: Coded,
    pub contacted: Coded,
    pub other: Party<'a>,
}

impl Contact<'_> {
    /// The header line citing the event.
    pub fn cite(&self) -> String {
        let other = match &self.other {
            Party::Vehicle(_, _, c) => format!(", {}", c.cite("ContactedAreaOfDamage")),
            Party::Object => String::new(),
        };
        format!(
            "EventSum {}: V{} {}, {}{other}.",
            self.ev.number,
            self.ev.vehicle,
            self.own_c.cite("AreaOfDamage"),
            self.contacted.cite("Contacted")
        )
    }
    /// The unordered vehicle pair, for contacts coded from both sides.
    fn key(&self) -> (u32, u32, u32) {
        let o = match &self.other {
            Party::Vehicle(v, _, _) => v.number,
            Party::Object => 0,
        };
        (self.ev.number, self.me.number.min(o), self.me.number.max(o))
    }
}

/// Decode one event: the vehicle, its damaged area, and the party it met.
pub(super) fn decode<'a>(cx: &Ctx<'a>, ev: &'a Event) -> Result<Contact<'a>, Vec<Diagnostic>> {
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
    let own_c = need(&ev.area, "AreaOfDamage")?;
    let contacted = need(&ev.contacted, "Contacted")?;
    let own = area(&own_c).ok_or_else(|| cx.unknown("AreaOfDamage", &own_c, "known CDC areas: F, B, L, R, T, U"))?;
    let vehicle = |n: u32| cx.case.vehicles.iter().find(|v| v.number == n);
    let Some(me) = vehicle(ev.vehicle) else {
        return Err(cx.err(
            "E0802",
            format!("the event names V{} but the record has no GeneralVehicleForm for it", ev.vehicle),
            Some((ev_span, "this event")),
            "each vehicle of the event needs its GeneralVehicleForm (body type, pre-crash data)",
        ));
    };
    let t = contacted.lower();
    let other_no: Option<u32> =
        t.split('#').nth(1).and_then(|n| n.trim().split(|c: char| !c.is_ascii_digit()).next()?.parse().ok());
    let other = match other_no.filter(|_| t.contains("vehicle")) {
        Some(on) => {
            let oc = need(&ev.contacted_area, "ContactedAreaOfDamage")?;
            let oa = area(&oc)
                .ok_or_else(|| cx.unknown("ContactedAreaOfDamage", &oc, "known CDC areas: F, B, L, R, T, U"))?;
            let Some(o) = vehicle(on) else {
                return Err(cx.err(
                    "E0802",
                    format!("V{} contacted V{on}, which has no GeneralVehicleForm", ev.vehicle),
                    Some((cx.span(&contacted), "this vehicle")),
                    "each vehicle of the event needs its GeneralVehicleForm (body type, pre-crash data)",
                ));
            };
            Party::Vehicle(o, oa, oc)
        }
        None => Party::Object,
    };
    Ok(Contact { ev, me, own, own_c, contacted, other })
}

/// The case's contacts in time order, one per contact, and the index of the first-ranked.
pub(super) fn contacts<'a>(cx: &Ctx<'a>) -> Result<(Vec<Contact<'a>>, usize), Vec<Diagnostic>> {
    let mut events: Vec<&Event> = cx.case.events.iter().collect();
    events.sort_by_key(|e| (e.number, e.vehicle));
    let mut out: Vec<Contact> = Vec::new();
    for e in events {
        let c = decode(cx, e)?;
        if !out.iter().any(|o| o.key() == c.key() && c.key().1 != 0) {
            out.push(c);
        }
    }
    let primary =
        (0..out.len()).min_by_key(|&i| (out[i].ev.rank.unwrap_or(u32::MAX), out[i].ev.number, out[i].ev.vehicle));
    match primary {
        Some(p) => Ok((out, p)),
        None => Err(cx.err(
            "E0802",
            "no Events/EventSum row: the record codes no collision".into(),
            None,
            "a case needs at least one EventSum with AreaOfDamage, Contacted and ContactedAreaOfDamage",
        )),
    }
}

/// Add a contact other than the first-ranked one to the crash: its conflict, and a vehicle or
/// object it brings that the crash does not hold yet. `earlier` are the conflicts before it in
/// time order.
pub(super) fn join(
    cx: &mut Ctx,
    story: &crate::ciren::narrative::Narrative,
    crash: &mut Crash,
    c: &Contact,
    earlier: &[ConflictDesc],
) -> Result<ConflictDesc, Vec<Diagnostic>> {
    let span = cx.tag_span(&c.ev.range, "EventSum");
    let Party::Vehicle(other, oa, oc) = &c.other else {
        return slide_object(cx, crash, c, earlier);
    };
    let (af, st, impact, point, face, why) = pair_conflict(cx, (c.me, c.own, &c.own_c), (other, *oa, oc))?;
    let (af_n, st_n) = (format!("v{af}"), format!("v{st}"));
    let known = |n: &str| crash.vehicle(n).is_some();
    let (new, partner) = match (known(&af_n), known(&st_n)) {
        (true, true) => (None, st_n.clone()),
        (false, true) => (Some(af), st_n.clone()),
        (true, false) => (Some(st), af_n.clone()),
        (false, false) => {
            return Err(cx.err(
                "E0804",
                format!(
                    "event {} (V{af} into V{st}) involves no vehicle of the first-ranked event; rocc stages later \
                     contacts beside it",
                    c.ev.number
                ),
                Some((span, "this event")),
                "import the case's contacts that chain from its first-ranked event",
            ));
        }
    };
    if let Some(n) = new {
        let v = cx.case.vehicles.iter().find(|v| v.number == n).expect("decoded vehicle");
        let sliding = earlier.iter().rev().find(|k| k.at_fault == af_n || k.struck == af_n);
        let desc = match sliding {
            // Struck by a vehicle sliding from its earlier impact: stopped where the slide goes.
            Some(k) if n == st => stopped_on_slide(cx, story, v, c, (&af_n, k))?,
            _ => extra_vehicle(cx, story, crash, v, &partner, impact)?,
        };
        crash.vehicles.push(desc);
    }
    crash.header.push(c.cite());
    Ok(ConflictDesc {
        at: None,
        at_fault: af_n,
        struck: st_n,
        impact,
        point,
        face,
        clocks: Vec::new(),
        closing: None,
        notes: vec![format!("Event {}: {why} (EventSum damage areas).", c.ev.number)],
    })
}

/// A vehicle the record brings, struck by `striker` on its slide from its earlier contact
/// `before`: stopped where that slide goes (`ciren::slide`). A moving one would have to be timed
/// onto the slide: refused.
fn stopped_on_slide(
    cx: &mut Ctx,
    story: &crate::ciren::narrative::Narrative,
    v: &CaseVehicle,
    c: &Contact,
    (striker, before): (&str, &ConflictDesc),
) -> Result<VehicleDesc, Vec<Diagnostic>> {
    let span = cx.tag_span(&c.ev.range, "EventSum");
    let (man, man_cite) = manoeuvre(v, story.vehicle(v.number));
    if man != Manoeuvre::Stopped {
        return Err(cx.err(
            "E0804",
            format!(
                "event {}: V{} is struck by {striker} on its slide from an earlier impact while moving ({man_cite}); \
                 the importer places only a stopped vehicle or a fixed object where a slide goes",
                c.ev.number, v.number
            ),
            Some((span, "this event")),
            "import the case's other contacts, or write the vehicle into the imported scenario by hand",
        ));
    }
    let (kind, kind_cite) = vehicle_kind(cx, v, cx_class(cx.case, v.number).as_ref())?;
    let partner = if before.at_fault == striker { &before.struck } else { &before.at_fault };
    Ok(VehicleDesc {
        name: format!("v{}", v.number),
        kind,
        arm: "west",
        lane: 1,
        speed_kmh: 0.0,
        manoeuvre: Manoeuvre::Stopped,
        on_slide: true,
        at: None,
        notes: vec![
            format!("v{}: {kind_cite}", v.number),
            format!(
                "stopped ({man_cite}), where {striker}'s slide from its impact with {partner} reaches it, its coded \
                 side toward the slide"
            ),
        ],
    })
}

/// A fixed object struck by a vehicle after its earlier contact: the slide from that contact
/// brings the vehicle to it, so the object is placed where the slide goes (`emit::slide`), and the
/// struck side is the one the slide reaches (CIREN codes none for an object). An object struck
/// before any contact of its striker would need a staged strike beside the other contacts:
/// refused.
fn slide_object(
    cx: &mut Ctx,
    crash: &mut Crash,
    c: &Contact,
    earlier: &[ConflictDesc],
) -> Result<ConflictDesc, Vec<Diagnostic>> {
    let span = cx.tag_span(&c.ev.range, "EventSum");
    let me = format!("v{}", c.me.number);
    let involved = |k: &&ConflictDesc| k.at_fault == me || k.struck == me;
    let Some(before) = earlier.iter().rev().find(involved) else {
        return Err(cx.err(
            "E0804",
            format!(
                "event {}: V{} struck {} before any contact with the case's other vehicles; rocc places a fixed \
                 object either beside the road of a single-vehicle case or on the slide after an impact",
                c.ev.number,
                c.me.number,
                c.contacted.cite("Contacted")
            ),
            Some((span, "this event")),
            "write the object into the imported scenario by hand, or import the vehicle contacts alone",
        ));
    };
    let kind = super::object::object_kind(cx, c.me, &c.contacted)?;
    let face = match c.own {
        Area::Front => Face::Front,
        Area::Left => Face::Left,
        Area::Right => Face::Right,
        Area::Back => Face::Back,
        _ => {
            return Err(cx.err(
                "E0804",
                format!("event {}: V{}'s {} struck a {kind}", c.ev.number, c.me.number, c.own.name()),
                Some((cx.span(&c.own_c), "coded here")),
                "rocc stages planar contacts: a vehicle strikes with its front, back or a side",
            ));
        }
    };
    let name = format!("obj{}", crash.objects.len() + 1);
    let partner = if before.at_fault == me { &before.struck } else { &before.at_fault };
    crash.objects.push(ObjectDesc {
        name: name.clone(),
        kind: kind.into(),
        side: Side::Right,
        on_slide: true,
        at: None,
        notes: vec![format!(
            "{name}: {} -> {kind} (a structure), where {me}'s slide from its impact with {partner} takes its {}",
            c.contacted.cite("Contacted"),
            face.name()
        )],
    });
    crash.header.push(c.cite());
    Ok(ConflictDesc {
        at_fault: me.clone(),
        struck: name,
        impact: Impact::Object,
        point: Point::Front,
        face,
        clocks: Vec::new(),
        closing: None,
        at: None,
        notes: vec![format!(
            "Event {}: {me}'s {} ({}) strikes the {kind} on its slide from the impact with {partner}: not staged, \
             the slide brings it there; `point` is the side the slide reaches.",
            c.ev.number,
            face.name(),
            c.own_c.cite("AreaOfDamage")
        )],
    })
}

/// The language's rules for several crashes, checked before emission: a vehicle strikes in one
/// contact, is struck only after (or when) it strikes, and a pair meets once.
pub(super) fn check_order(cx: &Ctx, crash: &Crash, events: &[(u32, Span)]) -> Result<(), Vec<Diagnostic>> {
    let Some((i, j, how)) = crate::ciren::crash::chain_break(&crash.conflicts, |k| crash.on_slide(k)) else {
        return Ok(());
    };
    let ((ev, span), earlier) = (events[i], events[j].0);
    Err(cx.err(
        "E0804",
        format!("event {ev}: {}", how.say(&crash.conflicts[i], &format!("event {earlier}"))),
        Some((span, "this event")),
        how.help(),
    ))
}
