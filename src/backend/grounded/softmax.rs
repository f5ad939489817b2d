//! The decoder's attention weights for a training step on the CPU, as one backend operation:
//! `softmax(scores / scale)` over the keys, padded keys set to `fill` first (burn's
//! `div_scalar`, `mask_fill` and `softmax`, the same values to float rounding). burn's CPU
//! formulation runs libm's `expf` one value at a time on the calling thread, twice (its
//! exponential's backward computes the exponential again), over tensors of b x heads x q x q
//! (4.7 M values per `cpu-small` layer), each of its five steps writing one more such tensor.
//! Here the forward pass is one pass over the rows on all cores, with `expf`'s exponential, and
//! the backward pass one more, from the weights it kept: `y * (g - sum(g * y)) / scale`, zero
//! on padded keys. Inference keeps burn's formulation (its labels keep their bits); a GPU keeps
//! it throughout. This file's tests check values and gradients against burn's.

use super::expf::exp;
use super::host_read::{flex_f32, flex_slice, host_vec};
use super::par::{CHUNK, par_zeroed_parts};
use burn::backend::autodiff::checkpoint::{base::Checkpointer, strategy::CheckpointStrategy};
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind, unary};
use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{Autodiff, AutodiffBackend, Backend, DType, Dispatch, Flex, TensorMetadata, backend_extension};
use burn::prelude::*;
use std::sync::Arc;

/// The keys of a batch of attention rows: `pad[b * n + j]` is true where key `j` of set `b`
/// is padding; scores are divided by `scale`, padded ones set to `fill` instead.
#[derive(Clone, Debug)]
pub struct Keys {
    pub pad: Arc<[bool]>,
    pub scale: f32,
    pub fill: f32,
}

#[backend_extension(Flex, Cube: cfg(any(feature = "wgpu", feature = "cuda")), Autodiff)]
pub trait AttentionSoftmaxOps: burn::backend::Backend {
    /// Scores `[b, heads, n, n]` -> the attention weights, the same shape.
    fn attention_softmax(scores: FloatTensor<Self>, keys: Keys) -> FloatTensor<Self> {
        let (device, shape) = (scores.device(), scores.shape());
        let n = shape[3];
        let y = forward(&host_vec::<Self>(scores), n, &keys);
        Self::float_from_data(TensorData::new(y, shape), &device)
    }

    /// The weights (`attention_softmax`'s output) and their gradient -> the scores' gradient.
    fn attention_softmax_backward(
        weights: FloatTensor<Self>,
        grad: FloatTensor<Self>,
        keys: Keys,
    ) -> FloatTensor<Self> {
        let (device, shape) = (weights.device(), weights.shape());
        let n = shape[3];
        let g = backward(&host_vec::<Self>(weights), &host_vec::<Self>(grad), n, &keys);
        Self::float_from_data(TensorData::new(g, shape), &device)
    }
}

impl AttentionSoftmaxOps for Flex {
    fn attention_softmax(scores: FloatTensor<Self>, keys: Keys) -> FloatTensor<Self> {
        let shape = scores.shape();
        let n = shape[3];
        let s = flex_f32(&scores);
        FlexTensor::from_data(TensorData::new(forward(flex_slice(&s), n, &keys), shape))
    }

    fn attention_softmax_backward(
        weights: FloatTensor<Self>,
        grad: FloatTensor<Self>,
        keys: Keys,
    ) -> FloatTensor<Self> {
        let shape = weights.shape();
        let n = shape[3];
        let (y, g) = (flex_f32(&weights), flex_f32(&grad));
        FlexTensor::from_data(TensorData::new(backward(flex_slice(&y), flex_slice(&g), n, &keys), shape))
    }
}

#[cfg(any(feature = "wgpu", feature = "cuda"))]
impl AttentionSoftmaxOps for burn_cubecl::CubeBackend {}

#[derive(Debug)]
struct SoftmaxBackward;

impl<B: Backend + AttentionSoftmaxOps> Backward<B, 1> for SoftmaxBackward {
    /// The weights and the keys.
    type State = (FloatTensor<B>, Keys);

    fn backward(self, ops: Ops<Self::State, 1>, grads: &mut Gradients, _checkpointer: &mut Checkpointer) {
        let (y, keys) = ops.state;
        unary::<B, _>(ops.parents, ops.node, grads, |grad| B::attention_softmax_backward(y, grad, keys));
    }
}

