//! The last steps of the generator, fused into one pass over the voxels: the layer bias added
//! to the splat and the background head's gated residual (free -> background), then, for
//! inference, the argmax. In: the splat `[voxels, 9]` (no bias), the layer bias `[NZ, 9]`, the
//! residual per voxel (training) or per feature pixel and layer (inference). Out: logits, or one
//! label per voxel.
//!
//! The arithmetic is the tensor formulation's (`head_tensor_ops`, what a GPU runs), operation
//! for operation (burn's CPU softmax of a 9-wide row is a scalar max, `exp`, a sum in order and
//! a multiply by the inverse; argmax keeps the first maximum), so inference labels are the same
//! bits (tests/grounded_infer.rs) without the grid-sized temporaries the tensor path builds:
//! the repeated bias, the softmax, the residual's three channels, two sums. (Under autodiff
//! burn's softmax rounds differently, so training logits agree with the tensor formulation to
//! float rounding, tests/grounded.rs.) For training the
//! logits are one backend operation with its own backward pass (`HeadOps`): the splat's
//! gradient is the logits', the bias's a sum per layer, the residual's the gate times the
//! difference of the background and free channels' gradients (the gate is computed from
//! detached logits, as in the tensor formulation; the forward pass keeps it, with `expf`'s
//! exponentials, so the backward pass takes no softmax). Host code on the CPU, reading the
//! tensors in place; the model keeps the tensor formulation on a GPU.

use super::expf;
use super::host_read::{flex_f32, flex_slice, host_vec};
use super::par::{CHUNK, par_vec2, par_zeros};
use crate::backend::layout::{N_LABELS, NZ};
use burn::backend::autodiff::checkpoint::{base::Checkpointer, strategy::CheckpointStrategy};
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind};
use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{Autodiff, AutodiffBackend, Backend, Dispatch, Flex, TensorMetadata, backend_extension};
use burn::prelude::*;
use rayon::prelude::*;

/// The background head's residual: `values` `[pixels * NZ]`, and for each column of the splat
/// the pixel it reads (`model::feature_columns`).
pub struct Residual<'a> {
    pub values: &'a [f32],
    pub columns: &'a [i64],
}

/// Columns per task: a task's voxels are contiguous and independent of the others'.
const COLUMNS_PER_TASK: usize = 1024;

/// Labels of `splat + bias (+ the gated residual)`, one per voxel.
pub fn labels(splat: &[f32], bias: &[f32], residual: Option<Residual>) -> Vec<u8> {
    let voxels = splat.len() / N_LABELS;
    let mut out = vec![0u8; voxels];
    let per_task = COLUMNS_PER_TASK * NZ;
    out.par_chunks_mut(per_task).enumerate().for_each(|(task, labels)| {
        let v0 = task * per_task;
        for (dv, label) in labels.iter_mut().enumerate() {
            let v = v0 + dv;
            let mut l = biased(splat, bias, v);
            if let Some(r) = &residual {
                let r = r.values[r.columns[v / NZ] as usize * NZ + v % NZ];
                if let Some(known) = label_whatever_the_gate(&l, r) {
                    *label = known;
                    continue;
                }
                let rr = r * gate(&l);
                l[0] += -rr;
                l[1] += rr;
            }
            *label = argmax(&l);
        }
    });
    out
}

/// The label when no gate in [0, 1] can change it (the residual moves at most |r| between free
/// and background), so most voxels skip the softmax; `None` when it might, with a margin far
/// above the rounding of `l[0] - r gate` and `l[1] + r gate`.
#[inline]
fn label_whatever_the_gate(l: &[f32; N_LABELS], r: f32) -> Option<u8> {
    let (mut agent, mut best) = (2, l[2]);
    for (c, &v) in l.iter().enumerate().skip(3) {
        if v > best {
            (agent, best) = (c, v);
        }
    }
    if l.iter().any(|v| v.is_nan()) || r.is_nan() {
        return None;
    }
    let reach = r.abs() * 1.001 + 1e-4 * (l[0].abs() + l[1].abs() + best.abs() + r.abs()) + 1e-30;
    let (lo0, hi0, lo1, hi1) = (l[0] - reach, l[0] + reach, l[1] - reach, l[1] + reach);
    if best > hi0 && best > hi1 {
        Some(agent as u8)
    } else if lo0 > hi1 && lo0 > best {
        Some(0)
    } else if lo1 > hi0 && lo1 > best {
        Some(1)
    } else {
        None
    }
}

