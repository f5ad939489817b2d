//! `rocc ciren`: snapshots of the generated scenario of every bundled CIREN case (`tests/fixtures/`) and SAFE
//! extraction; the staged contact measured on the rolled-out boxes against the source's own
//! statement of the damaged parts (CIREN: `external.csv`, SAFE: `point_of_impact`); bad inputs
//! (malformed, missing, unknown, non-UTF-8, huge) give diagnostics and write nothing while the
//! rest of the batch goes on.

#[path = "support/contact.rs"]
mod contact;

use contact::{measured_contact, obb, sector};
use rocc::check::scenario::Point;
use rocc::ciren::{self, Imported};
use rocc::rollout::Tracks;
use rocc::source::SourceMap;
use std::path::{Path, PathBuf};

fn dirs(root: &str, want_dir: bool) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root)
        .expect("test fixtures")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            if want_dir { p.join("crash_report.xml").is_file() } else { p.extension().is_some_and(|e| e == "json") }
        })
        .collect();
    v.sort();
    v
}

fn rendered(diags: &[rocc::diag::Diagnostic], sources: &SourceMap) -> String {
    diags.iter().map(|d| d.render_plain(sources)).collect::<Vec<_>>().join("")
}

/// The imported text, then the warnings; or the diagnostics of a case that does not import.
fn snapshot_text(r: &Result<Imported, Vec<rocc::diag::Diagnostic>>, sources: &SourceMap) -> String {
    match r {
        Ok(imp) => {
            let w: Vec<String> = imp.warnings.iter().map(|d| format!("{} {}", d.code, d.message)).collect();
            format!("{}\n---- warnings ----\n{}\n", imp.staged.text, w.join("\n"))
        }
        Err(d) => format!("---- not imported ----\n{}", rendered(d, sources)),
    }
}

#[test]
fn every_bundled_ciren_case_imports_as_snapshotted() {
    let cases = dirs("tests/fixtures/ciren-cases", true);
    assert_eq!(cases.len(), 6);
    for p in cases {
        let mut sources = SourceMap::default();
        let r = ciren::import_case(&p, &mut sources);
        let id = p.file_name().and_then(|n| n.to_str()).unwrap_or("case").to_string();
        insta::assert_snapshot!(format!("ciren_{id}"), snapshot_text(&r, &sources));
    }
}

/// The VLM route's worked examples (prompts/ciren/) are this importer's output, so the model is
/// shown exactly what the deterministic route writes.
#[test]
fn the_vlm_worked_examples_are_the_importers_output() {
    let mut files: Vec<PathBuf> = std::fs::read_dir("prompts/ciren")
        .expect("prompts/ciren")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "scn"))
        .collect();
    files.sort();
    assert!(files.len() >= 2, "worked examples in prompts/ciren/");
    for f in files {
        let id = f.file_stem().and_then(|n| n.to_str()).expect("utf-8 name").to_string();
        let mut sources = SourceMap::default();
        let imp = ciren::import_case(&Path::new("tests/fixtures/ciren-cases").join(&id), &mut sources)
            .unwrap_or_else(|d| panic!("{}", rendered(&d, &sources)));
        let shown = std::fs::read_to_string(&f).expect("readable example");
        assert_eq!(shown, imp.staged.text, "{} differs from `rocc ciren import` output", f.display());
    }
}

#[test]
fn every_bundled_safe_extraction_imports_as_snapshotted() {
    let files = dirs("tests/fixtures/safe", false);
    assert_eq!(files.len(), 8);
    for p in files {
        let mut sources = SourceMap::default();
        let r = ciren::import_safe(&p, &mut sources);
        let id = p.file_stem().and_then(|n| n.to_str()).unwrap_or("safe").to_string();
        insta::assert_snapshot!(format!("safe_{id}"), snapshot_text(&r, &sources));
    }
}

// ------------------------------------------------------------------ contact sides

/// The damaged part of a vehicle as the source states it.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Part {
    Front,
    Left,
    Right,
    Rear,
}

fn part(word: &str) -> Option<Part> {
    match word.trim().to_ascii_lowercase().as_str() {
        "front" => Some(Part::Front),
        "left" | "left side" => Some(Part::Left),
        "right" | "right side" => Some(Part::Right),
        "rear" | "back" => Some(Part::Rear),
        _ => None,
    }
}

/// Run the front on an imported scenario and check each stated part against the latched contact:
/// the struck vehicle's sector is exactly the stated side; the striker touches with the stated
/// face (outer 40% of its box along that axis, as tests/rollout.rs checks a face).
fn check_contact(imp: &Imported, stated: &[(String, Part)]) -> Tracks {
    let mut sources = SourceMap::default();
    let scen = rocc::check::check_text(&imp.file_name(), &imp.staged.text, Path::new("."), &mut sources)
        .unwrap_or_else(|d| panic!("{}: {}", imp.crash.id, rendered(&d, &sources)));
    let front =
        rocc::compile::front(scen, None).unwrap_or_else(|d| panic!("{}: {}", imp.crash.id, rendered(&d, &sources)));
    let t = front.tracks;
    let rec = t.impacts.first().unwrap_or_else(|| panic!("{}: no impact", imp.crash.id));
    check_parts(&t, rec, stated, &imp.crash.id);
    t
}

