//! Traffic signals, tested on the tracks and the clip files of the scenes in
//! `tests/signal-cases/` (each says in its first line what it shows).

#[path = "support/front.rs"]
mod front;

use front::front_of;
use rocc::compile::Front;
use rocc::road::signals::{Light, light, phase_of};
use rocc::rollout::Tracks;

fn case(name: &str) -> String {
    std::fs::read_to_string(format!("tests/signal-cases/{name}.scn")).expect("case")
}

fn idx(t: &Tracks, name: &str) -> usize {
    t.agents.iter().position(|a| a.name == name).expect("agent")
}

/// How far agent `i`'s front is past the stop line of its approach at frame `f`, m (negative
/// short of it), along its placed heading.
fn past_line(f: &Front, i: usize, frame: usize) -> f64 {
    let t = &f.tracks;
    let p0 = t.poses[i][0];
    let dir = glam::DVec2::from_angle(p0.yaw);
    let line = f
        .map
        .stop_lines
        .iter()
        .map(|s| 0.5 * (s.a + s.b))
        .min_by(|a, b| {
            let d = |q: glam::DVec2| {
                let r = q - glam::DVec2::new(p0.x, p0.y);
                (r.perp_dot(dir)).abs() + if r.dot(dir) < 0.0 { 1e6 } else { 0.0 }
            };
            d(*a).total_cmp(&d(*b))
        })
        .expect("a stop line ahead");
    let p = t.poses[i][frame];
    (glam::DVec2::new(p.x, p.y) - line).dot(dir) + 0.5 * t.agents[i].size[0]
}

/// The light agent `i`'s approach shows at frame `frame`.
fn light_of(f: &Front, i: usize, frame: usize) -> Light {
    let plan = f.map.signals.as_ref().expect("signals");
    let p0 = f.tracks.poses[i][0];
    let arm =
        if p0.yaw.sin().abs() > 0.7 { rocc::check::scenario::Arm::South } else { rocc::check::scenario::Arm::West };
    light(&plan.cycle, phase_of(arm), frame as f64 / f.tracks.rate)
}

/// The scene with its `behaviour` blocks removed: the compliant twin.
fn compliant(text: &str) -> String {
    text.lines().filter(|l| !l.trim_start().starts_with("behaviour")).collect::<Vec<_>>().join("\n")
}

/// The scene with its signals switched off: the road's signal parameters (written last in
/// these scenes) dropped.
fn unsignalled(text: &str) -> String {
    let cut = |l: &str| match l.find("; signals on") {
        Some(k) => format!("{} }}", &l[..k]),
        None => l.to_string(),
    };
    text.lines().map(cut).collect::<Vec<_>>().join("\n")
}

/// The first frame at which the light of agent `i`'s approach is green, after frame 0.
fn first_green(f: &Front, i: usize) -> usize {
    (1..f.tracks.frames).find(|&k| light_of(f, i, k) == Light::Green).expect("a green")
}

#[test]
fn a_car_stops_at_a_red_and_goes_on_the_green() {
    let f = front_of(&case("red-then-green"));
    let car = idx(&f.tracks, "car");
    let green = first_green(&f, car);
    assert_eq!(green, 90, "south's green comes at 9 s");
    for k in 0..green {
        assert!(
            past_line(&f, car, k) <= 0.0,
            "frame {k}: the car's front is {:.2} m past its line on red",
            past_line(&f, car, k)
        );
    }
    assert!(f.tracks.speeds[car][green - 1] < 0.05, "the car stands at its line when the light turns");
    let end = f.tracks.frames - 1;
    assert!(past_line(&f, car, end) > 15.0, "the car drives on through the junction on the green");
    // Without the signals it would not have stopped.
    let free = front_of(&unsignalled(&case("red-then-green")));
    assert!(past_line(&free, car, 50) > 0.0, "unsignalled, the car is through its line by 5 s");
}

#[test]
fn a_red_light_runner_crosses_on_red_into_green_cross_traffic() {
    let f = front_of(&case("red-light-runner"));
    let (runner, cross) = (idx(&f.tracks, "runner"), idx(&f.tracks, "cross"));
    let over = (0..f.tracks.frames).find(|&k| past_line(&f, runner, k) > 0.0).expect("the runner crosses its line");
    assert_eq!(light_of(&f, runner, over), Light::Red, "it crosses on red");
    assert_eq!(light_of(&f, cross, over), Light::Green, "into cross traffic on green");
    assert!(
        f.tracks.speeds[cross][over] > 5.0,
        "the cross traffic is moving ({:.1} m/s)",
        f.tracks.speeds[cross][over]
    );
    assert!(f.tracks.speeds[runner][over] > 11.0, "the runner does not slow for the red");
    // The compliant twin stops at its line for as long as the light is red.
    let twin = front_of(&compliant(&case("red-light-runner")));
    for k in 0..twin.tracks.frames {
        if light_of(&twin, runner, k) == Light::Red {
            assert!(past_line(&twin, runner, k) <= 0.0, "frame {k}: the compliant driver crosses on red");
        }
    }
}

