//! What a map point stands on. In: a `Map` and a world point. Out: the set of surfaces there
//! (lane, shoulder, junction, crosswalk, sidewalk, other drivable paving) and the name of the most
//! specific one, for diagnostics.

use crate::geom::point_in_polygon;
use crate::road::Map;
use glam::DVec2;

/// Slack for points on a surface's edge (float noise of the map's own construction).
const EDGE: f64 = 1e-6;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Surfaces {
    pub lane: bool,
    pub shoulder: bool,
    pub junction: bool,
    pub crosswalk: bool,
    pub sidewalk: bool,
    /// Any drivable paving (lanes, shoulders, median, junction).
    pub drivable: bool,
    /// A parking area: a parking lane or a driveway (`road/parking.rs`).
    pub carpark: bool,
}

impl Surfaces {
    pub fn at(map: &Map, p: DVec2) -> Surfaces {
        let mut s = Surfaces::default();
        for l in &map.lanes {
            if l.centre.points.len() < 2 {
                continue;
            }
            let (at, d) = l.centre.project(p);
            // Past either end the projection clamps: require the point to be beside the lane.
            let (q, yaw) = l.centre.pose_at(at);
            if (p - q).dot(DVec2::from_angle(yaw)).abs() > 0.05 {
                continue;
            }
            let half = l.width / 2.0;
            if d.abs() <= half + EDGE {
                s.lane = true;
            } else if d < 0.0 && -d <= half + l.shoulder_right + EDGE {
                s.shoulder = true;
            }
        }
        let inside = |polys: &[Vec<DVec2>]| polys.iter().any(|poly| point_in_polygon(p, poly));
        s.junction = inside(&map.intersections);
        s.crosswalk = inside(&map.crosswalk_polygons);
        s.sidewalk = inside(&map.walkways);
        s.drivable = s.lane || s.shoulder || s.junction || inside(&map.drivable);
        s.carpark = inside(&map.carparks);
        s
    }

    /// Where the point is, most specific surface first: "on a crosswalk", "in the junction", ...
    pub fn describe(&self) -> &'static str {
        if self.crosswalk {
            "on a crosswalk"
        } else if self.junction {
            "in the junction"
        } else if self.lane {
            "on a lane"
        } else if self.shoulder {
            "on the shoulder"
        } else if self.carpark {
            "in a parking lane or driveway"
        } else if self.sidewalk {
            "on a sidewalk"
        } else if self.drivable {
            "on the median"
        } else {
            "off the road"
        }
    }
}
