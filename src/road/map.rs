//! The map a road template produces: plain data in the world frame (metres, x east, y north).
//! Everything the BEV channels need is here as polygons and polylines, so `raster/` never has to
//! know how a template was built.

use crate::check::scenario::{Arm, LaneId, Turn};
use crate::geom::{Polygon, Polyline};
use glam::DVec2;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Map {
    pub lanes: Vec<Lane>,
    /// Paths through the junction from an in-lane to an out-lane.
    pub connectors: Vec<Connector>,
    pub stop_lines: Vec<StopLine>,
    pub crosswalks: Vec<Crosswalk>,
    pub sidewalks: Vec<Sidewalk>,

    // ---- BEV layers (SPEC.md channel table) ----
    /// ch 0: junction area.
    pub intersections: Vec<Polygon>,
    /// ch 1: all drivable surface: lanes, shoulders, junction.
    pub drivable: Vec<Polygon>,
    /// ch 2: sidewalks (same polygons as `sidewalks[i].polygon`).
    pub walkways: Vec<Polygon>,
    /// ch 3: parking areas.
    pub carparks: Vec<Polygon>,
    /// ch 4 (filled) and ch 16 (outlines): crosswalk polygons.
    pub crosswalk_polygons: Vec<Polygon>,
    /// ch 5: lane-group corridors inside the junction.
    pub lane_group_connectors: Vec<Polygon>,
    /// ch 6: lane groups outside the junction (all lanes of one direction of one arm).
    pub lane_groups: Vec<Polygon>,
    /// ch 7: road blocks (union of the lane groups of an arm, shoulders included).
    pub road_segments: Vec<Polygon>,
    /// ch 15: lane dividers and centre lines, each dash its own polyline.
    pub dividers: Vec<Vec<DVec2>>,
    /// ch 17 is the outline of (road_segments U intersections), computed by the rasteriser.

    /// Axis-aligned bounds of everything above: (min, max).
    pub bounds: (DVec2, DVec2),
    /// Traffic signals at the junction (`signals on`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signals: Option<crate::road::signals::SignalPlan>,
    /// Parking slots and driveways (`road/parking.rs`): where `parking(ARM.DIR)[K]` and
    /// `driveway(NAME)` stand.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub kerb_places: Vec<KerbPlace>,
}

/// A parking slot or a driveway's standing place: its centre and the heading of a vehicle in it
/// (along the lanes beside a slot; nosed in, away from the road, in a driveway).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KerbPlace {
    pub at: KerbRef,
    pub centre: DVec2,
    pub yaw: f64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum KerbRef {
    Slot {
        arm: Arm,
        dir: crate::check::scenario::Dir,
        slot: u32,
    },
    /// Index into `Road::kerb.driveways`.
    Driveway(usize),
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Lane {
    pub id: LaneId,
    /// Centre line in the direction of travel.
    pub centre: Polyline,
    pub width: f64,
    pub speed_limit: f64,
    /// Arc length (along `centre`) of the landmarks on this lane.
    pub center_s: f64,
    pub junction_s: Option<f64>,
    pub stop_line_s: Option<f64>,
    /// Width of paved shoulder on this lane's right (outermost lanes only), m.
    pub shoulder_right: f64,
    /// Lane that continues this one beyond its end without a junction choice (straight roads).
    pub next: Option<usize>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Connector {
    /// Indices into `Map::lanes`.
    pub from: usize,
    pub to: usize,
    pub turn: Turn,
    pub path: Polyline,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StopLine {
    pub lane: usize,
    pub a: DVec2,
    pub b: DVec2,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Crosswalk {
    pub arm: Arm,
    pub polygon: Polygon,
    /// Walking line across the road, from the kerb on the in-lanes' right to the far kerb.
    pub line: Polyline,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sidewalk {
    pub arm: Arm,
    /// The side of the road: along the arm's in-lanes or its out-lanes.
    pub dir: crate::check::scenario::Dir,
    pub polygon: Polygon,
    /// Centre line, oriented like the adjacent lanes' direction of travel.
    pub centre: Polyline,
}

impl Map {
    pub fn lane(&self, id: LaneId) -> Option<&Lane> {
        self.lanes.iter().find(|l| l.id == id)
    }
}