/// The contact of impact `rec` on the parts `stated` (each vehicle's damaged part).
fn check_parts(t: &Tracks, rec: &rocc::rollout::ImpactRecord, stated: &[(String, Part)], id: &str) {
    let (af, st, f) = (rec.at_fault, rec.struck, rec.frame);
    let (in_struck, in_af) = measured_contact(t, af, st, f).expect("contact at the latched frame");
    let mut checked = 0;
    for (name, p) in stated {
        let Some(i) = t.agents.iter().position(|a| &a.name == name) else { continue };
        let s = t.agents[i].size;
        if i == st {
            let want = match p {
                Part::Front => Point::Front,
                Part::Left => Point::Left,
                Part::Right => Point::Right,
                Part::Rear => Point::Rear,
            };
            assert_eq!(sector(in_struck, s[0], s[1]), want, "{id}: struck {name} contact {in_struck}");
            assert_eq!(rec.struck_side, want, "{id}");
        } else if i == af {
            let ok = match p {
                Part::Front => in_af.x > 0.6 * s[0] / 2.0,
                Part::Left => in_af.y > 0.6 * s[1] / 2.0,
                Part::Right => in_af.y < -0.6 * s[1] / 2.0,
                Part::Rear => in_af.x < -0.6 * s[0] / 2.0,
            };
            assert!(ok, "{id}: striker {name} touches at {in_af}, not its {p:?}");
        } else {
            panic!("{id}: {name} is damaged in the source but not in the staged impact");
        }
        checked += 1;
    }
    assert!(checked >= 1, "{id}: nothing checked");
}

#[test]
fn ciren_contacts_land_on_the_sides_in_external_csv() {
    for p in dirs("tests/fixtures/ciren-cases", true) {
        let mut sources = SourceMap::default();
        let imp = ciren::import_case(&p, &mut sources).unwrap_or_else(|d| panic!("{}", rendered(&d, &sources)));
        // external.csv: one row per vehicle in sketch colour order (red = V1, blue = V2).
        let csv = std::fs::read_to_string(p.join("external.csv")).expect("external.csv");
        let stated: Vec<(String, Part)> = csv
            .lines()
            .skip(1)
            .enumerate()
            .filter_map(|(i, l)| Some((format!("v{}", i + 1), part(l.split(',').nth(1)?)?)))
            .collect();
        assert!(!stated.is_empty());
        let t = check_contact(&imp, &stated);
        // Both vehicles of a two-vehicle case are checked, not only one of them.
        let movers = t.agents.iter().filter(|a| a.name.starts_with('v') && !a.background).count();
        if movers == 2 {
            let rec = &t.impacts[0];
            let names = [&t.agents[rec.at_fault].name, &t.agents[rec.struck].name];
            assert!(stated.iter().filter(|(n, _)| names.contains(&n)).count() == 2, "{}", imp.crash.id);
        }
    }
}

#[test]
fn safe_contacts_land_on_the_parts_in_point_of_impact() {
    for p in dirs("tests/fixtures/safe", false) {
        let mut sources = SourceMap::default();
        let imp = ciren::import_safe(&p, &mut sources).unwrap_or_else(|d| panic!("{}", rendered(&d, &sources)));
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&p).expect("read")).expect("json");
        let poi = json["dsl"]["Conflict"]["point_of_impact"].as_str().expect("point_of_impact");
        check_contact(&imp, &stated_parts(poi));
    }
}

/// The "PART of Vn" phrases of a `point_of_impact`, read independently of the importer's parser.
fn stated_parts(poi: &str) -> Vec<(String, Part)> {
    let poi = poi.to_ascii_lowercase();
    let mut stated = Vec::new();
    for (i, _) in poi.match_indices(" of v") {
        let n = poi[i + 5..].chars().take_while(char::is_ascii_digit).collect::<String>();
        let before: Vec<&str> = poi[..i].split_whitespace().collect();
        let two = before.iter().rev().take(2).rev().copied().collect::<Vec<_>>().join(" ");
        let one = before.last().copied().unwrap_or("");
        if let Some(pt) = part(&two).or_else(|| part(one)) {
            stated.push((format!("v{n}"), pt));
        }
    }
    stated
}

/// SAFE extractions whose `Conflict` lists several impacts (tests/fixtures/safe-chains/: a
/// rear-end chain of three, a junction crash then a rear end into the struck car) import with
/// one conflict per entry, and on the rolled-out boxes each impact lands on the parts its
/// `point_of_impact` names, in the listed order; no pair outside the entries touches.
#[test]
fn every_impact_of_a_safe_list_lands_on_its_parts_in_order() {
    let files = dirs("tests/fixtures/safe-chains", false);
    assert_eq!(files.len(), 2);
    for p in files {
        let mut sources = SourceMap::default();
        let imp = ciren::import_safe(&p, &mut sources).unwrap_or_else(|d| panic!("{}", rendered(&d, &sources)));
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&p).expect("read")).expect("json");
        let list = json["dsl"]["Conflict"].as_array().expect("a list");
        let id = imp.crash.id.clone();
        let scen = rocc::check::check_text(&imp.file_name(), &imp.staged.text, Path::new("."), &mut sources)
            .unwrap_or_else(|d| panic!("{}", rendered(&d, &sources)));
        assert_eq!(scen.conflicts.len(), list.len(), "{id}: one conflict per entry");
        let t = rocc::compile::front(scen, None).expect("front").tracks;
        let mut frames = vec![];
        let mut pairs = vec![];
        for (i, c) in list.iter().enumerate() {
            let rec =
                t.impacts.iter().find(|r| r.conflict == i).unwrap_or_else(|| panic!("{id}: entry {i}: no impact"));
            let stated = stated_parts(c["point_of_impact"].as_str().expect("point_of_impact"));
            assert_eq!(stated.len(), 2, "{id}: entry {i} names both parts");
            check_parts(&t, rec, &stated, &id);
            // The first touch of the pair is this impact's, not an earlier graze.
            let first = (0..t.frames).find(|&f| obb(&t, rec.at_fault, f).overlaps(&obb(&t, rec.struck, f)));
            assert!(first.is_some_and(|f| f + 15 >= rec.frame), "{id}: entry {i} touched at {first:?}");
            frames.push(rec.frame);
            pairs.push((rec.at_fault.min(rec.struck), rec.at_fault.max(rec.struck)));
        }
        assert!(frames.windows(2).all(|w| w[0] < w[1]), "{id}: impacts out of order {frames:?}");
        for a in 0..t.agents.len() {
            for b in a + 1..t.agents.len() {
                let touch = (0..t.frames).any(|f| obb(&t, a, f).overlaps(&obb(&t, b, f)));
                assert!(pairs.contains(&(a, b)) || !touch, "{id}: {} and {} touch", t.agents[a].name, t.agents[b].name);
            }
        }
    }
}

