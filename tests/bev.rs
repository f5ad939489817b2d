//! BEV rasterisation, view transform and output files, on hand-made maps and boxes.

use glam::DVec2;
use ndarray::{Array2, Axis, s};
use rocc::check::scenario::Class;
use rocc::output::{self, FrameBoxes, Manifest};
use rocc::place::Pose;
use rocc::raster::fill::Filler;
use rocc::raster::layout::*;
use rocc::raster::{Bev, Rasterizer, fill, rasterize};
use rocc::road::map::Map;
use rocc::view::{AgentState, EgoBox, to_ego};
use std::f64::consts::FRAC_PI_2;
use std::path::PathBuf;
use std::process::Command;

const ORIGIN: Pose = Pose { x: 0.0, y: 0.0, yaw: 0.0 };

fn ego_box(class: Class, x: f64, y: f64, yaw: f64, l: f64, w: f64, h: f64) -> EgoBox {
    EgoBox { agent: "a".into(), kind: "k".into(), class, track: 0, x, y, z: h / 2.0, l, w, h, yaw }
}

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<DVec2> {
    vec![DVec2::new(x0, y0), DVec2::new(x1, y0), DVec2::new(x1, y1), DVec2::new(x0, y1)]
}

/// A plus-shaped junction: two crossing 14 m roads, a 14 m square intersection, a divider and a
/// crosswalk per arm.
fn cross_map() -> Map {
    let mut m = Map::default();
    let (r, far) = (7.0, 120.0);
    m.intersections = vec![rect(-r, -r, r, r)];
    m.road_segments = vec![rect(r, -r, far, r), rect(-far, -r, -r, r), rect(-r, r, r, far), rect(-r, -far, r, -r)];
    m.drivable = vec![rect(-far, -r, far, r), rect(-r, -far, r, far)];
    m.lane_groups = vec![rect(r, -r, far, 0.0), rect(r, 0.0, far, r)];
    m.lane_group_connectors = vec![vec![DVec2::new(-r, 0.0), DVec2::new(0.0, r), DVec2::new(r, 0.0)]];
    m.walkways = vec![rect(r, r + 0.5, far, r + 3.0)];
    m.crosswalk_polygons = vec![rect(r + 0.5, -r, r + 4.5, r)];
    m.dividers = vec![vec![DVec2::new(r + 5.0, 0.1), DVec2::new(far, 0.1)]];
    m
}

fn on_pixels(p: ndarray::ArrayView2<i8>) -> Vec<(usize, usize)> {
    p.indexed_iter().filter(|(_, v)| **v != 0).map(|(ij, _)| ij).collect()
}

fn bbox(px: &[(usize, usize)]) -> (usize, usize, usize, usize) {
    let i0 = px.iter().map(|p| p.0).min().expect("non-empty");
    let i1 = px.iter().map(|p| p.0).max().expect("non-empty");
    let j0 = px.iter().map(|p| p.1).min().expect("non-empty");
    let j1 = px.iter().map(|p| p.1).max().expect("non-empty");
    (i0, i1, j0, j1)
}

#[test]
fn shapes_and_dtypes_follow_the_spec() {
    let bev = rasterize(&Map::default(), ORIGIN, &[]);
    assert_eq!(bev.masks.dim(), (18, 400, 400));
    assert_eq!(bev.aux.dim(), (7, 400, 400));
    assert_eq!(bev.structure.dim(), (400, 400));
    assert!(bev.masks.iter().all(|&v| v == 0));
}

