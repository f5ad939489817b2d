//! People and animals standing, kneeling or lying where they can physically be, and static things
//! anywhere on or near the map (tests/fixtures/posture/): the posture sets the box, and the BEV,
//! the occupancy and the LiDAR follow it.

use rocc::backend::layout::{K_GROUND_TOP, ORIGIN, PEDESTRIAN, VEHICLE, VOXEL};
use rocc::backend::{Background, OccInput, Occupancy, OccupancyBackend, Procedural};
use rocc::check;
use rocc::compile::{Front, frame_boxes, front};
use rocc::diag::Diagnostic;
use rocc::raster::layout::{AUX_HEIGHT, CH_PEDESTRIAN, CH_VEHICLE};
use rocc::raster::{Bev, rasterize};
use rocc::source::SourceMap;
use rocc::view::EgoBox;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn load(name: &str) -> Front {
    let path = root().join("tests/fixtures/posture").join(format!("{name}.scn"));
    let mut sources = SourceMap::default();
    let render = |d: Vec<Diagnostic>, s: &SourceMap| d.iter().map(|d| d.render_plain(s)).collect::<String>();
    let s = check::check_path(&path, &mut sources).unwrap_or_else(|d| panic!("{}", render(d, &sources)));
    front(s, None).unwrap_or_else(|d| panic!("{}", render(d, &sources)))
}

fn front_of(src: &str) -> Result<Front, Vec<Diagnostic>> {
    let mut sources = SourceMap::default();
    let s = check::check_text("t.scn", src, Path::new("."), &mut sources)?;
    front(s, None)
}

/// One frame of the first ego: its boxes, BEV and procedural occupancy, as `rocc compile` renders.
fn render(f: &Front, frame: usize) -> (Vec<EgoBox>, Bev, Occupancy) {
    let ego = f.concrete.egos[0];
    let boxes = frame_boxes(f, ego, frame);
    let pose = f.tracks.poses[ego][frame];
    let bev = rasterize(&f.map, pose, &boxes);
    let bg = Background::generate(&f.map, f.concrete.seed);
    let input = OccInput { boxes: &boxes, bev: &bev, background: &bg, ego: pose, seed: f.concrete.seed, frame };
    let occ = Procedural::default().occupancy(&input);
    (boxes, bev, occ)
}

fn boxed<'a>(boxes: &'a [EgoBox], name: &str) -> &'a EgoBox {
    boxes.iter().find(|b| b.agent == name).unwrap_or_else(|| panic!("no box of {name}"))
}

/// Whether ego-frame point (x, y) lies in `b`'s footprint grown by `margin` m.
fn inside(b: &EgoBox, x: f64, y: f64, margin: f64) -> bool {
    let (dx, dy) = (x - b.x, y - b.y);
    let (c, s) = (b.yaw.cos(), b.yaw.sin());
    let (u, v) = (dx * c + dy * s, -dx * s + dy * c);
    u.abs() <= b.l / 2.0 + margin && v.abs() <= b.w / 2.0 + margin
}

/// The highest top face (m above the road) of `label` voxels in `b`'s footprint, and their count.
fn occupied_top(occ: &Occupancy, b: &EgoBox, label: u8) -> (f64, usize) {
    let (mut top, mut n) = (f64::NEG_INFINITY, 0);
    for ((i, j, k), &l) in occ.labels.indexed_iter() {
        let (x, y) = (ORIGIN[0] + (i as f64 + 0.5) * VOXEL, ORIGIN[1] + (j as f64 + 0.5) * VOXEL);
        if l == label && inside(b, x, y, 0.0) {
            top = top.max((k + 1 - K_GROUND_TOP) as f64 * VOXEL);
            n += 1;
        }
    }
    (top, n)
}

