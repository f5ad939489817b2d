//! Where things stand: `at` placements along an arm's lanes, headings and rows of objects.

use super::scenario::*;
use super::units::Dim;
use super::{Checker, MAX_ROW_OBJECTS, lane_count, word};
use crate::diag::Diagnostic;
use crate::syntax::ast;
use std::collections::BTreeMap;

impl Checker {
    fn along(&mut self, a: &ast::Along, road: &Road, dir: Dir, sidewalk: bool) -> Option<Along> {
        let landmark = word(self, &a.landmark, &LANDMARKS, "landmark");
        let dist = self.bounded(&a.dist, Dim::Length, "distance", 0.0, 2000.0, "0..2000 m");
        let landmark = landmark?;
        let bad = match landmark {
            Landmark::Center => None,
            Landmark::Junction if !road.template.has_junction() => {
                Some(format!("a {} road has no junction", road.template.name()))
            }
            Landmark::StopLine if !road.template.has_stop_lines() => {
                Some(format!("a {} road has no stop lines", road.template.name()))
            }
            Landmark::StopLine if dir == Dir::Out || sidewalk => Some("stop lines are on in-lanes only".to_string()),
            _ => None,
        };
        if let Some(msg) = bad {
            self.err(
                Diagnostic::error("E0111", msg)
                    .label(a.landmark.span, "landmark not on this road")
                    .help(if road.template.has_junction() { "use `junction` or `center`" } else { "use `center`" }),
            );
            return None;
        }
        let dist = dist?;
        Some(Along { landmark, dist: if a.rel == ast::Rel::Before { dist.map(|d| -d) } else { dist } })
    }

    fn offset(&mut self, o: &Option<ast::Offset>) -> Option<f64> {
        let Some(o) = o else { return Some(0.0) };
        let side = word(self, &o.side, &SIDES, "side");
        let d = self.fixed(&o.dist, Dim::Length, "offset", 0.0, 50.0, "0..50 m")?;
        Some(if side? == Side::Left { d } else { -d })
    }

    fn heading(&mut self, h: &Option<ast::Value>) -> Option<Option<Dist>> {
        match h {
            None => Some(None),
            Some(v) => self
                .bounded(
                    v,
                    Dim::Angle,
                    "heading",
                    -4.0 * std::f64::consts::PI,
                    4.0 * std::f64::consts::PI,
                    "-720..720 deg",
                )
                .map(Some),
        }
    }

    fn dir(d: ast::Dir) -> Dir {
        if d == ast::Dir::In { Dir::In } else { Dir::Out }
    }

    pub(super) fn placement(&mut self, p: &ast::Placement, road: Option<&Road>, class: Option<Class>) -> Option<Place> {
        match p {
            ast::Placement::World { x, y, heading, .. } => {
                let x = self.bounded(x, Dim::Length, "x", -1000.0, 1000.0, "-1000..1000 m");
                let y = self.bounded(y, Dim::Length, "y", -1000.0, 1000.0, "-1000..1000 m");
                let heading = self.heading(heading);
                Some(Place::World { x: x?, y: y?, heading: heading? })
            }
            ast::Placement::Lane { lane, along, offset, heading, .. } => {
                let road = road?;
                let arm = self.arm(&lane.arm, road);
                let dir = Self::dir(lane.dir);
                let along = self.along(along, road, dir, false);
                let offset = self.offset(offset);
                let heading = self.heading(heading);
                let arm = arm?;
                let lanes = lane_count(road, arm, dir);
                if lanes == 0 {
                    self.err(
                        Diagnostic::error(
                            "E0112",
                            format!(
                                "the {} arm has no {} lanes",
                                arm.name(),
                                if dir == Dir::In { "in" } else { "out" }
                            ),
                        )
                        .label(lane.span, "no such lanes")
                        .help("the ramp of a merge has one in-lane: `ramp.in[1]`"),
                    );
                    return None;
                }
                if lane.index == 0 || lane.index > lanes {
                    self.err(
                        Diagnostic::error(
                            "E0112",
                            format!(
                                "lane {} does not exist on a road with {} lane{} per direction",
                                lane.index,
                                lanes,
                                if lanes == 1 { "" } else { "s" }
                            ),
                        )
                        .label(lane.index_span, format!("lanes are numbered 1..={lanes}"))
                        .help(format!(
                            "use {}.{}[1] (nearest the centre line) .. [{lanes}], or raise `lanes`",
                            arm.name(),
                            if dir == Dir::In { "in" } else { "out" }
                        )),
                    );
                    return None;
                }
                Some(Place::Lane {
                    lane: LaneId { arm, dir, index: lane.index },
                    along: along?,
                    offset: offset?,
                    heading: heading?,
                })
            }
            ast::Placement::Crosswalk { arm, fraction, span } => {
                let road = road?;
                let a = self.arm(arm, road);
                let f = self.bounded(fraction, Dim::Ratio, "crosswalk position", 0.0, 1.0, "0..100 %");
                if !road.crosswalks {
                    self.err(
                        Diagnostic::error("E0203", "this road has no crosswalks")
                            .label(*span, "crosswalk placement")
                            .help("add `crosswalks on` to the road block"),
                    );
                    return None;
                }
                Some(Place::Crosswalk { arm: a?, fraction: f? })
            }
            ast::Placement::Sidewalk { side, along, offset, heading, span } => {
                let road = road?;
                let arm = self.arm(&side.arm, road);
                let dir = Self::dir(side.dir);
                let along = self.along(along, road, dir, true);
                let offset = self.offset(offset);
                let heading = self.heading(heading);
                if !road.sidewalks {
                    self.err(
                        Diagnostic::error("E0203", "this road has no sidewalks")
                            .label(*span, "sidewalk placement")
                            .help("add `sidewalks on` to the road block"),
                    );
                    return None;
                }
                if let Some(c @ Class::Vehicle) = class {
                    self.err(
                        Diagnostic::error("E0201", format!("a {} cannot be placed on a sidewalk", c.name()))
                            .label(*span, "sidewalk")
                            .help("place vehicles on a lane, e.g. `at east.out[1], 10 m after center`, or on the shoulder with `offset`"),
                    );
                    return None;
                }
                Some(Place::Sidewalk { arm: arm?, dir, along: along?, offset: offset?, heading: heading? })
            }
            ast::Placement::Parking { .. } | ast::Placement::Driveway { .. } => self.kerb_placement(p, road?),
        }
    }

