//! The BEV encoder's convolution operation (`conv::forward`: burn's forward, the CPU's own weight
//! gradient and, for a sparse input under autodiff, its own forward) against burn's `Conv2d` with
//! autodiff: the same values (bit for bit, except a sparse input's training forward: to float
//! rounding), and the same gradients of the input, the weight and the bias, for the shapes the
//! encoder uses (stride 1 and 2, up to 16 and beyond 16 output channels, batch 1 and 2, odd
//! sizes). Its activation (`gelu::gelu`) likewise: burn's bits for inference, burn's values and
//! gradient to float rounding for a training step.

use burn::nn::PaddingConfig2d;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::prelude::*;
use rocc::backend::grounded::{conv, gelu};

struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32 * 2.0 - 1.0
    }
    fn vec(&mut self, n: usize) -> Vec<f32> {
        (0..n).map(|_| self.next()).collect()
    }
}

/// Output values and the gradients of input, weight and bias of `sum(out * w)`.
fn run(c: &Conv2d, x: &[f32], dims: [usize; 4], w_seed: u64, ours: bool) -> [Vec<f32>; 4] {
    let device = c.weight.val().device();
    let x = Tensor::<4>::from_data(TensorData::new(x.to_vec(), dims), &device).require_grad();
    let out = if ours { conv::forward(c, x.clone()) } else { c.forward(x.clone()) };
    let n = out.dims().iter().product();
    let w = Tensor::<4>::from_data(TensorData::new(Lcg(w_seed).vec(n), out.dims()), &device);
    let grads = (out.clone() * w).sum().backward();
    let host = |t: Tensor<4>| t.to_data().iter::<f32>().collect::<Vec<_>>();
    let gw = c.weight.val().grad(&grads).expect("the weight gets a gradient").to_data().iter::<f32>().collect();
    let bias = c.bias.as_ref().expect("a bias").val();
    let gb = bias.grad(&grads).expect("the bias gets a gradient").to_data().iter::<f32>().collect();
    [host(out), host(x.grad(&grads).expect("the input gets a gradient")), gw, gb]
}

fn max_rel_err(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    let scale = b.iter().fold(1e-3f32, |m, v| m.max(v.abs()));
    a.iter().zip(b).fold(0f32, |m, (x, y)| m.max((x - y).abs())) / scale
}

#[test]
fn the_bev_convolution_matches_burns_in_values_and_gradients() {
    // (batch, in, out, stride, height, width, one element in `sparse` non-zero): the sparse
    // inputs, like the BEV, take the weight gradient's path over non-zero elements.
    let shapes = [
        (2, 25, 16, 2, 23, 19, 1),
        (1, 16, 32, 2, 12, 15, 1),
        (2, 32, 32, 1, 9, 11, 1),
        (2, 3, 4, 1, 8, 8, 1),
        (2, 25, 16, 2, 23, 19, 10),
        (1, 5, 4, 1, 13, 10, 6),
    ];
    for (seed, &(b, ci, co, s, h, w, sparse)) in shapes.iter().enumerate() {
        let device = Device::flex().autodiff();
        device.seed(seed as u64);
        let c = Conv2dConfig::new([ci, co], [3, 3])
            .with_stride([s, s])
            .with_padding(PaddingConfig2d::Explicit(1, 1, 1, 1))
            .init(&device);
        let dims = [b, ci, h, w];
        let mut x = Lcg(100 + seed as u64).vec(dims.iter().product());
        let mut keep = Lcg(200 + seed as u64);
        x.iter_mut().filter(|_| keep.next().abs() * sparse as f32 > 1.0).for_each(|v| *v = 0.0);
        let ours = run(&c, &x, dims, 7, true);
        let burns = run(&c, &x, dims, 7, false);
        if sparse == 1 {
            assert_eq!(ours[0], burns[0], "case {seed}: the forward pass is burn's, bit for bit");
        } else {
            // A training step sums a sparse input's non-zero elements alone, in another order.
            let e = max_rel_err(&ours[0], &burns[0]);
            assert!(e < 1e-5 && ours[0] != burns[0], "case {seed}: the forward pass differs by {e}");
            // Inference (no autodiff) keeps burn's bits.
            let (cv, xv) = (c.valid(), Tensor::<4>::from_data(TensorData::new(x.clone(), dims), &Device::flex()));
            let host = |t: Tensor<4>| t.to_data().iter::<f32>().collect::<Vec<_>>();
            assert_eq!(host(conv::forward(&cv, xv.clone())), host(cv.forward(xv)), "case {seed}: inference");
        }
        for (name, i) in [("input", 1), ("weight", 2), ("bias", 3)] {
            let e = max_rel_err(&ours[i], &burns[i]);
            assert!(e < 1e-5, "case {seed}: the gradient of the {name} differs by {e}");
        }
        assert!(ours[2].iter().any(|&v| v != 0.0), "case {seed}: a zero weight gradient proves nothing");
    }
}

#[test]
fn the_training_gelu_matches_burns_in_values_and_gradients() {
    // Beyond the BEV encoder's range on both sides, and a 5 x 7 x 300 block (several tasks).
    let mut x = Lcg(5).vec(5 * 7 * 300);
    x.iter_mut().enumerate().for_each(|(i, v)| *v *= 1.0 + (i % 13) as f32);
    let run = |ours: bool| {
        let device = Device::flex().autodiff();
        let t = Tensor::<3>::from_data(TensorData::new(x.clone(), [5, 7, 300]), &device).require_grad();
        let y = if ours { gelu::gelu(t.clone()) } else { burn::tensor::activation::gelu(t.clone()) };
        let w = Tensor::<3>::from_data(TensorData::new(Lcg(9).vec(x.len()), [5, 7, 300]), &device);
        let grads = (y.clone() * w).sum().backward();
        let g = t.grad(&grads).expect("the input gets a gradient");
        (y.to_data().iter::<f32>().collect::<Vec<_>>(), g.to_data().iter::<f32>().collect::<Vec<_>>())
    };
    let ((y, g), (by, bg)) = (run(true), run(false));
    let (ey, eg) = (max_rel_err(&y, &by), max_rel_err(&g, &bg));
    assert!(ey < 2e-6 && eg < 2e-6, "values differ by {ey}, gradients by {eg}");
    assert!(y != by, "a training step takes its own GELU");
    // Inference (no autodiff) keeps burn's bits.
    let t = Tensor::<3>::from_data(TensorData::new(x.clone(), [5, 7, 300]), &Device::flex());
    let host = |t: Tensor<3>| t.to_data().iter::<f32>().collect::<Vec<_>>();
    assert_eq!(host(gelu::gelu(t.clone())), host(burn::tensor::activation::gelu(t)));
}
