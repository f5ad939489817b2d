//! The class-weighted cross-entropy as one backend operation with its own backward pass, for
//! the CPU: forward is one pass over the logits that returns the scalar (no log-softmax, gather
//! or weight tensor of the logits' size), backward writes the logits' gradient
//! `w[y] / W * (softmax - onehot(y))` in one more pass. burn's tensor formulation
//! (`loss::weighted_cross_entropy_tensor_ops`) builds about ten logits-sized temporaries between
//! the two. A GPU keeps that formulation (`loss::weighted_cross_entropy` chooses); the host code
//! here runs on any backend. Both passes take their exponentials from `expf`, several rows'
//! at once. tests/grounded.rs checks value and gradient against the tensor formulation.

use super::expf;
use super::host_read::{flex_f32, flex_slice, host_vec};
use super::par::{CHUNK, par_vec};
use crate::backend::layout::N_LABELS;
use burn::backend::autodiff::checkpoint::{base::Checkpointer, strategy::CheckpointStrategy};
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind, unary};
use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{Autodiff, AutodiffBackend, Backend, Dispatch, Flex, TensorMetadata, backend_extension};
use burn::prelude::*;
use rayon::prelude::*;
use std::sync::Arc;

/// The labels of the logits' rows and the weight of each class, divided by the weights' sum
/// over the rows (so the loss is a weighted mean).
#[derive(Clone, Debug)]
pub struct Targets {
    pub labels: Arc<[u8]>,
    pub weights: [f32; N_LABELS],
}

impl Targets {
    pub fn new(labels: &[u8], weights: &[f32; N_LABELS]) -> Self {
        let total: f64 = labels.iter().map(|&t| weights[class(t)] as f64).sum();
        let inv = 1.0 / total.max(1e-12);
        Targets { labels: labels.into(), weights: weights.map(|w| (w as f64 * inv) as f32) }
    }
}

/// A target's class (labels past the last class count as the last).
#[inline]
pub(super) fn class(t: u8) -> usize {
    (t as usize).min(N_LABELS - 1)
}

#[backend_extension(Flex, Cube: cfg(any(feature = "wgpu", feature = "cuda")), Autodiff)]
pub trait CrossEntropyOps: burn::backend::Backend {
    /// Logits `[N, 9]` -> the weighted cross-entropy `[1]`.
    fn cross_entropy(logits: FloatTensor<Self>, t: Targets) -> FloatTensor<Self> {
        let device = logits.device();
        let v = forward(&host_vec::<Self>(logits), &t);
        Self::float_from_data(TensorData::new(vec![v], [1]), &device)
    }

    /// Logits and the loss's gradient `[1]` -> the logits' gradient `[N, 9]`.
    fn cross_entropy_backward(logits: FloatTensor<Self>, grad: FloatTensor<Self>, t: Targets) -> FloatTensor<Self> {
        let device = logits.device();
        let g = host_vec::<Self>(grad).first().copied().unwrap_or(0.0);
        let out = backward(&host_vec::<Self>(logits), g, &t);
        let n = t.labels.len();
        Self::float_from_data(TensorData::new(out, [n, N_LABELS]), &device)
    }

    /// Logits `[N, 9]` -> `[1 + m * 9]`: the weighted cross-entropy, then the softmax of the
    /// `m` rows `rows`, ascending and distinct (the Lovász term's probabilities). One operation,
    /// so that its backward pass writes the logits' one gradient: a row selection's backward
    /// builds a second logits-sized gradient (38 MB for a `cpu-small` crop) to add to the first.
    fn cross_entropy_and_rows(logits: FloatTensor<Self>, t: Targets, rows: Arc<[usize]>) -> FloatTensor<Self> {
        let device = logits.device();
        let out = forward_rows(&host_vec::<Self>(logits), &t, &rows);
        let n = out.len();
        Self::float_from_data(TensorData::new(out, [n]), &device)
    }

    /// Logits and the gradient of `cross_entropy_and_rows`'s output -> the logits' gradient.
    fn cross_entropy_and_rows_backward(
        logits: FloatTensor<Self>,
        grad: FloatTensor<Self>,
        t: Targets,
        rows: Arc<[usize]>,
    ) -> FloatTensor<Self> {
        let device = logits.device();
        let out = backward_rows(&host_vec::<Self>(logits), &host_vec::<Self>(grad), &t, &rows);
        let n = t.labels.len();
        Self::float_from_data(TensorData::new(out, [n, N_LABELS]), &device)
    }

