//! Avoidance and emergency yielding on the road, tested on the boxes of the regression scenes in
//! `tests/rollout-cases/`: passing what stands in a lane, waiting for oncoming traffic, stopping
//! where there is no room, and pulling over for a fire truck's siren.

#[path = "support/contact.rs"]
mod contact;

use contact::obb;
use rocc::rollout::Tracks;

fn front_of(path: &str) -> rocc::compile::Front {
    let text = std::fs::read_to_string(path).expect("case");
    let mut sources = rocc::source::SourceMap::default();
    let s = rocc::check::check_text(path, &text, std::path::Path::new("."), &mut sources)
        .unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| d.message.clone()).collect::<Vec<_>>()));
    rocc::compile::front(s, None)
        .unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| d.message.clone()).collect::<Vec<_>>()))
}

fn idx(t: &Tracks, name: &str) -> usize {
    t.agents.iter().position(|a| a.name == name).expect("agent")
}

/// Frame by frame: position, heading and speed of agent `k`, for failure messages.
fn trace(t: &Tracks, k: usize) -> String {
    (0..t.frames)
        .step_by(5)
        .map(|f| {
            let p = t.poses[k][f];
            format!("{f}: ({:.2}, {:.2}) yaw {:.3} v {:.2}", p.x, p.y, p.yaw, t.speeds[k][f])
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn touches(t: &Tracks, a: usize, b: usize) -> Option<usize> {
    (0..t.frames).find(|&f| obb(t, a, f).overlaps(&obb(t, b, f)))
}

fn slowest(t: &Tracks, k: usize) -> f64 {
    t.speeds[k].iter().copied().fold(f64::INFINITY, f64::min)
}

#[test]
fn a_car_passes_a_wreck_blocking_half_its_lane_without_stopping() {
    let f = front_of("tests/rollout-cases/car-passes-a-wreck-blocking-half-its-lane.scn");
    let t = &f.tracks;
    let (car, wreck) = (idx(t, "car"), idx(t, "wreck"));
    let tr = trace(t, car);
    assert_eq!(touches(t, car, wreck), None, "{tr}");
    assert!(slowest(t, car) > 5.0, "the car slowed to {:.2} m/s\n{tr}", slowest(t, car));
    let end = t.poses[car][t.frames - 1];
    assert!(end.x > t.poses[wreck][0].x + 10.0, "the car is not past the wreck\n{tr}");
}

#[test]
fn a_car_waits_for_an_oncoming_car_then_passes_the_wreck() {
    let f = front_of("tests/rollout-cases/car-waits-for-an-oncoming-car-to-pass-a-wreck.scn");
    let t = &f.tracks;
    let (car, wreck, oncoming) = (idx(t, "car"), idx(t, "wreck"), idx(t, "oncoming"));
    let tr = trace(t, car);
    assert_eq!(touches(t, car, wreck), None, "{tr}");
    assert_eq!(touches(t, car, oncoming), None, "{tr}");
    // The oncoming car goes by at its speed: nobody drives into its lane ahead of it.
    assert!(slowest(t, oncoming) > 8.0, "the oncoming car slowed to {:.2} m/s", slowest(t, oncoming));
    // Its rear passes the car's front: from then on the lane is free.
    let by = (0..t.frames).find(|&f| t.poses[oncoming][f].x < t.poses[car][f].x).expect("the oncoming car passes");
    let lane_y = t.poses[car][0].y;
    let moved_out = (0..t.frames).find(|&f| t.poses[car][f].y > lane_y + 0.5).expect("the car never moves out");
    assert!(
        moved_out > by.saturating_sub(15),
        "the car moved out at frame {moved_out}, the oncoming car passed at {by}\n{tr}"
    );
    assert!(t.speeds[car][..by].iter().any(|&v| v < 3.0), "the car did not wait\n{tr}");
    let end = t.poses[car][t.frames - 1];
    assert!(end.x > t.poses[wreck][0].x + 10.0, "the car is not past the wreck\n{tr}");
}

/// A pass over the line into a lane going our way waits while a vehicle there is beside us:
/// the car crosses the line only once the bus's rear is ahead of its front, then gets past.
#[test]
fn a_car_waits_for_a_bus_beside_it_then_passes_the_wreck() {
    let f = front_of("tests/rollout-cases/car-waits-for-a-bus-beside-it-to-pass-a-wreck.scn");
    let t = &f.tracks;
    let (car, wreck, bus) = (idx(t, "car"), idx(t, "wreck"), idx(t, "bus"));
    let tr = trace(t, car);
    assert_eq!(touches(t, car, wreck), None, "{tr}");
    assert_eq!(touches(t, car, bus), None, "{tr}");
    // The road runs along x; the inner lane is to the left (+y) of the car's.
    let (line, [l, w, _]) = (t.poses[car][0].y + 1.75, t.agents[car].size);
    let [bl, ..] = t.agents[bus].size;
    let over = (0..t.frames)
        .find(|&f| {
            let p = t.poses[car][f];
            p.y + 0.5 * l * p.yaw.sin().abs() + 0.5 * w * p.yaw.cos() > line
        })
        .unwrap_or_else(|| panic!("the car never moves over\n{tr}"));
    let (p, b) = (t.poses[car][over], t.poses[bus][over]);
    assert!(b.x - bl / 2.0 > p.x + l / 2.0, "over the line at frame {over} beside the bus at {:.1}\n{tr}", b.x);
    let end = t.poses[car][t.frames - 1];
    assert!(end.x > t.poses[wreck][0].x + 10.0, "the car is not past the wreck\n{tr}");
}

#[test]
fn a_car_stops_behind_a_wreck_that_leaves_no_room() {
    let f = front_of("tests/rollout-cases/car-stops-behind-a-wreck-across-the-road.scn");
    let t = &f.tracks;
    let (car, wreck) = (idx(t, "car"), idx(t, "wreck"));
    let tr = trace(t, car);
    assert_eq!(touches(t, car, wreck), None, "{tr}");
    let last = t.frames - 1;
    assert!(t.speeds[car][last] < 0.05, "the car did not stop\n{tr}");
    let lane_y = t.poses[car][0].y;
    assert!((0..t.frames).all(|f| (t.poses[car][f].y - lane_y).abs() < 0.3), "the car left its lane\n{tr}");
    let gap = obb(t, wreck, last).corners().iter().map(|q| q.x).fold(f64::INFINITY, f64::min) - t.poses[car][last].x;
    assert!(gap < 10.0, "the car stopped {gap:.1} m short of the wreck\n{tr}");
}

#[test]
fn cars_ahead_of_a_fire_truck_pull_over_and_go_on_after_it_passed() {
    let f = front_of("tests/rollout-cases/fire-truck-from-behind-cars-pull-over.scn");
    let t = &f.tracks;
    let (truck, c1, c2) = (idx(t, "truck"), idx(t, "c1"), idx(t, "c2"));
    let lane_y = t.poses[truck][0].y;
    for c in [c1, c2] {
        let tr = trace(t, c);
        assert_eq!(touches(t, truck, c), None, "{tr}");
        // Where the truck passes it, the car is on the shoulder side and (nearly) standing.
        let at = (0..t.frames).find(|&f| t.poses[truck][f].x > t.poses[c][f].x).expect("the truck passes");
        assert!(t.poses[c][at].y < lane_y - 1.0, "{} not pulled over when passed\n{tr}", t.agents[c].name);
        assert!(t.speeds[c][at] < 1.0, "{} at {:.2} m/s when passed\n{tr}", t.agents[c].name, t.speeds[c][at]);
        // And goes on afterwards.
        let last = t.frames - 1;
        assert!(t.speeds[c][last] > 3.0, "{} did not go on\n{tr}", t.agents[c].name);
    }
    assert!(slowest(t, truck) > 5.0, "the truck slowed to {:.2} m/s\n{}", slowest(t, truck), trace(t, truck));
}

/// The fire-truck scene with the truck's siren stated.
fn fire_truck_scene(siren: &str) -> String {
    let text = std::fs::read_to_string("tests/rollout-cases/fire-truck-from-behind-cars-pull-over.scn").expect("case");
    text.replacen("goal { speed 60 km/h }", &format!("goal {{ speed 60 km/h }}\n        siren {siren}"), 1)
}

fn front_of_text(text: &str) -> Result<rocc::compile::Front, Vec<rocc::diag::Diagnostic>> {
    let mut sources = rocc::source::SourceMap::default();
    let s = rocc::check::check_text("t.scn", text, std::path::Path::new("."), &mut sources)?;
    rocc::compile::front(s, None)
}

/// `siren on` is the default; `siren off` makes the fire truck an ordinary vehicle, which the
/// cars ahead do not pull over for: it follows them.
#[test]
fn with_its_siren_off_the_fire_truck_gets_no_way() {
    let on = front_of_text(&fire_truck_scene("on")).expect("checks");
    let default = front_of("tests/rollout-cases/fire-truck-from-behind-cars-pull-over.scn");
    let digest = |t: &Tracks| {
        let mut h = rocc::fsio::Fnv1a::default();
        t.digest(&mut h);
        h.finish()
    };
    assert_eq!(digest(&on.tracks), digest(&default.tracks), "`siren on` is not the default");
    let off = front_of_text(&fire_truck_scene("off")).expect("checks");
    let t = &off.tracks;
    let (truck, c1) = (idx(t, "truck"), idx(t, "c1"));
    let lane_y = t.poses[c1][0].y;
    assert!((0..t.frames).all(|f| (t.poses[c1][f].y - lane_y).abs() < 0.05), "c1 moved over\n{}", trace(t, c1));
    assert!(slowest(t, c1) > 10.0, "c1 slowed to {:.2} m/s", slowest(t, c1));
    assert!((0..t.frames).all(|f| t.poses[truck][f].x < t.poses[c1][f].x), "the truck passed c1");
}

#[test]
fn a_siren_is_on_or_off_and_only_on_emergency_kinds() {
    let err = |text: &str| front_of_text(text).err().map(|d| d[0].code);
    assert_eq!(err(&fire_truck_scene("loud")), Some("E0116"));
    let sedan = fire_truck_scene("on").replacen("truck: fire_truck", "truck: sedan", 1);
    assert_eq!(err(&sedan), Some("E0170"));
    let derived = format!(
        "kind pumper: fire_truck {{ length 9 m }}\n{}",
        fire_truck_scene("off").replacen("truck: fire_truck", "truck: pumper", 1)
    );
    assert_eq!(err(&derived), None);
}

#[test]
fn cross_traffic_drives_around_a_car_stalled_in_the_junction() {
    let f = front_of("tests/rollout-cases/car-stalled-in-a-junction-cross-traffic-drives-around.scn");
    let t = &f.tracks;
    let (car, stalled) = (idx(t, "car"), idx(t, "stalled"));
    let tr = trace(t, car);
    assert_eq!(touches(t, car, stalled), None, "{tr}");
    assert!(slowest(t, car) > 5.0, "the car slowed to {:.2} m/s\n{tr}", slowest(t, car));
    let end = t.poses[car][t.frames - 1];
    assert!(end.x > t.poses[stalled][0].x + 10.0, "the car is not past the stalled one\n{tr}");
}

/// `away_from` a standing object: the car eases to the far side of its lane as it nears the
/// debris on the lane's right edge, and goes by without touching or slowing.
#[test]
fn away_from_a_standing_object_eases_to_the_far_side_of_the_lane() {
    let text = "scenario t {\n    seed 2\n    duration 8 s\n    rate 10 Hz\n    egos [car]\n    \
                road straight { lanes 1; lane_width 3.5 m; speed_limit 50 km/h; length 300 m }\n    \
                object junk: debris { at west.in[1], 20 m after center offset 1.3 m right }\n    \
                agent car: sedan {\n        at west.in[1], 50 m before center\n        speed 40 km/h\n        \
                goal { speed 40 km/h; lateral away_from junk }\n    }\n}\n";
    let f = front_of_text(text).unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| &d.message).collect::<Vec<_>>()));
    let t = &f.tracks;
    let (car, junk) = (idx(t, "car"), idx(t, "junk"));
    let tr = trace(t, car);
    assert_eq!(touches(t, car, junk), None, "{tr}");
    assert!(slowest(t, car) > 10.0, "the car slowed to {:.2} m/s\n{tr}", slowest(t, car));
    let lane_y = t.poses[car][0].y;
    let beside = (0..t.frames).find(|&k| t.poses[car][k].x > t.poses[junk][0].x).expect("the car reaches the debris");
    assert!(t.poses[car][beside].y > lane_y + 0.4, "the car did not ease away\n{tr}");
}

