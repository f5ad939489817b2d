//! LiDAR pass. In: one frame's `Occupancy`, a `Rig` (RON; `rigs/nuplan.ron` by default), the
//! seed and the frame index. Out: a `PointCloud` in the ego frame (x, y, z, intensity 0-255,
//! ring, lidar id) and its KITTI-style `.bin` and PCD v0.7 `.pcd` files.
//!
//! Every (sensor, beam, azimuth) fires one ray, cast through the grid by 3D DDA (`dda`). A ray
//! reports the first non-free voxel it enters. Per beam, `fan` finds per azimuth sector how far
//! the rays pass above every block, and the walk starts there (the same hits, fewer steps). The ground needs no special case: the occupancy
//! backend labels the layer below z = 0 background (see `backend`), so ground returns are hits
//! on its top face. Then, per return, with the rig's parameters:
//!
//! - range limits: hits nearer than `min_range` or farther than `max_range` are dropped;
//! - drop: with probability base + incidence (1 - cos i)^2 + range (r / max_range)^2, where i is
//!   the angle between the ray and the normal of the voxel face it entered;
//! - range noise: the surface is somewhere inside the hit voxel, so the return is placed at
//!   entry + |N(0, sigma)| along the ray, sigma = sigma_m + sigma_per_m r, capped at the voxel's
//!   exit. One-sided on purpose: the voxels in front are free by the occupancy's own account, so
//!   every point stays in or on the boundary of a non-free voxel;
//! - intensity: 255 reflectivity(label) ((1 - lambert) + lambert cos i) exp(-2 alpha r)
//!   (1 + noise N(0, 1)), rounded and clamped to 0..=255.
//!
//! Randomness: each (sensor, beam) draws from its own `sample::Rng` keyed by (seed, frame,
//! sensor id, beam), three uniforms per ray hit or not, so the cloud does not depend on rayon's
//! scheduling or thread count. Points come out ordered by sensor, beam, then azimuth.
//!
//! Rays that leave the 100 m x 100 m x 8 m grid return nothing: the occupancy is the whole world
//! the sensor can see.

pub mod dda;
pub mod fan;
pub mod rig;
mod walk;

pub use rig::{Rig, RigError, Sensor};

use crate::backend::Occupancy;
use crate::backend::layout::{NX, NY, NZ};
use crate::fsio::To;
use crate::sample::Rng;
use rayon::prelude::*;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// One return in the ego frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    pub x: f32,
    pub y: f32,
    pub z: f32,
    /// 0..=255 (whole numbers).
    pub intensity: f32,
    /// Beam index within its sensor.
    pub ring: u16,
    /// Sensor id.
    pub lidar: u8,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointCloud {
    pub points: Vec<Point>,
}

/// The stream of one (sensor, beam) of one frame.
fn beam_rng(seed: u64, frame: usize, sensor: u8, beam: usize) -> Rng {
    // Each stage's SplitMix64 output scrambles the next key, so nearby keys give unrelated streams.
    let a = Rng::new(seed ^ 0x6c69_6461_725f_7631).next_u64();
    let b = Rng::new(a ^ (frame as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)).next_u64();
    Rng::new(b ^ (u64::from(sensor) << 40) ^ beam as u64)
}

/// Fire every ray of `rig` through `occ`.
pub fn scan(occ: &Occupancy, rig: &Rig, seed: u64, frame: usize) -> PointCloud {
    scan_with(occ, None, rig, seed, frame)
}

