//! The rare-scene library `scenarios/rare/`: it passes `rocc test` (its `expect` blocks and
//! committed snapshots), and each scene does what its first comment says, measured on the
//! rolled-out boxes.

#[path = "support/contact.rs"]
mod contact;
#[path = "support/front.rs"]
mod front;

use contact::{no_overlap, obb};
use rocc::rollout::Tracks;
use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tracks(name: &str) -> Tracks {
    let text = std::fs::read_to_string(root().join(format!("scenarios/rare/{name}.scn"))).expect("rare scene");
    front::front_of(&text).tracks
}

fn idx(t: &Tracks, name: &str) -> usize {
    t.agents.iter().position(|a| a.name == name).unwrap_or_else(|| panic!("no agent {name}"))
}

fn dist(t: &Tracks, a: usize, b: usize, f: usize) -> f64 {
    let (p, q) = (t.poses[a][f], t.poses[b][f]);
    (p.x - q.x).hypot(p.y - q.y)
}

fn slowest(t: &Tracks, i: usize) -> f64 {
    t.speeds[i].iter().cloned().fold(f64::INFINITY, f64::min)
}

/// Frames where `who`'s box reaches into `car`'s lane (`lane_width` wide, centred on the car's
/// line, the car driving east) ahead of the car, with the car less than `within` away.
fn in_lane_ahead(t: &Tracks, who: usize, car: usize, lane_width: f64, within: f64) -> usize {
    let reach = t.agents[who].size[0].max(t.agents[who].size[1]) / 2.0;
    (0..t.frames)
        .filter(|&f| {
            let (w, c) = (t.poses[who][f], t.poses[car][f]);
            (w.y - c.y).abs() < lane_width / 2.0 + reach && w.x > c.x && dist(t, who, car, f) < within
        })
        .count()
}

#[test]
fn the_rare_library_passes_rocc_test_and_checks() {
    let dir = root().join("scenarios/rare");
    let o =
        Command::new(env!("CARGO_BIN_EXE_rocc")).args(["test", dir.to_str().expect("utf-8")]).output().expect("run");
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out}{}", String::from_utf8_lossy(&o.stderr));
    let n = std::fs::read_dir(&dir)
        .expect("scenarios/rare")
        .filter(|e| e.as_ref().is_ok_and(|e| e.path().extension().is_some_and(|x| x == "scn")))
        .count();
    assert!(n >= 5, "{n} rare scenes");
    assert!(out.contains(&format!("{n} of {n} scenario(s) passed")), "{out}");
    for line in out.lines().filter(|l| l.starts_with("ok ")) {
        assert!(!line.contains(": 0 of 0 expectation"), "a rare scene without expectations: {line}");
    }
}

#[test]
fn a_child_darts_out_between_parked_cars_into_the_egos_lane_near_it() {
    let t = tracks("child_between_parked_cars");
    let (kid, ego) = (idx(&t, "kid"), idx(&t, "ego"));
    let near = in_lane_ahead(&t, kid, ego, 3.5, 20.0);
    assert!(near >= 10, "the child is in the ego's lane with the ego under 20 m away for {near} frames");
    // It steps out through the gap between the parked cars, not round their ends.
    let (rear, front) = (t.poses[idx(&t, "parked_rear")][0].x, t.poses[idx(&t, "parked_front")][0].x);
    assert!(t.poses[kid].iter().all(|p| p.x > rear + 2.4 && p.x < front - 2.4), "the child left the gap");
    // The ego brakes hard for it, misses it, and drives on once it is across.
    assert!(slowest(&t, ego) < 4.0, "the ego did not brake: {:.2} m/s", slowest(&t, ego));
    assert!(t.speeds[ego][t.frames - 1] > 3.0, "the ego did not drive on");
    no_overlap(&t);
}

