//! Training objectives. In: logits `[N, 9]` (or probabilities) and ground-truth labels. Out:
//! scalar loss tensors: class-weighted cross-entropy, Lovász-softmax (Berman et al. 2018, the
//! "present classes" variant), the VAE's KL term and the background head's auxiliary
//! cross-entropy.

use super::cross_entropy;
use crate::backend::layout::N_LABELS;
use burn::prelude::*;
use burn::tensor::activation::{log_softmax, softmax};

/// Rows per slice of the cross-entropy: its [rows, 9] intermediates stay near 150 MB, inside a
/// GPU buffer, however many voxels the batch holds (full grids at batch 6 are 30.7 M rows).
const CE_ROWS: usize = 4 << 20;

/// sum_v w[y_v] * -log softmax(logits_v)[y_v] / sum_v w[y_v]: on the CPU one fused operation
/// (`cross_entropy`), elsewhere `weighted_cross_entropy_tensor_ops`.
pub fn weighted_cross_entropy(logits: Tensor<2>, target: &[u8], weights: &[f32; N_LABELS]) -> Tensor<1> {
    if logits.device() == Device::flex() {
        return cross_entropy::cross_entropy(logits, cross_entropy::Targets::new(target, weights));
    }
    weighted_cross_entropy_tensor_ops(logits, target, weights)
}

/// `weighted_cross_entropy` and the softmax of the rows `rows` (ascending, distinct) of the
/// logits, `[m, 9]` (the Lovász term's probabilities): on the CPU one operation with one
/// gradient of the logits (`cross_entropy::cross_entropy_and_rows`), elsewhere the two apart.
pub fn cross_entropy_and_probs(
    logits: Tensor<2>,
    target: &[u8],
    weights: &[f32; N_LABELS],
    rows: Vec<usize>,
) -> (Tensor<1>, Tensor<2>) {
    if logits.device() == Device::flex() {
        return cross_entropy::cross_entropy_and_rows(
            logits,
            cross_entropy::Targets::new(target, weights),
            rows.into(),
        );
    }
    let idx = rows.into_iter().map(|r| r as i64).collect();
    (weighted_cross_entropy(logits.clone(), target, weights), softmax(super::rows::take_rows(logits, idx), 1))
}

/// `weighted_cross_entropy` written with tensor operations, in slices of `CE_ROWS` rows. Only
/// the targets cross to the device (as the device's own 32-bit integers, no conversion there);
/// each voxel's weight is looked up on the device and their total comes from the class counts.
pub fn weighted_cross_entropy_tensor_ops(logits: Tensor<2>, target: &[u8], weights: &[f32; N_LABELS]) -> Tensor<1> {
    use rayon::prelude::*;
    let device = logits.device();
    let n = target.len();
    let class = cross_entropy::class;
    let mut counts = [0u64; N_LABELS];
    for &t in target {
        counts[class(t)] += 1;
    }
    let total = counts.iter().zip(weights).map(|(&c, &w)| c as f64 * w as f64).sum::<f64>().max(1e-12) as f32;
    let per_class = Tensor::<1>::from_data(TensorData::new(weights.to_vec(), [N_LABELS]), &device);
    let mut sum: Option<Tensor<1>> = None;
    for start in (0..n).step_by(CE_ROWS) {
        let end = (start + CE_ROWS).min(n);
        let rows = end - start;
        let t: Vec<i32> = target[start..end].par_iter().map(|&t| class(t) as i32).collect();
        let t = Tensor::<1, Int>::from_data(TensorData::new(t, [rows]), &device);
        let lp = log_softmax(logits.clone().narrow(0, start, rows), 1);
        let picked = lp.gather(1, t.clone().reshape([rows, 1])).reshape([rows]);
        let part = (picked * per_class.clone().select(0, t)).sum();
        sum = Some(match sum {
            Some(s) => s + part,
            None => part,
        });
    }
    sum.unwrap_or_else(|| Tensor::zeros([1], &device)).neg() / total
}

/// Gradient of the Lovász extension of the Jaccard loss for ground-truth bits sorted by
/// decreasing error (Berman et al., Alg. 1).
pub fn lovasz_grad(gt_sorted: &[bool]) -> Vec<f32> {
    let total: f64 = gt_sorted.iter().filter(|&&g| g).count() as f64;
    let mut out = Vec::with_capacity(gt_sorted.len());
    let (mut inter, mut union_extra) = (0.0f64, 0.0f64);
    let mut prev = 0.0f64;
    for &g in gt_sorted {
        if g {
            inter += 1.0;
        } else {
            union_extra += 1.0;
        }
        // Jaccard loss of predicting the first i+1 as positive.
        let jac = 1.0 - (total - inter) / (total + union_extra);
        out.push((jac - prev) as f32);
        prev = jac;
    }
    out
}