/// `scan` with `occ`'s block summary already made (`dda::Skip::summary`, fed `occ`'s labels
/// while a writer passed over them); `None` makes it here. The same cloud either way.
pub fn scan_with(occ: &Occupancy, skip: Option<&dda::Skip>, rig: &Rig, seed: u64, frame: usize) -> PointCloud {
    let std_layout;
    let labels: &[u8] = match occ.labels.as_slice() {
        Some(s) if occ.labels.dim() == (NX, NY, NZ) => s,
        _ if occ.labels.dim() == (NX, NY, NZ) => {
            std_layout = occ.labels.as_standard_layout();
            std_layout.as_slice().unwrap_or(&[])
        }
        _ => return PointCloud::default(),
    };
    let units: Vec<(usize, usize)> = rig
        .sensors
        .iter()
        .enumerate()
        .flat_map(|(s, sen)| (0..sen.elevations_deg.len()).map(move |b| (s, b)))
        .collect();
    let made;
    let skip = match skip {
        Some(s) => s,
        None => {
            made = dda::Skip::new(labels);
            &made
        }
    };
    let tables = RigTables::of(rig);
    let chunks: Vec<Vec<Point>> = units
        .par_iter()
        .map(|&(s, b)| {
            let sensor = Beam { sensor: &rig.sensors[s], view: &tables.views[s], trig: &tables.trig[s], beam: b };
            let mut out = take_buffer();
            fire_beam(labels, skip, rig, sensor, seed, frame, &mut out);
            out
        })
        .collect();
    let mut points = Vec::with_capacity(chunks.iter().map(Vec::len).sum());
    for c in chunks {
        points.extend_from_slice(&c);
        give_buffer(c);
    }
    PointCloud { points }
}

/// What `scan` derives from the rig alone, per sensor: the cosines and sines of its azimuths
/// (every beam sweeps the same ones) and its view of the blocks (`fan::SensorBlocks`, 2,500
/// blocks sorted by distance). The same every frame, so made once per rig: per frame they
/// were about 1 % of a full frame's CPU time at 0.2 deg (docs/benchmarks.md, "Full frames").
struct RigTables {
    trig: Vec<Vec<(f64, f64)>>,
    views: Vec<fan::SensorBlocks>,
}

/// The tables of the last few rigs scanned (a bench alternates two; a batch uses one).
static TABLES: std::sync::Mutex<Vec<(Rig, std::sync::Arc<RigTables>)>> = std::sync::Mutex::new(Vec::new());
const KEPT_TABLES: usize = 4;

impl RigTables {
    fn new(rig: &Rig) -> Self {
        let trig = rig.azimuth_trig();
        let views = rig
            .sensors
            .iter()
            .map(|s| fan::SensorBlocks::new(rig.sensor_origin(s), dda::NBX, dda::NBY, dda::BLOCK_M))
            .collect();
        RigTables { trig, views }
    }

    /// The tables of `rig`, made now if no earlier scan kept them. The same values either way.
    fn of(rig: &Rig) -> std::sync::Arc<RigTables> {
        let kept = TABLES.lock().ok().and_then(|t| t.iter().find(|(r, _)| r == rig).map(|(_, x)| x.clone()));
        kept.unwrap_or_else(|| {
            let made = std::sync::Arc::new(RigTables::new(rig));
            if let Ok(mut t) = TABLES.lock() {
                if t.len() >= KEPT_TABLES {
                    t.remove(0);
                }
                t.push((rig.clone(), made.clone()));
            }
            made
        })
    }
}

/// Per-beam point buffers kept between scans. Allocated and freed every frame, the 6 MB of
/// them went back to the kernel and came back as page faults: 3 ms of a 37 ms frame (system
/// time, docs/benchmarks.md "LiDAR"). Order and contents do not depend on which buffer a beam
/// gets.
static BUFFERS: std::sync::Mutex<Vec<Vec<Point>>> = std::sync::Mutex::new(Vec::new());

/// At most this many are kept: the beams of two scans at once of the nuPlan rig.
const KEPT_BUFFERS: usize = 320;

fn take_buffer() -> Vec<Point> {
    BUFFERS.lock().ok().and_then(|mut b| b.pop()).unwrap_or_default()
}

fn give_buffer(mut v: Vec<Point>) {
    v.clear();
    if let Ok(mut b) = BUFFERS.lock()
        && b.len() < KEPT_BUFFERS
    {
        b.push(v);
    }
}

/// The ego-frame direction of the ray at elevation (cos, sin) `e` and azimuth (cos, sin) `a` of
/// a sensor turned by `rot` (`Sensor::rotation`).
#[inline]
pub fn ray_dir(rot: &[[f64; 3]; 3], (ce, se): (f64, f64), (ca, sa): (f64, f64)) -> [f64; 3] {
    let l = [ce * ca, ce * sa, se];
    [
        rot[0][0] * l[0] + rot[0][1] * l[1] + rot[0][2] * l[2],
        rot[1][0] * l[0] + rot[1][1] * l[1] + rot[1][2] * l[2],
        rot[2][0] * l[0] + rot[2][1] * l[1] + rot[2][2] * l[2],
    ]
}

