//! `rocc compile --visibility`: Occ3D's `gts/NNNNNN/labels.npz`. A wall in front of one camera
//! and one level LiDAR beam shows what each mask holds; a compiled library scene shows the file
//! (keys, dtypes, shapes, numpy and the Python reader) and that every LiDAR return lies in
//! `mask_lidar`; bad flags and camera rigs are coded errors.

use ndarray::Array3;
use ndarray_npy::NpzReader;
use rocc::backend::layout::{BARRIER, FREE, NX, NY, NZ, ORIGIN, VOXEL, flat};
use rocc::backend::{Occupancy, read_npy};
use rocc::compile::{Options, Stage, batch};
use rocc::lidar::Rig;
use rocc::lidar::rig::Mount;
use rocc::visibility::{Camera, CameraRig, Masks, masks_into};
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rocc-vis-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// The flat index of the voxel holding ego-frame point (x, y, z).
fn at(x: f64, y: f64, z: f64) -> usize {
    let v = |a: usize, p: f64| ((p - ORIGIN[a]) / VOXEL).floor() as usize;
    flat(v(0, x), v(1, y), v(2, z))
}

/// Sensors 1.6 m up at the origin; a barrier one voxel thick at x = 10 m, 10 m wide, 3 m tall.
fn wall_scene() -> Masks {
    let mut labels = Array3::<u8>::zeros((NX, NY, NZ));
    for j in 180..220 {
        for k in 12..24 {
            labels[[240, j, k]] = BARRIER;
        }
    }
    let occ = Occupancy { labels };
    let mut rig = Rig::nuplan();
    rig.mount = Mount::default();
    rig.sensors.truncate(1);
    rig.horizontal_resolution_deg = 0.2;
    rig.max_range = 40.0;
    let s = &mut rig.sensors[0];
    (s.origin, s.rotation_deg, s.elevations_deg, s.azimuth_deg) =
        ((0.0, 0.0, 1.6), (0.0, 0.0, 0.0), vec![0.0], (0.0, 0.0));
    s.horizontal_resolution_deg = None;
    let camera = Camera {
        name: "front".into(),
        origin: (0.0, 0.0, 1.6),
        yaw_deg: 0.0,
        pitch_deg: 0.0,
        hfov_deg: 60.0,
        width: 600,
        height: 300,
    };
    let cameras = CameraRig { name: "one".into(), ray_stride_px: 2, cameras: vec![camera] };
    let mut m = Masks::default();
    masks_into(&occ, &rig, &cameras, &mut m);
    m
}

#[test]
fn a_wall_hides_what_is_behind_it_from_the_camera_and_the_lidar() {
    let m = wall_scene();
    let (cam, lid) = (|p: usize| m.camera[p] == 1, |p: usize| m.lidar[p] == 1);
    let (between, wall, behind) = (at(5.0, 0.1, 1.6), at(10.1, 0.1, 1.6), at(12.0, 0.1, 1.6));
    // The free voxels between the sensors and the wall, and the wall's face, are observed.
    assert!(cam(between) && cam(wall) && lid(between) && lid(wall));
    for x in [1.0, 3.0, 7.0, 9.9] {
        assert!(lid(at(x, 0.1, 1.6)) && cam(at(x, 0.1, 1.6)), "free voxel at x = {x}");
    }
    // Behind the wall: seen by neither.
    assert!(!cam(behind) && !lid(behind));
    // Beside the wall's end, as far out, the camera sees past it (28 deg, inside its 30).
    assert!(cam(at(12.0, 6.5, 1.6)));
    // Behind the camera: outside its frustum; the LiDAR turns all the way round.
    assert!(!cam(at(-10.0, 0.1, 1.6)) && lid(at(-10.0, 0.1, 1.6)));
    // A level beam does not reach the ground, and stops at its range.
    assert!(!lid(at(5.0, 0.1, 0.3)) && !lid(at(-45.0, 0.1, 1.6)));
    assert!(m.camera.iter().chain(&m.lidar).all(|&v| v <= 1));
}

fn read_labels(path: &Path) -> [Array3<u8>; 3] {
    let mut z = NpzReader::new(std::fs::File::open(path).expect("labels.npz")).expect("npz");
    assert_eq!(z.names().unwrap(), ["semantics", "mask_lidar", "mask_camera"]);
    ["semantics", "mask_lidar", "mask_camera"].map(|k| z.by_name(k).expect(k))
}

fn python_with_numpy() -> bool {
    Command::new("python3").args(["-c", "import numpy"]).output().is_ok_and(|o| o.status.success())
}

