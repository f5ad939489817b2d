//! Issue 8: the shared scorer, the box-stream importer and scene editing.

#[path = "support/tmp.rs"]
mod tmp;

use ndarray::{Array2, Array3};
use ndarray_npy::{NpzWriter, WriteNpyExt};
use rocc::backend::layout::{NX, NY, NZ};
use rocc::check::scenario::Class;
use rocc::edit::{ClipEdit, Edit, edit_clip, edit_scn, parse_edit, read_boxes_json, rerasterize};
use rocc::eval::lidar::{bev_map, js_distance, jsd, mmd, read_points};
use rocc::eval::{OccScorer, read_occ, score_lidar_dirs, score_occ_dirs};
use rocc::import::{Convention, import_boxes, map_class, reference_frames};
use rocc::output::{bev_frame_path, read_npz};
use rocc::raster::{Bev, Rasterizer, rasterize};
use rocc::road::Map;
use rocc::source::SourceMap;
use std::path::{Path, PathBuf};
use tmp::TempDir;

/// A directory for this test's outputs, removed when dropped.
fn tmp_dir(name: &str) -> TempDir {
    TempDir::new("rocc-eval", name)
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/import").join(name)
}

// ------------------------------------------------------------------ scorer

#[test]
fn occ_scorer_matches_hand_computed_ious_and_the_absent_class_convention() {
    let mut gt = Array3::<u8>::zeros((NX, NY, NZ));
    let mut pred = Array3::<u8>::zeros((NX, NY, NZ));
    // Ground truth: four vehicle voxels. Prediction: two of them, two vehicle voxels elsewhere and
    // one pedestrian voxel — a class the ground truth never has.
    for k in 0..4 {
        gt[[10, 10, k]] = 2;
    }
    pred[[10, 10, 0]] = 2;
    pred[[10, 10, 1]] = 2;
    pred[[20, 20, 0]] = 2;
    pred[[20, 20, 1]] = 2;
    pred[[30, 30, 0]] = 4;
    let mut s = OccScorer::new();
    s.add(&pred, &gt);
    let r = s.scores();
    let n = (NX * NY * NZ) as f64;
    let c = |l: usize| &r.classes[l];
    // vehicle: TP 2, GT 4, pred 4 -> 2 / 6.
    assert_eq!((c(2).tp, c(2).gt, c(2).pred), (2, 4, 4));
    assert!((c(2).iou - 100.0 * 2.0 / 6.0).abs() < 1e-9);
    // pedestrian: absent from ground truth -> 100 by convention, and flagged.
    assert!(c(4).absent_from_gt && c(4).iou == 100.0 && c(4).pred == 1);
    // free: TP n-7, GT n-4, pred n-5 -> (n-7) / (n-2).
    let free = 100.0 * (n - 7.0) / (n - 2.0);
    assert!((c(0).iou - free).abs() < 1e-9);
    // background absent too.
    assert!(c(1).absent_from_gt && c(1).iou == 100.0);
    let us = (free + 100.0 + 100.0 * 2.0 / 6.0 + 5.0 * 100.0) / 8.0;
    let fg = (100.0 * 2.0 / 6.0 + 6.0 * 100.0) / 7.0;
    assert!((r.miou_us - us).abs() < 1e-9, "{} vs {us}", r.miou_us);
    assert!((r.fg_miou - fg).abs() < 1e-9);
    // occ-IoU: TP 2, GT 4, pred 5 -> 2 / 7.
    assert!((r.occ_iou - 100.0 * 2.0 / 7.0).abs() < 1e-9);
    assert!(r.table().contains("UniScene convention"));
}

#[test]
fn accumulation_is_over_the_set_not_a_mean_of_frames() {
    let mut a = Array3::<u8>::zeros((NX, NY, NZ));
    let b = Array3::<u8>::zeros((NX, NY, NZ));
    a[[0, 0, 0]] = 2;
    // Frame 1: one vehicle voxel, predicted. Frame 2: nine, none predicted.
    let mut g2 = Array3::<u8>::zeros((NX, NY, NZ));
    for k in 0..9 {
        g2[[5, 5, k]] = 2;
    }
    let mut s = OccScorer::new();
    s.add(&a, &a);
    s.add(&b, &g2);
    // Summed: TP 1, GT 10, pred 1 -> 10 %, not the per-frame mean of 100 % and 0 %.
    assert!((s.scores().classes[2].iou - 10.0).abs() < 1e-9);
}

fn write_dense(path: &Path, a: &Array3<u8>) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    a.write_npy(std::fs::File::create(path).unwrap()).unwrap();
}