/// The least gap between two boxes over the clip is at least `m` (boxes grown by half of it
/// each never overlap; square corners make this a conservative test).
fn keeps_apart(t: &Tracks, a: usize, b: usize, m: f64) -> Option<usize> {
    (0..t.frames).find(|&f| obb(t, a, f).grown(m / 2.0).overlaps(&obb(t, b, f).grown(m / 2.0)))
}

#[test]
fn a_car_passes_a_slow_cyclist_in_the_clear_oncoming_lane_a_metre_away() {
    let f = front_of("tests/rollout-cases/car-passes-a-slow-cyclist.scn");
    let t = &f.tracks;
    let (car, cyclist) = (idx(t, "car"), idx(t, "cyclist"));
    let tr = trace(t, car);
    assert_eq!(keeps_apart(t, car, cyclist, 1.0), None, "closer than 1 m\n{tr}");
    assert!(slowest(t, car) > 9.0, "the car slowed to {:.2} m/s behind the cyclist\n{tr}", slowest(t, car));
    let (end, lane_y) = (t.poses[car][t.frames - 1], t.poses[car][0].y);
    assert!(end.x > t.poses[cyclist][t.frames - 1].x + 20.0, "the car did not pass\n{tr}");
    assert!((end.y - lane_y).abs() < 0.2, "the car is not back in its lane\n{tr}");
    assert!(t.poses[car].iter().any(|p| p.y > 0.0), "the car did not cross the centre line\n{tr}");
}

