//! Kerbside places and reversing: parking lanes and driveways in the road block, placements in
//! a parking slot or a driveway, and the `reverse` goal (E0250-E0259). The geometry constants
//! here are the ones the road pass lays out (`road/parking.rs`).

use super::scenario::*;
use super::units::Dim;
use super::{Checker, lane_count, word};
use crate::diag::{Diagnostic, did_you_mean};
use crate::source::Span;
use crate::syntax::ast;
use serde::{Deserialize, Serialize};

/// A parking lane's width unless stated, m.
pub const PARKING_WIDTH_M: f64 = 2.5;
/// Length of one parallel-parking slot along the kerb, m.
pub const SLOT_LENGTH_M: f64 = 6.0;
/// A driveway's width along the kerb, m.
pub const DRIVEWAY_WIDTH_M: f64 = 3.5;
/// How far a driveway reaches beyond the sidewalk (where a car stands in it), m.
pub const DRIVEWAY_APRON_M: f64 = 7.0;
/// Kerbside places keep this far from the centre of a road with a mid-block crosswalk, m (the
/// crosswalk is 4 m wide; the kerb there is a kerb extension, walkway).
pub const KERB_CLEAR_M: f64 = 3.0;
/// The fastest a vehicle reverses, and its pace when its goal gives none, m/s.
pub const REVERSE_MAX_MS: f64 = 3.0;
pub const REVERSE_SPEED_MS: f64 = 1.5;

impl Road {
    /// Where kerbside places start along each arm, m from the road's centre.
    pub fn kerb_start(&self) -> f64 {
        if self.crosswalks { KERB_CLEAR_M } else { 0.0 }
    }

    /// How many parking slots fit along one arm.
    pub fn parking_slots(&self) -> u32 {
        ((self.length / 2.0 - self.kerb_start()) / SLOT_LENGTH_M).floor().max(0.0) as u32
    }

    /// Slot `k`'s stretch along its arm (1 = nearest the centre), m from the road's centre.
    pub fn slot_stretch(&self, k: u32) -> (f64, f64) {
        let lo = self.kerb_start() + f64::from(k.max(1) - 1) * SLOT_LENGTH_M;
        (lo, lo + SLOT_LENGTH_M)
    }

    /// The parking lane along a kerb, if there is one.
    pub fn parking_at(&self, arm: Arm, dir: Dir) -> Option<&ParkingLane> {
        self.kerb.parking.iter().find(|p| p.arm == arm && p.dir == dir)
    }
}

fn dir_of(d: ast::Dir) -> Dir {
    if d == ast::Dir::In { Dir::In } else { Dir::Out }
}

fn side_name(arm: Arm, dir: Dir) -> String {
    format!("{}.{}", arm.name(), if dir == Dir::In { "in" } else { "out" })
}