#[test]
fn a_deer_leaps_across_the_rural_road_in_front_of_the_ego() {
    let t = tracks("deer_leaps_onto_rural_road");
    let (deer, ego) = (idx(&t, "deer"), idx(&t, "ego"));
    assert!(in_lane_ahead(&t, deer, ego, 3.3, 40.0) >= 3, "the deer never crossed the ego's lane near it");
    // A leap: faster than a person runs, from one verge to the other.
    let top = t.speeds[deer].iter().cloned().fold(0.0, f64::max);
    assert!(top > 8.0, "the deer's top speed is {top:.2} m/s");
    // An animal bounds off: 8 m/s about a second after it sets off, not a walker's five.
    let off = t.speeds[deer].iter().position(|&v| v > 0.05).expect("the deer never moves");
    let fast = t.speeds[deer].iter().position(|&v| v >= 8.0).expect("never 8 m/s");
    assert!(fast - off <= 13, "8 m/s after {:.1} s", (fast - off) as f64 / 10.0);
    // It leaps across in front of the ego: it never stops on the road or at its edge.
    let mut on_road = (off..t.frames).filter(|&f| t.poses[deer][f].y.abs() < 5.0);
    assert!(on_road.all(|f| t.speeds[deer][f] > 4.0), "the deer slowed on the road");
    let (y0, y1) = (t.poses[deer][0].y, t.poses[deer][t.frames - 1].y);
    assert!(y0 < -5.0 && y1 > 4.0, "the deer went from y = {y0:.2} to {y1:.2}");
    assert!(slowest(&t, ego) < 15.0, "the ego did not brake: {:.2} m/s", slowest(&t, ego));
    no_overlap(&t);
}

#[test]
fn traffic_passes_an_active_crash_scene_without_stopping() {
    let t = tracks("post_crash_scene");
    // The injured person lies on the outer eastbound lane (-7 < y < -3.5): about 0.3 m tall.
    let injured = idx(&t, "injured");
    let p = t.poses[injured][0];
    assert!(t.agents[injured].size[2] <= 0.31 && t.agents[injured].size[0] > 1.5, "{:?}", t.agents[injured].size);
    assert!(p.y < -3.5 && p.y > -7.0, "the injured person is not on the lane: y = {:.2}", p.y);
    // Two wrecks at odd angles to the road.
    for w in ["wreck_a", "wreck_b"] {
        let yaw = t.poses[idx(&t, w)][0].yaw.to_degrees().rem_euclid(90.0);
        assert!(yaw > 15.0 && yaw < 75.0, "{w} lies at {yaw:.1} deg off the road's axes");
    }
    // The ambulance and the police car stand; the cones run across from the kerb side to the
    // lane line (a taper).
    for s in ["amb", "police"] {
        assert!(t.speeds[idx(&t, s)].iter().all(|v| *v == 0.0), "{s} moves");
    }
    let cones: Vec<f64> =
        t.agents.iter().enumerate().filter(|(_, a)| a.kind == "traffic_cone").map(|(i, _)| t.poses[i][0].y).collect();
    assert!(cones.len() >= 5 && cones.windows(2).all(|w| w[1] > w[0]), "not a taper: {cones:?}");
    // Traffic passes in the other lanes without stopping.
    for car in ["ego", "follower", "westbound", "westbound_outer"] {
        assert!(slowest(&t, idx(&t, car)) > 11.0, "{car} slowed to {:.2} m/s", slowest(&t, idx(&t, car)));
    }
    let ego = idx(&t, "ego");
    assert!(t.poses[ego][t.frames - 1].x > t.poses[idx(&t, "wreck_b")][0].x + 10.0, "the ego did not get past");
    no_overlap(&t);
}

#[test]
fn a_wrong_way_driver_drives_against_the_lane_of_a_divided_road() {
    let t = tracks("wrong_way_divided_road");
    let (ww, blocked, ego) = (idx(&t, "wrong_way"), idx(&t, "blocked"), idx(&t, "ego"));
    // It is in the eastbound carriageway (south of the median) driving west.
    assert!(t.poses[ww].iter().all(|p| p.y < -2.0), "the wrong-way driver left the eastbound lanes");
    assert!(t.poses[ww][20].x < t.poses[ww][0].x - 30.0, "the wrong-way driver does not drive west");
    assert!((t.poses[ww][0].y - t.poses[blocked][0].y).abs() < 0.01, "not in the SUV's lane");
    // The SUV in its lane stops short of it; the ego in the other lane keeps its speed.
    assert!(t.speeds[blocked][t.frames - 1] < 0.1 && t.speeds[ww][t.frames - 1] < 0.1);
    assert!(slowest(&t, ego) > 22.0, "the ego slowed to {:.2} m/s", slowest(&t, ego));
    no_overlap(&t);
}

