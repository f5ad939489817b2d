//! The BEV encoder's convolutions as one backend operation whose weight gradient the CPU computes
//! as im2col and one matrix product, or, from an input mostly of zeros (the BEV itself, under
//! the first convolution), from its non-zero elements alone; a training step's forward pass over
//! such an input also sums its non-zero elements alone (the same values to float rounding).
//! Inference's forward and the input's gradient are burn's own (`conv2d`, `conv2d_x_backward`):
//! inference logits do not change. burn's CPU weight gradient is a
//! convolution of the input with the output's gradient as the kernel, which at batch 1-4 and up
//! to 16 output channels takes its direct small-channel path: a third of a `cpu-small` training
//! step on the 400 x 400 BEV. A GPU without `fusion` computes the weight gradient as one batched
//! matrix product over the input's patches (`weight_grad_by_patches`) and the bias gradient per
//! plane; with `fusion` it runs burn's own convolution throughout.
//! tests/bev_conv.rs checks the CPU's forward pass and weight gradient against burn's, on dense
//! and sparse inputs;
//! the GPU formulations are checked against burn's on the CPU (this file's tests).

use super::host_read::flex_slice;
use super::par::{par_vec, par_zeroed_parts, par_zeros};
use burn::backend::autodiff::checkpoint::{base::Checkpointer, strategy::CheckpointStrategy};
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind};
use burn::backend::flex::FlexTensor;
use burn::backend::ops::{FloatTensorOps, ModuleOps};
use burn::backend::tensor::FloatTensor;
use burn::backend::{Autodiff, AutodiffBackend, Backend, DType, Dispatch, Flex, TensorMetadata, backend_extension};
use burn::nn::conv::Conv2d;
use burn::prelude::*;
use burn::tensor::ops::ConvOptions;
use rayon::prelude::*;

fn options(stride: usize, padding: usize) -> ConvOptions<2> {
    ConvOptions::new([stride, stride], [padding, padding], [1, 1], 1)
}

#[backend_extension(Flex, Cube: cfg(any(feature = "wgpu", feature = "cuda")), Autodiff)]
pub trait BevConvOps: burn::backend::Backend {
    /// `x` `[B, C, H, W]`, weight `[O, C, kh, kw]`, bias `[O]` -> `[B, O, H', W']`.
    fn bev_conv(
        x: FloatTensor<Self>,
        weight: FloatTensor<Self>,
        bias: FloatTensor<Self>,
        stride: usize,
        padding: usize,
    ) -> FloatTensor<Self> {
        Self::conv2d(x, weight, Some(bias), options(stride, padding))
    }

    /// `bev_conv` for a training step (the autodiff graph tracks it): the same values to float
    /// rounding, where `bev_conv` keeps burn's bits for inference.
    fn bev_conv_train(
        x: FloatTensor<Self>,
        weight: FloatTensor<Self>,
        bias: FloatTensor<Self>,
        stride: usize,
        padding: usize,
    ) -> FloatTensor<Self> {
        Self::bev_conv(x, weight, bias, stride, padding)
    }

    /// The weight's gradient `[O, C, kh, kw]` from the input and the output's gradient.
    fn bev_conv_weight_grad(
        x: FloatTensor<Self>,
        weight: FloatTensor<Self>,
        grad: FloatTensor<Self>,
        stride: usize,
        padding: usize,
    ) -> FloatTensor<Self> {
        Self::conv2d_weight_backward(x, weight, grad, options(stride, padding))
    }

    /// The bias's gradient `[O]` from the output's gradient `[B, O, H', W']`.
    fn bev_conv_bias_grad(grad: FloatTensor<Self>) -> FloatTensor<Self> {
        let [b, o, ho, wo] = grad.shape().dims();
        let g = Self::float_reshape(Self::float_swap_dims(grad, 0, 1), [o, b * ho * wo].into());
        Self::float_reshape(Self::float_sum_dim(g, 1), [o].into())
    }
}

