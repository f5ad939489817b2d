//! The splat operation (host code on the CPU, a kernel on a GPU) against the same sum written
//! with ordinary tensor operations and autodiff (`splat_tensor_ops`): values and the gradients
//! of every Gaussian parameter on random small cases. With `--features wgpu` the device kernel
//! is checked against the CPU the same way (on a software Vulkan adapter where there is no GPU).

use burn::prelude::*;
use rocc::backend::grounded::splat::{Gaussians, Region, splat, splat_tensor_ops};
use rocc::backend::layout::{N_LABELS, NZ};

struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.next()
    }
}

/// Host values of one random case: N Gaussians around a small region (some straddling its
/// edges, some in the other batch element), unit quaternions turned into rotations.
struct Case {
    n: usize,
    mean: Vec<f32>,
    scale: Vec<f32>,
    rot: Vec<f32>,
    opacity: Vec<f32>,
    feat: Vec<f32>,
    batch: Vec<usize>,
    weights: Vec<f32>,
    region: Region,
    window: usize,
}

fn case(seed: u64, n: usize, window: usize) -> Case {
    let mut r = Lcg(seed);
    let region = Region { i0: 20, j0: 30, ni: 9, nj: 7 };
    let smax = window as f32 / 3.0;
    let mut c = Case {
        n,
        mean: vec![],
        scale: vec![],
        rot: vec![],
        opacity: vec![],
        feat: vec![],
        batch: vec![],
        weights: vec![],
        region,
        window,
    };
    for _ in 0..n {
        c.mean.push(r.range(17.0, 31.0));
        c.mean.push(r.range(27.0, 39.0));
        c.mean.push(r.range(-1.5, NZ as f32 + 1.5));
        for _ in 0..3 {
            c.scale.push(r.range(0.25, smax));
        }
        let q: [f32; 4] = std::array::from_fn(|_| r.range(-1.0, 1.0));
        let norm = q.iter().map(|v| v * v).sum::<f32>().sqrt().max(1e-3);
        let [w, x, y, z] = q.map(|v| v / norm);
        c.rot.extend([
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ]);
        c.opacity.push(r.range(0.05, 0.95));
        for _ in 0..N_LABELS {
            c.feat.push(r.range(-2.0, 2.0));
        }
        c.batch.push((r.next() * 2.0) as usize);
    }
    for _ in 0..2 * region.voxels() * N_LABELS {
        c.weights.push(r.range(-1.0, 1.0));
    }
    c
}

struct Tensors {
    g: Gaussians,
    params: [Tensor<2>; 5],
}

fn tensors(c: &Case, device: &Device) -> Tensors {
    let t = |v: &Vec<f32>, cols: usize| {
        Tensor::<2>::from_data(TensorData::new(v.clone(), [c.n, cols]), device).require_grad()
    };
    let params = [t(&c.mean, 3), t(&c.scale, 3), t(&c.rot, 9), t(&c.opacity, 1), t(&c.feat, N_LABELS)];
    let [mean, scale, rot, opacity, feat] = params.clone();
    Tensors { g: Gaussians { mean, scale, rot, opacity, feat, batch: c.batch.clone() }, params }
}

/// Logits and the gradient of sum(weights * logits) for each parameter tensor.
fn run(c: &Case, device: &Device, reference: bool) -> (Vec<f32>, Vec<Vec<f32>>) {
    let t = tensors(c, device);
    let f = if reference { splat_tensor_ops } else { splat };
    let logits = f(&t.g, c.region, 2, c.window);
    let w = Tensor::<2>::from_data(TensorData::new(c.weights.clone(), [2 * c.region.voxels(), N_LABELS]), device);
    let grads = (logits.clone() * w).sum().backward();
    let values = logits.to_data().iter::<f32>().collect();
    let gs = t
        .params
        .iter()
        .map(|p| p.grad(&grads).expect("every parameter gets a gradient").to_data().iter::<f32>().collect())
        .collect();
    (values, gs)
}

fn max_rel_err(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    let scale = b.iter().fold(1e-3f32, |m, v| m.max(v.abs()));
    a.iter().zip(b).map(|(x, y)| (x - y).abs() / scale).fold(0.0, f32::max)
}

const NAMES: [&str; 5] = ["mean", "scale", "rotation", "opacity", "features"];

#[test]
fn the_splat_operation_matches_tensor_operations_in_values_and_gradients() {
    let device = Device::flex().autodiff();
    for (seed, n, window) in [(1, 40, 2), (2, 25, 3), (3, 60, 1), (4, 1, 2)] {
        let c = case(seed, n, window);
        let (v, g) = run(&c, &device, false);
        let (rv, rg) = run(&c, &device, true);
        assert!(v.iter().any(|x| x.abs() > 1e-3), "case {seed} splats nothing: the test would prove nothing");
        let e = max_rel_err(&v, &rv);
        assert!(e < 1e-5, "case {seed}: logits differ by {e} (relative to the largest)");
        for (k, name) in NAMES.iter().enumerate() {
            let e = max_rel_err(&g[k], &rg[k]);
            assert!(e < 1e-4, "case {seed}: gradient of {name} differs by {e}");
        }
    }
}

#[test]
fn a_gaussian_with_a_non_finite_mean_adds_nothing_and_gets_no_gradient() {
    let device = Device::flex().autodiff();
    let mut c = case(7, 12, 2);
    let (clean, _) = run(&c, &device, false);
    c.mean.extend([f32::NAN, 24.0, 3.0]);
    c.scale.extend([0.5; 3]);
    c.rot.extend([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    c.opacity.push(0.5);
    c.feat.extend([1.0; N_LABELS]);
    c.batch.push(0);
    c.n += 1;
    let (v, g) = run(&c, &device, false);
    assert_eq!(v, clean, "the NaN-mean Gaussian changed the logits");
    for (k, name) in NAMES.iter().enumerate() {
        let row = &g[k][g[k].len() / c.n * (c.n - 1)..];
        assert!(row.iter().all(|x| *x == 0.0), "the NaN-mean Gaussian got a {name} gradient {row:?}");
    }
}

#[test]
fn the_cpu_splat_is_byte_identical_on_one_thread_and_many() {
    let device = Device::flex().autodiff();
    let c = case(11, 300, 3);
    let t = tensors(&c, &device);
    let many: Vec<f32> = splat(&t.g, c.region, 2, c.window).to_data().iter::<f32>().collect();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a one-thread pool");
    let one: Vec<f32> = pool.install(|| splat(&t.g, c.region, 2, c.window).to_data().iter::<f32>().collect());
    assert!(many.iter().zip(&one).all(|(a, b)| a.to_bits() == b.to_bits()), "thread count changed the bytes");
}

/// The device kernel against the CPU: same values and gradients (up to the order of atomic adds).
#[cfg(feature = "wgpu")]
#[test]
fn the_wgpu_kernel_matches_the_cpu() {
    let cpu = Device::flex().autodiff();
    let gpu = Device::wgpu(Default::default()).autodiff();
    for (seed, n, window) in [(21, 200, 2), (22, 120, 3)] {
        let c = case(seed, n, window);
        let (v, g) = run(&c, &gpu, false);
        let (rv, rg) = run(&c, &cpu, false);
        let e = max_rel_err(&v, &rv);
        assert!(e < 1e-5, "case {seed}: device logits differ by {e}");
        for (k, name) in NAMES.iter().enumerate() {
            let e = max_rel_err(&g[k], &rg[k]);
            assert!(e < 1e-4, "case {seed}: device gradient of {name} differs by {e}");
        }
    }
}