    /// Logits `[N, 9]` -> `[N]`: 1 where the row's argmax (its first largest value) is an agent
    /// class (2 and up), else 0. No gradient.
    fn agent_rows(logits: FloatTensor<Self>) -> FloatTensor<Self> {
        let device = logits.device();
        let out = agent_rows(&host_vec::<Self>(logits));
        let n = out.len();
        Self::float_from_data(TensorData::new(out, [n]), &device)
    }
}

/// `CrossEntropyOps::agent_rows` on the host.
pub fn agent_rows(logits: &[f32]) -> Vec<f32> {
    par_vec(logits.len() / N_LABELS, |start, part| {
        let rows = logits[start * N_LABELS..(start + part.len()) * N_LABELS].as_chunks::<N_LABELS>().0;
        for (o, l) in part.iter_mut().zip(rows) {
            *o = is_agent(l) as u8 as f32;
        }
    })
}

/// Whether the argmax of `l` (the first largest value, or the first NaN) is an agent class:
/// the largest agent logit above both free and background, as trees of compares (no branch
/// per element); a row holding NaN takes the argmax itself.
#[inline]
fn is_agent(l: &[f32; N_LABELS]) -> bool {
    let m = |a: f32, b: f32| if a > b { a } else { b };
    let agents = m(m(m(l[2], l[3]), m(l[4], l[5])), m(m(l[6], l[7]), l[8]));
    if l.iter().sum::<f32>().is_nan() {
        return super::head::argmax(l) >= 2;
    }
    agents > m(l[0], l[1])
}

impl CrossEntropyOps for Flex {
    fn cross_entropy(logits: FloatTensor<Self>, t: Targets) -> FloatTensor<Self> {
        let l = flex_f32(&logits);
        FlexTensor::from_data(TensorData::new(vec![forward(flex_slice(&l), &t)], [1]))
    }

    fn cross_entropy_backward(logits: FloatTensor<Self>, grad: FloatTensor<Self>, t: Targets) -> FloatTensor<Self> {
        let g = host_vec::<Self>(grad).first().copied().unwrap_or(0.0);
        let n = t.labels.len();
        let out = backward(flex_slice(&flex_f32(&logits)), g, &t);
        FlexTensor::from_data(TensorData::new(out, [n, N_LABELS]))
    }

    fn cross_entropy_and_rows(logits: FloatTensor<Self>, t: Targets, rows: Arc<[usize]>) -> FloatTensor<Self> {
        let out = forward_rows(flex_slice(&flex_f32(&logits)), &t, &rows);
        let n = out.len();
        FlexTensor::from_data(TensorData::new(out, [n]))
    }

    fn cross_entropy_and_rows_backward(
        logits: FloatTensor<Self>,
        grad: FloatTensor<Self>,
        t: Targets,
        rows: Arc<[usize]>,
    ) -> FloatTensor<Self> {
        let n = t.labels.len();
        let out = backward_rows(flex_slice(&flex_f32(&logits)), flex_slice(&flex_f32(&grad)), &t, &rows);
        FlexTensor::from_data(TensorData::new(out, [n, N_LABELS]))
    }

    fn agent_rows(logits: FloatTensor<Self>) -> FloatTensor<Self> {
        let out = agent_rows(flex_slice(&flex_f32(&logits)));
        let n = out.len();
        FlexTensor::from_data(TensorData::new(out, [n]))
    }
}

#[cfg(any(feature = "wgpu", feature = "cuda"))]
impl CrossEntropyOps for burn_cubecl::CubeBackend {}

/// Rows per task: partial sums are taken per block and added in block order, so the value
/// does not depend on the thread count.
const ROWS: usize = 16384;

/// -sum_v w[y_v] log softmax(l_v)[y_v] (weights already divided by their sum).
pub fn forward(logits: &[f32], t: &Targets) -> f32 {
    let parts: Vec<f64> = logits
        .par_chunks(ROWS * N_LABELS)
        .zip(t.labels.par_chunks(ROWS))
        .map(|(rows, labels)| {
            let mut sum = 0f64;
            let (mut e, mut maxes) = ([0f32; BLOCK * N_LABELS], Vec::with_capacity(BLOCK));
            for (rows, labels) in rows.chunks(BLOCK * N_LABELS).zip(labels.chunks(BLOCK)) {
                let e = &mut e[..rows.len()];
                expf::shifted_exp(rows, N_LABELS, e, &mut maxes);
                for ((e, l), (&y, &max)) in
                    e.chunks_exact(N_LABELS).zip(rows.chunks_exact(N_LABELS)).zip(labels.iter().zip(&maxes))
                {
                    let lse = e.iter().sum::<f32>().ln();
                    sum += (t.weights[class(y)] * (l[class(y)] - max - lse)) as f64;
                }
            }
            sum
        })
        .collect();
    -parts.iter().sum::<f64>() as f32
}

