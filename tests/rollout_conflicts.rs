//! Staged conflicts on hand-made maps: every impact type lands on the requested side and point at
//! the requested time, the pair parts within the impact's window and slides to rest, and
//! bystanders keep clear.

#[path = "support/contact.rs"]
mod contact;
#[path = "support/rollout_scenes.rs"]
mod rollout_scenes;

use contact::{measured_contact, obb, sector};
use glam::DVec2;
use rocc::check::scenario::*;
use rocc::place::Pose;
use rocc::road::Map;
use rocc::rollout::{Tracks, contact_centroid};
use rollout_scenes::*;
use std::f64::consts::FRAC_PI_2;

// ------------------------------------------------------------------ conflicts

fn conflict(at_fault: usize, struck: usize, impact: Impact, point: Point, at: Option<f64>) -> Conflict {
    Conflict { at_fault, struck, impact, point, at, after: Default::default(), span: Default::default() }
}

/// Run a staged conflict (agent 0 strikes agent 1) and check side, time, face, and that the pair
/// parts within the impact's window and slides to rest.
fn check_conflict(specs: Vec<Spec>, map: &Map, impact: Impact, point: Point, at: f64) -> Tracks {
    check_conflict_for(specs, map, impact, point, at, 12.0)
}

/// `check_conflict` over a clip of `secs`.
fn check_conflict_for(specs: Vec<Spec>, map: &Map, impact: Impact, point: Point, at: f64, secs: f64) -> Tracks {
    let t = run(specs, vec![conflict(0, 1, impact, point, Some(at))], map, secs);
    let rec = t.impacts.first().unwrap_or_else(|| panic!("{impact:?} {point:?}: no impact"));
    let f = rec.frame;
    let when = f as f64 / t.rate;
    assert!((when - at).abs() <= 1.0, "{impact:?} {point:?}: impact at {when} s, asked {at}");
    let (in_struck, in_af) = measured_contact(&t, 0, 1, f).expect("contact at the latched frame");
    let s = t.agents[1].size;
    assert_eq!(sector(in_struck, s[0], s[1]), point, "{impact:?}: contact {in_struck} on the struck box");
    assert_eq!(rec.struck_side, point);
    let a = t.agents[0].size;
    if impact == Impact::Sideswipe {
        assert!(in_af.y.abs() > 0.6 * a[1] / 2.0, "{impact:?} {point:?}: not the side: {in_af}");
    } else {
        assert!(in_af.x > 0.6 * a[0] / 2.0, "{impact:?} {point:?}: not the front: {in_af}");
    }
    // Only the pair overlaps, until the impact's window (0.5 s) closes; then each slides to
    // rest, no longer driven.
    assert!(overlaps(&t, &[(0, 1)]).is_empty(), "{:?}", overlaps(&t, &[(0, 1)]));
    let window = (0.5 * t.rate).round() as usize + 1;
    let in_window = |g: usize| t.contacts.iter().any(|c| c.frame <= g && g <= c.frame + window);
    assert!(
        (f..t.frames).all(|g| in_window(g) || !obb(&t, 0, g).overlaps(&obb(&t, 1, g))),
        "{impact:?}: the pair stays together {:?}",
        t.contacts
    );
    for k in [0, 1] {
        assert_eq!(t.poses[k][t.frames - 2], t.poses[k][t.frames - 1], "{impact:?}: {k} still moves");
    }
    // First contact comes at most half a second before the latched (deepest) frame, and is
    // already on the requested side.
    let first = (0..=f).find(|&g| obb(&t, 0, g).overlaps(&obb(&t, 1, g))).expect("contact");
    assert!(f - first <= 5, "{impact:?} {point:?}: first contact at {first}, latched at {f}");
    let q = contact_centroid(&obb(&t, 0, first), &obb(&t, 1, first)).expect("overlap");
    let b = obb(&t, 1, first);
    let local = (q - b.center).rotate(DVec2::from_angle(-b.yaw));
    assert_eq!(sector(local, s[0], s[1]), point, "{impact:?}: first contact {local}");
    t
}

