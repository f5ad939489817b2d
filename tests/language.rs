//! The `.scn` language end to end: every scenario checks (snapshot of the checked scenario),
//! every invalid file fails with its expected code (snapshot of the rendered diagnostic), and
//! the formatter is idempotent, keeps comments and never changes meaning.

use rocc::check::{self, scenario::Scenario};
use rocc::diag::Diagnostic;
use rocc::source::SourceMap;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn scn_files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()))
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "scn"))
        .collect();
    v.sort();
    v
}

/// Check a file under a stable display name (so snapshots do not contain machine paths).
fn check_named(path: &Path) -> (Result<Scenario, Vec<Diagnostic>>, SourceMap) {
    let text = std::fs::read_to_string(path).expect("read scenario");
    let name = path.strip_prefix(root()).or_else(|_| path.strip_prefix(root().join(".."))).unwrap_or(path);
    let mut sources = SourceMap::default();
    let r = check::check_text(&name.display().to_string(), &text, path.parent().expect("file has a dir"), &mut sources);
    (r, sources)
}

fn corpus() -> Vec<PathBuf> {
    let mut v = scn_files(&root().join("scenarios"));
    v.extend(scn_files(&root().join("tests/fixtures/examples")));
    v
}

#[test]
fn every_scenario_checks_and_matches_its_snapshot() {
    for path in scn_files(&root().join("scenarios")) {
        let (r, sources) = check_named(&path);
        let s = r.unwrap_or_else(|d| {
            panic!("{} failed:\n{}", path.display(), d.iter().map(|d| d.render_plain(&sources)).collect::<String>())
        });
        let name = path.file_stem().expect("stem").to_string_lossy().into_owned();
        insta::assert_ron_snapshot!(format!("checked_{name}"), s);
    }
}

#[test]
fn shared_examples_check_unchanged() {
    for path in scn_files(&root().join("tests/fixtures/examples")) {
        let (r, sources) = check_named(&path);
        if let Err(d) = r {
            panic!("{} failed:\n{}", path.display(), d.iter().map(|d| d.render_plain(&sources)).collect::<String>());
        }
    }
}

#[test]
fn ast_snapshot_of_a_representative_file() {
    let path = root().join("scenarios/deer_crossing.scn");
    let text = std::fs::read_to_string(&path).expect("read");
    let ast = rocc::syntax::parse(0, &text).expect("parses");
    insta::assert_ron_snapshot!("ast_deer_crossing", ast);
}

/// Expected (code, words in the message or help) of the shared invalid examples; their first
/// line describes the error in prose.
const SHARED_INVALID: &[(&str, &str, &[&str])] = &[
    ("car_on_sidewalk.scn", "E0201", &["vehicle", "sidewalk"]),
    ("lane_out_of_range.scn", "E0112", &["lane 3", "2 lanes per direction"]),
    ("self_conflict.scn", "E0114", &["two different agents"]),
    ("syntax_error.scn", "E0001", &["expected `}`"]),
    ("unit_mismatch.scn", "E0101", &["`5 m`", "m/s, km/h or mph"]),
    ("unknown_agent.scn", "E0107", &["frnt", "did you mean `front`"]),
];

fn render_all(d: &[Diagnostic], sources: &SourceMap) -> String {
    d.iter().map(|d| d.render_plain(sources)).collect()
}

