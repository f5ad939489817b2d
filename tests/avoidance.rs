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
