//! rocc's benchmarks: figures printed to stdout, never asserted (speed targets live here, not in
//! unit tests). `cargo run --release --bin bench [-- SECTION...]`, sections `front`, `rollout`,
//! `stages`, `e2e` (default: all).
//!
//! - front: parse + check per library file, and generated files of 10/100/1000 agents;
//! - rollout: cost per agent-frame over the library, and on generated 50- and 200-agent scenes;
//!   `bench rollout-loop NAME [SECONDS]` rolls one library scene (file stem, or `gen50`/`gen200`)
//!   out again and again for a profiler (default 10 s); opt in.
//! - stages: frames/s of BEV, occupancy, LiDAR (+ rays/s) and of each writer, on the
//!   ambulance example (background traffic included), one core and every core;
//! - e2e: `rocc compile` of the whole library at full stage into a temporary directory
//!   (BEV + occupancy + LiDAR + compressed writes + previews), frames/s, CPU time per frame and
//!   peak memory; with and without previews at the default 0.4 deg, and at the sensor's native
//!   0.2 deg without previews. `bench e2e-lean [FRAMES]` measures the 0.2 deg run without
//!   keeping its outputs (file by file, each deleted before the next), optionally on the first
//!   FRAMES frames of each clip; opt in.
//! - bev20: BEV frames/s on one core at exactly 20 boxes per frame (each frame's boxes, repeated
//!   3.5 m further left until there are 20), on every map of the library (roundabout included);
//!   opt in (`bench bev20`).
//! - grounded: inference time per frame of the learned backend (random weights: the cost does
//!   not depend on their values) for `configs/cpu-small.ron` and `configs/paper.ron`, on frames
//!   of the ambulance example; opt in (`bench grounded`, not in the default set), with
//!   `--device wgpu|cuda` (a build with that feature), `--batch N` frames per forward pass
//!   (default 1 on the CPU, 4 on a GPU) and `--configs cpu-small,paper`.

use rayon::prelude::*;
use rocc::backend::{Background, OccInput, Occupancy, OccupancyBackend, Procedural};
use rocc::compile::{Front, Options, batch, frame_boxes, front};
use rocc::fsio::Fnv1a;
use rocc::lidar::{Rig, scan, write_bin, write_pcd};
use rocc::output::{DEFLATE, Deflate, write_labels, write_npz, write_npz_with};
use rocc::raster::{Bev, Rasterizer};
use rocc::source::SourceMap;
use rocc::visibility::{CameraRig, Masks, masks_into};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn library() -> Vec<PathBuf> {
    batch::collect_inputs(&[root().join("scenarios")]).unwrap_or_default()
}

/// Median seconds of `f` over `reps` runs.
fn median(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let t0 = Instant::now();
            f();
            t0.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

/// CPU time of this thread, s (Linux `/proc/thread-self/schedstat`, nanoseconds), or `None`
/// elsewhere: on a shared machine it is the steadier figure, as waiting for a core does not count.
fn thread_cpu() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse::<f64>().ok().map(|ns| ns * 1e-9)
}

/// Median wall seconds of `f` over `reps` runs, and its mean CPU seconds (`thread_cpu` over all
/// runs together, as the kernel may count CPU time in whole scheduler ticks; NaN where
/// unavailable).
fn median_cpu(reps: usize, mut f: impl FnMut()) -> (f64, f64) {
    let reps = reps.max(1);
    let c0 = thread_cpu();
    let t = median(reps, &mut f);
    let cpu = match (c0, thread_cpu()) {
        (Some(a), Some(b)) => (b - a) / reps as f64,
        _ => f64::NAN,
    };
    (t, cpu)
}

/// A valid scenario with `n` agents spread over a long six-lane straight road.
fn generated(n: usize) -> String {
    let mut s = String::from(
        "scenario generated {\n    seed 1\n    duration 10 s\n    rate 10 Hz\n    egos [a0]\n\n    road straight { lanes 6; lane_width 3.5 m; speed_limit 100 km/h; length 1000 m }\n\n",
    );
    let slots = [("west", "in"), ("east", "in"), ("west", "out"), ("east", "out")];
    for i in 0..n {
        let (arm, dir) = slots[i % 4];
        let lane = 1 + (i / 4) % 6;
        let dist = 5.0 + 10.0 * (i / 24) as f64;
        let rel = if dir == "in" { "before" } else { "after" };
        s += &format!(
            "    agent a{i}: one_of [sedan, suv, hatchback] {{\n        at {arm}.{dir}[{lane}], {dist} m {rel} center\n        speed 20..30 m/s\n        goal {{ speed 25 m/s; lateral hold_lane }}\n    }}\n"
        );
    }
    s + "}\n"
}