/// `g * w[y] * (softmax(l) - onehot(y))` per row.
pub fn backward(logits: &[f32], g: f32, t: &Targets) -> Vec<f32> {
    par_vec(logits.len(), |start, o| ce_backward_part(logits, g, t, start, o))
}

/// `backward`'s elements `start..start + o.len()` (whole rows).
#[inline]
fn ce_backward_part(logits: &[f32], g: f32, t: &Targets, start: usize, o: &mut [f32]) {
    let labels = &t.labels[start / N_LABELS..(start + o.len()) / N_LABELS];
    expf::shifted_exp(&logits[start..start + o.len()], N_LABELS, o, &mut Vec::with_capacity(CHUNK / N_LABELS));
    for (o, &y) in o.chunks_exact_mut(N_LABELS).zip(labels) {
        let sum: f32 = o.iter().sum();
        let s = g * t.weights[class(y)];
        let inv = 1.0 / sum;
        for (c, o) in o.iter_mut().enumerate() {
            *o = s * (*o * inv - (c == class(y)) as u8 as f32);
        }
    }
}

/// The softmax of row `l`.
#[inline]
fn softmax_row(l: &[f32]) -> [f32; N_LABELS] {
    let max = l.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let e: [f32; N_LABELS] = std::array::from_fn(|c| expf::exp(l[c] - max));
    let inv = 1.0 / e.iter().sum::<f32>();
    e.map(|e| e * inv)
}

/// `cross_entropy_and_rows` on the host (`rows` ascending and distinct).
pub fn forward_rows(logits: &[f32], t: &Targets, rows: &[usize]) -> Vec<f32> {
    debug_assert!(rows.windows(2).all(|w| w[0] < w[1]));
    let probs = par_vec(rows.len() * N_LABELS, |start, part| {
        for (p, &r) in part.chunks_exact_mut(N_LABELS).zip(&rows[start / N_LABELS..]) {
            p.copy_from_slice(&softmax_row(&logits[r * N_LABELS..(r + 1) * N_LABELS]));
        }
    });
    let mut out = Vec::with_capacity(1 + probs.len());
    out.push(forward(logits, t));
    out.extend_from_slice(&probs);
    out
}

/// `cross_entropy_and_rows_backward` on the host: the cross-entropy's gradient times `grad[0]`,
/// plus on each selected row the softmax's backward of its part of `grad`, in the same pass
/// (each task finds its rows among the ascending `rows`).
pub fn backward_rows(logits: &[f32], grad: &[f32], t: &Targets, rows: &[usize]) -> Vec<f32> {
    let g0 = grad.first().copied().unwrap_or(0.0);
    let gp = grad.get(1..).unwrap_or(&[]);
    par_vec(logits.len(), |start, o| {
        ce_backward_part(logits, g0, t, start, o);
        let (r0, r1) = (start / N_LABELS, (start + o.len()) / N_LABELS);
        let (a, b) = (rows.partition_point(|&r| r < r0), rows.partition_point(|&r| r < r1));
        for (k, &r) in (a..b).zip(&rows[a..b]) {
            let p = softmax_row(&logits[r * N_LABELS..(r + 1) * N_LABELS]);
            let Some(g) = gp.get(k * N_LABELS..(k + 1) * N_LABELS) else { continue };
            let dot: f32 = p.iter().zip(g).map(|(p, g)| p * g).sum();
            for ((o, &p), &g) in o[(r - r0) * N_LABELS..(r - r0 + 1) * N_LABELS].iter_mut().zip(&p).zip(g) {
                *o += p * (g - dot);
            }
        }
    })
}

/// Rows per block of the forward pass's exponentials (a buffer on the stack).
const BLOCK: usize = 256;

#[derive(Debug)]
struct CrossEntropyBackward;

#[derive(Debug)]
struct CrossEntropyRowsBackward;

impl<B: Backend + CrossEntropyOps> Backward<B, 1> for CrossEntropyRowsBackward {
    type State = (FloatTensor<B>, Targets, Arc<[usize]>);

    fn backward(self, ops: Ops<Self::State, 1>, grads: &mut Gradients, _checkpointer: &mut Checkpointer) {
        let (logits, t, rows) = ops.state;
        unary::<B, _>(ops.parents, ops.node, grads, |grad| B::cross_entropy_and_rows_backward(logits, grad, t, rows));
    }
}