impl Checker {
    /// The road block's `parking` and `driveway` lines, checked against the road built from its
    /// parameters.
    pub(super) fn kerbside(&mut self, r: &ast::Road, road: &Road) -> Option<Kerbside> {
        let mut out = Kerbside::default();
        let mut ok = true;
        let mut spans: Vec<(Arm, Dir, Span)> = vec![];
        let mut drive_spans: Vec<Span> = vec![];
        for k in &r.kerb {
            let span = match k {
                ast::KerbDecl::Parking { span, .. } | ast::KerbDecl::Driveway { span, .. } => *span,
            };
            if road.template != Template::Straight {
                self.err(
                    Diagnostic::error(
                        "E0254",
                        format!(
                            "parking lanes and driveways are laid along straight roads, not a {}",
                            road.template.name()
                        ),
                    )
                    .label(span, "not on this road")
                    .help("use `road straight { ... }` for a street with parking or driveways"),
                );
                ok = false;
                continue;
            }
            match k {
                ast::KerbDecl::Parking { arm, side, width, .. } => {
                    let arm = self.arm(arm, road);
                    let sides = word(
                        self,
                        side,
                        &[
                            ("in", [Some(Dir::In), None]),
                            ("out", [Some(Dir::Out), None]),
                            ("both", [Some(Dir::In), Some(Dir::Out)]),
                        ],
                        "kerb side",
                    );
                    let width = match width {
                        Some(w) => self.fixed(w, Dim::Length, "parking lane width", 2.0, 4.0, "2..4 m"),
                        None => Some(PARKING_WIDTH_M),
                    };
                    let (Some(arm), Some(sides), Some(width)) = (arm, sides, width) else {
                        ok = false;
                        continue;
                    };
                    for dir in sides.into_iter().flatten() {
                        if let Some(&(_, _, first)) = spans.iter().find(|(a, d, _)| *a == arm && *d == dir) {
                            self.err(
                                Diagnostic::error(
                                    "E0255",
                                    format!("two parking lanes overlap along {}", side_name(arm, dir)),
                                )
                                .label(span, "second one here")
                                .label(first, "first one here")
                                .help("one parking lane per kerb: keep one line (`both` covers in and out)"),
                            );
                            ok = false;
                            continue;
                        }
                        spans.push((arm, dir, span));
                        out.parking.push(ParkingLane { arm, dir, width });
                    }
                }
                ast::KerbDecl::Driveway { name, side, at, .. } => {
                    let arm = self.arm(&side.arm, road);
                    let dir = dir_of(side.dir);
                    let at_v = self.fixed(at, Dim::Length, "driveway position", 0.0, 1000.0, "0..1000 m");
                    let (Some(arm), Some(at_m)) = (arm, at_v) else {
                        ok = false;
                        continue;
                    };
                    if !road.sidewalks {
                        self.err(
                            Diagnostic::error("E0256", format!("driveway `{}` crosses no sidewalk", name.name))
                                .label(span, "this road has no sidewalks")
                                .help("a driveway crosses the sidewalk: add `sidewalks on` to the road block"),
                        );
                        ok = false;
                        continue;
                    }
                    let (lo, hi) =
                        (road.kerb_start() + DRIVEWAY_WIDTH_M / 2.0, road.length / 2.0 - DRIVEWAY_WIDTH_M / 2.0);
                    if at_m < lo || at_m > hi {
                        self.err(
                            Diagnostic::error("E0257", format!("driveway `{}` is off its arm", name.name))
                                .label(at.span, format!("must be within {lo:.2}..{hi:.2} m of the road's centre"))
                                .help(format!(
                                    "the {} arm runs {:.0} m from the centre; a driveway is {DRIVEWAY_WIDTH_M} m wide{}",
                                    arm.name(),
                                    road.length / 2.0,
                                    if road.crosswalks { " and keeps clear of the crosswalk" } else { "" }
                                )),
                        );
                        ok = false;
                        continue;
                    }
                    if let Some(k) = out.driveways.iter().position(|d| d.name == name.name) {
                        self.dup(&format!("driveway `{}`", name.name), drive_spans[k], span);
                        ok = false;
                        continue;
                    }
                    if let Some(k) = out
                        .driveways
                        .iter()
                        .position(|d| d.arm == arm && d.dir == dir && (d.at - at_m).abs() < DRIVEWAY_WIDTH_M)
                    {
                        self.err(
                            Diagnostic::error(
                                "E0255",
                                format!("driveways `{}` and `{}` overlap", out.driveways[k].name, name.name),
                            )
                            .label(span, "this one")
                            .label(drive_spans[k], "overlaps this one")
                            .help(format!("driveways on one kerb keep {DRIVEWAY_WIDTH_M} m apart (their width)")),
                        );
                        ok = false;
                        continue;
                    }
                    drive_spans.push(span);
                    out.driveways.push(Driveway { name: name.name.clone(), arm, dir, at: at_m });
                }
            }
        }
        ok.then_some(out)
    }

