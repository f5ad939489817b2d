//! Where a beam's rays can start walking. In: a sensor's position, one beam's lowest slope and
//! the block heights of `dda::Skip`. Out: per azimuth sector (of the sensor's horizontal
//! position), the horizontal distance before which no ray of the beam in that sector can meet
//! anything, so `Skip::cast_from` starts its block walk there instead of at the sensor.
//!
//! A block is relevant to a beam when some ray of the beam could pass below its top over it:
//! rays of slope (dz / horizontal length) at least `s_min` from height `z0` are, at horizontal
//! distance r, at least as high as z0 + s_min r. Every other block the walk would skip anyway
//! (`Skip::cast` walks a block only when the ray's lowest point over it is below its top), so
//! starting past them changes no hit. The ground counts: a block's top is that of its ground
//! layer at least, so a descending beam's sectors end where it reaches the road.
//!
//! Measured on the ambulance example at 0.2 deg (docs/benchmarks.md, "LiDAR"): upper beams find
//! most sectors empty and cast nothing; lower ones skip the blocks between the car and the road.

use crate::backend::layout::ORIGIN;

/// Azimuth sectors of a full turn, in pseudo-angle (see `pseudo_angle`).
pub const SECTORS: usize = 1024;

/// Safety margins against rounding, far below a voxel: a block counts as relevant when its top
/// is within `Z_EPS` of the beam's lowest point over it; start distances are shortened by
/// `R_EPS`.
const Z_EPS: f64 = 1e-6;
const R_EPS: f64 = 1e-6;

/// A monotone stand-in for the angle of (x, y) counter-clockwise from +x, in [0, 4): one
/// division instead of atan2's polynomial. None for (0, 0).
#[inline]
pub fn pseudo_angle(x: f64, y: f64) -> Option<f64> {
    let n = x.abs() + y.abs();
    if n == 0.0 || n.is_nan() {
        return None;
    }
    let p = y / n;
    Some(if x < 0.0 {
        2.0 - p
    } else if y < 0.0 {
        4.0 + p
    } else {
        p
    })
}

/// The sector of a horizontal direction (x, y); None for a vertical ray.
#[inline]
pub fn sector(x: f64, y: f64) -> Option<usize> {
    pseudo_angle(x, y).map(|a| ((a * (SECTORS as f64 / 4.0)) as usize).min(SECTORS - 1))
}

/// The blocks of `Skip` as seen from one sensor: nearest first.
pub struct SensorBlocks {
    /// (block, nearest and farthest horizontal distance, first sector, sector count), by
    /// nearest distance.
    blocks: Vec<BlockView>,
}

#[derive(Clone, Copy)]
struct BlockView {
    block: u32,
    near: f64,
    far: f64,
    first: u16,
    count: u16,
}

impl SensorBlocks {
    /// `blocks`: (nbx, nby) squares of side `side` metres from the grid's corner.
    pub fn new(origin: [f64; 3], nbx: usize, nby: usize, side: f64) -> SensorBlocks {
        let (ox, oy) = (origin[0], origin[1]);
        let mut blocks = Vec::with_capacity(nbx * nby);
        for bi in 0..nbx {
            for bj in 0..nby {
                let (x0, y0) = (ORIGIN[0] + side * bi as f64 - ox, ORIGIN[1] + side * bj as f64 - oy);
                let (x1, y1) = (x0 + side, y0 + side);
                let dx = (x0.max(0.0)).max(-x1);
                let dy = (y0.max(0.0)).max(-y1);
                // sqrt, not hypot: no overflow at these sizes, and no libm call.
                let near = ((dx * dx + dy * dy).sqrt() - R_EPS).max(0.0);
                let corners = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)];
                let far = corners.iter().map(|&(x, y)| (x * x + y * y).sqrt()).fold(0.0, f64::max) + R_EPS;
                let (first, count) = if near < 0.01 {
                    // The sensor is in the block or next to it: every direction may cross it.
                    (0, SECTORS as u16)
                } else {
                    span(&corners)
                };
                blocks.push(BlockView { block: (bi * nby + bj) as u32, near, far, first, count });
            }
        }
        blocks.sort_by(|a, b| a.near.total_cmp(&b.near));
        SensorBlocks { blocks }
    }

    /// For a beam from height `z0` whose rays have slopes of at least `s_min`, per sector the
    /// horizontal distance where its rays may meet the first block whose top (`top`, per
    /// block) they can pass below; infinity where they meet none.
    pub fn starts(&self, top: &[f64], z0: f64, s_min: f64, out: &mut [f64; SECTORS]) {
        out.fill(f64::INFINITY);
        let mut filled = 0;
        for b in &self.blocks {
            if filled == SECTORS {
                break;
            }
            let lowest = z0 + s_min * if s_min < 0.0 { b.far } else { b.near };
            if top[b.block as usize] <= lowest - Z_EPS {
                continue;
            }
            for k in 0..b.count as usize {
                let s = &mut out[(b.first as usize + k) % SECTORS];
                if *s == f64::INFINITY {
                    *s = b.near;
                    filled += 1;
                }
            }
        }
    }
}

