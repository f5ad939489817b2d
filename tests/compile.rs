//! `rocc compile` end to end: the SPEC output layout, byte-identical outputs on 1 and N threads,
//! resume, frame/ego selection, batch failures, and files that load in numpy like nuPlan-Occ's.

#[path = "support/tmp.rs"]
mod tmp;

use rocc::compile::{Options, Stage, batch};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use tmp::TempDir;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A directory for this test's outputs, removed when dropped.
fn tmp(name: &str) -> TempDir {
    TempDir::new("rocc-compile", name)
}

fn opts(stage: Stage, frames: &str) -> Options {
    // A coarse azimuth step keeps the debug-build test fast; the rig is otherwise nuPlan's.
    let mut o = Options { stage, frames: Some(frames.to_string()), ..Options::default() };
    o.rig.horizontal_resolution_deg = 2.0;
    o
}

/// Every file under `dir` (relative path -> bytes), `manifest.json` left out: it holds timings.
fn tree(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(base: &Path, d: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(d).expect("read dir") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                walk(base, &p, out);
            } else if p.file_name().is_some_and(|n| n != "manifest.json") {
                let rel = p.strip_prefix(base).expect("under base").to_string_lossy().into_owned();
                out.insert(rel, std::fs::read(&p).expect("read"));
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

fn run_in_pool(threads: usize, inputs: &[PathBuf], out: &Path, o: &Options) -> batch::BatchReport {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool")
        .install(|| batch::run(inputs, out, o, true))
}

#[test]
fn outputs_follow_the_spec_layout_and_are_identical_on_1_and_4_threads() {
    let input = vec![root().join("scenarios/rear_end_queue.scn")];
    let o = opts(Stage::Lidar, "0,29..=31");
    let (a, b) = (tmp("threads1"), tmp("threads4"));
    let ra = run_in_pool(1, &input, &a, &o);
    let rb = run_in_pool(4, &input, &b, &o);
    assert!(ra.failures.is_empty() && rb.failures.is_empty());
    assert_eq!(ra.clips.len(), 2, "one clip per ego (ego, striker)");
    let (ta, tb) = (tree(&a), tree(&b));
    assert_eq!(ta.keys().collect::<Vec<_>>(), tb.keys().collect::<Vec<_>>());
    for (k, v) in &ta {
        assert!(v == &tb[k], "{k} differs between 1 and 4 threads");
    }
    let clip = a.join("rear_end_queue/ego");
    for f in [
        "boxes.json",
        "bev/000000.npz",
        "bev/000031.npz",
        "occ/000030.npy",
        "lidar/000029.bin",
        "lidar/000029.pcd",
        "preview/bev.png",
        "preview/bev.gif",
        "preview/occ.gif",
        "preview/lidar.gif",
        "preview/sheet.png",
        "manifest.json",
    ] {
        assert!(clip.join(f).is_file(), "missing {f}");
    }
    assert!(!clip.join("bev/000001.npz").exists(), "--frames selected 0, 29, 30, 31 only");
    // The manifest lists every file with its size, and nothing temporary is left behind.
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(clip.join("manifest.json")).expect("manifest")).expect("json");
    assert_eq!(m["frames"], serde_json::json!([0, 29, 30, 31]));
    assert_eq!(m["stage"], "lidar");
    assert_eq!(m["ego"], "ego");
    let files = m["files"].as_array().expect("files");
    assert_eq!(files.len(), ta.keys().filter(|k| k.starts_with("rear_end_queue/ego/")).count());
    for f in files {
        let len = std::fs::metadata(clip.join(f["path"].as_str().expect("path"))).expect("listed file").len();
        assert_eq!(len, f["bytes"].as_u64().expect("bytes"));
    }
    assert!(ta.keys().all(|k| !k.contains(".tmp-")), "temporary files left behind");
    // boxes.json: one record per frame, the ego never in its own boxes, the striker behind it.
    let boxes: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(clip.join("boxes.json")).expect("boxes")).expect("json");
    let frames = boxes.as_array().expect("frames");
    assert_eq!(frames.iter().map(|f| f["frame"].as_u64().expect("frame")).collect::<Vec<_>>(), vec![0, 29, 30, 31]);
    for f in frames {
        let bs = f["boxes"].as_array().expect("boxes");
        assert!(bs.iter().all(|b| b["agent"] != "ego"));
        let striker = bs.iter().find(|b| b["agent"] == "striker").expect("striker in view");
        assert!(striker["x"].as_f64().expect("x") < 0.0, "the striker comes from behind");
    }
}

