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
    use rayon::prelude::*;
    if logits.device() == Device::flex() {
        return cross_entropy::cross_entropy_and_rows(
            logits,
            cross_entropy::Targets::new(target, weights),
            rows.into(),
        );
    }
    let idx = rows.into_par_iter().map(|r| r as i64).collect();
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
    let counts = class_counts(target);
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

/// Voxels per class of `target` (labels past the last class count as the last), on all cores:
/// a serial count of 30.7 M labels (`paper` on full grids) holds a GPU step 50 ms.
pub fn class_counts(target: &[u8]) -> [u64; N_LABELS] {
    use rayon::prelude::*;
    // A comparison count per class over a chunk in cache vectorises; one counter per voxel's
    // class would wait on its own last store.
    target
        .par_chunks(1 << 17)
        .map(|chunk| {
            let mut c = [0u64; N_LABELS];
            for (l, count) in c.iter_mut().enumerate().take(N_LABELS - 1) {
                *count = chunk.iter().map(|&t| (t == l as u8) as u32).sum::<u32>() as u64;
            }
            c[N_LABELS - 1] = chunk.len() as u64 - c.iter().sum::<u64>();
            c
        })
        .reduce(|| [0u64; N_LABELS], |a, b| std::array::from_fn(|i| a[i] + b[i]))
}

/// Gradient of the Lovász extension of the Jaccard loss for ground-truth bits sorted by
/// decreasing error (Berman et al., Alg. 1).
pub fn lovasz_grad(gt_sorted: &[bool]) -> Vec<f32> {
    let mut grad = LovaszGrad::new(gt_sorted.iter().filter(|&&g| g).count());
    gt_sorted.iter().map(|&g| grad.next(g)).collect()
}

/// `lovasz_grad` one sorted row at a time: the Jaccard loss of predicting the rows so far as
/// positive, less its value before this row. Each value depends only on the counts so far, so a
/// walk can start anywhere (`at`) with the same bits as one from the first row.
struct LovaszGrad {
    total: f64,
    inter: f64,
    union_extra: f64,
    prev: f64,
}

impl LovaszGrad {
    fn new(total: usize) -> Self {
        LovaszGrad::at(total, 0, 0)
    }

    /// After `inter` truth rows and `union_extra` others.
    fn at(total: usize, inter: usize, union_extra: usize) -> Self {
        let mut g = LovaszGrad { total: total as f64, inter: inter as f64, union_extra: union_extra as f64, prev: 0.0 };
        if inter + union_extra > 0 {
            g.prev = g.jaccard();
        }
        g
    }

    fn jaccard(&self) -> f64 {
        1.0 - (self.total - self.inter) / (self.total + self.union_extra)
    }

    fn next(&mut self, g: bool) -> f32 {
        if g {
            self.inter += 1.0;
        } else {
            self.union_extra += 1.0;
        }
        let jac = self.jaccard();
        let out = (jac - self.prev) as f32;
        self.prev = jac;
        out
    }
}

/// Lovász-softmax over the rows of `probs` `[N, 9]`: mean over the classes present in `target`
/// of the Lovász extension of 1 - IoU applied to the sorted errors |1[y = c] - p_c|.
///
/// The sort runs on the host (`lovasz_weights`); each row's Lovász weight goes back to the row's
/// own place, so the device takes a weighted sum of the errors without gathering them into
/// sorted order.
pub fn lovasz_softmax(probs: Tensor<2>, target: &[u8]) -> Tensor<1> {
    let device = probs.device();
    let n = target.len();
    let present = present_classes(target);
    if present.is_empty() {
        return Tensor::zeros([1], &device);
    }
    let k = present.len();
    let cols = Tensor::<1, Int>::from_data(
        TensorData::new(present.iter().map(|&c| c as i64).collect::<Vec<_>>(), [k]),
        &device,
    );
    // The present classes' columns, one row per class: only those cross, and each class's sort
    // reads its own row in order.
    let pc = probs.select(1, cols).transpose();
    let data = pc.clone().into_data().convert::<f32>();
    let (fg, w) = match data.as_slice::<f32>() {
        Ok(host) => lovasz_weights(host, target, &present),
        Err(_) => lovasz_weights(&data.iter::<f32>().collect::<Vec<_>>(), target, &present),
    };
    let fg_t = Tensor::<2>::from_data(TensorData::new(fg, [k, n]), &device);
    let w_t = Tensor::<2>::from_data(TensorData::new(w, [k, n]), &device);
    // Per class first: one f32 sum over every class at once loses digits at a million rows.
    super::rows::sum_rows((fg_t - pc).abs() * w_t).sum() / k as f32
}

