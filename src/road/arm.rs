//! One road arm. In: an axis polyline from the arm's mouth (where it meets the junction or the
//! road centre) outward, lane counts and cross-section. Out: its lanes, stop lines, crosswalk,
//! sidewalks, lane groups, road segment, drivable strip and painted dividers, added to a `Map`.
//!
//! Cross-section, looking outward along the axis: out-lanes (driving away) on the right at
//! `-(median/2 + (k-0.5) w)`, in-lanes (driving toward the mouth) on the left at
//! `+(median/2 + (k-0.5) w)`, k = 1 nearest the axis, shoulders beyond the outermost lanes,
//! sidewalks beyond the shoulders.

use super::map::{Crosswalk, Lane, Map, Sidewalk, StopLine};
use super::shape::{dashes, parallel, reversed, strip};
use crate::check::scenario::{Arm, Dir, LaneId};
use crate::geom::Polyline;

/// Sidewalk width (m); the checker's minimum curve radius counts it too.
pub(crate) const SIDEWALK: f64 = crate::check::SIDEWALK_WIDTH_M;
/// Crosswalk width along the road (m).
pub(crate) const CROSSWALK: f64 = 4.0;

pub(crate) struct ArmSpec {
    pub arm: Arm,
    /// From the mouth outward; station 0 is the mouth.
    pub axis: Polyline,
    pub n_in: u32,
    pub n_out: u32,
    pub lane_width: f64,
    pub median: f64,
    pub shoulder: f64,
    pub speed_limit: f64,
    /// Axis station of the stop (or yield) line across the in-lanes.
    pub stop_at: Option<f64>,
    /// Axis station of the crosswalk's edge nearest the mouth.
    pub crosswalk_at: Option<f64>,
    /// Lanes get `junction_s` (at the mouth).
    pub junction: bool,
    /// Dividers are painted from this station outward (clear of the crosswalk and stop line).
    pub markings_from: f64,
    pub sidewalks: bool,
    /// One-way stretches (merge) put their sidewalk on the empty side of the axis instead.
    pub sidewalk_inner: bool,
}

impl ArmSpec {
    /// Lateral extent of the paved road on the in side (positive) and out side (as a positive
    /// number), shoulders and median included.
    pub fn half_widths(&self) -> (f64, f64) {
        let side =
            |n: u32| if n > 0 { self.median / 2.0 + f64::from(n) * self.lane_width + self.shoulder } else { 0.0 };
        (side(self.n_in), side(self.n_out))
    }
}

/// Lane indices (into `Map::lanes`) of an arm, `ins[k-1]` = `ARM.in[k]`.
pub(crate) struct BuiltArm {
    pub ins: Vec<usize>,
    pub outs: Vec<usize>,
}

