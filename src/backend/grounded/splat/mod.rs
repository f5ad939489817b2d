//! Semantic-Gaussian splatting (SPEC.md, GaussianFormer's formula). In: activated Gaussians
//! (means in continuous voxel coordinates, per-axis scales, rotations, opacities, class features)
//! and a `Region` of columns. Out: per-voxel class logits of the region, `[B * voxels, 9]`,
//! channel 0 free.
//!
//! logits(p) = sum_i a_i exp(-1/2 d^T Sigma_i^-1 d) c_i, d = m_i - p, Sigma = R diag(s^2) R^T,
//! evaluated only on the (2 r + 1)^3 voxels around the voxel holding m_i (the window, `r` =
//! `GaussianConfig::window`; scales are capped at r / 3 so the 3-sigma ellipsoid fits it). The
//! cost is N x window, never Gaussians x voxels. `splat` packs the Gaussians into one table
//! (`layout`) and runs one backend operation (`op`) with its own backward pass: host code on the
//! CPU (`host`), a kernel on wgpu and CUDA (`cube`). `splat_tensor_ops` is the same sum written
//! with ordinary tensor operations and autodiff: the reference both are tested against.

pub mod check;
#[cfg(any(feature = "wgpu", feature = "cuda"))]
pub mod cube;
pub mod host;
pub mod layout;
pub mod op;

use crate::backend::layout::{N_LABELS, NX, NY, NZ};
use burn::prelude::*;
use burn::tensor::IndexingUpdateOp;

/// Raw decoder outputs per Gaussian: offset 3, scale 3, quaternion 4, opacity 1, features 9.
pub const PARAMS: usize = 3 + 3 + 4 + 1 + N_LABELS;

/// A rectangle of columns (every layer of each): the whole grid, or a training crop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Region {
    pub i0: usize,
    pub j0: usize,
    pub ni: usize,
    pub nj: usize,
}

impl Region {
    pub fn full() -> Self {
        Region { i0: 0, j0: 0, ni: NX, nj: NY }
    }

    pub fn voxels(&self) -> usize {
        self.ni * self.nj * NZ
    }

    /// Flat index of grid voxel (i, j, k) inside the region, `None` outside it.
    #[inline]
    pub fn flat(&self, i: i64, j: i64, k: i64) -> Option<usize> {
        let (li, lj) = (i - self.i0 as i64, j - self.j0 as i64);
        if li < 0 || lj < 0 || k < 0 || li >= self.ni as i64 || lj >= self.nj as i64 || k >= NZ as i64 {
            return None;
        }
        Some((li as usize * self.nj + lj as usize) * NZ + k as usize)
    }
}

/// Activated Gaussians, one row each.
#[derive(Clone, Debug)]
pub struct Gaussians {
    /// [N, 3], continuous voxel coordinates (voxel i spans [i, i + 1)).
    pub mean: Tensor<2>,
    /// [N, 3], standard deviations along the local axes (voxels).
    pub scale: Tensor<2>,
    /// [N, 9], R row-major: column j is local axis j in grid coordinates.
    pub rot: Tensor<2>,
    /// [N, 1] in (0, 1).
    pub opacity: Tensor<2>,
    /// [N, 9] class features, channel 0 free.
    pub feat: Tensor<2>,
    /// Batch element of each row.
    pub batch: Vec<usize>,
}

/// Host-side anchor of each active Gaussian: its latent's voxel position and heading.
#[derive(Clone, Debug, Default)]
pub struct ActiveAnchors {
    pub pos: Vec<[f32; 3]>,
    pub cos: Vec<f32>,
    pub sin: Vec<f32>,
    pub batch: Vec<usize>,
}

fn col(t: &Tensor<2>, c: usize) -> Tensor<2> {
    let n = t.dims()[0];
    t.clone().slice([0..n, c..c + 1])
}

fn column(v: Vec<f32>, device: &Device) -> Tensor<2> {
    let n = v.len();
    Tensor::from_data(TensorData::new(v, [n, 1]), device)
}