#[test]
fn box_at_the_ego_origin_is_centred_on_pixel_200() {
    let bev = rasterize(&Map::default(), ORIGIN, &[ego_box(Class::Vehicle, 0.0, 0.0, 0.0, 4.0, 2.0, 1.5)]);
    let px = on_pixels(bev.masks.index_axis(Axis(0), CH_VEHICLE));
    let (i0, i1, j0, j1) = bbox(&px);
    // Corners at u = 200 +- 8, v = 200 +- 4; cv2 includes the edges.
    assert_eq!((i0, i1, j0, j1), (192, 208, 196, 204));
    assert_eq!((i0 + i1, j0 + j1), (400, 400));
    for ij in [(199, 199), (199, 200), (200, 199), (200, 200)] {
        assert_eq!(bev.masks[[CH_VEHICLE, ij.0, ij.1]], 1);
    }
}

#[test]
fn box_ten_metres_ahead_lands_at_i_240() {
    let bev = rasterize(&Map::default(), ORIGIN, &[ego_box(Class::Vehicle, 10.0, 0.0, 0.0, 4.0, 2.0, 1.5)]);
    let (i0, i1, j0, j1) = bbox(&on_pixels(bev.masks.index_axis(Axis(0), CH_VEHICLE)));
    assert_eq!(((i0 + i1) / 2, (j0 + j1) / 2), (240, 200));
}

#[test]
fn axis_aligned_4_by_2_box_fills_17_by_9_pixels() {
    let bev = rasterize(&Map::default(), ORIGIN, &[ego_box(Class::Pedestrian, 3.3, -7.1, 0.0, 4.0, 2.0, 1.0)]);
    let count = bev.masks.index_axis(Axis(0), CH_PEDESTRIAN).iter().filter(|&&v| v == 1).count();
    assert_eq!(count, 17 * 9);
    // Every other channel stays empty.
    assert_eq!(bev.masks.iter().filter(|&&v| v == 1).count(), count);
}

#[test]
fn every_class_goes_to_its_channel_and_structure_to_its_own_mask() {
    let classes = [
        (Class::Vehicle, Some(8)),
        (Class::Bicycle, Some(9)),
        (Class::Pedestrian, Some(10)),
        (Class::TrafficCone, Some(11)),
        (Class::Barrier, Some(12)),
        (Class::CzoneSign, Some(13)),
        (Class::GenericObject, Some(14)),
        (Class::Structure, None),
    ];
    for (k, (class, ch)) in classes.into_iter().enumerate() {
        let b = ego_box(class, -20.0 + 5.0 * k as f64, 3.0, 0.4, 2.0, 1.0, 1.0);
        let bev = rasterize(&Map::default(), ORIGIN, &[b]);
        match ch {
            Some(ch) => {
                assert!(bev.masks.index_axis(Axis(0), ch).iter().any(|&v| v == 1), "{class:?}");
                assert!(bev.structure.iter().all(|&v| v == 0));
            }
            None => {
                assert!(bev.structure.iter().any(|&v| v == 1));
                assert!(bev.masks.iter().all(|&v| v == 0), "structure must not touch the 18 channels");
                assert!(bev.aux.iter().all(|&v| v == 0), "structure gets no aux");
            }
        }
    }
}

#[test]
fn rerasterising_is_identical() {
    let map = cross_map();
    let ego = Pose { x: 3.0, y: -2.0, yaw: 0.3 };
    let boxes: Vec<EgoBox> = (0..20)
        .map(|k| {
            ego_box(Class::Vehicle, -40.0 + 4.3 * k as f64, (k % 5) as f64 * 3.1 - 6.0, 0.1 * k as f64, 4.5, 1.9, 1.6)
        })
        .collect();
    let a = rasterize(&map, ego, &boxes);
    let mut r = Rasterizer::new();
    let mut b = Bev::zeros();
    // A dirty buffer from another frame must not leak into the next one.
    r.rasterize_into(&map, ORIGIN, &[ego_box(Class::Barrier, 1.0, 1.0, 0.0, 30.0, 30.0, 1.0)], &mut b);
    r.rasterize_into(&map, ego, &boxes, &mut b);
    assert_eq!(a, b);
    // IoU 1.0 per channel, spelled out.
    for ch in 0..N_MASKS {
        let (pa, pb) = (a.masks.index_axis(Axis(0), ch), b.masks.index_axis(Axis(0), ch));
        let inter = pa.iter().zip(pb.iter()).filter(|(x, y)| **x == 1 && **y == 1).count();
        let union = pa.iter().zip(pb.iter()).filter(|(x, y)| **x == 1 || **y == 1).count();
        assert_eq!(inter, union, "channel {ch}");
    }
}