impl<B: Backend + CrossEntropyOps> Backward<B, 1> for CrossEntropyBackward {
    type State = (FloatTensor<B>, Targets);

    fn backward(self, ops: Ops<Self::State, 1>, grads: &mut Gradients, _checkpointer: &mut Checkpointer) {
        let (logits, t) = ops.state;
        unary::<B, _>(ops.parents, ops.node, grads, |grad| B::cross_entropy_backward(logits, grad, t));
    }
}

impl<B: Backend + CrossEntropyOps, C: CheckpointStrategy> CrossEntropyOps for Autodiff<B, C> {
    fn cross_entropy(logits: FloatTensor<Self>, t: Targets) -> FloatTensor<Self> {
        match CrossEntropyBackward.prepare::<C>([logits.node()]).compute_bound().stateful() {
            OpsKind::Tracked(prep) => {
                let inner = logits.primitive().clone();
                let out = B::cross_entropy(inner.clone(), t.clone());
                prep.finish((inner, t), out)
            }
            OpsKind::UnTracked(prep) => prep.finish(B::cross_entropy(logits.into_primitive(), t)),
        }
    }

    fn cross_entropy_backward(logits: FloatTensor<Self>, grad: FloatTensor<Self>, t: Targets) -> FloatTensor<Self> {
        Self::from_inner(B::cross_entropy_backward(Self::inner(logits), Self::inner(grad), t))
    }

    fn cross_entropy_and_rows(logits: FloatTensor<Self>, t: Targets, rows: Arc<[usize]>) -> FloatTensor<Self> {
        match CrossEntropyRowsBackward.prepare::<C>([logits.node()]).compute_bound().stateful() {
            OpsKind::Tracked(prep) => {
                let inner = logits.primitive().clone();
                let out = B::cross_entropy_and_rows(inner.clone(), t.clone(), rows.clone());
                prep.finish((inner, t, rows), out)
            }
            OpsKind::UnTracked(prep) => prep.finish(B::cross_entropy_and_rows(logits.into_primitive(), t, rows)),
        }
    }

    fn cross_entropy_and_rows_backward(
        logits: FloatTensor<Self>,
        grad: FloatTensor<Self>,
        t: Targets,
        rows: Arc<[usize]>,
    ) -> FloatTensor<Self> {
        Self::from_inner(B::cross_entropy_and_rows_backward(Self::inner(logits), Self::inner(grad), t, rows))
    }

    fn agent_rows(logits: FloatTensor<Self>) -> FloatTensor<Self> {
        Self::from_inner(B::agent_rows(Self::inner(logits)))
    }
}

/// The weighted cross-entropy of `logits` `[N, 9]` through `CrossEntropyOps`.
pub fn cross_entropy(logits: Tensor<2>, t: Targets) -> Tensor<1> {
    Tensor::from_dispatch(<Dispatch as CrossEntropyOps>::cross_entropy(logits.into_dispatch(), t))
}

/// The weighted cross-entropy of `logits` `[N, 9]` and the softmax of its rows `rows` (ascending, distinct)
/// (`[m, 9]`), through `CrossEntropyOps::cross_entropy_and_rows`.
pub fn cross_entropy_and_rows(logits: Tensor<2>, t: Targets, rows: Arc<[usize]>) -> (Tensor<1>, Tensor<2>) {
    let m = rows.len();
    let out: Tensor<1> =
        Tensor::from_dispatch(<Dispatch as CrossEntropyOps>::cross_entropy_and_rows(logits.into_dispatch(), t, rows));
    (out.clone().narrow(0, 0, 1), out.narrow(0, 1, m * N_LABELS).reshape([m, N_LABELS]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The compare trees give the argmax's answer on ties, signed zeros, infinities and NaN.
    #[test]
    fn agent_rows_follow_the_argmax() {
        let special = [0.0, -0.0, 1.0, 1.0, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, -2.5];
        let mut rows = Vec::new();
        let mut h = 1u32;
        for _ in 0..20_000 {
            for _ in 0..N_LABELS {
                h = h.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                rows.push(special[(h >> 24) as usize % special.len()]);
            }
        }
        let flags = agent_rows(&rows);
        for (l, &f) in rows.as_chunks::<N_LABELS>().0.iter().zip(&flags) {
            assert_eq!(f == 1.0, super::super::head::argmax(l) >= 2, "{l:?}");
        }
        assert!(flags.contains(&1.0) && flags.contains(&0.0));
    }
}
