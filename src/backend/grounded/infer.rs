//! Inference: boxes and BEV of frames -> per-voxel labels, several frames per forward pass.
//!
//! Every frame's latent set passes the decoder at its own length and attends within itself alone
//! (`Decoder::raw`); the other layers work row by row. So labels do not depend on `--grounded-batch` or on which frames
//! share a pass (on the CPU they are byte-identical; tests/grounded.rs checks a batch of 3
//! against single frames). On a GPU the
//! device work runs under `guard::guarded`, so a device failure is a diagnostic.

use super::device::largest_buffer;
use super::guard::guarded;
use super::model::{HostBatch, bev_batch};
use super::splat::Region;
use super::{GBox, Grounded, latents, strips};
use crate::backend::layout::{NX, NY, NZ};
use crate::backend::{OccInput, Occupancy, OccupancyBackend};
use crate::diag::Diagnostic;
use ndarray::Array3;
use rayon::prelude::*;

/// One frame as the model reads it.
pub struct FrameIn<'a> {
    pub boxes: Vec<GBox>,
    pub masks: &'a Array3<i8>,
    pub aux: &'a Array3<i32>,
}

impl<'a> FrameIn<'a> {
    pub fn of(input: &OccInput<'a>) -> Self {
        FrameIn {
            boxes: input.boxes.iter().map(GBox::from_ego).collect(),
            masks: &input.bev.masks,
            aux: &input.bev.aux,
        }
    }
}

impl Grounded {
    /// Labels (400, 400, 32) for one frame.
    pub fn predict(&self, boxes: &[GBox], masks: &Array3<i8>, aux: &Array3<i32>) -> Array3<u8> {
        let frame = FrameIn { boxes: boxes.to_vec(), masks, aux };
        self.forward_labels(std::slice::from_ref(&frame)).pop().unwrap_or_else(|| Array3::zeros((NX, NY, NZ)))
    }

    /// Labels of every frame, `batch` frames per forward pass: on the CPU the passes run side by
    /// side on the thread pool, on a GPU one after another (its memory holds one pass).
    pub fn predict_frames(&self, frames: &[FrameIn]) -> Result<Vec<Array3<u8>>, Diagnostic> {
        if !self.device().is_gpu() {
            let parts: Vec<Vec<Array3<u8>>> = frames.par_chunks(self.batch).map(|c| self.forward_labels(c)).collect();
            return Ok(parts.into_iter().flatten().collect());
        }
        let mut out = Vec::with_capacity(frames.len());
        for c in frames.chunks(self.pass_frames()) {
            out.extend(guarded(|| self.forward_labels(c))?);
        }
        Ok(out)
    }

    /// Frames one `predict_frames` call should get to keep the device busy.
    fn frames_per_call(&self) -> usize {
        if self.device().is_gpu() { self.pass_frames() } else { self.batch * rayon::current_num_threads() }
    }

    /// Frames per forward pass on a GPU: `batch`, fewer where the device's largest buffer cannot
    /// hold a pass's decoder Gaussians (`strips::frames_per_pass`).
    fn pass_frames(&self) -> usize {
        let device = self.model.decoder.layer_bias.val().device();
        strips::frames_per_pass(self.batch, &self.config, largest_buffer(&device))
    }

    /// One forward pass over `frames`.
    fn forward_labels(&self, frames: &[FrameIn]) -> Vec<Array3<u8>> {
        if frames.is_empty() {
            return Vec::new();
        }
        let sets: Vec<_> = frames.iter().map(|f| latents::build(&self.config, &f.boxes, f.masks)).collect();
        let hb = HostBatch::new(sets);
        let bev = bev_batch(&frames.iter().map(|f| (f.masks, f.aux)).collect::<Vec<_>>());
        // The model's own device decides (a model trained on a GPU is validated there).
        let device = self.model.decoder.layer_bias.val().device();
        let labels: Vec<u8> = if device != burn::prelude::Device::flex() {
            let rows = strips::rows_per_strip(hb.b(), largest_buffer(&device));
            let prep = self.model.prepare(bev, &hb, Region::full());
            strips::labels(hb.b(), rows, |r| self.model.region_out(&prep, &hb, r).logits)
        } else {
            // The same labels without the grid-sized tensors (`head`).
            self.model.labels(bev, &hb, Region::full())
        };
        labels
            .chunks(NX * NY * NZ)
            .map(|c| Array3::from_shape_vec((NX, NY, NZ), c.to_vec()).unwrap_or_else(|_| Array3::zeros((NX, NY, NZ))))
            .collect()
    }
}

impl OccupancyBackend for Grounded {
    fn name(&self) -> &str {
        &self.name
    }

    fn occupancy(&self, input: &OccInput) -> Occupancy {
        let f = FrameIn::of(input);
        Occupancy { labels: self.predict(&f.boxes, f.masks, f.aux) }
    }

    fn batch(&self) -> Option<usize> {
        Some(self.frames_per_call())
    }

    fn occupancy_batch(&self, inputs: &[OccInput], out: &mut [Occupancy]) -> Result<(), Diagnostic> {
        let frames: Vec<FrameIn> = inputs.iter().map(FrameIn::of).collect();
        for (o, labels) in out.iter_mut().zip(self.predict_frames(&frames)?) {
            o.labels = labels;
        }
        Ok(())
    }
}

impl OccupancyBackend for &Grounded {
    fn name(&self) -> &str {
        (**self).name()
    }

    fn occupancy(&self, input: &OccInput) -> Occupancy {
        (**self).occupancy(input)
    }

    fn batch(&self) -> Option<usize> {
        (**self).batch()
    }

    fn occupancy_batch(&self, inputs: &[OccInput], out: &mut [Occupancy]) -> Result<(), Diagnostic> {
        (**self).occupancy_batch(inputs, out)
    }
}