/// The BEV pixels of `ch` in `b`'s footprint, and the extent of those pixels along the ego's y.
fn bev_footprint(bev: &Bev, ch: usize, b: &EgoBox) -> (usize, f64) {
    let (mut n, mut lo, mut hi) = (0, f64::INFINITY, f64::NEG_INFINITY);
    for ((i, j), &m) in bev.masks.index_axis(ndarray::Axis(0), ch).indexed_iter() {
        let (x, y) = (-50.0 + 0.25 * i as f64, -50.0 + 0.25 * j as f64);
        if m == 1 && inside(b, x, y, 0.25) {
            n += 1;
            lo = lo.min(y);
            hi = hi.max(y);
        }
    }
    (n, hi - lo)
}

#[test]
fn posture_sets_the_box_lying_is_long_and_low_kneeling_half_height() {
    let f = load("person-lying-on-lane");
    let (boxes, _, _) = render(&f, 0);
    let (lying, kneeling, standing) = (boxed(&boxes, "injured"), boxed(&boxes, "aider"), boxed(&boxes, "onlooker"));
    // An adult's standing priors: 0.5..0.7 m square, 1.6..1.9 m tall.
    assert!((1.6..=1.9).contains(&lying.l) && lying.h == 0.3 && (0.5..=0.7).contains(&lying.w), "{lying:?}");
    assert!((0.8..=0.95).contains(&kneeling.h) && kneeling.l >= 0.45 * 1.6, "{kneeling:?}");
    assert!((1.6..=1.9).contains(&standing.h) && standing.l <= 0.7, "{standing:?}");
    // The box stands on the ground: its centre is half its height up.
    assert!((lying.z - 0.15).abs() < 1e-9, "{lying:?}");
}

#[test]
fn a_person_lying_on_the_lane_is_a_low_long_footprint_in_bev_occupancy_and_lidar() {
    let f = load("person-lying-on-lane");
    let (boxes, bev, occ) = render(&f, 0);
    let (lying, kneeling, standing) = (boxed(&boxes, "injured"), boxed(&boxes, "aider"), boxed(&boxes, "onlooker"));
    // BEV: lying across the lane (heading 90 deg, the ego faces east), the footprint spans the
    // body's length along the ego's y; the aux height channel stores its 0.3 m truncated to 0.
    let (px, span) = bev_footprint(&bev, CH_PEDESTRIAN, lying);
    assert!(px >= 12 && span >= lying.l - 0.5, "{px} px spanning {span} m for a {:.2} m body", lying.l);
    let (i, j) = (((lying.x + 50.0) * 4.0) as usize, ((lying.y + 50.0) * 4.0) as usize);
    assert_eq!(bev.aux[[AUX_HEIGHT, i, j]], 0);
    assert_eq!(bev.masks[[CH_PEDESTRIAN, i, j]], 1);
    // Occupancy: the lying body is no taller than 0.3 m (its voxels reach the layer holding
    // 0.3 m, at most 0.5 m); kneeling about half a standing person; standing above 1.5 m.
    let (top, n) = occupied_top(&occ, lying, PEDESTRIAN);
    assert!(n >= 10 && (0.25..=0.5).contains(&top), "lying: {n} voxels, top {top} m");
    let (top_k, n_k) = occupied_top(&occ, kneeling, PEDESTRIAN);
    assert!(n_k > 0 && top_k <= 1.0 && top_k > 0.5, "kneeling: {n_k} voxels, top {top_k} m");
    let (top_s, _) = occupied_top(&occ, standing, PEDESTRIAN);
    assert!(top_s >= 1.5, "standing: top {top_s} m");
    // LiDAR: the returns off the lying body are within its 0.3 m (plus the voxel they land in).
    let pc = rocc::lidar::scan(&occ, &rocc::lidar::Rig::nuplan(), f.concrete.seed, 0);
    let on: Vec<f32> =
        pc.points.iter().filter(|p| inside(lying, p.x as f64, p.y as f64, 0.0) && p.z > 0.05).map(|p| p.z).collect();
    assert!(!on.is_empty(), "no LiDAR return off the lying body");
    let high = on.iter().copied().fold(f32::MIN, f32::max);
    assert!(high <= 0.5, "a LiDAR return {high} m above the road off a 0.3 m body");
    let standing_high = pc
        .points
        .iter()
        .filter(|p| inside(standing, p.x as f64, p.y as f64, 0.0))
        .map(|p| p.z)
        .fold(f32::MIN, f32::max);
    assert!(standing_high > 1.0, "the standing onlooker returns up to {standing_high} m");
}

