//! The decoder's transformer, in full or mixed precision, over several sets of latents at once
//! (`Sets`). Its layer is burn's `TransformerEncoderLayer::forward` written out (bit for bit
//! burn's on one padded batch, a test checks), so that the row-wise layers run once over every
//! set's rows and the attention within each set. Mixed precision (`--precision mixed`, meant
//! for GPUs with tensor cores) runs every matrix product of the transformer — the projections,
//! the attention's scores and weighted sums, the feed-forward — on half-precision (f16) operands
//! with f32 accumulation; the norms, the softmax, the activation and the residual sums stay in
//! f32 (what PyTorch's autocast does).
//!
//! Half precision cannot hold the small gradients that reach the transformer (its smallest
//! normal number is 6.1e-5), so the gradient is scaled up by `GradScale` where it enters each
//! half-precision region and back down where it leaves it (into the f32 activations and
//! weights). An overflow (a non-finite gradient) skips the step and halves the scale; a run of
//! clean steps doubles it again: PyTorch's `GradScaler` policy, applied to these regions.

use burn::nn::Linear;
use burn::nn::activation::Activation;
use burn::nn::attention::MultiHeadAttention;
use burn::nn::transformer::PositionWiseFeedForward;
use burn::nn::transformer::{TransformerEncoder, TransformerEncoderLayer};
use burn::prelude::*;
use burn::tensor::FloatDType;
use burn::tensor::activation::{quiet_softmax, softmax};
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

/// Where the decoder's transformer computes its matrix products.
#[derive(Clone, Debug, Default)]
pub enum Precision {
    /// Everything in f32: the operations of burn's transformer.
    #[default]
    Full,
    /// The transformer's products on f16 operands, with the gradient scale they share.
    Mixed(GradScale),
}

impl std::str::FromStr for Precision {
    type Err = String;

    /// `full` or `mixed` (the command line's words).
    fn from_str(word: &str) -> Result<Self, String> {
        match word {
            "full" | "f32" => Ok(Precision::Full),
            "mixed" | "f16" => Ok(Precision::Mixed(GradScale::default())),
            _ => Err(format!("unknown precision `{word}` (expected full or mixed)")),
        }
    }
}

impl Precision {
    pub fn name(&self) -> &'static str {
        match self {
            Precision::Full => "full",
            Precision::Mixed(_) => "mixed",
        }
    }
}

/// Whether `precision` can run on `device` (the device already probed): E0914 for mixed precision
/// on the CPU, or on a GPU that fails a first half-precision product.
pub fn check(precision: &Precision, device: &Device) -> Result<(), crate::diag::Diagnostic> {
    use crate::diag::Diagnostic;
    if matches!(precision, Precision::Full) {
        return Ok(());
    }
    let refuse = |why: String| {
        Diagnostic::error("E0914", why).help("use `--precision full` (the default): everything in f32, on any device")
    };
    if *device == Device::flex() {
        return Err(refuse("mixed precision is for GPUs: the CPU has no fast half-precision products".into()));
    }
    super::guard::guarded(|| {
        let t =
            Tensor::<2>::from_data(TensorData::new(vec![1.0f32, 2.0, 3.0, 4.0], [2, 2]), device).cast(FloatDType::F16);
        t.clone().matmul(t).cast(FloatDType::F32).to_data()
    })
    .map(|_| ())
    .map_err(|d| refuse(format!("this device cannot compute in half precision: {}", d.message)))
}

/// The gradient scale of the half-precision regions (a power of two, so scaling is exact),
/// shared by every clone of the model the training loop makes.
#[derive(Clone, Debug)]
pub struct GradScale(Arc<ScaleState>);

#[derive(Debug)]
struct ScaleState {
    log2: AtomicU32,
    clean: AtomicU64,
    skipped: AtomicU64,
}

/// Starting scale 2^16 (PyTorch's), kept within 2^0..2^24; doubled after this many clean steps.
const START_LOG2: u32 = 16;
const MAX_LOG2: u32 = 24;
const GROWTH_STEPS: u64 = 1000;

impl Default for GradScale {
    fn default() -> Self {
        GradScale(Arc::new(ScaleState {
            log2: AtomicU32::new(START_LOG2),
            clean: AtomicU64::new(0),
            skipped: AtomicU64::new(0),
        }))
    }
}

impl GradScale {
    /// A scale starting at 2^`log2` instead of 2^16 (tests).
    pub fn starting_at(log2: u32) -> Self {
        let s = GradScale::default();
        s.0.log2.store(log2.min(60), Ordering::Relaxed);
        s
    }

