//! `rocc test` end to end: the bundled library passes its own `expect` blocks and snapshots;
//! failing expectations point at their line with what happened instead; snapshots are written
//! atomically, compared with a diff, reviewed from stdin, refused when foreign or corrupt; the
//! JUnit and JSON reports; output independent of the thread count.

#[path = "support/tmp.rs"]
mod tmp;

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};
use tmp::TempDir;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A directory for this test's outputs, removed when dropped.
fn tmp(name: &str) -> TempDir {
    TempDir::new("rocc-libtest", name)
}

fn rocc(args: &[&str], stdin: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rocc"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run rocc");
    child.stdin.take().expect("stdin").write_all(stdin.as_bytes()).expect("write stdin");
    child.wait_with_output().expect("rocc output")
}

fn text(o: &Output) -> (String, String) {
    (String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// The rear-end scene of the library with `expect` lines of the test's choosing.
fn rear_end(expect: &str) -> String {
    let scene = std::fs::read_to_string(root().join("scenarios/rear_end_queue.scn")).expect("library scene");
    let at = scene.find("    expect {").expect("the scene has an expect block");
    format!("{}    expect {{\n{expect}\n    }}\n}}\n", &scene[..at])
}

fn scene_dir(name: &str, expect: &str) -> TempDir {
    let d = tmp(name);
    std::fs::write(d.join("queue.scn"), rear_end(expect)).expect("write scene");
    d
}

#[test]
fn the_bundled_library_passes_rocc_test() {
    let o = rocc(&["test", root().join("scenarios").to_str().expect("utf-8")], "");
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}{err}");
    let n = std::fs::read_dir(root().join("scenarios"))
        .expect("scenarios")
        .filter(|e| e.as_ref().is_ok_and(|e| e.path().extension().is_some_and(|x| x == "scn")))
        .count();
    assert!(out.contains(&format!("{n} of {n} scenario(s) passed")), "{out}");
    // Every scene states what it is for.
    for line in out.lines().filter(|l| l.starts_with("ok ")) {
        assert!(!line.contains(": 0 of 0 expectation"), "a library scene without expectations: {line}");
    }
}

#[test]
fn failing_expectations_point_at_their_line_with_time_and_value() {
    let d = scene_dir(
        "fail",
        "        no_contact\n        contact striker with ego on front\n        stopped striker before stop_line during 0..2 s\n        speed striker at_most 30 km/h during 0..2 s\n        gap first with ego at_least 5 m\n        reach ego junction by 3 s",
    );
    let o = rocc(&["test", d.to_str().expect("utf-8"), "--accept"], "");
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}{err}");
    assert!(out.contains("FAIL") && out.contains("0 of 6 expectation(s) hold"), "{out}");
    // The crash lands at 3.0 s on the ego's rear.
    assert!(err.contains("E1011") && err.contains("ego's rear touches striker's front at t = 3.0 s"), "{err}");
    assert!(err.contains("E1010") && err.contains("contact at t = 3.0 s on ego's rear, not its front"), "{err}");
    assert!(err.contains("E1013") && err.contains("it never stops: slowest"), "{err}");
    assert!(err.contains("E1015") && err.contains("45.0 km/h at t = 0.0 s"), "{err}");
    // The impact shunts the ego into `first`.
    assert!(err.contains("E1012") && err.contains("closest 0.00 m apart, at t = 3.4 s"), "{err}");
    assert!(err.contains("E1014") && err.contains("short of the junction"), "{err}");
    // Each report points at its line of the file.
    assert!(err.contains("queue.scn:31:9"), "{err}");
    // `--accept` still wrote the snapshot (expectations and snapshots are separate verdicts).
    assert!(d.join("snapshots/queue.snap").is_file());
}

