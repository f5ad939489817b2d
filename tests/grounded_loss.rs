//! The learned backend's training objectives: Lovász-softmax against a hand-computed case and
//! its definition (ties included), the rows it sees, the weighted cross-entropy's fused CPU
//! operations against the tensor formulation, the training exponential, and (a `wgpu` build)
//! the whole loss on a GPU against the CPU.

use burn::prelude::*;
use rocc::backend::grounded::cpu;
use rocc::backend::grounded::loss::{
    class_weights, lovasz_grad, lovasz_rows, lovasz_softmax, lovasz_weights, weighted_cross_entropy,
};
use rocc::backend::layout::N_LABELS;
use rocc::sample::Rng;

#[test]
fn lovasz_softmax_matches_a_hand_computed_case() {
    let device = cpu();
    // Four voxels, classes 0 (free) and 1 (background) present; see the comment for the numbers.
    let mut p = vec![0f32; 4 * N_LABELS];
    for (v, (p0, p1)) in [(0.9, 0.1), (0.4, 0.6), (0.3, 0.7), (0.8, 0.2)].into_iter().enumerate() {
        p[v * N_LABELS] = p0;
        p[v * N_LABELS + 1] = p1;
    }
    let target = [0u8, 0, 1, 1];
    // Class 0: errors [0.1, 0.6, 0.3, 0.8] -> order v3 v1 v2 v0, truth [0, 1, 0, 1], Jaccard
    // 1/3, 2/3, 3/4, 1 -> grad [1/3, 1/3, 1/12, 1/4] -> 0.8/3 + 0.6/3 + 0.3/12 + 0.1/4.
    // Class 1: same errors, truth [1, 0, 1, 0], Jaccard 1/2, 2/3, 1, 1 -> 0.4 + 0.1 + 0.1 + 0.
    let want = ((0.8 / 3.0 + 0.6 / 3.0 + 0.3 / 12.0 + 0.1 / 4.0) + (0.4 + 0.1 + 0.1)) / 2.0;
    let probs = Tensor::<2>::from_data(TensorData::new(p, [4, N_LABELS]), &device);
    let got = lovasz_softmax(probs, &target).into_scalar::<f32>() as f64;
    assert!((got - want).abs() < 1e-6, "lovasz {got}, by hand {want}");
    assert_eq!(lovasz_grad(&[false, true, false, true]), vec![1.0 / 3.0, 1.0 / 3.0, 1.0 / 12.0, 0.25]);
    // On hard 0/1 predictions the Lovász extension is exactly 1 - IoU, averaged over present classes.
    let hard: Vec<f32> =
        [0usize, 1, 1, 1].iter().flat_map(|&c| (0..N_LABELS).map(move |k| (k == c) as u8 as f32)).collect();
    let got = lovasz_softmax(Tensor::<2>::from_data(TensorData::new(hard, [4, N_LABELS]), &device), &target);
    // class 0: IoU 1/2; class 1: IoU 2/3.
    assert!((got.into_scalar::<f32>() as f64 - ((1.0 - 0.5) + (1.0 - 2.0 / 3.0)) / 2.0).abs() < 1e-6);
}

/// Lovász weights by the definition: per class, rows by decreasing error (ties by row), then
/// `lovasz_grad` of the truth bits in that order, each weight put back at its row. `p`: the
/// class's probability of each row.
fn lovasz_weights_by_definition(p: &[f32], target: &[u8], c: usize) -> Vec<f32> {
    let err = |v: usize| ((target[v] as usize == c) as u8 as f32 - p[v]).abs();
    let mut order: Vec<usize> = (0..target.len()).collect();
    order.sort_by(|&a, &b| err(b).total_cmp(&err(a)).then(a.cmp(&b)));
    let grad = lovasz_grad(&order.iter().map(|&v| target[v] as usize == c).collect::<Vec<_>>());
    let mut w = vec![0f32; target.len()];
    for (v, g) in order.into_iter().zip(grad) {
        w[v] = g;
    }
    w
}

