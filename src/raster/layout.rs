//! The BEV format's numbers in one place: grid, resolution, channel indices, class ids.
//! In: nothing. Out: constants and the two lookups (class -> channel, class -> index) that every
//! BEV reader and writer in rocc must agree on. Format: docs/output.md, "BEV", as
//! read from UniScene-v2's `nuplan_bev_dataset` (nuPlan-Occ layout).

use crate::check::scenario::Class;

/// Pixels per side (SPEC: shape (18, 400, 400)).
pub const GRID: usize = 400;
/// Metres per pixel (SPEC: x = -50 + 0.25 i).
pub const RES: f64 = 0.25;
/// Pixels per metre, the scale of `lidar2canvas` in UniScene (`canvas / patch` = 400 / 100).
pub const PX_PER_M: f64 = 4.0;
/// Half the side of the square patch around the ego (SPEC: x, y in [-50, 50)).
pub const HALF_EXTENT_M: f64 = 50.0;
/// Whether any part of a box can reach the patch: its centre within half its diagonal of the
/// square. `boxes.json` lists exactly these boxes, so `rocc edit` applies the same rule.
pub fn box_reaches_patch(x: f64, y: f64, length: f64, width: f64) -> bool {
    let r = 0.5 * length.hypot(width);
    x.abs() <= HALF_EXTENT_M + r && y.abs() <= HALF_EXTENT_M + r
}
/// Canvas coordinate of the ego origin: u = 4 x + 200 (SPEC).
pub const CANVAS_ORIGIN: f64 = 200.0;

/// `gt_bev_masks` channels (SPEC channel table).
pub const N_MASKS: usize = 18;
/// `gt_aux_bev` channels (SPEC; UniScene `AUX_DATA_CH`: center_offset 2 + center_ohw 4 + height 1).
pub const N_AUX: usize = 7;

pub const CH_INTERSECTIONS: usize = 0;
pub const CH_DRIVABLE: usize = 1;
pub const CH_WALKWAYS: usize = 2;
pub const CH_CARPARKS: usize = 3;
pub const CH_CROSSWALKS: usize = 4;
pub const CH_LANE_GROUP_CONNECTORS: usize = 5;
pub const CH_LANE_GROUPS: usize = 6;
pub const CH_ROAD_SEGMENTS: usize = 7;
pub const CH_VEHICLE: usize = 8;
pub const CH_BICYCLE: usize = 9;
pub const CH_PEDESTRIAN: usize = 10;
pub const CH_TRAFFIC_CONE: usize = 11;
pub const CH_BARRIER: usize = 12;
pub const CH_CZONE_SIGN: usize = 13;
pub const CH_GENERIC_OBJECT: usize = 14;
pub const CH_DIVIDER: usize = 15;
pub const CH_PED_CROSSING: usize = 16;
pub const CH_BOUNDARY: usize = 17;

/// Channel names in `gt_bev_masks` order (SPEC table; UniScene `classes` + `object_classes` +
/// `map_classes`).
pub const MASK_NAMES: [&str; N_MASKS] = [
    "intersections",
    "generic_drivable_areas",
    "walkways",
    "carpark_areas",
    "crosswalks",
    "lane_group_connectors",
    "lane_groups_polygons",
    "road_segments",
    "vehicle",
    "bicycle",
    "pedestrian",
    "traffic_cone",
    "barrier",
    "czone_sign",
    "generic_object",
    "divider",
    "ped_crossing",
    "boundary",
];

pub const AUX_OFFSET_X: usize = 0;
pub const AUX_OFFSET_Y: usize = 1;
pub const AUX_HALF_LENGTH: usize = 2;
pub const AUX_HALF_WIDTH: usize = 3;
pub const AUX_HEADING_X: usize = 4;
pub const AUX_HEADING_Y: usize = 5;
pub const AUX_HEIGHT: usize = 6;

/// Key names inside the `.npz` (SPEC; UniScene `np.savez_compressed(..., gt_bev_masks=...,
/// gt_aux_bev=...)`). `structure` is rocc's extra key, kept apart so the standard ones stay
/// format-identical.
pub const KEY_MASKS: &str = "gt_bev_masks";
pub const KEY_AUX: &str = "gt_aux_bev";
pub const KEY_STRUCTURE: &str = "structure";

/// The mask channel an agent class is drawn into; `None` for `Structure`, which has no nuPlan
/// channel and goes to the extra `structure` mask.
pub fn class_channel(c: Class) -> Option<usize> {
    match c {
        Class::Vehicle => Some(CH_VEHICLE),
        Class::Bicycle => Some(CH_BICYCLE),
        Class::Pedestrian => Some(CH_PEDESTRIAN),
        Class::TrafficCone => Some(CH_TRAFFIC_CONE),
        Class::Barrier => Some(CH_BARRIER),
        Class::CzoneSign => Some(CH_CZONE_SIGN),
        Class::GenericObject => Some(CH_GENERIC_OBJECT),
        Class::Structure => None,
    }
}

/// Class index as in UniScene's `object_classes` list (`gt_labels_3d`): vehicle 0 ..
/// generic_object 6; rocc's `structure` extends it as 7. Written into `boxes.json`.
pub fn class_index(c: Class) -> u8 {
    match c {
        Class::Vehicle => 0,
        Class::Bicycle => 1,
        Class::Pedestrian => 2,
        Class::TrafficCone => 3,
        Class::Barrier => 4,
        Class::CzoneSign => 5,
        Class::GenericObject => 6,
        Class::Structure => 7,
    }
}

/// Continuous canvas coordinate of an ego-frame coordinate (metres): u = 4 x + 200.
#[inline]
pub fn to_canvas(m: f64) -> f64 {
    m * PX_PER_M + CANVAS_ORIGIN
}

/// Ego-frame coordinate (metres) of pixel index `i` (its centre in cv2's pixel model).
#[inline]
pub fn pixel_to_m(i: usize) -> f64 {
    -HALF_EXTENT_M + RES * i as f64
}