fn load(path: &Path) -> Option<Front> {
    let mut sources = SourceMap::default();
    let s = rocc::check::check_path(path, &mut sources).ok()?;
    front(s, None).ok()
}

fn bench_front() {
    println!("== front: parse + check (median of 50 runs, one core)");
    for p in library() {
        let text = std::fs::read_to_string(&p).unwrap_or_default();
        let dir = p.parent().unwrap_or(Path::new(".")).to_path_buf();
        let t = median(50, || {
            let mut sources = SourceMap::default();
            let _ = std::hint::black_box(rocc::check::check_text("x.scn", &text, &dir, &mut sources));
        });
        let name = p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        println!("  {name:<40} {:>5} B  {:>8.1} us", text.len(), t * 1e6);
    }
    for n in [10, 100, 1000] {
        let text = generated(n);
        let t = median(if n >= 1000 { 10 } else { 50 }, || {
            let mut sources = SourceMap::default();
            let r = rocc::check::check_text("gen.scn", &text, Path::new("."), &mut sources);
            std::hint::black_box(r.is_ok());
        });
        println!(
            "  generated, {n:>4} agents {:>9} B  {:>8.1} us  ({:.2} us/agent)",
            text.len(),
            t * 1e6,
            t * 1e6 / n as f64
        );
    }
}

fn bench_rollout() {
    println!("== rollout: cost per agent-frame (one core; median wall time of 20 runs, then mean CPU time)");
    let mut total = (0.0, 0usize, 0.0);
    // Every track rolled out below, bit for bit (`Tracks::digest`): a speed-up must leave it as it is.
    let mut h = Fnv1a::new();
    let shared = batch::collect_inputs(&[root().join("tests/fixtures/examples")]).unwrap_or_default();
    for p in &shared {
        if let Some(f) = load(p) {
            f.tracks.digest(&mut h);
        }
    }
    for p in library() {
        let Some(f) = load(&p) else { continue };
        f.tracks.digest(&mut h);
        let (t, c) = median_cpu(20, || {
            std::hint::black_box(rocc::rollout::rollout(&f.concrete, &f.map, &f.placed).is_ok());
        });
        let af = f.tracks.agents.len() * f.tracks.frames;
        total.0 += t;
        total.1 += af;
        total.2 += c;
        let name = p.file_stem().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        println!(
            "  {name:<32} {:>3} agents x {:>3} frames  {:>7.2} ms  {:>6.3} us/agent-frame  cpu {:>6.3}",
            f.tracks.agents.len(),
            f.tracks.frames,
            t * 1e3,
            t * 1e6 / af as f64,
            c * 1e6 / af as f64
        );
    }
    let af = total.1.max(1) as f64;
    println!("  library total: {:.3} us/agent-frame  cpu {:.3}", total.0 * 1e6 / af, total.2 * 1e6 / af);
    // 50 agents: below the grid's threshold (a scan of all agents); 200: bucketed.
    for n in [50, 200] {
        let mut sources = SourceMap::default();
        let Some(f) = rocc::check::check_text("gen.scn", &generated(n), Path::new("."), &mut sources)
            .ok()
            .and_then(|s| front(s, None).ok())
        else {
            println!("  generated {n} agents: does not compile");
            continue;
        };
        let (t, c) = median_cpu(10, || {
            std::hint::black_box(rocc::rollout::rollout(&f.concrete, &f.map, &f.placed).is_ok());
        });
        let af = (f.tracks.agents.len() * f.tracks.frames) as f64;
        f.tracks.digest(&mut h);
        println!(
            "  generated {n} agents x {} frames: {:.3} us/agent-frame  cpu {:.3}",
            f.tracks.frames,
            t * 1e6 / af,
            c * 1e6 / af
        );
    }
    println!("  digest of every track above and of {} shared examples: {:016x}", shared.len(), h.finish());
}