#[test]
fn map_layers_land_in_their_channels() {
    let bev = rasterize(&cross_map(), ORIGIN, &[]);
    let at = |ch: usize, x: f64, y: f64| bev.masks[[ch, to_canvas(x) as usize, to_canvas(y) as usize]];
    assert_eq!(at(CH_INTERSECTIONS, 0.0, 0.0), 1);
    assert_eq!(at(CH_INTERSECTIONS, 20.0, 0.0), 0);
    assert_eq!(at(CH_ROAD_SEGMENTS, 20.0, 0.0), 1);
    assert_eq!(at(CH_DRIVABLE, 0.0, 30.0), 1);
    assert_eq!(at(CH_DRIVABLE, 20.0, 20.0), 0);
    assert_eq!(at(CH_WALKWAYS, 20.0, 9.0), 1);
    assert_eq!(at(CH_CROSSWALKS, 9.5, 3.0), 1);
    assert_eq!(at(CH_LANE_GROUPS, 20.0, -3.0), 1);
    assert_eq!(at(CH_LANE_GROUP_CONNECTORS, 0.0, 3.0), 1);
    // Divider at y = 0.1 m: canvas v = 200.4, truncated to 200; a line plus dots at its ends.
    let div = on_pixels(bev.masks.index_axis(Axis(0), CH_DIVIDER));
    assert!(div.iter().filter(|p| p.0 > 260 && p.0 < 390).all(|p| p.1 == 200));
    assert!(div.contains(&(4 * 12 + 200, 199)) && div.contains(&(4 * 12 + 200, 201)), "radius-1 dot at the start");
    // Crosswalk outline: the polygon's edge, not its inside.
    assert_eq!(bev.masks[[CH_PED_CROSSING, 230, 200]], 1);
    assert_eq!(bev.masks[[CH_PED_CROSSING, 236, 200]], 0);
    // Far geometry is cropped at the patch: nothing wraps or overflows.
    assert_eq!(bev.masks[[CH_ROAD_SEGMENTS, 399, 200]], 1);
}

/// The rule spelled out on the rasterised channels; tests/raster_templates.rs checks ch 17
/// against an independent point-in-polygon reference on every template.
#[test]
fn boundary_is_the_outline_of_road_segments_and_intersections() {
    let ego = Pose { x: 2.0, y: 1.0, yaw: 0.35 };
    let bev = rasterize(&cross_map(), ego, &[]);
    let road: Array2<bool> = ndarray::Zip::from(bev.masks.index_axis(Axis(0), CH_ROAD_SEGMENTS))
        .and(bev.masks.index_axis(Axis(0), CH_INTERSECTIONS))
        .map_collect(|&a, &b| a == 1 || b == 1);
    let mut expect = Array2::<i8>::zeros((400, 400));
    for ((i, j), &r) in road.indexed_iter() {
        let out = |di: i64, dj: i64| {
            let (a, b) = (i as i64 + di, j as i64 + dj);
            (0..400).contains(&a) && (0..400).contains(&b) && !road[[a as usize, b as usize]]
        };
        if r && (out(-1, 0) || out(1, 0) || out(0, -1) || out(0, 1)) {
            expect[[i, j]] = 1;
        }
    }
    assert_eq!(bev.masks.index_axis(Axis(0), CH_BOUNDARY), expect);
    assert!(expect.iter().filter(|&&v| v == 1).count() > 400, "the outline is non-trivial");
}

