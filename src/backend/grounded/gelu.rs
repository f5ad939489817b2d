//! GELU for a training step on the CPU: the BEV encoder's activations (2.6 M values per
//! `cpu-small` step, forward and backward). burn's CPU GELU calls libm's `erff` one value at a
//! time on the calling thread: a tenth of a step while the other cores wait. Here Phi(x) comes
//! from Numerical Recipes' erfc (`t exp(-z^2 + P(t))`, relative error under 1.2e-7) with
//! `expf`'s exponential: no table or branch, so a loop runs several lanes at once, on all cores.
//! Within 2e-6 of the exact function (relative, or absolute near zero; this file's tests).
//! Inference keeps burn's GELU (`GeluOps::bev_gelu` untracked), so its labels keep their bits;
//! a GPU keeps burn's throughout.

use super::expf::exp;
use super::host_read::{flex_f32, flex_slice};
use super::par::par_vec;
use burn::backend::autodiff::checkpoint::{base::Checkpointer, strategy::CheckpointStrategy};
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind, unary};
use burn::backend::flex::FlexTensor;
use burn::backend::ops::ActivationOps;
use burn::backend::tensor::FloatTensor;
use burn::backend::{Autodiff, AutodiffBackend, Backend, DType, Dispatch, Flex, TensorMetadata, backend_extension};
use burn::prelude::*;

#[backend_extension(Flex, Cube: cfg(any(feature = "wgpu", feature = "cuda")), Autodiff)]
pub trait GeluOps: burn::backend::Backend {
    /// burn's GELU (what inference runs).
    fn bev_gelu(x: FloatTensor<Self>) -> FloatTensor<Self> {
        <Self as ActivationOps<Self>>::gelu(x)
    }

    /// GELU for a training step (the autodiff graph tracks it).
    fn bev_gelu_train(x: FloatTensor<Self>) -> FloatTensor<Self> {
        Self::bev_gelu(x)
    }

    /// The input's gradient from the input and the output's gradient.
    fn bev_gelu_backward(x: FloatTensor<Self>, grad: FloatTensor<Self>) -> FloatTensor<Self> {
        <Self as ActivationOps<Self>>::gelu_backward(x, grad)
    }
}

impl GeluOps for Flex {
    fn bev_gelu_train(x: FloatTensor<Self>) -> FloatTensor<Self> {
        if x.dtype() != DType::F32 {
            return Self::bev_gelu(x);
        }
        let shape = x.shape();
        let x = flex_f32(&x);
        let xs = flex_slice(&x);
        let y = par_vec(xs.len(), |start, part| gelu_slice(&xs[start..start + part.len()], part));
        FlexTensor::from_data(TensorData::new(y, shape))
    }

    fn bev_gelu_backward(x: FloatTensor<Self>, grad: FloatTensor<Self>) -> FloatTensor<Self> {
        if x.dtype() != DType::F32 || grad.dtype() != DType::F32 || x.shape() != grad.shape() {
            return <Self as ActivationOps<Self>>::gelu_backward(x, grad);
        }
        let shape = x.shape();
        let (x, grad) = (flex_f32(&x), flex_f32(&grad));
        let (xs, gs) = (flex_slice(&x), flex_slice(&grad));
        let out = par_vec(xs.len(), |start, part| {
            let end = start + part.len();
            gelu_grad_slice(&xs[start..end], &gs[start..end], part)
        });
        FlexTensor::from_data(TensorData::new(out, shape))
    }
}

#[cfg(any(feature = "wgpu", feature = "cuda"))]
impl GeluOps for burn_cubecl::CubeBackend {}

#[derive(Debug)]
struct GeluBackward;

impl<B: Backend + GeluOps> Backward<B, 1> for GeluBackward {
    /// The input.
    type State = FloatTensor<B>;

    fn backward(self, ops: Ops<Self::State, 1>, grads: &mut Gradients, _checkpointer: &mut Checkpointer) {
        let x = ops.state;
        unary::<B, _>(ops.parents, ops.node, grads, |grad| B::bev_gelu_backward(x, grad));
    }
}

impl<B: Backend + GeluOps, C: CheckpointStrategy> GeluOps for Autodiff<B, C> {
    fn bev_gelu(x: FloatTensor<Self>) -> FloatTensor<Self> {
        match GeluBackward.prepare::<C>([x.node()]).compute_bound().stateful() {
            OpsKind::Tracked(prep) => {
                let xi = x.primitive().clone();
                let out = B::bev_gelu_train(xi.clone());
                prep.finish(xi, out)
            }
            OpsKind::UnTracked(prep) => prep.finish(B::bev_gelu(x.into_primitive())),
        }
    }

    fn bev_gelu_train(x: FloatTensor<Self>) -> FloatTensor<Self> {
        Self::from_inner(B::bev_gelu_train(Self::inner(x)))
    }

    fn bev_gelu_backward(x: FloatTensor<Self>, grad: FloatTensor<Self>) -> FloatTensor<Self> {
        Self::from_inner(B::bev_gelu_backward(Self::inner(x), Self::inner(grad)))
    }
}

/// GELU through `GeluOps` on the CPU; burn's elsewhere (a GPU's fused queue has no place for a
/// backend extension).
pub fn gelu<const D: usize>(x: Tensor<D>) -> Tensor<D> {
    if x.device() != Device::flex() {
        return burn::tensor::activation::gelu(x);
    }
    Tensor::from_dispatch(<Dispatch as GeluOps>::bev_gelu(x.into_dispatch()))
}

const FRAC_1_SQRT_2: f32 = std::f32::consts::FRAC_1_SQRT_2;
/// 1 / sqrt(2 pi).
const INV_SQRT_2PI: f32 = 0.398_942_3;