/// One scene rolled out for `secs` seconds, so that a profiler sees nothing else.
fn rollout_loop(name: &str, secs: f64) {
    let f = match name.strip_prefix("gen").and_then(|n| n.parse::<usize>().ok()) {
        Some(n) => {
            let mut sources = SourceMap::default();
            rocc::check::check_text("gen.scn", &generated(n), Path::new("."), &mut sources)
                .ok()
                .and_then(|s| front(s, None).ok())
        }
        None => load(&root().join(format!("scenarios/{name}.scn"))),
    };
    let Some(f) = f else {
        println!("== rollout-loop: no scene `{name}` (a library file stem, or gen50/gen200)");
        return;
    };
    let t0 = Instant::now();
    let mut runs = 0usize;
    while t0.elapsed().as_secs_f64() < secs {
        std::hint::black_box(rocc::rollout::rollout(&f.concrete, &f.map, &f.placed).is_ok());
        runs += 1;
    }
    let af = (f.tracks.agents.len() * f.tracks.frames * runs.max(1)) as f64;
    println!("== rollout-loop {name}: {runs} runs, {:.3} us/agent-frame", t0.elapsed().as_secs_f64() * 1e6 / af);
}

/// The ambulance example's frames scanned at 0.2 deg on one core for `secs` seconds, so that a
/// profiler sees nothing else: CPU ms per frame (median of the passes over its 80 frames) and
/// the clouds' point count.
fn lidar_loop(secs: f64) {
    let Some(f) = load(&root().join("scenarios/ambulance_crowded_intersection.scn")) else { return };
    let ego = f.concrete.egos[0];
    let bg = Background::generate(&f.map, f.concrete.seed);
    let occs: Vec<Occupancy> = (0..f.tracks.frames)
        .map(|i| {
            let boxes = frame_boxes(&f, ego, i);
            let mut b = Bev::zeros();
            Rasterizer::new().rasterize_into(&f.map, f.tracks.poses[ego][i], &boxes, &mut b);
            let input =
                OccInput { boxes: &boxes, bev: &b, background: &bg, ego: f.tracks.poses[ego][i], seed: 1, frame: i };
            Procedural::default().occupancy(&input)
        })
        .collect();
    let mut rig = Rig::nuplan();
    rig.horizontal_resolution_deg = 0.2;
    let (t0, mut per, mut points) = (Instant::now(), Vec::new(), 0);
    pool(1).install(|| {
        while t0.elapsed().as_secs_f64() < secs || per.is_empty() {
            let c0 = thread_cpu().unwrap_or(0.0);
            points = occs.iter().enumerate().map(|(i, o)| scan(o, &rig, 1, i).points.len()).sum::<usize>();
            per.push((thread_cpu().unwrap_or(0.0) - c0) * 1e3 / occs.len() as f64);
        }
    });
    per.sort_by(f64::total_cmp);
    // Every point's bytes, frame after frame: equal digests, equal clouds (for A/B runs of two builds).
    let mut digest = rocc::fsio::Fnv1a::new();
    for (i, o) in occs.iter().enumerate() {
        for p in scan(o, &rig, 1, i).points {
            digest.write(&p.x.to_le_bytes()).write(&p.y.to_le_bytes()).write(&p.z.to_le_bytes());
            digest.write(&p.intensity.to_le_bytes()).write(&p.ring.to_le_bytes()).write(&[p.lidar]);
        }
    }
    println!(
        "== lidar-loop: {} passes over {} frames at 0.2 deg, one core: {:.2} ms CPU per frame (median; min {:.2}), {points} points, digest {:016x}",
        per.len(),
        occs.len(),
        per[per.len() / 2],
        per[0],
        digest.finish()
    );
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool")
}