#[test]
fn identical_sets_score_100_and_sparse_npz_reads_like_dense() {
    let d = tmp_dir("occ-ident");
    let mut a = Array3::<u8>::zeros((NX, NY, NZ));
    a[[100, 200, 12]] = 2;
    a[[101, 200, 12]] = 5;
    a[[3, 4, 11]] = 1;
    write_dense(&d.join("gt/000000.npy"), &a);
    write_dense(&d.join("pred/000000.npy"), &a);
    // nuPlan-Occ style sparse rows, int64.
    let rows = Array2::<i64>::from_shape_vec((3, 4), vec![100, 200, 12, 2, 101, 200, 12, 5, 3, 4, 11, 1]).unwrap();
    let mut w = NpzWriter::new(std::fs::File::create(d.join("sparse.npz")).unwrap());
    w.add_array("arr_0", &rows).unwrap();
    w.finish().unwrap();
    assert_eq!(read_occ(&d.join("sparse.npz")).unwrap(), a);
    let r = score_occ_dirs(&d.join("pred"), &d.join("gt")).unwrap();
    assert!(r.classes.iter().all(|c| c.iou == 100.0));
    assert_eq!((r.miou_us, r.fg_miou, r.occ_iou), (100.0, 100.0, 100.0));
    // A missing prediction and a bad label are diagnostics, not panics.
    write_dense(&d.join("gt/000001.npy"), &a);
    assert_eq!(score_occ_dirs(&d.join("pred"), &d.join("gt")).unwrap_err()[0].code, "E0703");
    let mut bad = a.clone();
    bad[[0, 0, 0]] = 9;
    write_dense(&d.join("pred/000001.npy"), &bad);
    assert_eq!(score_occ_dirs(&d.join("pred"), &d.join("gt")).unwrap_err()[0].code, "E0701");
    std::fs::write(d.join("pred/000001.npy"), b"not numpy").unwrap();
    assert_eq!(score_occ_dirs(&d.join("pred"), &d.join("gt")).unwrap_err()[0].code, "E0701");
}

