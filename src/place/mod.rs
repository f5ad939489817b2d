//! Place pass. In: a `Concrete` scenario and its `Map`. Out: `Placed` — every agent, object and
//! row element with a world pose and box — or E02xx diagnostics (off the road, off a valid
//! surface, overlap, a `stop behind` leader that is not ahead: `leader.rs`).

mod leader;
mod resolve;
mod surface;
mod track;

pub use resolve::Miss;
pub use surface::Surfaces;
pub use track::resolve_keys;

use crate::check::scenario::{Class, Kind, Lateral, Motion, Place};
use crate::diag::Diagnostic;
use crate::geom::Obb;
use crate::road::Map;
use crate::sample::{Concrete, ConcreteRow, Rng};
use crate::source::Span;
use glam::DVec2;
use resolve::Guide;
use serde::{Deserialize, Serialize};

/// A pose on the ground plane: world metres, yaw counter-clockwise from +x (rad).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlacedAgent {
    /// The declared name; row elements are named `ROWKIND_rowN_K`.
    pub name: String,
    pub kind: String,
    pub class: Class,
    pub motion: Motion,
    pub is_object: bool,
    /// Box length, width, height (m); the box stands on the ground (z from 0 to height).
    pub size: [f64; 3],
    pub pose: Pose,
    pub speed: f64,
    /// Index into `Concrete::agents`, `None` for row elements.
    pub source: Option<usize>,
    #[serde(skip)]
    pub span: Span,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Placed {
    pub agents: Vec<PlacedAgent>,
}

/// Holonomic movers that are not pedestrians (animals, strollers) may start this far outside the
/// map's bounds (m): a deer steps out of the woods.
const NEAR_MAP: f64 = 10.0;

/// Resolve every placement of `c` on `map`, lay out the rows, and check surfaces and overlaps.
pub fn place(c: &Concrete, map: &Map) -> Result<Placed, Vec<Diagnostic>> {
    let mut errs = Vec::new();
    let mut out = Vec::new();
    // Which row each placed box came from; boxes of one row may touch each other.
    let mut row_of: Vec<Option<usize>> = Vec::new();

    for (i, a) in c.agents.iter().enumerate() {
        let pose = match resolve::pose(map, &a.place, a.track.as_deref()) {
            Ok(p) => p,
            Err(miss) => {
                errs.push(off_road(&miss, &a.name, a.place_span));
                continue;
            }
        };
        if let Some(keys) = a.track.as_deref().filter(|_| !a.is_object) {
            errs.extend(track::check(map, a, keys));
        } else if !matches!(a.place, Place::Track) {
            let cross = a.goal.as_ref().is_some_and(|g| g.lateral == Lateral::Cross);
            if let Err(need) = surface_ok(map, a.class, a.motion, cross, pose) {
                errs.push(wrong_surface(map, &a.name, a.class, need, pose, a.place_span));
            }
        }
        out.push(PlacedAgent {
            name: a.name.clone(),
            kind: a.kind.clone(),
            class: a.class,
            motion: a.motion,
            is_object: a.is_object,
            size: a.size,
            pose,
            speed: a.speed,
            source: Some(i),
            span: a.span,
        });
        row_of.push(None);
    }

    for (ri, row) in c.rows.iter().enumerate() {
        match lay_out(c, map, row, ri) {
            Ok(elems) => {
                for e in elems {
                    if let Err(need) = surface_ok(map, e.class, e.motion, false, e.pose) {
                        errs.push(wrong_surface(map, &e.name, e.class, need, e.pose, row.span));
                    }
                    out.push(e);
                    row_of.push(Some(ri));
                }
            }
            Err(miss) => errs.push(off_road(&miss, &format!("row {}", ri + 1), row.span)),
        }
    }

    // Boxes may touch (`Obb::overlaps` ignores contact) but not interpenetrate at all: the
    // rollout's tracks start from these poses and hold no overlap but a conflict's from frame 0
    // (a 1 cm per side allowance here once let two walkers start 1 cm into each other).
    let boxes: Vec<Obb> = out
        .iter()
        .map(|a| Obb { center: DVec2::new(a.pose.x, a.pose.y), yaw: a.pose.yaw, length: a.size[0], width: a.size[1] })
        .collect();
    for i in 0..boxes.len() {
        for j in i + 1..boxes.len() {
            if row_of[i].is_some() && row_of[i] == row_of[j] {
                continue;
            }
            // Two recorded tracks start where the recording had them (and may not even be in the
            // scene at the same time): annotation overlaps are data, not authoring mistakes.
            let replayed = |k: usize| out[k].source.is_some_and(|s| matches!(c.agents[s].place, Place::Track));
            if replayed(i) && replayed(j) {
                continue;
            }
            let (bi, bj) = (&boxes[i], &boxes[j]);
            let reach = 0.5 * (bi.length.hypot(bi.width) + bj.length.hypot(bj.width));
            if bi.center.distance(bj.center) >= reach || !bi.overlaps(bj) {
                continue;
            }
            let (a, b) = (&out[i], &out[j]);
            errs.push(
                Diagnostic::error("E0202", format!("`{}` and `{}` overlap at their initial placement", a.name, b.name))
                    .label(a.span, format!("`{}` starts here", a.name))
                    .label(b.span, format!("`{}` starts here, overlapping `{}`", b.name, a.name))
                    .help(format!(
                        "their centres are {:.1} m apart but the boxes ({:.1} x {:.1} m and {:.1} x {:.1} m) need more room; move one further along the lane or to another lane",
                        bi.center.distance(bj.center),
                        a.size[0],
                        a.size[1],
                        b.size[0],
                        b.size[1]
                    )),
            );
        }
    }

    // Leaders are judged on the poses only once every pose is right.
    if errs.is_empty() {
        errs = leader::check(c, map, &out);
    }
    if errs.is_empty() { Ok(Placed { agents: out }) } else { Err(errs) }
}