#[test]
fn a_complete_clip_is_kept_and_force_recompiles_it() {
    let input = vec![root().join("scenarios/replayed_cut_in.scn")];
    let out = tmp("resume");
    let o = Options { previews: false, ..opts(Stage::Bev, "0..3") };
    let first = batch::run(&input, &out, &o, true);
    assert!(first.failures.is_empty() && first.clips.iter().all(|c| !c.resumed));
    let second = batch::run(&input, &out, &o, true);
    assert!(second.clips.iter().all(|c| c.resumed), "a complete clip is recompiled");
    // A truncated or missing file makes the clip incomplete again.
    let clip = &second.clips[0].dir;
    std::fs::remove_file(clip.join("bev/000001.npz")).expect("remove");
    let third = batch::run(&input, &out, &o, true);
    assert!(third.clips.iter().all(|c| !c.resumed) && clip.join("bev/000001.npz").is_file());
    // Asking for more than was written is not "complete" either.
    let more = batch::run(&input, &out, &Options { previews: false, ..opts(Stage::Bev, "0..4") }, true);
    assert!(more.clips.iter().all(|c| !c.resumed));
    let forced = batch::run(&input, &out, &Options { force: true, previews: false, ..opts(Stage::Bev, "0..4") }, true);
    assert!(forced.clips.iter().all(|c| !c.resumed));
}

#[test]
fn an_edited_clip_is_not_overwritten_without_force() {
    let input = vec![root().join("scenarios/replayed_cut_in.scn")];
    let out = tmp("edited");
    let o = Options { previews: false, ..opts(Stage::Bev, "0..2") };
    assert!(batch::run(&input, &out, &o, true).failures.is_empty());
    let clip = out.join("replayed_cut_in/ego");
    let edit = rocc::edit::Edit::Delete { agent: "cutter".into() };
    let ce = rocc::edit::ClipEdit { scenario: Some(input[0].clone()), ..Default::default() };
    rocc::edit::edit_clip(&clip, &[edit], &ce).expect("edit");
    let edited = tree(&clip);
    let manifest = std::fs::read(clip.join("manifest.json")).expect("manifest");
    // A later compile into the same directory refuses, names the edit and leaves every byte.
    let again = batch::run(&input, &out, &o, true);
    assert!(again.clips.is_empty(), "the edited clip was recompiled");
    let d = &again.failures[0].diags[0];
    assert_eq!(d.code, "E0403");
    assert!(d.message.contains("delete cutter") && d.message.contains("replayed_cut_in"), "{}", d.message);
    assert!(d.help.as_deref().is_some_and(|h| h.contains("--force")));
    assert_eq!(tree(&clip), edited);
    assert_eq!(std::fs::read(clip.join("manifest.json")).expect("manifest"), manifest);
    // The command line says so and fails.
    let run = Command::new(env!("CARGO_BIN_EXE_rocc"))
        .args(["compile", input[0].to_str().unwrap(), "-o", out.to_str().unwrap(), "--frames", "0..2"])
        .args(["--stage", "bev", "--no-previews", "-q"])
        .output()
        .expect("run rocc");
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success() && err.contains("E0403") && err.contains("--force"), "{err}");
    assert_eq!(tree(&clip), edited);
    // `--force` recompiles from the scenario: the cutter is back and the history is gone.
    let forced = batch::run(&input, &out, &Options { force: true, ..o.clone() }, true);
    assert!(forced.failures.is_empty() && forced.clips.iter().all(|c| !c.resumed && c.manifest.edits.is_empty()));
    let boxes = std::fs::read_to_string(clip.join("boxes.json")).expect("boxes");
    assert!(boxes.contains("\"cutter\""));
    assert!(batch::run(&input, &out, &o, true).clips.iter().all(|c| c.resumed));
}