pub(crate) fn add_arm(map: &mut Map, a: &ArmSpec) -> BuiltArm {
    let (w, m) = (a.lane_width, a.median);
    let len = a.axis.length();
    let (h_in, h_out) = a.half_widths();
    let mut built = BuiltArm { ins: Vec::new(), outs: Vec::new() };

    for k in 1..=a.n_out {
        let centre = a.axis.shifted(-(m / 2.0 + (f64::from(k) - 0.5) * w));
        built.outs.push(map.lanes.len());
        map.lanes.push(Lane {
            id: LaneId { arm: a.arm, dir: Dir::Out, index: k },
            centre,
            width: w,
            speed_limit: a.speed_limit,
            center_s: 0.0,
            junction_s: a.junction.then_some(0.0),
            stop_line_s: None,
            shoulder_right: if k == a.n_out { a.shoulder } else { 0.0 },
            next: None,
        });
    }
    for k in 1..=a.n_in {
        let off = m / 2.0 + (f64::from(k) - 0.5) * w;
        let centre = reversed(&a.axis.shifted(off));
        let end = centre.length();
        // Stations on a curved axis and on a lane beside it differ; the projection maps one to the other.
        let stop_line_s = a.stop_at.map(|st| centre.project(a.axis.offset_point(st, off)).0);
        if let Some(s) = stop_line_s {
            map.stop_lines.push(StopLine {
                lane: map.lanes.len(),
                a: centre.offset_point(s, w / 2.0),
                b: centre.offset_point(s, -w / 2.0),
            });
        }
        built.ins.push(map.lanes.len());
        map.lanes.push(Lane {
            id: LaneId { arm: a.arm, dir: Dir::In, index: k },
            centre,
            width: w,
            speed_limit: a.speed_limit,
            center_s: end,
            junction_s: a.junction.then_some(end),
            stop_line_s,
            shoulder_right: if k == a.n_in { a.shoulder } else { 0.0 },
            next: None,
        });
    }

    // Surfaces.
    let road = strip(&a.axis, 0.0, len, -h_out, h_in);
    map.road_segments.push(road.clone());
    map.drivable.push(road);
    if a.n_in > 0 {
        map.lane_groups.push(strip(&a.axis, 0.0, len, m / 2.0, m / 2.0 + f64::from(a.n_in) * w));
    }
    if a.n_out > 0 {
        map.lane_groups.push(strip(&a.axis, 0.0, len, -(m / 2.0 + f64::from(a.n_out) * w), -m / 2.0));
    }

    // Paint: broken lines between lanes of one direction, solid lines between directions (or at
    // the inner edge of a one-way stretch). Lane boundaries sit at multiples of the lane width
    // from the median edge, so no line ever runs through a lane centre whatever the lane count.
    let from = a.markings_from.min(len);
    for k in 1..a.n_in {
        map.dividers.extend(dashes(&a.axis, from, len, m / 2.0 + f64::from(k) * w));
    }
    for k in 1..a.n_out {
        map.dividers.extend(dashes(&a.axis, from, len, -(m / 2.0 + f64::from(k) * w)));
    }
    match (a.n_in > 0, a.n_out > 0) {
        (true, true) if m < 0.1 => map.dividers.push(parallel(&a.axis, from, len, 0.0)),
        (true, true) => {
            map.dividers.push(parallel(&a.axis, from, len, m / 2.0));
            map.dividers.push(parallel(&a.axis, from, len, -m / 2.0));
        }
        (true, false) => map.dividers.push(parallel(&a.axis, from, len, m / 2.0)),
        (false, true) => map.dividers.push(parallel(&a.axis, from, len, -m / 2.0)),
        (false, false) => {}
    }

    if let Some(c) = a.crosswalk_at {
        let polygon = strip(&a.axis, c, c + CROSSWALK, -h_out, h_in);
        let mid = c + CROSSWALK / 2.0;
        // The in-lanes drive toward the mouth, so their right-hand kerb is the far left of the axis.
        let line = Polyline::new(vec![a.axis.offset_point(mid, h_in), a.axis.offset_point(mid, -h_out)]);
        map.crosswalk_polygons.push(polygon.clone());
        map.crosswalks.push(Crosswalk { arm: a.arm, polygon, line });
    }

    if a.sidewalks {
        for (dir, n) in [(Dir::In, a.n_in), (Dir::Out, a.n_out)] {
            if n == 0 {
                continue;
            }
            let sign = if dir == Dir::In { 1.0 } else { -1.0 };
            let (near, far) = match (a.sidewalk_inner, dir) {
                (true, _) => (0.0, -sign * SIDEWALK),
                (false, Dir::In) => (h_in, h_in + SIDEWALK),
                (false, Dir::Out) => (-h_out, -h_out - SIDEWALK),
            };
            let polygon = strip(&a.axis, 0.0, len, near, far);
            let along = a.axis.shifted((near + far) / 2.0);
            let centre = if dir == Dir::In { reversed(&along) } else { along };
            map.walkways.push(polygon.clone());
            map.sidewalks.push(Sidewalk { arm: a.arm, dir, polygon, centre });
        }
    }
    built
}