impl<B: Backend + AttentionSoftmaxOps, C: CheckpointStrategy> AttentionSoftmaxOps for Autodiff<B, C> {
    fn attention_softmax(scores: FloatTensor<Self>, keys: Keys) -> FloatTensor<Self> {
        match SoftmaxBackward.prepare::<C>([scores.node()]).compute_bound().stateful() {
            OpsKind::Tracked(prep) => {
                let y = B::attention_softmax(scores.into_primitive(), keys.clone());
                prep.finish((y.clone(), keys), y)
            }
            OpsKind::UnTracked(prep) => prep.finish(B::attention_softmax(scores.into_primitive(), keys)),
        }
    }

    fn attention_softmax_backward(
        weights: FloatTensor<Self>,
        grad: FloatTensor<Self>,
        keys: Keys,
    ) -> FloatTensor<Self> {
        Self::from_inner(B::attention_softmax_backward(Self::inner(weights), Self::inner(grad), keys))
    }
}

/// The attention weights of a training step's `scores` `[b, heads, n, n]` on the CPU through
/// `AttentionSoftmaxOps`; `None` elsewhere (untracked, or on a GPU), where burn's formulation
/// runs.
pub fn attention_weights(
    scores: &Tensor<4>,
    pad: Option<&Tensor<2, Bool>>,
    scale: f32,
    fill: f32,
) -> Option<Tensor<4>> {
    if !scores.is_tracked() || scores.device() != Device::flex() || scores.dtype() != DType::F32 {
        return None;
    }
    let [b, _, _, n] = scores.dims();
    let pad: Arc<[bool]> = match pad {
        Some(pad) => pad.to_data().try_to_vec::<bool>().ok()?.into(),
        None => vec![false; b * n].into(),
    };
    if pad.len() != b * n {
        return None;
    }
    let keys = Keys { pad, scale, fill };
    Some(Tensor::from_dispatch(<Dispatch as AttentionSoftmaxOps>::attention_softmax(
        scores.clone().into_dispatch(),
        keys,
    )))
}

/// `len` values built on all cores, row by row (rows of `n`, whole rows per task, about `CHUNK`
/// values each): `f(row, pad, out)` writes flat row `row`, whose keys' padding is `pad` (rows run
/// set by set, `heads x n` rows per set).
fn by_rows(len: usize, n: usize, keys: &Keys, f: impl Fn(usize, &[bool], &mut [f32]) + Sync) -> Vec<f32> {
    let n = n.max(1);
    let rows_per_set = (len / n / (keys.pad.len() / n).max(1)).max(1);
    let per = (CHUNK / n).max(1) * n;
    let lens: Vec<usize> = (0..len).step_by(per).map(|start| per.min(len - start)).collect();
    par_zeroed_parts(&lens, |task, out| {
        let r0 = task * per / n;
        for (k, o) in out.chunks_exact_mut(n).enumerate() {
            let set = (r0 + k) / rows_per_set;
            f(r0 + k, &keys.pad[set * n..(set + 1) * n], o);
        }
    })
}

/// `AttentionSoftmaxOps::attention_softmax` on the host (`scores` flat, rows of `n`).
pub fn forward(scores: &[f32], n: usize, keys: &Keys) -> Vec<f32> {
    by_rows(scores.len(), n, keys, |r, pad, o| softmax_row(&scores[r * n..(r + 1) * n], pad, keys, o))
}

/// `AttentionSoftmaxOps::attention_softmax_backward` on the host.
pub fn backward(y: &[f32], g: &[f32], n: usize, keys: &Keys) -> Vec<f32> {
    by_rows(y.len(), n, keys, |r, pad, o| {
        let row = r * n..(r + 1) * n;
        softmax_grad_row(&y[row.clone()], &g[row], pad, keys.scale, o)
    })
}

