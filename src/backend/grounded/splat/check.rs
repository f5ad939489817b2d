//! The splat operation checked on random small cases: values and the gradients of every Gaussian
//! parameter against a reference (the same sum written with ordinary tensor operations and
//! autodiff, `splat_tensor_ops`, or the operation on another device). `tests/splat.rs` runs it on
//! the CPU and, with `--features wgpu`, the device kernel against the CPU; `bench splat --device`
//! runs the latter on whatever GPU the user has.

use super::{Gaussians, Region, splat, splat_tensor_ops};
use crate::backend::layout::{N_LABELS, NZ};
use crate::sample::Rng;
use burn::prelude::*;

/// The Gaussian parameters in the order `Case::errors` reports them.
pub const NAMES: [&str; 5] = ["mean", "scale", "rotation", "opacity", "features"];

/// The largest relative difference accepted for the logits (`errors[0]`) and for each
/// parameter's gradient (the rest): float sums in another order, nothing more.
pub const VALUE_TOLERANCE: f32 = 1e-5;
pub const GRADIENT_TOLERANCE: f32 = 1e-4;

/// Whether `Case::errors`' differences are all within the tolerances.
pub fn within_tolerance(e: &[f32; 6]) -> bool {
    e[0] < VALUE_TOLERANCE && e[1..].iter().all(|v| *v < GRADIENT_TOLERANCE)
}

/// Host values of one random case: N Gaussians around a small region (some straddling its
/// edges, some in the other batch element), unit quaternions turned into rotations, and the
/// weights of the scalar whose gradient is taken.
#[derive(Clone, Debug)]
pub struct Case {
    pub n: usize,
    pub mean: Vec<f32>,
    pub scale: Vec<f32>,
    pub rot: Vec<f32>,
    pub opacity: Vec<f32>,
    pub feat: Vec<f32>,
    pub batch: Vec<usize>,
    pub weights: Vec<f32>,
    pub region: Region,
    pub window: usize,
}

impl Case {
    pub fn random(seed: u64, n: usize, window: usize) -> Case {
        let mut r = Rng::new(seed);
        let mut u = |a: f32, b: f32| r.range(a as f64, b as f64) as f32;
        let region = Region { i0: 20, j0: 30, ni: 9, nj: 7 };
        let smax = window as f32 / 3.0;
        let mut c = Case {
            n,
            mean: vec![],
            scale: vec![],
            rot: vec![],
            opacity: vec![],
            feat: vec![],
            batch: vec![],
            weights: vec![],
            region,
            window,
        };
        for _ in 0..n {
            c.mean.extend([u(17.0, 31.0), u(27.0, 39.0), u(-1.5, NZ as f32 + 1.5)]);
            for _ in 0..3 {
                c.scale.push(u(0.25, smax));
            }
            let q: [f32; 4] = std::array::from_fn(|_| u(-1.0, 1.0));
            let norm = q.iter().map(|v| v * v).sum::<f32>().sqrt().max(1e-3);
            let [w, x, y, z] = q.map(|v| v / norm);
            c.rot.extend([
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
                2.0 * (x * y + w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - w * x),
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ]);
            c.opacity.push(u(0.05, 0.95));
            for _ in 0..N_LABELS {
                c.feat.push(u(-2.0, 2.0));
            }
            c.batch.push(usize::from(u(0.0, 1.0) >= 0.5));
        }
        for _ in 0..2 * region.voxels() * N_LABELS {
            c.weights.push(u(-1.0, 1.0));
        }
        c
    }

    /// One more Gaussian with the given mean (in batch element 0).
    pub fn push(&mut self, mean: [f32; 3]) {
        self.mean.extend(mean);
        self.scale.extend([0.5; 3]);
        self.rot.extend([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        self.opacity.push(0.5);
        self.feat.extend([1.0; N_LABELS]);
        self.batch.push(0);
        self.n += 1;
    }

    /// The parameters as tensors that take gradients, and the Gaussians made of them.
    pub fn tensors(&self, device: &Device) -> (Gaussians, [Tensor<2>; 5]) {
        let t = |v: &Vec<f32>, cols: usize| {
            Tensor::<2>::from_data(TensorData::new(v.clone(), [self.n, cols]), device).require_grad()
        };
        let params =
            [t(&self.mean, 3), t(&self.scale, 3), t(&self.rot, 9), t(&self.opacity, 1), t(&self.feat, N_LABELS)];
        let [mean, scale, rot, opacity, feat] = params.clone();
        (Gaussians { mean, scale, rot, opacity, feat, batch: self.batch.clone() }, params)
    }

    /// Logits and the gradient of sum(weights * logits) for each parameter, on `device` (an
    /// autodiff device), by the operation or, with `reference`, by tensor operations.
    pub fn run(&self, device: &Device, reference: bool) -> (Vec<f32>, [Vec<f32>; 5]) {
        let (g, params) = self.tensors(device);
        let f = if reference { splat_tensor_ops } else { splat };
        let logits = f(&g, self.region, 2, self.window);
        let rows = 2 * self.region.voxels();
        let w = Tensor::<2>::from_data(TensorData::new(self.weights.clone(), [rows, N_LABELS]), device);
        let grads = (logits.clone() * w).sum().backward();
        let values = logits.to_data().iter::<f32>().collect();
        let gs = params.map(|p| p.grad(&grads).map(|t| t.to_data().iter::<f32>().collect()).unwrap_or_default());
        (values, gs)
    }

    /// Largest differences, relative to the reference's largest magnitude, of the logits and of
    /// each parameter's gradient (`NAMES` order) between `device` and `reference`.
    pub fn errors(&self, device: &Device, reference: &Device, tensor_ops: bool) -> [f32; 6] {
        let (v, g) = self.run(device, false);
        let (rv, rg) = self.run(reference, tensor_ops);
        let mut e = [max_rel_err(&v, &rv); 6];
        for k in 0..5 {
            e[k + 1] = max_rel_err(&g[k], &rg[k]);
        }
        e
    }
}

/// max |a - b| / max(|b|, 1e-3); infinite where the lengths differ.
pub fn max_rel_err(a: &[f32], b: &[f32]) -> f32 {
    if a.len() != b.len() {
        return f32::INFINITY;
    }
    let scale = b.iter().fold(1e-3f32, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / scale)
        .fold(0.0, |m: f32, d| if d.is_nan() { f32::INFINITY } else { m.max(d) })
}