#[test]
fn lovasz_weights_follow_the_definition_ties_included() {
    let mut rng = Rng::new(11);
    let present = [0, 1, 2, 5];
    // Below and above the size where the sort turns to buckets and the walk to blocks; on a
    // coarse grid of 17 probabilities most errors tie with many others.
    for (n, coarse) in [(5_000, true), (200_000, true), (200_000, false)] {
        let target: Vec<u8> = (0..n).map(|_| [0, 0, 0, 1, 2, 5][rng.index(6)]).collect();
        let draw = |rng: &mut Rng| if coarse { rng.index(17) as f32 / 16.0 } else { rng.unit() as f32 };
        let probs: Vec<f32> = (0..n * present.len()).map(|_| draw(&mut rng)).collect();
        let (fg, w) = lovasz_weights(&probs, &target, &present);
        for (i, &c) in present.iter().enumerate() {
            let row = i * n..(i + 1) * n;
            let truth: Vec<f32> = target.iter().map(|&t| (t as usize == c) as u8 as f32).collect();
            assert_eq!(fg[row.clone()], truth[..], "class {c}: truth bits");
            let want = lovasz_weights_by_definition(&probs[row.clone()], &target, c);
            let same = w[row.clone()].iter().zip(&want).all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "{n} rows, coarse {coarse}, class {c}: weights");
            // The weights of a class are the steps of the Jaccard loss: they sum to 1.
            assert!((w[row].iter().map(|&x| x as f64).sum::<f64>() - 1.0).abs() < 1e-4);
        }
    }
    let (fg, w) = lovasz_weights(&[], &[], &present);
    assert!(fg.is_empty() && w.is_empty());
}

#[test]
fn lovasz_rows_are_the_claimed_voxels_and_the_draws() {
    let mut rng = Rng::new(5);
    let n = 100_000;
    let target: Vec<u8> =
        (0..n).map(|_| if rng.unit() < 0.05 { 2 + rng.index(7) as u8 } else { rng.index(2) as u8 }).collect();
    let predicted: Vec<bool> = (0..n - 10).map(|_| rng.unit() < 0.03).collect();
    let draws: Vec<usize> = (0..2_000).map(|_| rng.index(n)).chain([0, n - 1, n - 1, n + 7]).collect();
    let got = lovasz_rows(&target, predicted.clone(), &draws);
    let mut want: Vec<usize> =
        (0..n).filter(|&v| target[v] >= 2 || predicted.get(v) == Some(&true)).chain(draws.iter().copied()).collect();
    want.retain(|&v| v < n);
    want.sort_unstable();
    want.dedup();
    assert_eq!(got, want);
    assert!(got.len() > 7_000, "agents, predictions and draws: {}", got.len());
}

#[test]
fn weighted_cross_entropy_and_class_weights() {
    let device = cpu();
    let logits = Tensor::<2>::from_data(TensorData::new(vec![0f32; 2 * N_LABELS], [2, N_LABELS]), &device);
    let mut w = [1f32; N_LABELS];
    w[2] = 3.0;
    // Uniform logits: -log(1/9) per voxel whatever the weights.
    let ce = weighted_cross_entropy(logits, &[0, 2], &w).into_scalar::<f32>() as f64;
    assert!((ce - 9f64.ln()).abs() < 1e-5);
    let mut counts = [0u64; N_LABELS];
    counts[0] = 1_000_000;
    counts[1] = 10_000;
    counts[2] = 100;
    let cw = class_weights(&counts, 0.5, 25.0, &[1.0; N_LABELS]);
    assert_eq!(cw[0], 1.0);
    assert!((cw[1] - 10.0).abs() < 1e-4);
    assert_eq!(cw[2], 25.0, "clipped");
    assert_eq!(cw[5], 25.0, "unseen classes get the clip");
}