impl BevConvOps for Flex {
    /// An input mostly of zeros (the BEV under the first convolution) sums its non-zero
    /// elements alone (`Im2col::sparse_forward`); anything else runs burn's convolution.
    fn bev_conv_train(
        x: FloatTensor<Self>,
        weight: FloatTensor<Self>,
        bias: FloatTensor<Self>,
        stride: usize,
        padding: usize,
    ) -> FloatTensor<Self> {
        if x.dtype() != DType::F32 || weight.dtype() != DType::F32 || bias.dtype() != DType::F32 {
            return Self::bev_conv(x, weight, bias, stride, padding);
        }
        let x = x.to_contiguous();
        let xs = flex_slice(&x);
        if !mostly_zero(xs) {
            return Self::bev_conv(x, weight, bias, stride, padding);
        }
        let (weight, bias) = (weight.to_contiguous(), bias.to_contiguous());
        let wshape: [usize; 4] = weight.shape().dims();
        let xdims: [usize; 4] = x.shape().dims();
        let along = |n: usize, k: usize| (n + 2 * padding).saturating_sub(k) / stride + 1;
        let out = [along(xdims[2], wshape[2]), along(xdims[3], wshape[3])];
        let cols = Im2col { x: xdims, out, kernel: [wshape[2], wshape[3]], stride, padding };
        let y = cols.sparse_forward(xs, flex_slice(&weight), flex_slice(&bias));
        FlexTensor::from_data(TensorData::new(y, [xdims[0], wshape[0], out[0], out[1]]))
    }

    fn bev_conv_weight_grad(
        x: FloatTensor<Self>,
        weight: FloatTensor<Self>,
        grad: FloatTensor<Self>,
        stride: usize,
        padding: usize,
    ) -> FloatTensor<Self> {
        if x.dtype() != DType::F32 || grad.dtype() != DType::F32 {
            return Self::conv2d_weight_backward(x, weight, grad, options(stride, padding));
        }
        let wshape: [usize; 4] = weight.shape().dims();
        let (x, grad) = (x.to_contiguous(), grad.to_contiguous());
        let xdims: [usize; 4] = x.shape().dims();
        let gdims: [usize; 4] = grad.shape().dims();
        let cols = Im2col { x: xdims, out: [gdims[2], gdims[3]], kernel: [wshape[2], wshape[3]], stride, padding };
        let gt = transposed_grad(flex_slice(&grad), gdims);
        let xs = flex_slice(&x);
        if mostly_zero(xs) {
            return FlexTensor::from_data(TensorData::new(cols.sparse_weight_grad(xs, &gt, gdims[1]), wshape));
        }
        let xcol = cols.build(xs);
        let (k, bp, o) = (cols.rows(), cols.columns(), gdims[1]);
        // [C kh kw, B H' W'] x [B H' W', O]: one matrix product over every output pixel.
        let prod = Self::float_matmul(
            FlexTensor::from_data(TensorData::new(xcol, [k, bp])),
            FlexTensor::from_data(TensorData::new(gt, [bp, o])),
        );
        let prod = prod.to_contiguous();
        let prod = flex_slice(&prod);
        let mut out = vec![0f32; o * k];
        for (r, row) in prod.chunks_exact(o).enumerate() {
            for (oi, &v) in row.iter().enumerate() {
                out[oi * k + r] = v;
            }
        }
        FlexTensor::from_data(TensorData::new(out, wshape))
    }
}

/// On a GPU burn's weight gradient is a direct convolution with one unit per weight, each
/// summing over every output pixel of the batch (0.3 s for the first `paper` layer at batch 6
/// on an H200), and its bias gradient one unit per channel over the same pixels: here the
/// weight gradient is a batched matrix product over the input's patches and the bias gradient
/// sums each frame's channel plane first.
#[cfg(any(feature = "wgpu", feature = "cuda"))]
impl BevConvOps for burn_cubecl::CubeBackend {
    fn bev_conv_weight_grad(
        x: FloatTensor<Self>,
        weight: FloatTensor<Self>,
        grad: FloatTensor<Self>,
        stride: usize,
        padding: usize,
    ) -> FloatTensor<Self> {
        weight_grad_by_patches::<Self>(x, weight.shape().dims(), grad, stride, padding)
    }