#[test]
fn a_compiled_clip_directory_scores_its_occupancy_and_skips_bev_archives() {
    use rocc::compile::{Options, Stage, batch};
    let d = tmp_dir("occ-clip");
    let input = vec![PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios/replayed_cut_in.scn")];
    let o = Options { stage: Stage::Occ, frames: Some("0".into()), previews: false, ..Options::default() };
    let r = batch::run(&input, &d, &o, true);
    assert!(r.failures.is_empty());
    let clip = d.join("replayed_cut_in/ego");
    assert!(clip.join("bev/000000.npz").is_file() && clip.join("occ/000000.npy").is_file());
    // The recursive scan finds bev/*.npz too; those are BEV maps, not occupancy.
    let s = score_occ_dirs(&clip, &clip).expect("a clip directory scores");
    assert_eq!(s.occ_iou, 100.0);
    // A sparse archive under any member name is still occupancy, and still checked.
    let rows = Array2::<i64>::from_shape_vec((1, 4), vec![0, 0, 0, 9]).unwrap();
    let mut w = NpzWriter::new(std::fs::File::create(clip.join("bad_rows.npz")).unwrap());
    w.add_array("rows", &rows).unwrap();
    w.finish().unwrap();
    assert_eq!(score_occ_dirs(&clip, &clip).unwrap_err()[0].code, "E0701");
}

#[test]
fn lidar_metrics_on_hand_computed_fixtures() {
    // Disjoint distributions: JS distance sqrt(ln 2).
    assert!((js_distance(&[1.0, 0.0], &[0.0, 1.0]) - 2f64.ln().sqrt()).abs() < 1e-12);
    assert!(js_distance(&[0.2, 0.8], &[0.2, 0.8]).abs() < 1e-12);
    // One point in one voxel: the 100 x 100 map has one non-zero bin.
    let m = bev_map(&[[0.01, 0.01, 0.1]], false);
    let nz: Vec<(usize, f64)> = m.iter().copied().enumerate().filter(|(_, v)| *v > 0.0).collect();
    assert_eq!(nz.len(), 1);
    // x = 0.01 m -> voxel floor(51.21 / 0.15625) = 327; pooled bin 49 spans
    // [floor(6.56 * 49), ceil(6.56 * 50)) = [321, 328): 7 x 7 = 49 cells.
    assert_eq!(nz[0].0, 49 * 100 + 49);
    assert!((nz[0].1 - 1.0 / 49.0).abs() < 1e-12);
    // MMD of two single maps a, b (each normalised to 1): 2 - 2 k(a, b).
    let a = bev_map(&[[0.01, 0.01, 0.1]], false);
    let b = bev_map(&[[20.0, 0.01, 0.1]], false);
    let expect = 2.0 - 2.0 * (-2.0f64 / (2.0 * 0.25)).exp();
    let (sa, sb) = (std::slice::from_ref(&a), std::slice::from_ref(&b));
    assert!((mmd(sa, sb) - expect).abs() < 1e-12);
    assert_eq!(mmd(sa, sa), 0.0);
    assert_eq!(jsd(sa, sa), 0.0);
    // Range filter drops points inside 3 m.
    assert!(bev_map(&[[1.0, 0.0, 0.0]], true).iter().all(|v| *v == 0.0));
}

#[test]
fn identical_lidar_sets_give_mmd_and_jsd_zero() {
    let d = tmp_dir("lidar-ident");
    for sub in ["pred", "gt"] {
        std::fs::create_dir_all(d.join(sub)).unwrap();
        let mut bytes = Vec::new();
        for i in 0..500 {
            let a = i as f32 * 0.1;
            for v in [10.0 * a.cos(), 10.0 * a.sin(), -1.0 + 0.001 * i as f32, 100.0] {
                bytes.extend(v.to_le_bytes());
            }
        }
        std::fs::write(d.join(sub).join("000000.bin"), &bytes).unwrap();
    }
    let s = score_lidar_dirs(&d.join("pred"), &d.join("gt"), false).unwrap();
    assert_eq!((s.mmd, s.jsd), (0.0, 0.0));
    std::fs::write(d.join("pred/000001.bin"), [0u8; 7]).unwrap();
    assert_eq!(score_lidar_dirs(&d.join("pred"), &d.join("gt"), false).unwrap_err()[0].code, "E0704");
}

#[test]
fn eval_lidar_reads_the_clouds_of_clip_directories_and_pcd_files() {
    let compile = |out: &Path, stage: &str| {
        let scn = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/replayed_cut_in.scn");
        let st = std::process::Command::new(env!("CARGO_BIN_EXE_rocc"))
            .args(["compile", scn.to_str().unwrap(), "-o", out.to_str().unwrap(), "--frames", "0..2", "-q"])
            .args(["--no-previews", "--lidar-resolution", "2", "--stage", stage])
            .status()
            .unwrap();
        assert!(st.success());
        out.join("replayed_cut_in/ego")
    };
    let out = tmp_dir("lidar-clip");
    let clip = compile(&out, "lidar");
    // The clip, the whole output and the lidar folder hold the same two clouds: each frame's
    // `.bin` and `.pcd` count once, and `occ/*.npy` is never read as a cloud.
    for d in [clip.as_path(), out.path(), &clip.join("lidar")] {
        let s = score_lidar_dirs(d, &clip, false).unwrap_or_else(|e| panic!("{}: {}", d.display(), e[0].message));
        assert_eq!((s.pred_clouds, s.gt_clouds, s.mmd, s.jsd), (2, 2, 0.0, 0.0), "{}", d.display());
    }
    // PCD (binary, as rocc writes it) reads like the `.bin`; a plain directory of `.pcd` scores alike.
    let plain = out.join("plain");
    std::fs::create_dir_all(&plain).unwrap();
    for f in 0..2 {
        let (bin, pcd) = (clip.join(format!("lidar/{f:06}.bin")), clip.join(format!("lidar/{f:06}.pcd")));
        let pts = read_points(&bin).unwrap();
        assert!(pts.len() > 1000);
        assert_eq!(read_points(&pcd).unwrap(), pts);
        std::fs::copy(&pcd, plain.join(format!("{f:06}.pcd"))).unwrap();
    }
    let s = score_lidar_dirs(&plain, &clip, false).unwrap();
    assert_eq!((s.pred_clouds, s.mmd, s.jsd), (2, 0.0, 0.0));
    // ASCII PCD with extra fields and counts.
    let ascii = "VERSION 0.7\nFIELDS ring x y z rgb\nSIZE 2 4 4 4 4\nTYPE U F F F F\nCOUNT 1 1 1 1 2\n\
                 WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n3 1.5 -2 0.25 0 0\n4 10 20 -1 0 0\n";
    assert_eq!(rocc::eval::lidar::read_pcd(ascii.as_bytes()).unwrap(), vec![[1.5, -2.0, 0.25], [10.0, 20.0, -1.0]]);
    assert!(
        rocc::eval::lidar::read_pcd(b"VERSION 0.7\nFIELDS a b\nSIZE 4 4\nTYPE F F\nPOINTS 0\nDATA ascii\n").is_err()
    );
    // A clip compiled without LiDAR, or a directory with no clouds: E0703 naming it, not an
    // attempt to read `occ/*.npy` as points.
    let none = tmp_dir("lidar-none");
    let occ_only = compile(&none, "occ");
    let e = score_lidar_dirs(&occ_only, &clip, false).unwrap_err();
    assert_eq!(e[0].code, "E0703");
    assert!(e[0].message.contains("no LiDAR frames") && e[0].message.contains("replayed_cut_in"), "{}", e[0].message);
    let empty = tmp_dir("lidar-empty");
    assert_eq!(score_lidar_dirs(&clip, &empty, false).unwrap_err()[0].code, "E0703");
}

// ------------------------------------------------------------------ import

fn import(name: &str, conv: Convention) -> rocc::import::Imported {
    let mut sources = SourceMap::default();
    import_boxes(&fixture(name), conv, "imported", &mut sources)
        .unwrap_or_else(|d| panic!("{}", d.iter().map(|d| d.render_plain(&sources)).collect::<String>()))
}

fn box_of<'a>(imp: &'a rocc::import::Imported, frame: usize, track: &str) -> &'a rocc::import::RecBox {
    imp.recorded.frames[frame].boxes.iter().find(|b| b.track == track).unwrap()
}

