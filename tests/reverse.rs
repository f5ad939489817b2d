//! Reversing, parking lanes and driveways (tests/fixtures/reverse/, scenarios/rare/
//! reversing_from_driveway.scn): a reversing vehicle moves rear first on its tracks, stops short
//! of what is behind it, and others brake for it; parked cars stand in their slots; the parking
//! areas reach `scene.json`; the files are canonically formatted.

#[path = "support/contact.rs"]
mod contact;
#[path = "support/front.rs"]
mod front;

use contact::{no_overlap, obb};
use glam::DVec2;
use rocc::compile::Front;
use rocc::output::SceneMap;
use rocc::rollout::Tracks;
use std::path::PathBuf;

fn path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/reverse").join(format!("{name}.scn"))
}

fn load(name: &str) -> Front {
    front::front_of(&std::fs::read_to_string(path(name)).expect("fixture"))
}

fn idx(t: &Tracks, name: &str) -> usize {
    t.agents.iter().position(|a| a.name == name).unwrap_or_else(|| panic!("no agent {name}"))
}

/// Frames in which agent `i` moves, each checked to move against its heading with a speed below
/// zero and no faster than the reverse limit.
fn reversing_frames(t: &Tracks, i: usize) -> usize {
    let mut n = 0;
    for f in 1..t.frames {
        let (p, q) = (t.poses[i][f - 1], t.poses[i][f]);
        let d = DVec2::new(q.x - p.x, q.y - p.y);
        assert!(t.speeds[i][f] <= 0.0 && t.speeds[i][f] >= -3.0 - 1e-9, "frame {f}: speed {}", t.speeds[i][f]);
        if d.length() * t.rate > 0.2 {
            n += 1;
            let along = d.normalize().dot(DVec2::from_angle(q.yaw));
            assert!(along < -0.95, "frame {f}: velocity at {along:.2} to the heading");
        }
    }
    n
}

#[test]
fn a_car_backing_up_stops_short_of_the_car_parked_behind_it() {
    let f = load("car-backs-toward-a-parked-car");
    let t = &f.tracks;
    let (car, parked) = (idx(t, "car"), idx(t, "parked"));
    assert!(reversing_frames(t, car) >= 20);
    let end = t.frames - 1;
    let (p0, p1) = (t.poses[car][0], t.poses[car][end]);
    assert!(p0.x - p1.x > 4.0 && p0.x - p1.x < 10.0, "it backed {:.2} m", p0.x - p1.x);
    assert!(t.poses[car].iter().all(|p| p.yaw == 0.0 && p.y == p0.y), "it left its line");
    let gap = (p1.x - t.agents[car].size[0] / 2.0) - (t.poses[parked][end].x + t.agents[parked].size[0] / 2.0);
    assert!(gap > 1.0 && gap < 3.0, "it stopped {gap:.2} m short");
    assert_eq!(t.speeds[car][end], 0.0);
    no_overlap(t);
}

#[test]
fn a_follower_brakes_for_a_car_backing_up_toward_it() {
    let f = load("car-backs-up-as-a-follower-comes");
    let t = &f.tracks;
    let (car, follower) = (idx(t, "car"), idx(t, "follower"));
    assert!(reversing_frames(t, car) >= 20);
    let end = t.frames - 1;
    let backed = t.poses[car][0].x - t.poses[car][end].x;
    assert!((backed - 8.0).abs() < 0.3, "it backed {backed:.2} m of 8");
    assert!(t.speeds[car].iter().all(|v| *v >= -2.0 - 1e-9), "over its goal speed");
    let slowest = t.speeds[follower].iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(t.speeds[follower][0] > 8.0 && slowest < 0.5, "the follower did not brake: {slowest:.2} m/s");
    assert!(t.poses[follower][end].x < t.poses[car][end].x - 4.0);
    no_overlap(t);
}

#[test]
fn a_car_backs_out_of_its_parking_slot_into_the_lane_between_parked_cars() {
    let f = load("parked-street-with-a-crosswalk");
    let t = &f.tracks;
    // Parked cars stand in their slots, along the lanes beside them (east.in's face west).
    for (name, x, y, yaw) in
        [("p1", 6.0, -4.75, 0.0), ("p2", 24.0, 4.75, std::f64::consts::PI), ("p3", -12.0, -5.0, 0.0)]
    {
        let p = t.poses[idx(t, name)][0];
        assert!((p.x - x).abs() < 1e-9 && (p.y - y).abs() < 1e-9, "{name} at ({:.2}, {:.2})", p.x, p.y);
        assert!((rocc::geom::wrap_angle(p.yaw - yaw)).abs() < 1e-9, "{name} faces {:.1} deg", p.yaw.to_degrees());
    }
    let (car, ego) = (idx(t, "leaving"), idx(t, "ego"));
    assert!(reversing_frames(t, car) >= 30);
    let end = t.frames - 1;
    let last = t.poses[car][end];
    assert!(last.yaw.abs() < 5f64.to_radians(), "it ends at {:.1} deg", last.yaw.to_degrees());
    for c in obb(t, car, end).corners() {
        assert!(c.y > -3.5 - 0.1 && c.y < 0.0, "a corner at y = {:.2} is off east.out[1]", c.y);
    }
    let slowest = t.speeds[ego].iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(slowest < 1.0, "the ego did not slow for it: {slowest:.2} m/s");
    no_overlap(t);
}

#[test]
fn parking_areas_reach_scene_json_only_where_the_road_has_them() {
    let parked = load("parked-street-with-a-crosswalk");
    let s = SceneMap::of("parked", &parked.map);
    assert_eq!(s.parking_areas.len(), 4, "three parking lanes and a driveway");
    assert!(s.parking_areas.iter().all(|a| a.len() >= 4 && a.first() == a.last()), "closed outlines");
    let plain = load("car-backs-toward-a-parked-car");
    let json = serde_json::to_string(&SceneMap::of("plain", &plain.map)).expect("json");
    assert!(!json.contains("parking_areas"), "a road without parking writes none");
}

#[test]
fn reverse_and_kerbside_files_are_canonically_formatted() {
    let mut files: Vec<PathBuf> =
        ["car-backs-toward-a-parked-car", "car-backs-up-as-a-follower-comes", "parked-street-with-a-crosswalk"]
            .into_iter()
            .map(path)
            .collect();
    files.push(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios/rare/reversing_from_driveway.scn"));
    for p in files {
        let text = std::fs::read_to_string(&p).expect("read");
        assert_eq!(rocc::syntax::format_source(&text).expect("formats"), text, "run `rocc fmt {}`", p.display());
    }
}

/// Occupancy grounds parking areas like the road: the procedural background (trees, buildings,
/// poles) never stands on a parking lane or a driveway, whatever the seed.
#[test]
fn no_background_stands_on_a_parking_lane_or_a_driveway() {
    let f = load("parked-street-with-a-crosswalk");
    let mut seen = 0;
    for seed in 0..8 {
        let bg = rocc::backend::Background::generate(&f.map, seed);
        seen += bg.items.len();
        for it in &bg.items {
            let o = rocc::geom::Obb { center: DVec2::new(it.x, it.y), yaw: it.yaw, length: it.l, width: it.w };
            for poly in &f.map.carparks {
                for c in o.corners().into_iter().chain([o.center]) {
                    assert!(!rocc::geom::point_in_polygon(c, poly), "seed {seed}: {:?} on a parking area", it.kind);
                }
            }
        }
    }
    assert!(seen > 0, "no background at all");
}