#[test]
fn a_failing_file_does_not_stop_the_batch() {
    let inputs = vec![
        root().join("tests/invalid/unknown_kind.scn"),
        root().join("scenarios/replayed_cut_in.scn"),
        root().join("tests/fixtures/examples/invalid/overlap.scn"),
    ];
    for p in &inputs {
        assert!(p.is_file(), "{} missing", p.display());
    }
    let out = tmp("failures");
    let r = batch::run(&inputs, &out, &Options { previews: false, ..opts(Stage::Bev, "0") }, true);
    assert_eq!(r.clips.len(), 1);
    let codes: Vec<&str> = r.failures.iter().map(|f| f.diags[0].code).collect();
    assert_eq!(codes, vec!["E0108", "E0202"]);
    // Nothing was written for the failed files; the root's index lists the one clip.
    let mut dirs: Vec<String> = std::fs::read_dir(&out)
        .expect("out")
        .map(|e| e.expect("e").file_name().to_string_lossy().into_owned())
        .collect();
    dirs.sort();
    assert_eq!(dirs, vec!["index.jsonl".to_string(), "replayed_cut_in".to_string()]);
}

#[test]
fn resume_recompiles_when_the_rig_or_an_import_changed() {
    // A different `--lidar-resolution` keeps the rig's name but changes every scan.
    let input = vec![root().join("scenarios/replayed_cut_in.scn")];
    let out = tmp("resume-rig");
    let o = Options { previews: false, ..opts(Stage::Lidar, "0") };
    assert!(batch::run(&input, &out, &o, true).clips.iter().all(|c| !c.resumed));
    assert!(batch::run(&input, &out, &o, true).clips.iter().all(|c| c.resumed));
    let mut finer = o.clone();
    finer.rig.horizontal_resolution_deg = 1.5;
    assert_eq!(finer.rig.name, o.rig.name);
    let r = batch::run(&input, &out, &finer, true);
    assert!(r.failures.is_empty() && r.clips.iter().all(|c| !c.resumed), "a stale LiDAR clip was kept");

    // An edited import changes the scene though the root file's bytes are the same.
    let dir = tmp("resume-import");
    std::fs::create_dir_all(dir.join("kinds")).expect("mkdir");
    std::fs::copy(root().join("scenarios/car_into_tree.scn"), dir.join("car_into_tree.scn")).expect("copy");
    let kinds = std::fs::read_to_string(root().join("scenarios/kinds/rural.scn")).expect("kinds");
    std::fs::write(dir.join("kinds/rural.scn"), &kinds).expect("write");
    let input = vec![dir.join("car_into_tree.scn")];
    let out = dir.join("out");
    let o = Options { previews: false, ..opts(Stage::Bev, "0") };
    assert!(batch::run(&input, &out, &o, true).clips.iter().all(|c| !c.resumed));
    assert!(batch::run(&input, &out, &o, true).clips.iter().all(|c| c.resumed));
    std::fs::write(dir.join("kinds/rural.scn"), format!("{kinds}\n// edited\n")).expect("write");
    let r = batch::run(&input, &out, &o, true);
    assert!(r.failures.is_empty() && r.clips.iter().all(|c| !c.resumed), "a clip of a changed import was kept");
}

#[test]
fn bad_egos_frames_and_duplicate_names_are_diagnosed() {
    let input = vec![root().join("scenarios/replayed_cut_in.scn")];
    let out = tmp("bad-options");
    let r = batch::run(&input, &out, &Options { egos: vec!["eg".into()], ..opts(Stage::Bev, "0") }, true);
    assert_eq!(r.failures[0].diags[0].code, "E0301");
    assert!(r.failures[0].diags[0].help.as_deref().unwrap_or("").contains("`ego`"), "suggests the right name");
    let r = batch::run(&input, &out, &opts(Stage::Bev, "0..999"), true);
    assert_eq!(r.failures[0].diags[0].code, "E0302");
    let twice = vec![root().join("scenarios/car_u_turn.scn"), root().join("tests/fixtures/examples/car_u_turn.scn")];
    let r = batch::run(&twice, &out, &Options { previews: false, ..opts(Stage::Bev, "0") }, true);
    assert_eq!((r.clips.len(), r.failures.len()), (1, 1));
    assert_eq!(r.failures[0].diags[0].code, "E0303");
}

#[test]
fn duplicate_names_in_different_shards_are_diagnosed() {
    let twice = vec![root().join("scenarios/car_u_turn.scn"), root().join("tests/fixtures/examples/car_u_turn.scn")];
    let out = tmp("dup-shards");
    let o = Options { previews: false, ..opts(Stage::Bev, "0") };
    // Shard 1 of 2 owns the first file: it compiles, as it would without sharding.
    let first = batch::run_shard(&twice, Some((1, 2)), &out, &o, true);
    assert_eq!((first.clips.len(), first.failures.len()), (1, 0));
    // Shard 2 of 2 owns only the second: its name clashes with a file of shard 1.
    let second = batch::run_shard(&twice, Some((2, 2)), &out, &o, true);
    assert_eq!((second.clips.len(), second.failures.len()), (0, 1));
    assert_eq!(second.failures[0].diags[0].code, "E0303");
    assert_eq!(second.failures[0].input, twice[1]);
}