#[test]
fn compiled_labels_hold_the_occupancy_and_every_lidar_return_is_in_mask_lidar() {
    let out = tmp("queue");
    let mut opts = Options {
        stage: Stage::Lidar,
        frames: Some("0..2".into()),
        previews: false,
        visibility: Some(CameraRig::nuplan()),
        ..Options::default()
    };
    opts.rig.horizontal_resolution_deg = 1.0;
    let r = batch::run(&[root().join("scenarios/rear_end_queue.scn")], &out, &opts, true);
    assert!(r.failures.is_empty());
    let dir = out.join("rear_end_queue/ego");
    for f in 0..2 {
        let [semantics, lidar, camera] = read_labels(&dir.join(format!("gts/{f:06}/labels.npz")));
        let occ = read_npy(&dir.join(format!("occ/{f:06}.npy"))).expect("occ");
        assert_eq!(semantics, occ.labels);
        assert!(lidar.iter().chain(&camera).all(|&v| v <= 1));
        let seen = |m: &Array3<u8>| m.iter().filter(|&&v| v == 1).count();
        assert!(seen(&lidar) > 10_000 && seen(&camera) > 10_000, "{} {}", seen(&lidar), seen(&camera));
        // Every return lies in or on the face of its hit voxel (float32 coordinates: look 1 mm
        // around the point), and that voxel is in the mask.
        let bin = std::fs::read(dir.join(format!("lidar/{f:06}.bin"))).expect("bin");
        let pts: Vec<[f64; 3]> = bin
            .chunks_exact(16)
            .map(|c| std::array::from_fn(|i| f32::from_le_bytes(c[4 * i..4 * i + 4].try_into().unwrap()).into()))
            .collect();
        let mask = lidar.as_slice().unwrap();
        let near = |p: &[f64; 3]| {
            (0..8).any(|c: usize| {
                let e = |a: usize| if c >> a & 1 == 1 { 1e-3 } else { -1e-3 };
                let idx = at(p[0] + e(0), p[1] + e(1), p[2] + e(2));
                mask[idx] == 1 && semantics.as_slice().unwrap()[idx] != FREE
            })
        };
        assert!(pts.len() > 1000);
        let outside: Vec<_> = pts.iter().filter(|p| !near(p)).take(5).collect();
        assert!(outside.is_empty(), "returns outside mask_lidar: {outside:?}");
    }
    let manifest = std::fs::read_to_string(dir.join("manifest.json")).expect("manifest");
    assert!(manifest.contains("\"visibility\": \"nuplan-nominal\"") && manifest.contains("gts/000001/labels.npz"));
    if python_with_numpy() {
        let run = Command::new("python3")
            .arg(root().join("tests/python/check_labels.py"))
            .arg(&out)
            .env("PYTHONPATH", root().join("python"))
            .output()
            .expect("python3");
        let log = format!("{}{}", String::from_utf8_lossy(&run.stdout), String::from_utf8_lossy(&run.stderr));
        assert!(run.status.success() && log.contains("ok: 4 frames"), "{log}");
    } else {
        eprintln!("SKIP: python3 with numpy not available");
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn without_the_flag_no_labels_are_written_and_asking_later_rewrites_the_clip() {
    let out = tmp("noflag");
    let opts = Options { stage: Stage::Occ, frames: Some("0".into()), previews: false, ..Options::default() };
    let r = batch::run(&[root().join("scenarios/rear_end_queue.scn")], &out, &opts, true);
    assert!(r.failures.is_empty());
    let dir = out.join("rear_end_queue/ego");
    assert!(!dir.join("gts").exists());
    assert!(!std::fs::read_to_string(dir.join("manifest.json")).unwrap().contains("\"visibility\""));
    let opts = Options { visibility: Some(CameraRig::nuplan()), ..opts };
    let r = batch::run(&[root().join("scenarios/rear_end_queue.scn")], &out, &opts, true);
    assert!(r.clips.iter().all(|c| !c.resumed));
    assert!(dir.join("gts/000000/labels.npz").is_file());
    let _ = std::fs::remove_dir_all(&out);
}

fn rocc_fails(args: &[&str], out: &Path) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_rocc"))
        .arg("compile")
        .args(args)
        .arg("-o")
        .arg(out)
        .arg(root().join("scenarios/rear_end_queue.scn"))
        .output()
        .expect("rocc");
    assert!(!o.status.success());
    assert!(!out.join("rear_end_queue").exists(), "nothing written");
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn bad_flags_and_camera_rigs_are_coded_errors() {
    let out = tmp("errors");
    let bad = out.join("bad.ron");
    std::fs::write(&bad, CameraRig::nuplan_ron().replace("hfov_deg: 64.0", "hfov_deg: 0.0")).unwrap();
    let bad = bad.to_str().unwrap();
    let missing = out.join("missing.ron");
    let cases: [(&[&str], &str, &str); 5] = [
        (&["--stage", "bev", "--visibility"], "E0432", "--stage bev"),
        (&["--camera-rig", bad], "E0433", "--visibility"),
        (&["--visibility", "--camera-rig", bad], "E0431", "hfov_deg 0"),
        (&["--visibility", "--camera-rig", missing.to_str().unwrap()], "E0431", "cannot read"),
        (&["--visibility", "--camera-rig", "Cargo.toml"], "E0431", "camera rig"),
    ];
    for (args, code, words) in cases {
        let err = rocc_fails(args, &out.join("o"));
        assert!(err.contains(code) && err.contains(words), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&out);
}