#[test]
fn shared_invalid_examples_fail_with_the_described_error() {
    for (file, code, words) in SHARED_INVALID {
        let path = root().join("tests/fixtures/examples/invalid").join(file);
        let (r, sources) = check_named(&path);
        let diags = r.err().unwrap_or_else(|| panic!("{file} should fail"));
        let d = &diags[0];
        assert_eq!(d.code, *code, "{file}: {}", render_all(&diags, &sources));
        let text = format!("{} {}", d.message, d.help.clone().unwrap_or_default());
        for w in *words {
            assert!(text.contains(w), "{file}: `{w}` not in `{text}`");
        }
        assert!(d.span().is_some(), "{file}: diagnostic has no span");
        insta::assert_snapshot!(format!("invalid_shared_{file}"), render_all(&diags, &sources));
    }
    // The parse error points at the `{` that was left open (line 5), not at EOF, and labels the
    // statement after the unclosed block (line 6).
    let path = root().join("tests/fixtures/examples/invalid/syntax_error.scn");
    let (r, sources) = check_named(&path);
    let d = &r.expect_err("fails")[0];
    let file = d.labels[0].span.file;
    assert_eq!(sources.line_col(file, d.labels[0].span.start as usize).0, 5);
    assert_eq!(&sources.text(file)[d.labels[0].span.range()], "{");
    assert_eq!(sources.line_col(file, d.labels[1].span.start as usize).0, 6);
}

#[test]
fn own_invalid_files_fail_with_the_code_in_their_first_line() {
    let files = scn_files(&root().join("tests/invalid"));
    assert!(files.len() >= 20, "the invalid corpus shrank");
    for path in files {
        let text = std::fs::read_to_string(&path).expect("read");
        let first = text.lines().next().unwrap_or_default();
        let rest = first
            .strip_prefix("// expect ")
            .unwrap_or_else(|| panic!("{}: first line must be `// expect CODE: words`", path.display()));
        let (code, words) = rest.split_once(": ").expect("`CODE: words`");
        let (r, sources) = check_named(&path);
        // As `rocc check` does: a file that checks goes through the front (sample to rollout),
        // which reports what only the map and the motion can tell (an unstageable conflict).
        let r = r.and_then(|s| rocc::compile::front(s, None).map(|_| ()));
        let diags = r.err().unwrap_or_else(|| panic!("{} should fail", path.display()));
        let d = &diags[0];
        let all = render_all(&diags, &sources);
        assert_eq!(d.code, code, "{}: {all}", path.display());
        let text = format!("{} {}", d.message, d.help.clone().unwrap_or_default());
        assert!(text.contains(words), "{}: `{words}` not in `{text}`", path.display());
        assert!(!d.labels.is_empty(), "{}: no span", path.display());
        let name = path.file_name().expect("name").to_string_lossy().into_owned();
        insta::assert_snapshot!(format!("invalid_{name}"), all);
    }
}

