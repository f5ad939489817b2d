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
