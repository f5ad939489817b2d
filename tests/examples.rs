//! Every scenario of the library and of `tests/fixtures/examples` compiles to clips whose behaviour
//! matches the comment at its top: assertions on the tracks, plus a snapshot per clip of a
//! summary of its `boxes.json` (where each agent is, in the ego's frame, every second).

use rocc::check::{self, scenario::Point};
use rocc::compile::{Front, frame_boxes, front};
use rocc::source::SourceMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn load(path: &Path) -> Front {
    let mut sources = SourceMap::default();
    let s = check::check_path(path, &mut sources).unwrap_or_else(|d| {
        panic!("{}:\n{}", path.display(), d.iter().map(|d| d.render_plain(&sources)).collect::<String>())
    });
    front(s, None).unwrap_or_else(|d| {
        panic!("{}:\n{}", path.display(), d.iter().map(|d| d.render_plain(&sources)).collect::<String>())
    })
}

fn shared(name: &str) -> Front {
    load(&root().join("tests/fixtures/examples").join(format!("{name}.scn")))
}

fn idx(f: &Front, name: &str) -> usize {
    f.tracks.agents.iter().position(|a| a.name == name).unwrap_or_else(|| panic!("no agent {name}"))
}

/// Distance an agent covers over the clip (m).
fn travelled(f: &Front, name: &str) -> f64 {
    let p = &f.tracks.poses[idx(f, name)];
    p.windows(2).map(|w| (w[1].x - w[0].x).hypot(w[1].y - w[0].y)).sum()
}

fn speeds<'a>(f: &'a Front, name: &str) -> &'a [f64] {
    &f.tracks.speeds[idx(f, name)]
}

/// Largest lateral displacement from the agent's initial heading line (m).
fn lateral_shift(f: &Front, name: &str) -> f64 {
    let p = &f.tracks.poses[idx(f, name)];
    let (x0, y0, c, s) = (p[0].x, p[0].y, p[0].yaw.cos(), p[0].yaw.sin());
    p.iter().map(|q| (-(q.x - x0) * s + (q.y - y0) * c).abs()).fold(0.0, f64::max)
}

/// `boxes.json` of one clip, summarised: per second, each box's agent and ego-frame position.
fn summary(f: &Front, ego: usize) -> String {
    let mut out = String::new();
    let step = (f.tracks.rate.round() as usize).max(1);
    for fr in (0..f.tracks.frames).step_by(step) {
        let _ = write!(out, "t={:>4.1}", fr as f64 / f.tracks.rate);
        for b in frame_boxes(f, ego, fr) {
            let _ = write!(out, " | {} ({:.0}, {:.0})", b.agent, b.x, b.y);
        }
        out.push('\n');
    }
    for i in &f.tracks.impacts {
        let _ = writeln!(
            out,
            "impact frame {}: {} -> {} on {:?}",
            i.frame, f.tracks.agents[i.at_fault].name, f.tracks.agents[i.struck].name, i.struck_side
        );
    }
    out
}

#[test]
fn every_clip_matches_its_boxes_summary_snapshot() {
    let mut files: Vec<PathBuf> = Vec::new();
    for dir in [root().join("scenarios"), root().join("tests/fixtures/examples")] {
        let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
            .expect("read dir")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "scn"))
            .collect();
        v.sort();
        files.extend(v);
    }
    for path in files {
        let f = load(&path);
        let origin = if path.starts_with(root().join("scenarios")) { "lib" } else { "shared" };
        for &ego in &f.concrete.egos {
            let name = format!("boxes_{origin}_{}_{}", f.concrete.name, f.tracks.agents[ego].name);
            insta::assert_snapshot!(name, summary(&f, ego));
        }
    }
}

#[test]
fn ambulance_blocked_stalled_car_stays_and_the_car_ahead_eases_aside() {
    let f = shared("ambulance_blocked");
    assert!(travelled(&f, "stalled") < 0.01, "the stalled car moved");
    assert!(travelled(&f, "amb") > 15.0, "the ambulance barely moved: {:.1} m", travelled(&f, "amb"));
    assert!(lateral_shift(&f, "ego") > 0.5, "ego did not pull aside: {:.2} m", lateral_shift(&f, "ego"));
}