/// The classes that label some row of `target`, ascending: the ones the Lovász term averages.
pub fn present_classes(target: &[u8]) -> Vec<usize> {
    use rayon::prelude::*;
    (0..N_LABELS).filter(|&c| target.par_iter().any(|&t| t as usize == c)).collect()
}

/// The Lovász term's host side: for each class of `present` (row c of the two `[k, n]` outputs,
/// classes on all cores), its truth bits and each row's Lovász weight, from `probs` `[k, n]`
/// (row c: class `present[c]`'s probability of each row) read on the host.
///
/// Each class sorts packed keys: the error's bits inverted (non-negative floats order as their
/// bits: descending error), then the row, then the row's truth bit, so ties go by row and the
/// order never depends on the sort; the truth bit rides in the key, so the walk in sorted order
/// reads nothing else at random.
pub fn lovasz_weights(probs: &[f32], target: &[u8], present: &[usize]) -> (Vec<f32>, Vec<f32>) {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicU32, Ordering::Relaxed};
    // Rows per task of the walk in sorted order.
    const BLOCK: usize = 1 << 16;
    let n = target.len();
    assert!(n < 1 << 31, "{n} Lovász rows: a row and its truth bit share 32 bits of the sort key");
    assert_eq!(probs.len(), present.len() * n, "one row of probabilities per present class");
    let k = present.len();
    let (mut fg, mut w) = (vec![0f32; k * n], vec![0f32; k * n]);
    if n == 0 {
        return (fg, w);
    }
    // Classes side by side, and each on all cores: fewer classes than cores is the usual case.
    let classes = fg.par_chunks_mut(n).zip(w.par_chunks_mut(n)).zip(probs.par_chunks(n).zip(present));
    classes.for_each(|((fg, w), (p, &c))| {
        fg.par_iter_mut().zip(target).for_each(|(f, &t)| *f = (t as usize == c) as u8 as f32);
        let keys: Vec<u64> = fg
            .par_iter()
            .zip(p)
            .enumerate()
            .map(|(v, (&f, &p))| {
                let e = (f - p).abs();
                (u64::from(!e.to_bits()) << 32) | ((v as u64) << 1) | (f != 0.0) as u64
            })
            .collect();
        let keys = sort_keys(keys);
        // The walk in blocks, each from the truth rows of the blocks before it, each weight
        // stored at its row (rows are distinct: plain stores, from every core).
        let truths: Vec<usize> = keys.par_chunks(BLOCK).map(|b| b.iter().filter(|&&k| k & 1 == 1).count()).collect();
        let total = truths.iter().sum();
        let at_row: Vec<AtomicU32> = (0..n).into_par_iter().map(|_| AtomicU32::new(0)).collect();
        keys.par_chunks(BLOCK).enumerate().for_each(|(i, keys)| {
            let inter = truths[..i].iter().sum();
            let mut grad = LovaszGrad::at(total, inter, i * BLOCK - inter);
            for &key in keys {
                at_row[(key as u32 >> 1) as usize].store(grad.next(key & 1 == 1).to_bits(), Relaxed);
            }
        });
        w.par_iter_mut().zip(at_row).for_each(|(w, g)| *w = f32::from_bits(g.into_inner()));
    });
    (fg, w)
}