#[test]
fn a_kneeling_person_on_the_shoulder_and_a_dog_lying_on_the_lane_stay_put_while_the_ego_passes() {
    let f = load("kneeling-on-shoulder");
    let last = f.tracks.frames - 1;
    let idx = |n: &str| f.tracks.agents.iter().position(|a| a.name == n).expect(n);
    for who in ["kneeler", "dog", "parked"] {
        let (p0, p1) = (f.tracks.poses[idx(who)][0], f.tracks.poses[idx(who)][last]);
        assert!((p0.x - p1.x).abs() < 1e-9 && (p0.y - p1.y).abs() < 1e-9, "{who} moved");
    }
    let ego = idx("ego");
    assert!(f.tracks.poses[ego][last].x - f.tracks.poses[ego][0].x > 15.0, "the ego drove on");
    let (boxes, _, occ) = render(&f, 0);
    let dog = boxed(&boxes, "dog");
    assert!(dog.h <= 0.3 + 1e-9, "{dog:?}");
    let (top, n) = occupied_top(&occ, boxed(&boxes, "kneeler"), PEDESTRIAN);
    assert!(n > 0 && top <= 1.0, "kneeling: {n} voxels, top {top} m");
}

#[test]
fn a_wreck_lies_across_a_lane_and_another_beside_the_road() {
    let f = load("wreck-across-lane");
    let (boxes, bev, occ) = render(&f, 0);
    for who in ["wreck", "ditched"] {
        let b = boxed(&boxes, who);
        let (px, _) = bev_footprint(&bev, CH_VEHICLE, b);
        let (_, n) = occupied_top(&occ, b, VEHICLE);
        assert!(px > 50 && n > 50, "{who}: {px} BEV px, {n} voxels");
    }
    // The ego in the free lane passes the wreck.
    let ego = f.tracks.agents.iter().position(|a| a.name == "ego").expect("ego");
    assert!(f.tracks.poses[ego][f.tracks.frames - 1].x > 15.0, "the ego drove past the wreck");
}

#[test]
fn posture_belongs_to_people_and_animals_and_a_person_stays_near_the_map() {
    let scene = |body: &str| {
        format!(
            "scenario s {{ duration 2 s\n road straight {{ lanes 1 }}\n agent ego: sedan {{ at west.in[1], 30 m before center }}\n {body}\n}}\n"
        )
    };
    let code = |body: &str| front_of(&scene(body)).err().map(|d| d[0].code);
    // Anywhere on the lane or beside the road, in any posture.
    for body in [
        "agent p: pedestrian { at west.in[1], 10 m before center; posture lying }",
        "agent p: child { at (0 m, -8 m); posture kneeling }",
        "object d: deer_carcass { at west.in[1], 5 m before center; posture lying }",
        "agent d: dog { at west.in[1], 5 m before center; posture standing }",
    ] {
        let body = body.replace("deer_carcass", "animal");
        assert_eq!(code(&body), None, "{body}");
    }
    assert_eq!(code("object c: sedan { at west.in[1], 5 m before center; posture lying }"), Some("E0130"));
    assert_eq!(code("object c: traffic_cone { at west.in[1], 5 m before center; posture lying }"), Some("E0130"));
    assert_eq!(code("agent p: adult { at west.in[1], 5 m before center; posture sitting }"), Some("E0116"));
    assert_eq!(
        code("agent p: adult { at west.in[1], 5 m before center; posture lying; posture kneeling }"),
        Some("E0105")
    );
    // Off the map entirely is still a mistake.
    assert_eq!(code("agent p: adult { at (0 m, -60 m); posture lying }"), Some("E0201"));
}