#[test]
fn nuscenes_convention_is_wlh_global_yaw() {
    let imp = import("nuscenes.json", Convention::NuScenes);
    let r = &imp.recorded;
    assert_eq!(r.rate, 2.0);
    assert_eq!(r.origin, (0.0, 1000.0));
    let car = box_of(&imp, 0, "car-a");
    assert_eq!(car.size, [4.6, 1.9, 1.6]);
    assert_eq!((car.pose.x, car.pose.y, car.pose.yaw), (412.0, 103.5, 0.1));
    assert_eq!((car.class, car.kind), (Class::Vehicle, "sedan"));
    // Quaternion (cos 0.01, 0, 0, sin 0.01) ~ yaw 0.04 for (0.9998, 0, 0, 0.02).
    assert!((r.frames[1].ego.yaw - 2f64 * 0.02f64.atan2(0.9998)).abs() < 1e-6);
    // Unknown class: kept as generic_object, with a warning.
    let x = box_of(&imp, 0, "x9");
    assert_eq!(x.class, Class::GenericObject);
    assert!(imp.warnings.iter().any(|w| w.code == "E0715" && !w.is_error()));
    // A track with a gap becomes two agents.
    assert!(imp.agents.iter().any(|a| a.0 == "t_ped_1") && imp.agents.iter().any(|a| a.0 == "t_ped_1_2"));
}

#[test]
fn mmdet3d_convention_converts_yaw_dims_and_sensor_frame() {
    let imp = import("mmdet3d.json", Convention::Mmdet3d);
    let car = box_of(&imp, 0, "1");
    // dims (w, l, h) -> (l, w, h); yaw = -(-pi/2) - pi/2 = 0 in the sensor frame.
    assert_eq!(car.size, [4.4, 1.8, 1.5]);
    // Sensor (8, -3) -> ego (8.94, -3) -> world by the ego pose (10, 20, 0.5).
    let (s, c) = 0.5f64.sin_cos();
    assert!((car.pose.x - (10.0 + c * 8.94 + s * 3.0)).abs() < 1e-12);
    assert!((car.pose.y - (20.0 + s * 8.94 - c * 3.0)).abs() < 1e-12);
    assert!((car.pose.yaw - 0.5).abs() < 1e-12);
    // yaw_mm = 0 -> yaw = -pi/2 in the sensor frame.
    let bike = box_of(&imp, 0, "2");
    assert!((bike.pose.yaw - (0.5 - std::f64::consts::FRAC_PI_2)).abs() < 1e-12);
    assert_eq!((bike.class, bike.size), (Class::Bicycle, [1.8, 0.6, 1.7]));
}