#[test]
fn a_stopped_car_stays_stopped_until_struck() {
    let mut sources = SourceMap::default();
    let imp = ciren::import_safe(Path::new("tests/fixtures/ciren/safe_stopped.json"), &mut sources)
        .unwrap_or_else(|d| panic!("{}", rendered(&d, &sources)));
    let t = check_contact(&imp, &[("v1".into(), Part::Right), ("v2".into(), Part::Front)]);
    let v1 = t.agents.iter().position(|a| a.name == "v1").expect("v1");
    // Until the impact; from it on the impulse moves it.
    let hit = t.impacts.first().expect("impact").frame;
    assert!(t.speeds[v1][..hit].iter().all(|&s| s.abs() < 1e-9), "v1 moved: {:?}", t.speeds[v1]);
    assert_eq!(t.poses[v1][0], t.poses[v1][hit]);
    assert!(t.poses[v1][hit] != t.poses[v1][t.frames - 1], "the impact did not move v1");
}

// ------------------------------------------------------------------ bad inputs

#[test]
fn bad_case_records_give_specific_diagnostics() {
    let cases = [
        ("malformed.xml", "E0801"),
        ("missing_events.xml", "E0802"),
        ("not_a_case.xml", "E0802"),
        ("unknown_area.xml", "E0803"),
        ("unknown_body.xml", "E0803"),
        ("rollover.xml", "E0804"),
        ("back_strike.xml", "E0804"),
        ("not_utf8.xml", "E0800"),
    ];
    for (f, code) in cases {
        let mut sources = SourceMap::default();
        let p = Path::new("tests/fixtures/ciren").join(f);
        let d = ciren::import_case(&p, &mut sources).err().unwrap_or_else(|| panic!("{f} imported"));
        assert_eq!(d[0].code, code, "{f}");
        insta::assert_snapshot!(format!("bad_{f}"), rendered(&d, &sources));
    }
}

#[test]
fn bad_safe_extractions_give_specific_diagnostics() {
    let cases = [
        ("safe_not_json.json", "E0801"),
        ("safe_bad_speed.json", "E0803"),
        ("safe_bad_direction.json", "E0803"),
        ("safe_unknown_vehicle.json", "E0803"),
        ("safe_undecidable.json", "E0808"),
        ("safe_two_impacts.json", "E0804"),
    ];
    for (f, code) in cases {
        let mut sources = SourceMap::default();
        let p = Path::new("tests/fixtures/ciren").join(f);
        let d = ciren::import_safe(&p, &mut sources).err().unwrap_or_else(|| panic!("{f} imported"));
        assert_eq!(d[0].code, code, "{f}");
        insta::assert_snapshot!(format!("bad_{f}"), rendered(&d, &sources));
    }
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rocc-ciren-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("tmp");
    d
}