#[test]
fn a_cyclist_waits_at_a_red_between_two_stopped_cars() {
    let f = front_of(&case("cyclist-between-cars-at-red"));
    let t = &f.tracks;
    let (front, rider, back) = (idx(t, "front"), idx(t, "rider"), idx(t, "back"));
    let green = first_green(&f, front);
    let k = green - 1;
    for i in [front, rider, back] {
        assert!(t.speeds[i][k] < 0.1, "{} stands at the red ({:.2} m/s)", t.agents[i].name, t.speeds[i][k]);
        assert!(past_line(&f, i, k) < 0.0, "{} is short of the line", t.agents[i].name);
    }
    // Along the lane: the front car, then the cyclist, then the back car, boxes apart.
    let nose = |i: usize| past_line(&f, i, k);
    let tail = |i: usize| nose(i) - t.agents[i].size[0];
    assert!(tail(front) > nose(rider) + 0.5, "the cyclist stands behind the front car");
    assert!(tail(rider) > nose(back) + 0.5, "the back car stands behind the cyclist");
    let end = t.frames - 1;
    for i in [front, rider, back] {
        assert!(t.speeds[i][end] > 1.0, "{} moves off on the green", t.agents[i].name);
    }
}

#[test]
fn walkers_wait_for_the_walk_signal_and_cross_on_it() {
    let f = front_of(&case("walkers-cross-on-walk"));
    let t = &f.tracks;
    let plan = f.map.signals.as_ref().expect("signals");
    // The crosswalk across the north arm walks with the east-west green.
    let walk = |k: usize| rocc::road::signals::walk(&plan.cycle, rocc::check::scenario::Arm::North, k as f64 / t.rate);
    let first_walk = (0..t.frames).find(|&k| walk(k)).expect("a walk signal");
    assert_eq!(first_walk, 90, "the walk signal comes with the east-west green at 9 s");
    for name in ["w1", "w2"] {
        let i = idx(t, name);
        let x0 = t.poses[i][0].x;
        for k in 0..first_walk {
            assert!((t.poses[i][k].x - x0).abs() < 1e-6, "frame {k}: {name} leaves the kerb before the walk signal");
        }
        let end = t.frames - 1;
        assert!((t.poses[i][end].x - x0).abs() > 7.0, "{name} crosses on the walk signal");
    }
    // One who ignores signals crosses the south arm before its walk signal (the same as the
    // north crosswalk's), at a gap in traffic.
    let w3 = idx(t, "w3");
    let gone = (0..first_walk).find(|&k| (t.poses[w3][k].x - t.poses[w3][0].x).abs() > 7.0);
    assert!(gone.is_some(), "w3 crosses before the walk signal");
    // Without signals they step off at once.
    let free = front_of(&unsignalled(&case("walkers-cross-on-walk")));
    let w1 = idx(&free.tracks, "w1");
    assert!(
        (free.tracks.poses[w1][30].x - free.tracks.poses[w1][0].x).abs() > 1.0,
        "unsignalled, w1 is crossing by 3 s"
    );
}