#[test]
fn nuplan_convention_is_lwh_and_large_coordinates_shift_by_whole_km() {
    let imp = import("nuplan.json", Convention::NuPlan);
    assert_eq!(imp.recorded.origin, (664000.0, 3997000.0));
    let v = box_of(&imp, 0, "tok1");
    assert_eq!(v.size, [4.8, 2.0, 1.6]);
    assert_eq!((v.pose.x, v.pose.y, v.pose.yaw), (340.0, 110.0, -2.1));
    assert_eq!(box_of(&imp, 0, "tok2").class, Class::CzoneSign);
    assert_eq!(imp.recorded.rate, 20.0);
    // The convention named in the file must agree with the flag.
    let mut sources = SourceMap::default();
    let e = import_boxes(&fixture("nuplan.json"), Convention::NuScenes, "x", &mut sources).unwrap_err();
    assert_eq!(e[0].code, "E0706");
}

#[test]
fn class_names_map_to_the_nuplan_taxonomy() {
    for (n, c) in [
        ("vehicle.bus.rigid", Class::Vehicle),
        ("vehicle.motorcycle", Class::Bicycle),
        ("motorcycle", Class::Bicycle),
        ("human.pedestrian.police_officer", Class::Pedestrian),
        ("movable_object.trafficcone", Class::TrafficCone),
        ("construction_vehicle", Class::Vehicle),
        ("animal", Class::GenericObject),
        ("czone_sign", Class::CzoneSign),
    ] {
        let m = map_class(n);
        assert!(m.known && m.class == c, "{n}");
    }
    assert!(!map_class("ufo").known);
}

#[test]
fn bad_box_streams_are_diagnostics_with_a_span() {
    let d = tmp_dir("bad-stream");
    let mut sources = SourceMap::default();
    std::fs::write(d.join("a.json"), "{ \"frames\": [ { \"frame\": 0, \"time\": 0.0 } ] }").unwrap();
    let e = import_boxes(&d.join("a.json"), Convention::NuPlan, "x", &mut sources).unwrap_err();
    assert_eq!(e[0].code, "E0705");
    assert!(e[0].span().is_some());
    std::fs::write(d.join("b.json"), "{ \"frames\": [] }").unwrap();
    assert_eq!(import_boxes(&d.join("b.json"), Convention::NuPlan, "x", &mut sources).unwrap_err()[0].code, "E0706");
}

/// Per-channel IoU of two BEVs (masks), 1.0 where both are empty.
fn channel_ious(a: &Bev, b: &Bev) -> Vec<f64> {
    (0..18)
        .map(|c| {
            let (mut i, mut u) = (0u64, 0u64);
            for (x, y) in a.masks.index_axis(ndarray::Axis(0), c).iter().zip(b.masks.index_axis(ndarray::Axis(0), c)) {
                i += (*x != 0 && *y != 0) as u64;
                u += (*x != 0 || *y != 0) as u64;
            }
            if u == 0 { 1.0 } else { i as f64 / u as f64 }
        })
        .collect()
}

#[test]
fn import_is_lossless_at_the_recorded_frames() {
    for (f, conv) in [
        ("nuscenes.json", Convention::NuScenes),
        ("mmdet3d.json", Convention::Mmdet3d),
        ("nuplan.json", Convention::NuPlan),
    ] {
        let imp = import(f, conv);
        let mut sources = SourceMap::default();
        let scen = rocc::check::check_text("imported.scn", &imp.text, Path::new("."), &mut sources).unwrap();
        let front = rocc::compile::front(scen, None).unwrap();
        let ego = front.egos(&[]).unwrap()[0];
        assert_eq!(front.tracks.frames, imp.recorded.frames.len(), "{f}");
        let reference = reference_frames(&imp);
        let mut drawn = 0;
        for (n, (pose, boxes)) in reference.iter().enumerate() {
            let via_scn =
                rasterize(&front.map, front.tracks.poses[ego][n], &rocc::compile::frame_boxes(&front, ego, n));
            let direct = rasterize(&Map::default(), *pose, boxes);
            let ious = channel_ious(&via_scn, &direct);
            assert!(ious.iter().all(|&v| v == 1.0), "{f} frame {n}: {ious:?}");
            assert_eq!(via_scn, direct, "{f} frame {n}: masks, aux and structure identical");
            drawn += direct.masks.iter().filter(|&&v| v != 0).count();
        }
        assert!(drawn > 0, "{f}: the fixture draws something");
    }
}

// ------------------------------------------------------------------ edit

/// A compiled clip of the library's cut-in, and the directory that holds it (removed when
/// dropped).
fn compiled_clip(name: &str) -> (TempDir, PathBuf) {
    let out = tmp_dir(name);
    let scn = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/replayed_cut_in.scn");
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_rocc"))
        .args(["compile", scn.to_str().unwrap(), "-o", out.to_str().unwrap(), "--frames", "0..2", "-q"])
        .status()
        .unwrap();
    assert!(st.success());
    let clip = out.join("replayed_cut_in/ego");
    (out, clip)
}

