//! Whole-grid labels on a device, a strip of grid rows at a time. A frame's logits are 184 MB in
//! f32 (400 x 400 x 32 voxels x 9 classes), beyond the largest buffer some devices bind (Mesa's
//! software Vulkan, and wgpu's default limits: 128 MiB): inference splats and reads one strip of
//! rows after another from one pass of the decoder, each strip's logits within the device's
//! limit. A device that binds a whole batch's logits takes it in one strip.

use super::config::GroundedConfig;
use super::splat::layout::COLS;
use super::splat::{PARAMS, Region};
use crate::backend::layout::{N_LABELS, NX, NY, NZ};
use burn::prelude::*;

/// The share of the device's largest buffer one block of a pass run in blocks may take (a strip's
/// logits, beside the splat's and the head's buffers of the same size; a block of attention
/// scores).
pub const SHARE: f64 = 0.9;

/// How many units of `unit_bytes` fit in `SHARE` of a largest buffer of `max_bytes`, between 1
/// and `most` (`most` where the device has no limit): the one sizing rule of every pass run in
/// blocks (strips, frames a pass, attention's query blocks).
pub fn fitting(max_bytes: Option<u64>, unit_bytes: usize, most: usize) -> usize {
    let most = most.max(1);
    let Some(max) = max_bytes else { return most };
    ((max as f64 * SHARE / unit_bytes.max(1) as f64).floor() as usize).clamp(1, most)
}

/// Grid rows per strip for `b` frames on a device whose largest buffer is `max_bytes` (`None`:
/// no limit, the whole grid).
pub fn rows_per_strip(b: usize, max_bytes: Option<u64>) -> usize {
    fitting(max_bytes, b.max(1) * NY * NZ * N_LABELS * 4, NX)
}

/// Frames per inference pass: `batch`, fewer where one pass's Gaussians would exceed `SHARE` of
/// the device's largest buffer. They are the largest tensors a pass does not split: at most
/// `latents x max_gaussians` a frame, in rows of `PARAMS` floats (the decoder's output) or of
/// `COLS` (the table the splat reads), `paper` 40.9 MB a frame at `COLS`.
pub fn frames_per_pass(batch: usize, cfg: &GroundedConfig, max_bytes: Option<u64>) -> usize {
    fitting(max_bytes, cfg.latents * cfg.max_gaussians() * PARAMS.max(COLS) * 4, batch)
}

/// Labels `[b * NX * NY * NZ]` (frame by frame, standard layout) from `logits`, which returns a
/// region's logits `[b * region voxels, 9]`, strip by strip of `rows` grid rows.
pub fn labels(b: usize, rows: usize, mut logits: impl FnMut(Region) -> Tensor<2>) -> Vec<u8> {
    let frame = NX * NY * NZ;
    let mut out = vec![0u8; b * frame];
    let rows = rows.clamp(1, NX);
    for i0 in (0..NX).step_by(rows) {
        let region = Region { i0, j0: 0, ni: rows.min(NX - i0), nj: NY };
        let per = region.voxels();
        let ids = logits(region).argmax(1).into_data();
        // A strip of whole rows is one contiguous run of each frame's labels.
        for (k, l) in ids.iter::<i64>().enumerate() {
            out[(k / per) * frame + i0 * NY * NZ + k % per] = l.clamp(0, N_LABELS as i64 - 1) as u8;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_fit_the_limit_and_cover_the_grid() {
        assert_eq!(rows_per_strip(4, None), NX);
        assert_eq!(rows_per_strip(1, Some(u64::MAX)), NX);
        // Mesa's software Vulkan binds 128 MiB: 4 frames take 65 rows a strip.
        let rows = rows_per_strip(4, Some(128 << 20));
        assert_eq!(rows, 65);
        assert!((4 * rows * NY * NZ * N_LABELS * 4) as f64 <= (128u64 << 20) as f64 * SHARE);
        assert_eq!(rows_per_strip(64, Some(1 << 20)), 1);
    }

    #[test]
    fn a_pass_takes_the_frames_whose_gaussians_fit() {
        let paper: GroundedConfig = ron::from_str(include_str!("../../../configs/paper.ron")).unwrap();
        let small: GroundedConfig = ron::from_str(include_str!("../../../configs/cpu-small.ron")).unwrap();
        // 4,096 latents x 96 Gaussians x 26 floats: 40.9 MB a frame; 2 fit in 90 % of 128 MiB.
        assert_eq!(frames_per_pass(4, &paper, Some(128 << 20)), 2);
        assert_eq!(frames_per_pass(4, &paper, None), 4);
        assert_eq!(frames_per_pass(4, &paper, Some(1 << 20)), 1);
        assert_eq!(frames_per_pass(4, &small, Some(128 << 20)), 4);
        assert_eq!(frames_per_pass(0, &small, None), 1);
    }

    #[test]
    fn labels_land_where_their_strip_lies() {
        // The label of voxel (f, i, j, k) is (f + i + j + k) % 9, as argmax of a one-hot row.
        let device = Device::flex();
        let b = 2;
        let truth = |f: usize, i: usize, j: usize, k: usize| (f + i + j + k) % N_LABELS;
        let out = labels(b, 150, |r| {
            let mut v = vec![0f32; b * r.voxels() * N_LABELS];
            for f in 0..b {
                for i in 0..r.ni {
                    for j in 0..r.nj {
                        for k in 0..NZ {
                            let row = f * r.voxels() + (i * r.nj + j) * NZ + k;
                            v[row * N_LABELS + truth(f, r.i0 + i, j, k)] = 1.0;
                        }
                    }
                }
            }
            Tensor::from_data(TensorData::new(v, [b * r.voxels(), N_LABELS]), &device)
        });
        for (f, i, j, k) in [(0, 0, 0, 0), (0, 149, 399, 31), (0, 150, 0, 0), (1, 399, 7, 3), (1, 300, 200, 16)] {
            assert_eq!(out[((f * NX + i) * NY + j) * NZ + k] as usize, truth(f, i, j, k), "{f} {i} {j} {k}");
        }
    }
}
