//! The dataset side of compiled outputs: ego poses, box motion and instance ids in `boxes.json`,
//! the vector map in `scene.json` against the BEV painted from the same geometry, the output
//! root's `index.jsonl` through batches, resumes and shards, and the Python reader on a real tree.

use glam::DVec2;
use rocc::compile::index::{INDEX_FILE, read_index};
use rocc::compile::{Options, Stage, batch};
use rocc::output::{read_npz, read_scene_json};
use rocc::raster::layout::{CH_BOUNDARY, CH_DIVIDER, CH_DRIVABLE, CH_PED_CROSSING, GRID};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A temporary directory, removed when dropped (compiled trees with LiDAR are tens of MB).
struct Tmp(PathBuf);

impl std::ops::Deref for Tmp {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Tmp {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn tmp(name: &str) -> Tmp {
    let d = std::env::temp_dir().join(format!("rocc-dataset-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    Tmp(d)
}

fn bev_opts(frames: &str) -> Options {
    Options { stage: Stage::Bev, frames: Some(frames.to_string()), previews: false, ..Options::default() }
}

fn json(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))).expect("json")
}

fn num(v: &Value) -> f64 {
    v.as_f64().expect("number")
}

fn xy(v: &Value) -> DVec2 {
    DVec2::new(num(&v[0]), num(&v[1]))
}

/// A box's ego-frame centre and yaw taken to the world by its frame's `ego2global`.
fn to_world(frame: &Value, b: &Value) -> (DVec2, f64) {
    let m = &frame["ego"]["ego2global"];
    let (x, y) = (num(&b["x"]), num(&b["y"]));
    let row = |r: usize| num(&m[r][0]) * x + num(&m[r][1]) * y + num(&m[r][3]);
    let yaw = num(&b["yaw"]) + num(&m[1][0]).atan2(num(&m[0][0]));
    (DVec2::new(row(0), row(1)), yaw)
}

fn wrap(a: f64) -> f64 {
    (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
}

/// The first 24 frames (10 Hz) of a library scene with two egos, compiled to the BEV.
fn two_egos(scenario: &str, name: &str) -> (Tmp, PathBuf) {
    let out = tmp(name);
    let r = batch::run(&[root().join(format!("scenarios/{scenario}.scn"))], &out, &bev_opts("0..24"), true);
    assert!(r.failures.is_empty() && r.clips.len() == 2);
    let dir = out.join(scenario);
    (out, dir)
}

/// A striker closing on a queue behind the ego: the two egos see each other.
const QUEUE: &str = "rear_end_queue";

#[test]
fn ego_poses_match_the_boxes_seen_by_the_other_ego_and_ids_are_stable() {
    let (_out, scene) = two_egos(QUEUE, "poses");
    let (a, b) = (json(&scene.join("ego/boxes.json")), json(&scene.join("striker/boxes.json")));
    let mut ids: BTreeMap<String, String> = BTreeMap::new();
    let mut seen_each_other = 0;
    for (fa, fb) in a.as_array().unwrap().iter().zip(b.as_array().unwrap()) {
        assert_eq!(fa["frame"], fb["frame"]);
        assert_eq!(num(&fa["timestamp_us"]), (num(&fa["t"]) * 1e6).round());
        for (me, other) in [(fa, fb), (fb, fa)] {
            let e = &me["ego"];
            // The matrix, the pose and the quaternion say the same thing.
            let yaw = num(&e["yaw"]);
            let m = &e["ego2global"];
            assert!((num(&m[0][0]) - yaw.cos()).abs() < 1e-12 && (num(&m[1][0]) - yaw.sin()).abs() < 1e-12);
            assert!(num(&m[0][3]) == num(&e["x"]) && num(&m[1][3]) == num(&e["y"]) && num(&m[2][3]) == 0.0);
            let q = &e["ego2global_rotation"];
            assert!((2.0 * num(&q[3]).atan2(num(&q[0])) - yaw).abs() < 1e-12);
            // Where this ego sees the other ego, the other's own pose agrees.
            if let Some(seen) = me["boxes"].as_array().unwrap().iter().find(|b| b["agent"] == other["ego"]["agent"]) {
                let (p, y) = to_world(me, seen);
                let o = &other["ego"];
                assert!((p - DVec2::new(num(&o["x"]), num(&o["y"]))).length() < 1e-9, "frame {}", me["frame"]);
                assert!(wrap(y - num(&o["yaw"])).abs() < 1e-9);
                assert_eq!(seen["instance_id"], o["instance_id"]);
                assert_eq!((&seen["l"], &seen["kind"]), (&o["l"], &o["kind"]));
                seen_each_other += 1;
            }
            // One id per agent, the same in every frame and in both clips, never shared.
            let named = me["boxes"].as_array().unwrap().iter().chain([e]);
            for b in named {
                let (agent, id) = (b["agent"].as_str().unwrap(), b["instance_id"].as_str().unwrap());
                assert_eq!(ids.entry(agent.to_string()).or_insert_with(|| id.to_string()), id);
            }
        }
    }
    assert!(seen_each_other >= 10, "the two egos should see each other in most frames");
    let distinct: std::collections::BTreeSet<&String> = ids.values().collect();
    assert!(ids.len() >= 3 && distinct.len() == ids.len(), "{ids:?}");
}

#[test]
fn velocities_agree_with_finite_differences_of_positions() {
    let (_out, scene) = two_egos(QUEUE, "motion");
    let frames = json(&scene.join("ego/boxes.json"));
    let frames = frames.as_array().unwrap();
    // World position and velocity of every agent per frame, from the written ego-frame boxes.
    type Sample = (DVec2, f64, DVec2, DVec2, f64);
    let mut tracks: BTreeMap<String, BTreeMap<usize, Sample>> = BTreeMap::new();
    for f in frames {
        let k = f["frame"].as_u64().unwrap() as usize;
        let yaw = num(&f["ego"]["yaw"]);
        let ego_pos = DVec2::new(num(&f["ego"]["x"]), num(&f["ego"]["y"]));
        let mut put = |name: &str, p: DVec2, y: f64, b: &Value| {
            let (vw, ve) = (xy(&b["velocity_world"]), xy(&b["velocity"]));
            // The ego-frame vector is the world vector in the ego's axes.
            assert!((DVec2::from_angle(-yaw).rotate(vw) - ve).length() < 1e-9);
            let s = (p, y, vw, xy(&b["acceleration_world"]), num(&b["yaw_rate"]));
            tracks.entry(name.to_string()).or_default().insert(k, s);
        };
        put(f["ego"]["agent"].as_str().unwrap(), ego_pos, yaw, &f["ego"]);
        for b in f["boxes"].as_array().unwrap() {
            let (p, y) = to_world(f, b);
            put(b["agent"].as_str().unwrap(), p, y, b);
        }
    }
    let dt = 0.1;
    let mut checked = 0;
    let (mut moving, mut turning) = (0, 0);
    for (name, t) in &tracks {
        for (&k, &(_, _, v, a, r)) in t {
            let (Some(prev), Some(next)) = (k.checked_sub(1).and_then(|p| t.get(&p)), t.get(&(k + 1))) else {
                continue;
            };
            let fd = (next.0 - prev.0) / (2.0 * dt);
            assert!((fd - v).length() < 1e-6, "{name} frame {k}: velocity {v} vs finite difference {fd}");
            let fa = (next.2 - prev.2) / (2.0 * dt);
            assert!((fa - a).length() < 1e-6, "{name} frame {k}: acceleration {a} vs {fa}");
            let fr = wrap(next.1 - prev.1) / (2.0 * dt);
            assert!((fr - r).abs() < 1e-6, "{name} frame {k}: yaw rate {r} vs {fr}");
            checked += 1;
            moving += (v.length() > 1.0) as usize;
            turning += (r.abs() > 1e-3) as usize;
        }
    }
    assert!(checked > 50 && moving > 20, "{checked} agent-frames checked, {moving} moving, {turning} turning");
}

/// The pixel of an ego-frame point, as the BEV indexes it (axes [x, y], 0.25 m).
fn pixel(p: DVec2) -> Option<(usize, usize)> {
    let (i, j) = ((p.x * 4.0 + 200.0).floor(), (p.y * 4.0 + 200.0).floor());
    (i >= 0.0 && j >= 0.0 && i < GRID as f64 && j < GRID as f64).then_some((i as usize, j as usize))
}

#[test]
fn the_vector_map_rasterises_to_the_bevs_lane_and_crosswalk_channels() {
    let (_out, scene_dir) = two_egos("ambulance_crowded_intersection", "vectors");
    let clip = scene_dir.join("ego");
    let scene = read_scene_json(&clip.join("scene.json")).expect("scene.json");
    assert_eq!(scene.frame, "world");
    let boxes = json(&clip.join("boxes.json"));
    let poly = |l: &Vec<[f64; 2]>| l.iter().map(|p| DVec2::new(p[0], p[1])).collect::<Vec<_>>();
    // Only dividers and crosswalks: the lines of BEV channels 15 and 16.
    let map = rocc::road::Map {
        dividers: scene.lane_dividers.iter().map(poly).collect(),
        crosswalk_polygons: scene
            .crosswalks
            .iter()
            .map(|c| {
                let mut p = poly(c);
                assert_eq!(p.first(), p.last(), "crosswalks are closed");
                p.pop();
                p
            })
            .collect(),
        ..Default::default()
    };
    for f in [0usize, 12, 23] {
        let e = &boxes[f]["ego"];
        let pose = rocc::place::Pose { x: num(&e["x"]), y: num(&e["y"]), yaw: num(&e["yaw"]) };
        let ours = rocc::raster::rasterize(&map, pose, &[]);
        let bev = read_npz(&clip.join(format!("bev/{f:06}.npz"))).expect("npz");
        for ch in [CH_DIVIDER, CH_PED_CROSSING] {
            let (a, b) = (ours.masks.index_axis(ndarray::Axis(0), ch), bev.masks.index_axis(ndarray::Axis(0), ch));
            assert!(b.iter().any(|&v| v == 1), "channel {ch} is drawn in frame {f}");
            assert_eq!(a, b, "channel {ch}, frame {f}");
        }
        // Road boundaries run along channel 17 (a filled outline, so within a pixel or two) and
        // lane centrelines over drivable paving.
        let to_ego = |p: &[f64; 2]| DVec2::from_angle(-pose.yaw).rotate(DVec2::new(p[0] - pose.x, p[1] - pose.y));
        let near_boundary = |(i, j): (usize, usize)| {
            (i.saturating_sub(2)..=(i + 2).min(GRID - 1))
                .any(|a| (j.saturating_sub(2)..=(j + 2).min(GRID - 1)).any(|b| bev.masks[[CH_BOUNDARY, a, b]] == 1))
        };
        let inner = |p: DVec2| p.x.abs() < 49.0 && p.y.abs() < 49.0;
        let samples = |lines: &[Vec<[f64; 2]>]| -> Vec<DVec2> {
            let mut out = Vec::new();
            for l in lines {
                for w in l.windows(2) {
                    let (a, b) = (to_ego(&w[0]), to_ego(&w[1]));
                    let n = ((b - a).length() / 0.1).ceil().max(1.0) as usize;
                    out.extend((0..=n).map(|k| a.lerp(b, k as f64 / n as f64)).filter(|&p| inner(p)));
                }
            }
            out
        };
        let bound = samples(&scene.road_boundaries);
        assert!(bound.len() > 500, "frame {f}: boundaries cross the patch");
        let off = bound.iter().filter(|&&p| pixel(p).is_none_or(|q| !near_boundary(q))).count();
        assert_eq!(off, 0, "frame {f}: {off} of {} boundary samples away from channel 17", bound.len());
        let centre = samples(&scene.lane_centrelines);
        let dry = centre.iter().filter(|&&p| pixel(p).is_none_or(|(i, j)| bev.masks[[CH_DRIVABLE, i, j]] != 1)).count();
        assert!(centre.len() > 500 && dry == 0, "frame {f}: {dry} of {} centreline samples off the road", centre.len());
    }
    assert!(!scene.stop_lines.is_empty() && scene.stop_lines.iter().all(|s| s.len() == 2));
}

fn index_dirs(out: &Path) -> Vec<String> {
    read_index(out).expect("index").clips.iter().map(|c| c.dir.clone()).collect()
}

#[test]
fn the_index_lists_exactly_the_finished_clips_through_batches_resumes_and_shards() {
    let out = tmp("index");
    let lib = |n: &str| root().join("scenarios").join(n);
    let (a, b, c) = (lib("ambulance_crowded_intersection.scn"), lib("rear_end_queue.scn"), lib("car_u_turn.scn"));
    let o = bev_opts("0..3");
    assert!(batch::run(std::slice::from_ref(&a), &out, &o, true).failures.is_empty());
    assert_eq!(index_dirs(&out), ["ambulance_crowded_intersection/amb", "ambulance_crowded_intersection/ego"]);
    let idx = read_index(&out).unwrap();
    let f1 = &idx.clips[1].frames[1];
    assert_eq!((f1.frame, f1.timestamp_us), (1, 100_000));
    assert_eq!(f1.bev, "ambulance_crowded_intersection/ego/bev/000001.npz");
    assert!(out.join(&f1.bev).is_file() && f1.occ.is_none() && f1.pose.is_some());
    let bx = json(&out.join(&idx.clips[1].boxes));
    assert_eq!(f1.pose.unwrap()[0], num(&bx[1]["ego"]["x"]));
    assert_eq!(f1.ego2global.unwrap()[1][3], num(&bx[1]["ego"]["y"]));

    // Shards of one batch, run one after the other into the same root, each refresh the index.
    let inputs = vec![b.clone(), c.clone()];
    for k in 1..=2 {
        assert!(batch::run_shard(&inputs, Some((k, 2)), &out, &o, true).failures.is_empty());
    }
    let all = index_dirs(&out);
    assert_eq!(all.len(), 2 + 2 + 1, "{all:?}");
    assert!(all.iter().any(|d| d.starts_with("rear_end_queue/")) && all.iter().any(|d| d.starts_with("car_u_turn/")));

    // A resumed run rewrites nothing: the index is byte-identical.
    let before = std::fs::read(out.join(INDEX_FILE)).unwrap();
    let r = batch::run(&inputs, &out, &o, true);
    assert!(r.failures.is_empty() && r.clips.iter().all(|c| c.resumed));
    assert_eq!(std::fs::read(out.join(INDEX_FILE)).unwrap(), before);

    // Half-written clips are not listed: one lost its manifest (a run killed mid-clip), one a
    // frame, and a stray directory is no clip at all.
    let cut = out.join("car_u_turn/ego");
    std::fs::remove_file(cut.join("manifest.json")).unwrap();
    std::fs::remove_file(out.join("ambulance_crowded_intersection/amb/bev/000002.npz")).unwrap();
    std::fs::create_dir_all(out.join("notes/misc")).unwrap();
    std::fs::write(out.join("notes/misc/manifest.json"), "{\"not\": \"rocc\"}").unwrap();
    assert!(batch::run(std::slice::from_ref(&b), &out, &o, true).failures.is_empty());
    assert_eq!(
        index_dirs(&out),
        ["ambulance_crowded_intersection/ego", "rear_end_queue/ego", "rear_end_queue/striker"]
    );
    // Compiling the missing ones again lists them again.
    assert!(batch::run(&[a, c], &out, &o, true).failures.is_empty());
    assert_eq!(index_dirs(&out).len(), 5);
}

#[test]
fn shards_running_at_once_leave_an_index_of_every_clip() {
    let out = tmp("index-concurrent");
    let lib = |n: &str| root().join("scenarios").join(n);
    let inputs: Vec<PathBuf> =
        ["rear_end_queue.scn", "car_u_turn.scn", "cyclist_red_light.scn", "deer_crossing.scn"].map(lib).to_vec();
    let o = bev_opts("0..2");
    std::thread::scope(|s| {
        for k in 1..=3 {
            let (inputs, out, o) = (&inputs, &out, &o);
            s.spawn(move || assert!(batch::run_shard(inputs, Some((k, 3)), out, o, true).failures.is_empty()));
        }
    });
    let dirs = index_dirs(&out);
    let on_disk: usize = inputs
        .iter()
        .map(|p| {
            let name = p.file_stem().unwrap();
            std::fs::read_dir(out.join(name)).map_or(0, |d| d.count())
        })
        .sum();
    assert!(on_disk >= 5 && dirs.len() == on_disk, "{dirs:?}");
}

#[test]
fn an_edited_clip_is_indexed_with_its_new_manifest() {
    let out = tmp("index-edit");
    let input = root().join("scenarios/rear_end_queue.scn");
    assert!(batch::run(std::slice::from_ref(&input), &out, &bev_opts("0..3"), true).failures.is_empty());
    let clip = out.join("rear_end_queue/ego");
    let hash = |out: &Path| {
        read_index(out).unwrap().clips.iter().find(|c| c.dir == "rear_end_queue/ego").unwrap().manifest_hash.clone()
    };
    let before = hash(&out);
    let seen = json(&clip.join("boxes.json"))[0]["boxes"][0]["agent"].as_str().unwrap().to_string();
    let del = rocc::edit::parse_edit("delete", &[seen]).unwrap();
    let o = rocc::edit::ClipEdit { scenario: Some(input), ..Default::default() };
    rocc::edit::edit_clip(&clip, &[del], &o).expect("edit");
    assert_ne!(hash(&out), before);
    assert_eq!(index_dirs(&out).len(), 2);
}

#[test]
fn an_index_that_cannot_be_written_is_an_error_after_the_clips() {
    let out = tmp("index-blocked");
    std::fs::create_dir_all(out.join(INDEX_FILE).join("x")).unwrap();
    let r = batch::run(&[root().join("scenarios/rear_end_queue.scn")], &out, &bev_opts("0"), true);
    assert_eq!(r.clips.len(), 2);
    assert_eq!(r.failures.len(), 1);
    assert_eq!(r.failures[0].diags[0].code, "E0410");
}

fn python_with_numpy() -> bool {
    Command::new("python3").args(["-c", "import numpy"]).output().is_ok_and(|o| o.status.success())
}

#[test]
fn the_python_reader_loads_a_compiled_tree() {
    if !python_with_numpy() {
        eprintln!("SKIP: python3 with numpy not available (.ci/run installs it with `pip install numpy`)");
        return;
    }
    let out = tmp("python");
    let mut o =
        Options { stage: Stage::Lidar, frames: Some("0..3".to_string()), previews: false, ..Options::default() };
    o.rig.horizontal_resolution_deg = 2.0;
    let inputs =
        [root().join("scenarios/ambulance_crowded_intersection.scn"), root().join("scenarios/rear_end_queue.scn")];
    assert!(batch::run(&inputs, &out, &o, true).failures.is_empty());
    // A half-written clip beside the finished ones: frames but no manifest.
    let half = out.join("half_written/ego/bev");
    std::fs::create_dir_all(&half).unwrap();
    std::fs::copy(out.join("rear_end_queue/ego/bev/000000.npz"), half.join("000000.npz")).unwrap();
    let not_output = tmp("python-not-output");
    let run = Command::new("python3")
        .arg(root().join("tests/python/check_reader.py"))
        .args([&*out, &*not_output])
        .env("PYTHONPATH", root().join("python"))
        .output()
        .expect("python3");
    let log = format!("{}{}", String::from_utf8_lossy(&run.stdout), String::from_utf8_lossy(&run.stderr));
    assert!(run.status.success(), "{log}");
    assert!(log.contains("ok: 4 clips, 12 frames"), "{log}");
}