/// Rotate a world point by +90 degrees about the origin.
fn rot90(p: DVec2) -> DVec2 {
    DVec2::new(-p.y, p.x)
}

#[test]
fn rotating_map_and_ego_together_changes_nothing() {
    // Axis-aligned rectangles on exact pixel coordinates, so rounding cannot differ.
    let m = Map {
        road_segments: vec![rect(-30.0, -3.5, 40.0, 3.5)],
        intersections: vec![rect(-3.5, -12.0, 3.5, 20.0)],
        dividers: vec![vec![DVec2::new(-20.1, 0.1), DVec2::new(30.1, 0.1)]],
        ..Map::default()
    };
    let mut r = m.clone();
    for layer in [&mut r.road_segments, &mut r.intersections] {
        for poly in layer.iter_mut() {
            for p in poly.iter_mut() {
                *p = rot90(*p);
            }
        }
    }
    for l in &mut r.dividers {
        for p in l.iter_mut() {
            *p = rot90(*p);
        }
    }
    let a = rasterize(&m, Pose { x: 0.0, y: 0.0, yaw: 0.0 }, &[]);
    let b = rasterize(&r, Pose { x: 0.0, y: 0.0, yaw: FRAC_PI_2 }, &[]);
    assert_eq!(a.masks, b.masks);
}

#[test]
fn turning_the_ego_rotates_the_raster() {
    // Ego facing north: a world point (X, Y) is at ego (Y, -X); pixel (i, j) <- (400 - j, i).
    let m = Map { road_segments: vec![rect(-30.0, -3.5, 40.0, 3.5), rect(10.0, 5.0, 20.0, 25.0)], ..Map::default() };
    let a = rasterize(&m, ORIGIN, &[]);
    let b = rasterize(&m, Pose { x: 0.0, y: 0.0, yaw: FRAC_PI_2 }, &[]);
    let (pa, pb) = (a.masks.index_axis(Axis(0), CH_ROAD_SEGMENTS), b.masks.index_axis(Axis(0), CH_ROAD_SEGMENTS));
    for i in 1..400 {
        for j in 1..400 {
            assert_eq!(pb[[i, j]], pa[[400 - j, i]], "pixel ({i}, {j})");
        }
    }
    assert!(pb.iter().any(|&v| v == 1));
}

#[test]
fn world_boxes_go_through_the_ego_frame() {
    // Ego at (100, 50) facing north; an agent 10 m north of it, facing west.
    let ego = Pose { x: 100.0, y: 50.0, yaw: FRAC_PI_2 };
    let st = AgentState {
        track: 7,
        name: "amb",
        kind: "ambulance",
        class: Class::Vehicle,
        size: [6.0, 2.4, 2.8],
        pose: Pose { x: 100.0, y: 60.0, yaw: std::f64::consts::PI },
    };
    let boxes = to_ego(ego, [st]);
    let bev = rasterize(&Map::default(), ego, &boxes);
    let (i0, i1, j0, j1) = bbox(&on_pixels(bev.masks.index_axis(Axis(0), CH_VEHICLE)));
    // Ahead (i centre 240) and turned left: its 6 m length lies along y.
    assert_eq!(((i0 + i1) / 2, (j0 + j1) / 2), (240, 200));
    assert!((j1 - j0) > (i1 - i0));
}