#[test]
fn rear_end_hits_the_requested_rear_side_and_bystanders_keep_clear() {
    let m = straight(2);
    let l = id(Arm::West, Dir::In, 1);
    for point in [Point::Rear, Point::RearLeft, Point::RearRight] {
        let striker = car("striker", on(&m, l, 30.0, 0.0), 14.0, None);
        let victim = car("victim", on(&m, l, 80.0, 0.0), 6.0, None);
        let follower = car("follower", on(&m, l, 5.0, 0.0), 12.0, None);
        // 16 s: the follower, 25 m back at 12 m/s, sees the crash and slows while the wrecks
        // slide, then draws up to where they rest.
        let t = check_conflict_for(vec![striker, victim, follower], &m, Impact::RearEnd, point, 3.0, 16.0);
        // The wrecks slide where the impulse sends them; the follower stops behind them or
        // passes where they left room, touching neither.
        assert!(t.first_contact(2).is_none(), "{point:?}: the follower ran into the wreck: {:?}", t.contacts);
        let (last, w) = (t.frames - 1, 2.0);
        let (f, s) = (t.poses[2][last], t.poses[0][last]);
        if (s.y - f.y).abs() < w && s.x > f.x {
            assert!(front_gap(&t, 2, 0, last) > 1.0 && t.speeds[2][last] < 0.5, "{point:?}: not stopped behind");
        }
    }
}

#[test]
fn head_on_hits_the_front() {
    let m = straight(1);
    for point in [Point::Front, Point::FrontLeft, Point::FrontRight] {
        let victim = car("victim", on(&m, id(Arm::West, Dir::In, 1), 100.0, 0.0), 9.0, None);
        let striker = car("striker", on(&m, id(Arm::East, Dir::In, 1), 120.0, 0.0), 9.0, None);
        check_conflict(vec![striker, victim], &m, Impact::HeadOn, point, 3.0);
    }
}

#[test]
fn sideswipe_hits_the_requested_side() {
    let m = straight(2);
    for point in [Point::Right, Point::FrontRight, Point::RearRight] {
        // As in ciren_sideswipe.scn: the striker starts ahead and faster, in the right lane.
        let striker = car(
            "striker",
            on(&m, id(Arm::West, Dir::In, 2), 60.0, 0.0),
            22.0,
            Some(Goal { speed: Some(22.0), ..goal() }),
        );
        let victim = car(
            "victim",
            on(&m, id(Arm::West, Dir::In, 1), 55.0, 0.0),
            20.0,
            Some(Goal { speed: Some(20.0), ..goal() }),
        );
        check_conflict(vec![striker, victim], &m, Impact::Sideswipe, point, 3.0);
    }
    let striker =
        car("striker", on(&m, id(Arm::West, Dir::In, 1), 50.0, 0.0), 20.0, Some(Goal { speed: Some(20.0), ..goal() }));
    let victim =
        car("victim", on(&m, id(Arm::West, Dir::In, 2), 60.0, 0.0), 18.0, Some(Goal { speed: Some(18.0), ..goal() }));
    check_conflict(vec![striker, victim], &m, Impact::Sideswipe, Point::Left, 3.0);
}

#[test]
fn angle_crash_in_a_junction() {
    let m = four_way();
    let straight_on = Some(Goal { turn: Some(Turn::Straight), ..goal() });
    for (arm, point) in [(Arm::West, Point::Left), (Arm::West, Point::FrontLeft), (Arm::East, Point::Right)] {
        let victim = car("victim", on(&m, id(Arm::South, Dir::In, 1), 30.0, 0.0), 8.0, straight_on.clone());
        let striker = car("striker", on(&m, id(arm, Dir::In, 1), 28.0, 0.0), 8.0, straight_on.clone());
        check_conflict(vec![striker, victim], &m, Impact::Angle, point, 4.0);
    }
}

#[test]
fn single_vehicle_crash_into_an_object() {
    let m = straight(2);
    // Its left side is hit by a car swerving in from the lane to its left.
    for (point, lane) in [(Point::Rear, 2), (Point::RearLeft, 2), (Point::Left, 1)] {
        let striker = car("striker", on(&m, id(Arm::West, Dir::In, lane), 20.0, 0.0), 12.0, None);
        let mut barrier = car("barrier", on(&m, id(Arm::West, Dir::In, 2), 75.0, 0.0), 0.0, None);
        barrier.class = Class::Barrier;
        barrier.motion = Motion::Static;
        barrier.object = true;
        barrier.size = [2.0, 0.6, 1.0];
        check_conflict(vec![striker, barrier], &m, Impact::Object, point, 4.0);
    }
}