    fn bev_conv_bias_grad(grad: FloatTensor<Self>) -> FloatTensor<Self> {
        bias_grad_by_planes::<Self>(grad)
    }
}

/// The bias's gradient, each frame's channel plane (contiguous) summed first.
pub fn bias_grad_by_planes<B: Backend>(grad: FloatTensor<B>) -> FloatTensor<B> {
    let [b, o, ho, wo] = grad.shape().dims();
    let per_frame = B::float_sum_dim(B::float_reshape(grad, [b, o, ho * wo].into()), 2);
    B::float_reshape(B::float_sum_dim(per_frame, 0), [o].into())
}

/// The weight's gradient as one batched matrix product: the output's gradient `[B S, O, P]`
/// times the input's patches `[B S, P, C kh kw]`, summed over the batch, where each frame's
/// output rows are cut into `S` groups of `P` pixels so that the product has enough
/// independent parts to fill a GPU.
pub fn weight_grad_by_patches<B: Backend>(
    x: FloatTensor<B>,
    [o, c, kh, kw]: [usize; 4],
    grad: FloatTensor<B>,
    stride: usize,
    padding: usize,
) -> FloatTensor<B> {
    use burn::tensor::Slice;
    let [b, _, h, w] = x.shape().dims();
    let [_, _, ho, wo] = grad.shape().dims();
    let xp = if padding > 0 {
        let (hp, wp) = (h + 2 * padding, w + 2 * padding);
        let zeros = B::float_zeros([b, c, hp, wp].into(), &x.device(), x.dtype().into());
        let inner = |n: usize| Slice::new(padding as isize, Some((padding + n) as isize), 1);
        B::float_slice_assign(zeros, &[Slice::full(), Slice::full(), inner(h), inner(w)], x)
    } else {
        x
    };
    let groups = (1..=ho.min(16)).rev().find(|d| ho.is_multiple_of(*d)).unwrap_or(1);
    let p = ho / groups * wo;
    let g = B::float_permute(B::float_reshape(grad, [b, o, groups, p].into()), &[0, 2, 1, 3]);
    let g = B::float_reshape(g, [b * groups, o, p].into());
    let along = |k: usize, n: usize| Slice::new(k as isize, Some((k + (n - 1) * stride + 1) as isize), stride as isize);
    let mut patches = Vec::with_capacity(kh * kw);
    for ky in 0..kh {
        for kx in 0..kw {
            let xs = B::float_slice(xp.clone(), &[Slice::full(), Slice::full(), along(ky, ho), along(kx, wo)]);
            let xs = B::float_reshape(xs, [b, c, groups, p, 1].into());
            patches.push(B::float_permute(xs, &[0, 2, 3, 1, 4]));
        }
    }
    // [B, S, P, C, kh kw] -> [B S, P, C kh kw]: the weight's own (c, ky, kx) order.
    let patches = B::float_reshape(B::float_cat(patches, 4), [b * groups, p, c * kh * kw].into());
    B::float_reshape(B::float_sum_dim(B::float_matmul(g, patches), 0), [o, c, kh, kw].into())
}

/// The output's gradient `[B, O, P]` as `[B P, O]`.
fn transposed_grad(g: &[f32], [b, o, ho, wo]: [usize; 4]) -> Vec<f32> {
    let p = ho * wo;
    let mut out = par_zeros(b * p * o);
    out.par_chunks_mut(p * o).enumerate().for_each(|(bi, dst)| {
        for oi in 0..o {
            let src = &g[(bi * o + oi) * p..(bi * o + oi + 1) * p];
            for (pi, &v) in src.iter().enumerate() {
                dst[pi * o + oi] = v;
            }
        }
    });
    out
}

