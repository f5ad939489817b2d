//! Occupancy flow (`rocc compile --flow`). In: one frame's `Occupancy`, its ego-frame boxes and
//! each box's velocity over the ground in that frame's ego axes. Out: float32 (400, 400, 32, 3),
//! per voxel (vx, vy, vz) in m/s, which `output::write_flow` writes as `flow/NNNNNN.npz`.
//!
//! A voxel carries the velocity of the agent whose box holds its centre when its label is that
//! agent's class label; every other voxel (free space, background, structures, parked or
//! standing agents) is zero. vz is always 0: the rollout moves agents on the ground plane. The
//! velocity is the agent's own motion over the ground, not its motion relative to the ego: the
//! convention of occupancy-flow labels (UniOcc, Cam4DOcc), where static voxels have zero flow.

use super::Occupancy;
use super::layout::{BACKGROUND, NX, NY, NZ, ORIGIN, VOXEL, centre, class_label, flat};
use crate::view::EgoBox;

/// Components per voxel.
pub const C: usize = 3;

/// A flow grid: standard-layout (400, 400, 32, 3) float32, and the voxels set since the last
/// clear, so reusing it costs the moving voxels, not the whole 61 MB.
#[derive(Clone, Debug, Default)]
pub struct Flow {
    v: Vec<f32>,
    touched: Vec<usize>,
}

impl Flow {
    /// (vx, vy, vz) of voxel (i, j, k).
    pub fn at(&self, i: usize, j: usize, k: usize) -> [f32; 3] {
        let n = C * flat(i, j, k);
        self.v.get(n..n + C).map_or([0.0; 3], |s| [s[0], s[1], s[2]])
    }

    /// Every voxel's components in standard layout; empty before the first `flow_into`.
    pub fn values(&self) -> &[f32] {
        &self.v
    }

    fn clear(&mut self) {
        if self.v.len() != NX * NY * NZ * C {
            self.v = vec![0.0; NX * NY * NZ * C];
        }
        for &n in &self.touched {
            self.v[C * n..C * n + C].fill(0.0);
        }
        self.touched.clear();
    }
}

/// Fill `out` with the flow of `occ`: `velocity[b]` (m/s, ego axes) for the voxels of `boxes[b]`.
pub fn flow_into(occ: &Occupancy, boxes: &[EgoBox], velocity: &[[f64; 2]], out: &mut Flow) {
    out.clear();
    // Voxels are chosen by centre inside the box's solid (`voxel`); the margin keeps a voxel
    // whose centre sits on the box's face.
    let m = 0.5 * VOXEL;
    for (b, v) in boxes.iter().zip(velocity) {
        let label = class_label(b.class);
        if label == BACKGROUND || *v == [0.0, 0.0] {
            continue;
        }
        let (c, s) = (b.yaw.cos(), b.yaw.sin());
        let r = 0.5 * b.l.hypot(b.w) + m;
        let range = |a: usize, lo: f64, hi: f64, n: usize| {
            let f = |x: f64| ((x - ORIGIN[a]) / VOXEL).floor().clamp(0.0, n as f64) as usize;
            f(lo)..f(hi + VOXEL).min(n)
        };
        let (z0, z1) = (b.z - 0.5 * b.h - m, b.z + 0.5 * b.h + m);
        for i in range(0, b.x - r, b.x + r, NX) {
            for j in range(1, b.y - r, b.y + r, NY) {
                let (dx, dy) = (centre(0, i) - b.x, centre(1, j) - b.y);
                let (u, w) = (dx * c + dy * s, -dx * s + dy * c);
                if u.abs() > 0.5 * b.l + m || w.abs() > 0.5 * b.w + m {
                    continue;
                }
                for k in range(2, z0, z1, NZ) {
                    let z = centre(2, k);
                    if z < z0 || z > z1 || occ.labels[[i, j, k]] != label {
                        continue;
                    }
                    let n = flat(i, j, k);
                    out.v[C * n..C * n + C].copy_from_slice(&[v[0] as f32, v[1] as f32, 0.0]);
                    out.touched.push(n);
                }
            }
        }
    }
}

/// A world-axes vector in the axes of an ego heading `yaw`.
pub fn to_ego_axes(v: [f64; 2], yaw: f64) -> [f64; 2] {
    let (c, s) = (yaw.cos(), yaw.sin());
    [v[0] * c + v[1] * s, -v[0] * s + v[1] * c]
}