    /// The current scale.
    pub fn value(&self) -> f32 {
        (1u64 << self.0.log2.load(Ordering::Relaxed)) as f32
    }

    /// Steps skipped so far for a non-finite gradient.
    pub fn skipped(&self) -> u64 {
        self.0.skipped.load(Ordering::Relaxed)
    }

    /// After a step's backward pass: whether its gradient is finite (take the step) or not (skip
    /// it; the scale halves).
    pub fn after_backward(&self, finite: bool) -> bool {
        let s = &self.0;
        if finite {
            if s.clean.fetch_add(1, Ordering::Relaxed) + 1 >= GROWTH_STEPS {
                s.clean.store(0, Ordering::Relaxed);
                let l = s.log2.load(Ordering::Relaxed);
                s.log2.store((l + 1).min(MAX_LOG2), Ordering::Relaxed);
            }
        } else {
            s.clean.store(0, Ordering::Relaxed);
            s.skipped.fetch_add(1, Ordering::Relaxed);
            let l = s.log2.load(Ordering::Relaxed);
            s.log2.store(l.saturating_sub(1), Ordering::Relaxed);
        }
        finite
    }
}

/// `t` unchanged, with its gradient multiplied by `k` (a power of two) on the way back: the
/// forward adds `t * k - t * k`, which is exactly zero.
fn grad_times<const D: usize>(t: Tensor<D>, k: f32) -> Tensor<D> {
    if !t.is_tracked() {
        return t;
    }
    let scaled = t.clone() * k;
    t.detach() + (scaled.clone() - scaled.detach())
}

/// The sets of latents a transformer pass attends within. Every layer but the attention works
/// row by row, so it runs once over all rows; the attention's scores, softmax and weighted sums
/// stay within each set.
pub struct Sets {
    /// Each set's rows of `x` along its second axis, and its key mask `[b, len]` (true: not a
    /// latent) where it has padding.
    groups: Vec<(std::ops::Range<usize>, Option<Tensor<2, Bool>>)>,
}

impl Sets {
    /// `x` `[b, n, width]`: each of the `b` rows one set, its padded latents masked by `pad`
    /// `[b, n]`.
    pub fn padded(pad: Tensor<2, Bool>) -> Self {
        Sets { groups: vec![(0..pad.dims()[1], Some(pad))] }
    }

    /// `x` `[1, N, width]`: sets of `lens` rows one after another, no padding.
    pub fn ragged(lens: &[usize]) -> Self {
        Sets { groups: starts(lens).into_iter().zip(lens).map(|(start, &len)| (start..start + len, None)).collect() }
    }

    /// `f(q, k, v, mask)` per set, the results in the sets' order along the second axis.
    fn each(
        &self,
        q: Tensor<3>,
        k: Tensor<3>,
        v: Tensor<3>,
        f: impl Fn(Tensor<3>, Tensor<3>, Tensor<3>, Option<&Tensor<2, Bool>>) -> Tensor<3>,
    ) -> Tensor<3> {
        let [b, n, w] = q.dims();
        if let [(rows, mask)] = self.groups.as_slice()
            && *rows == (0..n)
        {
            return f(q, k, v, mask.as_ref());
        }
        let part = |t: &Tensor<3>, r: &std::ops::Range<usize>| t.clone().slice([0..b, r.clone(), 0..w]);
        let out = self.groups.iter().map(|(r, mask)| f(part(&q, r), part(&k, r), part(&v, r), mask.as_ref()));
        Tensor::cat(out.collect(), 1)
    }
}

/// Where each of sets of `lens` rows starts when they lie one after another.
pub fn starts(lens: &[usize]) -> Vec<usize> {
    lens.iter()
        .scan(0, |s, &len| {
            *s += len;
            Some(*s - len)
        })
        .collect()
}

/// The transformer over `x` (its sets as `sets` lays them out).
pub fn encode(t: &TransformerEncoder, x: Tensor<3>, sets: &Sets, precision: &Precision) -> Tensor<3> {
    let half = match precision {
        Precision::Full => None,
        Precision::Mixed(scale) => Some(scale.value()),
    };
    t.layers.iter().fold(x, |x, l| layer(l, x, sets, half))
}