/// The input patches of a convolution: one row per (channel, ky, kx), one column per output
/// pixel (b, y, x); zero where the window reaches into the padding.
struct Im2col {
    x: [usize; 4],
    out: [usize; 2],
    kernel: [usize; 2],
    stride: usize,
    padding: usize,
}

/// An input with fewer than one non-zero in `SPARSE` elements (the BEV: 0/1 masks and aux
/// channels that are zero outside boxes) takes `Im2col::sparse_weight_grad`.
const SPARSE: usize = 4;

/// Whether fewer than one element of `xs` in `SPARSE` is non-zero (a count on all cores, several
/// lanes at once: the BEV at batch 2 is 8 M elements).
fn mostly_zero(xs: &[f32]) -> bool {
    let nonzero: usize = xs.par_chunks(1 << 16).map(count_nonzero).sum();
    nonzero * SPARSE < xs.len()
}

/// The non-zero elements of `xs` (under 2^32 of them), compiled for AVX2 where the CPU has it.
fn count_nonzero(xs: &[f32]) -> usize {
    #[inline(always)]
    fn body(xs: &[f32]) -> usize {
        xs.iter().map(|&v| (v != 0.0) as u32).sum::<u32>() as usize
    }
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn avx2(xs: &[f32]) -> usize {
        body(xs)
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above: the one requirement of the callee.
        return unsafe { avx2(xs) };
    }
    body(xs)
}

/// The non-zero elements of `row` and their indices, in order; a block of eight zeros is
/// passed over with one test (the BEV's rows are mostly zeros).
fn nonzeros(row: &[f32]) -> impl Iterator<Item = (usize, f32)> + '_ {
    let (blocks, tail) = row.as_chunks::<8>();
    let whole = blocks.len() * 8;
    // Shifting out the sign bit: -0.0 is a zero too.
    let busy = blocks.iter().enumerate().filter(|(_, b)| b.iter().fold(0u32, |a, v| a | v.to_bits() << 1) != 0);
    let busy = busy.flat_map(|(i, b)| b.iter().enumerate().map(move |(j, &v)| (i * 8 + j, v)));
    busy.chain(tail.iter().enumerate().map(move |(j, &v)| (whole + j, v))).filter(|&(_, v)| v != 0.0)
}

impl Im2col {
    /// The weight's gradient `[O, C, kh, kw]` from the input's non-zero elements only: each adds
    /// its value times the output gradient `gt` (`[B P, O]`) of every output pixel its kernel
    /// positions reach. One task per input channel, elements in (batch, row, column) order: the
    /// same sums on any thread count.
    fn sparse_weight_grad(&self, x: &[f32], gt: &[f32], o: usize) -> Vec<f32> {
        let [b, c, h, w] = self.x;
        let [ho, wo] = self.out;
        let [kh, kw] = self.kernel;
        let (s, pad) = (self.stride, self.padding);
        // Output row (or column) `t / s` that kernel row `k` of input row `i` reaches, if any.
        let reach = |i: usize, k: usize, n: usize| {
            let t = (i + pad).checked_sub(k)?;
            (t % s == 0 && t / s < n).then_some(t / s)
        };
        let per_channel: Vec<Vec<f32>> = (0..c)
            .into_par_iter()
            .map(|ci| {
                let mut acc = vec![0f32; kh * kw * o];
                for bi in 0..b {
                    let plane = &x[(bi * c + ci) * h * w..(bi * c + ci + 1) * h * w];
                    for (iy, row) in plane.chunks_exact(w).enumerate() {
                        for (ix, v) in nonzeros(row) {
                            for ky in 0..kh {
                                let Some(y) = reach(iy, ky, ho) else { continue };
                                for kx in 0..kw {
                                    let Some(xo) = reach(ix, kx, wo) else { continue };
                                    let g = &gt[((bi * ho + y) * wo + xo) * o..][..o];
                                    let a = &mut acc[(ky * kw + kx) * o..][..o];
                                    for (a, &g) in a.iter_mut().zip(g) {
                                        *a += v * g;
                                    }
                                }
                            }
                        }
                    }
                }
                acc
            })
            .collect();
        let k = c * kh * kw;
        let mut out = vec![0f32; o * k];
        for (ci, acc) in per_channel.iter().enumerate() {
            for (kk, g) in acc.chunks_exact(o).enumerate() {
                for (oi, &v) in g.iter().enumerate() {
                    out[oi * k + ci * kh * kw + kk] = v;
                }
            }
        }
        out
    }