#[test]
fn aux_channels_at_and_around_the_box_centre() {
    let b = ego_box(Class::Vehicle, 10.0, 5.0, 0.0, 4.5, 1.9, 1.6);
    let bev = rasterize(&Map::default(), ORIGIN, &[b]);
    let aux = |c: usize, i: usize, j: usize| bev.aux[[c, i, j]];
    // Centre at canvas (240, 220).
    assert_eq!((0..7).map(|c| aux(c, 240, 220)).collect::<Vec<_>>(), vec![0, 0, 9, 3, 0, 0, 1]);
    assert_eq!((aux(AUX_OFFSET_X, 245, 220), aux(AUX_OFFSET_Y, 245, 220)), (5, 0));
    assert_eq!((aux(AUX_OFFSET_X, 237, 223), aux(AUX_OFFSET_Y, 237, 223)), (-3, 3));
    // Off the footprint everything is zero.
    assert!((0..7).all(|c| aux(c, 260, 220) == 0));
    // A long axis-aligned box (2 l >= 34 px) is where the truncated heading becomes 1, and a
    // reversed one gives -1 (float32 rounding of (front - centre) / (|front - centre| + 1e-6)).
    let bev = rasterize(&Map::default(), ORIGIN, &[ego_box(Class::Vehicle, 0.0, 0.0, 0.0, 18.0, 2.5, 3.9)]);
    assert_eq!((bev.aux[[AUX_HEADING_X, 200, 200]], bev.aux[[AUX_HEADING_Y, 200, 200]]), (1, 0));
    assert_eq!((bev.aux[[AUX_HALF_LENGTH, 200, 200]], bev.aux[[AUX_HEIGHT, 200, 200]]), (36, 3));
    let bev = rasterize(&Map::default(), ORIGIN, &[ego_box(Class::Vehicle, 0.0, 0.0, FRAC_PI_2, 18.0, 2.5, 3.9)]);
    assert_eq!((bev.aux[[AUX_HEADING_X, 200, 200]], bev.aux[[AUX_HEADING_Y, 200, 200]]), (0, 1));
}

#[test]
fn later_boxes_win_the_aux_where_footprints_overlap() {
    let a = ego_box(Class::Vehicle, 0.0, 0.0, 0.0, 4.0, 2.0, 1.5);
    let b = ego_box(Class::Pedestrian, 1.0, 0.0, 0.0, 1.0, 1.0, 2.0);
    let bev = rasterize(&Map::default(), ORIGIN, &[a.clone(), b.clone()]);
    assert_eq!(bev.aux[[AUX_HEIGHT, 204, 200]], 2);
    assert_eq!(bev.aux[[AUX_OFFSET_X, 204, 200]], 0);
    let bev = rasterize(&Map::default(), ORIGIN, &[b, a]);
    assert_eq!(bev.aux[[AUX_HEIGHT, 204, 200]], 1);
    assert_eq!(bev.aux[[AUX_OFFSET_X, 204, 200]], 4);
    // Both masks keep their own footprint.
    assert_eq!((bev.masks[[CH_VEHICLE, 204, 200]], bev.masks[[CH_PEDESTRIAN, 204, 200]]), (1, 1));
}

#[test]
fn boxes_off_the_canvas_are_clipped_or_skipped() {
    let boxes = [
        ego_box(Class::Vehicle, 49.5, 0.0, 0.3, 4.0, 2.0, 1.5),
        ego_box(Class::Vehicle, -1e7, 3e8, 0.0, 4.0, 2.0, 1.5),
        ego_box(Class::Vehicle, f64::NAN, 0.0, 0.0, 4.0, 2.0, 1.5),
    ];
    let bev = rasterize(&Map::default(), ORIGIN, &boxes);
    assert_eq!(bev.masks[[CH_VEHICLE, 399, 200]], 1);
    assert_eq!(bev.masks[[CH_VEHICLE, 0, 0]], 0, "a NaN pose draws nothing");
}

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rocc-bev-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn sample_bev() -> Bev {
    let boxes = vec![
        ego_box(Class::Vehicle, 10.0, 5.0, 0.3, 4.5, 1.9, 1.6),
        ego_box(Class::Pedestrian, -3.0, 8.0, 1.0, 0.6, 0.6, 1.8),
        ego_box(Class::Structure, 20.0, -15.0, 0.0, 1.0, 1.0, 6.0),
    ];
    rasterize(&cross_map(), Pose { x: -20.0, y: -2.0, yaw: 0.1 }, &boxes)
}