/// Voxel `v`'s splat plus the bias of its layer.
#[inline]
fn biased(splat: &[f32], bias: &[f32], v: usize) -> [f32; N_LABELS] {
    let k = v % NZ;
    std::array::from_fn(|c| splat[v * N_LABELS + c] + bias[k * N_LABELS + c])
}

/// softmax(l)[0] + softmax(l)[1], as burn's CPU softmax computes it.
#[inline]
fn gate(l: &[f32; N_LABELS]) -> f32 {
    let mut max = f32::NEG_INFINITY;
    for &x in l {
        if x > max {
            max = x;
        }
    }
    let mut e = [0f32; N_LABELS];
    let mut sum = 0f32;
    for (e, &x) in e.iter_mut().zip(l) {
        *e = (x - max).exp();
        sum += *e;
    }
    let inv = 1.0 / sum;
    e[0] * inv + e[1] * inv
}

/// The first index of the largest value (of the first NaN, as burn's CPU argmax).
#[inline]
pub(crate) fn argmax(l: &[f32; N_LABELS]) -> u8 {
    let mut best = 0;
    for (c, &v) in l.iter().enumerate() {
        if v.is_nan() {
            return c as u8;
        }
        if v > l[best] {
            best = c;
        }
    }
    best as u8
}

/// Logits `[voxels, 9]`: splat + bias, free -> background by `r[v] * gate`.
pub fn logits(splat: &[f32], bias: &[f32], r: &[f32]) -> Vec<f32> {
    let mut out = par_zeros(splat.len());
    out.par_chunks_mut(COLUMNS_PER_TASK * NZ * N_LABELS).enumerate().for_each(|(task, o)| {
        let v0 = task * COLUMNS_PER_TASK * NZ;
        for (dv, o) in o.chunks_exact_mut(N_LABELS).enumerate() {
            let v = v0 + dv;
            let mut l = biased(splat, bias, v);
            let rr = r[v] * gate(&l);
            l[0] += -rr;
            l[1] += rr;
            o.copy_from_slice(&l);
        }
    });
    out
}

/// `logits` for training, and each voxel's gate (what the backward pass needs: it then takes no
/// softmax of its own). The gate's exponentials are `expf`'s, so these logits agree with
/// `logits` to float rounding.
pub fn logits_and_gate(splat: &[f32], bias: &[f32], r: &[f32]) -> (Vec<f32>, Vec<f32>) {
    par_vec2(r.len(), [N_LABELS, 1], |v0, o, gates| {
        // A task starts on a column (`CHUNK / 9` voxels, a multiple of NZ): the bias adds
        // column by column, several lanes at once.
        for (o, s) in o.chunks_mut(NZ * N_LABELS).zip(splat[v0 * N_LABELS..].chunks(NZ * N_LABELS)) {
            for ((o, &s), &b) in o.iter_mut().zip(s).zip(bias) {
                *o = s + b;
            }
        }
        let (mut e, mut maxes) = ([0f32; CHUNK], Vec::with_capacity(CHUNK / N_LABELS));
        let e = &mut e[..o.len()];
        expf::shifted_exp(o, N_LABELS, e, &mut maxes);
        for (dv, (o, e)) in o.chunks_exact_mut(N_LABELS).zip(e.chunks_exact(N_LABELS)).enumerate() {
            let inv = 1.0 / e.iter().sum::<f32>();
            let g = e[0] * inv + e[1] * inv;
            gates[dv] = g;
            let rr = r[v0 + dv] * g;
            o[0] += -rr;
            o[1] += rr;
        }
    })
}