fn off_road(miss: &Miss, who: &str, span: Span) -> Diagnostic {
    let (msg, help) = miss.message(who);
    Diagnostic::error("E0203", msg).label(span, "this placement").help(help)
}

/// The surfaces a class may start on, as a phrase, when `pose` is not on one of them.
fn surface_ok(map: &Map, class: Class, motion: Motion, cross: bool, pose: Pose) -> Result<(), &'static str> {
    let p = DVec2::new(pose.x, pose.y);
    let s = Surfaces::at(map, p);
    let (ok, need) = match class {
        // A road-less scene (replayed tracks) has no map for a static object to be near.
        _ if motion == Motion::Static && map.lanes.is_empty() => (true, ""),
        // A wreck, a parked car or a bicycle on its side can be anywhere a static thing can.
        Class::Vehicle if motion != Motion::Static => {
            (s.lane || s.shoulder || s.junction || s.carpark, "a lane, the shoulder, a parking lane or a driveway")
        }
        Class::Bicycle if motion != Motion::Static => {
            (s.lane || s.shoulder || s.junction || s.sidewalk || s.crosswalk, "a lane, the shoulder or a sidewalk")
        }
        // A crossing pedestrian starts at a kerb, wherever the scenario puts it.
        Class::Pedestrian if cross => (true, ""),
        // People and animals stand, kneel or lie wherever they can physically be, a lane
        // included (tests/rollout-cases/person-lying-on-lane.scn); so do cones, barriers, debris
        // and wrecks. Far off the map, a thing is outside every frame and almost surely a
        // mistaken coordinate.
        _ => {
            let (lo, hi) = map.bounds;
            let near =
                p.x >= lo.x - NEAR_MAP && p.x <= hi.x + NEAR_MAP && p.y >= lo.y - NEAR_MAP && p.y <= hi.y + NEAR_MAP;
            (near, "the map or within 10 m of it")
        }
    };
    if ok { Ok(()) } else { Err(need) }
}

fn wrong_surface(map: &Map, who: &str, class: Class, need: &str, pose: Pose, span: Span) -> Diagnostic {
    let found = Surfaces::at(map, DVec2::new(pose.x, pose.y)).describe();
    let help = match class {
        Class::Vehicle => {
            "place vehicles on a lane, e.g. `at south.in[1], 20 m before stop_line`, or on the shoulder with `offset`"
        }
        _ => "move it onto the road, or onto a sidewalk",
    };
    Diagnostic::error(
        "E0201",
        format!(
            "a {} must start on {need}, but `{who}` starts {found} at ({:.1}, {:.1})",
            class.name(),
            pose.x,
            pose.y
        ),
    )
    .label(span, found)
    .help(help)
}

/// Sizes for a kind the scenario did not carry priors for (a `Concrete` built by hand).
fn fallback_size(class: Class) -> [f64; 3] {
    match class {
        Class::Vehicle => [4.6, 1.8, 1.5],
        Class::Bicycle => [1.8, 0.6, 1.7],
        Class::Pedestrian => [0.6, 0.6, 1.75],
        Class::TrafficCone => [0.4, 0.4, 0.8],
        Class::Barrier => [2.0, 0.5, 0.9],
        Class::CzoneSign => [0.2, 1.0, 1.8],
        Class::GenericObject | Class::Structure => [0.8, 0.6, 0.5],
    }
}