/// The CPU's fused cross-entropy (`weighted_cross_entropy` on the CPU) against the tensor
/// formulation: value and the logits' gradient, over more rows than one block of the fused pass.
#[test]
fn fused_cross_entropy_matches_the_tensor_formulation() {
    use rocc::backend::grounded::loss::weighted_cross_entropy_tensor_ops;
    let device = cpu().autodiff();
    let mut rng = Rng::new(4);
    let n = 40_000;
    let logits: Vec<f32> = (0..n * N_LABELS).map(|_| (rng.normal() * 3.0) as f32).collect();
    let target: Vec<u8> = (0..n).map(|_| rng.index(N_LABELS) as u8).collect();
    let mut w = [1f32; N_LABELS];
    w[3] = 7.5;
    w[8] = 0.25;
    let run = |fused: bool| -> (f32, Vec<f32>) {
        let l = Tensor::<2>::from_data(TensorData::new(logits.clone(), [n, N_LABELS]), &device).require_grad();
        let ce = if fused {
            weighted_cross_entropy(l.clone(), &target, &w)
        } else {
            weighted_cross_entropy_tensor_ops(l.clone(), &target, &w)
        };
        let v = ce.clone().into_scalar::<f32>();
        let grads = (ce * 3.0).backward();
        (v, l.grad(&grads).expect("the logits get a gradient").to_data().iter::<f32>().collect())
    };
    let ((v, g), (rv, rg)) = (run(true), run(false));
    assert!((v - rv).abs() < 1e-5 * rv.abs(), "value {v} against {rv}");
    let scale = rg.iter().fold(0f32, |m, x| m.max(x.abs()));
    let err = g.iter().zip(&rg).fold(0f32, |m, (a, b)| m.max((a - b).abs())) / scale;
    assert!(err < 1e-5, "gradient differs by {err} of its largest element");
    assert!(scale > 0.0);
}

/// The CPU's cross-entropy with the Lovász rows' softmax in one operation against the tensor
/// formulation (the cross-entropy, and `softmax` of the rows taken with `take_rows`): both
/// values, and the logits' gradient through a loss that uses both.
#[test]
fn cross_entropy_and_rows_match_the_tensor_formulation() {
    use burn::tensor::activation::softmax;
    use rocc::backend::grounded::cross_entropy::{Targets, cross_entropy_and_rows};
    use rocc::backend::grounded::loss::weighted_cross_entropy_tensor_ops;
    use rocc::backend::grounded::rows::take_rows;
    let device = cpu().autodiff();
    let mut rng = Rng::new(6);
    let n = 30_000;
    let logits: Vec<f32> = (0..n * N_LABELS).map(|_| (rng.normal() * 3.0) as f32).collect();
    let target: Vec<u8> = (0..n).map(|_| rng.index(N_LABELS) as u8).collect();
    let rows: Vec<usize> = (0..n).filter(|v| v % 7 == 3 || v % 11 == 0).collect();
    let m = rows.len();
    let weights_of_probs: Vec<f32> = (0..m * N_LABELS).map(|_| rng.normal() as f32).collect();
    let w = [1.0, 0.5, 3.0, 1.0, 1.0, 9.0, 1.0, 1.0, 2.0];
    let run = |fused: bool| -> (f32, Vec<f32>, Vec<f32>) {
        let l = Tensor::<2>::from_data(TensorData::new(logits.clone(), [n, N_LABELS]), &device).require_grad();
        let (ce, probs) = if fused {
            cross_entropy_and_rows(l.clone(), Targets::new(&target, &w), rows.clone().into())
        } else {
            let sel = rows.iter().map(|&r| r as i64).collect();
            (weighted_cross_entropy_tensor_ops(l.clone(), &target, &w), softmax(take_rows(l.clone(), sel), 1))
        };
        let pw = Tensor::<2>::from_data(TensorData::new(weights_of_probs.clone(), [m, N_LABELS]), &device);
        let p: Vec<f32> = probs.to_data().iter::<f32>().collect();
        let v = ce.clone().into_scalar::<f32>();
        let grads = (ce * 3.0 + (probs * pw).sum()).backward();
        (v, p, l.grad(&grads).expect("the logits get a gradient").to_data().iter::<f32>().collect())
    };
    let ((v, p, g), (rv, rp, rg)) = (run(true), run(false));
    assert!((v - rv).abs() < 1e-5 * rv.abs(), "value {v} against {rv}");
    let max_diff = |a: &[f32], b: &[f32]| a.iter().zip(b).fold(0f32, |m, (x, y)| m.max((x - y).abs()));
    assert!(p.len() == m * N_LABELS && max_diff(&p, &rp) < 1e-6, "probabilities differ by {}", max_diff(&p, &rp));
    let scale = rg.iter().fold(0f32, |m, x| m.max(x.abs()));
    assert!(max_diff(&g, &rg) < 1e-5 * scale && scale > 0.0, "gradient differs by {}", max_diff(&g, &rg) / scale);
}