    /// `parking(ARM.DIR)[K]` and `driveway(NAME)`.
    pub(super) fn kerb_placement(&mut self, p: &ast::Placement, road: &Road) -> Option<Place> {
        match p {
            ast::Placement::Parking { side, slot, slot_span, span } => {
                let arm = self.arm(&side.arm, road)?;
                let dir = dir_of(side.dir);
                if road.parking_at(arm, dir).is_none() {
                    let a = arm.name();
                    self.err(
                        Diagnostic::error("E0259", format!("there is no parking lane along {}", side_name(arm, dir)))
                            .label(side.span, "no parking here")
                            .help(format!(
                                "add `parking {a} {}` to the road block",
                                if dir == Dir::In { "in" } else { "out" }
                            )),
                    );
                    return None;
                }
                let n = road.parking_slots();
                if *slot == 0 || *slot > n {
                    self.err(
                        Diagnostic::error("E0258", format!("parking slot {slot} does not exist"))
                            .label(*slot_span, format!("slots are numbered 1..={n}"))
                            .help(format!(
                                "slots are {SLOT_LENGTH_M} m long, numbered from the road's centre outward; a longer \
                                 road (`length`) has more"
                            )),
                    );
                    return None;
                }
                let (lo, hi) = road.slot_stretch(*slot);
                let across = road.kerb.driveways.iter().find(|d| {
                    d.arm == arm
                        && d.dir == dir
                        && d.at + DRIVEWAY_WIDTH_M / 2.0 > lo
                        && d.at - DRIVEWAY_WIDTH_M / 2.0 < hi
                });
                if let Some(d) = across {
                    self.err(
                        Diagnostic::error("E0255", format!("parking slot {slot} overlaps driveway `{}`", d.name))
                            .label(*span, format!("slot {slot} runs {lo:.1}..{hi:.1} m along {}", arm.name()))
                            .help("a driveway's mouth is kept clear: use another slot, or move the driveway"),
                    );
                    return None;
                }
                Some(Place::Parking { arm, dir, slot: *slot })
            }
            ast::Placement::Driveway { name, span } => {
                match road.kerb.driveways.iter().position(|d| d.name == name.name) {
                    Some(index) => Some(Place::Driveway { index }),
                    None => {
                        let names: Vec<&str> = road.kerb.driveways.iter().map(|d| d.name.as_str()).collect();
                        let help = if names.is_empty() {
                            "declare one in the road block, e.g. `driveway d1 east.out 20 m` (needs `sidewalks on`)"
                                .to_string()
                        } else {
                            did_you_mean(&name.name, &names, "driveway")
                        };
                        self.err(
                            Diagnostic::error("E0259", format!("there is no driveway `{}`", name.name))
                                .label(*span, "unknown driveway")
                                .help(help),
                        );
                        None
                    }
                }
            }
            _ => None,
        }
    }

    /// A `reverse` goal's own words: vehicles only, a distance in range, a lane that exists.
    pub(super) fn reverse(
        &mut self,
        to: &ast::ReverseTo,
        span: Span,
        class: Class,
        road: Option<&Road>,
    ) -> Option<Reverse> {
        if class != Class::Vehicle {
            self.err(
                Diagnostic::error("E0250", format!("a {} cannot reverse", class.name()))
                    .label(span, "reverse goal")
                    .help("reverse goals are for vehicles; a walker or an animal turns and walks (`heading`)"),
            );
            return None;
        }
        match to {
            ast::ReverseTo::Dist(v) => {
                self.fixed(v, Dim::Length, "reverse distance", 0.5, 100.0, "0.5..100 m").map(Reverse::Dist)
            }
            ast::ReverseTo::Into(l) => {
                let road = road?;
                let arm = self.arm(&l.arm, road)?;
                let dir = dir_of(l.dir);
                let lanes = lane_count(road, arm, dir);
                if l.index == 0 || l.index > lanes {
                    self.err(
                        Diagnostic::error("E0253", format!("there is no lane {} to reverse into", l.index))
                            .label(l.index_span, format!("lanes are numbered 1..={lanes}"))
                            .help(format!("reverse into {}[1] .. [{lanes}]", side_name(arm, dir))),
                    );
                    return None;
                }
                Some(Reverse::Into(LaneId { arm, dir, index: l.index }))
            }
        }
    }

