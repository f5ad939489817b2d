//! The splat as one backend operation with its own backward pass (burn's backend extension):
//! the host code (`host`) on the `flex` backend, a device kernel (`cube`) on wgpu and CUDA, and
//! autodiff that calls the backward operation of whichever backend runs it. Nothing of window
//! size is ever materialised and no tensor makes a round trip through the host on a device.

use super::super::host_read::host_vec;
use super::host;
use super::layout::{COLS, SplatShape};
use crate::backend::layout::N_LABELS;
use burn::backend::autodiff::checkpoint::{base::Checkpointer, strategy::CheckpointStrategy};
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind, unary};
use burn::backend::tensor::FloatTensor;
use burn::backend::{Autodiff, AutodiffBackend, Backend, Dispatch, Flex, TensorMetadata, backend_extension};
use burn::prelude::*;

// With the `fusion` feature burn queues a device's element-wise work lazily (`Fusion`): the splat
// joins that queue as an opaque operation whose output shape is known up front.
#[backend_extension(
    Flex,
    Cube: cfg(any(feature = "wgpu", feature = "cuda")),
    Fusion: cfg(all(feature = "fusion", any(feature = "wgpu", feature = "cuda"))),
    Autodiff
)]
pub trait SplatOps: burn::backend::Backend {
    /// Packed Gaussians `[N, COLS]` -> logits `[batch * voxels, 9]`.
    #[fusion(dtype = g, shape = burn::tensor::Shape::new([s.batch * s.region.voxels(), N_LABELS]))]
    fn splat_forward(g: FloatTensor<Self>, s: SplatShape) -> FloatTensor<Self>;
    /// Packed Gaussians and the logits' gradient -> the Gaussians' gradient `[N, COLS]`.
    #[fusion(dtype = g, shape = g)]
    fn splat_backward(g: FloatTensor<Self>, grad: FloatTensor<Self>, s: SplatShape) -> FloatTensor<Self>;
}

/// The host implementation on any backend: read, compute, upload (the `flex` path, and the
/// device fallback where the device has no atomic float add).
pub fn host_forward<B: Backend>(g: FloatTensor<B>, s: SplatShape) -> FloatTensor<B> {
    let device = g.device();
    let out = host::forward(&host_vec::<B>(g), &s);
    let rows = s.batch * s.region.voxels();
    B::float_from_data(TensorData::new(out, [rows, N_LABELS]), &device)
}

pub fn host_backward<B: Backend>(g: FloatTensor<B>, grad: FloatTensor<B>, s: SplatShape) -> FloatTensor<B> {
    let device = g.device();
    let gv = host_vec::<B>(g);
    let n = gv.len() / COLS;
    let out = host::backward(&gv, &host_vec::<B>(grad), &s);
    B::float_from_data(TensorData::new(out, [n, COLS]), &device)
}

impl SplatOps for Flex {
    fn splat_forward(g: FloatTensor<Self>, s: SplatShape) -> FloatTensor<Self> {
        host_forward::<Self>(g, s)
    }

    fn splat_backward(g: FloatTensor<Self>, grad: FloatTensor<Self>, s: SplatShape) -> FloatTensor<Self> {
        host_backward::<Self>(g, grad, s)
    }
}

#[derive(Debug)]
struct SplatBackward;

impl<B: Backend + SplatOps> Backward<B, 1> for SplatBackward {
    type State = (FloatTensor<B>, SplatShape);

    fn backward(self, ops: Ops<Self::State, 1>, grads: &mut Gradients, _checkpointer: &mut Checkpointer) {
        let (g, s) = ops.state;
        unary::<B, _>(ops.parents, ops.node, grads, |grad| B::splat_backward(g, grad, s));
    }
}

impl<B: Backend + SplatOps, C: CheckpointStrategy> SplatOps for Autodiff<B, C> {
    fn splat_forward(g: FloatTensor<Self>, s: SplatShape) -> FloatTensor<Self> {
        match SplatBackward.prepare::<C>([g.node()]).compute_bound().stateful() {
            OpsKind::Tracked(prep) => {
                let inner = g.primitive().clone();
                let out = B::splat_forward(inner.clone(), s);
                prep.finish((inner, s), out)
            }
            OpsKind::UnTracked(prep) => prep.finish(B::splat_forward(g.into_primitive(), s)),
        }
    }

    fn splat_backward(g: FloatTensor<Self>, grad: FloatTensor<Self>, s: SplatShape) -> FloatTensor<Self> {
        Self::from_inner(B::splat_backward(Self::inner(g), Self::inner(grad), s))
    }
}

/// Logits `[batch * voxels, 9]` of packed Gaussians `[N, COLS]` on whatever device they live on.
pub fn splat_packed(g: Tensor<2>, s: SplatShape) -> Tensor<2> {
    let out = <Dispatch as SplatOps>::splat_forward(g.into_dispatch(), s);
    Tensor::from_dispatch(out)
}