#[test]
fn npz_round_trip() {
    let dir = tmp_dir("npz");
    let bev = sample_bev();
    let f = output::write_bev_frame(&dir, 3, &bev).expect("write npz");
    assert_eq!(f.path, "bev/000003.npz");
    let path = dir.join(&f.path);
    assert_eq!(std::fs::metadata(&path).expect("exists").len(), f.bytes);
    let back = output::read_npz(&path).expect("read npz");
    assert_eq!(back, bev);
    // No temporary left behind.
    let names: Vec<String> = std::fs::read_dir(dir.join("bev"))
        .expect("bev dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["000003.npz".to_string()]);
    let _ = std::fs::remove_dir_all(&dir);
}

fn python_with(module: &str) -> bool {
    Command::new("python3").args(["-c", &format!("import {module}")]).output().is_ok_and(|o| o.status.success())
}

#[test]
fn python_loads_the_npz_like_a_nuplan_occ_bev() {
    if !python_with("numpy") {
        eprintln!("SKIP: python3 with numpy not available (CI installs it with `pip install numpy`)");
        return;
    }
    let dir = tmp_dir("py");
    let f = output::write_bev_frame(&dir, 0, &sample_bev()).expect("write npz");
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/python/check_bev.py");
    let out = Command::new("python3").arg(&script).arg(dir.join(&f.path)).output().expect("run python3");
    assert!(
        out.status.success(),
        "check_bev.py failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Tiny deterministic generator for test shapes.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self, lo: i64, hi: i64) -> i64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        lo + ((self.0 >> 33) % (hi - lo + 1) as u64) as i64
    }
}

#[test]
fn fill_and_line_match_opencv_when_available() {
    if !python_with("cv2") {
        eprintln!("SKIP: python3 with cv2 not available");
        return;
    }
    let (w, h) = (64i64, 48i64);
    let mut rng = Lcg(12345);
    let mut polys = Vec::new();
    for k in 0..300 {
        let n = 3 + (k % 6) as usize;
        // Two thirds inside the image, one third crossing or beyond its border.
        let (lo, hi) = if k % 3 == 2 { (-40, 110) } else { (0, 63) };
        polys.push((0..n).map(|_| (rng.next(lo, hi), rng.next(lo * 3 / 4, hi * 3 / 4))).collect::<Vec<_>>());
    }
    let mut lines = Vec::new();
    for k in 0..300 {
        let (lo, hi) = if k % 2 == 1 { (-50, 120) } else { (0, 63) };
        lines.push([(rng.next(lo, hi), rng.next(lo, hi)), (rng.next(lo, hi), rng.next(lo, hi))]);
    }
    let dir = tmp_dir("cv2");
    let spec = serde_json::json!({
        "w": w, "h": h,
        "polys": polys.iter().map(|p| p.iter().map(|&(u, v)| [u, v]).collect::<Vec<_>>()).collect::<Vec<_>>(),
        "lines": lines.iter().map(|l| [[l[0].0, l[0].1], [l[1].0, l[1].1]]).collect::<Vec<_>>(),
    });
    std::fs::write(dir.join("in.json"), spec.to_string()).expect("write spec");
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/python/cv2_fill.py");
    let out = Command::new("python3")
        .arg(&script)
        .arg(dir.join("in.json"))
        .arg(dir.join("out.npy"))
        .output()
        .expect("python3");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let want: ndarray::Array3<u8> = ndarray_npy::read_npy(dir.join("out.npy")).expect("read npy");
    let mut filler = Filler::default();
    let mut bad = Vec::new();
    let mut mine = ndarray::Array3::<u8>::zeros(want.dim());
    for k in 0..polys.len() + lines.len() {
        let mut img = Array2::<u8>::zeros((h as usize, w as usize));
        let mut set = |v: i64, u0: i64, u1: i64| img.slice_mut(s![v as usize, u0 as usize..=u1 as usize]).fill(1);
        if k < polys.len() {
            filler.fill_poly(w, h, &polys[k], &mut set);
        } else {
            let l = lines[k - polys.len()];
            fill::line(w, h, l[0], l[1], &mut set);
        }
        if img != want.index_axis(Axis(0), k) {
            bad.push(k);
        }
        mine.index_axis_mut(Axis(0), k).assign(&img);
    }
    if !bad.is_empty() {
        ndarray_npy::write_npy(dir.join("mine.npy"), &mine).expect("write npy");
    }
    assert!(
        bad.is_empty(),
        "{} of {} shapes differ from cv2 (see {}): {:?}",
        bad.len(),
        polys.len() + lines.len(),
        dir.display(),
        &bad[..bad.len().min(20)]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn boxes_json_and_manifest() {
    let dir = tmp_dir("json");
    let frames =
        vec![FrameBoxes { frame: 0, t: 0.0, boxes: vec![ego_box(Class::Bicycle, 1.0, 2.0, 0.5, 1.8, 0.6, 1.5)] }];
    let f = output::write_boxes_json(&dir, &frames).expect("boxes.json");
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join(&f.path)).expect("read")).expect("json");
    let b = &v[0]["boxes"][0];
    assert_eq!(
        (v[0]["frame"].as_u64(), b["class"].as_u64(), b["class_name"].as_str()),
        (Some(0), Some(1), Some("bicycle"))
    );
    for k in ["agent", "kind", "class", "track", "x", "y", "z", "l", "w", "h", "yaw"] {
        assert!(b.get(k).is_some(), "missing {k}");
    }
    let mut m = Manifest::new("x.scn", b"scenario x {}", 7, "ego", 1, 10.0);
    m.files.push(f);
    let mf = output::write_manifest(&dir, &m).expect("manifest");
    let back: Manifest = serde_json::from_slice(&std::fs::read(dir.join(&mf.path)).expect("read")).expect("json");
    assert_eq!(back, m);
    assert!(m.input_hash.starts_with("fnv1a64:"));
    let p = output::write_preview_png(&dir, &sample_bev()).expect("png");
    assert!(p.bytes > 1000);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A reused `Bev` must come out as a fresh one: boxes of the frame before, off-canvas corners
/// and a `Bev` read back from a file (whose painted rectangles are unknown) leave no trace.
#[test]
fn a_reused_bev_equals_a_fresh_one() {
    let map = cross_map();
    let frames = [
        (
            Pose { x: -20.0, y: -2.0, yaw: 0.1 },
            vec![
                ego_box(Class::Vehicle, 10.0, 5.0, 0.3, 4.5, 1.9, 1.6),
                ego_box(Class::Structure, 20.0, -15.0, 0.0, 1.0, 1.0, 6.0),
                ego_box(Class::Barrier, 49.0, -49.5, 0.7, 12.0, 2.5, 3.2),
            ],
        ),
        (Pose { x: 5.0, y: 3.0, yaw: -0.4 }, vec![ego_box(Class::Pedestrian, -3.0, 8.0, 1.0, 0.6, 0.6, 1.8)]),
        (Pose { x: 0.0, y: 0.0, yaw: 0.0 }, vec![]),
    ];
    let (mut raster, mut bev) = (Rasterizer::new(), Bev::zeros());
    for (pose, boxes) in &frames {
        raster.rasterize_into(&map, *pose, boxes, &mut bev);
        assert_eq!(bev, rasterize(&map, *pose, boxes));
    }
    let mut read = sample_bev();
    read.aux.fill(7);
    read.structure.fill(1);
    read.masks.fill(1);
    let mut from_file = Bev::from_arrays(read.masks, read.aux, read.structure);
    let (pose, boxes) = &frames[1];
    raster.rasterize_into(&map, *pose, boxes, &mut from_file);
    assert_eq!(from_file, rasterize(&map, *pose, boxes));
}