#[test]
fn a_car_behind_a_slow_cyclist_waits_for_the_oncoming_car_then_passes() {
    let f = front_of("tests/rollout-cases/car-behind-a-slow-cyclist-waits-for-an-oncoming-car.scn");
    let t = &f.tracks;
    let (car, cyclist, oncoming) = (idx(t, "car"), idx(t, "cyclist"), idx(t, "oncoming"));
    let tr = trace(t, car);
    assert_eq!(touches(t, car, oncoming), None, "{tr}");
    assert_eq!(keeps_apart(t, car, cyclist, 1.0), None, "closer than 1 m\n{tr}");
    assert!(slowest(t, oncoming) > 10.0, "the oncoming car slowed to {:.2} m/s", slowest(t, oncoming));
    // It follows the cyclist at its pace, and moves out only once the oncoming car is by.
    let by = (0..t.frames).find(|&f| t.poses[oncoming][f].x < t.poses[car][f].x).expect("the oncoming car passes");
    let lane_y = t.poses[car][0].y;
    let moved_out = (0..t.frames).find(|&f| t.poses[car][f].y > lane_y + 0.5).expect("the car never moves out");
    assert!(moved_out >= by, "the car moved out at frame {moved_out}, the oncoming car passed at {by}\n{tr}");
    assert!(t.speeds[car][..by].iter().any(|&v| v < 5.0), "the car did not slow behind the cyclist\n{tr}");
    let end = t.poses[car][t.frames - 1];
    assert!(end.x > t.poses[cyclist][t.frames - 1].x + 10.0, "the car did not pass\n{tr}");
}