/// One row's weights into `out`; on x86-64 with AVX2, compiled for it (eight lanes).
fn softmax_row(s: &[f32], pad: &[bool], keys: &Keys, out: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above: the one requirement of the callee.
        return unsafe { softmax_row_avx2(s, pad, keys.scale, keys.fill, out) };
    }
    softmax_row_body(s, pad, keys.scale, keys.fill, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn softmax_row_avx2(s: &[f32], pad: &[bool], scale: f32, fill: f32, out: &mut [f32]) {
    softmax_row_body(s, pad, scale, fill, out);
}

/// Eight running maxima and sums, so the loops run in lanes (a single fold is a chain).
const LANES: usize = 8;

#[inline(always)]
fn softmax_row_body(s: &[f32], pad: &[bool], scale: f32, fill: f32, out: &mut [f32]) {
    for ((o, &v), &p) in out.iter_mut().zip(s).zip(pad) {
        *o = if p { fill } else { v / scale };
    }
    let mut m = [f32::NEG_INFINITY; LANES];
    let (chunks, tail) = out.as_chunks::<LANES>();
    for c in chunks {
        for l in 0..LANES {
            m[l] = if c[l] > m[l] { c[l] } else { m[l] };
        }
    }
    let max = tail.iter().chain(&m).copied().fold(f32::NEG_INFINITY, f32::max);
    for o in out.iter_mut() {
        *o = exp(*o - max);
    }
    let mut acc = [0f32; LANES];
    let (chunks, tail) = out.as_chunks::<LANES>();
    for c in chunks {
        for l in 0..LANES {
            acc[l] += c[l];
        }
    }
    let sum: f32 = acc.iter().sum::<f32>() + tail.iter().sum::<f32>();
    for o in out.iter_mut() {
        *o /= sum;
    }
}

/// One row's gradient into `out`.
fn softmax_grad_row(y: &[f32], g: &[f32], pad: &[bool], scale: f32, out: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above: the one requirement of the callee.
        return unsafe { softmax_grad_row_avx2(y, g, pad, scale, out) };
    }
    softmax_grad_row_body(y, g, pad, scale, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn softmax_grad_row_avx2(y: &[f32], g: &[f32], pad: &[bool], scale: f32, out: &mut [f32]) {
    softmax_grad_row_body(y, g, pad, scale, out);
}

#[inline(always)]
fn softmax_grad_row_body(y: &[f32], g: &[f32], pad: &[bool], scale: f32, out: &mut [f32]) {
    let mut acc = [0f32; LANES];
    let (yc, yt) = y.as_chunks::<LANES>();
    let (gc, gt) = g.as_chunks::<LANES>();
    for (a, b) in yc.iter().zip(gc) {
        for l in 0..LANES {
            acc[l] += a[l] * b[l];
        }
    }
    let dot: f32 = acc.iter().sum::<f32>() + yt.iter().zip(gt).map(|(a, b)| a * b).sum::<f32>();
    for (((o, &y), &g), &p) in out.iter_mut().zip(y).zip(g).zip(pad) {
        // A padded key's score was replaced (`mask_fill`): no gradient reaches it.
        *o = if p { 0.0 } else { y * (g - dot) / scale };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::activation::softmax;

    fn close(a: &[f32], b: &[f32], tol: f32) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol * (1.0 + y.abs()))
    }

    /// Values and gradients of the operation and of burn's formulation, on sets with padded
    /// keys, an all-padding set (uniform weights, no gradient) and a row width that is not a
    /// multiple of the lanes, over several tasks.
    #[test]
    fn the_fused_weights_follow_burns_formulation() {
        let device = super::super::cpu().autodiff();
        let (b, h, n) = (3, 2, 37);
        let x: Vec<f32> =
            (0..b * h * n * n).map(|i| ((i as u32).wrapping_mul(2654435761) % 4000) as f32 / 400.0 - 5.0).collect();
        let pad: Vec<bool> = (0..b * n).map(|i| (i / n == 1 && i % n > 20) || i / n == 2).collect();
        let pad_t = Tensor::<2, Bool>::from_data(TensorData::new(pad.clone(), [b, n]), &device);
        let upstream: Vec<f32> = (0..x.len()).map(|i| ((i * 7919) % 101) as f32 / 50.0 - 1.0).collect();
        let up = Tensor::<4>::from_data(TensorData::new(upstream, [b, h, n, n]), &device);
        let (scale, fill) = (4.0, -1.0e9);
        let run = |fused: bool| {
            let s = Tensor::<4>::from_data(TensorData::new(x.clone(), [b, h, n, n]), &device).require_grad();
            let y = if fused {
                attention_weights(&s, Some(&pad_t), scale, fill).expect("a tracked CPU tensor takes the fused path")
            } else {
                softmax(s.clone().div_scalar(scale).mask_fill(pad_t.clone().reshape([b, 1, 1, n]), fill), 3)
            };
            let grads = (y.clone() * up.clone()).sum().backward();
            let g = s.grad(&grads).unwrap();
            (y.into_data().try_to_vec::<f32>().unwrap(), g.into_data().try_to_vec::<f32>().unwrap())
        };
        let ((y, g), (yb, gb)) = (run(true), run(false));
        assert!(close(&y, &yb, 1e-6), "weights");
        assert!(close(&g, &gb, 1e-5), "gradients");
        // The all-padding set: uniform weights, and no gradient on any score.
        let set2 = 2 * h * n * n;
        assert!(y[set2..].iter().all(|&v| (v - 1.0 / n as f32).abs() < 1e-7));
        assert!(g[set2..].iter().all(|&v| v == 0.0));
        assert!(g[..set2].iter().any(|&v| v.abs() > 1e-4));
        // Untracked (inference), the operation is not taken.
        let plain = Tensor::<4>::from_data(TensorData::new(x.clone(), [b, h, n, n]), &super::super::cpu());
        assert!(attention_weights(&plain, Some(&pad_t), scale, fill).is_none());
    }
}
