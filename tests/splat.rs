//! The splat operation (host code on the CPU, a kernel on a GPU) against the same sum written
//! with ordinary tensor operations and autodiff (`splat_tensor_ops`): values and the gradients
//! of every Gaussian parameter on random small cases (`splat::check`). With `--features wgpu` the
//! device kernel is checked against the CPU the same way (on a software Vulkan adapter where there
//! is no GPU).

use burn::prelude::*;
use rocc::backend::grounded::splat::check::{Case, GRADIENT_TOLERANCE, NAMES, VALUE_TOLERANCE};
use rocc::backend::grounded::splat::splat;

fn assert_close(e: [f32; 6], seed: u64, what: &str) {
    assert!(e[0] < VALUE_TOLERANCE, "case {seed}: {what} logits differ by {}", e[0]);
    for (k, name) in NAMES.iter().enumerate() {
        assert!(e[k + 1] < GRADIENT_TOLERANCE, "case {seed}: {what} gradient of {name} differs by {}", e[k + 1]);
    }
}

#[test]
fn the_splat_operation_matches_tensor_operations_in_values_and_gradients() {
    let device = Device::flex().autodiff();
    for (seed, n, window) in [(1, 40, 2), (2, 25, 3), (3, 60, 1), (4, 1, 2)] {
        let c = Case::random(seed, n, window);
        let (v, _) = c.run(&device, false);
        assert!(v.iter().any(|x| x.abs() > 1e-3), "case {seed} splats nothing: the test would prove nothing");
        assert_close(c.errors(&device, &device, true), seed, "host");
    }
}

#[test]
fn the_check_notices_a_wrong_gradient() {
    // The comparison itself can fail: a case against a different case is far off.
    let device = Device::flex().autodiff();
    let (a, b) = (Case::random(5, 30, 2), Case::random(6, 30, 2));
    let (va, ga) = a.run(&device, false);
    let (vb, gb) = b.run(&device, false);
    assert!(rocc::backend::grounded::splat::check::max_rel_err(&va, &vb) > 1e-2);
    assert!(rocc::backend::grounded::splat::check::max_rel_err(&ga[0], &gb[0]) > 1e-2);
}

#[test]
fn a_gaussian_with_a_non_finite_mean_adds_nothing_and_gets_no_gradient() {
    let device = Device::flex().autodiff();
    let mut c = Case::random(7, 12, 2);
    let (clean, _) = c.run(&device, false);
    c.push([f32::NAN, 24.0, 3.0]);
    let (v, g) = c.run(&device, false);
    assert_eq!(v, clean, "the NaN-mean Gaussian changed the logits");
    for (k, name) in NAMES.iter().enumerate() {
        let row = &g[k][g[k].len() / c.n * (c.n - 1)..];
        assert!(row.iter().all(|x| *x == 0.0), "the NaN-mean Gaussian got a {name} gradient {row:?}");
    }
}

#[test]
fn the_cpu_splat_is_byte_identical_on_one_thread_and_many() {
    let device = Device::flex().autodiff();
    let c = Case::random(11, 300, 3);
    let (g, _) = c.tensors(&device);
    let many: Vec<f32> = splat(&g, c.region, 2, c.window).to_data().iter::<f32>().collect();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a one-thread pool");
    let one: Vec<f32> = pool.install(|| splat(&g, c.region, 2, c.window).to_data().iter::<f32>().collect());
    assert!(many.iter().zip(&one).all(|(a, b)| a.to_bits() == b.to_bits()), "thread count changed the bytes");
}

/// The device kernel against the CPU: same values and gradients (up to the order of atomic adds).
#[cfg(feature = "wgpu")]
#[test]
fn the_wgpu_kernel_matches_the_cpu() {
    let cpu = Device::flex().autodiff();
    let gpu = Device::wgpu(Default::default()).autodiff();
    for (seed, n, window) in [(21, 200, 2), (22, 120, 3)] {
        assert_close(Case::random(seed, n, window).errors(&gpu, &cpu, false), seed, "device");
    }
}