/// The gradients of the bias `[NZ, 9]` and of the residual `[voxels]` from each voxel's gate
/// (`logits_and_gate`) and the logits' gradient. The bias's is summed per block of columns and
/// the blocks in order: the same bits on any thread count.
pub fn backward(gates: &[f32], grad: &[f32]) -> (Vec<f32>, Vec<f32>) {
    let per_task = COLUMNS_PER_TASK * NZ;
    let mut gr = par_zeros(gates.len());
    let parts: Vec<Vec<f32>> = gr
        .par_chunks_mut(per_task)
        .enumerate()
        .map(|(task, gr)| {
            let v0 = task * per_task;
            let grad = &grad[v0 * N_LABELS..(v0 + gr.len()) * N_LABELS];
            // Column after column (a task starts on one): each element of the bias's gradient
            // sums its voxels in the same order as one voxel at a time would.
            let mut gb = vec![0f32; NZ * N_LABELS];
            for col in grad.chunks_exact(NZ * N_LABELS) {
                for (a, &g) in gb.iter_mut().zip(col) {
                    *a += g;
                }
            }
            for (dv, (gr, g)) in gr.iter_mut().zip(grad.chunks_exact(N_LABELS)).enumerate() {
                *gr = gates[v0 + dv] * (g[1] - g[0]);
            }
            gb
        })
        .collect();
    let mut gb = vec![0f32; NZ * N_LABELS];
    for p in parts {
        for (a, b) in gb.iter_mut().zip(p) {
            *a += b;
        }
    }
    (gb, gr)
}

#[backend_extension(Flex, Cube: cfg(any(feature = "wgpu", feature = "cuda")), Autodiff)]
pub trait HeadOps: burn::backend::Backend {
    /// Splat `[V, 9]`, bias `[NZ, 9]`, residual `[V, 1]` -> logits `[V, 9]`.
    fn head(splat: FloatTensor<Self>, bias: FloatTensor<Self>, r: FloatTensor<Self>) -> FloatTensor<Self> {
        let device = splat.device();
        let shape = splat.shape();
        let out = logits(&host_vec::<Self>(splat), &host_vec::<Self>(bias), &host_vec::<Self>(r));
        Self::float_from_data(TensorData::new(out, shape), &device)
    }

    /// `head`, and each voxel's gate `[V]` for `head_backward`.
    fn head_gated(
        splat: FloatTensor<Self>,
        bias: FloatTensor<Self>,
        r: FloatTensor<Self>,
    ) -> (FloatTensor<Self>, FloatTensor<Self>) {
        let device = splat.device();
        let shape = splat.shape();
        let (out, gates) = logits_and_gate(&host_vec::<Self>(splat), &host_vec::<Self>(bias), &host_vec::<Self>(r));
        let n = gates.len();
        (
            Self::float_from_data(TensorData::new(out, shape), &device),
            Self::float_from_data(TensorData::new(gates, [n]), &device),
        )
    }

    /// The gradients of the bias `[NZ, 9]` and of the residual `[V, 1]` from the gates and the
    /// logits' gradient.
    fn head_backward(gates: FloatTensor<Self>, grad: FloatTensor<Self>) -> (FloatTensor<Self>, FloatTensor<Self>) {
        let device = gates.device();
        let (gb, gr) = backward(&host_vec::<Self>(gates), &host_vec::<Self>(grad));
        let n = gr.len();
        (
            Self::float_from_data(TensorData::new(gb, [NZ, N_LABELS]), &device),
            Self::float_from_data(TensorData::new(gr, [n, 1]), &device),
        )
    }
}

/// The CPU reads its tensors in place (a copy only where one is not contiguous f32).
impl HeadOps for Flex {
    fn head(splat: FloatTensor<Self>, bias: FloatTensor<Self>, r: FloatTensor<Self>) -> FloatTensor<Self> {
        let shape = splat.shape();
        let [s, b, r] = [splat, bias, r].map(|t| flex_f32(&t));
        let out = logits(flex_slice(&s), flex_slice(&b), flex_slice(&r));
        FlexTensor::from_data(TensorData::new(out, shape))
    }

    fn head_gated(
        splat: FloatTensor<Self>,
        bias: FloatTensor<Self>,
        r: FloatTensor<Self>,
    ) -> (FloatTensor<Self>, FloatTensor<Self>) {
        let shape = splat.shape();
        let [s, b, r] = [splat, bias, r].map(|t| flex_f32(&t));
        let (out, gates) = logits_and_gate(flex_slice(&s), flex_slice(&b), flex_slice(&r));
        let n = gates.len();
        (FlexTensor::from_data(TensorData::new(out, shape)), FlexTensor::from_data(TensorData::new(gates, [n])))
    }