/// One beam of a sensor, with what is shared by the sensor's beams: its blocks seen from it and
/// the cosines and sines of its azimuths.
struct Beam<'a> {
    sensor: &'a Sensor,
    view: &'a fan::SensorBlocks,
    trig: &'a [(f64, f64)],
    beam: usize,
}

/// Append the beam's returns to `out`. On x86-64 CPUs with AVX2 the same code runs compiled
/// for them (`fire_beam_avx2`): the same IEEE operations in the same order (Rust never fuses a
/// multiply and an add), so the same points, with fewer instructions.
fn fire_beam(labels: &[u8], skip: &dda::Skip, rig: &Rig, b: Beam, seed: u64, frame: usize, out: &mut Vec<Point>) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above: the one requirement of the callee.
        return unsafe { fire_beam_avx2(labels, skip, rig, b, seed, frame, out) };
    }
    fire_beam_body(labels, skip, rig, b, seed, frame, out);
}

/// `fire_beam_body` compiled with AVX2 (`fire_beam`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn fire_beam_avx2(
    labels: &[u8],
    skip: &dda::Skip,
    rig: &Rig,
    b: Beam,
    seed: u64,
    frame: usize,
    out: &mut Vec<Point>,
) {
    fire_beam_body(labels, skip, rig, b, seed, frame, out);
}

#[inline(always)]
fn fire_beam_body(labels: &[u8], skip: &dda::Skip, rig: &Rig, b: Beam, seed: u64, frame: usize, out: &mut Vec<Point>) {
    let Beam { sensor, view, trig, beam } = b;
    let mut rng = beam_rng(seed, frame, sensor.id, beam);
    let rot = sensor.rotation();
    let o = rig.sensor_origin(sensor);
    let el = sensor.elevations_deg[beam].to_radians();
    let (ce, se) = (el.cos(), el.sin());
    // Per azimuth sector, how far the beam's rays pass above everything (`fan`).
    let tilt = rot[2][2].clamp(-1.0, 1.0).acos();
    let mut starts = [0.0; fan::SECTORS];
    view.starts(skip.tops(), o[2], fan::lowest_slope(el, tilt), &mut starts);
    out.reserve(trig.len());
    for &(ca, sa) in trig {
        let d = ray_dir(&rot, (ce, se), (ca, sa));
        // Three uniforms per ray, hit or not; the two normals (Box-Muller) only for returns.
        let (u_drop, u1, u2) = (rng.unit(), rng.unit(), rng.unit());
        let t_start = fan::sector(d[0], d[1]).map_or(0.0, |s| starts[s] / (d[0] * d[0] + d[1] * d[1]).sqrt());
        let Some(h) = skip.cast_from(labels, o, d, rig.max_range, t_start) else { continue };
        if h.t < rig.min_range || h.t > rig.max_range {
            continue;
        }
        let cos_i = if h.axis < 3 { d[h.axis].abs() } else { 1.0 };
        let p_drop =
            rig.drop.base + rig.drop.incidence * (1.0 - cos_i).powi(2) + rig.drop.range * (h.t / rig.max_range).powi(2);
        if u_drop < p_drop {
            continue;
        }
        // The noise draws and the attenuation in single precision: glibc's f32 logf, sincosf
        // and expf take half the time of the f64 ones, and their error is far below the noise
        // they shape (tests/lidar_stats.rs pins the cloud's statistics).
        let rad = (-2.0 * (u1 as f32).max(f32::MIN_POSITIVE).ln()).sqrt();
        let (sn, cs) = (std::f32::consts::TAU * u2 as f32).sin_cos();
        let (n1, n2) = (f64::from(rad * cs), f64::from(rad * sn));
        let sigma = rig.noise.sigma_m + rig.noise.sigma_per_m * h.t;
        let r = (h.t + (n1 * sigma).abs()).min(h.t_exit).min(rig.max_range);
        let refl = rig.reflectivity.get(h.label as usize).copied().unwrap_or(0.0);
        let i = 255.0
            * refl
            * ((1.0 - rig.intensity.lambert) + rig.intensity.lambert * cos_i)
            * f64::from(((-2.0 * rig.intensity.attenuation_per_m * r) as f32).exp())
            * (1.0 + rig.intensity.noise * n2);
        out.push(Point {
            x: (o[0] + r * d[0]) as f32,
            y: (o[1] + r * d[1]) as f32,
            z: (o[2] + r * d[2]) as f32,
            // Rounded half up by truncation (no libm call on baseline x86-64); i >= 0 here.
            intensity: (i.clamp(0.0, 255.0) + 0.5).min(255.0) as u8 as f32,
            ring: beam as u16,
            lidar: sensor.id,
        });
    }
}