#[test]
fn bad_expectations_are_check_errors() {
    for (expect, code, says) in [
        ("        contact strikr with ego", "E0107", "`strikr` names no agent"),
        ("        contact striker with ego by 8 s", "E1001", "outside the clip"),
        ("        contact striker with ego by 1..2 s", "E1001", "`by` takes one time"),
        ("        gap ego with ego at_least 1 m", "E1003", "names `ego` twice"),
        ("        stopped ego before center during 0..9 s", "E1001", "the clip runs 0..6 s"),
        ("        contact striker with ego on behind", "E0116", "unknown side of a box `behind`"),
        ("        speed ego at_most 30 m", "E0101", "speed bound needs"),
    ] {
        let d = scene_dir("bad", expect);
        let o = rocc(&["test", d.to_str().expect("utf-8")], "");
        let (out, err) = text(&o);
        assert_eq!(o.status.code(), Some(1), "{expect}: {out}{err}");
        assert!(err.contains(code) && err.contains(says), "{expect}: {err}");
        assert!(out.contains("snapshot not run"), "{expect}: {out}");
        assert!(!d.join("snapshots").exists(), "{expect}: a snapshot of a scene that does not check");
    }
    // A landmark needs an agent on a lane of a road that has it.
    let d = tmp("landmark");
    let scene = "scenario s {\n    duration 2 s\n    road straight { lanes 1 }\n    agent a: sedan { at west.in[1], 10 m before center }\n    agent w: pedestrian { at (0 m, 20 m) }\n    expect {\n        stopped a before stop_line\n        reach w center by 1 s\n    }\n}\n";
    std::fs::write(d.join("s.scn"), scene).expect("write");
    let (_, err) = text(&rocc(&["test", d.to_str().expect("utf-8")], ""));
    assert!(err.contains("E1002") && err.contains("a straight road has no stop lines"), "{err}");
    assert!(err.contains("`w` is not placed on a lane"), "{err}");
}

#[test]
fn stopped_before_center_sees_a_car_that_drove_past_it() {
    // A straight road's in-lane ends at its centre; the front is measured on past it.
    let d = tmp("past-center");
    let scene = "scenario s {\n    duration 4 s\n    road straight { lanes 1 }\n    agent car: sedan {\n        at west.in[1], 10 m before center\n        speed 10 m/s\n        goal { speed 10 m/s; stop after 25 m }\n    }\n    expect {\n        stopped car before center during 3..4 s\n        reach car center by 1 s\n    }\n}\n";
    std::fs::write(d.join("s.scn"), scene).expect("write");
    let (out, err) = text(&rocc(&["test", d.to_str().expect("utf-8"), "--accept"], ""));
    assert!(out.contains("1 of 2 expectation(s) hold"), "{out}{err}");
    assert!(err.contains("E1013") && err.contains("its front passes the center by 13.42 m at t = 3.0 s"), "{err}");
}

#[test]
fn snapshots_are_written_compared_and_reviewed() {
    let d = scene_dir("review", "        contact striker with ego on rear");
    let dir = d.to_str().expect("utf-8");
    let snap = d.join("snapshots/queue.snap");
    let o = rocc(&["test", dir], "");
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).1.contains("E1021"), "{}", text(&o).1);
    assert!(!snap.exists(), "a plain run writes nothing");

    assert!(rocc(&["test", dir, "--accept"], "").status.success());
    let first = std::fs::read_to_string(&snap).expect("snapshot");
    assert!(
        first.starts_with("---\nsource: queue.scn\nexpression: rocc test\n---\nscenario rear_end_queue"),
        "{first}"
    );
    assert!(first.contains("  ok   contact striker with ego on rear\n"), "{first}");
    // The striker and the ego part within the impact's window; the ego is shunted into `first`.
    assert!(first.contains("contacts\n  frames 30..31: ego (rear) with striker (front)\n"), "{first}");
    assert!(first.contains("digests (first ego; BEV, procedural occupancy)\n  frame 0: bev "), "{first}");
    assert!(std::fs::read_dir(d.join("snapshots")).expect("dir").count() == 1, "a temporary file was left");
    assert!(rocc(&["test", dir], "").status.success());

    // A change of behaviour: another start speed for the striker.
    let changed = rear_end("        contact striker with ego on rear")
        .replace("speed 45 km/h\n        goal", "speed 40 km/h\n        goal");
    std::fs::write(d.join("queue.scn"), changed).expect("write");
    let o = rocc(&["test", dir, "--pending"], "");
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}{err}");
    assert!(out.contains("snapshot differs") && err.contains("E1020"), "{out}{err}");
    assert!(err.lines().any(|l| l.starts_with("-       0: 5.25, -64.00, 90.0, 12.50")), "{err}");
    assert!(err.lines().any(|l| l.starts_with("+       0: 5.25, -64.00, 90.0, 11.11")), "{err}");
    assert!(d.join("snapshots/queue.snap.new").is_file(), "--pending leaves a file for `cargo insta review`");

    // Review: skip, then reject, keep the old snapshot; accept takes the new one.
    let o = rocc(&["test", dir, "--review"], "s\n");
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).1.contains("accept (a), reject (r) or skip (s)?"));
    assert!(d.join("snapshots/queue.snap.new").is_file(), "skip keeps the pending file");
    assert_eq!(rocc(&["test", dir, "--review"], "r\n").status.code(), Some(1));
    assert_eq!(std::fs::read_to_string(&snap).expect("snapshot"), first);
    assert!(!d.join("snapshots/queue.snap.new").exists(), "reject removes the pending file");
    assert!(rocc(&["test", dir, "--review"], "a\n").status.success());
    assert_ne!(std::fs::read_to_string(&snap).expect("snapshot"), first);
    assert!(rocc(&["test", dir], "").status.success());
}