#[test]
fn json_diagnostics_carry_code_span_position_and_help() {
    let path = root().join("tests/fixtures/examples/invalid/unknown_agent.scn");
    let (r, sources) = check_named(&path);
    let d = &r.expect_err("fails")[0];
    let j = d.to_json(&sources);
    assert_eq!(j["code"], "E0107");
    assert_eq!(j["span"]["line"], 6);
    assert_eq!(j["help"], "did you mean `front`?");
    let (start, end) =
        (j["span"]["start"].as_u64().expect("start") as usize, j["span"]["end"].as_u64().expect("end") as usize);
    assert_eq!(&sources.text(d.labels[0].span.file)[start..end], "frnt");
    assert!(j["file"].as_str().expect("file").ends_with("unknown_agent.scn"));
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("reading {}: {e}", dir.display())) {
        let p = e.expect("entry").path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn explain_covers_every_code_the_sources_emit() {
    let mut files = vec![];
    rust_files(&root().join("src"), &mut files);
    assert!(files.iter().any(|p| p.ends_with("src/road/mod.rs")), "the walk must reach every pass folder");
    let mut missing = vec![];
    for p in files {
        let text = std::fs::read_to_string(&p).expect("read source");
        for (i, _) in text.match_indices("\"E0") {
            let code = &text[i + 1..(i + 6).min(text.len())];
            if rocc::diag::codes::lookup(code).is_none() {
                missing.push(format!("{code} in {}", p.display()));
            }
        }
    }
    assert!(missing.is_empty(), "codes without an explanation: {missing:?}");
}

#[test]
fn explanations_keep_the_indentation_of_their_examples() {
    // A `\` continuation before an indented line strips the indentation from the printed text.
    let mut files: Vec<_> = std::fs::read_dir(root().join("src/diag/codes"))
        .expect("read src/diag/codes")
        .map(|e| e.expect("entry").path())
        .collect();
    files.sort();
    assert!(files.len() > 5, "the code tables: {files:?}");
    let src: String = files.iter().map(|f| std::fs::read_to_string(f).expect("read a code table")).collect();
    let bad: Vec<&str> = src
        .split("\\\n")
        .skip(1)
        .filter(|rest| rest.starts_with(' '))
        .map(|rest| rest.lines().next().unwrap_or_default())
        .collect();
    assert!(bad.is_empty(), "indented lines after a `\\` continuation lose their indentation: {bad:?}");
    let e0001 = rocc::diag::codes::lookup("E0001").expect("E0001").explanation;
    assert!(e0001.contains("\n\n    agent ego: sedan {"), "{e0001}");
    // Every explanation shows an example: an indented line.
    let bare: Vec<&str> = rocc::diag::codes::all()
        .filter(|c| !c.explanation.lines().any(|l| l.starts_with("    ")))
        .map(|c| c.code)
        .collect();
    assert!(bare.is_empty(), "explanations without an example: {bare:?}");
}

fn comments(text: &str) -> Vec<String> {
    text.lines().filter_map(|l| l.find("//").map(|i| l[i..].trim_end().to_string())).collect()
}

#[test]
fn formatting_is_idempotent_keeps_comments_and_meaning() {
    for path in corpus() {
        let text = std::fs::read_to_string(&path).expect("read");
        let once = rocc::syntax::format_source(&text).expect("formats");
        let twice = rocc::syntax::format_source(&once).expect("formats again");
        assert_eq!(once, twice, "{}: not idempotent", path.display());
        assert_eq!(comments(&text), comments(&once), "{}: comments changed", path.display());
        let dir = path.parent().expect("dir");
        let a = check::check_text("a.scn", &text, dir, &mut SourceMap::default()).expect("original checks");
        let b = check::check_text("a.scn", &once, dir, &mut SourceMap::default()).expect("formatted checks");
        // Compared as serialised data: spans (which formatting moves) are not part of the meaning.
        let (a, b) = (ron::to_string(&a).expect("ron"), ron::to_string(&b).expect("ron"));
        assert_eq!(a, b, "{}: formatting changed the checked scenario", path.display());
    }
}

/// A blank line after a statement whose optional tail is absent (a bare number) is kept the same
/// way on every pass, with or without a `;` after it.
#[test]
fn blank_line_after_a_bare_number_is_kept_once_and_for_all() {
    for src in [
        "scenario x {\n    seed 1\n    rate 1;\n\n    road straight { lanes 1 }\n}\n",
        "scenario x {\n    seed 1\n    rate 1\n\n    road straight { lanes 1 }\n}\n",
    ] {
        let once = rocc::syntax::format_source(src).expect("formats");
        assert!(once.contains("rate 1\n\n    road"), "blank line lost:\n{once}");
        assert_eq!(rocc::syntax::format_source(&once).expect("formats again"), once, "not idempotent");
    }
}

#[test]
fn scenario_library_is_canonically_formatted() {
    let mut files = scn_files(&root().join("scenarios"));
    files.extend(scn_files(&root().join("scenarios/kinds")));
    files.extend(scn_files(&root().join("scenarios/rare")));
    files.push(root().join("stdlib/kinds.scn"));
    for path in files {
        let text = std::fs::read_to_string(&path).expect("read");
        assert_eq!(rocc::syntax::format_source(&text).expect("formats"), text, "run `rocc fmt {}`", path.display());
    }
}

#[test]
fn formatter_expands_long_blocks_and_keeps_blank_lines() {
    let src = "scenario s { duration 4 s\n\n\n  road straight { lanes 2; lane_width 3.5 m; speed_limit 50 km/h; shoulder 2.0 m; median 1.0 m; sidewalks on }   // wide\n agent ego: sedan { at west.in[1], 20 m before center } }\n";
    let out = rocc::syntax::format_source(src).expect("formats");
    insta::assert_snapshot!("fmt_expand", out);
}

/// A `use` path that stays under the root textually but leaves it through a symbolic link is
/// refused, and the outside file's text never reaches a diagnostic.
#[cfg(unix)]
#[test]
fn import_through_a_symlink_out_of_the_root_is_refused() {
    let tmp = std::env::temp_dir().join(format!("rocc-symlink-{}", std::process::id()));
    let (root_dir, outside) = (tmp.join("project"), tmp.join("outside"));
    std::fs::create_dir_all(root_dir.join("kinds")).expect("mkdir");
    std::fs::create_dir_all(&outside).expect("mkdir");
    std::fs::write(outside.join("passwd"), "root:x:0:0:secret-line\n").expect("write");
    std::os::unix::fs::symlink(&outside, root_dir.join("kinds/etc")).expect("symlink");
    let text = "use \"kinds/etc/passwd\"\nscenario s { road straight { lanes 1 } }\n";
    let mut sources = SourceMap::default();
    let r = check::check_text("s.scn", text, &root_dir, &mut sources);
    let _ = std::fs::remove_dir_all(&tmp);
    let diags = r.expect_err("an import through an escaping symlink must fail");
    assert_eq!(diags[0].code, "E0004", "{}", render_all(&diags, &sources));
    assert!(diags[0].message.contains("symbolic link"), "{}", diags[0].message);
    let all = render_all(&diags, &sources);
    assert!(!all.contains("secret-line"), "outside file leaked into a diagnostic: {all}");
}

/// Every (impact, point) pair: E0120 exactly for the pairs outside `points_for`, and the table
/// `rocc explain E0120` prints lists the same points.
#[test]
fn impact_point_table_is_enforced_and_explained() {
    use rocc::check::scenario::{IMPACTS, POINTS};
    let explanation = rocc::diag::codes::lookup("E0120").expect("E0120").explanation;
    let mut rejected = 0;
    for (iname, imp) in IMPACTS {
        let fits = rocc::check::points_for(imp);
        let row = explanation
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("impact {iname} ")))
            .unwrap_or_else(|| panic!("no row for {iname} in E0120's table"));
        for (pname, pt) in POINTS {
            let listed = row.contains("any point") || row.split(['|', ' ']).any(|w| w == pname);
            assert_eq!(listed, fits.contains(&pt), "E0120 table row `{row}` vs points_for for {pname}");
            // The struck agent fits the impact type (a pedestrian, a static object, a car).
            let struck = match imp {
                rocc::check::scenario::Impact::Pedestrian => "pedestrian",
                rocc::check::scenario::Impact::Object => "barrier",
                _ => "sedan",
            };
            let text = format!(
                "scenario t {{ duration 6 s; road straight {{ lanes 1; sidewalks on }}
                  agent a: sedan {{ at west.in[1], 40 m before center; speed 30 km/h; goal {{ speed 30 km/h }} }}
                  agent b: {struck} {{ at west.in[1], 10 m before center }}
                  conflict {{ at_fault a; struck b; impact {iname}; point {pname} }} }}"
            );
            let mut sources = SourceMap::default();
            let r = check::check_text("t.scn", &text, &root(), &mut sources);
            let codes: Vec<&str> = r.as_ref().err().map(|d| d.iter().map(|d| d.code).collect()).unwrap_or_default();
            assert_eq!(codes.contains(&"E0120"), !fits.contains(&pt), "{iname} / {pname}: {codes:?}");
            rejected += usize::from(!fits.contains(&pt));
            if fits.contains(&pt) {
                assert!(r.is_ok(), "{iname} / {pname}: {codes:?}");
            }
        }
    }
    assert_eq!(rejected, 5 + 5 + 2 + 2, "rear_end and head_on reject five points, angle and sideswipe two");
}