/// Raw parameters [N, PARAMS] -> Gaussians: offsets tanh-bounded to `offset_bound` voxels in the
/// anchor's frame (rotated by its heading), scales in [min_scale, max_scale], a normalised
/// quaternion composed with the anchor's heading, sigmoid opacity, features as they are.
pub fn activate(
    raw: Tensor<2>,
    anchors: &ActiveAnchors,
    offset_bound: f32,
    min_scale: f32,
    max_scale: f32,
) -> Gaussians {
    let device = raw.device();
    let n = raw.dims()[0];
    let sl = |a: usize, b: usize| raw.clone().slice([0..n, a..b]);
    let off = sl(0, 3).tanh() * offset_bound;
    let (c, s) = (column(anchors.cos.clone(), &device), column(anchors.sin.clone(), &device));
    let p = |a: usize| column(anchors.pos.iter().map(|p| p[a]).collect(), &device);
    let (ox, oy, oz) = (col(&off, 0), col(&off, 1), col(&off, 2));
    let mx = p(0) + c.clone() * ox.clone() - s.clone() * oy.clone();
    let my = p(1) + s.clone() * ox + c.clone() * oy;
    let mz = p(2) + oz;
    let mean = Tensor::cat(vec![mx, my, mz], 1);
    let scale = burn::tensor::activation::sigmoid(sl(3, 6)) * (max_scale - min_scale) + min_scale;
    let q = sl(6, 10) + Tensor::<2>::from_data(TensorData::new(vec![1.0f32, 0.0, 0.0, 0.0], [1, 4]), &device);
    let norm = (q.clone().powi_scalar(2).sum_dim(1) + 1e-8).sqrt();
    let q = q / norm;
    let (w, x, y, z) = (col(&q, 0), col(&q, 1), col(&q, 2), col(&q, 3));
    let two = |t: Tensor<2>| t * 2.0;
    let rq = [
        [
            -two(y.clone() * y.clone() + z.clone() * z.clone()) + 1.0,
            two(x.clone() * y.clone() - w.clone() * z.clone()),
            two(x.clone() * z.clone() + w.clone() * y.clone()),
        ],
        [
            two(x.clone() * y.clone() + w.clone() * z.clone()),
            -two(x.clone() * x.clone() + z.clone() * z.clone()) + 1.0,
            two(y.clone() * z.clone() - w.clone() * x.clone()),
        ],
        [
            two(x.clone() * z.clone() - w.clone() * y.clone()),
            two(y.clone() * z.clone() + w.clone() * x.clone()),
            -two(x.clone() * x + y.clone() * y) + 1.0,
        ],
    ];
    // R = Rz(anchor heading) * R(q): rows 0 and 1 rotate about z, row 2 is R(q)'s.
    let [r0, r1, r2] = rq;
    let mut rot: Vec<Tensor<2>> = Vec::with_capacity(9);
    rot.extend(r0.iter().zip(&r1).map(|(a, b)| c.clone() * a.clone() - s.clone() * b.clone()));
    rot.extend(r0.iter().zip(&r1).map(|(a, b)| s.clone() * a.clone() + c.clone() * b.clone()));
    rot.extend(r2);
    let rot = Tensor::cat(rot, 1);
    let opacity = burn::tensor::activation::sigmoid(sl(10, 11));
    let feat = sl(11, PARAMS);
    Gaussians { mean, scale, rot, opacity, feat, batch: anchors.batch.clone() }
}

/// Splat into `region` of each of `batch` grids: logits `[batch * region.voxels(), 9]`.
pub fn splat(g: &Gaussians, region: Region, batch: usize, window: usize) -> Tensor<2> {
    let device = g.mean.device();
    let n = g.mean.dims()[0];
    let shape = layout::SplatShape { region, batch, window };
    if n == 0 {
        return Tensor::<2>::zeros([batch * region.voxels(), N_LABELS], &device);
    }
    let b = column(g.batch.iter().map(|&b| b as f32).collect(), &device);
    let packed =
        Tensor::cat(vec![g.mean.clone(), g.scale.clone(), g.rot.clone(), g.opacity.clone(), g.feat.clone(), b], 1);
    op::splat_packed(packed, shape)
}

/// `splat` written with tensor operations and autodiff: window indices computed on the host, a
/// dense [N, window, 9] contribution, one index-add. Slow and memory-hungry; the reference the
/// splat operation's values and gradients are tested against.
pub fn splat_tensor_ops(g: &Gaussians, region: Region, batch: usize, window: usize) -> Tensor<2> {
    let device = g.mean.device();
    let n = g.mean.dims()[0];
    let out = Tensor::<2>::zeros([batch * region.voxels(), N_LABELS], &device);
    if n == 0 {
        return out;
    }
    let r = window as i64;
    let side = 2 * r + 1;
    let wn = (side * side * side) as usize;
    let means: Vec<f32> = g.mean.to_data().iter::<f32>().collect();
    let mut idx = Vec::with_capacity(n * wn);
    let mut valid = Vec::with_capacity(n * wn);
    let mut centre = [Vec::with_capacity(n * wn), Vec::with_capacity(n * wn), Vec::with_capacity(n * wn)];
    for row in 0..n {
        let m = [means[3 * row], means[3 * row + 1], means[3 * row + 2]];
        let c = m.map(|v| if v.is_finite() { v.floor() as i64 } else { i64::MIN / 4 });
        let base = g.batch[row] * region.voxels();
        for di in -r..=r {
            for dj in -r..=r {
                for dk in -r..=r {
                    let (vi, vj, vk) = (c[0] + di, c[1] + dj, c[2] + dk);
                    match region.flat(vi, vj, vk) {
                        Some(f) => {
                            idx.push((base + f) as i64);
                            valid.push(1.0f32);
                        }
                        None => {
                            idx.push(0);
                            valid.push(0.0);
                        }
                    }
                    centre[0].push(vi as f32 + 0.5);
                    centre[1].push(vj as f32 + 0.5);
                    centre[2].push(vk as f32 + 0.5);
                }
            }
        }
    }
    let grid = |v: Vec<f32>| Tensor::<2>::from_data(TensorData::new(v, [n, wn]), &device);
    let [cx, cy, cz] = centre;
    // d = p - m; the quadratic form is symmetric in the sign.
    let d = [grid(cx) - col(&g.mean, 0), grid(cy) - col(&g.mean, 1), grid(cz) - col(&g.mean, 2)];
    let mut maha = Tensor::<2>::zeros([n, wn], &device);
    for j in 0..3 {
        let u = d[0].clone() * col(&g.rot, j) + d[1].clone() * col(&g.rot, 3 + j) + d[2].clone() * col(&g.rot, 6 + j);
        maha = maha + (u / col(&g.scale, j)).powi_scalar(2);
    }
    let w = (maha * -0.5).exp() * g.opacity.clone() * grid(valid);
    let contrib = w.reshape([n, wn, 1]) * g.feat.clone().reshape([n, 1, N_LABELS]);
    let contrib = contrib.reshape([n * wn, N_LABELS]);
    let idx = Tensor::<1, Int>::from_data(TensorData::new(idx, [n * wn]), &device);
    out.select_assign(0, idx, contrib, IndexingUpdateOp::Add)
}
