//! Lamps and doors on the outputs: each vehicle's `states` in `boxes.json` (headlights, brake
//! lights, hazards, beacons, siren, doors) and an open door's box in the frame's boxes that the
//! BEV, occupancy and LiDAR are made from (scenarios/rare/dooring.scn).

#[path = "support/front.rs"]
mod front;

use rocc::compile::{Front, frame_boxes, is_door};
use rocc::view::EgoBox;
use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn scene(path: &str) -> String {
    std::fs::read_to_string(root().join(path)).expect("scene")
}

fn idx(f: &Front, name: &str) -> usize {
    f.tracks.agents.iter().position(|a| a.name == name).unwrap_or_else(|| panic!("no agent {name}"))
}

/// The corners of a box's footprint.
fn corners(b: &EgoBox) -> [[f64; 2]; 4] {
    let (c, s) = (b.yaw.cos(), b.yaw.sin());
    let (hl, hw) = (b.l / 2.0, b.w / 2.0);
    [[hl, hw], [-hl, hw], [-hl, -hw], [hl, -hw]].map(|[x, y]| [b.x + c * x - s * y, b.y + s * x + c * y])
}

/// Whether two footprints overlap (separating axes).
fn overlap(a: &EgoBox, b: &EgoBox) -> bool {
    let (ca, cb) = (corners(a), corners(b));
    let right = std::f64::consts::FRAC_PI_2;
    for yaw in [a.yaw, a.yaw + right, b.yaw, b.yaw + right] {
        let ax = [yaw.cos(), yaw.sin()];
        let proj = |cs: &[[f64; 2]; 4]| {
            let d: Vec<f64> = cs.iter().map(|p| p[0] * ax[0] + p[1] * ax[1]).collect();
            (d.iter().cloned().fold(f64::INFINITY, f64::min), d.iter().cloned().fold(f64::NEG_INFINITY, f64::max))
        };
        let ((a0, a1), (b0, b1)) = (proj(&ca), proj(&cb));
        if a1 < b0 || b1 < a0 {
            return false;
        }
    }
    true
}

#[test]
fn the_parked_cars_door_swings_open_into_the_cyclists_path() {
    let f = front::front_of(&scene("scenarios/rare/dooring.scn"));
    let (ego, bike) = (idx(&f, "ego"), idx(&f, "bike"));
    let rate = f.tracks.rate;
    let doors_at = |fr: usize| -> Vec<EgoBox> { frame_boxes(&f, ego, fr).into_iter().filter(is_door).collect() };
    // Shut until the cyclist is within 4 m (centre to centre), then swinging open.
    let (p, b) = (idx(&f, "parked"), bike);
    let dist = |fr: usize| {
        let (a, c) = (f.tracks.poses[p][fr], f.tracks.poses[b][fr]);
        (a.x - c.x).hypot(a.y - c.y)
    };
    let first = (0..f.tracks.frames).find(|&fr| !doors_at(fr).is_empty()).expect("the door opens");
    assert!(dist(first) <= 4.0 && dist(first - 1) > 4.0, "starts to open as the cyclist comes within 4 m");
    let wide = first + rate as usize;
    let door = &doors_at(wide)[0];
    assert_eq!((door.agent.as_str(), door.track), ("parked", p as u32), "a box of the parked car");
    // Wide open: 70 degrees from the body, reaching about a metre beyond the car's side.
    let car = frame_boxes(&f, ego, wide).into_iter().find(|x| x.agent == "parked" && !is_door(x)).expect("car");
    let reach = door.y + 0.5 * door.l * (door.yaw - car.yaw).sin().abs() - (car.y + car.w / 2.0);
    assert!((0.8..1.2).contains(&reach), "the door reaches {reach:.2} m beyond the car's side");
    // Opened too late to ease round, the door meets the cyclist's box: dooring.
    assert!(door_meets_bike(&f, first..f.tracks.frames).is_some(), "the door stands in the cyclist's path");
}