    /// A reverse goal is the whole goal: no turn, lane move or stop beside it, at reverse speed,
    /// and `reverse into` starts off the lanes (a driveway or a parking slot).
    pub(super) fn reverse_fits(&mut self, g: &Goal, r: Reverse, ast_goal: &ast::Goal, place: Option<&Place>) -> bool {
        let mut ok = true;
        for st in &ast_goal.stmts {
            let clash = match st {
                ast::GoalStmt::Turn { .. } => Some("turn"),
                ast::GoalStmt::Stop { .. } => Some("stop"),
                ast::GoalStmt::Lateral { .. } if g.lateral != Lateral::HoldLane => Some("lateral move"),
                _ => None,
            };
            if let Some(what) = clash {
                self.err(
                    Diagnostic::error("E0252", format!("a reverse goal cannot also {what}"))
                        .label(st.span(), "drives forward")
                        .help(format!(
                            "a reverse goal says where the vehicle ends, and it stops there: remove the {what}"
                        )),
                );
                ok = false;
            }
            if let ast::GoalStmt::Speed { span, .. } = st
                && g.speed.is_some_and(|v| v.hi() > REVERSE_MAX_MS + 1e-9)
            {
                self.err(
                    Diagnostic::error("E0251", "too fast for reversing")
                        .label(*span, format!("reverse speeds are at most {REVERSE_MAX_MS} m/s"))
                        .help(format!(
                            "give `speed {REVERSE_MAX_MS} m/s` or less (without one it reverses at {REVERSE_SPEED_MS} m/s)"
                        )),
                );
                ok = false;
            }
        }
        if let (Reverse::Into(_), Some(Place::Lane { .. } | Place::Crosswalk { .. } | Place::Sidewalk { .. })) =
            (r, place)
        {
            let span = ast_goal.stmts.iter().find(|s| matches!(s, ast::GoalStmt::Reverse { .. })).map(|s| s.span());
            self.err(
                Diagnostic::error("E0253", "`reverse into` starts in a driveway or a parking slot")
                    .label(span.unwrap_or(ast_goal.span), "reverse into a lane")
                    .help("place it `at driveway(NAME)` or `at parking(ARM.DIR)[K]`; on a lane use `reverse DIST`"),
            );
            ok = false;
        }
        ok
    }
}

// ---- kerbside places and reversing (re-exported by `scenario`; road/parking.rs, rollout/drive/reverse.rs) ----

/// Parking lanes and driveways along a road's kerbs.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Kerbside {
    pub parking: Vec<ParkingLane>,
    pub driveways: Vec<Driveway>,
}

impl Kerbside {
    pub fn is_empty(&self) -> bool {
        self.parking.is_empty() && self.driveways.is_empty()
    }
}

/// A parking lane along the kerb of an arm's in-lanes or out-lanes, between the paving and the
/// sidewalk.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParkingLane {
    pub arm: Arm,
    pub dir: Dir,
    /// Its width, m.
    pub width: f64,
}

/// A driveway across the sidewalk on the kerb of an arm's in-lanes or out-lanes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Driveway {
    pub name: String,
    pub arm: Arm,
    pub dir: Dir,
    /// Its centre's distance along the arm from the road's centre, m.
    pub at: f64,
}

/// Where a reverse goal ends.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reverse {
    /// Straight back along its heading, this far (m).
    Dist(f64),
    /// Rear first into this lane, ending aligned with it, facing its direction of travel.
    Into(LaneId),
}