#[test]
fn a_wheelchair_user_crosses_mid_block_and_the_ego_waits_for_it() {
    let t = tracks("wheelchair_midblock");
    let (chair, ego) = (idx(&t, "chair"), idx(&t, "ego"));
    let (y0, y1) = (t.poses[chair][0].y, t.poses[chair][t.frames - 1].y);
    assert!(y0 < -3.5 && y1 > 3.5, "the chair went from y = {y0:.2} to {y1:.2}");
    // The ego is slowest while the chair is in its lane, and passes it only once it has left.
    let f = (0..t.frames).min_by(|&a, &b| t.speeds[ego][a].total_cmp(&t.speeds[ego][b])).expect("frames");
    assert!(t.poses[chair][f].y > -3.5 - 0.6 && t.poses[chair][f].y < 0.6, "slowest at frame {f}");
    let chair_x = t.poses[chair][0].x;
    for f in 0..t.frames {
        if t.poses[ego][f].x + t.agents[ego].size[0] / 2.0 > chair_x - 0.4 {
            assert!(t.poses[chair][f].y > -0.6, "the ego passed the chair in its lane at frame {f}");
        }
    }
    no_overlap(&t);
}

#[test]
fn cross_traffic_drives_around_a_car_stalled_in_the_junction() {
    let t = tracks("stalled_in_junction");
    let (stalled, ego, east) = (idx(&t, "stalled"), idx(&t, "ego"), idx(&t, "eastbound"));
    let s = t.poses[stalled][0];
    assert!(t.poses[stalled].iter().all(|p| *p == s), "the stalled car moves");
    // The northbound ego goes by in the southbound half (x < 0), without stopping.
    for f in 0..t.frames {
        if (t.poses[ego][f].y - s.y).abs() < 4.0 {
            assert!(t.poses[ego][f].x < 0.0, "the ego is not in the free half beside the stalled car at frame {f}");
        }
    }
    assert!(t.poses[ego][t.frames - 1].y > s.y + 15.0, "the ego did not get past");
    // The eastbound car passes it too.
    assert!(t.poses[east][t.frames - 1].x > s.x + 5.0, "the eastbound car did not get past");
    for (who, floor) in [(ego, 6.9), (east, 4.0)] {
        assert!(slowest(&t, who) > floor, "{} slowed to {:.2} m/s", t.agents[who].name, slowest(&t, who));
    }
    no_overlap(&t);
}

#[test]
fn cars_ahead_and_oncoming_pull_over_for_a_fire_truck_from_behind() {
    let t = tracks("fire_truck_from_behind");
    let engine = idx(&t, "engine");
    // Each is over to its right and at rest when the truck goes by, and back in lane, moving,
    // at the end. Eastbound lane centre y = -1.75, westbound y = 1.75.
    for (name, lane_y, right) in [("ego", -1.75, -1.0), ("ahead", -1.75, -1.0), ("oncoming", 1.75, 1.0)] {
        let i = idx(&t, name);
        let meet = (1..t.frames)
            .find(|&f| {
                let (e0, e1, c) = (t.poses[engine][f - 1].x, t.poses[engine][f].x, t.poses[i][f].x);
                (e0 - c).signum() != (e1 - c).signum()
            })
            .unwrap_or_else(|| panic!("the truck never passes {name}"));
        let y = t.poses[i][meet].y;
        assert!((y - lane_y) * right > 1.5, "{name} is at y = {y:.2} as the truck passes (frame {meet})");
        assert!(t.speeds[i][meet] < 0.5, "{name} moves at {:.2} m/s as the truck passes", t.speeds[i][meet]);
        let end = t.frames - 1;
        assert!((t.poses[i][end].y - lane_y).abs() < 0.2 && t.speeds[i][end] > 3.0, "{name} did not go on");
    }
    assert!(slowest(&t, engine) > 12.5, "the truck slowed to {:.2} m/s", slowest(&t, engine));
    // Back in its lane, `ahead` drives on past the van steering back off the shoulder (its box
    // stays clear of the centre line): no braking for it between 11.6 and 13.4 s.
    let (ahead, van) = (idx(&t, "ahead"), idx(&t, "oncoming"));
    for f in 116..=134 {
        let v = &t.speeds[ahead];
        assert!(
            v[f] >= v[f - 1] - 0.3 * 0.1,
            "ahead brakes at {:.1} s: {:.2} -> {:.2} m/s",
            f as f64 / 10.0,
            v[f - 1],
            v[f]
        );
        let c = contact::obb(&t, van, f).corners();
        assert!(c.iter().all(|p| p.y > 0.0), "the van crosses the centre line at frame {f}");
    }
    no_overlap(&t);
}

