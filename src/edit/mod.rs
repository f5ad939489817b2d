//! Scene editing (`rocc edit`). In: a compiled clip directory (or a `.scn` file) and box edits —
//! insert an agent, delete one, move one. Out: the same clip with its box list edited, the
//! dynamic and auxiliary BEV channels re-rasterised from the edited boxes over the untouched
//! static layers, and occupancy, LiDAR, previews and manifest rerun (paper, App. E); or, for a
//! `.scn`, the edited text, gated by the checker and the placement pass.
//!
//! An edit changes only the box list. An inserted or moved box is accepted only on a surface the
//! BEV marks valid for its class and without overlapping another box or the ego; a rejected edit
//! is an E07xx diagnostic that says why, and nothing is written.

mod clip;
mod scn;
mod spec;

pub use crate::output::read_boxes_json;
pub use clip::{ClipEdit, edit_clip, rerasterize};
pub use scn::edit_scn;
pub use spec::{Edit, parse_edit};

use crate::check::scenario::Class;
use crate::diag::{Diagnostic, did_you_mean};
use crate::geom::Obb;
use crate::raster::Bev;
use crate::raster::layout::*;
use crate::view::EgoBox;
use glam::DVec2;
use std::collections::BTreeMap;
use std::sync::Mutex;

/// Boxes may touch; they overlap only past this much interpenetration (m per side), as in `place`.
const TOUCH: f64 = 0.01;

/// A stdlib kind's class and its mid-range box (l, w, h).
#[derive(Clone, Debug, PartialEq)]
pub struct KindInfo {
    pub class: Class,
    pub size: [f64; 3],
    /// (lo, hi) per side, for samplers.
    pub ranges: [(f64, f64); 3],
}

static KINDS: Mutex<BTreeMap<String, KindInfo>> = Mutex::new(BTreeMap::new());

/// Look a kind up in the stdlib prelude (through the checker, so the answer is the language's).
pub fn kind_info(name: &str) -> Result<KindInfo, Diagnostic> {
    if let Some(k) = KINDS.lock().ok().and_then(|m| m.get(name).cloned()) {
        return Ok(k);
    }
    let bad =
        || Diagnostic::error("E0713", format!("unknown kind `{name}`")).help(did_you_mean(name, &STDLIB_KINDS, "kind"));
    if !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') || name.is_empty() {
        return Err(bad());
    }
    let text = format!(
        "scenario k {{ duration 1 s; rate 10 Hz; egos [e]; road none\n agent e: sedan {{ track {{ 0 s: (0 m, 0 m) yaw 0 rad }} }}\n agent x: {name} {{ track {{ 0 s: (50 m, 0 m) yaw 0 rad }} }} }}"
    );
    let mut sources = crate::source::SourceMap::default();
    let s = crate::check::check_text("kind.scn", &text, std::path::Path::new("."), &mut sources).map_err(|_| bad())?;
    let k = s.kinds.get(name).ok_or_else(bad)?;
    let r = |d: crate::check::scenario::Dist| (d.lo(), d.hi());
    let ranges = [r(k.length), r(k.width), r(k.height)];
    let info = KindInfo { class: k.class, size: ranges.map(|(a, b)| 0.5 * (a + b)), ranges };
    if let Ok(mut m) = KINDS.lock() {
        m.insert(name.to_string(), info.clone());
    }
    Ok(info)
}

/// The stdlib kinds, for suggestions (stdlib/kinds.scn).
pub const STDLIB_KINDS: [&str; 32] = [
    "sedan",
    "hatchback",
    "suv",
    "pickup_truck",
    "van",
    "bus",
    "truck",
    "semi_truck",
    "ambulance",
    "fire_truck",
    "police_car",
    "motorcycle",
    "bicycle",
    "scooter",
    "pedestrian",
    "adult",
    "child",
    "wheelchair_user",
    "traffic_cone",
    "barrier",
    "jersey_barrier",
    "construction_sign",
    "debris",
    "tire",
    "stroller",
    "animal",
    "dog",
    "trash_bin",
    "tree",
    "pole",
    "wall",
    "building",
];

/// Whether the BEV's map layers make the pixel under an ego-frame point a valid surface for
/// `class` (the BEV twin of `place`'s surface rule): vehicles on drivable paving, bicycles there
/// or on walkways and crosswalks; people, like static things, anywhere on the grid (standing,
/// kneeling or lying on a lane included, as the checker allows). `Err` names what was needed.
pub fn surface_ok(bev: &Bev, class: Class, x: f64, y: f64) -> Result<(), &'static str> {
    surface(bev, class, x, y, false)
}

/// `surface_ok` with people where they usually are: on walkways, crosswalks or the shoulder
/// (road block outside the lane groups). The edit protocol inserts them there, as the paper does.
pub fn usual_surface_ok(bev: &Bev, class: Class, x: f64, y: f64) -> Result<(), &'static str> {
    surface(bev, class, x, y, true)
}

