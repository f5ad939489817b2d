//! What the tracks show, measured on the boxes: contacts (overlapping footprints), the distance
//! between two boxes, and how far along its starting lane an agent's front is.

use crate::check::scenario::{Landmark, LaneId, Point};
use crate::compile::Front;
use crate::geom::Obb;
use crate::rollout::side_of;
use glam::DVec2;

/// The footprint of track `i` at frame `f`.
pub fn footprint(front: &Front, i: usize, f: usize) -> Obb {
    let p = front.tracks.poses[i][f];
    let s = front.tracks.agents[i].size;
    Obb { center: DVec2::new(p.x, p.y), yaw: p.yaw, length: s[0], width: s[1] }
}

/// Whether the boxes of `i` and `j` overlap at frame `f` (both present).
pub fn touching(front: &Front, i: usize, j: usize, f: usize) -> bool {
    if !front.present(i, f) || !front.present(j, f) {
        return false;
    }
    let (a, b) = (footprint(front, i, f), footprint(front, j, f));
    let reach = 0.5 * (a.length.hypot(a.width) + b.length.hypot(b.width));
    a.center.distance(b.center) < reach && a.overlaps(&b)
}

/// The side of `j`'s box that `i`'s box overlaps at frame `f` (the overlap's centroid, in
/// thirds of each face as `rollout::side_of` cuts them).
pub fn side_hit(front: &Front, i: usize, j: usize, f: usize) -> Point {
    let (a, b) = (footprint(front, i, f), footprint(front, j, f));
    let c = crate::rollout::contact_centroid(&a, &b).unwrap_or(a.center);
    let local = DVec2::from_angle(-b.yaw).rotate(c - b.center);
    side_of(local, b.length, b.width)
}

/// One run of frames in which two boxes overlap.
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    pub a: usize,
    pub b: usize,
    pub first: usize,
    pub last: usize,
    /// The side of each box hit at the first frame.
    pub side_a: Point,
    pub side_b: Point,
}

/// Every contact of the clip, ordered by first frame, then by track indices.
pub fn contacts(front: &Front) -> Vec<Contact> {
    let n = front.tracks.agents.len();
    let mut out = vec![];
    for a in 0..n {
        for b in a + 1..n {
            let mut run: Option<usize> = None;
            for f in 0..=front.tracks.frames {
                let on = f < front.tracks.frames && touching(front, a, b, f);
                match (on, run) {
                    (true, None) => run = Some(f),
                    (false, Some(first)) => {
                        let (side_a, side_b) = (side_hit(front, b, a, first), side_hit(front, a, b, first));
                        out.push(Contact { a, b, first, last: f - 1, side_a, side_b });
                        run = None;
                    }
                    _ => {}
                }
            }
        }
    }
    out.sort_by_key(|c| (c.first, c.a, c.b));
    out
}

/// Least distance between two boxes (0 when they overlap).
pub fn box_distance(a: &Obb, b: &Obb) -> f64 {
    if a.overlaps(b) {
        return 0.0;
    }
    let (ca, cb) = (a.corners(), b.corners());
    let mut best = f64::INFINITY;
    for (pts, edges) in [(&ca, &cb), (&cb, &ca)] {
        for p in pts {
            for e in 0..4 {
                best = best.min(point_segment(*p, edges[e], edges[(e + 1) % 4]));
            }
        }
    }
    best
}

fn point_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let t = if d.length_squared() > 0.0 { ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
    p.distance(a + d * t)
}

/// How far track `i`'s front is past `landmark` of `lane` at frame `f` (m; negative = short of
/// it), measured along that lane's centre line; `None` when the map has no such lane or landmark.
pub fn past_landmark(front: &Front, i: usize, f: usize, lane: LaneId, landmark: Landmark) -> Option<f64> {
    let l = front.map.lanes.iter().find(|l| l.id == lane)?;
    let at = match landmark {
        Landmark::Center => Some(l.center_s),
        Landmark::Junction => l.junction_s,
        Landmark::StopLine => l.stop_line_s,
    }?;
    let b = footprint(front, i, f);
    let nose = b.center + DVec2::from_angle(b.yaw) * (b.length / 2.0);
    // Past the lane's end (a straight road's in-lane ends at its centre) the projection stops
    // at the end; the line runs on along its last heading, so a nose beyond it is measured
    // along that (tests/library_test.rs, `stopped_before_center_sees_a_car_that_drove_past_it`).
    let len = l.centre.length();
    let s = match l.centre.project(nose).0 {
        s if s < len - 1e-9 => s,
        _ => {
            let (end, yaw) = l.centre.pose_at(len);
            len + (nose - end).dot(DVec2::from_angle(yaw)).max(0.0)
        }
    };
    Some(s - at)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obb(x: f64, y: f64, yaw: f64) -> Obb {
        Obb { center: DVec2::new(x, y), yaw, length: 4.0, width: 2.0 }
    }

    #[test]
    fn box_distance_is_the_gap_between_footprints() {
        // Nose to tail on one line: 10 m between centres, 4 m of box.
        assert!((box_distance(&obb(0.0, 0.0, 0.0), &obb(10.0, 0.0, 0.0)) - 6.0).abs() < 1e-12);
        // Side by side, 3 m between centres, 2 m wide.
        assert!((box_distance(&obb(0.0, 0.0, 0.0), &obb(0.0, 3.0, 0.0)) - 1.0).abs() < 1e-12);
        // A corner toward a face: the box turned 45 degrees reaches sqrt(5) from its centre.
        let d = box_distance(&obb(0.0, 0.0, 0.0), &obb(6.0, 0.0, std::f64::consts::FRAC_PI_4));
        assert!((d - (6.0 - 2.0 - 1.5 * std::f64::consts::SQRT_2)).abs() < 1e-9, "{d}");
        assert_eq!(box_distance(&obb(0.0, 0.0, 0.0), &obb(1.0, 0.5, 0.3)), 0.0);
    }
}