#[test]
fn a_huge_file_is_refused_before_it_is_read() {
    let d = tmp("huge");
    let p = d.join("crash_report.xml");
    // Sparse: the size is what matters, and it must be refused without reading it.
    let f = std::fs::File::create(&p).expect("create");
    f.set_len(ciren::case::MAX_CASE_BYTES + 1).expect("set_len");
    let mut sources = SourceMap::default();
    let e = ciren::import_case(&d, &mut sources).expect_err("refused");
    assert_eq!(e[0].code, "E0800");
    assert!(e[0].message.contains("case files up to"), "{}", e[0].message);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_batch_goes_on_past_bad_cases_and_writes_nothing_for_them() {
    let out = tmp("batch");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_rocc"))
        .args(["ciren", "import", "tests/fixtures/ciren-cases/100237", "tests/fixtures/ciren/malformed.xml"])
        .args(["tests/fixtures/ciren/rollover.xml", "tests/fixtures/ciren/not_utf8.xml", "no/such/case"])
        .args(["tests/fixtures/ciren-cases/117021", "-o"])
        .arg(&out)
        .output()
        .expect("run rocc");
    assert!(!status.status.success(), "failures must give a non-zero exit");
    let stderr = String::from_utf8_lossy(&status.stderr);
    assert!(stderr.contains("2 imported, 4 failed"), "{stderr}");
    let mut names: Vec<String> =
        std::fs::read_dir(&out).expect("out").filter_map(|e| e.ok()?.file_name().into_string().ok()).collect();
    names.sort();
    // The two good cases, and nothing else: no partial or temporary files.
    assert_eq!(names, ["100237.scn", "117021.scn"]);
    let _ = std::fs::remove_dir_all(&out);
}

/// A CIREN case and the SAFE extraction of the same case go to one directory as two files with
/// two scenario names (`117021.scn`: `ciren_117021`, `safe_117021.scn`: `safe_117021`).
#[test]
fn a_case_and_its_safe_extraction_import_side_by_side() {
    let out = tmp("both");
    for (sub, input) in
        [("import", "tests/fixtures/ciren-cases/117021"), ("import-safe", "tests/fixtures/safe/117021.json")]
    {
        let st = std::process::Command::new(env!("CARGO_BIN_EXE_rocc"))
            .args(["ciren", sub, input, "-o"])
            .arg(&out)
            .output()
            .expect("run rocc");
        assert!(st.status.success(), "{sub}: {}", String::from_utf8_lossy(&st.stderr));
    }
    let mut names: Vec<String> =
        std::fs::read_dir(&out).expect("out").filter_map(|e| e.ok()?.file_name().into_string().ok()).collect();
    names.sort();
    assert_eq!(names, ["117021.scn", "safe_117021.scn"]);
    let record = std::fs::read_to_string(out.join("117021.scn")).expect("record");
    let safe = std::fs::read_to_string(out.join("safe_117021.scn")).expect("safe");
    assert!(record.contains("scenario ciren_117021 {"), "{record}");
    assert!(safe.contains("scenario safe_117021 {"), "{safe}");
    assert!(record.contains("rocc ciren import`") && safe.contains("rocc ciren import-safe`"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn generated_files_check_format_and_are_deterministic() {
    let out = tmp("det");
    let run = || {
        let safe = std::process::Command::new(env!("CARGO_BIN_EXE_rocc"))
            .args(["ciren", "import-safe", "tests/fixtures/safe/117330.json", "tests/fixtures/safe/121520.json", "-o"])
            .arg(&out)
            .status()
            .expect("run rocc");
        // A party placed on a slide is written at a world point.
        let slide = std::process::Command::new(env!("CARGO_BIN_EXE_rocc"))
            .args(["ciren", "import", "tests/fixtures/ciren-slides/glanced-into-stopped-car.xml", "-o"])
            .arg(&out)
            .status()
            .expect("run rocc");
        safe.success() && slide.success()
    };
    assert!(run());
    let files = [out.join("safe_117330.scn"), out.join("safe_121520.scn"), out.join("900203.scn")];
    let first: Vec<String> = files.iter().map(|f| std::fs::read_to_string(f).expect("written")).collect();
    assert!(run());
    for (f, text) in files.iter().zip(&first) {
        assert_eq!(text, &std::fs::read_to_string(f).expect("written"));
    }
    let check =
        std::process::Command::new(env!("CARGO_BIN_EXE_rocc")).arg("check").args(&files).status().expect("check");
    assert!(check.success());
    let fmt = std::process::Command::new(env!("CARGO_BIN_EXE_rocc"))
        .args(["fmt", "--check"])
        .args(&files)
        .status()
        .expect("fmt");
    assert!(fmt.success(), "the emitter writes canonical layout");
    let _ = std::fs::remove_dir_all(&out);
}

// ------------------------------------------------------------------ generated records

/// A later contact of a generated record: vehicle `by` (3 brings a third vehicle) with its
/// `area` against `other` (0: a tree, or a pole when `pole`) and its `other_area`.
#[derive(Debug, Clone)]
struct Extra {
    by: u32,
    area: &'static str,
    other: u32,
    other_area: &'static str,
    dir: Option<&'static str>,
    pole: bool,
}

/// One coded record built from the fields the importer reads: the configuration, the narrated
/// directions, junction and road, the coded areas, movements and body types, and up to two
/// later contacts.
#[derive(Debug, Clone)]
struct Record {
    extras: Vec<Extra>,
    config: &'static str,
    junction: &'static str,
    relation: &'static str,
    alignment: &'static str,
    lanes: u32,
    dirs: [Option<&'static str>; 2],
    areas: [&'static str; 2],
    moves: [&'static str; 2],
    bodies: [&'static str; 2],
    /// V3 is coded stopped (a car a slide may run into).
    third_stopped: bool,
}

impl Record {
    fn xml(&self) -> String {
        let travel = |n: usize, word: &str| match self.dirs[n] {
            Some(d) => format!("Vehicle {word} (V{}) was traveling {d} in the {d}bound lane of a road. ", n + 1),
            None => format!("Vehicle {word} (V{}) was on a road. ", n + 1),
        };
        let summary = format!(
            "{}{}{}{}The front of V2 struck the {} of V1.",
            travel(0, "one"),
            travel(1, "two"),
            match self.extras.iter().find(|e| e.by == 3 || e.other == 3).and_then(|e| e.dir) {
                Some(d) => format!("Vehicle three (V3) was traveling {d} in the {d}bound lane. "),
                None => String::new(),
            },
            self.junction,
            self.areas[0].to_lowercase()
        );
        fn area_code(a: &str) -> &str {
            &a[..1]
        }
        let form = |n: usize| {
            format!(
                r#"<GeneralVehicleForm VehicleNumber="{v}">
      <Vehicle><BodyType value="1" sasCode="1">{body}</BodyType></Vehicle>
      <OfficialRecords><PoliceReport><TravelSpeed UOM="kmph" value="40" sasCode="40">40</TravelSpeed><PostedSpeedLimit UOM="kmph" value="50" sasCode="50">50</PostedSpeedLimit></PoliceReport></OfficialRecords>
      <Precrash><Trafficway><RelationToJunction value="1" sasCode="1">{rel}</RelationToJunction><RelationToFlow value="1" sasCode="4">Not physically divided (two way traffic)</RelationToFlow></Trafficway><Roadway><TravelLanes value="{l}" sasCode="{l}">{l}</TravelLanes><Alignment value="1" sasCode="1">{al}</Alignment></Roadway></Precrash>
      <Driver><PreeventMovement value="1" sasCode="01">{mv}</PreeventMovement></Driver>
    </GeneralVehicleForm>"#,
                v = n + 1,
                body = self.bodies[n % 2],
                rel = self.relation,
                l = self.lanes,
                al = self.alignment,
                mv = if n == 2 && self.third_stopped { "Stopped in traffic lane" } else { self.moves[n % 2] },
            )
        };
        format!(
            r#"<?xml version="1.0" encoding="UTF-8"?>
<Case CaseID="990001">
  <CaseForm>
    <CaseSummary>
      <CrashType value="1" sasCode="01">Vehicle to vehicle</CrashType>
      <Configuration value="2" sasCode="02">{cfg}</Configuration>
      <Summary>{summary}</Summary>
    </CaseSummary>
    <Events>
      <EventSum VehicleNumber="1" EventNumber="1"><Rank>1</Rank><Class value="2" sasCode="2">Compact</Class><AreaOfDamage value="1" sasCode="{a1c}">{a1}</AreaOfDamage><Contacted value="2" sasCode="2">Vehicle#2</Contacted><ContactedClass value="2" sasCode="2">Compact</ContactedClass><ContactedAreaOfDamage value="1" sasCode="{a2c}">{a2}</ContactedAreaOfDamage></EventSum>
      {later}
    </Events>
  </CaseForm>
  <GeneralVehicleForms>
    {f1}
    {f2}
    {f3}
  </GeneralVehicleForms>
</Case>
"#,
            cfg = self.config,
            a1 = self.areas[0],
            a1c = area_code(self.areas[0]),
            a2 = self.areas[1],
            a2c = area_code(self.areas[1]),
            f1 = form(0),
            f2 = form(1),
            f3 = if self.extras.iter().any(|e| e.by == 3 || e.other == 3) { form(2) } else { String::new() },
            later = self.extras.iter().enumerate().map(|(i, e)| {
                let contacted = if e.other == 0 && e.pole {
                    r#"<Contacted value="43" sasCode="43">Pole/post (&lt;= 10 cm in diameter)</Contacted><ContactedAreaOfDamage value="1" sasCode="0">Not a motor vehicle</ContactedAreaOfDamage>"#.to_string()
                } else if e.other == 0 {
                    r#"<Contacted value="42" sasCode="42">Tree(&gt; 10 cm in diameter)</Contacted><ContactedAreaOfDamage value="1" sasCode="0">Not a motor vehicle</ContactedAreaOfDamage>"#.to_string()
                } else {
                    format!(
                        r#"<Contacted value="{o}" sasCode="{o}">Vehicle#{o}</Contacted><ContactedAreaOfDamage value="1" sasCode="{c}">{a}</ContactedAreaOfDamage>"#,
                        o = e.other,
                        c = area_code(e.other_area),
                        a = e.other_area
                    )
                };
                format!(
                    r#"<EventSum VehicleNumber="{v}" EventNumber="{n}"><Rank>{n}</Rank><AreaOfDamage value="1" sasCode="{c}">{a}</AreaOfDamage>{contacted}</EventSum>"#,
                    v = e.by,
                    n = i + 2,
                    c = area_code(e.area),
                    a = e.area
                )
            }).collect::<Vec<_>>().join("\n      "),
        )
    }
}

fn record() -> impl proptest::strategy::Strategy<Value = Record> {
    use proptest::prelude::*;
    let dir = prop_oneof![Just(None), Just(Some("north")), Just(Some("south")), Just(Some("east")), Just(Some("west"))];
    let area = prop_oneof![Just("Front"), Just("Back"), Just("Left Side"), Just("Right Side")];
    let mv = prop_oneof![
        Just("Going Straight"),
        Just("Turning left"),
        Just("Turning right"),
        Just("Stopped in traffic lane"),
        Just("Unknown")
    ];
    let body = prop_oneof![Just("4-door sedan, hardtop"), Just("Compact utility"), Just("Pickup"), Just("Minivan")];
    let road = (
        prop_oneof![Just("Angle/sideswipe"), Just("Head-on"), Just("Rear end")],
        prop_oneof![
            Just(""),
            Just("It was approaching a 4-leg intersection. "),
            Just("It was approaching a T-intersection. ")
        ],
        prop_oneof![Just("Intersection related / non-interchange"), Just("Non-junction")],
        prop_oneof![Just("Straight"), Just("Curve right"), Just("Curve left")],
        1u32..=4,
    );
    // Mostly a third vehicle's front into the pair (a chain), often a tree or pole struck on the
    // slide after the first impact (by either vehicle of the pair, with any face), or a second
    // strike, into the third vehicle too (stopped or moving).
    let by = prop_oneof![2 => Just(3u32), 1 => 1u32..=2];
    let front_mostly = prop_oneof![3 => Just("Front"), 1 => area.clone()];
    let extra = (by, front_mostly, 0u32..=3, area.clone(), dir.clone(), proptest::bool::ANY).prop_map(
        |(by, area, other, other_area, dir, pole)| Extra {
            by,
            area,
            other: if other == by { 0 } else { other },
            other_area,
            dir,
            pole,
        },
    );
    let extras = proptest::collection::vec(extra, 0..=2);
    let parts = (road, [dir.clone(), dir], [area.clone(), area], [mv.clone(), mv], [body.clone(), body]);
    (parts, extras, proptest::bool::ANY).prop_map(
        |(((config, junction, relation, alignment, lanes), dirs, areas, moves, bodies), extras, third_stopped)| {
            Record { extras, config, junction, relation, alignment, lanes, dirs, areas, moves, bodies, third_stopped }
        },
    )
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 96, ..Default::default() })]

    /// Whatever a coded record says, the importer either stages it or refuses it with a reason:
    /// it never emits a scenario its own checker rejects.
    #[test]
    fn the_importer_never_emits_a_scenario_that_fails_to_check(r in record()) {
        let d = tmp(&format!("gen-{}", std::thread::current().name().unwrap_or("t").len()));
        let p = d.join("crash_report.xml");
        std::fs::write(&p, r.xml()).expect("write");
        let mut sources = SourceMap::default();
        let got = ciren::import_case(&p, &mut sources);
        if let Ok(imp) = &got {
            // Every later contact is staged, none left out.
            proptest::prop_assert_eq!(imp.crash.conflicts.len(), 1 + r.extras.len());
            proptest::prop_assert_eq!(imp.staged.text.matches("conflict {").count(), 1 + r.extras.len());
            // Every object a later event strikes stands where the striker's slide took it.
            let objects = r.extras.iter().filter(|e| e.other == 0).count();
            proptest::prop_assert_eq!(imp.staged.text.matches(" { at (").count(), objects);
        }
        if let Err(diags) = &got {
            // An object struck on the slide never breaks the chain rules.
            if r.extras.iter().all(|e| e.other == 0) {
                for x in diags {
                    proptest::prop_assert!(!x.message.contains("strikes again") && !x.message.contains("strikes after"));
                }
            }
                for x in diags {
                proptest::prop_assert!(
                    !x.message.contains("does not check"),
                    "{}: {}\n{}",
                    x.code,
                    x.message,
                    r.xml()
                );
            }
        }
        let _ = std::fs::remove_dir_all(&d);
    }
}

// ------------------------------------------------------------------ force direction

/// The coded force per (vehicle, event), read from the record's `VehicleExteriorForm` CDC rows
/// with roxmltree, independently of the importer: clock direction and total delta-V (km/h).
fn coded_forces(xml: &str) -> Vec<(u32, u32, Option<u32>, Option<f64>)> {
    let doc = roxmltree::Document::parse(xml).expect("xml");
    let mut out = vec![];
    for f in doc.descendants().filter(|n| n.has_tag_name("VehicleExteriorForm")) {
        let v: u32 = f.attribute("VehicleNumber").and_then(|x| x.parse().ok()).expect("vehicle");
        for e in f.descendants().filter(|n| n.has_tag_name("CDCevent")) {
            let ev: u32 = e.attribute("eventNumber").and_then(|x| x.parse().ok()).expect("event");
            let clock = e.children().find(|n| n.has_tag_name("ClockDirection")).and_then(|n| n.text());
            let h = clock.and_then(|t| t.trim().parse::<u32>().ok()).filter(|h| (1..=12).contains(h));
            let dv = e
                .descendants()
                .find(|n| n.has_tag_name("Total"))
                .and_then(|n| n.attribute("value"))
                .and_then(|x| x.parse::<f64>().ok())
                .filter(|x| *x > 0.0 && *x < 250.0);
            out.push((v, ev, h, dv));
        }
    }
    out
}

/// Curb weight (kg) of vehicle `v` in its `GeneralVehicleForm`.
fn curb_weight(xml: &str, v: u32) -> Option<f64> {
    let doc = roxmltree::Document::parse(xml).expect("xml");
    let g = doc
        .descendants()
        .find(|n| n.has_tag_name("GeneralVehicleForm") && n.attribute("VehicleNumber") == Some(&v.to_string()))?;
    g.descendants().find(|n| n.has_tag_name("CurbWeight"))?.attribute("value")?.parse().ok()
}

/// Velocity of agent `i` over the frame leading into frame `f`, m/s.
fn vel(t: &Tracks, i: usize, f: usize) -> glam::DVec2 {
    let (p0, p1) = (t.poses[i][f - 1], t.poses[i][f]);
    glam::DVec2::new(p1.x - p0.x, p1.y - p0.y) * t.rate
}

/// The clock direction (0.5..12.5) of the force on agent `a` from agent `b`, measured from the
/// boxes' relative velocity over the frame leading into contact `f`: the force on `a` comes
/// from where `a` moves relative to `b` (12 straight ahead, 3 the right side).
fn measured_clock(t: &Tracks, a: usize, b: usize, f: usize) -> f64 {
    let rel = (vel(t, a, f) - vel(t, b, f)).rotate(glam::DVec2::from_angle(-t.poses[a][f - 1].yaw));
    let h = (-rel.y.atan2(rel.x).to_degrees()).rem_euclid(360.0) / 30.0;
    if h < 0.5 { h + 12.0 } else { h }
}

fn clock_gap(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(12.0);
    d.min(12.0 - d)
}

/// Every coded clock direction is met within one hour at its contact, and where a delta-V and
/// both curb weights (or a fixed object) are coded, the closing speed at contact is within 25%
/// of the momentum balance with a common velocity after: `dv * (m1 + m2) / m2`.
#[test]
fn each_impact_meets_its_coded_clock_direction_and_delta_v() {
    let mut checked = (0, 0);
    for p in dirs("tests/fixtures/ciren-cases", true) {
        let xml = std::fs::read_to_string(p.join("crash_report.xml")).expect("xml");
        let mut sources = SourceMap::default();
        let imp = ciren::import_case(&p, &mut sources).unwrap_or_else(|d| panic!("{}", rendered(&d, &sources)));
        let scen = rocc::check::check_text(&imp.file_name(), &imp.staged.text, Path::new("."), &mut sources)
            .unwrap_or_else(|d| panic!("{}", rendered(&d, &sources)));
        let t = rocc::compile::front(scen, None).expect("front").tracks;
        let id = &imp.crash.id;
        for (v, ev, h, dv) in coded_forces(&xml) {
            let a = t.agents.iter().position(|x| x.name == format!("v{v}")).expect("agent");
            let rec = &t.impacts[ev as usize - 1];
            assert!(rec.at_fault == a || rec.struck == a, "{id}: event {ev} is not v{v}'s");
            let b = if rec.at_fault == a { rec.struck } else { rec.at_fault };
            if let Some(h) = h {
                let m = measured_clock(&t, a, b, rec.frame);
                assert!(clock_gap(m, f64::from(h)) <= 1.0, "{id}: v{v} coded {h} o'clock, measured {m:.2}");
                checked.0 += 1;
            }
            let m_other = if t.agents[b].name.starts_with("obj") {
                Some(None)
            } else {
                curb_weight(&xml, t.agents[b].name[1..].parse().expect("vN")).map(Some)
            };
            if let (Some(dv), Some(m_self), Some(m_other)) = (dv, curb_weight(&xml, v), m_other) {
                let want = m_other.map_or(dv, |m| dv * (m_self + m) / m);
                let got = (vel(&t, a, rec.frame) - vel(&t, b, rec.frame)).length() * 3.6;
                assert!((got - want).abs() <= 0.25 * want, "{id}: closing {got:.1} km/h, delta-V asks {want:.1}");
                checked.1 += 1;
            }
        }
    }
    assert!(checked.0 >= 6 && checked.1 >= 3, "checked {checked:?}");
}

// ------------------------------------------------------------------ several contacts

/// Each `EventSum` of a record in event order: (event, vehicle, its area, other vehicle, its
/// area), read with roxmltree, independently of the importer.
fn coded_events(xml: &str) -> Vec<(u32, u32, Part, u32, Part)> {
    let vehicle = |(e, v, a, o): CodedContact| {
        let (o, oa) = o.expect("a vehicle");
        (e, v, a, o, oa)
    };
    coded_contacts(xml).into_iter().map(vehicle).collect()
}

/// One bundled record of `dir` imported, checked and rolled out.
struct RolledOut {
    xml: String,
    id: String,
    /// Each staged conflict's time, s.
    at: Vec<f64>,
    tracks: rocc::rollout::Tracks,
}

fn rolled_out_records(dir: &str) -> Vec<RolledOut> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir).expect("records").map(|e| e.expect("entry").path()).collect();
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let xml = std::fs::read_to_string(&p).expect("xml");
            let mut sources = SourceMap::default();
            let imp = ciren::import_case(&p, &mut sources).unwrap_or_else(|d| panic!("{}", rendered(&d, &sources)));
            let scen = rocc::check::check_text(&imp.file_name(), &imp.staged.text, Path::new("."), &mut sources)
                .unwrap_or_else(|d| panic!("{}", rendered(&d, &sources)));
            let at = scen.conflicts.iter().map(|c| c.at.expect("at")).collect();
            let tracks = rocc::compile::front(scen, None).expect("front").tracks;
            RolledOut { xml, id: imp.crash.id.clone(), at, tracks }
        })
        .collect()
}

/// Records with several contacts (tests/fixtures/ciren-chains/) import with one conflict per
/// event, and on the rolled-out boxes each pair first touches in event order, within 1.5 s of
/// its `at`, the struck box on its coded side and the striker with its front; every coded clock
/// direction is met within one hour; no pair outside the events touches.
#[test]
fn every_event_of_a_chain_lands_on_its_coded_sides_in_order() {
    let cases = rolled_out_records("tests/fixtures/ciren-chains");
    assert!(cases.len() >= 2);
    for RolledOut { xml, id, at, tracks: t } in cases {
        let events = coded_events(&xml);
        assert_eq!(at.len(), events.len(), "{id}: one conflict per event");
        let idx = |v: u32| t.agents.iter().position(|a| a.name == format!("v{v}")).expect("agent");
        let mut firsts = vec![];
        for (i, &(ev, v, va, o, oa)) in events.iter().enumerate() {
            // The struck one is the vehicle whose coded part is not its front.
            let ((s, sp), (f, fp)) = if oa == Part::Front { ((v, va), (o, oa)) } else { ((o, oa), (v, va)) };
            assert_eq!(fp, Part::Front, "{id}: event {ev} has no striking front");
            let (a, b) = (idx(f), idx(s));
            let first = (1..t.frames)
                .find(|&fr| obb(&t, a, fr).overlaps(&obb(&t, b, fr)))
                .unwrap_or_else(|| panic!("{id}: event {ev}: v{f} never touches v{s}"));
            assert!((first as f64 / t.rate - at[i]).abs() <= 1.5, "{id}: event {ev} at frame {first}, asked {}", at[i]);
            let (on_struck, on_striker) = measured_contact(&t, a, b, first).expect("contact");
            let (sb, sa) = (t.agents[b].size, t.agents[a].size);
            let want = match sp {
                Part::Front => Point::Front,
                Part::Left => Point::Left,
                Part::Right => Point::Right,
                Part::Rear => Point::Rear,
            };
            assert_eq!(sector(on_struck, sb[0], sb[1]), want, "{id}: event {ev}: v{s} struck elsewhere");
            assert!(on_striker.x > 0.6 * sa[0] / 2.0, "{id}: event {ev}: v{f} not with its front");
            firsts.push(first);
        }
        assert!(firsts.windows(2).all(|w| w[0] <= w[1]), "{id}: contacts out of order {firsts:?}");
        for (v, ev, h, _) in coded_forces(&xml) {
            let Some(h) = h else { continue };
            let (_, x, _, y, _) = events.iter().find(|e| e.0 == ev).expect("event");
            let (a, b) = if *x == v { (idx(*x), idx(*y)) } else { (idx(*y), idx(*x)) };
            let m = measured_clock(&t, a, b, firsts[events.iter().position(|e| e.0 == ev).expect("event")]);
            assert!(clock_gap(m, f64::from(h)) <= 1.0, "{id}: v{v} event {ev} coded {h} o'clock, measured {m:.2}");
        }
        for a in 0..t.agents.len() {
            for b in a + 1..t.agents.len() {
                let listed = events.iter().any(|e| {
                    let (x, y) = (idx(e.1), idx(e.3));
                    (x, y) == (a, b) || (x, y) == (b, a)
                });
                let touch = (0..t.frames).any(|fr| obb(&t, a, fr).overlaps(&obb(&t, b, fr)));
                assert!(listed || !touch, "{id}: {} and {} touch", t.agents[a].name, t.agents[b].name);
            }
        }
    }
}

// ------------------------------------------------------------------ strikes on a slide

type CodedContact = (u32, u32, Part, Option<(u32, Part)>);

/// Each `EventSum` of a record in event order, with objects: (event, vehicle, its area, the
/// other vehicle or `None` for a fixed object, its area), read with roxmltree.
fn coded_contacts(xml: &str) -> Vec<CodedContact> {
    let doc = roxmltree::Document::parse(xml).expect("xml");
    let text = |e: roxmltree::Node, tag: &str| {
        e.children().find(|n| n.has_tag_name(tag)).and_then(|n| n.text()).unwrap_or("").to_string()
    };
    let part = |t: String| part(t.split_whitespace().next().unwrap_or("")).expect("a part");
    let mut out: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("EventSum"))
        .map(|e| {
            let num = |a: &str| e.attribute(a).and_then(|x| x.parse::<u32>().ok()).expect("number");
            let contacted = text(e, "Contacted");
            let other = contacted
                .strip_prefix("Vehicle#")
                .map(|n| (n.parse().expect("vehicle number"), part(text(e, "ContactedAreaOfDamage"))));
            (num("EventNumber"), num("VehicleNumber"), part(text(e, "AreaOfDamage")), other)
        })
        .collect();
    out.sort_by_key(|e| e.0);
    out
}