/// One encoder layer, laid out as burn's `TransformerEncoderLayer::forward` (so the two share
/// parameters and checkpoints); `half` = the gradient scale of the half-precision region, `None`
/// for f32.
fn layer(l: &TransformerEncoderLayer, x: Tensor<3>, sets: &Sets, half: Option<f32>) -> Tensor<3> {
    let r = if l.norm_first { l.norm_2.forward(x.clone()) } else { x.clone() };
    let mut x = x + l.dropout.forward(self_attention(&l.mha, r, sets, half));
    let r = if l.norm_first {
        l.norm_1.forward(x.clone())
    } else {
        x = l.norm_1.forward(x);
        x.clone()
    };
    let ff = match half {
        None => feed_forward(&l.pwff, r),
        Some(scale) => {
            let h = Half(scale);
            let p = &l.pwff;
            // The activation in f32 between the two f16 products (inside the region: plain casts).
            let inner = h.linear(&p.linear_inner, h.into(r)).cast(FloatDType::F32);
            let inner = p.dropout.forward(p.activation.forward(inner)).cast(FloatDType::F16);
            h.out(h.linear(&p.linear_outer, inner))
        }
    };
    let x = x + l.dropout.forward(ff);
    if l.norm_first { x } else { l.norm_2.forward(x) }
}

/// burn's `PositionWiseFeedForward::forward`, its exact GELU through `gelu::gelu` (the same bits
/// untracked; on all cores in a CPU training step).
fn feed_forward(p: &PositionWiseFeedForward, x: Tensor<3>) -> Tensor<3> {
    match &p.activation {
        Activation::Gelu(g) if !g.approximate => {
            p.linear_outer.forward(p.dropout.forward(super::gelu::gelu(p.linear_inner.forward(x))))
        }
        _ => p.forward(x),
    }
}

/// The half-precision region with gradient scale `.0`: what enters it (activations, weights)
/// is cast to f16 with its gradient scaled back down on the way out; what leaves it is cast to
/// f32 with the gradient scaled up on the way in.
#[derive(Clone, Copy)]
struct Half(f32);

impl Half {
    fn into<const D: usize>(self, t: Tensor<D>) -> Tensor<D> {
        grad_times(t, 1.0 / self.0).cast(FloatDType::F16)
    }

    fn out<const D: usize>(self, t: Tensor<D>) -> Tensor<D> {
        grad_times(t.cast(FloatDType::F32), self.0)
    }

    /// `lin` on an f16 input, its weight and bias brought in.
    fn linear<const D: usize>(self, lin: &Linear, x: Tensor<D>) -> Tensor<D> {
        burn::tensor::module::linear(x, self.into(lin.weight.val()), lin.bias.as_ref().map(|b| self.into(b.val())))
    }
}

fn self_attention(m: &MultiHeadAttention, x: Tensor<3>, sets: &Sets, half: Option<f32>) -> Tensor<3> {
    let [b, _, width] = x.dims();
    // The softmax (and the mask before it) in f32 in both precisions; `scale` divides the
    // scores first.
    let weights = |scores: Tensor<4>, pad: Option<&Tensor<2, Bool>>, scale: Option<f32>| {
        let n = scores.dims()[3];
        let fused = (!m.quiet_softmax)
            .then(|| super::softmax::attention_weights(&scores, pad, scale.unwrap_or(1.0), m.min_float as f32))
            .flatten();
        let w = fused.unwrap_or_else(|| {
            let s = match scale {
                Some(k) => scores.div_scalar(k),
                None => scores,
            };
            let s = match pad {
                Some(pad) => s.mask_fill(pad.clone().reshape([b, 1, 1, n]), m.min_float),
                None => s,
            };
            if m.quiet_softmax { quiet_softmax(s, 3) } else { softmax(s, 3) }
        });
        m.dropout.forward(w)
    };
    let scale = (m.d_k as f32).sqrt();
    // One set's queries, keys and values `[b, n, width]` -> its context `[b, n, width]`.
    let attend = |q: Tensor<3>, k: Tensor<3>, v: Tensor<3>, pad: Option<&Tensor<2, Bool>>| {
        let n = q.dims()[1];
        let split = |t: Tensor<3>| t.reshape([b, n, m.n_heads, m.d_k]).swap_dims(1, 2);
        let (q, kt, v) = (split(q), split(k).transpose(), split(v));
        let rows = query_rows(b * m.n_heads, n, &q.device());
        let context = by_query_rows(q, rows, |q| match half {
            None => weights(q.matmul(kt.clone()), pad, Some(scale)).matmul(v.clone()),
            Some(_) => {
                let scores = q.div_scalar(scale).matmul(kt.clone()).cast(FloatDType::F32);
                weights(scores, pad, None).cast(FloatDType::F16).matmul(v.clone())
            }
        });
        context.swap_dims(1, 2).reshape([b, n, width])
    };
    match half {
        None => {
            let (q, k, v) = (m.query.forward(x.clone()), m.key.forward(x.clone()), m.value.forward(x));
            m.output.forward(sets.each(q, k, v, attend))
        }
        Some(s) => {
            let h = Half(s);
            let x = h.into(x);
            let (q, k, v) = (h.linear(&m.query, x.clone()), h.linear(&m.key, x.clone()), h.linear(&m.value, x));
            h.out(h.linear(&m.output, sets.each(q, k, v, attend)))
        }
    }
}

