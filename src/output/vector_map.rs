//! `scene.json`: a clip's map as world-frame vectors, one list of polylines per class (the
//! MapTR convention), taken from the same `road::Map` the BEV is painted from. Classes: lane
//! centrelines (lanes and junction connectors, in the direction of travel), lane dividers (the
//! painted lines of BEV channel 15, each dash its own polyline), road boundaries (the outline of
//! road blocks and junctions, BEV channel 17), crosswalks (closed outlines, channel 16) and stop
//! lines (two points each); and the junction's signals, where it has them. Parking lanes and
//! driveways (BEV channel 3) are no MapTR class: where a road has them they are written as
//! closed outlines under `parking_areas`.

use crate::geom::{Polygon, point_in_polygon};
use crate::road::Map;
use glam::DVec2;
use serde::{Deserialize, Serialize};
use std::io::{self, Write};
use std::path::Path;

/// One polyline: `[x, y]` points in metres, world frame.
pub type Points = Vec<[f64; 2]>;

/// `scene.json`, as written and as read back.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneMap {
    pub scenario: String,
    /// Always `world`: x east, y north, metres.
    pub frame: String,
    pub lane_centrelines: Vec<Points>,
    pub lane_dividers: Vec<Points>,
    pub road_boundaries: Vec<Points>,
    pub crosswalks: Vec<Points>,
    pub stop_lines: Vec<Points>,
    /// The junction's signals: the cycle and each approach lane's head (`signals on`); each
    /// frame's lights are in `boxes.json`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signals: Option<crate::road::signals::SignalPlan>,
    /// Parking lanes and driveways (`parking`, `driveway`), closed outlines; absent without.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub parking_areas: Vec<Points>,
}

fn pts(line: &[DVec2]) -> Points {
    line.iter().map(|p| [p.x, p.y]).collect()
}

impl SceneMap {
    pub fn of(scenario: &str, map: &Map) -> SceneMap {
        let centres = map.lanes.iter().map(|l| &l.centre).chain(map.connectors.iter().map(|c| &c.path));
        let closed = |p: &Polygon| -> Points {
            let mut v = pts(p);
            if let Some(&first) = v.first() {
                v.push(first);
            }
            v
        };
        SceneMap {
            scenario: scenario.to_string(),
            frame: "world".to_string(),
            lane_centrelines: centres.map(|c| pts(&c.points)).collect(),
            lane_dividers: map.dividers.iter().map(|d| pts(d)).collect(),
            road_boundaries: road_boundaries(map),
            crosswalks: map.crosswalk_polygons.iter().map(closed).collect(),
            stop_lines: map.stop_lines.iter().map(|s| pts(&[s.a, s.b])).collect(),
            signals: map.signals.clone(),
            parking_areas: map.carparks.iter().map(closed).collect(),
        }
    }
}

/// How far either side of an edge the union is probed, m: well under any lane width, well over
/// rounding.
const PROBE_M: f64 = 0.05;

/// The outline of the union of road blocks and junctions: every polygon edge with road on one
/// side only, consecutive edges of one polygon chained into one polyline.
fn road_boundaries(map: &Map) -> Vec<Points> {
    let polys: Vec<&Polygon> = map.road_segments.iter().chain(&map.intersections).collect();
    let inside = |p: DVec2| polys.iter().any(|q| point_in_polygon(p, q));
    let mut out = Vec::new();
    for poly in &polys {
        let n = poly.len();
        if n < 3 || !poly.iter().all(|p| p.is_finite()) {
            continue;
        }
        let outer = |i: usize| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            let d = b - a;
            if d.length() < 1e-9 {
                return false;
            }
            let (mid, nrm) = ((a + b) * 0.5, d.perp().normalize() * PROBE_M);
            inside(mid + nrm) != inside(mid - nrm)
        };
        let edges: Vec<bool> = (0..n).map(outer).collect();
        // Start each chain just after an inner edge so a closed run is not split at index 0.
        let start = edges.iter().position(|e| !e).map_or(0, |i| i + 1);
        let mut cur: Vec<DVec2> = Vec::new();
        for k in 0..n {
            let i = (start + k) % n;
            if edges[i] {
                if cur.is_empty() {
                    cur.push(poly[i]);
                }
                cur.push(poly[(i + 1) % n]);
            } else if !cur.is_empty() {
                out.push(pts(&std::mem::take(&mut cur)));
            }
        }
        if !cur.is_empty() {
            out.push(pts(&cur));
        }
    }
    out
}

/// Write `dir/scene.json`, compact: pretty-printed, every coordinate would take a line.
pub fn write_scene_json(dir: &Path, scene: &SceneMap) -> io::Result<super::OutputFile> {
    let bytes = crate::fsio::write_atomic(&dir.join("scene.json"), |w| {
        serde_json::to_writer(&mut *w, scene).map_err(io::Error::other)?;
        w.write_all(b"\n")
    })?;
    Ok(super::OutputFile { path: "scene.json".to_string(), bytes })
}

/// Read `scene.json` back.
pub fn read_scene_json(path: &Path) -> Result<SceneMap, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("`{}`: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_touching_squares_have_one_outline_without_the_shared_edge() {
        let sq = |x0: f64| {
            vec![DVec2::new(x0, 0.0), DVec2::new(x0 + 1.0, 0.0), DVec2::new(x0 + 1.0, 1.0), DVec2::new(x0, 1.0)]
        };
        let map = Map { road_segments: vec![sq(0.0)], intersections: vec![sq(1.0)], ..Map::default() };
        let b = road_boundaries(&map);
        // Each square keeps its three outer edges as one chain; the shared edge x = 1 is dropped.
        assert_eq!(b.len(), 2);
        assert!(b.iter().all(|l| l.len() == 4));
        let on_shared = |l: &Points| l.windows(2).any(|w| w[0][0] == 1.0 && w[1][0] == 1.0);
        assert!(!b.iter().any(on_shared));
    }
}