#[test]
fn default_impact_time_is_mid_clip() {
    let m = straight(2);
    let l = id(Arm::West, Dir::In, 1);
    let striker = car("striker", on(&m, l, 30.0, 0.0), 14.0, None);
    let victim = car("victim", on(&m, l, 80.0, 0.0), 6.0, None);
    let t = run(vec![striker, victim], vec![conflict(0, 1, Impact::RearEnd, Point::Rear, None)], &m, 8.0);
    let f = t.impacts.first().expect("impact").frame;
    assert!((f as f64 / 10.0 - 4.0).abs() <= 1.0, "frame {f}");
}

// ------------------------------------------------------------------ conflicts on every side

/// All eight `point` sides, each with an impact type that reaches it (rear sides by rear_end,
/// front ones by head_on, the sides by angle in a junction), measured on the boxes.
#[test]
fn every_point_side_is_hit() {
    for (name, point) in POINTS {
        let (lon, lat) = match point {
            Point::Front => (1, 0),
            Point::Rear => (-1, 0),
            Point::Left => (0, 1),
            Point::Right => (0, -1),
            Point::FrontLeft => (1, 1),
            Point::FrontRight => (1, -1),
            Point::RearLeft => (-1, 1),
            Point::RearRight => (-1, -1),
        };
        let t = match (lon, lat) {
            (-1, _) => {
                let m = straight(2);
                let l = id(Arm::West, Dir::In, 1);
                let striker = car("striker", on(&m, l, 30.0, 0.0), 14.0, None);
                let victim = car("victim", on(&m, l, 80.0, 0.0), 6.0, None);
                check_conflict(vec![striker, victim], &m, Impact::RearEnd, point, 3.0)
            }
            (1, _) => {
                let m = straight(1);
                let victim = car("victim", on(&m, id(Arm::West, Dir::In, 1), 100.0, 0.0), 9.0, None);
                let striker = car("striker", on(&m, id(Arm::East, Dir::In, 1), 120.0, 0.0), 9.0, None);
                check_conflict(vec![striker, victim], &m, Impact::HeadOn, point, 3.0)
            }
            _ => {
                let m = four_way();
                let straight_on = Some(Goal { turn: Some(Turn::Straight), ..goal() });
                let arm = if lat > 0 { Arm::West } else { Arm::East };
                let victim = car("victim", on(&m, id(Arm::South, Dir::In, 1), 30.0, 0.0), 8.0, straight_on.clone());
                let striker = car("striker", on(&m, id(arm, Dir::In, 1), 28.0, 0.0), 8.0, straight_on);
                check_conflict(vec![striker, victim], &m, Impact::Angle, point, 4.0)
            }
        };
        assert_eq!(t.impacts[0].struck_side, point, "{name}");
        check_kinematics(&t, &[30.0, 20.0], &[0]);
    }
}

/// A car strikes a walker crossing the road: contact on the walker's side that faces the car
/// (its left as it walks north and the car comes from the west; its right for a car from the
/// east), at the requested time; the car moves as a bicycle throughout.
#[test]
fn impact_on_a_crossing_pedestrian() {
    let m = straight(1);
    for (arm, s, point, at) in [(Arm::West, 154.0, Point::Left, 3.0), (Arm::East, 50.0, Point::Right, 5.0)] {
        let ped = Spec {
            name: "walker",
            class: Class::Pedestrian,
            motion: Motion::Holonomic,
            size: [0.6, 0.6, 1.7],
            pose: Pose { x: 40.0, y: -W - 1.5, yaw: FRAC_PI_2 },
            speed: 0.0,
            goal: Some(Goal { speed: Some(1.4), lateral: Lateral::Cross, ..goal() }),
            object: false,
            track: None,
        };
        let striker = car("striker", on(&m, id(arm, Dir::In, 1), s, 0.0), 12.0, None);
        let t = check_conflict(vec![striker, ped], &m, Impact::Pedestrian, point, at);
        check_kinematics(&t, &[20.0, 1.4], &[0]);
    }
}
