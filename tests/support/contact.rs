//! Where two boxes touch, measured on the rolled-out boxes themselves, shared by the tests that
//! check staged crashes (`tests/rollout_conflicts.rs`: every impact type and point;
//! `tests/ciren.rs`: the imported cases against their sources). Deliberately independent of
//! `src/rollout/stage.rs`: sampling the boxes, not the stager's own geometry, so a stager bug
//! cannot hide itself.
#![allow(dead_code)] // each test crate uses part of it

use glam::DVec2;
use rocc::check::scenario::Point;
use rocc::geom::Obb;
use rocc::rollout::Tracks;

/// Agent `a`'s box at frame `f`.
pub fn obb(t: &Tracks, a: usize, f: usize) -> Obb {
    let p = t.poses[a][f];
    Obb { center: DVec2::new(p.x, p.y), yaw: p.yaw, length: t.agents[a].size[0], width: t.agents[a].size[1] }
}

/// No two declared boxes overlap in any frame.
pub fn no_overlap(t: &Tracks) {
    for f in 0..t.frames {
        for a in 0..t.agents.len() {
            for b in a + 1..t.agents.len() {
                assert!(
                    !obb(t, a, f).overlaps(&obb(t, b, f)),
                    "{} and {} overlap at frame {f}",
                    t.agents[a].name,
                    t.agents[b].name
                );
            }
        }
    }
}

/// The contact, measured by sampling: the mean of at-fault box points inside the struck box, in
/// the struck frame and in the at-fault frame, on a grid fine enough that a bus's step (4 cm)
/// keeps the centroid of a thin sliver within the 0.1 m that tests allow. A sliver thinner
/// than that is sampled again, four times finer; `None` if the boxes do not overlap.
pub fn measured_contact(t: &Tracks, af: usize, st: usize, f: usize) -> Option<(DVec2, DVec2)> {
    let (a, b) = (obb(t, af, f), obb(t, st, f));
    for (nl, nw) in [(320, 160), (1280, 640)] {
        let (mut sum, mut n) = (DVec2::ZERO, 0);
        for i in 0..=nl {
            for j in 0..=nw {
                let q = DVec2::new((i as f64 / nl as f64 - 0.5) * a.length, (j as f64 / nw as f64 - 0.5) * a.width);
                let w = a.center + q.rotate(DVec2::from_angle(a.yaw));
                let l = (w - b.center).rotate(DVec2::from_angle(-b.yaw));
                if l.x.abs() < b.length / 2.0 && l.y.abs() < b.width / 2.0 {
                    sum += w;
                    n += 1;
                }
            }
        }
        if n > 0 {
            let w = sum / n as f64;
            return Some((
                (w - b.center).rotate(DVec2::from_angle(-b.yaw)),
                (w - a.center).rotate(DVec2::from_angle(-a.yaw)),
            ));
        }
    }
    None
}

/// Thirds of each face, as in the language reference: outer thirds are corners.
pub fn sector(p: DVec2, l: f64, w: f64) -> Point {
    let (u, v) = (p.x / (l / 2.0), p.y / (w / 2.0));
    let third = |x: f64| {
        if x > 1.0 / 3.0 {
            1
        } else if x < -1.0 / 3.0 {
            -1
        } else {
            0
        }
    };
    match (third(u), third(v)) {
        (1, 1) => Point::FrontLeft,
        (1, -1) => Point::FrontRight,
        (-1, 1) => Point::RearLeft,
        (-1, -1) => Point::RearRight,
        (1, _) => Point::Front,
        (-1, _) => Point::Rear,
        (_, 1) => Point::Left,
        _ => Point::Right,
    }
}