fn bench_stages() {
    let path = root().join("scenarios/ambulance_crowded_intersection.scn");
    let Some(f) = load(&path) else {
        println!("== stages: {} does not compile", path.display());
        return;
    };
    let ego = f.concrete.egos[0];
    let frames: Vec<usize> = (0..f.tracks.frames).collect();
    let boxes: Vec<_> = frames.iter().map(|&i| frame_boxes(&f, ego, i)).collect();
    let mean_boxes = boxes.iter().map(Vec::len).sum::<usize>() as f64 / frames.len() as f64;
    let cores = rayon::current_num_threads();
    println!(
        "== stages: ambulance_crowded_intersection, ego `{}`, {} frames, {mean_boxes:.1} boxes/frame; 1 core / {cores} cores",
        f.tracks.agents[ego].name,
        frames.len()
    );
    let bg = Background::generate(&f.map, f.concrete.seed);
    let backend = Procedural::default();
    let rig = Rig::nuplan();
    let bevs: Vec<Bev> = frames
        .iter()
        .map(|&i| {
            let mut r = Rasterizer::new();
            let mut b = Bev::zeros();
            r.rasterize_into(&f.map, f.tracks.poses[ego][i], &boxes[i], &mut b);
            b
        })
        .collect();
    let occ_input = |i: usize| OccInput {
        boxes: &boxes[i],
        bev: &bevs[i],
        background: &bg,
        ego: f.tracks.poses[ego][i],
        seed: 1,
        frame: i,
    };
    let occs: Vec<Occupancy> = frames.iter().map(|&i| backend.occupancy(&occ_input(i))).collect();

    // Frames/s, and CPU ms per frame (the process's CPU time: on a shared machine it moves less
    // than wall time does).
    let fps = |threads: usize, work: &(dyn Fn(usize) + Sync)| {
        let p = pool(threads);
        let (t0, c0) = (Instant::now(), cpu_secs());
        p.install(|| frames.par_iter().for_each(|&i| work(i)));
        let n = frames.len() as f64;
        (n / t0.elapsed().as_secs_f64(), cpu_secs().zip(c0).map(|(c1, c0)| 1e3 * (c1 - c0) / n))
    };
    let report = |name: &str, work: &(dyn Fn(usize) + Sync), extra: &dyn Fn(f64) -> String| {
        let ((one, cpu), (all, _)) = (fps(1, work), fps(cores, work));
        let cpu = cpu.map_or(String::new(), |c| format!("{c:>6.1} ms CPU/frame"));
        println!("  {name:<26} {one:>8.1} fr/s  {all:>8.1} fr/s  {cpu}  {}", extra(all));
    };
    let bev_work = |i: usize| {
        thread_local!(static S: std::cell::RefCell<(Rasterizer, Bev)> = std::cell::RefCell::new((Rasterizer::new(), Bev::zeros())));
        S.with(|s| {
            let (r, b) = &mut *s.borrow_mut();
            r.rasterize_into(&f.map, f.tracks.poses[ego][i], &boxes[i], b);
        });
    };
    report("bev (raster)", &bev_work, &|_| String::new());
    let occ_work = |i: usize| {
        thread_local!(static O: std::cell::RefCell<Occupancy> = std::cell::RefCell::new(Occupancy::empty()));
        O.with(|o| backend.occupancy_into(&occ_input(i), &mut o.borrow_mut()));
    };
    report("occupancy (procedural)", &occ_work, &|_| String::new());
    for res in [0.4, 0.2] {
        let mut r = rig.clone();
        r.horizontal_resolution_deg = res;
        let rays: usize =
            r.sensors.iter().map(|s| s.elevations_deg.len() * s.azimuths(r.horizontal_resolution_deg).count()).sum();
        let lidar_work = |i: usize| {
            std::hint::black_box(scan(&occs[i], &r, 1, i).points.len());
        };
        report(&format!("lidar (nuPlan rig, {res} deg)"), &lidar_work, &|fps| {
            format!("{rays} rays/frame, {:.2} M rays/s", fps * rays as f64 / 1e6)
        });
    }
    let cameras = CameraRig::nuplan();
    let vis_work = |i: usize| {
        thread_local!(static M: std::cell::RefCell<Masks> = std::cell::RefCell::new(Masks::default()));
        M.with(|m| masks_into(&occs[i], &rig, &cameras, &mut m.borrow_mut()));
    };
    report("visibility (both masks)", &vis_work, &|_| String::new());
    // A short clip has fewer frames than cores: the masks of one frame share its rays out.
    let (t0, c0, mut m) = (Instant::now(), cpu_secs(), Masks::default());
    let n = 16.min(frames.len());
    pool(cores).install(|| frames.iter().take(n).for_each(|&i| masks_into(&occs[i], &rig, &cameras, &mut m)));
    let cpu = cpu_secs()
        .zip(c0)
        .map_or(String::new(), |(c1, c0)| format!("{:>6.1} ms CPU/frame", 1e3 * (c1 - c0) / n as f64));
    println!(
        "  {:<26} {:>8.1} ms wall/frame on {cores} cores  {cpu}",
        "visibility, frame by frame",
        1e3 * t0.elapsed().as_secs_f64() / n as f64
    );
    let dir = std::env::temp_dir().join(format!("rocc-bench-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let mut masks = Masks::default();
    masks_into(&occs[0], &rig, &cameras, &mut masks);
    let labels = |i: usize| {
        let _ = write_labels(&dir.join(format!("g{i}.npz")), &occs[i], &masks);
    };
    report("write labels.npz", &labels, &|_| String::new());
    let npz = |i: usize| {
        let _ = write_npz(&dir.join(format!("b{i}.npz")), &bevs[i]);
    };
    report("write bev .npz (deflate)", &npz, &|_| String::new());
    let npy = |i: usize| {
        let _ = rocc::output::write_occ_npy(rocc::fsio::To::Now, &dir.join(format!("o{i}.npy")), &occs[i], |_| {});
    };
    report("write occ .npy", &npy, &|_| String::new());
    let clouds: Vec<_> = frames.iter().take(8).map(|&i| scan(&occs[i], &rig, 1, i)).collect();
    let pts = clouds.iter().map(|c| c.points.len()).sum::<usize>() / clouds.len().max(1);
    let bin = |i: usize| {
        let c = &clouds[i % clouds.len()];
        let _ = write_bin(rocc::fsio::To::Now, &dir.join(format!("l{i}.bin")), c);
        let _ = write_pcd(rocc::fsio::To::Now, &dir.join(format!("l{i}.pcd")), c);
    };
    report("write lidar .bin + .pcd", &bin, &|_| format!("{pts} points/frame"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The value after `name` in the arguments.
fn opt<'a>(args: &'a [String], name: &str) -> Option<&'a str> {
    args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).map(String::as_str)
}

/// User + system CPU seconds of this process so far (all threads), from /proc/self/stat: on a
/// shared machine the steadier figure, as waiting for a core does not count.
fn cpu_secs() -> Option<f64> {
    cpu_split().map(|(user, system)| user + system)
}

/// Process CPU seconds so far: (user, system).
fn cpu_split() -> Option<(f64, f64)> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| f.get(i)?.parse::<f64>().ok();
    // USER_HZ: 100 on every Linux this runs on (`getconf CLK_TCK`).
    Some((ticks(11)? / 100.0, ticks(12)? / 100.0))
}

fn peak_rss_mb() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb: f64 = s.lines().find(|l| l.starts_with("VmHWM:"))?.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn bench_e2e() {
    let inputs = library();
    let out = std::env::temp_dir().join(format!("rocc-bench-e2e-{}", std::process::id()));
    let native = Rig::load(None, Some(0.2)).expect("the bundled rig steps 0.2 degrees");
    let runs = [
        ("with previews", true, Rig::nuplan()),
        ("no previews", false, Rig::nuplan()),
        ("0.2 deg, no previews", false, native),
    ];
    for (label, previews, rig) in runs {
        let _ = std::fs::remove_dir_all(&out);
        let opts = Options { previews, force: true, rig, ..Options::default() };
        let (t0, c0) = (Instant::now(), cpu_split());
        let r = batch::run(&inputs, &out, &opts, true);
        let secs = t0.elapsed().as_secs_f64();
        let frames: usize = r.clips.iter().map(|c| c.frames).sum();
        if let Some(((u1, s1), (u0, s0))) = cpu_split().zip(c0) {
            let per = |x: f64| 1e3 * x / frames.max(1) as f64;
            println!(
                "  CPU time: {:.1} ms per frame (user {:.1}, system {:.1})",
                per(u1 - u0 + s1 - s0),
                per(u1 - u0),
                per(s1 - s0)
            );
        }
        println!(
            "== e2e ({label}): {} clips, {frames} frames of BEV + occupancy + LiDAR + writes in {secs:.1} s on {} cores: {:.1} frames/s ({} failed)",
            r.clips.len(),
            rayon::current_num_threads(),
            frames as f64 / secs,
            r.failures.len()
        );
        if label == "no previews" {
            let per = secs / frames.max(1) as f64;
            println!("  a 65,518-frame corpus at this rate: {:.0} min on this machine", 65_518.0 * per / 60.0);
        }
    }
    let _ = std::fs::remove_dir_all(&out);
    if let Some(mb) = peak_rss_mb() {
        println!("  peak resident memory of the whole bench: {mb:.0} MB");
    }
}

/// `bench e2e`'s 0.2 deg run (all stages, no previews) without keeping its 28 GB: one library
/// file at a time, each file's outputs deleted before the next (a clip's frames still run on
/// every core), optionally only the first `frames` frames of each clip. Frames/s and process
/// CPU ms per frame, the writes included.
fn bench_e2e_lean(frames: Option<usize>) {
    let inputs = library();
    let out = std::env::temp_dir().join(format!("rocc-bench-e2e-lean-{}", std::process::id()));
    let rig = Rig::load(None, Some(0.2)).expect("the bundled rig steps 0.2 degrees");
    let opts =
        Options { previews: false, force: true, rig, frames: frames.map(|n| format!("0..{n}")), ..Options::default() };
    let (mut done, mut failed, mut secs) = (0, 0, 0.0);
    let c0 = cpu_secs();
    for input in &inputs {
        let _ = std::fs::remove_dir_all(&out);
        let t0 = Instant::now();
        let r = batch::run(std::slice::from_ref(input), &out, &opts, true);
        secs += t0.elapsed().as_secs_f64();
        done += r.clips.iter().map(|c| c.frames).sum::<usize>();
        failed += r.failures.len();
    }
    let _ = std::fs::remove_dir_all(&out);
    let cpu = cpu_secs().zip(c0).map_or(String::new(), |(c1, c0)| {
        format!(", {:.1} ms CPU per frame (deletes included)", 1e3 * (c1 - c0) / done.max(1) as f64)
    });
    println!(
        "== e2e-lean (0.2 deg, no previews, {} per clip, outputs deleted file by file): {done} frames in {secs:.1} s on {} cores: {:.1} frames/s{cpu} ({failed} failed)",
        frames.map_or("every frame".to_string(), |n| format!("first {n} frames")),
        rayon::current_num_threads(),
        done as f64 / secs.max(1e-9),
    );
}

/// One 16-frame clip of the ambulance example at the BEV stage with previews (the size of a
/// CIREN case's clip), on every core: median wall time of 9 runs, mean process CPU time, and the
/// manifest's per-stage seconds (wall time summed over threads) of the median run.
fn bench_clip() {
    use rocc::compile::{ClipInput, Stage, compile_clip};
    let path = root().join("scenarios/ambulance_crowded_intersection.scn");
    let mut sources = SourceMap::default();
    let Some(f) = rocc::check::check_path(&path, &mut sources).ok().and_then(|s| front(s, None).ok()) else {
        println!("== clip: {} does not compile", path.display());
        return;
    };
    let bytes = std::fs::read(&path).unwrap_or_default();
    let bg = Background::generate(&f.map, f.concrete.seed);
    let frames: Vec<usize> = (0..16.min(f.tracks.frames)).collect();
    let ci = ClipInput {
        input: "ambulance.scn",
        input_bytes: &bytes,
        sources: &sources,
        front: &f,
        background: &bg,
        ego: f.concrete.egos[0],
        frames: &frames,
    };
    let dir = std::env::temp_dir().join(format!("rocc-bench-clip-{}", std::process::id()));
    println!(
        "== clip: {} frames, BEV stage, previews, {} cores (median of 9)",
        frames.len(),
        rayon::current_num_threads()
    );
    for previews in [false, true] {
        let opts = Options { stage: Stage::Bev, previews, force: true, ..Options::default() };
        let c0 = cpu_secs();
        let mut runs: Vec<(f64, Vec<(String, f64)>)> = (0..9)
            .map(|_| {
                let t0 = Instant::now();
                let r = compile_clip(&ci, &opts, &dir, &|| {});
                let secs = t0.elapsed().as_secs_f64();
                let stages = r.map(|r| r.manifest.timings.iter().map(|t| (t.stage.clone(), t.seconds)).collect());
                (secs, stages.unwrap_or_default())
            })
            .collect();
        let cpu = cpu_secs().zip(c0).map_or(f64::NAN, |(c1, c0)| (c1 - c0) / runs.len() as f64);
        runs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (secs, stages) = &runs[runs.len() / 2];
        let parts: Vec<String> = stages.iter().map(|(n, s)| format!("{n} {:.1}", s * 1e3)).collect();
        let label = if previews { "with previews" } else { "no previews" };
        println!(
            "  {label:<14} {:>6.1} ms per clip, {:>6.1} ms CPU (thread-ms by stage: {})",
            secs * 1e3,
            cpu * 1e3,
            parts.join(", ")
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// BEV `.npz` writes: rocc's writer (fdeflate, and miniz_oxide's RLE strategy at levels 1-3; `*`
/// marks the one rocc writes with) against ndarray-npy's (zlib through the zip crate) at deflate
/// levels 0 (stored), 1, 2, 6 (its default) and 9, on the ambulance example's first 16 frames,
/// one core: the writers take turns, 5 rounds, median ms per file, bytes per file.
fn bench_npz() {
    use ndarray_npy::NpzWriter;
    use rocc::raster::layout::{KEY_AUX, KEY_MASKS, KEY_STRUCTURE};
    use zip::{CompressionMethod, write::SimpleFileOptions};
    let Some(f) = load(&root().join("scenarios/ambulance_crowded_intersection.scn")) else { return };
    let ego = f.concrete.egos[0];
    let bevs: Vec<Bev> = (0..16.min(f.tracks.frames))
        .map(|i| {
            let (mut r, mut b) = (Rasterizer::new(), Bev::zeros());
            r.rasterize_into(&f.map, f.tracks.poses[ego][i], &frame_boxes(&f, ego, i), &mut b);
            b
        })
        .collect();
    let dir = std::env::temp_dir().join(format!("rocc-bench-npz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let zlib = |path: &Path, b: &Bev, level: i64| -> std::io::Result<u64> {
        let opts = match level {
            0 => SimpleFileOptions::default().compression_method(CompressionMethod::Stored),
            l => {
                SimpleFileOptions::default().compression_method(CompressionMethod::Deflated).compression_level(Some(l))
            }
        };
        rocc::fsio::write_atomic(path, |w| {
            // The zip writer seeks back to its local headers: it writes into memory first.
            let mut npz = NpzWriter::new_with_options(std::io::Cursor::new(Vec::new()), opts);
            let e = |e: ndarray_npy::WriteNpzError| std::io::Error::other(e.to_string());
            npz.add_array(KEY_MASKS, &b.masks).map_err(e)?;
            npz.add_array(KEY_AUX, &b.aux).map_err(e)?;
            npz.add_array(KEY_STRUCTURE, &b.structure).map_err(e)?;
            std::io::Write::write_all(w, npz.finish().map_err(e)?.get_ref())
        })
    };
    type Writer<'a> = Box<dyn Fn(&Path, &Bev) -> std::io::Result<u64> + 'a>;
    let ours = [
        Deflate::Fdeflate,
        Deflate::Rle(1),
        Deflate::Rle(2),
        Deflate::Zlib(2),
        Deflate::ZlibRsRle(1),
        Deflate::ZlibRsRle(2),
        Deflate::ZlibRsRle(3),
        Deflate::Runs,
    ]
    .map(|how| {
        let name = match how {
            Deflate::Fdeflate => "rocc fdeflate".to_string(),
            Deflate::Rle(l) => format!("rocc rle {l}"),
            Deflate::Zlib(l) => format!("rocc level {l}"),
            Deflate::ZlibRsRle(l) => format!("rocc zlib-rs rle {l}"),
            Deflate::Runs => "rocc runs".to_string(),
        };
        let mark = if how == DEFLATE { " *" } else { "" };
        (format!("{name}{mark}"), Box::new(move |p: &Path, b: &Bev| write_npz_with(p, b, how)) as Writer)
    });
    let writers: Vec<(String, Writer)> = ours
        .into_iter()
        .chain(
            [0i64, 1, 2, 6, 9]
                .map(|l| (format!("zlib level {l}"), Box::new(move |p: &Path, b: &Bev| zlib(p, b, l)) as Box<_>)),
        )
        .collect();
    let mut times = vec![Vec::new(); writers.len()];
    let mut cpu = vec![Vec::new(); writers.len()];
    let mut bytes = vec![0u64; writers.len()];
    let per = bevs.len() as f64;
    for _ in 0..5 {
        for (n, (_, w)) in writers.iter().enumerate() {
            let (t0, c0) = (Instant::now(), thread_cpu().unwrap_or(f64::NAN));
            bytes[n] = bevs.iter().enumerate().map(|(i, b)| w(&dir.join(format!("{i}.npz")), b).unwrap_or(0)).sum();
            times[n].push(t0.elapsed().as_secs_f64() / per);
            cpu[n].push((thread_cpu().unwrap_or(f64::NAN) - c0) / per);
        }
    }
    println!("== npz: BEV .npz writers, {} frames, one core (median of 5 rounds)", bevs.len());
    for (n, (name, _)) in writers.iter().enumerate() {
        times[n].sort_by(f64::total_cmp);
        cpu[n].sort_by(f64::total_cmp);
        println!(
            "  {name:<16} {:>6.2} ms per file ({:>6.2} ms CPU), {:>8.0} bytes per file",
            times[n][2] * 1e3,
            cpu[n][2] * 1e3,
            bytes[n] as f64 / per
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The BEV target is stated at 20 agents; the library's scenes have fewer, so each
/// frame's boxes are repeated beside themselves (cost depends on box count and size, not on
/// where the boxes stand). One core, median of 5 passes over the frames; scenes with a frame
/// without boxes are skipped.
fn bench_bev20() {
    println!("== bev20: 1 core, 20 boxes/frame, median of 5 passes");
    for path in library() {
        let Some(f) = load(&path) else { continue };
        let ego = f.concrete.egos[0];
        let frames: Vec<Vec<_>> = (0..f.tracks.frames)
            .map(|i| {
                let real = frame_boxes(&f, ego, i);
                let mut out = real.clone();
                let mut k = 1.0;
                while out.len() < 20 && !real.is_empty() {
                    out.extend(real.iter().take(20 - out.len()).map(|b| {
                        let mut b = b.clone();
                        b.y += 3.5 * k;
                        b
                    }));
                    k += 1.0;
                }
                out
            })
            .collect();
        if frames.iter().any(|b| b.len() != 20) {
            continue;
        }
        let (mut r, mut b) = (Rasterizer::new(), Bev::zeros());
        let secs = median(5, || {
            for (i, boxes) in frames.iter().enumerate() {
                r.rasterize_into(&f.map, f.tracks.poses[ego][i], boxes, &mut b);
            }
        });
        println!(
            "  {:<36} {:<11} {:>8.1} fr/s",
            f.concrete.name,
            format!("{:?}", f.concrete.road.template),
            frames.len() as f64 / secs
        );
    }
}

#[path = "bench/learned.rs"]
mod learned;
#[path = "bench/splat.rs"]
mod splat;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let want = |s: &str| args.is_empty() || args.iter().any(|a| a == s);
    if want("front") {
        bench_front();
    }
    if want("rollout") {
        bench_rollout();
    }
    if let Some(i) = args.iter().position(|a| a == "rollout-loop") {
        let secs = args.get(i + 2).and_then(|s| s.parse().ok()).unwrap_or(10.0);
        rollout_loop(args.get(i + 1).map_or("", String::as_str), secs);
        return;
    }
    if let Some(i) = args.iter().position(|a| a == "lidar-loop") {
        let secs = args.get(i + 1).and_then(|s| s.parse().ok()).unwrap_or(10.0);
        lidar_loop(secs);
        return;
    }
    if want("stages") {
        bench_stages();
    }
    if want("e2e") {
        bench_e2e();
    }
    if let Some(i) = args.iter().position(|a| a == "e2e-lean") {
        bench_e2e_lean(args.get(i + 1).and_then(|s| s.parse().ok()));
    }
    if want("clip") {
        bench_clip();
    }
    if want("npz") {
        bench_npz();
    }
    if want("test") {
        bench_test();
    }
    if args.iter().any(|a| a == "bev20") {
        bench_bev20();
    }
    // Minutes on a 2-core machine with the paper's configuration: only when asked for.
    if args.iter().any(|a| a == "grounded") {
        learned::bench_grounded(&args);
    }
    if args.iter().any(|a| a == "train") {
        learned::bench_train(&args);
    }
    if args.iter().any(|a| a == "loss") {
        learned::bench_loss(&args);
    }
    if args.iter().any(|a| a == "splat") {
        splat::bench_splat(&args);
    }
}

/// `rocc test scenarios/` without the process around it: check, rollout, judging and snapshot
/// body per file on one core, then the whole library spread over every core as the command does.
fn bench_test() {
    println!("== test: `rocc test scenarios/` per file on one core (median of 5), then the library on every core");
    let files = library();
    let run = |p: &Path| {
        let mut sources = SourceMap::default();
        std::hint::black_box(rocc::expect::run(p, &mut sources).is_ok());
    };
    let mut cpu_total = 0.0;
    for p in &files {
        let (t, cpu) = median_cpu(5, || run(p));
        cpu_total += cpu;
        let name = p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        println!("  {name:<40} {:>7.1} ms  ({:.1} ms CPU)", t * 1e3, cpu * 1e3);
    }
    let t = median(5, || files.par_iter().for_each(|p| run(p)));
    println!(
        "  library, {} files, {} threads: {:.0} ms wall; {:.0} ms CPU on one core",
        files.len(),
        rayon::current_num_threads(),
        t * 1e3,
        cpu_total * 1e3
    );
}
