//! The BEV encoder's convolutions as one backend operation whose weight gradient the CPU computes
//! as im2col and one matrix product, or, from an input mostly of zeros (the BEV itself, under
//! the first convolution), from its non-zero elements alone. Forward and the input's gradient are burn's own
//! (`conv2d`, `conv2d_x_backward`): the logits do not change. burn's CPU weight gradient is a
//! convolution of the input with the output's gradient as the kernel, which at batch 1-4 and up
//! to 16 output channels takes its direct small-channel path: a third of a `cpu-small` training
//! step on the 400 x 400 BEV. Every other backend runs burn's `conv2d_weight_backward`.
//! tests/bev_conv.rs checks the CPU's weight gradient against burn's, on dense and sparse inputs.

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
}

impl BevConvOps for Flex {
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
        let gt = transposed_grad(contiguous(&grad), gdims);
        let xs = contiguous(&x);
        if xs.iter().filter(|&&v| v != 0.0).count() * SPARSE < xs.len() {
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
        let prod = contiguous(&prod);
        let mut out = vec![0f32; o * k];
        for (r, row) in prod.chunks_exact(o).enumerate() {
            for (oi, &v) in row.iter().enumerate() {
                out[oi * k + r] = v;
            }
        }
        FlexTensor::from_data(TensorData::new(out, wshape))
    }
}

#[cfg(any(feature = "wgpu", feature = "cuda"))]
impl BevConvOps for burn_cubecl::CubeBackend {}

/// A contiguous f32 tensor's elements.
fn contiguous(t: &FlexTensor) -> &[f32] {
    let start = t.layout().start_offset();
    &t.storage::<f32>()[start..start + t.layout().num_elements()]
}

/// The output's gradient `[B, O, P]` as `[B P, O]`.
fn transposed_grad(g: &[f32], [b, o, ho, wo]: [usize; 4]) -> Vec<f32> {
    let p = ho * wo;
    let mut out = vec![0f32; b * p * o];
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
                        for (ix, &v) in row.iter().enumerate() {
                            if v == 0.0 {
                                continue;
                            }
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
        let mut out = vec![0f32; self.rows() * self.columns()];
        out.par_chunks_mut(self.columns()).enumerate().for_each(|(row, dst)| {
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
        });
        out
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
            let [b, o, ho, wo] = grad.shape().dims();
            let g = B::float_reshape(B::float_swap_dims(grad.clone(), 0, 1), [o, b * ho * wo].into());
            grads.register::<B>(node.id, B::float_reshape(B::float_sum_dim(g, 1), [o].into()));
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
                let out = B::bev_conv(xi.clone(), wi.clone(), bias.into_primitive(), stride, padding);
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
    // A GPU runs burn's own convolution (with the `fusion` feature its queue has no place for
    // this operation).
    let (Some(bias), Some(padding)) = (&conv.bias, padding) else { return conv.forward(x) };
    if x.device() != Device::flex() {
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