/// A vehicle that strikes again after its first impact, on its slide
/// (tests/fixtures/ciren-slides/: a car struck at a junction slides into a pole, or into a
/// stopped car): the record imports, the struck party is placed where the slide goes, and on
/// the rolled-out boxes each contact happens in event order, within 1.5 s of its `at`: a struck
/// vehicle on its coded side, the striker with its coded face. No pair outside the events
/// touches.
#[test]
fn strikes_on_a_slide_land_on_their_coded_sides() {
    let cases = rolled_out_records("tests/fixtures/ciren-slides");
    assert!(!cases.is_empty());
    for RolledOut { xml, id, at, tracks: t } in cases {
        let events = coded_contacts(&xml);
        assert_eq!(at.len(), events.len(), "{id}: one conflict per event");
        // Some event's striker was in an earlier one: it strikes on its slide.
        let slides = events.iter().enumerate().any(|(i, e)| {
            let striker = match e.3 {
                Some((o, Part::Front)) if e.2 != Part::Front => o,
                _ => e.1,
            };
            events[..i].iter().any(|x| x.1 == striker || x.3.is_some_and(|(o, _)| o == striker))
        });
        assert!(slides, "{id}: a strike on a slide");
        let idx = |n: &str| t.agents.iter().position(|a| a.name == n).expect("agent");
        let objects: Vec<usize> = (0..t.agents.len()).filter(|&i| t.agents[i].name.starts_with("obj")).collect();
        let (mut firsts, mut pairs) = (vec![], vec![]);
        for (i, &(ev, v, va, other)) in events.iter().enumerate() {
            let ((a, face), b, struck) = match other {
                Some((o, oa)) => {
                    let ((s, sp), (f, fp)) = if oa == Part::Front { ((v, va), (o, oa)) } else { ((o, oa), (v, va)) };
                    ((idx(&format!("v{f}")), fp), idx(&format!("v{s}")), Some(sp))
                }
                None => ((idx(&format!("v{v}")), va), objects[0], None),
            };
            let first = (1..t.frames)
                .find(|&fr| obb(&t, a, fr).overlaps(&obb(&t, b, fr)))
                .unwrap_or_else(|| panic!("{id}: event {ev}: {} never touches {}", t.agents[a].name, t.agents[b].name));
            assert!((first as f64 / t.rate - at[i]).abs() <= 1.5, "{id}: event {ev} at frame {first}, asked {}", at[i]);
            let (on_struck, on_striker) = measured_contact(&t, a, b, first).expect("contact");
            if let Some(sp) = struck {
                let sb = t.agents[b].size;
                let want = match sp {
                    Part::Front => Point::Front,
                    Part::Left => Point::Left,
                    Part::Right => Point::Right,
                    Part::Rear => Point::Rear,
                };
                assert_eq!(sector(on_struck, sb[0], sb[1]), want, "{id}: event {ev}: struck elsewhere");
            }
            let (l, w) = (t.agents[a].size[0] / 2.0, t.agents[a].size[1] / 2.0);
            let on_face = match face {
                Part::Front => on_striker.x > 0.6 * l,
                Part::Rear => on_striker.x < -0.6 * l,
                Part::Left => on_striker.y > 0.6 * w,
                Part::Right => on_striker.y < -0.6 * w,
            };
            assert!(on_face, "{id}: event {ev}: {} touches at {on_striker:?}, not its {face:?}", t.agents[a].name);
            firsts.push(first);
            pairs.push((a.min(b), a.max(b)));
        }
        assert!(firsts.windows(2).all(|w| w[0] <= w[1]), "{id}: contacts out of order {firsts:?}");
        for a in 0..t.agents.len() {
            for b in a + 1..t.agents.len() {
                let touch = (0..t.frames).any(|fr| obb(&t, a, fr).overlaps(&obb(&t, b, fr)));
                assert!(pairs.contains(&(a, b)) || !touch, "{id}: {} and {} touch", t.agents[a].name, t.agents[b].name);
            }
        }
    }
}