#[test]
fn rerasterising_unedited_boxes_reproduces_the_bev() {
    let (_out, dir) = compiled_clip("rerast");
    let frames = read_boxes_json(&dir.join("boxes.json")).unwrap();
    let mut raster = Rasterizer::new();
    for fb in &frames {
        let old = read_npz(&bev_frame_path(&dir, fb.frame)).unwrap();
        let mut new = Bev::zeros();
        rerasterize(&old, &fb.boxes, &mut raster, &mut new);
        assert!(channel_ious(&old, &new).iter().all(|&v| v == 1.0));
        assert_eq!(old, new);
    }
}

#[test]
fn clip_edits_change_exactly_the_box_list_and_rerun_the_stages() {
    let (_out, dir) = compiled_clip("edit");
    let before = read_boxes_json(&dir.join("boxes.json")).unwrap();
    let bev0 = read_npz(&bev_frame_path(&dir, 0)).unwrap();
    let o = ClipEdit {
        scenario: Some(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/replayed_cut_in.scn")),
        ..Default::default()
    };

    // Rejected: off its surface, overlapping, unknown agent, unknown kind. Nothing is written.
    let manifest_before = std::fs::read(dir.join("manifest.json")).unwrap();
    let ins = |w: &str| parse_edit("insert", &w.split(' ').map(String::from).collect::<Vec<_>>()).unwrap();
    let code = |e: Edit| edit_clip(&dir, &[e], &o).unwrap_err()[0].code;
    assert_eq!(code(ins("sedan at 20,40 yaw 0")), "E0710");
    assert_eq!(code(ins("bicycle at 20,40 yaw 0")), "E0710");
    assert_eq!(code(ins("sedan at 10,-3 yaw 0")), "E0711");
    assert_eq!(code(ins("sedan at 1,0 yaw 0")), "E0711", "the ego's own box");
    assert_eq!(code(Edit::Delete { agent: "cuter".into() }), "E0709");
    assert_eq!(code(ins("sedna at 20,0 yaw 0")), "E0713");
    // Frames of the scenario the clip does not hold (it holds 0..2): an error, not a no-op.
    let later = ClipEdit { frames: Some("20..=25".into()), ..o.clone() };
    let err = edit_clip(&dir, &[ins("sedan at 20,0 yaw 0")], &later).unwrap_err();
    assert_eq!(err[0].code, "E0718");
    assert!(err[0].message.contains("--frames 20..=25"), "{}", err[0].message);
    assert_eq!(std::fs::read(dir.join("manifest.json")).unwrap(), manifest_before);
    assert_eq!(parse_edit("insert", &["sedan".into(), "at".into(), "x".into()]).unwrap_err().code, "E0717");

    // Insert: one more box in every frame; the static layers are untouched.
    edit_clip(&dir, &[ins("sedan at 20,0 yaw 0")], &o).unwrap();
    let after = read_boxes_json(&dir.join("boxes.json")).unwrap();
    for (a, b) in before.iter().zip(&after) {
        assert_eq!(b.boxes.len(), a.boxes.len() + 1);
        assert_eq!(&b.boxes[..a.boxes.len()], &a.boxes[..]);
        let new = b.boxes.last().unwrap();
        assert_eq!((new.agent.as_str(), new.class, new.y), ("inserted_sedan_1", Class::Vehicle, 0.0));
        // Given in frame 0's ego frame and fixed in the world: the ego drives east towards it.
        if b.frame == 0 {
            assert_eq!(new.x, 20.0);
        } else {
            assert!(new.x < 20.0 - 1.0, "frame {}: {}", b.frame, new.x);
        }
    }
    let bev1 = read_npz(&bev_frame_path(&dir, 0)).unwrap();
    for ch in rocc::raster::STATIC_CHANNELS {
        assert_eq!(bev0.masks.index_axis(ndarray::Axis(0), ch), bev1.masks.index_axis(ndarray::Axis(0), ch));
    }
    let veh = |b: &Bev| b.masks.index_axis(ndarray::Axis(0), 8).iter().filter(|&&v| v != 0).count();
    assert!(veh(&bev1) > veh(&bev0) + 100);
    // The occupancy now holds the inserted car.
    let occ = rocc::eval::occ::read_occupancy(&dir.join("occ/000000.npy")).unwrap();
    let car = after[0].boxes.last().unwrap();
    let cov = rocc::eval::edits::coverage(&occ, car, 2, None).unwrap();
    assert!(cov > 0.5, "inserted car covered {cov}");
    let m: rocc::output::Manifest =
        serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(m.edits.len(), 1);
    assert!(m.files.iter().any(|f| f.path == "lidar/000000.bin"));

    // Move then delete: the moved box keeps its identity; delete removes exactly it.
    edit_clip(&dir, &[Edit::Move { agent: "cutter".into(), dx: 0.0, dy: -1.0 }], &o).unwrap();
    let moved = read_boxes_json(&dir.join("boxes.json")).unwrap();
    let c0 = before[0].boxes.iter().find(|b| b.agent == "cutter").unwrap();
    let c1 = moved[0].boxes.iter().find(|b| b.agent == "cutter").unwrap();
    assert_eq!((c1.x, c1.y, c1.yaw), (c0.x, c0.y - 1.0, c0.yaw));
    edit_clip(&dir, &[Edit::Delete { agent: "cutter".into() }], &o).unwrap();
    let deleted = read_boxes_json(&dir.join("boxes.json")).unwrap();
    assert!(deleted.iter().all(|f| f.boxes.iter().all(|b| b.agent != "cutter") && f.boxes.len() == 1));

    // A person standing on the ego's lane: the checker places one there, and so does an edit.
    edit_clip(&dir, &[ins("pedestrian at 40,0 yaw 90deg")], &o).unwrap();
    let person = read_boxes_json(&dir.join("boxes.json")).unwrap();
    assert!(person.iter().all(|f| f.boxes.len() == 2 && f.boxes[1].class == Class::Pedestrian));
}

/// An ego driving east at exactly 10 m/s (1 m per frame at 10 Hz) past a static cone.
const DRIVE_BY: &str = "scenario drive_by {
    seed 1
    duration 1 s
    rate 10 Hz
    egos [ego]
    road straight { lanes 2; lane_width 3.5 m; speed_limit 60 km/h; length 240 m }
    agent ego: sedan {
        at west.in[1], 60 m before center
        speed 36 km/h
        goal { speed 36 km/h }
    }
    agent cone: traffic_cone { at (-40 m, 6 m) heading 0 deg }
}
";