    fn head_backward(gates: FloatTensor<Self>, grad: FloatTensor<Self>) -> (FloatTensor<Self>, FloatTensor<Self>) {
        let [gates, grad] = [gates, grad].map(|t| flex_f32(&t));
        let (gb, gr) = backward(flex_slice(&gates), flex_slice(&grad));
        let n = gr.len();
        (FlexTensor::from_data(TensorData::new(gb, [NZ, N_LABELS])), FlexTensor::from_data(TensorData::new(gr, [n, 1])))
    }
}

#[cfg(any(feature = "wgpu", feature = "cuda"))]
impl HeadOps for burn_cubecl::CubeBackend {}

#[derive(Debug)]
struct HeadBackward;

impl<B: Backend + HeadOps> Backward<B, 3> for HeadBackward {
    /// Each voxel's gate.
    type State = FloatTensor<B>;

    fn backward(self, ops: Ops<Self::State, 3>, grads: &mut Gradients, _checkpointer: &mut Checkpointer) {
        let [node_splat, node_bias, node_r] = ops.parents;
        let grad = grads.consume::<B>(&ops.node);
        if node_bias.is_some() || node_r.is_some() {
            let (gb, gr) = B::head_backward(ops.state, grad.clone());
            if let Some(node) = node_bias {
                grads.register::<B>(node.id, gb);
            }
            if let Some(node) = node_r {
                grads.register::<B>(node.id, gr);
            }
        }
        if let Some(node) = node_splat {
            grads.register::<B>(node.id, grad);
        }
    }
}

impl<B: Backend + HeadOps, C: CheckpointStrategy> HeadOps for Autodiff<B, C> {
    fn head(splat: FloatTensor<Self>, bias: FloatTensor<Self>, r: FloatTensor<Self>) -> FloatTensor<Self> {
        match HeadBackward.prepare::<C>([splat.node(), bias.node(), r.node()]).compute_bound().stateful() {
            OpsKind::Tracked(prep) => {
                let (s, b, r) = (splat.into_primitive(), bias.into_primitive(), r.into_primitive());
                let (out, gates) = B::head_gated(s, b, r);
                prep.finish(gates, out)
            }
            OpsKind::UnTracked(prep) => {
                prep.finish(B::head(splat.into_primitive(), bias.into_primitive(), r.into_primitive()))
            }
        }
    }

    fn head_gated(
        splat: FloatTensor<Self>,
        bias: FloatTensor<Self>,
        r: FloatTensor<Self>,
    ) -> (FloatTensor<Self>, FloatTensor<Self>) {
        let (out, gates) = B::head_gated(Self::inner(splat), Self::inner(bias), Self::inner(r));
        (Self::from_inner(out), Self::from_inner(gates))
    }

    fn head_backward(gates: FloatTensor<Self>, grad: FloatTensor<Self>) -> (FloatTensor<Self>, FloatTensor<Self>) {
        let (gb, gr) = B::head_backward(Self::inner(gates), Self::inner(grad));
        (Self::from_inner(gb), Self::from_inner(gr))
    }
}

/// The generator's logits `[V, 9]` from the splat `[V, 9]`, the layer bias `[NZ, 9]` and the
/// background residual of each voxel `[V, 1]`, through `HeadOps`.
pub fn head(splat: Tensor<2>, bias: Tensor<2>, r: Tensor<2>) -> Tensor<2> {
    let out = <Dispatch as HeadOps>::head(splat.into_dispatch(), bias.into_dispatch(), r.into_dispatch());
    Tensor::from_dispatch(out)
}

/// `head` written with tensor operations (a GPU runs this; the reference of the test).
pub fn head_tensor_ops(splat: Tensor<2>, bias: Tensor<2>, r: Tensor<2>) -> Tensor<2> {
    let device = splat.device();
    let nv = splat.dims()[0];
    let cols = nv / NZ;
    let logits = splat + super::rows::repeat_rows(bias.reshape([1, NZ * N_LABELS]), cols).reshape([nv, N_LABELS]);
    // Gate: the residual only acts where free or background already dominate, and it moves
    // mass from free to background, never touching the agent channels.
    let p = burn::tensor::activation::softmax(logits.clone().detach(), 1);
    let gate = p.slice([0..nv, 0..2]).sum_dim(1);
    let rr = r * gate;
    let delta = Tensor::cat(vec![rr.clone().neg(), rr, Tensor::zeros([nv, N_LABELS - 2], &device)], 1);
    logits + delta
}