/// The first frame in `frames` where an open door's box overlaps the bike's.
fn door_meets_bike(f: &Front, frames: std::ops::Range<usize>) -> Option<usize> {
    let ego = idx(f, "ego");
    frames.into_iter().find(|&fr| {
        let boxes = frame_boxes(f, ego, fr);
        let cyclist = boxes.iter().find(|x| x.agent == "bike").expect("bike in view");
        boxes.iter().filter(|x| is_door(x)).any(|d| overlap(d, cyclist))
    })
}

#[test]
fn a_cyclist_eases_aside_round_a_door_opened_in_time() {
    let f = front::front_of(&scene("tests/rollout-cases/cyclist-eases-aside-for-an-opening-door.scn"));
    let (bike, parked) = (idx(&f, "bike"), idx(&f, "parked"));
    assert!(f.tracks.bodies[parked].doors[0].1.contains(&70.0), "the door opens wide");
    assert_eq!(door_meets_bike(&f, 0..f.tracks.frames), None, "the cyclist keeps clear of the door");
    let y = |fr: usize| f.tracks.poses[bike][fr].y;
    let passing =
        (0..f.tracks.frames).find(|&fr| f.tracks.poses[bike][fr].x > f.tracks.poses[parked][fr].x).expect("passes");
    assert!(y(passing) - y(0) > 0.3, "eased aside by {:.2} m", y(passing) - y(0));
    assert!(f.tracks.speeds[bike].iter().all(|&v| v > 4.5), "and rides on without braking");
    // The same scene without the door: no easing aside.
    let shut = front::front_of(
        &scene("tests/rollout-cases/cyclist-eases-aside-for-an-opening-door.scn")
            .replace("door front_left open when bike within 8 m", ""),
    );
    assert!(shut.tracks.poses[bike].iter().all(|p| (p.y - y(0)).abs() < 0.05), "a shut door is no obstacle");
}

#[test]
fn an_open_door_changes_the_bev_and_the_occupancy() {
    use rocc::backend::{Background, OccInput, Occupancy, OccupancyBackend, Procedural};
    use rocc::raster::{Bev, Rasterizer};
    let text = scene("scenarios/rare/dooring.scn");
    let shut = text.replace("door front_left open when bike within 4 m", "");
    assert_ne!(shut, text);
    let render = |text: &str| {
        let f = front::front_of(text);
        let ego = f.concrete.egos[0];
        let fr = 40;
        let (pose, boxes) = (f.tracks.poses[ego][fr], frame_boxes(&f, ego, fr));
        let (mut bev, mut occ) = (Bev::zeros(), Occupancy::empty());
        Rasterizer::new().rasterize_into(&f.map, pose, &boxes, &mut bev);
        let bg = Background::generate(&f.map, f.concrete.seed);
        let input = OccInput { boxes: &boxes, bev: &bev, background: &bg, ego: pose, seed: 1, frame: fr };
        Procedural::default().occupancy_into(&input, &mut occ);
        let vehicle = |b: &Bev| b.masks.iter().filter(|&&x| x != 0).count();
        (vehicle(&bev), occ.labels.iter().copied().collect::<Vec<u8>>())
    };
    let ((bev_open, occ_open), (bev_shut, occ_shut)) = (render(&text), render(&shut));
    assert!(bev_open > bev_shut, "marked BEV pixels: {bev_open} open, {bev_shut} shut");
    assert!(occ_open != occ_shut, "the door's voxels");
}

/// `boxes.json` of `path` compiled to the BEV over `frames`.
fn boxes_json(path: &str, frames: &str) -> Vec<Value> {
    let out = std::env::temp_dir().join(format!("rocc-lamps-{}-{}", std::process::id(), path.replace('/', "_")));
    let st = Command::new(env!("CARGO_BIN_EXE_rocc"))
        .args(["compile", root().join(path).to_str().expect("utf-8"), "-o", out.to_str().expect("utf-8")])
        .args(["--stage", "bev", "--frames", frames, "--force"])
        .output()
        .expect("run rocc");
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    let dir = std::fs::read_dir(&out).expect("out").next().expect("scenario").expect("entry").path();
    let clip = std::fs::read_dir(&dir).expect("clip").next().expect("ego").expect("entry").path();
    let v: Value =
        serde_json::from_str(&std::fs::read_to_string(clip.join("boxes.json")).expect("boxes.json")).expect("json");
    std::fs::remove_dir_all(&out).expect("clean up");
    v.as_array().expect("frames").clone()
}