#[test]
fn ambulance_squeezes_past_the_easing_car_while_the_queues_hold() {
    let f = shared("ambulance_crowded_intersection");
    for held in ["ego", "north_queue", "east_queue"] {
        let v = speeds(&f, held);
        assert!(v.last().copied().unwrap_or(1.0) < 0.1, "{held} does not hold at the end: {:?}", v.last());
    }
    assert!(lateral_shift(&f, "lead") > 0.3, "lead did not ease aside: {:.2} m", lateral_shift(&f, "lead"));
    // The ambulance moves over to pass the car that makes room, and draws level with it.
    assert!(lateral_shift(&f, "amb") > 1.0, "ambulance did not move over: {:.2} m", lateral_shift(&f, "amb"));
    let (amb, lead) = (idx(&f, "amb"), idx(&f, "lead"));
    let last = f.tracks.frames - 1;
    assert!(f.tracks.poses[amb][last].x > f.tracks.poses[lead][last].x - 3.0, "ambulance stayed behind the lead");
    // The cross traffic gives it the junction: within the clip the whole ambulance is past the
    // stop line (x = -19), on red, with the background traffic of the example.
    let rear = f.tracks.poses[amb][last].x - f.tracks.agents[amb].size[0] / 2.0;
    assert!(rear > -19.0, "ambulance's rear ends at x = {rear:.1}, before the stop line at -19");
}

#[test]
fn u_turn_car_heads_into_the_junction_while_cross_traffic_holds() {
    // At 12 km/h from 12 m before a stop line that sits 6 m short of the junction box (the
    // crosswalk lies between), the U-turn proper needs about 9 s; this 6 s clip shows the approach
    // and its first metres. What the clip must show: the turner keeps its goal speed toward the
    // junction, and the cross traffic holds.
    let f = shared("car_u_turn");
    let v = speeds(&f, "turner");
    assert!(v.iter().all(|&v| v > 2.5), "the turner stalled");
    assert!(travelled(&f, "turner") > 17.0, "turner: {:.1} m", travelled(&f, "turner"));
    for held in ["ego", "queued"] {
        assert!(travelled(&f, held) < 0.5, "{held} moved {:.1} m", travelled(&f, held));
    }
    // The full manoeuvre, given the time: the turner ends up reversed.
    let mut long = f.scenario.clone();
    long.duration = 14.0;
    let g = front(long, None).expect("longer clip");
    let p = &g.tracks.poses[idx(&g, "turner")];
    let turned = rocc::geom::wrap_angle(p.last().expect("frames").yaw - p[0].yaw).abs();
    assert!(turned > 2.8, "turner turned {turned:.2} rad, not about pi");
}

#[test]
fn sideswipe_strikes_the_right_side_of_v2() {
    let f = shared("ciren_sideswipe");
    let i = f.tracks.impacts.first().expect("the sideswipe is staged");
    assert_eq!((f.tracks.agents[i.at_fault].name.as_str(), f.tracks.agents[i.struck].name.as_str()), ("v1", "v2"));
    assert!(matches!(i.struck_side, Point::Right | Point::FrontRight | Point::RearRight), "{:?}", i.struck_side);
}

#[test]
fn construction_traffic_merges_left_past_the_closure() {
    let f = shared("construction_lane_closure");
    assert!(lateral_shift(&f, "ego") > 2.5, "ego shifted {:.2} m", lateral_shift(&f, "ego"));
    assert!(f.tracks.impacts.is_empty());
}

#[test]
fn the_cyclist_materialises_in_the_bev() {
    let f = shared("cyclist_red_light");
    let ego = idx(&f, "ego");
    let boxes = frame_boxes(&f, ego, 0);
    assert!(boxes.iter().any(|b| b.agent == "rider"));
    let bev = rocc::raster::rasterize(&f.map, f.tracks.poses[ego][0], &boxes);
    let bicycle = rocc::raster::layout::MASK_NAMES.iter().position(|n| *n == "bicycle").expect("channel");
    let px = bev.masks.index_axis(ndarray::Axis(0), bicycle).iter().filter(|&&v| v != 0).count();
    assert!(px > 10, "bicycle channel has {px} px");
    // The rider stops behind the front car and ahead of the ego, never touching either.
    assert!(speeds(&f, "rider").last().copied().unwrap_or(1.0) < 0.1);
    assert!(f.tracks.impacts.is_empty());
}

#[test]
fn traffic_halts_for_the_deer() {
    let f = shared("deer_crossing");
    let min = speeds(&f, "ego").iter().copied().fold(f64::INFINITY, f64::min);
    assert!(min < 0.5, "ego never slowed below {min:.2} m/s");
    assert!(lateral_shift(&f, "deer") > 3.0, "deer did not cross");
}

#[test]
fn pickup_slows_behind_the_midblock_walker() {
    let f = shared("pedestrian_midblock");
    let v0 = speeds(&f, "pickup")[0];
    let min = speeds(&f, "pickup").iter().copied().fold(f64::INFINITY, f64::min);
    assert!(min < 0.5 * v0, "pickup kept {min:.2} of {v0:.2} m/s");
    assert!(lateral_shift(&f, "walker") > 3.0);
}