/// The objects of row `ri`: every `every` m from `from` to `to` inclusive, facing along the row.
fn lay_out(c: &Concrete, map: &Map, row: &ConcreteRow, ri: usize) -> Result<Vec<PlacedAgent>, Miss> {
    // A guide line, the stations of both ends on it, and their lateral offsets and headings.
    let (guide, s0, s1, off0, off1, heading): (Guide, f64, f64, f64, f64, Option<f64>) = match (&row.from, &row.to) {
        (Place::Lane { lane, along: a, offset: o0, heading }, Place::Lane { lane: l1, offset: o1, .. }) => {
            let (g, s0) = resolve::on_lane(map, *lane, a.landmark, a.dist)?;
            let (s1, across) = end_on(map, &g, &row.to)?;
            // A taper ends on another lane of the arm: its centre's offset from this guide
            // joins the end's own offset, so the row slides across linearly.
            let off1 = if l1 == lane { *o1 } else { *o1 + across };
            (g, s0, s1, *o0, off1, *heading)
        }
        (Place::Sidewalk { arm, dir, along: a, offset: o0, heading }, Place::Sidewalk { offset: o1, .. }) => {
            let (g, s0) = resolve::on_sidewalk(map, *arm, *dir, a.landmark, a.dist)?;
            let (s1, _) = end_on(map, &g, &row.to)?;
            (g, s0, s1, *o0, *o1, *heading)
        }
        _ => {
            let p0 = resolve::pose(map, &row.from, None)?;
            let p1 = resolve::pose(map, &row.to, None)?;
            let line = crate::geom::Polyline::new(vec![DVec2::new(p0.x, p0.y), DVec2::new(p1.x, p1.y)]);
            let len = line.length();
            let heading = match &row.from {
                Place::World { heading: Some(h), .. } => Some(*h),
                _ if len < 1e-9 => Some(p0.yaw),
                _ => None,
            };
            (Guide { line, what: format!("row {}", ri + 1) }, 0.0, len, 0.0, 0.0, heading)
        }
    };
    let span_len = (s1 - s0).abs();
    let step = row.every.max(1e-3);
    // The checker bounds the count; the cap only guards a hand-built `Concrete`.
    let count = ((span_len / step + 1e-9).floor() as usize + 1).min(10_000);
    let dir = if s1 >= s0 { 1.0 } else { -1.0 };
    let mut r = Rng::new(row.stream);
    let mut elems = Vec::with_capacity(count);
    for k in 0..count {
        let d = k as f64 * step;
        let s = s0 + dir * d;
        let t = if span_len > 1e-9 { d / span_len } else { 0.0 };
        let mut pose = resolve::along(&guide, s, off0 + (off1 - off0) * t, heading);
        if dir < 0.0 && heading.is_none() {
            pose.yaw = crate::geom::wrap_angle(pose.yaw + std::f64::consts::PI);
        }
        let kind_name =
            row.kinds.get(r.index(row.kinds.len().max(1))).cloned().unwrap_or_else(|| row.class.name().into());
        let kind: Option<&Kind> = c.kinds.get(&kind_name);
        let (size, motion) = match kind {
            Some(k) => ([r.draw(k.length), r.draw(k.width), r.draw(k.height)], k.motion),
            None => (fallback_size(row.class), Motion::Static),
        };
        elems.push(PlacedAgent {
            name: format!("{kind_name}_row{}_{}", ri + 1, k + 1),
            kind: kind_name,
            class: row.class,
            motion,
            is_object: true,
            size,
            pose,
            speed: 0.0,
            source: None,
            span: row.span,
        });
    }
    Ok(elems)
}

/// Station of a row's `to` end on the guide its `from` end chose, and the signed offset (left
/// positive) from the guide of that end's own line there (0 on the guide itself; of a lane end,
/// its lane's centre, which a taper across lanes slides to).
fn end_on(map: &Map, g: &Guide, to: &Place<f64>) -> Result<(f64, f64), Miss> {
    match to {
        Place::Lane { lane, along: b, .. } => {
            let (g2, s) = resolve::on_lane(map, *lane, b.landmark, b.dist)?;
            if g2.line == g.line {
                return Ok((s, 0.0));
            }
            let p = g2.line.pose_at(s).0;
            Ok(g.line.project(p))
        }
        Place::Sidewalk { arm, dir, along: b, .. } => {
            let (g2, s) = resolve::on_sidewalk(map, *arm, *dir, b.landmark, b.dist)?;
            if g2.line == g.line {
                return Ok((s, 0.0));
            }
            Ok(g.line.project(g2.line.pose_at(s).0))
        }
        other => {
            let p = resolve::pose(map, other, None)?;
            Ok(g.line.project(DVec2::new(p.x, p.y)))
        }
    }
}
