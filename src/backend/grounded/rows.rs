//! Row operations whose backward passes a GPU can run in parallel. burn's `select` on rows
//! gathers forward, but its backward on a cubecl device (wgpu, CUDA) runs one unit per column,
//! each walking every index in turn, and the backward of a `repeat_dim` over a million rows is
//! one unit per output summing the million: on one H200 a `paper` step at batch 6 spent 0.9 s
//! in the first (five calls of 0.1-0.48 s) and 185 ms in the second. Here a device gathers
//! (its backward scatters with atomic adds, one unit per element) and repeats in two stages
//! (two reductions of about a thousand terms each). The CPU keeps `select` and one
//! `repeat_dim`: its sums then run in index order, so training stays byte-identical on any
//! thread count.

use burn::prelude::*;

/// Rows `idx` of `t` (`[rows, cols]` -> `[idx.len(), cols]`).
pub fn take_rows(t: Tensor<2>, idx: Vec<i64>) -> Tensor<2> {
    let gather = t.device() != Device::flex();
    take_rows_as(t, idx, gather)
}

/// `take_rows` with the formulation chosen by the caller (tests run both on the CPU).
pub fn take_rows_as(t: Tensor<2>, idx: Vec<i64>, gather: bool) -> Tensor<2> {
    let device = t.device();
    let n = idx.len();
    let idx = Tensor::<1, Int>::from_data(TensorData::new(idx, [n]), &device);
    if !gather {
        return t.select(0, idx);
    }
    let cols = t.dims()[1];
    t.gather(0, idx.reshape([n, 1]).expand([n, cols]))
}

/// `row` (`[1, w]`) repeated `n` times: `[n, w]`.
pub fn repeat_rows(row: Tensor<2>, n: usize) -> Tensor<2> {
    let two_stage = row.device() != Device::flex();
    repeat_rows_as(row, n, two_stage)
}

/// `repeat_rows` with the formulation chosen by the caller (tests run both on the CPU).
pub fn repeat_rows_as(row: Tensor<2>, n: usize, two_stage: bool) -> Tensor<2> {
    let w = row.dims()[1];
    let inner = if two_stage { split(n) } else { 1 };
    if inner <= 1 {
        return row.repeat_dim(0, n);
    }
    row.repeat_dim(0, inner).reshape([1, inner * w]).repeat_dim(0, n / inner).reshape([n, w])
}

/// Each row's sum (`[k, n]` -> `[k, 1]`). A device sums blocks of `BLOCK` columns first: one
/// unit per row walking 1.4 M columns (the Lovász term of a `paper` step) is the other slow
/// reduction above.
pub fn sum_rows(t: Tensor<2>) -> Tensor<2> {
    let blocks = t.device() != Device::flex();
    sum_rows_as(t, blocks)
}

/// Columns per block of `sum_rows` on a device.
const BLOCK: usize = 1024;

/// `sum_rows` with the formulation chosen by the caller (tests run both on the CPU).
pub fn sum_rows_as(t: Tensor<2>, blocks: bool) -> Tensor<2> {
    let [k, n] = t.dims();
    if !blocks || n <= 4 * BLOCK {
        return t.sum_dim(1);
    }
    let m = n.div_ceil(BLOCK) * BLOCK;
    let t = if m > n { Tensor::cat(vec![t.clone(), Tensor::zeros([k, m - n], &t.device())], 1) } else { t };
    t.reshape([k, m / BLOCK, BLOCK]).sum_dim(2).sum_dim(1).reshape([k, 1])
}

/// The largest divisor of `n` up to 1024: the inner stage's length.
fn split(n: usize) -> usize {
    (1..=n.min(1024)).rev().find(|d| n.is_multiple_of(*d)).unwrap_or(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values(n: usize, salt: u32) -> Vec<f32> {
        (0..n).map(|i| ((i as u32).wrapping_mul(2654435761).wrapping_add(salt) % 1000) as f32 / 500.0 - 1.0).collect()
    }

    fn max_diff(a: &[f32], b: &[f32]) -> f32 {
        assert_eq!(a.len(), b.len());
        a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
    }

    /// Value and gradient (through a weighted sum) of `f` on a fresh leaf from `data`.
    fn run(
        data: &[f32],
        shape: [usize; 2],
        weights: &[f32],
        f: impl Fn(Tensor<2>) -> Tensor<2>,
    ) -> (Vec<f32>, Vec<f32>) {
        let device = super::super::cpu().autodiff();
        let x = Tensor::<2>::from_data(TensorData::new(data.to_vec(), shape), &device).require_grad();
        let y = f(x.clone());
        let dims = y.dims();
        let w = Tensor::<2>::from_data(TensorData::new(weights.to_vec(), dims), &device);
        let grads = (y.clone() * w).sum().backward();
        let g = x.grad(&grads).expect("gradient");
        (y.into_data().try_to_vec::<f32>().unwrap(), g.into_data().try_to_vec::<f32>().unwrap())
    }

    #[test]
    fn gathered_rows_match_selected_rows_and_their_gradient() {
        let (rows, cols) = (37, 5);
        let data = values(rows * cols, 7);
        // Repeated and unordered indices: the gradient sums every use of a row.
        let idx: Vec<i64> = (0..300).map(|i| ((i * 17 + i / 7) % rows) as i64).collect();
        let w = values(idx.len() * cols, 3);
        let (v_sel, g_sel) = run(&data, [rows, cols], &w, |t| take_rows_as(t, idx.clone(), false));
        let (v_gat, g_gat) = run(&data, [rows, cols], &w, |t| take_rows_as(t, idx.clone(), true));
        assert_eq!(v_sel, v_gat);
        assert!(max_diff(&g_sel, &g_gat) < 1e-5, "{}", max_diff(&g_sel, &g_gat));
        assert!(g_sel.iter().any(|&g| g.abs() > 0.1));
    }

    #[test]
    fn two_stage_repeat_matches_one_repeat_and_its_gradient() {
        for n in [1usize, 7, 960, 2 * 1031, 6 * 400] {
            let w = 12;
            let data = values(w, n as u32);
            let wts = values(n * w, 11);
            let (v1, g1) = run(&data, [1, w], &wts, |t| repeat_rows_as(t, n, false));
            let (v2, g2) = run(&data, [1, w], &wts, |t| repeat_rows_as(t, n, true));
            assert_eq!(v1, v2, "n = {n}");
            assert!(max_diff(&g1, &g2) < 1e-3, "n = {n}: {}", max_diff(&g1, &g2));
        }
        assert_eq!(split(960_000), 1000);
        assert_eq!(split(2 * 1031), 2);
    }

    #[test]
    fn blockwise_row_sums_match_row_sums_and_their_gradient() {
        for n in [100usize, 4 * BLOCK + 1, 5 * BLOCK, 13_000] {
            let k = 3;
            let data = values(k * n, n as u32);
            let wts = values(k, 5);
            let (v1, g1) = run(&data, [k, n], &wts, |t| sum_rows_as(t, false));
            let (v2, g2) = run(&data, [k, n], &wts, |t| sum_rows_as(t, true));
            assert!(max_diff(&v1, &v2) < 1e-2, "n = {n}: {}", max_diff(&v1, &v2));
            assert!(v1.iter().any(|v| v.abs() > 1.0));
            assert_eq!(g1, g2, "n = {n}");
        }
        assert_eq!(split(7), 7);
    }
}