fn surface(bev: &Bev, class: Class, x: f64, y: f64, usual: bool) -> Result<(), &'static str> {
    let px = |m: f64| to_canvas(m).floor();
    let (i, j) = (px(x), px(y));
    if !(0.0..GRID as f64).contains(&i) || !(0.0..GRID as f64).contains(&j) {
        return Err("a point inside the 100 m BEV");
    }
    let at = |ch: usize| bev.masks.get((ch, i as usize, j as usize)).is_some_and(|&v| v != 0);
    let drivable = at(CH_DRIVABLE)
        || at(CH_INTERSECTIONS)
        || at(CH_CARPARKS)
        || at(CH_LANE_GROUPS)
        || at(CH_LANE_GROUP_CONNECTORS);
    let shoulder = at(CH_ROAD_SEGMENTS) && !at(CH_LANE_GROUPS) && !at(CH_LANE_GROUP_CONNECTORS);
    let (ok, need) = match class {
        Class::Vehicle => (drivable, "drivable area (BEV channels 0, 1, 3, 5, 6)"),
        Class::Bicycle => (drivable || at(CH_WALKWAYS) || at(CH_CROSSWALKS), "drivable area, a walkway or a crosswalk"),
        Class::Pedestrian if usual => {
            (at(CH_WALKWAYS) || at(CH_CROSSWALKS) || shoulder, "a walkway, a crosswalk or the shoulder")
        }
        _ => (true, ""),
    };
    if ok { Ok(()) } else { Err(need) }
}

/// What the BEV shows under a point, for rejection messages.
pub fn describe_surface(bev: &Bev, x: f64, y: f64) -> &'static str {
    let (i, j) = (to_canvas(x).floor(), to_canvas(y).floor());
    if !(0.0..GRID as f64).contains(&i) || !(0.0..GRID as f64).contains(&j) {
        return "outside the BEV";
    }
    let at = |ch: usize| bev.masks.get((ch, i as usize, j as usize)).is_some_and(|&v| v != 0);
    if at(CH_CROSSWALKS) {
        "on a crosswalk"
    } else if at(CH_WALKWAYS) {
        "on a walkway"
    } else if at(CH_INTERSECTIONS) {
        "in a junction"
    } else if at(CH_LANE_GROUPS) || at(CH_LANE_GROUP_CONNECTORS) {
        "on a lane"
    } else if at(CH_ROAD_SEGMENTS) || at(CH_DRIVABLE) {
        "on the shoulder"
    } else {
        "off the road"
    }
}

fn obb(b: &EgoBox) -> Obb {
    Obb {
        center: DVec2::new(b.x, b.y),
        yaw: b.yaw,
        length: (b.l - 2.0 * TOUCH).max(0.0),
        width: (b.w - 2.0 * TOUCH).max(0.0),
    }
}

/// The first box of `others` (or the ego's own box, centred at the origin) that `b` overlaps.
pub fn overlap<'a>(b: &EgoBox, others: impl IntoIterator<Item = &'a EgoBox>, ego_size: [f64; 3]) -> Option<String> {
    let ob = obb(b);
    let reach = |o: &Obb| 0.5 * o.length.hypot(o.width);
    let hits = |o: &Obb| ob.center.distance(o.center) < reach(&ob) + reach(o) && ob.overlaps(o);
    let ego =
        Obb { center: DVec2::ZERO, yaw: 0.0, length: ego_size[0] - 2.0 * TOUCH, width: ego_size[1] - 2.0 * TOUCH };
    if hits(&ego) {
        return Some("the ego".to_string());
    }
    others.into_iter().find(|o| o.agent != b.agent && hits(&obb(o))).map(|o| format!("`{}`", o.agent))
}

/// Validate a box about to be placed in a frame: surface for its class, then overlap.
pub fn validate_box(
    bev: &Bev,
    b: &EgoBox,
    others: &[EgoBox],
    ego_size: [f64; 3],
    frame: usize,
    what: &str,
) -> Result<(), Diagnostic> {
    if let Err(need) = surface_ok(bev, b.class, b.x, b.y) {
        return Err(Diagnostic::error(
            "E0710",
            format!(
                "{what}: a {} must stand on {need}, but ({:.2}, {:.2}) in frame {frame}'s ego frame is {}",
                b.class.name(),
                b.x,
                b.y,
                describe_surface(bev, b.x, b.y)
            ),
        )
        .help("pick a point on a valid surface; the BEV preview (preview/bev.png) shows the map layers"));
    }
    no_overlap(b, others, ego_size, frame, what)
}

/// The overlap half of `validate_box`: E0711 when `b` interpenetrates another box or the ego.
pub fn no_overlap(
    b: &EgoBox,
    others: &[EgoBox],
    ego_size: [f64; 3],
    frame: usize,
    what: &str,
) -> Result<(), Diagnostic> {
    if let Some(who) = overlap(b, others, ego_size) {
        return Err(Diagnostic::error(
            "E0711",
            format!(
                "{what}: in frame {frame}, the {:.1} x {:.1} m box at ({:.2}, {:.2}) (that frame's ego frame) overlaps {who}",
                b.l, b.w, b.x, b.y
            ),
        )
        .help("move it clear of the other boxes (they may touch, not interpenetrate)"));
    }
    Ok(())
}
