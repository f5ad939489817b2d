//! Flaggers (`flag { ... }`), tested on the tracks and the clip files: the work zone of
//! `scenarios/rare/flagger_work_zone.scn`, and the three forms of a flag program.

#[path = "support/contact.rs"]
mod contact;
#[path = "support/front.rs"]
mod front;

use front::front_of;
use rocc::rollout::Tracks;

fn zone() -> String {
    std::fs::read_to_string("scenarios/rare/flagger_work_zone.scn").expect("scene")
}

fn idx(t: &Tracks, name: &str) -> usize {
    t.agents.iter().position(|a| a.name == name).unwrap_or_else(|| panic!("no agent {name}"))
}

/// What flagger `name` shows per frame (true: go).
fn shown(t: &Tracks, name: &str) -> Vec<bool> {
    let i = idx(t, name);
    t.flags.iter().find(|f| f.agent == i).unwrap_or_else(|| panic!("{name} is no flagger")).go.clone()
}

/// The scene with its `flag` blocks removed: nobody directs traffic.
fn unflagged(text: &str) -> String {
    text.lines().filter(|l| !l.trim_start().starts_with("flag")).collect::<Vec<_>>().join("\n")
}

#[test]
fn traffic_stops_short_of_a_flaggers_stop_and_goes_on_its_go() {
    let t = front_of(&zone()).tracks;
    let (ego, van, late) = (idx(&t, "ego"), idx(&t, "van"), idx(&t, "late"));
    let (west, east) = (idx(&t, "west_flagger"), idx(&t, "east_flagger"));
    let (wx, ex) = (t.poses[west][0].x, t.poses[east][0].x);
    let half = |i: usize| t.agents[i].size[0] / 2.0;
    let (ws, es) = (shown(&t, "west_flagger"), shown(&t, "east_flagger"));
    assert_eq!(ws.len(), t.frames);
    // The west flagger shows stop, then go from just after 9 s; the east one go, then stop
    // from just after 6 s.
    let go_at = ws.iter().position(|g| *g).expect("the west flagger shows go");
    assert!((90..=91).contains(&go_at) && ws[go_at..].iter().all(|g| *g), "west goes at frame {go_at}");
    let stop_at = es.iter().position(|g| !*g).expect("the east flagger shows stop");
    assert!((60..=61).contains(&stop_at) && !es[stop_at..].iter().any(|g| *g), "east stops at frame {stop_at}");
    // The eastbound ego's front stays short of the west flagger while it shows stop, and it
    // stands there before the go.
    for f in 0..go_at {
        let front = t.poses[ego][f].x + half(ego);
        assert!(front < wx - 1.5, "frame {f}: the ego's front is {:.2} m short of the flagger", wx - front);
    }
    assert!((60..go_at).all(|f| t.speeds[ego][f] < 0.15), "the ego stands at the flagger's stop");
    // On the go it drives past the flagger and round the cones into the zone.
    assert!(t.poses[ego][t.frames - 1].x > 10.0, "the ego is through the zone");
    // The van comes through westbound on the east flagger's go without slowing.
    assert!(t.speeds[van].iter().all(|v| *v > 10.0), "the van slowed");
    // The second westbound car stops short of the east flagger's stop and stands.
    for f in stop_at..t.frames {
        let front = t.poses[late][f].x - half(late);
        assert!(front > ex + 1.5, "frame {f}: the late car's front is {:.2} m short of the flagger", front - ex);
    }
    assert!(t.speeds[late][t.frames - 1] < 0.05, "the late car stands at the stop");
    for f in 0..t.frames {
        for (a, b) in [(ego, van), (ego, late), (ego, west), (late, east)] {
            assert!(!contact::obb(&t, a, f).overlaps(&contact::obb(&t, b, f)), "overlap at frame {f}");
        }
    }
    // Without the flaggers the late car drives on through the zone.
    let free = front_of(&unflagged(&zone())).tracks;
    assert!(free.flags.is_empty());
    let late = idx(&free, "late");
    assert!(free.poses[late][free.frames - 1].x < ex - 10.0, "unflagged, the late car drives on");
}

