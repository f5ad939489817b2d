//! `rocc train`'s optimiser (`learn::adam::FusedAdam`): on the CPU it is burn's Adam bit for bit,
//! its checkpoints and burn's Adam's resume each other, and (a `wgpu` build) its one-kernel update
//! follows burn's Adam on the same GPU.

use burn::nn::{Linear, LinearConfig};
use burn::optim::{AdamConfig, GradientsParams, ModuleOptimizer};
use burn::prelude::*;
use rocc::backend::grounded::cpu;
use rocc::learn::adam::FusedAdam;

/// A small linear layer with fixed weights, and the step's data.
fn layer(device: &Device) -> Linear {
    let mut l = LinearConfig::new(7, 5).init(device);
    let w: Vec<f32> = (0..35).map(|i| ((i * 37 % 11) as f32 - 5.0) * 0.1).collect();
    let b: Vec<f32> = (0..5).map(|i| i as f32 * 0.05 - 0.1).collect();
    l.weight = burn::module::Param::from_tensor(Tensor::from_data(TensorData::new(w, [7, 5]), device));
    l.bias = Some(burn::module::Param::from_tensor(Tensor::from_data(TensorData::new(b, [5]), device)));
    l
}

/// One step on batch `k`: a squared error against a fixed target, learning rate falling.
fn step(optim: &mut ModuleOptimizer, model: Linear, k: usize) -> Linear {
    let device = model.weight.val().device();
    let x: Vec<f32> = (0..21).map(|i| (((i + 3 * k) * 13 % 17) as f32 - 8.0) / 8.0).collect();
    let x = Tensor::<2>::from_data(TensorData::new(x, [3, 7]), &device);
    let target = Tensor::<2>::ones([3, 5], &device).mul_scalar(0.3);
    let loss = (model.forward(x) - target).powi_scalar(2).sum();
    let grads = GradientsParams::from_grads(loss.backward(), &model);
    optim.step(1e-2 / (k + 1) as f64, model, grads)
}

fn weights(m: &Linear) -> Vec<f32> {
    let mut v: Vec<f32> = m.weight.val().to_data().iter::<f32>().collect();
    v.extend(m.bias.as_ref().expect("a bias").val().to_data().iter::<f32>());
    v
}

fn run(mut optim: ModuleOptimizer, device: &Device, steps: std::ops::Range<usize>, model: Option<Linear>) -> Linear {
    let mut model = model.unwrap_or_else(|| layer(device));
    for k in steps {
        model = step(&mut optim, model, k);
    }
    model
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn on_the_cpu_it_is_burns_adam_bit_for_bit() {
    let device = cpu().autodiff();
    let start = weights(&layer(&device));
    let ours = weights(&run(FusedAdam::init(), &device, 0..5, None));
    let burns = weights(&run(AdamConfig::new().init(), &device, 0..5, None));
    assert_eq!(bits(&ours), bits(&burns));
    let moved = ours.iter().zip(&start).filter(|(a, b)| a != b).count();
    assert_eq!(moved, start.len(), "every weight moves in 5 steps");
}

/// A checkpoint of either optimiser resumes in the other: the same state type, the same file.
#[test]
fn checkpoints_resume_across_burns_adam_and_this_one() {
    let device = cpu().autodiff();
    let straight = weights(&run(AdamConfig::new().init(), &device, 0..4, None));
    let resume = |first: ModuleOptimizer, second: ModuleOptimizer| {
        let mut first = first;
        let mut model = layer(&device);
        for k in 0..2 {
            model = step(&mut first, model, k);
        }
        let bytes = first.into_bytes().expect("the optimiser state serialises");
        let second = second.from_bytes(bytes).expect("the state loads");
        weights(&run(second, &device, 2..4, Some(model)))
    };
    assert_eq!(bits(&resume(AdamConfig::new().init(), FusedAdam::init())), bits(&straight));
    assert_eq!(bits(&resume(FusedAdam::init(), AdamConfig::new().init())), bits(&straight));
    // Without the state the moments restart and the weights differ: the state is what carried.
    let fresh = {
        let mut model = layer(&device);
        let mut o = FusedAdam::init();
        for k in 0..2 {
            model = step(&mut o, model, k);
        }
        weights(&run(FusedAdam::init(), &device, 2..4, Some(model)))
    };
    assert_ne!(bits(&fresh), bits(&straight));
}

/// The kernel against burn's Adam on the same GPU (Mesa's software Vulkan here), five steps and
/// a checkpoint round trip in the middle: the same update to float rounding.
#[cfg(feature = "wgpu")]
#[test]
fn on_a_gpu_one_kernel_follows_burns_adam() {
    let device = Device::wgpu(Default::default()).autodiff();
    let start = weights(&layer(&device));
    let mid = run(FusedAdam::init(), &device, 0..2, None);
    let burns = weights(&run(AdamConfig::new().init(), &device, 0..5, None));
    let mut o = FusedAdam::init();
    let mut model = layer(&device);
    for k in 0..2 {
        model = step(&mut o, model, k);
    }
    assert_eq!(bits(&weights(&model)), bits(&weights(&mid)), "the kernel is deterministic");
    let o = FusedAdam::init().from_bytes(o.into_bytes().expect("serialises")).expect("loads");
    let ours = weights(&run(o, &device, 2..5, Some(model)));
    let scale = burns.iter().zip(&start).fold(0f32, |m, (a, b)| m.max((a - b).abs()));
    let diff = ours.iter().zip(&burns).fold(0f32, |m, (a, b)| m.max((a - b).abs()));
    assert!(scale > 1e-3, "the weights move: {scale}");
    assert!(diff <= 1e-5 * scale, "the kernel's weights differ from burn's by {diff} (updates up to {scale})");
    let cpu = weights(&run(AdamConfig::new().init(), &cpu().autodiff(), 0..5, None));
    let diff = ours.iter().zip(&cpu).fold(0f32, |m, (a, b)| m.max((a - b).abs()));
    assert!(diff <= 1e-5 * scale, "the GPU's weights differ from the CPU's by {diff}");
}
