//! `bench splat [--device cpu|wgpu|cuda] [--gaussians N]`: the splat operation on a device checked
//! against the CPU (values and every parameter's gradient on random small cases, `splat::check`),
//! then its forward and backward milliseconds for N Gaussians spread over full 400 x 400 x 32 grids
//! (default 2,359,296: the paper config's most, 4,096 latents x 96, at batch 6).

use super::opt;
use rocc::backend::grounded::DeviceKind;
use rocc::backend::grounded::splat::check::{Case, NAMES, within_tolerance};
use rocc::backend::grounded::splat::{Gaussians, Region, splat};
use rocc::backend::layout::{N_LABELS, NX, NY, NZ};
use rocc::sample::Rng;

use burn::prelude::*;
use std::time::Instant;

const BATCH: usize = 6;
const WINDOW: usize = 3;

pub fn bench_splat(args: &[String]) {
    let kind: DeviceKind = match opt(args, "--device").unwrap_or("cpu").parse() {
        Ok(k) => k,
        Err(e) => return println!("  {e}"),
    };
    let device = match kind.open() {
        Ok(d) => d.autodiff(),
        Err(e) => return println!("  {} {}", e.code, e.message),
    };
    let n: usize = opt(args, "--gaussians").and_then(|s| s.parse().ok()).unwrap_or(4096 * 96 * BATCH);
    println!("== splat on {kind}: checked against the CPU, then {n} Gaussians over {BATCH} full grids");
    let cpu = Device::flex().autodiff();
    for (seed, count, window) in [(21, 200, 2), (22, 120, 3), (23, 2000, 3)] {
        let e = Case::random(seed, count, window).errors(&device, &cpu, !kind.is_gpu());
        let grads: Vec<String> = NAMES.iter().zip(&e[1..]).map(|(k, v)| format!("{k} {v:.1e}")).collect();
        println!(
            "  case {seed} ({count} Gaussians, window {window}): logits {:.1e}, gradients {}: {}",
            e[0],
            grads.join(", "),
            if within_tolerance(&e) { "ok" } else { "DIFFERS" }
        );
    }
    let (mut fwd, mut bwd) = (Vec::new(), Vec::new());
    for rep in 0..5 {
        // Fresh leaves each time: a backward pass consumes the graph it ran on.
        let g = spread(n, rep, &device);
        let _ = device.sync();
        let t0 = Instant::now();
        let logits = splat(&g, Region::full(), BATCH, WINDOW);
        let _ = device.sync();
        let t1 = Instant::now();
        let grads = logits.sum().backward();
        let _ = device.sync();
        fwd.push((t1 - t0).as_secs_f64());
        bwd.push(t1.elapsed().as_secs_f64());
        drop(grads);
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2] * 1e3
    };
    println!(
        "  forward {:.1} ms, backward {:.1} ms (median of 5; logits {:.2} GB)",
        med(&mut fwd),
        med(&mut bwd),
        (BATCH * NX * NY * NZ * N_LABELS * 4) as f64 / 1e9
    );
}

/// N Gaussians at random over `BATCH` full grids, the scales the paper's window allows.
fn spread(n: usize, seed: u64, device: &Device) -> Gaussians {
    let mut r = Rng::new(5 + seed);
    let mut leaf = |cols: usize, range: &dyn Fn(usize) -> (f32, f32)| {
        let v: Vec<f32> = (0..n * cols)
            .map(|i| {
                let (lo, hi) = range(i % cols);
                r.range(lo as f64, hi as f64) as f32
            })
            .collect();
        Tensor::<2>::from_data(TensorData::new(v, [n, cols]), device).require_grad()
    };
    let extent = [NX as f32, NY as f32, NZ as f32];
    let mean = leaf(3, &|c| (0.0, extent[c]));
    let scale = leaf(3, &|_| (0.25, WINDOW as f32 / 3.0));
    let opacity = leaf(1, &|_| (0.05, 0.95));
    let feat = leaf(N_LABELS, &|_| (-2.0, 2.0));
    let eye: Vec<f32> = (0..n).flat_map(|_| [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]).collect();
    let rot = Tensor::<2>::from_data(TensorData::new(eye, [n, 9]), device).require_grad();
    Gaussians { mean, scale, rot, opacity, feat, batch: (0..n).map(|i| i % BATCH).collect() }
}
