//! Replayed tracks are checked like any motion (speed, acceleration, yaw rate, sideways slip,
//! surface): one infeasible track per limit is in tests/invalid/track_*.scn; here, recorded tracks
//! with their jitter still import and check, and the error names the keyframe.

use rocc::check;
use rocc::compile::front;
use rocc::diag::Diagnostic;
use rocc::import::{Convention, import_boxes};
use rocc::source::SourceMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn run(src: &str) -> Result<(), Vec<Diagnostic>> {
    let mut sources = SourceMap::default();
    let s = check::check_text("t.scn", src, Path::new("."), &mut sources)?;
    front(s, None).map(|_| ())
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/import").join(name)
}

#[test]
fn the_recorded_fixtures_import_and_check() {
    for (name, conv) in [
        ("nuplan.json", Convention::NuPlan),
        ("nuscenes.json", Convention::NuScenes),
        ("mmdet3d.json", Convention::Mmdet3d),
    ] {
        let mut sources = SourceMap::default();
        import_boxes(&fixture(name), conv, "imported", &mut sources)
            .unwrap_or_else(|d| panic!("{name}: {}", d.iter().map(|d| d.render_plain(&sources)).collect::<String>()));
    }
}

/// A deterministic jitter in [-1, 1] (a hash of the frame and the track), as recorded annotations
/// wobble from frame to frame.
fn wobble(frame: usize, salt: u64) -> f64 {
    let mut x = (frame as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ salt;
    x ^= x >> 31;
    x = x.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 29;
    (x % 20_001) as f64 / 10_000.0 - 1.0
}

/// A nuPlan-layout box stream at 20 Hz: a car turning left at 10 m/s, a car braking hard from
/// 15 m/s at 7 m/s^2 to a stop, a walker, each with 10 cm and 3 degrees (the walker 15) of
/// jitter; `glitch` moves the turning car `glitch` m sideways in frame 60.
fn stream(glitch: f64) -> String {
    stream_with(glitch, 60..61)
}

/// `stream`, the turning car moved `glitch` m sideways in `frames`.
fn stream_with(glitch: f64, frames_moved: std::ops::Range<usize>) -> String {
    let mut frames = vec![];
    for f in 0..120 {
        let t = f as f64 * 0.05;
        let (r, w) = (20.0, 10.0 / 20.0);
        let th = w * t;
        let mut turn = [r * th.sin(), r - r * th.cos(), th];
        if frames_moved.contains(&f) {
            turn[0] -= glitch * th.sin();
            turn[1] += glitch * th.cos();
        }
        let tb = t.min(15.0 / 7.0);
        let brake = [15.0 * tb - 3.5 * tb * tb, -10.0, 0.0];
        let walk = [5.0, 8.0 + 1.4 * t, std::f64::consts::FRAC_PI_2];
        let mut boxes = String::new();
        for (i, (id, class, p, size, yaw_jitter)) in [
            ("turn", "vehicle", turn, "[4.6, 1.9, 1.5]", 3.0_f64),
            ("brake", "vehicle", brake, "[4.6, 1.9, 1.5]", 3.0),
            ("walk", "pedestrian", walk, "[0.6, 0.6, 1.7]", 15.0),
        ]
        .into_iter()
        .enumerate()
        {
            let s = i as u64 * 3;
            let (x, y) = (p[0] + 0.1 * wobble(f, s), p[1] + 0.1 * wobble(f, s + 1));
            let yaw = p[2] + yaw_jitter.to_radians() * wobble(f, s + 2);
            let sep = if i == 0 { "" } else { ", " };
            let _ = write!(
                boxes,
                "{sep}{{\"track\": \"{id}\", \"class\": \"{class}\", \"center\": [{x}, {y}, 0.8], \"size\": {size}, \"yaw\": {yaw}}}"
            );
        }
        frames.push(format!(
            "{{\"frame\": {f}, \"time\": {t}, \"ego_pose\": {{\"x\": {}, \"y\": -20.0, \"yaw\": 0.0}}, \"boxes\": [{boxes}]}}",
            -30.0 + 8.0 * t
        ));
    }
    format!("{{\"convention\": \"nuplan\", \"ego_size\": [4.6, 1.9, 1.5], \"frames\": [{}]}}", frames.join(",\n"))
}

fn import_stream(text: &str, name: &str) -> Result<String, Vec<Diagnostic>> {
    let dir = std::env::temp_dir().join(format!("rocc-tracks-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("stream.json");
    std::fs::write(&path, text).expect("write");
    let mut sources = SourceMap::default();
    let r = import_boxes(&path, Convention::NuPlan, "recorded", &mut sources).map(|i| i.text);
    let _ = std::fs::remove_dir_all(&dir);
    r
}

#[test]
fn jittery_recorded_turns_hard_braking_and_walkers_import_and_check() {
    let text = import_stream(&stream(0.0), "clean").unwrap_or_else(|d| panic!("{d:?}"));
    assert!(["t_turn", "t_brake", "t_walk"].iter().all(|n| text.contains(&format!("agent {n}"))), "{text}");
}

/// Import `text`: the scene text and the warnings.
fn import_warned(text: &str, name: &str) -> (String, Vec<Diagnostic>) {
    let dir = std::env::temp_dir().join(format!("rocc-tracks-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("stream.json");
    std::fs::write(&path, text).expect("write");
    let mut sources = SourceMap::default();
    let r = import_boxes(&path, Convention::NuPlan, "recorded", &mut sources);
    let _ = std::fs::remove_dir_all(&dir);
    let i = r.unwrap_or_else(|d| panic!("{name}: {}", d.iter().map(|d| d.render_plain(&sources)).collect::<String>()));
    (i.text, i.warnings)
}

/// The keyframe times (s) of agent `name` in imported text.
fn key_times(text: &str, name: &str) -> Vec<String> {
    let from = text.find(&format!("agent {name}:")).unwrap_or_else(|| panic!("no agent {name}"));
    let body = &text[from..from + text[from..].find("\n    }").expect("end of agent")];
    body.lines().filter_map(|l| l.trim().split_once(" s: ").map(|(t, _)| t.to_string())).collect()
}

#[test]
fn a_recorded_box_jumping_sideways_is_dropped_with_a_warning_and_the_rest_kept() {
    // One glitched frame: dropped, the rest of the track kept, one E0135 naming it.
    let (text, warns) = import_warned(&stream(4.0), "glitch");
    let e0135: Vec<&Diagnostic> = warns.iter().filter(|d| d.code == "E0135").collect();
    assert_eq!(e0135.len(), 1, "{warns:?}");
    assert!(e0135[0].message.contains("`turn`") && e0135[0].message.contains("frame 60"), "{}", e0135[0].message);
    let times = key_times(&text, "t_turn");
    assert_eq!(times.len(), 119, "{times:?}");
    assert!(
        !times.contains(&"3".to_string()) && times.contains(&"2.95".to_string()) && times.contains(&"3.05".to_string())
    );
    assert_eq!(key_times(&text, "t_brake").len(), 120);
    // A jump for good: the rest of the track is an agent of its own, from the frame it jumps.
    let (text, warns) = import_warned(&stream_with(4.0, 60..120), "jump");
    assert_eq!(warns.iter().filter(|d| d.code == "E0135").count(), 1, "{warns:?}");
    assert_eq!(key_times(&text, "t_turn").len(), 60);
    assert_eq!(key_times(&text, "t_turn_from_60").len(), 60);
    assert_eq!(key_times(&text, "t_turn_from_60")[0], "3");
    // `rocc explain` knows the code.
    assert!(rocc::diag::codes::all().any(|c| c.code == "E0135"));
}

#[test]
fn a_sedan_jumping_90_m_sideways_off_the_road_fails_and_each_limit_names_its_keyframe() {
    let scene = |keys: &str| {
        format!(
            "scenario s {{ duration 3 s\n road straight {{ lanes 1; sidewalks on }}\n agent v: sedan {{ track {{ {keys} }} }}\n}}\n"
        )
    };
    let fails = |keys: &str, code: &str, words: &[&str]| {
        let src = scene(keys);
        let d = run(&src).expect_err(keys);
        assert_eq!(d[0].code, code, "{keys}: {d:?}");
        for w in words {
            assert!(d[0].message.contains(w), "{keys}: `{w}` not in {}", d[0].message);
        }
        // The first label is the keyframe the step ends at.
        let at = d[0].labels[0].span;
        let key = &src[at.start as usize..at.end as usize];
        assert!(key.starts_with("1 s:") || key.starts_with("2 s:"), "{keys}: labelled `{key}`");
        d
    };
    let d = fails("0 s: (0 m, -1.75 m) yaw 0 deg; 1 s: (0 m, 88.25 m) yaw 0 deg", "E0134", &["sideways", "90 deg"]);
    assert!(d.iter().any(|d| d.code == "E0210"), "off the road too: {d:?}");
    fails("0 s: (-55 m, -1.75 m) yaw 0 deg; 1 s: (45 m, -1.75 m) yaw 0 deg", "E0131", &["100.0 m/s", "90.0 m/s"]);
    fails(
        "0 s: (-50 m, -1.75 m) yaw 0 deg; 1 s: (-40 m, -1.75 m) yaw 0 deg; 2 s: (0 m, -1.75 m) yaw 0 deg",
        "E0132",
        &["30.0 m/s^2", "12.0 m/s^2"],
    );
    fails("0 s: (-20 m, -1.75 m) yaw 0 deg; 1 s: (-19.5 m, -1.75 m) yaw 90 deg", "E0133", &["yaw rate 90 deg/s"]);
    fails("0 s: (-20 m, -1.75 m) yaw 0 deg; 2 s: (-10 m, -5 m) yaw 0 deg", "E0210", &["keyframe 2", "sidewalk"]);
    // Feasible: 20 m/s along the lane, reversing slowly, a gentle lane-keeping wobble.
    run(&scene("0 s: (-50 m, -1.75 m) yaw 0 deg; 1 s: (-30 m, -1.6 m) yaw 1 deg; 2 s: (-10 m, -1.75 m) yaw 0 deg"))
        .expect("a plain drive");
    run(&scene("0 s: (0 m, -1.75 m) yaw 0 deg; 2 s: (-3 m, -1.75 m) yaw 0 deg")).expect("reversing");
    // A walker on the same road may go anywhere near it, sideways included.
    let walker = "scenario s { duration 3 s\n road straight { lanes 1; sidewalks on }\n agent ego: sedan { at west.in[1], 30 m before center }\n agent p: adult { track { 0 s: (0 m, -5 m) yaw 0 deg; 2 s: (0 m, -2 m) yaw 0 deg } }\n}\n";
    run(walker).expect("a walker sidesteps onto the road");
}

#[test]
fn keyframes_in_lane_coordinates_mix_with_world_ones_and_are_checked_like_them() {
    let scene = |keys: &str| {
        format!(
            "scenario s {{ duration 4 s\n road straight {{ lanes 2 }}\n agent ego: sedan {{ at west.in[1], 50 m before center; speed 10 m/s }}\n agent cutter: van {{ track {{ {keys} }} }}\n}}\n"
        )
    };
    let keys = "0 s: west.in[2], 40 m before center; 1 s: west.in[2], 26 m before center; \
                2 s: (-12 m, -3.5 m) yaw 5 deg; 3 s: west.in[1], 2 m after center offset 0.5 m left heading 0 deg";
    let mut sources = SourceMap::default();
    let s = check::check_text("t.scn", &scene(keys), Path::new("."), &mut sources).expect("checks");
    let f = front(s, None).unwrap_or_else(|d| panic!("{d:?}"));
    let i = f.tracks.agents.iter().position(|a| a.name == "cutter").expect("cutter");
    // west.in[2] runs east 5.25 m south of the centre line; in[1] 1.75 m south.
    for (frame, x, y, yaw) in
        [(0, -40.0, -5.25, 0.0), (10, -26.0, -5.25, 0.0), (20, -12.0, -3.5, 5.0), (30, 2.0, -1.25, 0.0)]
    {
        let p = f.tracks.poses[i][frame];
        assert!(
            (p.x - x).abs() < 1e-6 && (p.y - y).abs() < 1e-6 && (p.yaw - f64::to_radians(yaw)).abs() < 1e-6,
            "frame {frame}: {p:?}"
        );
    }
    // Formatting keeps both forms.
    let src = scene(keys);
    let text = rocc::syntax::fmt::format_file(&rocc::syntax::parse(0, &src).expect("parses"), &src);
    assert!(
        text.contains("1 s: west.in[2], 26 m before center") && text.contains("2 s: (-12 m, -3.5 m) yaw 5 deg"),
        "{text}"
    );
    let code = |keys: &str| run(&scene(keys)).expect_err(keys)[0].code;
    // 100 m along the lane in one second, past the lane's end, and a range.
    assert_eq!(code("0 s: west.in[2], 50 m before center; 1 s: west.in[2], 50 m after center"), "E0131");
    assert_eq!(code("0 s: west.in[2], 50 m before center; 1 s: west.in[2], 90 m after center"), "E0203");
    assert_eq!(code("0 s: west.in[2], 40..45 m before center"), "E0117");
}

#[test]
fn a_track_on_a_trigger_counts_its_keyframes_from_when_it_fires_and_is_checked_like_any() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/behaviour-cases/car-pulls-out-from-the-shoulder-on-a-trigger.scn");
    let src = std::fs::read_to_string(&path).expect("scene");
    let mut sources = SourceMap::default();
    let s = check::check_text("t.scn", &src, Path::new("."), &mut sources).expect("checks");
    let f = front(s, None).unwrap_or_else(|d| panic!("{d:?}"));
    let t = &f.tracks;
    let (car, ego) = (t.agents.iter().position(|a| a.name == "parked").expect("parked"), 1);
    // It fires on the first frame the ego is within 30 m; its keyframes count one step later.
    let dist = |k: usize| (t.poses[car][k].x - t.poses[ego][k].x).hypot(t.poses[car][k].y - t.poses[ego][k].y);
    let fired = (0..t.frames).find(|&k| dist(k) <= 30.0).expect("the ego comes within 30 m");
    assert!(fired > 10, "fired at frame {fired}");
    let first = t.poses[car][0];
    assert!((0..=fired).all(|k| t.poses[car][k] == first), "it moved before its trigger");
    // west.in[1] runs east 1.75 m south of the centre line.
    for (key_t, x, y, yaw) in [(1.0, -8.5, -4.15, 8.0), (2.0, -4.5, -3.25, 12.0), (3.0, 1.5, -2.05, 4.0)] {
        let p = t.poses[car][fired + (key_t * t.rate) as usize];
        assert!(
            (p.x - x).abs() < 1e-6 && (p.y - y).abs() < 1e-6 && (p.yaw - f64::to_radians(yaw)).abs() < 1e-6,
            "keyframe {key_t} s: {p:?}"
        );
    }
    // Feasibility and surface as for any track; triggers as for any start.
    let code = |from: &str, to: &str| run(&src.replacen(from, to, 1)).expect_err(to)[0].code;
    assert_eq!(code("1 s: west.in[1], 8.5 m before", "1 s: west.in[1], 80 m after"), "E0132");
    assert_eq!(code("4 s: west.in[1], 9.5 m after", "4 s: west.in[1], 120 m after"), "E0131");
    assert_eq!(code("shoulder 2.5 m", "shoulder 0.5 m"), "E0210");
    assert_eq!(code("track when ego within 30 m {", "track when ego within 30 s {"), "E0101");
    assert_eq!(code("track when ego within 30 m {", "track when ego near 30 m {"), "E0150");
    assert_eq!(code("track when ego within 30 m {", "track when parked within 30 m {"), "E0151");
    let cycle = src.replacen(
        "speed 40 km/h\n        goal { speed 40 km/h }",
        "speed 40 km/h\n        goal { speed 40 km/h; start when parked starts }",
        1,
    );
    assert_eq!(run(&cycle).expect_err("a cycle")[0].code, "E0151");
}