#[test]
fn a_car_reverses_out_of_a_driveway_into_the_lane_and_the_van_stops_behind_it() {
    use glam::DVec2;
    let text = std::fs::read_to_string(root().join("scenarios/rare/reversing_from_driveway.scn")).expect("scene");
    let f = front::front_of(&text);
    let t = &f.tracks;
    let (car, van) = (idx(t, "car"), idx(t, "van"));
    // It starts in the driveway beyond the sidewalk, nosed in (facing south, away from the road).
    let p0 = t.poses[car][0];
    assert!(p0.y < -9.0 && (p0.yaw + std::f64::consts::FRAC_PI_2).abs() < 1e-6, "{p0:?}");
    // Backwards: wherever it moves its velocity points opposite its heading, its speed below zero.
    let mut moving = 0;
    for fr in 1..t.frames {
        let (p, q) = (t.poses[car][fr - 1], t.poses[car][fr]);
        let d = DVec2::new(q.x - p.x, q.y - p.y);
        if d.length() * t.rate > 0.5 {
            moving += 1;
            let along = d.normalize().dot(DVec2::from_angle(q.yaw));
            assert!(along < -0.95, "frame {fr}: velocity at {along:.2} to the heading");
            assert!(t.speeds[car][fr] < 0.0, "frame {fr}: speed {:.2}", t.speeds[car][fr]);
        }
    }
    assert!(moving >= 50, "it reversed for {moving} frames");
    assert!(t.speeds[car].iter().all(|v| *v >= -3.0 - 1e-9), "faster than the reverse limit");
    // It ends at rest in east.out[1] (-3.5 < y < 0), its whole box in the lane, facing east.
    let end = t.frames - 1;
    let last = t.poses[car][end];
    assert!(last.yaw.abs() < 4f64.to_radians(), "it ends at {:.1} deg", last.yaw.to_degrees());
    for c in obb(t, car, end).corners() {
        assert!(c.y > -3.5 - 0.05 && c.y < 0.0, "a corner at y = {:.2} is off the lane", c.y);
    }
    assert_eq!(t.speeds[car][end], 0.0);
    // The van holds 30 km/h until the car backs into its lane ahead, then slows and stops behind it.
    assert!(t.speeds[van][..60].iter().all(|v| *v > 8.2), "the van slowed early");
    assert!(slowest(t, van) < 0.05, "the van did not stop: {:.2} m/s", slowest(t, van));
    assert!(t.poses[van][end].x + 2.5 < last.x - 2.2, "the van is not behind the car");
    no_overlap(t);
    // BEV channel 3 (carpark_areas) holds the parking lane and the driveway; the driveway lies
    // over the walkway (channel 2) and is no drivable paving (channel 1); the parking lane is.
    let mut bev = rocc::raster::Bev::zeros();
    let ego = rocc::place::Pose { x: p0.x, y: p0.y, yaw: 0.0 };
    rocc::raster::Rasterizer::new().rasterize_into(&f.map, ego, &[], &mut bev);
    // The pixel `dx`, `dy` m from the car's start (ego frame = world axes here).
    let px = |ch: usize, dx: f64, dy: f64| bev.masks[[ch, (200.0 + 4.0 * dx) as usize, (200.0 + 4.0 * dy) as usize]];
    assert_eq!((px(3, 0.0, 0.0), px(1, 0.0, 0.0), px(2, 0.0, 0.0)), (1, 0, 0), "the car stands in the driveway");
    assert_eq!((px(3, 0.0, 5.0), px(2, 0.0, 5.0), px(1, 0.0, 5.0)), (1, 1, 0), "across the sidewalk");
    assert_eq!((px(3, -15.0, 7.8), px(1, -15.0, 7.8)), (1, 1), "the parking lane");
    assert_eq!((px(3, -15.0, 5.0), px(2, -15.0, 5.0)), (0, 1), "the sidewalk beyond the parking lane");
    assert_eq!((px(3, -15.0, 17.0), px(2, -15.0, 17.0)), (0, 1), "no parking along the north kerb");
}