    pub(super) fn row(&mut self, r: &ast::Row, road: Option<&Road>, used: &mut BTreeMap<String, Kind>) -> Option<Row> {
        let kind = self.kind_ref(&r.kind, used);
        let class = kind.as_ref().map(|k| k.1);
        let from = self.placement(&r.from, road, class);
        let to = self.placement(&r.to, road, class);
        let every = self.fixed(&r.every, Dim::Length, "row spacing", 0.1, 1000.0, "0.1..1000 m");
        let (kind, from, to, every) = (kind?, from?, to?, every?);
        let same = match (&from, &to) {
            // Lanes of one arm and direction run side by side: a row across them is a taper.
            (Place::Lane { lane: a, .. }, Place::Lane { lane: b, .. }) => a.arm == b.arm && a.dir == b.dir,
            (Place::Sidewalk { arm: a, dir: d, .. }, Place::Sidewalk { arm: b, dir: e, .. }) => a == b && d == e,
            (Place::World { .. }, Place::World { .. }) => true,
            _ => false,
        };
        if !same {
            self.err(
                Diagnostic::error(
                    "E0118",
                    "a row runs along the lanes of one arm and direction, one sidewalk, or between two world points",
                )
                .label(r.to.span(), "different arm, direction or placement form than `from`")
                .label(r.from.span(), "row starts here")
                .help("put both ends on lanes of one arm and direction (a taper may change lane), e.g. `from west.in[2], 20 m before center to west.in[1], 30 m after center`"),
            );
            return None;
        }
        let extent = match (&from, &to) {
            (Place::Lane { along: a, .. }, Place::Lane { along: b, .. })
            | (Place::Sidewalk { along: a, .. }, Place::Sidewalk { along: b, .. }) => {
                // Different landmarks are a few metres apart at most; the road pass measures exactly.
                (b.dist.hi() - a.dist.lo()).abs() + 100.0 * f64::from(u8::from(a.landmark != b.landmark))
            }
            (Place::World { x: x0, y: y0, .. }, Place::World { x: x1, y: y1, .. }) => {
                (x1.hi() - x0.lo()).hypot(y1.hi() - y0.lo())
            }
            _ => 0.0,
        };
        if extent / every > MAX_ROW_OBJECTS as f64 {
            self.err(
                Diagnostic::error("E0118", format!("this row would place about {} objects", (extent / every) as u64))
                    .label(r.every.span, "spacing too small for the length")
                    .help(format!("a row holds at most {MAX_ROW_OBJECTS} objects; increase `every`")),
            );
            return None;
        }
        Some(Row { kinds: kind.0, class: kind.1, from, to, every, span: r.span })
    }
}