#[test]
fn boxes_json_and_scene_json_carry_the_signals() {
    use rocc::compile::{Options, Stage, batch};
    let dir = std::env::temp_dir().join(format!("rocc-signals-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let o = Options { stage: Stage::Bev, frames: Some("0,95".to_string()), ..Options::default() };
    let input = vec![std::path::PathBuf::from("tests/signal-cases/red-then-green.scn")];
    let r = batch::run(&input, &dir, &o, true);
    assert!(r.failures.is_empty(), "compiles");
    let clip = dir.join("red_then_green/car");
    let read = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(clip.join(name)).expect(name)).expect("json")
    };
    let boxes = read("boxes.json");
    let lights = |frame: usize| -> Vec<(String, String)> {
        let rec = boxes.as_array().expect("frames").iter().find(|r| r["frame"] == frame).expect("frame");
        rec["signals"]
            .as_array()
            .expect("signals")
            .iter()
            .map(|s| (s["lane"].as_str().expect("lane").to_string(), s["light"].as_str().expect("light").to_string()))
            .collect()
    };
    let (at0, at95) = (lights(0), lights(95));
    assert_eq!(at0.len(), 4, "one signal per approach lane: {at0:?}");
    let of = |v: &[(String, String)], lane: &str| v.iter().find(|s| s.0 == lane).expect("lane").1.clone();
    assert_eq!((of(&at0, "south.in[1]"), of(&at0, "west.in[1]")), ("red".to_string(), "green".to_string()));
    assert_eq!((of(&at95, "south.in[1]"), of(&at95, "west.in[1]")), ("green".to_string(), "red".to_string()));
    let scene = read("scene.json");
    assert_eq!(scene["signals"]["heads"].as_array().expect("heads").len(), 4);
    assert_eq!(scene["signals"]["cycle"]["green"], 6.0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The scene `name` with an `expect` block of `lines`, judged on its tracks: each line's text
/// and its failure's label (`None` when it holds).
fn judged(text: &str, lines: &str) -> Vec<(String, Option<String>)> {
    let end = text.trim_end().rfind('}').expect("scenario's closing brace");
    let f = front_of(&format!("{}    expect {{\n{lines}\n    }}\n}}\n", &text[..end]));
    let contacts = rocc::expect::geometry::contacts(&f);
    f.scenario
        .expects
        .iter()
        .map(|x| {
            let d = rocc::expect::eval::judge(&f, x, &contacts);
            (x.text.clone(), d.map(|d| format!("{} {}", d.code, d.labels[0].text)))
        })
        .collect()
}

#[test]
fn enters_names_the_light_at_the_stop_line() {
    let runner = judged(
        &case("red-light-runner"),
        "        enters runner on red\n        enters runner on green during 0..8 s\n        enters runner on red by 1 s",
    );
    assert_eq!(runner[0], ("enters runner on red".to_string(), None), "the runner crosses on red");
    let (_, miss) = &runner[1];
    let miss = miss.as_deref().expect("not on green");
    assert!(miss.starts_with("E1004 it enters at t = ") && miss.ends_with(" s on red"), "{miss}");
    let (_, early) = &runner[2];
    assert!(early.as_deref().is_some_and(|m| m.ends_with("on red, outside the window")), "{early:?}");
    // Its compliant twin waits out the red, which lasts past the end of the clip.
    let twin = judged(&compliant(&case("red-light-runner")), "        enters runner on red");
    let miss = twin[0].1.as_deref().expect("the twin never enters");
    assert!(miss.starts_with("E1004 it never enters: its front stays "), "{miss}");
    // The car of red-then-green stops for the red and enters on the green at 9 s.
    let car =
        judged(&case("red-then-green"), "        enters car on green during 8..14 s\n        enters car on yellow");
    assert_eq!(car[0].1, None, "{car:?}");
    assert!(car[1].1.as_deref().is_some_and(|m| m.contains("on green")), "{car:?}");
}

#[test]
fn enters_formats_back_to_itself() {
    let src = "scenario x {\n    duration 8 s\n    road four_way { lanes 1; signals on }\n    agent a: sedan { at south.in[1], 30 m before stop_line }\n    expect {\n        enters a on red during 1..8 s\n        enters a on green\n    }\n}\n";
    let once = rocc::syntax::format_source(src).expect("formats");
    assert!(once.contains("enters a on red during 1..8 s\n") && once.contains("enters a on green\n"), "{once}");
    assert_eq!(rocc::syntax::format_source(&once).expect("formats again"), once);
}

fn rare(name: &str) -> String {
    std::fs::read_to_string(format!("scenarios/rare/{name}.scn")).expect("rare scene")
}

#[test]
fn the_rare_red_light_runner_crosses_on_red_while_the_ego_crosses_on_green() {
    let f = front_of(&rare("red_light_runner"));
    let t = &f.tracks;
    let (runner, ego) = (idx(t, "runner"), idx(t, "ego"));
    let over = (0..t.frames).find(|&k| past_line(&f, runner, k) > 0.0).expect("the runner crosses its line");
    assert_eq!(light_of(&f, runner, over), Light::Red, "it crosses on red");
    assert_eq!(light_of(&f, ego, over), Light::Green, "while the ego has green");
    assert!(t.speeds[runner].iter().all(|v| *v > 11.9), "the runner never slows for its red");
    // The ego, on its way in on the green, brakes for the runner inside and does not stop.
    let slowest = t.speeds[ego].iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(slowest < 10.0 && slowest > 3.0, "the ego's slowest is {slowest:.2} m/s");
    let into = (0..t.frames).find(|&k| past_line(&f, ego, k) > 0.0).expect("the ego enters");
    assert_eq!(light_of(&f, ego, into), Light::Green);
    for k in 0..t.frames {
        let (a, b) = (t.poses[runner][k], t.poses[ego][k]);
        assert!((a.x - b.x).hypot(a.y - b.y) > 3.0, "frame {k}: the two cars meet");
    }
}

#[test]
fn the_rare_cyclist_waits_at_the_red_between_the_car_ahead_and_the_ego() {
    let f = front_of(&rare("cyclist_waits_at_red_between_cars"));
    let t = &f.tracks;
    let (front, rider, ego) = (idx(t, "front"), idx(t, "rider"), idx(t, "ego"));
    let green = first_green(&f, front);
    let k = green - 1;
    let nose = |i: usize| past_line(&f, i, k);
    let tail = |i: usize| nose(i) - t.agents[i].size[0];
    for i in [front, rider, ego] {
        assert!(t.speeds[i][k] < 0.1 && nose(i) < 0.0, "{} stands short of the line at the red", t.agents[i].name);
    }
    assert!(tail(front) > nose(rider) + 0.5 && tail(rider) > nose(ego) + 0.5, "car, cyclist, ego in that order");
    // The cyclist rides in the lane between them, not beside them.
    assert!((t.poses[rider][k].x - t.poses[front][k].x).abs() < 0.5);
    for i in [front, rider] {
        let into = (0..t.frames).find(|&j| past_line(&f, i, j) > 0.0).expect("enters");
        assert_eq!(light_of(&f, i, into), Light::Green, "{} enters on the green", t.agents[i].name);
    }
}

#[test]
fn a_leading_green_gives_the_left_turn_a_protected_phase() {
    use rocc::check::scenario::Arm;
    use rocc::road::signals::{arm_light, walk};
    let f = front_of(&case("leading-left-turn"));
    let t = &f.tracks;
    let c = f.map.signals.as_ref().expect("signals").cycle;
    // South is green from 0 s, north from 6 s; both turn yellow at 12 s; east and west wait.
    let at = |arm: Arm, s: f64| arm_light(&c, arm, s);
    assert_eq!((at(Arm::South, 0.0), at(Arm::North, 0.0), at(Arm::East, 0.0)), (Light::Green, Light::Red, Light::Red));
    assert_eq!(
        (at(Arm::North, 6.0), at(Arm::North, 12.5), at(Arm::North, 15.5)),
        (Light::Green, Light::Yellow, Light::Red)
    );
    assert_eq!(
        (at(Arm::East, 16.0), at(Arm::West, 27.0), at(Arm::South, 29.0)),
        (Light::Green, Light::Yellow, Light::Red)
    );
    // Walkers across north walk with the east-west green, not while north is red alone.
    assert!(!walk(&c, Arm::North, 2.0) && walk(&c, Arm::North, 17.0));
    let (turner, oncoming) = (idx(t, "turner"), idx(t, "oncoming"));
    let green = (0..t.frames).find(|&k| at(Arm::North, k as f64 / t.rate) == Light::Green).expect("north's green");
    assert_eq!(green, 60);
    for k in 0..green {
        assert!(past_line(&f, oncoming, k) <= 0.0, "frame {k}: the oncoming car is past its line on red");
    }
    let into = (0..t.frames).find(|&k| past_line(&f, turner, k) > 0.0).expect("the turner enters");
    assert!(into < green, "the turner enters on its lead ({into})");
    // It crosses the oncoming lane (x < 0) before the oncoming car reaches its line.
    let across = (0..t.frames).find(|&k| t.poses[turner][k].x < -1.75).expect("the turner turns left");
    assert!(past_line(&f, oncoming, across) < 0.0, "the oncoming car waits while the turner crosses");
    assert!(past_line(&f, oncoming, t.frames - 1) > 10.0, "the oncoming car goes on its green");
}

#[test]
fn boxes_json_lights_follow_the_per_approach_greens() {
    use rocc::compile::{Options, Stage, batch};
    let dir = std::env::temp_dir().join(format!("rocc-phases-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let o = Options { stage: Stage::Bev, frames: Some("0,70".to_string()), ..Options::default() };
    let input = vec![std::path::PathBuf::from("tests/signal-cases/leading-left-turn.scn")];
    assert!(batch::run(&input, &dir, &o, true).failures.is_empty(), "compiles");
    let text = std::fs::read_to_string(dir.join("leading_left_turn/turner/boxes.json")).expect("boxes.json");
    let boxes: serde_json::Value = serde_json::from_str(&text).expect("json");
    let light = |frame: usize, lane: &str| -> String {
        let rec = boxes.as_array().expect("frames").iter().find(|r| r["frame"] == frame).expect("frame");
        let s = rec["signals"].as_array().expect("signals").iter().find(|s| s["lane"] == lane).expect("lane");
        s["light"].as_str().expect("light").to_string()
    };
    assert_eq!((light(0, "south.in[1]"), light(0, "north.in[1]")), ("green".into(), "red".into()));
    assert_eq!((light(70, "north.in[1]"), light(70, "east.in[1]")), ("green".into(), "red".into()));
    let scene: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("leading_left_turn/turner/scene.json")).expect("scene"))
            .expect("json");
    assert_eq!(scene["signals"]["cycle"]["period"], 30.0);
    assert_eq!(scene["signals"]["cycle"]["windows"][0], serde_json::json!([6.0, 12.0]), "north's green");
    let _ = std::fs::remove_dir_all(&dir);
}