#[test]
fn foreign_or_corrupt_snapshots_are_refused_and_kept() {
    for (name, content, says) in [
        ("corrupt", "not a snapshot\n", "no `---` header"),
        ("foreign", "---\nsource: tests/x.rs\nexpression: summary(&f)\n---\nbody\n", "`expression: summary(&f)`"),
    ] {
        let d = scene_dir(name, "        contact striker with ego");
        std::fs::create_dir_all(d.join("snapshots")).expect("dir");
        std::fs::write(d.join("snapshots/queue.snap"), content).expect("write");
        let o = rocc(&["test", d.to_str().expect("utf-8"), "--accept"], "");
        let (out, err) = text(&o);
        assert_eq!(o.status.code(), Some(1), "{out}{err}");
        // The report wraps at 80 columns wherever the temporary path's length puts the break.
        let flat = err.replace('│', " ").split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(flat.contains("E1022") && flat.contains(says), "{err}");
        assert_eq!(std::fs::read_to_string(d.join("snapshots/queue.snap")).expect("kept"), content);
    }
    // Headers that `cargo insta` adds are read past.
    let d = scene_dir("insta", "        contact striker with ego");
    assert!(rocc(&["test", d.to_str().expect("utf-8"), "--accept"], "").status.success());
    let snap = d.join("snapshots/queue.snap");
    let s = std::fs::read_to_string(&snap)
        .expect("snapshot")
        .replace("expression: rocc test\n", "expression: rocc test\nsnapshot_kind: text\n");
    std::fs::write(&snap, s).expect("write");
    assert!(rocc(&["test", d.to_str().expect("utf-8")], "").status.success());
}

#[test]
fn junit_and_json_reports() {
    let d = scene_dir("reports", "        contact striker with ego on rear\n        no_contact");
    let dir = d.to_str().expect("utf-8");
    let junit = d.join("report.xml");
    let o = rocc(&["test", dir, "--junit", junit.to_str().expect("utf-8"), "--message-format", "json"], "");
    assert_eq!(o.status.code(), Some(1));
    let xml = std::fs::read_to_string(&junit).expect("junit");
    assert!(xml.contains("<testsuite name=\"rocc test\" tests=\"3\" failures=\"2\">"), "{xml}");
    assert!(xml.contains("name=\"expect contact striker with ego on rear\"/>"), "{xml}");
    assert!(xml.contains("name=\"expect no_contact\">\n    <failure message=\""), "{xml}");
    let (out, _) = text(&o);
    let lines: Vec<serde_json::Value> = out.lines().map(|l| serde_json::from_str(l).expect("JSON line")).collect();
    let test = lines.iter().find(|v| v["type"] == "test").expect("a test line");
    assert_eq!(test["ok"], false);
    assert_eq!(test["snapshot"], "missing");
    assert_eq!(test["expectations"][1], serde_json::json!({"expect": "no_contact", "ok": false}));
    assert!(lines.iter().any(|v| v["type"] == "diagnostic" && v["code"] == "E1011"), "{out}");
    assert_eq!(lines.last().expect("summary")["type"], "summary");
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    let lib = root().join("scenarios");
    let run = |threads: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_rocc"))
            .args(["test", lib.to_str().expect("utf-8"), "--message-format", "json"])
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .expect("run");
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    assert_eq!(run("1"), run("3"));
}

#[test]
fn nothing_to_test_is_an_error() {
    let d = tmp("empty");
    let (_, err) = text(&rocc(&["test", d.to_str().expect("utf-8")], ""));
    assert!(err.contains("E1023") && err.contains("holds no .scn file"), "{err}");
    let (_, err) = text(&rocc(&["test", d.join("missing.scn").to_str().expect("utf-8")], ""));
    assert!(err.contains("E1023") && err.contains("no such file"), "{err}");
}
