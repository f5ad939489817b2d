//! `rocc compile --flow` on a library scene: a moving agent's voxels carry its velocity, every
//! other voxel is zero; the file loads in numpy; `--flow` without occupancy is E0430.

use ndarray::Array4;
use ndarray_npy::NpzReader;
use rocc::backend::layout::{BACKGROUND, FREE, NX, NY, NZ, centre};
use rocc::backend::read_npy;
use rocc::compile::{Options, Stage, batch};
use rocc::output::read_boxes_json;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rocc-flow-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn read_flow(path: &Path) -> Array4<f32> {
    let mut z = NpzReader::new(std::fs::File::open(path).expect("flow file")).expect("npz");
    z.by_name("flow").expect("key `flow`")
}

/// Whether the centre of voxel (i, j) lies in the footprint of `b`, `m` metres inflated.
fn inside(b: &rocc::view::EgoBox, i: usize, j: usize, m: f64) -> bool {
    let (dx, dy) = (centre(0, i) - b.x, centre(1, j) - b.y);
    let (c, s) = (b.yaw.cos(), b.yaw.sin());
    (dx * c + dy * s).abs() <= 0.5 * b.l + m && (-dx * s + dy * c).abs() <= 0.5 * b.w + m
}

#[test]
fn a_moving_box_carries_its_velocity_and_everything_else_is_still() {
    // rear_end_queue: the ego and `first` stand at a red light, `striker` comes up behind them at
    // a steady 45 km/h in the same lane (so along the ego's +x), 40 m back at frame 0.
    let out = tmp("queue");
    let opts = Options { stage: Stage::Occ, frames: Some("0..3".into()), flow: true, ..Options::default() };
    let r = batch::run(&[root().join("scenarios/rear_end_queue.scn")], &out, &opts, true);
    assert!(r.failures.is_empty());
    let dir = out.join("rear_end_queue/ego");
    let frames = read_boxes_json(&dir.join("boxes.json")).expect("boxes.json");
    let mut sources = rocc::source::SourceMap::default();
    let scenario = rocc::check::check_path(&root().join("scenarios/rear_end_queue.scn"), &mut sources).expect("checks");
    let front = rocc::compile::front(scenario, None).expect("front");
    let s = front.tracks.agents.iter().position(|a| a.name == "striker").expect("striker");
    for fb in &frames {
        let f = fb.frame;
        let flow = read_flow(&dir.join(format!("flow/{f:06}.npz")));
        assert_eq!(flow.dim(), (NX, NY, NZ, 3));
        let occ = read_npy(&dir.join(format!("occ/{f:06}.npy"))).expect("occ");
        let striker = fb.boxes.iter().find(|b| b.agent == "striker").expect("striker in view");
        let mut moving = 0;
        for ((i, j, k, c), &v) in flow.indexed_iter() {
            let label = occ.labels[[i, j, k]];
            if c == 2 || label == FREE || label == BACKGROUND || !inside(striker, i, j, 0.125) {
                assert_eq!(v, 0.0, "voxel ({i}, {j}, {k}) label {label} component {c} at frame {f}");
                continue;
            }
            // Its speed along its heading, from the rollout (the flow differences poses).
            let want = if c == 0 { front.tracks.speeds[s][f] } else { 0.0 };
            assert!((v as f64 - want).abs() < 0.15, "striker voxel ({i}, {j}, {k}) has {v}, want {want}");
            moving += (c == 0) as usize;
        }
        assert!(moving > 100, "frame {f}: only {moving} striker voxels");
    }
    let manifest = std::fs::read_to_string(dir.join("manifest.json")).expect("manifest");
    assert!(manifest.contains("\"flow\": true") && manifest.contains("flow/000000.npz"));
    if Command::new("python3").args(["-c", "import numpy"]).output().is_ok_and(|o| o.status.success()) {
        let script = "import sys, numpy as np\nz = np.load(sys.argv[1])\nf = z['flow']\n\
                      assert f.dtype == np.float32 and f.shape == (400, 400, 32, 3), (f.dtype, f.shape)\n\
                      assert 12 < float(f[..., 0].max()) < 13\nprint('ok')";
        let o =
            Command::new("python3").args(["-c", script]).arg(dir.join("flow/000000.npz")).output().expect("python3");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    } else {
        eprintln!("SKIP: python3 with numpy not available");
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn without_the_flag_no_flow_is_written() {
    let out = tmp("noflag");
    let opts = Options { stage: Stage::Occ, frames: Some("0".into()), ..Options::default() };
    let r = batch::run(&[root().join("scenarios/rear_end_queue.scn")], &out, &opts, true);
    assert!(r.failures.is_empty());
    let dir = out.join("rear_end_queue/ego");
    assert!(!dir.join("flow").exists());
    let manifest = std::fs::read_to_string(dir.join("manifest.json")).expect("manifest");
    assert!(!manifest.contains("\"flow\""));
    // Asking again with `--flow` is not the same clip: it is rewritten, with its flow.
    let opts = Options { flow: true, ..opts };
    let r = batch::run(&[root().join("scenarios/rear_end_queue.scn")], &out, &opts, true);
    assert!(r.clips.iter().all(|c| !c.resumed));
    assert!(dir.join("flow/000000.npz").is_file());
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn flow_without_occupancy_is_e0430() {
    let out = tmp("e0430");
    let o = Command::new(env!("CARGO_BIN_EXE_rocc"))
        .args(["compile", "--stage", "bev", "--flow", "-o"])
        .arg(&out)
        .arg(root().join("scenarios/rear_end_queue.scn"))
        .output()
        .expect("rocc");
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("E0430"), "{err}");
    assert!(!out.join("rear_end_queue").exists(), "nothing written");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_replayed_track_moves_one_sidedly_at_its_ends_in_boxes_and_flow_alike() {
    let scn = root().join("tests/fixtures/flow/replayed_entry_exit.scn");
    let out = tmp("ends");
    let opts = Options { stage: Stage::Occ, frames: Some("10,20,30".into()), flow: true, ..Options::default() };
    let r = batch::run(std::slice::from_ref(&scn), &out, &opts, true);
    let why: Vec<String> = r.failures.iter().flat_map(|f| f.diags.iter().map(|d| format!("{d:?}"))).collect();
    assert!(r.failures.is_empty(), "{why:?}");
    let dir = out.join("replayed_entry_exit/ego");
    let mut sources = rocc::source::SourceMap::default();
    let front =
        rocc::compile::front(rocc::check::check_path(&scn, &mut sources).expect("checks"), None).expect("front");
    let t = &front.tracks;
    let van = t.agents.iter().position(|a| a.name == "van").expect("van");
    assert!(!front.present(van, 9) && front.present(van, 10) && front.present(van, 30) && !front.present(van, 31));
    let pos = |f: usize| (t.poses[van][f].x, t.poses[van][f].y);
    let text = std::fs::read_to_string(dir.join("boxes.json")).expect("boxes.json");
    let frames: Vec<serde_json::Value> = serde_json::from_str(&text).expect("json");
    let num = |v: &serde_json::Value| v.as_f64().expect("number");
    for fr in &frames {
        let f = fr["frame"].as_u64().expect("frame") as usize;
        // Forward at the first frame, backward at the last, central between.
        let (a, z) = match f {
            10 => (10, 11),
            30 => (29, 30),
            _ => (f - 1, f + 1),
        };
        let dt = (z - a) as f64 / t.rate;
        let want = [(pos(z).0 - pos(a).0) / dt, (pos(z).1 - pos(a).1) / dt];
        assert!(want[0] > 5.0, "frame {f}: the van should be moving, {want:?}");
        let b = fr["boxes"].as_array().expect("boxes").iter().find(|b| b["agent"] == "van").expect("van in view");
        let got = [num(&b["velocity_world"][0]), num(&b["velocity_world"][1])];
        assert!((got[0] - want[0]).abs() < 1e-9 && (got[1] - want[1]).abs() < 1e-9, "frame {f}: {got:?} vs {want:?}");
        // The flow of the van's voxels is boxes.json's ego-axes velocity, to float32 precision.
        let ego_axes = [num(&b["velocity"][0]) as f32, num(&b["velocity"][1]) as f32];
        let flow = read_flow(&dir.join(format!("flow/{f:06}.npz")));
        let occ = read_npy(&dir.join(format!("occ/{f:06}.npy"))).expect("occ");
        let boxes = read_boxes_json(&dir.join("boxes.json")).expect("boxes.json");
        let vb =
            boxes.iter().find(|x| x.frame == f).and_then(|x| x.boxes.iter().find(|b| b.agent == "van")).expect("van");
        let mut carried = 0;
        for i in 0..NX {
            for j in 0..NY {
                if !inside(vb, i, j, -0.125) {
                    continue;
                }
                for k in 0..NZ {
                    if occ.labels[[i, j, k]] != BACKGROUND && occ.labels[[i, j, k]] != FREE {
                        assert_eq!(
                            [flow[[i, j, k, 0]], flow[[i, j, k, 1]]],
                            ego_axes,
                            "frame {f} voxel ({i}, {j}, {k})"
                        );
                        carried += 1;
                    }
                }
            }
        }
        assert!(carried > 50, "frame {f}: {carried} van voxels");
    }
    assert_eq!(frames.len(), 3);
    let _ = std::fs::remove_dir_all(&out);
}