/// `rocc explain | head -1` and friends: a reader that closes its end of the pipe before rocc
/// writes ends the command quietly (exit 0, nothing on stderr) instead of a panic about a broken
/// pipe. The read end is closed before the spawn, so the first stdout write meets EPIPE whatever
/// the scheduling (closing it after the spawn races a fast command that fits the pipe buffer).
#[test]
fn stdout_commands_exit_quietly_when_the_reader_goes_away() {
    use std::process::{Command, Stdio};
    let dir = std::env::temp_dir().join(format!("rocc-pipe-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let messy = dir.join("messy.scn");
    std::fs::write(&messy, "scenario m { duration 4 s\nroad straight { lanes 1 } }\n").expect("write");
    let bad = root().join("tests/fixtures/examples/invalid/unknown_agent.scn");
    let cases: Vec<Vec<String>> = vec![
        vec!["explain".into()],
        vec!["explain".into(), "E0120".into()],
        vec!["grammar".into()],
        vec!["check".into(), "--message-format".into(), "json".into(), bad.display().to_string()],
        vec!["fmt".into(), "--check".into(), messy.display().to_string()],
    ];
    for args in cases {
        let (reader, writer) = std::io::pipe().expect("pipe");
        drop(reader);
        let out = Command::new(env!("CARGO_BIN_EXE_rocc"))
            .args(&args)
            .stdout(writer)
            .stderr(Stdio::piped())
            .output()
            .expect("run rocc");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!stderr.contains("panicked"), "rocc {args:?} panicked: {stderr}");
        assert_eq!(out.status.code(), Some(0), "rocc {args:?}: {stderr}");
        assert!(stderr.is_empty(), "rocc {args:?} wrote to stderr: {stderr}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `stop behind NAME` (E0206): leaders that are ahead, or that enter the route ahead, pass;
/// leaders behind, beside or across do not; a `change_lane` agent's route is the lane it moves to. Judged by the place pass on the placed poses.
#[test]
fn stop_behind_needs_a_leader_ahead_on_the_route() {
    let front_codes = |body: &str| -> Vec<&'static str> {
        let text = format!("scenario t {{ duration 4 s\n{body}\n}}");
        let mut sources = SourceMap::default();
        let s = check::check_text("t.scn", &text, &root(), &mut sources)
            .unwrap_or_else(|d| panic!("{body}: {}", render_all(&d, &sources)));
        rocc::compile::front(s, None).err().map(|d| d.iter().map(|d| d.code).collect()).unwrap_or_default()
    };
    let ok = [
        // Ahead in the lane, at the lane edge (a cyclist with an offset), ahead past the junction.
        "road straight { lanes 1 }
         agent a: sedan { at west.in[1], 30 m before center; speed 20 km/h; goal { stop behind b } }
         agent b: bicycle { at west.in[1], 10 m before center offset 1.2 m right; speed 10 km/h }",
        "road four_way { lanes 1 }
         agent a: sedan { at south.in[1], 20 m before stop_line; speed 20 km/h; goal { turn straight; stop behind b } }
         agent b: sedan { at north.out[1], 10 m after junction; speed 10 km/h }",
        // Joins ahead: a left turn from the west into a's exit lane; a merge from the ramp; a
        // lane change into a's lane; a pedestrian crossing in front.
        "road four_way { lanes 1 }
         agent a: sedan { at south.in[1], 30 m before stop_line; speed 20 km/h; goal { turn straight; stop behind b } }
         agent b: sedan { at west.in[1], 5 m before stop_line; speed 15 km/h; goal { turn left } }",
        "road merge { lanes 2 }
         agent a: sedan { at main.in[2], 60 m before center; speed 20 km/h; goal { stop behind b } }
         agent b: sedan { at ramp.in[1], 20 m before center; speed 20 km/h }",
        "road straight { lanes 2 }
         agent a: sedan { at west.in[1], 40 m before center; speed 20 km/h; goal { stop behind b } }
         agent b: sedan { at west.in[2], 20 m before center; speed 15 km/h; goal { lateral change_lane left } }",
        "road straight { lanes 1; sidewalks on }
         agent a: sedan { at west.in[1], 40 m before center; speed 20 km/h; goal { stop behind p } }
         agent p: pedestrian { at sidewalk(west.in), 10 m before center; goal { speed 1.4 m/s; lateral cross } }",
        // Changing lane into the leader's lane: its route starts in the lane it moves to.
        "road straight { lanes 2 }
         agent a: sedan { at west.in[2], 40 m before center; speed 20 km/h; goal { lateral change_lane left; stop behind b } }
         agent b: sedan { at west.in[1], 20 m before center; speed 15 km/h }",
        // Placed by coordinates in west.in[1] at the apex of a U-shaped curve: its route is still
        // the lane's (the rollout's route function), so a leader 60 m on round the bend is ahead
        // (a straight ray from its pose passes 30 m from it).
        "road curve { lanes 1; radius 40 m; angle 180 deg }
         agent a: sedan { at (0 m, -1.75 m) heading 0 deg; speed 20 km/h; goal { stop behind b } }
         agent b: sedan { at east.out[1], 60 m after center; speed 10 km/h }",
    ];
    for body in ok {
        assert_eq!(front_codes(body), Vec::<&str>::new(), "{body}");
    }
    let bad = [
        // Behind; in the next lane; the other direction; crossing the junction; a static cone
        // on the shoulder beside the lane.
        "road straight { lanes 1 }
         agent a: sedan { at west.in[1], 10 m before center; speed 20 km/h; goal { stop behind b } }
         agent b: sedan { at west.in[1], 30 m before center; speed 20 km/h }",
        "road straight { lanes 2 }
         agent a: sedan { at west.in[1], 40 m before center; speed 20 km/h; goal { stop behind b } }
         agent b: sedan { at west.in[2], 20 m before center; speed 15 km/h }",
        "road straight { lanes 1 }
         agent a: sedan { at west.in[1], 40 m before center; speed 20 km/h; goal { stop behind b } }
         agent b: sedan { at east.in[1], 20 m before center; speed 15 km/h }",
        "road four_way { lanes 1 }
         agent a: sedan { at south.in[1], 20 m before stop_line; speed 20 km/h; goal { turn straight; stop behind b } }
         agent b: sedan { at east.in[1], 5 m before stop_line; speed 15 km/h; goal { turn straight } }",
        "road straight { lanes 1; shoulder 3 m }
         agent a: sedan { at west.in[1], 40 m before center; speed 20 km/h; goal { stop behind c } }
         object c: traffic_cone { at west.in[1], 20 m before center offset 3 m right }",
        // Ahead in the lane the agent leaves: it passes the leader, never queues behind it.
        "road straight { lanes 2 }
         agent a: sedan { at west.in[2], 40 m before center; speed 20 km/h; goal { lateral change_lane left; stop behind b } }
         agent b: sedan { at west.in[2], 20 m before center; speed 15 km/h }",
        // The same car: a cone 30 m straight ahead of it, off the road where its lane has bent
        // 11 m away, is not on its route (a straight ray from its pose would meet it).
        "road curve { lanes 1; radius 40 m; angle 180 deg }
         agent a: sedan { at (0 m, -1.75 m) heading 0 deg; speed 20 km/h; goal { stop behind c } }
         object c: traffic_cone { at (30 m, -1.75 m) }",
    ];
    for body in bad {
        assert_eq!(front_codes(body), ["E0206"], "{body}");
    }
}