fn drive_by_clip(name: &str, stage: &str) -> (TempDir, PathBuf, PathBuf) {
    let out = tmp_dir(name);
    let scn = out.join("drive_by.scn");
    std::fs::write(&scn, DRIVE_BY).unwrap();
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_rocc"))
        .args(["compile", scn.to_str().unwrap(), "-o", out.to_str().unwrap(), "--frames", "0..4", "-q"])
        .args(["--no-previews", "--stage", stage])
        .status()
        .unwrap();
    assert!(st.success());
    let clip = out.join("drive_by/ego");
    (out, clip, scn)
}

#[test]
fn clip_edits_are_fixed_in_the_world_while_the_ego_moves() {
    let (_out, dir, scn) = drive_by_clip("world-fixed", "bev");
    let before = read_boxes_json(&dir.join("boxes.json")).unwrap();
    // The recorded static cone, hand-checked: the ego (yaw 0) gains 1 m per frame on it.
    let cone =
        |fs: &[rocc::output::FrameBoxes], f: usize| fs[f].boxes.iter().find(|b| b.agent == "cone").cloned().unwrap();
    for f in 0..4 {
        let c = cone(&before, f);
        assert!((c.x - (20.0 - f as f64)).abs() < 1e-9 && (c.y - 7.75).abs() < 1e-9, "frame {f}: {c:?}");
    }
    let o = ClipEdit { scenario: Some(scn.clone()), ..Default::default() };
    let ins = |w: &str| parse_edit("insert", &w.split(' ').map(String::from).collect::<Vec<_>>()).unwrap();
    edit_clip(&dir, &[ins("traffic_cone at 12,-6 yaw 30")], &o).unwrap();
    let after = read_boxes_json(&dir.join("boxes.json")).unwrap();
    for f in 0..4 {
        let b = after[f].boxes.iter().find(|b| b.agent == "inserted_traffic_cone_1").unwrap();
        // The inverse of the ego's motion: -1 m in x per frame, y and yaw unchanged.
        let want = (12.0 - f as f64, -6.0, 30f64.to_radians());
        assert!(
            (b.x - want.0).abs() < 1e-9 && (b.y - want.1).abs() < 1e-9 && (b.yaw - want.2).abs() < 1e-9,
            "frame {f}: {b:?}"
        );
        // Exactly like the compiled static cone.
        let c = cone(&after, f);
        assert!(((b.x - c.x) - (12.0 - 20.0)).abs() < 1e-9, "frame {f}");
    }
    // A move is a world displacement too: the cone shifts 2 m right in every frame.
    edit_clip(&dir, &[Edit::Move { agent: "cone".into(), dx: 0.5, dy: -2.0 }], &o).unwrap();
    let moved = read_boxes_json(&dir.join("boxes.json")).unwrap();
    for f in 0..4 {
        let (a, b) = (cone(&after, f), cone(&moved, f));
        assert!((b.x - a.x - 0.5).abs() < 1e-9 && (b.y - a.y + 2.0).abs() < 1e-9, "frame {f}");
    }
    // Free in frames 0 and 1, under the ego from frame 2 on (4 - 2 - 0.2 < the ego's half length):
    // refused, naming the frame; nothing written.
    let manifest = std::fs::read(dir.join("manifest.json")).unwrap();
    let e = edit_clip(&dir, &[ins("traffic_cone at 4,0 yaw 0")], &o).unwrap_err();
    assert_eq!(e[0].code, "E0711");
    assert!(e[0].message.contains("in frame 2,") && e[0].message.contains("the ego"), "{}", e[0].message);
    assert_eq!(std::fs::read(dir.join("manifest.json")).unwrap(), manifest);
    // With `--frames 0..2` it fits; the history records the frame the position was given in.
    let first = ClipEdit { frames: Some("0..2".into()), ..o.clone() };
    edit_clip(&dir, &[ins("traffic_cone at 4,0 yaw 0")], &first).unwrap();
    let m: rocc::output::Manifest =
        serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(
        m.edits,
        [
            "insert traffic_cone at 12,-6 yaw 30deg (ego frame of frame 0)",
            "move cone by 0.5,-2 (ego frame of frame 0)",
            "insert traffic_cone at 4,0 yaw 0deg (ego frame of frame 0; frames 0..2)",
        ]
    );
}

