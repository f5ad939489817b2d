//! The splat on the host, forward and backward, over a packed Gaussian table (`layout`). The
//! reference the device kernel is tested against, and the `flex` backend's implementation.
//!
//! Forward writes each output voxel from one thread only (the region is cut into bands of rows
//! and every band visits its Gaussians in index order), so a voxel's sum is taken in the same
//! order on any thread count: the bytes do not depend on the machine. Backward is one Gaussian
//! per task, each reading the voxels of its window and writing its own gradient row.

use super::super::par::{par_zeroed_parts, par_zeros};
use super::layout::{self, COLS, SplatShape};
use crate::backend::layout::{N_LABELS, NZ};
use rayon::prelude::*;

/// The window's anchor voxel of one Gaussian, `None` when its mean is not finite.
#[inline]
fn centre(row: &[f32]) -> Option<[i64; 3]> {
    let m = [row[layout::MEAN], row[layout::MEAN + 1], row[layout::MEAN + 2]];
    if m.iter().all(|v| v.is_finite() && v.abs() < 1e9) { Some(m.map(|v| v.floor() as i64)) } else { None }
}

/// The per-voxel terms of one Gaussian at voxel centre `p`: the offset d = p - m, the local
/// coordinates u = R^T d, and e = exp(-q / 2), q = sum_j (u_j / s_j)^2.
#[inline]
fn terms(row: &[f32], p: [f32; 3]) -> ([f32; 3], [f32; 3], f32) {
    let d = [p[0] - row[layout::MEAN], p[1] - row[layout::MEAN + 1], p[2] - row[layout::MEAN + 2]];
    let r = &row[layout::ROT..layout::ROT + 9];
    let mut u = [0f32; 3];
    let mut q = 0f32;
    for j in 0..3 {
        u[j] = d[0] * r[j] + d[1] * r[3 + j] + d[2] * r[6 + j];
        let t = u[j] / row[layout::SCALE + j];
        q += t * t;
    }
    (d, u, (-0.5 * q).exp())
}

/// Logits `[batch * region voxels, 9]`, row-major.
pub fn forward(g: &[f32], s: &SplatShape) -> Vec<f32> {
    let n = g.len() / COLS;
    let voxels = s.region.voxels();
    if n == 0 || s.batch * voxels == 0 {
        return par_zeros(s.batch * voxels * N_LABELS);
    }
    let r = s.window as i64;
    // Bands of BAND region rows (x) per batch element; each Gaussian is listed in every band its
    // window's rows touch, in index order.
    const BAND: usize = 4;
    let (ni, nj) = (s.region.ni, s.region.nj);
    let bands_per = ni.div_ceil(BAND);
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); s.batch * bands_per];
    for (idx, row) in g.chunks_exact(COLS).enumerate() {
        let Some(c) = centre(row) else { continue };
        let b = row[layout::BATCH] as usize;
        if b >= s.batch {
            continue;
        }
        let lo = (c[0] - r - s.region.i0 as i64).max(0);
        let hi = (c[0] + r - s.region.i0 as i64).min(ni as i64 - 1);
        if lo > hi {
            continue;
        }
        for band in lo as usize / BAND..=hi as usize / BAND {
            members[b * bands_per + band].push(idx as u32);
        }
    }
    let row_len = nj * NZ * N_LABELS;
    let lens: Vec<usize> = (0..s.batch * bands_per).map(|i| BAND.min(ni - i % bands_per * BAND) * row_len).collect();
    par_zeroed_parts(&lens, |i, o| {
        let li0 = (i % bands_per * BAND) as i64;
        let li1 = li0 + (o.len() / row_len) as i64;
        for &idx in &members[i] {
            let row = &g[idx as usize * COLS..(idx as usize + 1) * COLS];
            splat_one(row, s, r, li0, li1, o);
        }
    })
}