/// `dir/lidar/NNNNNN.bin` for frame `frame` (SPEC output layout).
pub fn bin_frame_path(dir: &Path, frame: usize) -> PathBuf {
    dir.join("lidar").join(format!("{frame:06}.bin"))
}

/// `dir/lidar/NNNNNN.pcd` for frame `frame`.
pub fn pcd_frame_path(dir: &Path, frame: usize) -> PathBuf {
    dir.join("lidar").join(format!("{frame:06}.pcd"))
}

/// Points coded per `write_all`: 256 kB of `.pcd` records, small enough that the copy
/// into the file's buffer reads them from the cache the coder just wrote them to.
const CHUNK_POINTS: usize = 1 << 14;

/// Write `pc`'s points to `w` as fixed-size records, `CHUNK_POINTS` at a time, through a buffer
/// kept per thread: one pass over the points, no per-field `Vec` growth, no fresh pages per frame.
fn write_records<const N: usize>(
    w: &mut impl Write,
    pc: &PointCloud,
    record: impl Fn(&Point, &mut [u8; N]),
) -> io::Result<()> {
    thread_local! {
        static CHUNK: std::cell::RefCell<Vec<u8>> = const { std::cell::RefCell::new(Vec::new()) };
    }
    CHUNK.with_borrow_mut(|buf| {
        for points in pc.points.chunks(CHUNK_POINTS) {
            buf.clear();
            buf.resize(points.len() * N, 0);
            for (dst, p) in buf.chunks_exact_mut(N).zip(points) {
                if let Ok(rec) = <&mut [u8; N]>::try_from(dst) {
                    record(p, rec);
                }
            }
            w.write_all(buf)?;
        }
        Ok(())
    })
}

/// x, y, z and intensity as float32 little endian: the first 16 bytes of both formats' records.
#[inline]
fn xyzi(p: &Point, rec: &mut [u8]) {
    rec[0..4].copy_from_slice(&p.x.to_le_bytes());
    rec[4..8].copy_from_slice(&p.y.to_le_bytes());
    rec[8..12].copy_from_slice(&p.z.to_le_bytes());
    rec[12..16].copy_from_slice(&p.intensity.to_le_bytes());
}

/// KITTI-style `.bin`: float32 little-endian x, y, z, intensity per point, atomically.
pub fn write_bin(to: To, path: &Path, pc: &PointCloud) -> io::Result<u64> {
    to.write_atomic(path, |w| write_records::<16>(w, pc, |p, rec| xyzi(p, rec)))
}

/// Binary PCD v0.7 with fields x y z intensity (float32), ring (uint16) and lidar (uint8),
/// little endian, atomically. Open3D's tensor reader and numpy (see tests/python) load it.
pub fn write_pcd(to: To, path: &Path, pc: &PointCloud) -> io::Result<u64> {
    to.write_atomic(path, |w| {
        let n = pc.points.len();
        write!(
            w,
            "# .PCD v0.7 - Point Cloud Data file format (rocc, ego frame)\nVERSION 0.7\n\
             FIELDS x y z intensity ring lidar\nSIZE 4 4 4 4 2 1\nTYPE F F F F U U\nCOUNT 1 1 1 1 1 1\n\
             WIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary\n"
        )?;
        write_records::<19>(w, pc, |p, rec| {
            xyzi(p, rec);
            rec[16..18].copy_from_slice(&p.ring.to_le_bytes());
            rec[18] = p.lidar;
        })
    })
}