/// First sector and count of the sectors a square (corners relative to the sensor, the sensor
/// outside it) covers, one more on each side against rounding.
fn span(corners: &[(f64, f64); 4]) -> (u16, u16) {
    let a: Vec<f64> = corners.iter().filter_map(|&(x, y)| pseudo_angle(x, y)).collect();
    let (lo, hi) = a.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
    // A square the sensor is outside of spans less than half a turn (2 in pseudo-angle); a
    // wider spread means it straddles the +x direction, where the pseudo-angle wraps.
    let (from, to) = if hi - lo > 2.0 {
        let hi_below = a.iter().copied().filter(|&v| v < 2.0).fold(f64::NEG_INFINITY, f64::max);
        let lo_above = a.iter().copied().filter(|&v| v >= 2.0).fold(f64::INFINITY, f64::min);
        (lo_above, hi_below + 4.0)
    } else {
        (lo, hi)
    };
    let k = SECTORS as f64 / 4.0;
    let first = (from * k) as i64 - 1;
    let last = (to * k) as i64 + 1;
    let count = ((last - first + 1) as usize).min(SECTORS);
    (first.rem_euclid(SECTORS as i64) as u16, count as u16)
}

/// The lowest slope (dz over horizontal length) of a beam at elevation `el` (rad) of a sensor
/// whose z axis is tilted by `tilt` (rad) from the vertical: every ray of it is at least as
/// steep upwards (or at most as steep downwards).
pub fn lowest_slope(el: f64, tilt: f64) -> f64 {
    let e = el - tilt;
    if e <= -std::f64::consts::FRAC_PI_2 + 1e-9 { f64::NEG_INFINITY } else { e.tan() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::layout::{K_GROUND, NX, NY, NZ, flat};
    use crate::lidar::dda::{BLOCK_M, NBX, NBY, Skip, cast};
    use crate::lidar::{Sensor, ray_dir};

    /// Ground everywhere, boxes of every height up to the grid's top, a few floating voxels.
    fn scene() -> Vec<u8> {
        let mut g = vec![0u8; NX * NY * NZ];
        for c in g.chunks_exact_mut(NZ) {
            c[K_GROUND] = 1;
        }
        let mut rng = crate::sample::Rng::new(17);
        for n in 0..500 {
            let (i, j) = (rng.index(NX - 12), rng.index(NY - 12));
            let (w, l) = (1 + rng.index(12), 1 + rng.index(12));
            let (k0, k1) = if n % 10 == 0 {
                (K_GROUND + 8 + rng.index(8), NZ)
            } else {
                (K_GROUND + 1, K_GROUND + 2 + rng.index(NZ - K_GROUND - 2))
            };
            for di in 0..w {
                for dj in 0..l {
                    for k in k0..k1 {
                        g[flat(i + di, j + dj, k)] = 2 + rng.index(7) as u8;
                    }
                }
            }
        }
        g
    }

    #[test]
    fn starting_where_the_fan_says_finds_the_same_hits() {
        let g = scene();
        let skip = Skip::new(&g);
        let mut hits = 0;
        // Sensors of the nuPlan rig's heights, one of them turned (roll, pitch, yaw).
        for (origin, rotation_deg) in [
            ([0.0673, -0.0081, 1.9847], (0.0, 0.0, 0.0)),
            ([2.561, 0.31, 0.378], (0.0, 0.0, 0.0)),
            ([-2.503, -0.7, 0.974], (4.0, -9.0, 30.0)),
        ] {
            let sensor = Sensor {
                id: 0,
                name: "test".into(),
                origin: (origin[0], origin[1], origin[2]),
                rotation_deg,
                elevations_deg: vec![],
                azimuth_deg: (0.0, 0.0),
                horizontal_resolution_deg: None,
            };
            let rot = sensor.rotation();
            let tilt = rot[2][2].clamp(-1.0, 1.0).acos();
            let view = SensorBlocks::new(origin, NBX, NBY, BLOCK_M);
            for el_deg in [15.0, 3.0, 0.5, 0.0, -0.5, -2.0, -5.0, -12.0, -25.0, -89.0] {
                let el: f64 = f64::to_radians(el_deg);
                let mut starts = [0.0; SECTORS];
                view.starts(skip.tops(), origin[2], lowest_slope(el, tilt), &mut starts);
                for n in 0..3600 {
                    let az = (n as f64 * 0.1).to_radians();
                    let d = ray_dir(&rot, (el.cos(), el.sin()), (az.cos(), az.sin()));
                    let t0 = sector(d[0], d[1]).map_or(0.0, |s| starts[s] / (d[0] * d[0] + d[1] * d[1]).sqrt());
                    let a = cast(&g, origin, d, 100.0);
                    let b = skip.cast_from(&g, origin, d, 100.0, t0);
                    match (a, b) {
                        (Some(x), Some(y)) => {
                            assert_eq!((x.voxel, x.label, x.axis), (y.voxel, y.label, y.axis), "el {el_deg} az {n}");
                            assert!((x.t - y.t).abs() < 1e-9 && (x.t_exit - y.t_exit).abs() < 1e-9, "{x:?} {y:?}");
                            hits += 1;
                        }
                        (None, None) => {}
                        other => panic!("el {el_deg} az {n} from {origin:?}: {other:?}"),
                    }
                }
            }
        }
        assert!(hits > 50_000, "{hits}");
    }

    #[test]
    fn pseudo_angle_is_monotone_in_the_angle() {
        let mut last = -1.0;
        for n in 0..3600 {
            let a = (n as f64 + 0.5).to_radians() / 10.0;
            let p = pseudo_angle(a.cos(), a.sin()).expect("not zero");
            assert!(p > last && (0.0..4.0).contains(&p), "{n}: {p} after {last}");
            last = p;
        }
        assert_eq!(pseudo_angle(0.0, 0.0), None);
    }

    #[test]
    fn a_block_spans_the_sectors_of_its_points() {
        // Every point of every block lies in one of the block's sectors, seen from an off-centre sensor.
        let o = [0.37, -0.21, 1.9];
        let v = SensorBlocks::new(o, 50, 50, 2.0);
        let mut rng = crate::sample::Rng::new(4);
        for b in &v.blocks {
            let (bi, bj) = (b.block as usize / 50, b.block as usize % 50);
            for _ in 0..20 {
                let x = ORIGIN[0] + 2.0 * (bi as f64 + rng.unit()) - o[0];
                let y = ORIGIN[1] + 2.0 * (bj as f64 + rng.unit()) - o[1];
                let s = sector(x, y).expect("off the sensor");
                let inside = (s + SECTORS - b.first as usize) % SECTORS < b.count as usize;
                assert!(inside, "block {bi},{bj}: sector {s} not in {} + {}", b.first, b.count);
                let r = x.hypot(y);
                assert!(b.near <= r && r <= b.far);
            }
        }
    }
}
