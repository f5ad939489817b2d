//! BEV benchmark. In: nothing (a synthetic four-way junction, 20 agents, an ego driving through).
//! Out: BEV frames per second on one core and on all cores, and the cost of writing one frame as
//! a compressed `.npz`, printed to stdout. Run with `cargo run --release --bin bench`
//! (`-- --preview DIR` also writes `DIR/preview/bev.png` of one frame).

use glam::DVec2;
use rayon::prelude::*;
use rocc::check::scenario::Class;
use rocc::place::Pose;
use rocc::raster::{Bev, Rasterizer};
use rocc::road::map::Map;
use rocc::view::{AgentState, to_ego};
use std::time::Instant;

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<DVec2> {
    vec![DVec2::new(x0, y0), DVec2::new(x1, y0), DVec2::new(x1, y1), DVec2::new(x0, y1)]
}

/// Four arms of 2 + 2 lanes (3.5 m), junction with rounded corners, sidewalks, crosswalks,
/// dashed dividers.
fn four_way() -> Map {
    let (hw, far) = (7.0, 150.0);
    let mut m = Map::default();
    // Junction: a square with corner arcs (many vertices, like a real template).
    let mut junction = Vec::new();
    for q in 0..4 {
        let (cx, cy) = [(hw + 5.0, hw + 5.0), (-hw - 5.0, hw + 5.0), (-hw - 5.0, -hw - 5.0), (hw + 5.0, -hw - 5.0)][q];
        let a0 = std::f64::consts::FRAC_PI_2 * (q as f64 + 2.0);
        for k in 0..=8 {
            let a = a0 + std::f64::consts::FRAC_PI_2 * k as f64 / 8.0;
            junction.push(DVec2::new(cx + 5.0 * a.cos(), cy + 5.0 * a.sin()));
        }
    }
    m.intersections = vec![junction.clone()];
    m.lane_group_connectors = vec![junction];
    let j = hw + 5.0;
    for rot in 0..4 {
        let r = |p: DVec2| DVec2::from_angle(std::f64::consts::FRAC_PI_2 * rot as f64).rotate(p);
        let rr = |v: Vec<DVec2>| v.into_iter().map(r).collect::<Vec<_>>();
        m.road_segments.push(rr(rect(j, -hw, far, hw)));
        m.lane_groups.push(rr(rect(j, -hw, far, 0.0)));
        m.lane_groups.push(rr(rect(j, 0.0, far, hw)));
        m.drivable.push(rr(rect(j, -hw, far, hw)));
        m.walkways.push(rr(rect(j, hw + 0.5, far, hw + 3.0)));
        m.walkways.push(rr(rect(j, -hw - 3.0, far, -hw - 0.5)));
        m.crosswalk_polygons.push(rr(rect(j + 0.5, -hw, j + 4.5, hw)));
        for lane_y in [-3.5, 3.5] {
            let mut x = j + 6.0;
            while x < far {
                m.dividers.push(vec![r(DVec2::new(x, lane_y)), r(DVec2::new(x + 3.0, lane_y))]);
                x += 9.0;
            }
        }
        m.dividers.push(vec![r(DVec2::new(j + 6.0, 0.0)), r(DVec2::new(far, 0.0))]);
    }
    m.drivable.push(m.intersections[0].clone());
    m
}

struct World {
    names: Vec<String>,
    poses: Vec<Pose>,
}

fn world(frame: usize) -> (Pose, World) {
    let t = frame as f64 * 0.1;
    let ego = Pose { x: -60.0 + 8.0 * t, y: -1.75, yaw: 0.02 * (t * 0.7).sin() };
    let mut names = Vec::new();
    let mut poses = Vec::new();
    for k in 0..20 {
        let arm = k % 4;
        let s = 20.0 + 7.0 * (k / 4) as f64 + 3.0 * t;
        let a = std::f64::consts::FRAC_PI_2 * arm as f64;
        let p = DVec2::from_angle(a).rotate(DVec2::new(s, 1.75 + 3.5 * (k % 2) as f64));
        names.push(format!("agent{k}"));
        poses.push(Pose { x: p.x, y: p.y, yaw: a + std::f64::consts::PI + 0.05 * k as f64 });
    }
    (ego, World { names, poses })
}

fn frame(r: &mut Rasterizer, bev: &mut Bev, map: &Map, i: usize) -> usize {
    let (ego, w) = world(i);
    let classes = [Class::Vehicle, Class::Vehicle, Class::Pedestrian, Class::Bicycle, Class::TrafficCone];
    let states = w.names.iter().zip(&w.poses).enumerate().map(|(k, (n, p))| AgentState {
        track: k as u32,
        name: n,
        kind: "sedan",
        class: classes[k % classes.len()],
        size: [4.6, 1.9, 1.6],
        pose: *p,
    });
    let boxes = to_ego(ego, states);
    r.rasterize_into(map, ego, &boxes, bev);
    bev.masks[[8, 200, 200]] as usize
}

fn fps(pool: &rayon::ThreadPool, map: &Map, frames: usize) -> f64 {
    pool.install(|| {
        let t0 = Instant::now();
        let sink: usize = (0..frames)
            .into_par_iter()
            .map_init(|| (Rasterizer::new(), Bev::zeros()), |(r, b), i| frame(r, b, map, i))
            .sum();
        std::hint::black_box(sink);
        frames as f64 / t0.elapsed().as_secs_f64()
    })
}

fn main() {
    let map = four_way();
    // `bench --preview DIR`: also write DIR/preview/bev.png of frame 30, to eyeball the raster.
    let args: Vec<String> = std::env::args().collect();
    if let Some(dir) = args.iter().position(|a| a == "--preview").and_then(|i| args.get(i + 1)) {
        let (mut r, mut bev) = (Rasterizer::new(), Bev::zeros());
        frame(&mut r, &mut bev, &map, 30);
        match rocc::output::write_preview_png(std::path::Path::new(dir), &bev) {
            Ok(f) => println!("wrote {dir}/{}", f.path),
            Err(e) => eprintln!("preview: {e}"),
        }
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a one-thread pool");
    let all = rayon::ThreadPoolBuilder::new().num_threads(cores).build().expect("a pool per core");
    fps(&one, &map, 100); // warm-up
    let f1 = fps(&one, &map, 2000);
    let fa = fps(&all, &map, 2000 * cores);
    println!("BEV raster, 400x400, four-way map, 20 agents (excluding compression)");
    println!("  1 core   : {f1:8.0} frames/s ({:.3} ms/frame)", 1e3 / f1);
    println!("  {cores} cores  : {fa:8.0} frames/s");

    let dir = std::env::temp_dir().join(format!("rocc-bench-{}", std::process::id()));
    let (mut r, mut bev) = (Rasterizer::new(), Bev::zeros());
    let n = 50;
    let mut bytes = 0;
    let t0 = Instant::now();
    for i in 0..n {
        frame(&mut r, &mut bev, &map, i);
        bytes += rocc::output::write_bev_frame(&dir, i, &bev).map(|f| f.bytes).unwrap_or(0);
    }
    let per = t0.elapsed().as_secs_f64() / n as f64 - 1.0 / f1;
    println!(
        "npz write (compressed, incl. rename): {:.2} ms/frame, {:.1} KiB/frame",
        per * 1e3,
        bytes as f64 / n as f64 / 1024.0
    );
    let _ = std::fs::remove_dir_all(&dir);
}