#[test]
fn a_driver_who_ignores_signals_ignores_the_flagger() {
    let text = zone().replace(
        "        goal { speed 40 km/h }\n    }\n\n    agent van",
        "        goal { speed 40 km/h }\n        behaviour { signal ignore }\n    }\n\n    agent van",
    );
    assert_ne!(text, zone(), "the ego's block was found");
    let t = front_of(&text).tracks;
    let (ego, west) = (idx(&t, "ego"), idx(&t, "west_flagger"));
    let wx = t.poses[west][0].x;
    // It stops only where the cones make it wait for the oncoming van, and drives past the
    // flagger before the go.
    let past = (0..90).find(|&f| t.poses[ego][f].x > wx);
    assert!(past.is_some(), "the ego drives past the flagger's stop");
}

/// A straight road with a flagger facing eastbound traffic (`flag` as given) and a car coming.
fn program(flag: &str) -> Tracks {
    let text = format!(
        "scenario p {{\n    duration 10 s\n    road straight {{ lanes 1; shoulder 2.5 m }}\n    agent f: adult {{ at west.in[1], 20 m before center offset 3 m right heading 180 deg; {flag} }}\n    agent car: sedan {{ at west.in[1], 60 m before center; speed 8 m/s; goal {{ speed 8 m/s }} }}\n}}\n"
    );
    let once = rocc::syntax::format_source(&text).expect("formats");
    assert_eq!(rocc::syntax::format_source(&once).expect("formats again"), once, "{once}");
    front_of(&text).tracks
}

#[test]
fn a_flag_cycle_repeats_its_states_for_their_lengths() {
    let t = program("flag { stop 3 s; go 2 s }");
    let go = shown(&t, "f");
    for (f, g) in go.iter().enumerate() {
        let at = (f as f64 / t.rate) % 5.0;
        if (at - 3.0).abs() > 1e-6 && at > 1e-6 {
            assert_eq!(*g, at > 3.0, "frame {f} ({at:.1} s into the cycle)");
        }
    }
}

#[test]
fn a_flag_step_on_a_trigger_follows_its_condition_by_one_step() {
    let t = program("flag { stop; go when car within 25 m }");
    let (f, car) = (idx(&t, "f"), idx(&t, "car"));
    let dist = |k: usize| (t.poses[f][k].x - t.poses[car][k].x).hypot(t.poses[f][k].y - t.poses[car][k].y);
    let near = (0..t.frames).find(|&k| dist(k) <= 25.0).expect("the car comes within 25 m");
    let go = shown(&t, "f");
    assert!(!go[near] && go[near + 1..].iter().all(|g| *g), "go from frame {}", near + 1);
    // The car, held until then, drives past once waved on.
    assert!(t.poses[car][t.frames - 1].x > t.poses[f][0].x + 5.0);
}

#[test]
fn boxes_json_and_scene_json_carry_the_flaggers() {
    use rocc::compile::{Options, Stage, batch};
    let dir = std::env::temp_dir().join(format!("rocc-flaggers-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let o = Options { stage: Stage::Bev, frames: Some("0,150".to_string()), ..Options::default() };
    let input = vec![std::path::PathBuf::from("scenarios/rare/flagger_work_zone.scn")];
    let r = batch::run(&input, &dir, &o, true);
    assert!(r.failures.is_empty(), "compiles");
    let clip = dir.join("flagger_work_zone/ego");
    let read = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(clip.join(name)).expect(name)).expect("json")
    };
    let boxes = read("boxes.json");
    let flag = |frame: usize, agent: &str| -> Option<String> {
        let rec = boxes.as_array().expect("frames").iter().find(|r| r["frame"] == frame).expect("frame");
        let b = rec["boxes"].as_array().expect("boxes").iter().find(|b| b["agent"] == agent).expect("box");
        b.get("flag").map(|v| v.as_str().expect("a word").to_string())
    };
    assert_eq!(flag(0, "west_flagger").as_deref(), Some("stop"));
    assert_eq!(flag(150, "west_flagger").as_deref(), Some("go"));
    assert_eq!(flag(150, "east_flagger").as_deref(), Some("stop"));
    assert_eq!(flag(150, "late"), None, "only flaggers carry a flag");
    let scene = read("scene.json");
    let flaggers = scene["flaggers"].as_array().expect("flaggers");
    let faces = |name: &str| -> serde_json::Value {
        flaggers.iter().find(|f| f["agent"] == name).expect("listed")["faces"].clone()
    };
    assert_eq!(faces("west_flagger"), serde_json::json!(["west.in[1]"]));
    assert_eq!(faces("east_flagger"), serde_json::json!(["east.in[1]"]));
    let _ = std::fs::remove_dir_all(&dir);
}
