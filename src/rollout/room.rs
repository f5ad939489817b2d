//! Set-up of what avoidance and emergency yielding read of the road: the paving round something
//! that stands in a lane (`Room`), and whether a vehicle's lane is the only one of its direction.

use crate::check::scenario::Side;
use crate::road::Map;
use crate::road::route::side_lane;
use glam::DVec2;

/// The paving across the lane something stands in, measured at its place: the lane's direction,
/// its centre's offset from the lane's centre line (left positive), and how far the paving
/// reaches left and right of that centre line (every lane beside it, either direction, and the
/// outer shoulders), m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Room {
    pub dir: DVec2,
    pub off: f64,
    pub left: f64,
    pub right: f64,
}

/// The lane that holds `p` (within its half width, or its shoulder on the right), nearest
/// centre line first, as (lane, arc length, offset).
fn lane_at(map: &Map, p: DVec2, skip: &[usize]) -> Option<(usize, f64, f64)> {
    let mut best: Option<(usize, f64, f64)> = None;
    for (k, l) in map.lanes.iter().enumerate() {
        if l.centre.points.len() < 2 || skip.contains(&k) {
            continue;
        }
        let (s, d) = l.centre.project(p);
        if s < 0.0 || s > l.centre.length() {
            continue;
        }
        let reach = l.width / 2.0 + if d < 0.0 { l.shoulder_right } else { 0.0 };
        if d.abs() <= reach && best.is_none_or(|b| d.abs() < b.2.abs()) {
            best = Some((k, s, d));
        }
    }
    best
}

/// The `Room` round `p`; `None` off the lanes (in a junction, on a sidewalk).
pub(crate) fn room_at(map: &Map, p: DVec2) -> Option<Room> {
    let (l, s, off) = lane_at(map, p, &[])?;
    let lane = &map.lanes[l];
    let (c, h) = lane.centre.pose_at(s);
    let dir = DVec2::from_angle(h);
    let n = dir.perp();
    // Lane by lane outward on each side, as long as the next lane's band holds the point just
    // past the edge (no median between them).
    let walk = |sign: f64| {
        let (mut edge, mut last, mut seen) = (lane.width / 2.0, l, [l; 8]);
        for k in 1..8 {
            let q = c + n * sign * (edge + 0.3);
            let Some((m, _, dm)) = lane_at(map, q, &seen[..k]) else { break };
            let next = &map.lanes[m];
            if dm.abs() > next.width / 2.0 {
                break;
            }
            edge += next.width;
            last = m;
            seen[k] = m;
        }
        // The shoulder at the far edge: the last lane's right-hand one, where that side faces out.
        let far = &map.lanes[last];
        let same = far.centre.pose_at(far.centre.project(c).0).1;
        let agrees = DVec2::from_angle(same).dot(dir) > 0.0;
        if (sign < 0.0) == agrees { edge + far.shoulder_right } else { edge }
    };
    Some(Room { dir, off, left: walk(1.0), right: walk(-1.0) })
}

/// Whether lane `l` is the only lane of its direction (a two-lane road): oncoming traffic there
/// pulls over for an emergency vehicle too.
pub(crate) fn single_lane(map: &Map, l: usize) -> bool {
    side_lane(map, l, Side::Left).is_none() && side_lane(map, l, Side::Right).is_none()
}