/// Lovász-softmax over the rows of `probs` `[N, 9]`: mean over the classes present in `target`
/// of the Lovász extension of 1 - IoU applied to the sorted errors |1[y = c] - p_c|.
///
/// The sort runs on the host over packed keys (error bits inverted, then the row: descending
/// error, ties by row, so the order never depends on the sort) for all classes at once; each
/// row's Lovász weight goes back to the row's own place, so the device takes a weighted sum of
/// the errors without gathering them into sorted order.
pub fn lovasz_softmax(probs: Tensor<2>, target: &[u8]) -> Tensor<1> {
    use rayon::prelude::*;
    let device = probs.device();
    let n = target.len();
    let host: Vec<f32> = probs.to_data().iter::<f32>().collect();
    let present: Vec<usize> = (0..N_LABELS).filter(|&c| target.iter().any(|&t| t as usize == c)).collect();
    if present.is_empty() {
        return Tensor::zeros([1], &device);
    }
    // Row c of `fg` and `w`: class `present[c]`'s truth bits and each row's Lovász weight.
    let k = present.len();
    let (mut fg, mut w) = (vec![0f32; k * n], vec![0f32; k * n]);
    fg.par_chunks_mut(n).zip(w.par_chunks_mut(n)).zip(&present).for_each(|((fg, w), &c)| {
        for (f, &t) in fg.iter_mut().zip(target) {
            *f = (t as usize == c) as u8 as f32;
        }
        let mut keys: Vec<u64> = (0..n)
            .map(|v| {
                let e = (fg[v] - host.get(v * N_LABELS + c).copied().unwrap_or(0.0)).abs();
                (u64::from(!e.to_bits()) << 32) | v as u64
            })
            .collect();
        keys.sort_unstable();
        let row = |k: &u64| (k & 0xffff_ffff) as usize;
        let grad = lovasz_grad(&keys.iter().map(|k| target[row(k)] as usize == c).collect::<Vec<_>>());
        for (k, g) in keys.iter().zip(grad) {
            w[row(k)] = g;
        }
    });
    let cols = Tensor::<1, Int>::from_data(
        TensorData::new(present.iter().map(|&c| c as i64).collect::<Vec<_>>(), [k]),
        &device,
    );
    let fg_t = Tensor::<2>::from_data(TensorData::new(fg, [k, n]), &device);
    let w_t = Tensor::<2>::from_data(TensorData::new(w, [k, n]), &device);
    let pc = probs.select(1, cols).transpose();
    // Per class first: one f32 sum over every class at once loses digits at a million rows.
    super::rows::sum_rows((fg_t - pc).abs() * w_t).sum() / k as f32
}

/// Whether each row's argmax (the first largest value, as burn's) is an agent class (2 and
/// up): the rows Lovász-softmax adds to its draw. The CPU reads the logits in place
/// (`CrossEntropyOps::agent_rows`); elsewhere the argmax runs on the device. Only one flag
/// per row crosses.
pub fn agent_predicted(logits: &Tensor<2>) -> Vec<bool> {
    use burn::backend::Dispatch;
    use cross_entropy::CrossEntropyOps;
    use rayon::prelude::*;
    let logits = logits.clone().detach();
    if logits.device() != Device::flex() {
        return logits.argmax(1).greater_equal_elem(2).to_data().iter::<bool>().collect();
    }
    let rows: Tensor<1> = Tensor::from_dispatch(<Dispatch as CrossEntropyOps>::agent_rows(logits.into_dispatch()));
    let rows = rows.into_data();
    match rows.as_slice::<f32>() {
        Ok(r) => r.par_iter().map(|&v| v != 0.0).collect(),
        Err(_) => rows.iter::<f32>().map(|v| v != 0.0).collect(),
    }
}

/// KL(N(mu, exp(logvar)) || N(0, 1)), summed over channels, averaged over the rows.
pub fn kl_divergence(mu: Tensor<2>, logvar: Tensor<2>) -> Tensor<1> {
    let rows = mu.dims()[0].max(1) as f32;
    let t = logvar.clone() + 1.0 - mu.powi_scalar(2) - logvar.exp();
    t.sum() * (-0.5 / rows)
}

/// Binary cross-entropy with logits, averaged: the background head's auxiliary term.
pub fn bce_with_logits(logit: Tensor<1>, target: &[bool]) -> Tensor<1> {
    let device = logit.device();
    let n = target.len().max(1) as f32;
    let y = Tensor::<1>::from_data(
        TensorData::new(target.iter().map(|&b| b as u8 as f32).collect::<Vec<_>>(), [target.len()]),
        &device,
    );
    // max(x, 0) - x y + log(1 + exp(-|x|)), the stable form.
    let pos = logit.clone().clamp_min(0.0);
    let soft = (logit.clone().abs().neg().exp() + 1.0).log();
    (pos - logit * y + soft).sum() / n
}

/// Class weights from label counts: (max count / count)^power clipped to `clip`, times `boost`;
/// a class never seen gets `clip`.
pub fn class_weights(counts: &[u64; N_LABELS], power: f32, clip: f32, boost: &[f32]) -> [f32; N_LABELS] {
    let max = counts.iter().copied().max().unwrap_or(1).max(1) as f64;
    let mut w = [0f32; N_LABELS];
    for c in 0..N_LABELS {
        let raw =
            if counts[c] == 0 { clip as f64 } else { (max / counts[c] as f64).powf(power as f64).min(clip as f64) };
        w[c] = raw as f32 * boost.get(c).copied().unwrap_or(1.0);
    }
    w
}