    /// The convolution's output `[B, O, H', W']` from the input's non-zero elements only: the
    /// bias, plus each element's value times the weights of every output pixel its kernel
    /// positions reach. One task per frame and band of output rows, each summing its pixels'
    /// terms in (channel, row, column, ky, kx) order: the same sums on any thread count.
    fn sparse_forward(&self, x: &[f32], weight: &[f32], bias: &[f32]) -> Vec<f32> {
        let [b, c, h, w] = self.x;
        let [ho, wo] = self.out;
        let [kh, kw] = self.kernel;
        let (s, pad, o) = (self.stride, self.padding, bias.len());
        let reach = |i: usize, k: usize, n: usize| {
            let t = (i + pad).checked_sub(k)?;
            (t % s == 0 && t / s < n).then_some(t / s)
        };
        // The weights as [C, kh, kw, O]: one element's terms for an output pixel are contiguous.
        let mut wt = vec![0f32; c * kh * kw * o];
        for (oi, wo_) in weight.chunks_exact(c * kh * kw).enumerate() {
            for (k, &v) in wo_.iter().enumerate() {
                wt[k * o + oi] = v;
            }
        }
        const BAND: usize = 8;
        let bands = ho.div_ceil(BAND);
        // Per task: its rows of output pixels, channels last.
        let parts: Vec<Vec<f32>> = (0..b * bands)
            .into_par_iter()
            .map(|task| {
                let (bi, y0) = (task / bands, task % bands * BAND);
                let y1 = (y0 + BAND).min(ho);
                let mut acc = vec![0f32; (y1 - y0) * wo * o];
                for px in acc.chunks_exact_mut(o) {
                    px.copy_from_slice(bias);
                }
                // Input rows whose kernel positions reach output rows y0..y1.
                let (r0, r1) = ((y0 * s).saturating_sub(pad), ((y1 - 1) * s + kh).saturating_sub(pad).min(h));
                for ci in 0..c {
                    let plane = &x[(bi * c + ci) * h * w..(bi * c + ci + 1) * h * w];
                    for iy in r0..r1 {
                        for (ix, v) in nonzeros(&plane[iy * w..(iy + 1) * w]) {
                            for ky in 0..kh {
                                let Some(y) = reach(iy, ky, ho).filter(|y| (y0..y1).contains(y)) else { continue };
                                for kx in 0..kw {
                                    let Some(xo) = reach(ix, kx, wo) else { continue };
                                    let wk = &wt[((ci * kh + ky) * kw + kx) * o..][..o];
                                    let a = &mut acc[((y - y0) * wo + xo) * o..][..o];
                                    for (a, &wv) in a.iter_mut().zip(wk) {
                                        *a += v * wv;
                                    }
                                }
                            }
                        }
                    }
                }
                acc
            })
            .collect();
        // [B, O, H', W'] from the tasks' rows, channels last.
        par_vec(b * o * ho * wo, |start, mut part| {
            // Run by run along output rows: a run's pixels are `o` apart in its task's part.
            let mut e = start;
            while !part.is_empty() {
                let (x0, y, oi, bi) = (e % wo, e / wo % ho, e / (wo * ho) % o, e / (wo * ho * o));
                let n = part.len().min(wo - x0);
                let src = &parts[bi * bands + y / BAND][((y % BAND) * wo + x0) * o + oi..];
                let (run, rest) = part.split_at_mut(n);
                for (i, v) in run.iter_mut().enumerate() {
                    *v = src[i * o];
                }
                (part, e) = (rest, e + n);
            }
        })
    }