#[test]
fn rear_end_hits_the_stopped_ego_from_behind() {
    let f = shared("rear_end_queue");
    let i = f.tracks.impacts.first().expect("the crash is staged");
    assert_eq!(f.tracks.agents[i.struck].name, "ego");
    assert!(matches!(i.struck_side, Point::Rear | Point::RearLeft | Point::RearRight), "{:?}", i.struck_side);
    assert!(travelled(&f, "first") < 3.5, "the first car of the queue should be (nearly) stopped");
}

#[test]
fn the_car_leaves_the_curve_into_the_tree_and_the_tractor_drives_on() {
    let f = load(&root().join("scenarios/car_into_tree.scn"));
    let i = f.tracks.impacts.first().expect("the run-off-road crash is staged");
    assert_eq!((f.tracks.agents[i.at_fault].name.as_str(), f.tracks.agents[i.struck].name.as_str()), ("car", "oak"));
    // The car's front strikes the trunk, about when asked (3 s).
    let car = &f.tracks.agents[i.at_fault];
    assert!(i.at_fault_local[0] > car.size[0] / 2.0 - 0.5, "contact at {:?} is not on the front", i.at_fault_local);
    assert!((i.frame as f64 / f.tracks.rate - 3.0).abs() <= 0.5, "impact at frame {}", i.frame);
    // The tractor in the other lane is a bystander: it passes the wreck.
    assert!(travelled(&f, "farm") > 30.0, "tractor: {:.1} m", travelled(&f, "farm"));
}

// ---------------------------------------------------------------- behaviour pin

fn scn_in(dir: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
        .unwrap_or_else(|e| panic!("{dir}: {e}"))
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "scn"))
        .collect();
    v.sort();
    v
}

/// The pin that every refactoring is held to: one digest per scene of every track of the library
/// and of the rollout's regression scenes, and of the BEV and occupancy bytes of the first, middle
/// and last frame of each library clip (first ego, procedural backend, as `rocc compile` renders
/// them). A change of behaviour shows as a changed line in `digest_pin.snap`; a refactoring that
/// claims to change nothing must leave the snapshot as it is.
#[test]
fn tracks_bev_and_occupancy_match_the_pinned_digests() {
    use rocc::backend::{Background, OccInput, Occupancy, OccupancyBackend, Procedural};
    use rocc::fsio::Fnv1a;
    use rocc::raster::{Bev, Rasterizer};
    let mut out = String::new();
    for dir in ["scenarios", "tests/rollout-cases"] {
        for path in scn_in(dir) {
            let f = load(&path);
            let mut h = Fnv1a::new();
            f.tracks.digest(&mut h);
            let name = path.file_stem().and_then(|n| n.to_str()).expect("utf-8 name");
            let _ = write!(out, "{dir}/{name}: tracks {:016x}", h.finish());
            if dir == "scenarios" {
                let ego = f.concrete.egos[0];
                let n = f.tracks.frames;
                let bg = Background::generate(&f.map, f.concrete.seed);
                let seed = rocc::compile::clip_seed(&f, ego);
                let (mut raster, mut bev, mut occ) = (Rasterizer::new(), Bev::zeros(), Occupancy::empty());
                let (mut hb, mut ho) = (Fnv1a::new(), Fnv1a::new());
                for fr in [0, n / 2, n - 1] {
                    let pose = f.tracks.poses[ego][fr];
                    let boxes = frame_boxes(&f, ego, fr);
                    raster.rasterize_into(&f.map, pose, &boxes, &mut bev);
                    hb.write(&i8_bytes(bev.masks.as_slice().expect("standard layout")));
                    for x in bev.aux.iter() {
                        hb.write(&x.to_le_bytes());
                    }
                    hb.write(&i8_bytes(bev.structure.as_slice().expect("standard layout")));
                    let input = OccInput { boxes: &boxes, bev: &bev, background: &bg, ego: pose, seed, frame: fr };
                    Procedural::default().occupancy_into(&input, &mut occ);
                    ho.write(occ.labels.as_slice().expect("standard layout"));
                }
                let _ = write!(out, " bev {:016x} occ {:016x}", hb.finish(), ho.finish());
            }
            out.push('\n');
        }
    }
    insta::assert_snapshot!("digest_pin", out);
}

fn i8_bytes(v: &[i8]) -> Vec<u8> {
    v.iter().map(|&x| x as u8).collect()
}