/// Sorts keys whose top 32 bits order them and whose low bits ascend within ties (rows in
/// order), on all cores, with the result of a full sort: one pass puts each key in the bucket of
/// its top 16 bits (each part of the input writes its own positions of each bucket, so the pass
/// is stable), then the buckets, small enough for the cache, each sort on their next 16 bits by
/// a stable radix sort of two 8-bit digits.
fn sort_keys(keys: Vec<u64>) -> Vec<u64> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
    const BUCKETS: usize = 1 << 16;
    const PARTS: usize = 16;
    let n = keys.len();
    if n <= BUCKETS {
        let mut keys = keys;
        keys.sort_unstable();
        return keys;
    }
    let bucket = |k: u64| (k >> 48) as usize;
    let part = n.div_ceil(PARTS);
    let counts: Vec<Vec<usize>> = keys
        .par_chunks(part)
        .map(|chunk| {
            let mut c = vec![0usize; BUCKETS];
            for &k in chunk {
                c[bucket(k)] += 1;
            }
            c
        })
        .collect();
    // Part i's first position in bucket b: every key of a lower bucket, then bucket b's keys of
    // the parts before i.
    let mut starts = vec![vec![0usize; BUCKETS]; counts.len()];
    let mut sizes = Vec::new();
    let mut next = 0;
    for b in 0..BUCKETS {
        let first = next;
        for (s, c) in starts.iter_mut().zip(&counts) {
            s[b] = next;
            next += c[b];
        }
        if next > first {
            sizes.push(next - first);
        }
    }
    let out: Vec<AtomicU64> = (0..n).into_par_iter().map(|_| AtomicU64::new(0)).collect();
    keys.par_chunks(part).zip(starts).for_each(|(chunk, mut at)| {
        for &k in chunk {
            let b = bucket(k);
            out[at[b]].store(k, Relaxed);
            at[b] += 1;
        }
    });
    let mut out: Vec<u64> = out.into_par_iter().map(AtomicU64::into_inner).collect();
    let mut buckets = Vec::with_capacity(sizes.len());
    let mut rest = out.as_mut_slice();
    for size in sizes {
        let (b, r) = std::mem::take(&mut rest).split_at_mut(size);
        buckets.push(b);
        rest = r;
    }
    buckets.into_par_iter().for_each(|b| {
        if b.len() <= 64 {
            return b.sort_unstable();
        }
        let mut tmp = vec![0u64; b.len()];
        for shift in [32, 40] {
            let digit = |k: u64| ((k >> shift) & 0xff) as usize;
            let mut at = [0usize; 256];
            for &k in b.iter() {
                at[digit(k)] += 1;
            }
            let mut next = 0;
            for a in at.iter_mut() {
                (*a, next) = (next, next + *a);
            }
            for &k in b.iter() {
                let d = digit(k);
                tmp[at[d]] = k;
                at[d] += 1;
            }
            b.copy_from_slice(&tmp);
        }
    });
    out
}

/// The rows the Lovász term sees, ascending: every voxel an agent class claims, in the truth or
/// the prediction (`predicted`, one flag per voxel, reused as the mark), and the uniform `draws`.
/// On all cores: full grids at batch 6 are 30.7 M voxels.
pub fn lovasz_rows(target: &[u8], mut predicted: Vec<bool>, draws: &[usize]) -> Vec<usize> {
    use rayon::prelude::*;
    const CHUNK: usize = 1 << 16;
    let n = target.len();
    predicted.resize(n, false);
    for &d in draws {
        if let Some(p) = predicted.get_mut(d) {
            *p = true;
        }
    }
    let parts: Vec<Vec<usize>> = predicted
        .par_chunks(CHUNK)
        .zip(target.par_chunks(CHUNK))
        .enumerate()
        .map(|(i, (p, t))| (0..p.len()).filter(|&v| p[v] | (t[v] >= 2)).map(|v| i * CHUNK + v).collect())
        .collect();
    parts.concat()
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
        return flags(&logits.argmax(1).greater_equal_elem(2).into_data());
    }
    let rows: Tensor<1> = Tensor::from_dispatch(<Dispatch as CrossEntropyOps>::agent_rows(logits.into_dispatch()));
    let rows = rows.into_data();
    match rows.as_slice::<f32>() {
        Ok(r) => r.par_iter().map(|&v| v != 0.0).collect(),
        Err(_) => rows.iter::<f32>().map(|v| v != 0.0).collect(),
    }
}

/// A bool tensor read back, as flags, on all cores (burn's element iterator takes 70 ms for the
/// 30.7 M flags of a `paper` batch).
pub fn flags(data: &TensorData) -> Vec<bool> {
    use burn::tensor::{BoolStore, DType};
    use rayon::prelude::*;
    let width = match data.dtype() {
        DType::Bool(BoolStore::U32) => 4,
        DType::Bool(_) => 1,
        _ => return data.iter::<bool>().collect(),
    };
    const CHUNK: usize = 1 << 16;
    let bytes = data.as_bytes();
    let mut out = vec![false; bytes.len() / width];
    out.par_chunks_mut(CHUNK).zip(bytes.par_chunks(CHUNK * width)).for_each(|(out, bytes)| {
        for (o, b) in out.iter_mut().zip(bytes.chunks_exact(width)) {
            *o = b.iter().any(|&x| x != 0);
        }
    });
    out
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

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::{BoolStore, DType};

    #[test]
    fn flags_read_every_bool_store() {
        let v: Vec<bool> = (0..1000).map(|i| i % 3 == 0 || i % 7 == 1).collect();
        let data = TensorData::new(v.clone(), [v.len()]);
        assert_eq!(flags(&data), v);
        for store in [BoolStore::U8, BoolStore::U32] {
            let cast = data.clone().convert_dtype(DType::Bool(store));
            assert_eq!(cast.dtype(), DType::Bool(store));
            assert_eq!(flags(&cast), v, "{store:?}");
        }
    }
}