fn box_of<'a>(frame: &'a Value, agent: &str) -> &'a Value {
    frame["boxes"].as_array().expect("boxes").iter().find(|b| b["agent"] == agent).expect("box")
}

#[test]
fn boxes_json_writes_each_vehicles_lamps_and_door_angle_per_frame() {
    let frames = boxes_json("scenarios/rare/dooring.scn", "30..50");
    let angles: Vec<f64> =
        frames.iter().map(|f| box_of(f, "parked")["states"]["doors"]["front_left"].as_f64().unwrap_or(0.0)).collect();
    assert_eq!(angles.first(), Some(&0.0), "shut at first: {angles:?}");
    assert_eq!(angles.last(), Some(&70.0), "wide open at last: {angles:?}");
    assert!(angles.windows(2).all(|w| w[1] >= w[0] && w[1] - w[0] <= 7.0 + 1e-9), "swings 70 deg/s: {angles:?}");
    for f in &frames {
        // A door is an attribute of its car, never a box of its own.
        assert!(f["boxes"].as_array().expect("boxes").iter().all(|b| b["kind"] != "door"));
        let ego = &f["ego"]["states"];
        assert_eq!(ego["headlights"], true, "`lights on`");
        let parked = &box_of(f, "parked")["states"];
        // Parked on the shoulder, not on a travel lane: no hazards, no brake lights.
        assert_eq!(
            (&parked["hazards"], &parked["brake_lights"], &parked["headlights"]),
            (&false.into(), &false.into(), &false.into())
        );
        // A bicycle carries lamps (`states`), not hazards, beacons or a siren.
        let bike = &box_of(f, "bike")["states"];
        assert_eq!((&bike["hazards"], &bike["beacons"], &bike["siren"]), (&false.into(), &false.into(), &false.into()));
    }
}

#[test]
fn brake_lights_follow_the_deceleration_and_a_stop() {
    let text = "scenario s {\n    duration 6 s\n    road straight { lanes 1; length 300 m }\n    agent ego: sedan {\n        at west.in[1], 60 m before center\n        speed 40 km/h\n        goal { speed 40 km/h; stop after 60 m }\n    }\n}\n";
    let f = front::front_of(text);
    let body = &f.tracks.bodies[0];
    let v = &f.tracks.speeds[0];
    let dt = 1.0 / f.tracks.rate;
    for k in 1..v.len() - 1 {
        let a = (v[k + 1] - v[k - 1]) / (2.0 * dt);
        let want = a < -1.0 || v[k] < 0.1;
        assert_eq!(body.brake_lights[k], want, "frame {k}: speed {:.2}, accel {a:.2}", v[k]);
    }
    assert!(!body.brake_lights[0], "cruising at first");
    assert!(*body.brake_lights.last().expect("frames"), "stopped at the end");
    // Reversing: pulling away backwards is no braking; standing still before it is.
    let f = front::front_of(&scene("scenarios/rare/reversing_from_driveway.scn"));
    let car = idx(&f, "car");
    let (v, lit) = (&f.tracks.speeds[car], &f.tracks.bodies[car].brake_lights);
    let backing = (1..v.len() - 1).find(|&k| v[k + 1] < v[k] - 0.05 && v[k] < -0.2).expect("speeds up backwards");
    assert!(!lit[backing], "frame {backing}: speed {:.2}", v[backing]);
    assert!(lit[0], "standing in the driveway before it backs out");
}

#[test]
fn hazards_default_on_for_a_car_stalled_on_the_lanes_and_off_for_a_parked_one() {
    let stalled = front::front_of(&scene("scenarios/rare/stalled_in_junction.scn"));
    assert!(stalled.tracks.bodies[idx(&stalled, "stalled")].hazards, "stalled in the junction");
    assert!(!stalled.tracks.bodies[idx(&stalled, "ego")].hazards, "a driving car");
    let parked = front::front_of(&scene("scenarios/rare/child_between_parked_cars.scn"));
    assert!(!parked.tracks.bodies[idx(&parked, "parked_front")].hazards, "parked on the shoulder");
    let stated = scene("scenarios/rare/child_between_parked_cars.scn")
        .replace("offset 3 m right }", "offset 3 m right; hazards on }")
        .replacen("hazards on }", "}", 1);
    let f = front::front_of(&stated);
    assert!(f.tracks.bodies[idx(&f, "parked_rear")].hazards, "`hazards on` on the rear car");
    assert!(!f.tracks.bodies[idx(&f, "parked_front")].hazards);
}