#[test]
fn scn_edits_are_gated_by_the_checker_and_placement() {
    let scn = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/replayed_cut_in.scn");
    let mut sources = SourceMap::default();
    let text = edit_scn(&scn, &[Edit::Move { agent: "cutter".into(), dx: 0.0, dy: 0.5 }], &mut sources).unwrap();
    assert!(text.contains("(-50 m, -4.75 m)") && text.contains("(9 m, -1.25 m)"));
    let text = edit_scn(
        &scn,
        &[
            Edit::Insert { kind: "traffic_cone".into(), x: 40.0, y: -7.0, yaw: 0.0 },
            Edit::Delete { agent: "cutter".into() },
        ],
        &mut sources,
    )
    .unwrap();
    assert!(text.contains("agent inserted_traffic_cone_1: traffic_cone { at (40 m, -7 m) heading 0 deg }"));
    assert!(!text.contains("agent cutter"));
    // The `expect` lines naming the deleted agent go with it; the others stay.
    assert!(!text.contains("gap cutter with ego") && text.contains("speed ego at_most"), "{text}");
    // Rejections say why: a vehicle off the road (E0201), an overlap (E0202), road-relative move.
    let code = |e: Edit| edit_scn(&scn, &[e], &mut SourceMap::default()).unwrap_err()[0].code;
    assert_eq!(code(Edit::Insert { kind: "sedan".into(), x: 0.0, y: 40.0, yaw: 0.0 }), "E0201");
    assert_eq!(code(Edit::Insert { kind: "sedan".into(), x: -60.0, y: -1.75, yaw: 0.0 }), "E0202");
    assert_eq!(code(Edit::Move { agent: "ego".into(), dx: 1.0, dy: 0.0 }), "E0714");
    assert_eq!(code(Edit::Delete { agent: "nobody".into() }), "E0709");
    // A person on a lane passes the checker's surface rule, as in a clip edit.
    let on_lane = Edit::Insert { kind: "pedestrian".into(), x: 30.0, y: -1.75, yaw: 0.0 };
    let text = edit_scn(&scn, &[on_lane], &mut SourceMap::default()).unwrap();
    assert!(text.contains("agent inserted_pedestrian_1: pedestrian { at (30 m, -1.75 m)"), "{text}");
}

#[test]
fn edit_protocol_runs_and_scores_every_class() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let s = rocc::eval::run_edit_protocol(&dir, 2, 7).unwrap();
    assert_eq!(s.scenes, 2);
    assert!(s.insert.values().filter(|c| c.n > 0).count() >= 5, "{}", s.table());
    assert!(s.table().contains("| vehicle |"));
}
