//! A single vehicle into a fixed object: the object beside the road on the side the narrative
//! says the vehicle left it.

use super::ctx::Ctx;
use super::fields::*;
use crate::check::scenario::{Impact, Point};
use crate::ciren::case::{CaseVehicle, Coded};
use crate::ciren::crash::{
    Compass, ConflictDesc, Crash, Face, Manoeuvre, ObjectDesc, RoadDesc, Side, Template, VehicleDesc,
};
use crate::ciren::narrative::{Narrative, Side2};
use crate::diag::Diagnostic;

pub(super) fn single_vehicle(
    cx: &mut Ctx,
    story: &Narrative,
    header: Vec<String>,
    me: &CaseVehicle,
    own: Area,
    own_c: &Coded,
    contacted: &Coded,
) -> Result<Crash, Vec<Diagnostic>> {
    let kind = object_kind(cx, me, contacted)?;
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
        on_slide: false,
        at: None,
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
        on_slide: false,
        at: None,
        notes: vec![format!(
            "obj1: {} -> {kind} (a structure), off the {} side ({side_cite})",
            contacted.cite("Contacted"),
            if side == Side::Left { "left" } else { "right" }
        )],
    };
    Ok(Crash {
        id: cx.case.id.clone(),
        source: crate::ciren::crash::Source::Record,
        header,
        road: RoadDesc {
            shoulder: 1.0,
            ..RoadDesc::new(
                template,
                lanes,
                limit,
                dir.turns_to(Compass::East),
                vec![
                    format!(
                        "road {}: {rel}; {}",
                        template.name(),
                        al.map(|c| c.cite("Alignment")).unwrap_or("Alignment missing".into())
                    ),
                    format!("lanes {lanes} per direction: {lanes_cite}"),
                    format!("speed_limit: {limit_cite}"),
                ],
            )
        },
        vehicles: vec![v],
        objects: vec![obj],
        conflicts: vec![ConflictDesc {
            at: None,
            clocks: Vec::new(),
            closing: None,
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
        }],
    })
}

/// rocc's kind for a struck fixed object, or the reason there is none.
pub(super) fn object_kind(cx: &Ctx, me: &CaseVehicle, contacted: &Coded) -> Result<&'static str, Vec<Diagnostic>> {
    let t = contacted.lower();
    Ok(if t.contains("tree") {
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
    })
}