#[test]
fn beacons_go_with_the_siren_unless_stated() {
    let text = scene("scenarios/rare/fire_truck_from_behind.scn");
    let f = front::front_of(&text);
    let engine = &f.tracks.bodies[idx(&f, "engine")];
    assert!(engine.siren && engine.beacons, "on by default");
    let quiet = front::front_of(&text.replacen("speed 60 km/h\n", "speed 60 km/h\n        siren off\n", 1));
    let e = &quiet.tracks.bodies[idx(&quiet, "engine")];
    assert!(!e.siren && !e.beacons, "`siren off` puts the beacons off too");
    let lit =
        front::front_of(&text.replacen("speed 60 km/h\n", "speed 60 km/h\n        siren off\n        beacons on\n", 1));
    let e = &lit.tracks.bodies[idx(&lit, "engine")];
    assert!(!e.siren && e.beacons, "`beacons on` with `siren off`: lights only");
}

#[test]
fn import_boxes_keeps_the_lamps_and_doors_it_is_given() {
    // A car standing with its hazards on whose driver's door opens at 0.5 s and starts to close
    // at 1.5 s; a walker whose (meaningless) states are not kept.
    let frames: Vec<Value> = (0..25)
        .map(|f| {
            let t = f as f64 * 0.1;
            let deg = if t < 0.45 { 0.0 } else if t < 1.45 { (70.0 * (t - 0.4)).min(70.0) } else { 70.0 - 70.0 * (t - 1.4) };
            let doors = if deg > 0.0 { serde_json::json!({"front_left": deg}) } else { serde_json::json!({}) };
            serde_json::json!({"frame": f, "time": t, "ego_pose": {"x": 0.0, "y": 0.0, "yaw": 0.0}, "boxes": [
                {"track": "car", "class": "vehicle.car", "center": [20.0, 3.0, 0.8], "size": [1.8, 4.6, 1.5], "yaw": 0.0,
                 "states": {"headlights": false, "hazards": true, "brake_lights": false, "doors": doors}},
                {"track": "kid", "class": "human.pedestrian.child", "center": [30.0, 6.0, 0.6], "size": [0.4, 0.4, 1.2], "yaw": 0.0,
                 "states": {"hazards": true}}
            ]})
        })
        .collect();
    let path = std::env::temp_dir().join(format!("rocc-import-states-{}.json", std::process::id()));
    std::fs::write(&path, serde_json::json!({"rate_hz": 10.0, "frames": frames}).to_string()).expect("write");
    let mut sources = rocc::source::SourceMap::default();
    let imp = rocc::import::import_boxes(&path, rocc::import::Convention::NuScenes, "kept", &mut sources)
        .unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| d.message.clone()).collect::<Vec<_>>()));
    std::fs::remove_file(&path).expect("clean up");
    for says in ["lights off", "hazards on", "door front_left open at 0.5 s", "door front_left close at 1.5 s"] {
        assert!(imp.text.contains(&format!("        {says}\n")), "{says}:\n{}", imp.text);
    }
    assert_eq!(imp.text.matches("hazards").count(), 1, "not on the walker:\n{}", imp.text);
    // Compiled again, the car's door swings as recorded, one frame behind at most.
    let f = front::front_of(&imp.text);
    let car = &imp.agents.iter().find(|a| a.1 == "car").expect("the car's agent").0;
    let body = &f.tracks.bodies[idx(&f, car)];
    assert!(body.hazards);
    let angle = &body.doors[0].1;
    assert_eq!((angle[4], angle[5], angle[14], angle[15]), (0.0, 7.0, 70.0, 63.0), "{angle:?}");
}