/// The exponential of the CPU's training passes against f64's, over the range a softmax feeds
/// it (and beyond), in units of the f32 result's last place.
#[test]
fn the_training_exponential_is_within_two_ulp() {
    use rocc::backend::grounded::expf::{exp, exp_in_place};
    let xs: Vec<f32> = (0..=400_000).map(|i| -87.0 + 97.0 * i as f32 / 400_000.0).collect();
    let mut v = xs.clone();
    exp_in_place(&mut v);
    let mut worst = 0f64;
    for (&x, &got) in xs.iter().zip(&v) {
        let truth = (x as f64).exp();
        let t = truth as f32;
        let ulp = (f32::from_bits(t.to_bits() + 1) - t) as f64;
        worst = worst.max((got as f64 - truth).abs() / ulp);
        assert_eq!(got.to_bits(), exp(x).to_bits());
    }
    assert!(worst <= 2.0, "{worst} ulp");
    assert!(exp(f32::NAN).is_nan());
    assert_eq!(exp(0.0), 1.0);
}

/// The CPU's fused head (bias and gated background residual) against its tensor formulation
/// under autodiff (whose softmax rounds differently from the CPU kernel the labels test pins):
/// the logits and the gradients of splat, bias and residual.
/// A training step's loss on a GPU (tensor operations, the predicted-agent flags read back in
/// the device's own bool layout) against the CPU's fused operations: on Mesa's software Vulkan
/// here, on whatever adapter a `wgpu` build finds elsewhere.
#[cfg(feature = "wgpu")]
#[test]
fn the_loss_on_a_gpu_matches_the_cpu() {
    use rocc::backend::grounded::loss::{agent_predicted, cross_entropy_and_probs};
    let mut rng = Rng::new(9);
    let n = 20_000;
    let logits: Vec<f32> = (0..n * N_LABELS).map(|_| (rng.normal() * 2.0) as f32).collect();
    let target: Vec<u8> = (0..n).map(|_| [0, 0, 0, 1, 1, 2, 4, 7][rng.index(8)]).collect();
    let w = [1.0, 0.5, 3.0, 1.0, 1.0, 9.0, 1.0, 1.0, 2.0];
    let run = |device: Device| -> (Vec<usize>, f32, f32, Vec<f32>) {
        let l = Tensor::<2>::from_data(TensorData::new(logits.clone(), [n, N_LABELS]), &device).require_grad();
        let rows = lovasz_rows(&target, agent_predicted(&l), &[3, 17, 4_000]);
        let sel: Vec<u8> = rows.iter().map(|&v| target[v]).collect();
        let (ce, probs) = cross_entropy_and_probs(l.clone(), &target, &w, rows.clone());
        let lov = lovasz_softmax(probs, &sel);
        let (c, v) = (ce.clone().into_scalar::<f32>(), lov.clone().into_scalar::<f32>());
        let grads = (ce + lov).backward();
        (rows, c, v, l.grad(&grads).expect("the logits get a gradient").to_data().iter::<f32>().collect())
    };
    let (rows, ce, lov, g) = run(Device::wgpu(Default::default()).autodiff());
    let (want_rows, want_ce, want_lov, want_g) = run(cpu().autodiff());
    assert_eq!(rows, want_rows, "the Lovász rows (agents claimed by the truth or the argmax)");
    assert!(rows.len() > n / 2, "random logits claim most voxels for an agent: {}", rows.len());
    assert!((ce - want_ce).abs() < 1e-5 * want_ce.abs(), "cross-entropy {ce} against {want_ce}");
    assert!((lov - want_lov).abs() < 1e-5 * want_lov.abs(), "Lovász {lov} against {want_lov}");
    let scale = want_g.iter().fold(0f32, |m, x| m.max(x.abs()));
    let diff = g.iter().zip(&want_g).fold(0f32, |m, (x, y)| m.max((x - y).abs()));
    assert!(diff < 1e-4 * scale && scale > 0.0, "gradient differs by {}", diff / scale);
}