fn python_with_numpy() -> bool {
    Command::new("python3").args(["-c", "import numpy"]).output().is_ok_and(|o| o.status.success())
}

#[test]
fn compiled_files_load_in_numpy_like_nuplan_occ_data() {
    if !python_with_numpy() {
        eprintln!("SKIP: python3 with numpy not available (.ci/run installs it with `pip install numpy`)");
        return;
    }
    let out = tmp("numpy");
    let r = batch::run(
        &[root().join("tests/fixtures/examples/cyclist_red_light.scn")],
        &out,
        &Options { previews: false, ..opts(Stage::Lidar, "5") },
        true,
    );
    assert!(r.failures.is_empty());
    let clip = out.join("cyclist_red_light/ego");
    let py = root().join("tests/python");
    let bev =
        Command::new("python3").arg(py.join("check_bev.py")).arg(clip.join("bev/000005.npz")).output().expect("python");
    assert!(bev.status.success(), "{}{}", String::from_utf8_lossy(&bev.stdout), String::from_utf8_lossy(&bev.stderr));
    let occ = Command::new("python3")
        .arg(py.join("check_occ_lidar.py"))
        .args([clip.join("occ/000005.npy"), clip.join("lidar/000005.bin"), clip.join("lidar/000005.pcd")])
        .output()
        .expect("python");
    assert!(occ.status.success(), "{}{}", String::from_utf8_lossy(&occ.stdout), String::from_utf8_lossy(&occ.stderr));
}

#[test]
fn a_batch_keeps_clip_summaries_and_sweeps_an_interrupted_runs_temporaries() {
    let input = vec![root().join("scenarios/rear_end_queue.scn")];
    let o = Options { force: true, ..opts(Stage::Bev, "0..=1") };
    let out = tmp("sweep");
    let r = batch::run(&input, &out, &o, true);
    assert!(r.failures.is_empty());
    let clip = &r.clips[0];
    // The report holds counts, not the file list: memory does not grow with the corpus.
    assert!(clip.manifest.files.is_empty());
    let on_disk: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(clip.dir.join("manifest.json")).expect("manifest"))
            .expect("json");
    let files = on_disk["files"].as_array().expect("file list on disk");
    assert_eq!(clip.files, files.len());
    assert_eq!(clip.bytes, files.iter().map(|f| f["bytes"].as_u64().expect("bytes")).sum::<u64>());
    assert!(clip.files >= 3 && clip.bytes > 0);
    // What a killed run leaves: temporaries of `write_atomic`, in the clip and its sub-directories.
    let stale = [clip.dir.join(".boxes.json.tmp-4242-0"), clip.dir.join("bev/.000001.npz.tmp-4242-17")];
    let keep = [clip.dir.join(".notes"), clip.dir.join("bev/notes.tmp-1-2"), clip.dir.join(".x.tmp-12")];
    for p in stale.iter().chain(&keep) {
        std::fs::write(p, b"partial").expect("write");
    }
    // Another clip's directory is not this clip's to sweep.
    let other = out.join("rear_end_queue/striker/bev/.000000.npz.tmp-4242-3");
    std::fs::create_dir_all(other.parent().expect("dir")).expect("dir");
    std::fs::write(&other, b"partial").expect("write");
    let o1 = Options { egos: vec!["ego".into()], ..o.clone() };
    let r = batch::run(&input, &out, &o1, true);
    assert!(r.failures.is_empty() && r.clips.len() == 1);
    for p in &stale {
        assert!(!p.exists(), "{} survived", p.display());
    }
    for p in keep.iter().chain([&other]) {
        assert!(p.exists(), "{} was removed", p.display());
    }
    assert!(rocc::output::is_atomic_tmp(".000001.npz.tmp-4242-17"));
    assert!(!rocc::output::is_atomic_tmp("000001.npz.tmp-4242-17") && !rocc::output::is_atomic_tmp(".tmp-1-2"));
    let _ = std::fs::remove_dir_all(&out);
}
