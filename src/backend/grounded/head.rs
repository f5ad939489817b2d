//! The last steps of the generator on the host, fused into one pass over the voxels: the layer
//! bias added to the splat, the background head's gated residual, the argmax. In: the splat
//! `[voxels, 9]` (no bias), the layer bias `[NZ, 9]`, the residual per feature pixel and layer
//! with the pixel each column reads. Out: one label per voxel.
//!
//! The arithmetic is `Generator::forward`'s, operation for operation (burn's CPU softmax of a
//! 9-wide row is a scalar max, `exp`, a sum in order and a multiply by the inverse; argmax keeps
//! the first maximum), so the labels are the argmax of its logits bit for bit
//! (tests/grounded_infer.rs) without the five grid-sized tensors the tensor path builds.

use crate::backend::layout::{N_LABELS, NZ};
use rayon::prelude::*;

/// The background head's residual: `values` `[pixels * NZ]`, and for each column of the splat
/// the pixel it reads (`model::feature_columns`).
pub struct Residual<'a> {
    pub values: &'a [f32],
    pub columns: &'a [i64],
}

/// Columns per task: a task's voxels are contiguous and independent of the others'.
const COLUMNS_PER_TASK: usize = 1024;

/// Labels of `splat + bias (+ the gated residual)`, one per voxel.
pub fn labels(splat: &[f32], bias: &[f32], residual: Option<Residual>) -> Vec<u8> {
    let voxels = splat.len() / N_LABELS;
    let mut out = vec![0u8; voxels];
    let per_task = COLUMNS_PER_TASK * NZ;
    out.par_chunks_mut(per_task).enumerate().for_each(|(task, labels)| {
        let v0 = task * per_task;
        for (dv, label) in labels.iter_mut().enumerate() {
            let v = v0 + dv;
            let k = v % NZ;
            let mut l = [0f32; N_LABELS];
            for (c, l) in l.iter_mut().enumerate() {
                *l = splat[v * N_LABELS + c] + bias[k * N_LABELS + c];
            }
            if let Some(r) = &residual {
                let pixel = r.columns[v / NZ] as usize;
                let rr = r.values[pixel * NZ + k] * gate(&l);
                l[0] += -rr;
                l[1] += rr;
            }
            *label = argmax(&l);
        }
    });
    out
}

/// softmax(l)[0] + softmax(l)[1], as burn's CPU softmax computes it.
#[inline]
fn gate(l: &[f32; N_LABELS]) -> f32 {
    let mut max = f32::NEG_INFINITY;
    for &x in l {
        if x > max {
            max = x;
        }
    }
    let mut e = [0f32; N_LABELS];
    let mut sum = 0f32;
    for (e, &x) in e.iter_mut().zip(l) {
        *e = (x - max).exp();
        sum += *e;
    }
    let inv = 1.0 / sum;
    e[0] * inv + e[1] * inv
}

/// The first index of the largest value (of the first NaN, as burn's CPU argmax).
#[inline]
fn argmax(l: &[f32; N_LABELS]) -> u8 {
    let mut best = 0;
    for (c, &v) in l.iter().enumerate() {
        if v.is_nan() {
            return c as u8;
        }
        if v > l[best] {
            best = c;
        }
    }
    best as u8
}