/// Numerical Recipes' `erfcc` exponent: erfc(z) = t exp(-z^2 + p(t)), t = 1 / (1 + z / 2).
#[inline(always)]
fn erfc_poly(t: f32) -> f32 {
    let mut p = 0.170_872_77f32;
    p = p * t - 0.822_152_23;
    p = p * t + 1.488_515_9;
    p = p * t - 1.135_204;
    p = p * t + 0.278_868_07;
    p = p * t - 0.186_288_06;
    p = p * t + 0.096_784_18;
    p = p * t + 0.374_091_96;
    p = p * t + 1.000_023_7;
    p * t - 1.265_512_2
}

/// Phi(x), the standard normal distribution function.
#[inline(always)]
fn cdf(x: f32) -> f32 {
    let z = x.abs() * FRAC_1_SQRT_2;
    let t = 1.0 / (1.0 + 0.5 * z);
    let tail = 0.5 * t * exp(erfc_poly(t) - z * z);
    if x >= 0.0 { 1.0 - tail } else { tail }
}

/// Phi(x) and the density phi(x).
#[inline(always)]
fn cdf_and_density(x: f32) -> (f32, f32) {
    let z = x.abs() * FRAC_1_SQRT_2;
    let t = 1.0 / (1.0 + 0.5 * z);
    let g = exp(-z * z);
    let tail = 0.5 * t * g * exp(erfc_poly(t));
    (if x >= 0.0 { 1.0 - tail } else { tail }, g * INV_SQRT_2PI)
}

/// `y = x Phi(x)` element by element.
fn gelu_slice(x: &[f32], y: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above: the one requirement of the callee.
        return unsafe { gelu_avx2(x, y) };
    }
    gelu_body(x, y);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn gelu_avx2(x: &[f32], y: &mut [f32]) {
    gelu_body(x, y);
}

#[inline(always)]
fn gelu_body(x: &[f32], y: &mut [f32]) {
    for (y, &x) in y.iter_mut().zip(x) {
        *y = x * cdf(x);
    }
}

/// `out = g (Phi(x) + x phi(x))` element by element.
fn gelu_grad_slice(x: &[f32], g: &[f32], out: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: as in `gelu_slice`.
        return unsafe { gelu_grad_avx2(x, g, out) };
    }
    gelu_grad_body(x, g, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn gelu_grad_avx2(x: &[f32], g: &[f32], out: &mut [f32]) {
    gelu_grad_body(x, g, out);
}

#[inline(always)]
fn gelu_grad_body(x: &[f32], g: &[f32], out: &mut [f32]) {
    for ((o, &x), &g) in out.iter_mut().zip(x).zip(g) {
        let (c, d) = cdf_and_density(x);
        *o = g * (c + x * d);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn density(x: f64) -> f64 {
        (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt()
    }

    /// Phi at `i / 1000` for i in -12000..=12000: Simpson's rule from 0 outward, one panel per
    /// step (about 1e-12 from the exact values).
    fn exact_cdf() -> Vec<f64> {
        let simpson = |a: f64, b: f64| (b - a) / 6.0 * (density(a) + 4.0 * density(0.5 * (a + b)) + density(b));
        let mut up = vec![0.5f64];
        let mut down = vec![0.5f64];
        for i in 1..=12_000 {
            let (a, b) = ((i - 1) as f64 / 1000.0, i as f64 / 1000.0);
            up.push(up[i - 1] + simpson(a, b));
            down.push(down[i - 1] - simpson(-b, -a));
        }
        down.reverse();
        down.pop();
        down.extend(up);
        down
    }

    /// The distance of `got` from `want`, relative where `want` is large and absolute near 0.
    fn err(got: f32, want: f64) -> f64 {
        (got as f64 - want).abs() / want.abs().max(1e-3)
    }

    #[test]
    fn gelu_and_its_derivative_are_within_2e6_of_the_exact_functions() {
        let xs: Vec<f32> = (-12_000..=12_000).map(|i| i as f32 / 1000.0).collect();
        let (mut y, mut d) = (vec![0f32; xs.len()], vec![0f32; xs.len()]);
        gelu_slice(&xs, &mut y);
        gelu_grad_slice(&xs, &vec![1.0; xs.len()], &mut d);
        let (mut worst_y, mut worst_d) = (0f64, 0f64);
        for (((&x, &y), &d), &cdf) in xs.iter().zip(&y).zip(&d).zip(&exact_cdf()) {
            let xd = x as f64;
            worst_y = worst_y.max(err(y, xd * cdf));
            // The two terms cancel near x = -0.75: the error there is measured against their size.
            let (want, size) = (cdf + xd * density(xd), cdf + xd.abs() * density(xd));
            worst_d = worst_d.max((d as f64 - want).abs() / size.max(1e-3));
        }
        assert!(worst_y < 2e-6 && worst_d < 2e-6, "gelu {worst_y:e}, derivative {worst_d:e}");
        // The plain path (no AVX2) gives the same bits as the dispatched one.
        let mut plain = vec![0f32; xs.len()];
        gelu_body(&xs, &mut plain);
        assert!(plain.iter().zip(&y).all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    #[test]
    fn special_values_follow_burns_gelu() {
        let xs = [0.0f32, -0.0, f32::INFINITY, f32::NAN, 1e-30, -1e-30, 40.0, -40.0];
        let mut y = [0f32; 8];
        gelu_slice(&xs, &mut y);
        assert_eq!(y[0], 0.0);
        assert_eq!(y[2], f32::INFINITY);
        assert!(y[3].is_nan());
        assert!((y[4] - 0.5e-30).abs() < 1e-36 && (y[5] + 0.5e-30).abs() < 1e-36);
        assert_eq!(y[6], 40.0);
        assert!(y[7] <= 0.0 && y[7] > -1e-30);
    }
}
