//! The statistics of a LiDAR cloud, pinned: a faster caster may change the bytes (the order of
//! floating-point steps), never what the cloud says about the scene. On two frames of the
//! ambulance example at the sensor's native 0.2 deg: the point count, the range histogram and
//! the share of returns per occupancy label, each within a tolerance well below what a wrong
//! caster (a missed block, a shifted origin, a lost sensor) would move.

use rocc::backend::layout::{FREE, N_LABELS, NX, NY, NZ, ORIGIN, VOXEL};
use rocc::backend::{Background, OccInput, Occupancy, OccupancyBackend, Procedural};
use rocc::compile::{frame_boxes, front};
use rocc::lidar::{PointCloud, Rig, scan};
use rocc::raster::rasterize;
use std::path::PathBuf;

/// Range bins of 10 m, 0..100 m.
const BINS: usize = 10;

struct Stats {
    points: usize,
    /// Share of points per range bin.
    range: [f64; BINS],
    /// Share of points per occupancy label (the non-free voxel each lies in or on).
    label: [f64; N_LABELS],
}

fn stats(pc: &PointCloud, occ: &Occupancy) -> Stats {
    let mut range = [0usize; BINS];
    let mut label = [0usize; N_LABELS];
    for p in &pc.points {
        // Range from the ego origin's vertical, a stable figure whichever sensor fired.
        let r = (p.x as f64).hypot(p.y as f64);
        range[((r / 10.0) as usize).min(BINS - 1)] += 1;
        label[voxel_label(occ, [p.x as f64, p.y as f64, p.z as f64]) as usize] += 1;
    }
    let n = pc.points.len().max(1) as f64;
    Stats { points: pc.points.len(), range: range.map(|c| c as f64 / n), label: label.map(|c| c as f64 / n) }
}

/// The label of the non-free voxel a point lies in or on (points sit on a face of their voxel).
fn voxel_label(occ: &Occupancy, p: [f64; 3]) -> u8 {
    let eps = 1e-4;
    let n = [NX, NY, NZ];
    let idx = |a: usize, v: f64| (((v - ORIGIN[a]) / VOXEL).floor().max(0.0) as usize).min(n[a] - 1);
    for dx in [0.0, -eps, eps] {
        for dy in [0.0, -eps, eps] {
            for dz in [0.0, -eps, eps] {
                let l = occ.labels[[idx(0, p[0] + dx), idx(1, p[1] + dy), idx(2, p[2] + dz)]];
                if l != FREE {
                    return l;
                }
            }
        }
    }
    FREE
}

fn frame(f: usize) -> (Occupancy, PointCloud) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios/ambulance_crowded_intersection.scn");
    let mut sources = rocc::source::SourceMap::default();
    let scenario = rocc::check::check_path(&path, &mut sources).expect("checks");
    let fr = front(scenario, None).expect("front");
    let ego = fr.concrete.egos[0];
    let pose = fr.tracks.poses[ego][f];
    let boxes = frame_boxes(&fr, ego, f);
    let bev = rasterize(&fr.map, pose, &boxes);
    let bg = Background::generate(&fr.map, fr.concrete.seed);
    let occ = Procedural::default().occupancy(&OccInput {
        boxes: &boxes,
        bev: &bev,
        background: &bg,
        ego: pose,
        seed: 1,
        frame: f,
    });
    let mut rig = Rig::nuplan();
    rig.horizontal_resolution_deg = 0.2;
    let pc = scan(&occ, &rig, 7, f);
    (occ, pc)
}

/// (frame, points, range shares, label shares) as the caster gave them when this test was written.
#[allow(clippy::type_complexity)]
const PINNED: [(usize, usize, [f64; BINS], [f64; N_LABELS]); 3] = [
    (
        0,
        154763,
        [0.31419, 0.410848, 0.179184, 0.068886, 0.018234, 0.008064, 0.000594, 0.0, 0.0, 0.0],
        [0.0, 0.921331, 0.078669, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    ),
    (
        30,
        147814,
        [0.312115, 0.329671, 0.209987, 0.067943, 0.044786, 0.026608, 0.00889, 0.0, 0.0, 0.0],
        [0.0, 0.917464, 0.082448, 0.0, 0.000088, 0.0, 0.0, 0.0, 0.0],
    ),
    (
        60,
        149105,
        [0.404037, 0.248348, 0.20061, 0.079011, 0.038356, 0.021468, 0.008169, 0.0, 0.0, 0.0],
        [0.0, 0.774857, 0.22466, 0.0, 0.000483, 0.0, 0.0, 0.0, 0.0],
    ),
];

/// How far a share may move: half a percentage point, and a tenth of itself for small shares
/// (the pedestrians' few dozen points must not vanish unnoticed).
fn tolerance(share: f64) -> f64 {
    (0.1 * share + 1e-5).min(0.005)
}

#[test]
fn cloud_statistics_match_the_pinned_figures() {
    let got: Vec<Stats> = PINNED
        .iter()
        .map(|&(f, ..)| {
            let (occ, pc) = frame(f);
            stats(&pc, &occ)
        })
        .collect();
    for ((f, ..), s) in PINNED.iter().zip(&got) {
        // What to paste into PINNED when a change of the model (not of the caster) moves them.
        let r4 = |x: f64| (x * 1e6).round() / 1e6;
        eprintln!("({f}, {}, {:?}, {:?}),", s.points, s.range.map(r4), s.label.map(r4));
    }
    for ((f, points, range, label), s) in PINNED.into_iter().zip(&got) {
        // Half a percent of the points.
        assert!(
            (s.points as f64 - points as f64).abs() <= 0.005 * points as f64,
            "frame {f}: {} points, pinned {points}",
            s.points
        );
        for (b, (&got, &want)) in s.range.iter().zip(&range).enumerate() {
            assert!(
                (got - want).abs() <= tolerance(want),
                "frame {f}: range bin {b} holds {got:.4} of the points, pinned {want:.4}"
            );
        }
        for (l, (&got, &want)) in s.label.iter().zip(&label).enumerate() {
            assert!(
                (got - want).abs() <= tolerance(want),
                "frame {f}: label {l} holds {got:.4} of the points, pinned {want:.4}"
            );
        }
        assert_eq!(s.label[FREE as usize], 0.0, "frame {f}: a point in free space");
    }
}