    fn rows(&self) -> usize {
        self.x[1] * self.kernel[0] * self.kernel[1]
    }

    fn columns(&self) -> usize {
        self.x[0] * self.out[0] * self.out[1]
    }

    fn build(&self, x: &[f32]) -> Vec<f32> {
        let [b, c, h, w] = self.x;
        let [ho, wo] = self.out;
        let [kh, kw] = self.kernel;
        let (s, pad) = (self.stride as i64, self.padding as i64);
        par_zeroed_parts(&vec![self.columns(); self.rows()], |row, dst| {
            let (ci, ky, kx) = (row / (kh * kw), (row / kw) % kh, row % kw);
            for bi in 0..b {
                let plane = &x[(bi * c + ci) * h * w..(bi * c + ci + 1) * h * w];
                for oy in 0..ho {
                    let iy = oy as i64 * s + ky as i64 - pad;
                    if iy < 0 || iy >= h as i64 {
                        continue;
                    }
                    let src = &plane[iy as usize * w..(iy as usize + 1) * w];
                    let d = &mut dst[(bi * ho + oy) * wo..(bi * ho + oy + 1) * wo];
                    for (ox, v) in d.iter_mut().enumerate() {
                        let ix = ox as i64 * s + kx as i64 - pad;
                        if ix >= 0 && ix < w as i64 {
                            *v = src[ix as usize];
                        }
                    }
                }
            }
        })
    }
}

#[derive(Debug)]
struct ConvBackward;

impl<B: Backend + BevConvOps> Backward<B, 3> for ConvBackward {
    /// The input, the weight, the stride and the padding.
    type State = (FloatTensor<B>, FloatTensor<B>, usize, usize);

    fn backward(self, ops: Ops<Self::State, 3>, grads: &mut Gradients, _checkpointer: &mut Checkpointer) {
        let [node_x, node_weight, node_bias] = ops.parents;
        let grad = grads.consume::<B>(&ops.node);
        let (x, weight, stride, padding) = ops.state;
        if let Some(node) = node_x {
            let g = B::conv2d_x_backward(x.clone(), weight.clone(), grad.clone(), options(stride, padding));
            grads.register::<B>(node.id, g);
        }
        if let Some(node) = node_bias {
            grads.register::<B>(node.id, B::bev_conv_bias_grad(grad.clone()));
        }
        if let Some(node) = node_weight {
            grads.register::<B>(node.id, B::bev_conv_weight_grad(x, weight, grad, stride, padding));
        }
    }
}

impl<B: Backend + BevConvOps, C: CheckpointStrategy> BevConvOps for Autodiff<B, C> {
    fn bev_conv(
        x: FloatTensor<Self>,
        weight: FloatTensor<Self>,
        bias: FloatTensor<Self>,
        stride: usize,
        padding: usize,
    ) -> FloatTensor<Self> {
        match ConvBackward.prepare::<C>([x.node(), weight.node(), bias.node()]).compute_bound().stateful() {
            OpsKind::Tracked(prep) => {
                let (xi, wi) = (x.primitive().clone(), weight.primitive().clone());
                let out = B::bev_conv_train(xi.clone(), wi.clone(), bias.into_primitive(), stride, padding);
                prep.finish((xi, wi, stride, padding), out)
            }
            OpsKind::UnTracked(prep) => prep.finish(B::bev_conv(
                x.into_primitive(),
                weight.into_primitive(),
                bias.into_primitive(),
                stride,
                padding,
            )),
        }
    }

    fn bev_conv_weight_grad(
        x: FloatTensor<Self>,
        weight: FloatTensor<Self>,
        grad: FloatTensor<Self>,
        stride: usize,
        padding: usize,
    ) -> FloatTensor<Self> {
        Self::from_inner(B::bev_conv_weight_grad(
            Self::inner(x),
            Self::inner(weight),
            Self::inner(grad),
            stride,
            padding,
        ))
    }
}

