//! Two vehicles in one contact: the rocc conflict from the two coded damage areas, then the
//! road, directions, lanes and starts that bring them together.

use super::ctx::Ctx;
use super::fields::*;
use crate::check::scenario::{Impact, Point};
use crate::ciren::case::{CaseVehicle, Coded};
use crate::ciren::crash::{
    Compass, ConflictDesc, Crash, Face, LANE_WIDTH, Manoeuvre, RoadDesc, Template, VehicleDesc, approach_arm, man_word,
};
use crate::ciren::narrative::{Junction, Narrative};
use crate::diag::Diagnostic;

/// Striker and struck vehicle numbers, impact, struck point, striking face, and why.
pub(super) type PairConflict = (u32, u32, Impact, Point, Face, String);

/// Pick the rocc conflict from two coded damage areas.
pub(super) fn pair_conflict(
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

pub(super) fn two_vehicles(
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
        median = LANE_WIDTH;
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
        man = fit_manoeuvre(template, arm, lane, lanes, man, &mut notes);
        notes.push(format!("manoeuvre {}: {man_cite}", man_word(man)));
        let (speed, speed_cite) = speed_of(cx, v, limit, man);
        notes.push(format!("speed: {speed_cite}"));
        vehicles.push(VehicleDesc {
            on_slide: false,
            at: None,
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
        at: None,
        clocks: Vec::new(),
        closing: None,
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
        source: crate::ciren::crash::Source::Record,
        header,
        road: RoadDesc { median, ..RoadDesc::new(template, lanes, limit, q, road_notes) },
        vehicles,
        objects: Vec::new(),
        conflicts: vec![conflict],
    })
}

/// A vehicle a later contact brings: on the crash's road, travelling as narrated (rotated into
/// rocc's frame), else as the contact suggests beside `partner` (behind it for a rear end, the
/// other way for a head-on, across it at a junction); a rear-end striker starts in its
/// partner's lane.
pub(super) fn extra_vehicle(
    cx: &mut Ctx,
    story: &Narrative,
    crash: &Crash,
    v: &CaseVehicle,
    partner: &str,
    impact: Impact,
) -> Result<VehicleDesc, Vec<Diagnostic>> {
    let road = &crash.road;
    let p = crash.vehicle(partner).expect("partner in the crash");
    // The partner's travel in rocc's frame: it comes from its arm (the merge's roads run east).
    let p_dir = Compass::parse(p.arm).map_or(Compass::East, Compass::opposite);
    let fallback = match impact {
        Impact::HeadOn => p_dir.opposite(),
        Impact::Angle if road.template.has_junction() => p_dir.rotate(1),
        _ => p_dir,
    };
    let back = fallback.rotate(-road.turns);
    let (dir, dir_cite) = travel_of(cx, story, v, back, &format!("{} assumed beside {partner}", back.name()));
    let rdir = dir.rotate(road.turns);
    let text = story.vehicle(v.number);
    let (man, man_cite) = manoeuvre(v, text);
    let mut notes = Vec::new();
    let (kind, kind_cite) = vehicle_kind(cx, v, cx_class(cx.case, v.number).as_ref())?;
    notes.push(format!("v{}: {kind_cite}", v.number));
    let (arm, lane, lane_cite): (&'static str, u32, String) = if impact == Impact::RearEnd && rdir == p_dir {
        (p.arm, p.lane, format!("behind {partner}, in its lane"))
    } else if road.template == Template::Merge {
        let (l, c) = lane_index(text.and_then(|t| t.lane.as_ref()), road.lanes);
        ("main", l, format!("on the main road: {c}"))
    } else {
        let (l, c) = lane_index(text.and_then(|t| t.lane.as_ref()), road.lanes);
        (approach_arm(rdir), l, c)
    };
    let across = matches!(road.template, Template::Straight | Template::Curve { .. })
        && matches!(rdir, Compass::North | Compass::South);
    if across || (road.template == Template::TJunction && arm == "north") {
        return Err(cx.err(
            "E0804",
            format!(
                "V{} travels {} ({dir_cite}): the {} road rocc builds for the first-ranked event has no arm it \
                 could come from",
                v.number,
                dir.name(),
                road.template.name()
            ),
            cx.case.summary.as_ref().map(|s| (cx.span(s), "the directions are narrated here")),
            "check the case's Summary; a scene with more roads is written by hand",
        ));
    }
    notes.push(format!("travels {} ({dir_cite}) -> {arm}.in[{lane}]: {lane_cite}", dir.name()));
    let man = fit_manoeuvre(road.template, arm, lane, road.lanes, man, &mut notes);
    notes.push(format!("manoeuvre {}: {man_cite}", man_word(man)));
    let (speed, speed_cite) = speed_of(cx, v, road.speed_limit_kmh, man);
    notes.push(format!("speed: {speed_cite}"));
    Ok(VehicleDesc {
        name: format!("v{}", v.number),
        kind,
        arm,
        lane,
        speed_kmh: speed,
        manoeuvre: man,
        on_slide: false,
        at: None,
        notes,
    })
}