/// Query rows per block of `n` keys over `sets` (sets x heads), such that a block's f32 scores
/// fit the device's largest buffer (`strips::fitting`): `n` where the whole square fits.
fn query_rows(sets: usize, n: usize, device: &Device) -> usize {
    super::strips::fitting(super::device::largest_buffer(device), sets.max(1) * n.max(1) * 4, n)
}

/// `attend` (queries `[b, heads, rows, d]` -> their context) over blocks of `rows` queries,
/// concatenated: each query's scores, softmax and weighted sum are its own, so the blocks give
/// what one pass gives; a device whose buffers cannot hold a set's whole score matrix (`paper`:
/// 6 heads x 4096^2 in f32, 403 MB) runs it block by block.
fn by_query_rows(q: Tensor<4>, rows: usize, attend: impl Fn(Tensor<4>) -> Tensor<4>) -> Tensor<4> {
    let [b, h, n, d] = q.dims();
    if rows >= n {
        return attend(q);
    }
    let blocks = (0..n).step_by(rows.max(1)).map(|s| attend(q.clone().slice([0..b, 0..h, s..(s + rows).min(n), 0..d])));
    Tensor::cat(blocks.collect(), 2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::nn::transformer::{TransformerEncoderConfig, TransformerEncoderInput};

    fn input(device: &Device, b: usize, n: usize, w: usize) -> (Tensor<3>, Tensor<2, Bool>) {
        let x: Vec<f32> =
            (0..b * n * w).map(|i| ((i as u32).wrapping_mul(2654435761) % 2000) as f32 / 1000.0 - 1.0).collect();
        let pad: Vec<bool> = (0..b * n).map(|i| i % n >= n - 1 - (i / n)).collect();
        (
            Tensor::from_data(TensorData::new(x, [b, n, w]), device),
            Tensor::from_data(TensorData::new(pad, [b, n]), device),
        )
    }

    fn vec<const D: usize>(t: Tensor<D>) -> Vec<f32> {
        t.into_data().convert::<f32>().try_to_vec().unwrap()
    }

    #[test]
    fn the_layer_here_is_burns_layer_bit_for_bit() {
        let device = super::super::cpu();
        for norm_first in [true, false] {
            let t =
                TransformerEncoderConfig::new(16, 32, 4, 2).with_dropout(0.0).with_norm_first(norm_first).init(&device);
            let (x, pad) = input(&device, 2, 7, 16);
            let burn = t.forward(TransformerEncoderInput::new(x.clone()).mask_pad(pad.clone()));
            let here = t.layers.iter().fold(x, |x, l| layer(l, x, &Sets::padded(pad.clone()), None));
            assert_eq!(vec(burn), vec(here), "norm_first {norm_first}");
        }
    }

    /// Values and gradients of `encode` in `precision`, for an upstream gradient as small as a
    /// training step's (1e-6 per element).
    fn run(t: &TransformerEncoder, precision: &Precision) -> (Vec<f32>, Vec<f32>, Vec<f32>, Vec<f32>) {
        run_with(t, |x, pad| encode(t, x, &Sets::padded(pad), precision))
    }

    /// `run` through `forward`.
    fn run_with(
        t: &TransformerEncoder,
        forward: impl Fn(Tensor<3>, Tensor<2, Bool>) -> Tensor<3>,
    ) -> (Vec<f32>, Vec<f32>, Vec<f32>, Vec<f32>) {
        let device = super::super::cpu().autodiff();
        let (x, pad) = input(&device, 2, 9, 32);
        let x = x.require_grad();
        let y = forward(x.clone(), pad);
        let w = y.clone().detach().cos() * 1e-6;
        let grads = (y.clone() * w).sum().backward();
        let gx = x.grad(&grads).unwrap();
        let gw = t.layers[0].mha.key.weight.val().grad(&grads).unwrap();
        let gf = t.layers[0].pwff.linear_inner.weight.val().grad(&grads).unwrap();
        (vec(y), vec(gx), vec(gw), vec(gf))
    }

    fn rel(a: &[f32], b: &[f32]) -> f32 {
        let scale = b.iter().fold(0f32, |m, v| m.max(v.abs()));
        a.iter().zip(b).fold(0f32, |m, (x, y)| m.max((x - y).abs())) / scale
    }

    /// The decoder's transformer at width 32, two blocks, weights drawn with `seed`.
    fn transformer(seed: u64) -> TransformerEncoder {
        let device = super::super::cpu().autodiff();
        device.seed(seed);
        TransformerEncoderConfig::new(32, 64, 4, 2).with_dropout(0.0).with_norm_first(true).init(&device)
    }

    /// A training step on the CPU (the layers here, with `softmax::attention_weights`) follows
    /// burn's transformer in values and gradients, to float rounding.
    #[test]
    fn full_precision_training_follows_burns_transformer() {
        let t = transformer(3);
        let (y, gx, gw, gf) = run(&t, &Precision::Full);
        let (yb, gxb, gwb, gfb) = run_with(&t, |x, pad| t.forward(TransformerEncoderInput::new(x).mask_pad(pad)));
        assert!(rel(&y, &yb) < 1e-5);
        assert!(rel(&gx, &gxb) < 1e-4 && rel(&gw, &gwb) < 1e-4 && rel(&gf, &gfb) < 1e-4);
        assert!(gw != gwb || gx != gxb, "the fused path ran (its rounding differs from burn's somewhere)");
    }

    #[test]
    fn mixed_precision_follows_full_precision_in_values_and_gradients() {
        let t = transformer(7);
        let (y, gx, gw, gf) = run(&t, &Precision::Full);
        let (ym, gxm, gwm, gfm) = run(&t, &Precision::Mixed(GradScale::default()));
        // f16 operands carry 11 bits: values and gradients within about 1e-3 of the largest
        // (4e-4 and 8e-4 with this seed).
        assert!(rel(&ym, &y) < 2e-3, "values {}", rel(&ym, &y));
        assert!(rel(&gxm, &gx) < 5e-3, "input gradient {}", rel(&gxm, &gx));
        assert!(rel(&gwm, &gw) < 5e-3, "key weight gradient {}", rel(&gwm, &gw));
        assert!(rel(&gfm, &gf) < 5e-3, "feed-forward weight gradient {}", rel(&gfm, &gf));
        assert!(gw.iter().any(|g| g.abs() > 1e-8));
        // Without the scale the gradients drown in f16's subnormals: the scale is what keeps them.
        let (_, _, gw1, _) = run(&t, &Precision::Mixed(GradScale::starting_at(0)));
        assert!(rel(&gw1, &gw) > 10.0 * rel(&gwm, &gw), "{} vs {}", rel(&gw1, &gw), rel(&gwm, &gw));
    }

    /// Sets laid one after another (`Sets::ragged`, the decoder's batch) give each set's values
    /// and input gradients alone, and the weights' gradients summed over the sets, in both
    /// precisions.
    #[test]
    fn ragged_sets_give_each_set_alone() {
        let t = transformer(5);
        let device = super::super::cpu().autodiff();
        let lens = [5, 9, 1];
        let mask = |n: usize| Tensor::<2, Bool>::from_data(TensorData::new(vec![false; n], [1, n]), &device);
        let (x, _) = input(&device, 1, 15, 32);
        let w = x.clone().cos() * 1e-3;
        let run = |x: Tensor<3>, w: Tensor<3>, sets: &Sets, precision: &Precision| {
            let x = x.require_grad();
            let y = encode(&t, x.clone(), sets, precision);
            let grads = (y.clone() * w).sum().backward();
            let gw = t.layers[1].mha.value.weight.val().grad(&grads).unwrap();
            (vec(y), vec(x.grad(&grads).unwrap()), vec(gw))
        };
        for precision in [Precision::Full, Precision::Mixed(GradScale::default())] {
            let (y, gx, gw) = run(x.clone(), w.clone(), &Sets::ragged(&lens), &precision);
            let (mut y1, mut gx1, mut gw1) = (Vec::new(), Vec::new(), vec![0f32; gw.len()]);
            let mut start = 0;
            for n in lens {
                let part = |t: &Tensor<3>| t.clone().slice([0..1, start..start + n]);
                let (y, gx, gw) = run(part(&x), part(&w), &Sets::padded(mask(n)), &precision);
                y1.extend(y);
                gx1.extend(gx);
                gw1.iter_mut().zip(gw).for_each(|(a, b)| *a += b);
                start += n;
            }
            // f16 operands: the products' rounding depends on the matrix's size at 11 bits.
            let (what, tol) = match precision {
                Precision::Full => ("full", 1e-5),
                Precision::Mixed(_) => ("mixed", 3e-3),
            };
            assert!(rel(&y, &y1) < tol, "{what}: values differ by {}", rel(&y, &y1));
            assert!(rel(&gx, &gx1) < tol, "{what}: input gradients differ by {}", rel(&gx, &gx1));
            assert!(rel(&gw, &gw1) < tol, "{what}: weight gradients differ by {}", rel(&gw, &gw1));
            // Attention across sets would change the first set's values by far more.
            let (whole, _, _) = run(x.clone(), w.clone(), &Sets::padded(mask(15)), &precision);
            assert!(rel(&whole, &y1) > 10.0 * tol, "{what}: one set of all rows is not the three sets");
        }
    }

    #[test]
    fn the_gradient_scale_halves_on_overflow_and_grows_back() {
        let s = GradScale::default();
        assert_eq!(s.value(), 65536.0);
        assert!(!s.after_backward(false));
        assert_eq!((s.value(), s.skipped()), (32768.0, 1));
        for _ in 0..GROWTH_STEPS {
            assert!(s.after_backward(true));
        }
        assert_eq!(s.value(), 65536.0);
        // Clones share the scale (the training loop's model is rebuilt every step).
        let c = s.clone();
        c.after_backward(false);
        assert_eq!(s.value(), 32768.0);
    }

    #[test]
    fn grad_times_keeps_values_and_scales_the_gradient() {
        let device = super::super::cpu().autodiff();
        let x = Tensor::<1>::from_data(TensorData::new(vec![0.3f32, -1e-7, 5.0, 0.0], [4]), &device).require_grad();
        let y = grad_times(x.clone(), 1024.0);
        assert_eq!(vec(y.clone()), vec(x.clone()));
        let g = x.grad(&(y * 2.0).sum().backward()).unwrap();
        assert_eq!(vec(g), vec![2048.0; 4]);
    }

    /// Attention by blocks of query rows gives the values and gradients of one pass over the
    /// whole score matrix (padded keys masked, as the decoder's sets are).
    #[test]
    fn query_blocks_give_the_whole_matrix_values_and_gradients() {
        let device = super::super::cpu().autodiff();
        let (b, h, n, d) = (2, 3, 11, 4);
        let t = |salt: u32| {
            let v: Vec<f32> = (0..b * h * n * d)
                .map(|i| ((i as u32 + salt).wrapping_mul(2654435761) % 2000) as f32 / 1000.0 - 1.0)
                .collect();
            Tensor::<4>::from_data(TensorData::new(v, [b, h, n, d]), &device).require_grad()
        };
        let (q, k, v) = (t(1), t(2), t(3));
        let pad: Vec<bool> = (0..b * n).map(|i| i % n >= n - 2 * (i / n) - 1).collect();
        let pad = Tensor::<2, Bool>::from_data(TensorData::new(pad, [b, n]), &device).reshape([b, 1, 1, n]);
        let attend =
            |q: Tensor<4>| softmax(q.matmul(k.clone().transpose()).mask_fill(pad.clone(), -1e9), 3).matmul(v.clone());
        let w = t(4).detach();
        let run = |rows: usize| {
            let out = by_query_rows(q.clone(), rows, attend);
            let grads = (out.clone() * w.clone()).sum().backward();
            let g = |x: &Tensor<4>| vec(x.grad(&grads).expect("a gradient"));
            (vec(out), g(&q), g(&k), g(&v))
        };
        let whole = run(n);
        for rows in [1, 3, 5] {
            let blocks = run(rows);
            for (name, a, e) in [
                ("values", &blocks.0, &whole.0),
                ("dq", &blocks.1, &whole.1),
                ("dk", &blocks.2, &whole.2),
                ("dv", &blocks.3, &whole.3),
            ] {
                let err = a.iter().zip(e).fold(0f32, |m, (x, y)| m.max((x - y).abs()));
                assert!(err < 1e-6, "{rows} rows: {name} differ by {err}");
            }
        }
        assert!(whole.2.iter().any(|x| x.abs() > 1e-3), "the key gradient would prove little");
    }
}