/// `conv.forward(x)` for a square-strided, symmetrically padded convolution with a bias (the
/// BEV encoder's), through `BevConvOps`; any other convolution runs `conv.forward`.
pub fn forward(conv: &Conv2d, x: Tensor<4>) -> Tensor<4> {
    let [kh, kw] = conv.kernel_size;
    let stride = conv.stride[0];
    let padding = match &conv.padding {
        burn::nn::PaddingConfig2d::Explicit(a, b, c, d) if a == b && b == c && c == d => Some(*a),
        _ => None,
    };
    // With the `fusion` feature a GPU runs burn's own convolution: the fused queue has no
    // place for this operation.
    let (Some(bias), Some(padding)) = (&conv.bias, padding) else { return conv.forward(x) };
    if cfg!(feature = "fusion") && x.device() != Device::flex() {
        return conv.forward(x);
    }
    if conv.stride[1] != stride || conv.dilation != [1, 1] || conv.groups != 1 || kh == 0 || kw == 0 {
        return conv.forward(x);
    }
    let out = <Dispatch as BevConvOps>::bev_conv(
        x.into_dispatch(),
        conv.weight.val().into_dispatch(),
        bias.val().into_dispatch(),
        stride,
        padding,
    );
    Tensor::from_dispatch(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flex(data: Vec<f32>, shape: [usize; 4]) -> FlexTensor {
        FlexTensor::from_data(TensorData::new(data, shape))
    }

    fn host(t: FlexTensor) -> Vec<f32> {
        flex_slice(&t.to_contiguous()).to_vec()
    }

    fn values(n: usize, salt: u32) -> Vec<f32> {
        (0..n).map(|i| ((i as u32).wrapping_mul(2654435761).wrapping_add(salt) % 2000) as f32 / 1000.0 - 1.0).collect()
    }

    /// The GPU's formulations against burn's own, on the CPU: odd sizes, both strides, the
    /// BEV encoder's 3 x 3 kernels with padding 1 and a 5 x 5 with padding 2.
    #[test]
    fn weight_and_bias_gradients_by_patches_match_burns() {
        for (stride, k, pad, [b, c, h, w], o) in [
            (1, 3, 1, [2, 3, 9, 7], 4),
            (2, 3, 1, [2, 3, 9, 8], 5),
            (2, 5, 2, [1, 2, 11, 6], 3),
            (1, 1, 0, [2, 4, 5, 5], 2),
        ] {
            let (ho, wo) = ((h + 2 * pad - k) / stride + 1, (w + 2 * pad - k) / stride + 1);
            let x = values(b * c * h * w, 1);
            let weight = values(o * c * k * k, 2);
            let grad = values(b * o * ho * wo, 3);
            let reference = host(Flex::conv2d_weight_backward(
                flex(x.clone(), [b, c, h, w]),
                flex(weight.clone(), [o, c, k, k]),
                flex(grad.clone(), [b, o, ho, wo]),
                options(stride, pad),
            ));
            let got = host(weight_grad_by_patches::<Flex>(
                flex(x, [b, c, h, w]),
                [o, c, k, k],
                flex(grad.clone(), [b, o, ho, wo]),
                stride,
                pad,
            ));
            let diff = reference.iter().zip(&got).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
            assert!(diff < 1e-4 && reference.iter().any(|v| v.abs() > 0.5), "stride {stride} k {k}: {diff}");
            let bias_ref = host(<Flex as BevConvOps>::bev_conv_bias_grad(flex(grad.clone(), [b, o, ho, wo])));
            let bias = host(bias_grad_by_planes::<Flex>(flex(grad, [b, o, ho, wo])));
            let diff = bias_ref.iter().zip(&bias).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
            assert!(diff < 1e-4 && bias.len() == o, "bias, stride {stride}: {diff}");
        }
    }
}