/// Adds one Gaussian's contributions to the rows `li0..li1` of a band (`o` starts at row li0).
#[inline]
fn splat_one(row: &[f32], s: &SplatShape, r: i64, li0: i64, li1: i64, o: &mut [f32]) {
    let Some(c) = centre(row) else { return };
    let (nj, a) = (s.region.nj as i64, row[layout::OPACITY]);
    let feat = &row[layout::FEAT..layout::FEAT + N_LABELS];
    for vi in c[0] - r..=c[0] + r {
        let li = vi - s.region.i0 as i64;
        if li < li0 || li >= li1 {
            continue;
        }
        for vj in c[1] - r..=c[1] + r {
            let lj = vj - s.region.j0 as i64;
            if lj < 0 || lj >= nj {
                continue;
            }
            for vk in (c[2] - r).max(0)..=(c[2] + r).min(NZ as i64 - 1) {
                let p = [vi as f32 + 0.5, vj as f32 + 0.5, vk as f32 + 0.5];
                let w = a * terms(row, p).2;
                let at = (((li - li0) * nj + lj) as usize * NZ + vk as usize) * N_LABELS;
                for (dst, f) in o[at..at + N_LABELS].iter_mut().zip(feat) {
                    *dst += w * f;
                }
            }
        }
    }
}

/// Gradient of sum(grad * forward(g)) with respect to `g`, `[N, COLS]` (the batch column's is 0).
pub fn backward(g: &[f32], grad: &[f32], s: &SplatShape) -> Vec<f32> {
    let mut out = par_zeros(g.len());
    let r = s.window as i64;
    out.par_chunks_mut(COLS).zip(g.par_chunks(COLS)).for_each(|(go, row)| {
        let Some(c) = centre(row) else { return };
        let b = row[layout::BATCH] as usize;
        if b >= s.batch {
            return;
        }
        let per = s.region.voxels() * N_LABELS;
        backward_one(row, &grad[b * per..(b + 1) * per], s, c, r, go);
    });
    out
}

fn backward_one(row: &[f32], grad: &[f32], s: &SplatShape, c: [i64; 3], r: i64, go: &mut [f32]) {
    let (a, feat) = (row[layout::OPACITY], &row[layout::FEAT..layout::FEAT + N_LABELS]);
    let rot = &row[layout::ROT..layout::ROT + 9];
    let sc = [row[layout::SCALE], row[layout::SCALE + 1], row[layout::SCALE + 2]];
    let (mut gm, mut gs, mut gr, mut ga, mut gf) = ([0f32; 3], [0f32; 3], [0f32; 9], 0f32, [0f32; N_LABELS]);
    for vi in c[0] - r..=c[0] + r {
        for vj in c[1] - r..=c[1] + r {
            for vk in c[2] - r..=c[2] + r {
                let Some(f) = s.region.flat(vi, vj, vk) else { continue };
                let gv = &grad[f * N_LABELS..(f + 1) * N_LABELS];
                let (d, u, e) = terms(row, [vi as f32 + 0.5, vj as f32 + 0.5, vk as f32 + 0.5]);
                let w = a * e;
                let mut gw = 0f32;
                for l in 0..N_LABELS {
                    gf[l] += w * gv[l];
                    gw += feat[l] * gv[l];
                }
                ga += gw * e;
                let gq = -0.5 * gw * w;
                let mut gu = [0f32; 3];
                for j in 0..3 {
                    let inv = 1.0 / sc[j];
                    gu[j] = gq * 2.0 * u[j] * inv * inv;
                    gs[j] -= gq * 2.0 * u[j] * u[j] * inv * inv * inv;
                }
                for ax in 0..3 {
                    let mut gd = 0f32;
                    for j in 0..3 {
                        gr[3 * ax + j] += gu[j] * d[ax];
                        gd += gu[j] * rot[3 * ax + j];
                    }
                    // d = p - m
                    gm[ax] -= gd;
                }
            }
        }
    }
    go[layout::MEAN..layout::MEAN + 3].copy_from_slice(&gm);
    go[layout::SCALE..layout::SCALE + 3].copy_from_slice(&gs);
    go[layout::ROT..layout::ROT + 9].copy_from_slice(&gr);
    go[layout::OPACITY] = ga;
    go[layout::FEAT..layout::FEAT + N_LABELS].copy_from_slice(&gf);
}
