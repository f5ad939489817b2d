//! The grounded model's sizes and training settings, as plain data read from RON
//! (`configs/paper.ron`, `configs/cpu-small.ron`). Nothing here touches tensors.

use serde::{Deserialize, Serialize};

/// Everything that fixes the model's shapes, plus how to train it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroundedConfig {
    /// Free-form name, recorded in the manifest's backend string.
    pub name: String,
    /// Q: capacity of the latent set (foreground first, then the background lattice).
    pub latents: usize,
    /// C: channels per latent.
    pub latent_dim: usize,
    /// At most this many foreground latents (boxes and their sub-latents), nearest the ego first.
    pub max_foreground: usize,
    pub decoder: DecoderConfig,
    pub gaussians: GaussianConfig,
    pub lattice: LatticeConfig,
    /// Boxes longer than this (m) are split into sub-latents along their heading.
    pub split_length_m: f64,
    /// At most this many sub-latents per box.
    pub max_split: usize,
    pub encoder: EncoderConfig,
    pub bev: BevConfig,
    pub train: TrainConfig,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DecoderConfig {
    /// Transformer width.
    pub width: usize,
    pub blocks: usize,
    pub heads: usize,
    /// Feed-forward width of each block.
    pub ff: usize,
}

/// Per-class Gaussian budgets and their geometry bounds (voxel units).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaussianConfig {
    /// Vehicles.
    pub vehicle: usize,
    /// Bicycles, barriers, generic objects.
    pub mid: usize,
    /// Background lattice latents and structures (trees, poles, walls, buildings).
    pub background: usize,
    /// Pedestrians, traffic cones, construction-zone signs.
    pub small: usize,
    /// Offsets from the anchor are bounded to this many voxels per axis (tanh).
    pub offset_bound: f32,
    /// Smallest standard deviation, voxels.
    pub min_scale: f32,
    /// Each Gaussian is evaluated on the (2 r + 1)^3 voxels around the voxel holding its mean;
    /// scales are capped at r / 3 voxels so the 3-sigma ellipsoid always fits the window.
    pub window: usize,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatticeConfig {
    /// Spacing of the background lattice in x and y (m).
    pub spacing_m: f64,
    /// Heights of the lattice layers (m, ego frame).
    pub z_m: Vec<f64>,
    /// BEV channels whose union is the footprint the lattice is restricted to.
    pub footprint_channels: Vec<usize>,
}

/// The autoencoder's encoder: each latent reads the ground truth at a small grid of points
/// spanning its box (or lattice cell) in its own frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EncoderConfig {
    /// Sample points along the anchor's length, width and height.
    pub samples: Vec<usize>,
    pub hidden: usize,
}

/// The generator's 2D BEV encoder: 3x3 convolutions, one per entry.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BevConfig {
    pub channels: Vec<usize>,
    /// Stride of each convolution (1 or 2); the feature map is 400 / product(strides) wide.
    pub strides: Vec<usize>,
    /// Width of the hidden layer mapping a sampled feature (plus anchor) to a latent.
    pub hidden: usize,
    /// The gated background residual head (App. A).
    pub background_head: bool,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainConfig {
    pub seed: u64,
    pub batch: usize,
    pub autoencoder: StageConfig,
    pub generator: StageConfig,
    /// Train on square crops of this many columns (0 = the whole 400 x 400 grid); validation
    /// always scores the whole grid.
    pub crop: usize,
    pub ce_weight: f32,
    pub lovasz_weight: f32,
    pub kl_weight: f32,
    /// Auxiliary background cross-entropy of the background head.
    pub background_aux_weight: f32,
    /// Class weights are (max frequency / class frequency)^power, clipped to this.
    pub weight_clip: f32,
    pub weight_power: f32,
    /// Per-class multipliers on top (labels 0..=8).
    pub class_boost: Vec<f32>,
    /// Lovász-softmax runs over every voxel whose truth or prediction is an agent class plus
    /// this many uniformly drawn voxels of the crop.
    pub lovasz_samples: usize,
    /// Save a checkpoint every this many steps (and at each epoch's end).
    pub checkpoint_every: usize,
    /// Without `--val`, this fraction of the clips (whole clips, chosen by the seed) is held out.
    pub val_fraction: f64,
    /// Score at most this many validation frames per epoch (0 = all).
    pub val_max_frames: usize,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StageConfig {
    pub epochs: usize,
    pub lr: f64,
    /// Cosine decay ends here.
    pub lr_min: f64,
}

impl GroundedConfig {
    pub fn from_ron(text: &str) -> Result<Self, String> {
        let c: GroundedConfig = ron::from_str(text).map_err(|e| e.to_string())?;
        c.validate()?;
        Ok(c)
    }

    pub fn to_ron(&self) -> String {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default()).expect("plain data serialises")
    }

    /// The largest per-latent budget: every latent emits this many Gaussians, of which its
    /// class's budget are splatted.
    pub fn max_gaussians(&self) -> usize {
        let g = &self.gaussians;
        g.vehicle.max(g.mid).max(g.background).max(g.small)
    }

    /// Largest standard deviation (voxels): the 3-sigma ellipsoid fits the window.
    pub fn max_scale(&self) -> f32 {
        self.gaussians.window as f32 / 3.0
    }

    /// Width of the BEV feature map and its stride in BEV pixels.
    pub fn bev_stride(&self) -> usize {
        self.bev.strides.iter().product()
    }

    /// Encoder sample points per latent.
    pub fn encoder_samples(&self) -> usize {
        self.encoder.samples.iter().product()
    }

    pub fn bev_features(&self) -> usize {
        self.bev.channels.last().copied().unwrap_or(crate::backend::grounded::BEV_CHANNELS)
    }

    pub fn validate(&self) -> Result<(), String> {
        let mut bad = Vec::new();
        if self.latents == 0 || self.latent_dim == 0 {
            bad.push("`latents` and `latent_dim` must be positive".to_string());
        }
        if self.max_foreground > self.latents {
            bad.push(format!("`max_foreground` {} exceeds `latents` {}", self.max_foreground, self.latents));
        }
        let d = &self.decoder;
        if d.width == 0 || d.heads == 0 || !d.width.is_multiple_of(d.heads) {
            bad.push(format!("decoder `width` {} must be a positive multiple of `heads` {}", d.width, d.heads));
        }
        if self.max_gaussians() == 0 {
            bad.push("every Gaussian budget is 0".into());
        }
        let g = &self.gaussians;
        if g.window == 0 || g.window > 6 {
            bad.push(format!("`window` {} must be 1..=6 voxels", g.window));
        }
        if !(g.min_scale > 0.0 && g.min_scale < self.max_scale()) {
            bad.push(format!("`min_scale` {} must lie in (0, window / 3 = {})", g.min_scale, self.max_scale()));
        }
        if g.offset_bound.is_nan() || g.offset_bound <= 0.0 {
            bad.push("`offset_bound` must be positive".into());
        }
        if self.lattice.spacing_m.is_nan() || self.lattice.spacing_m < 0.5 || self.lattice.z_m.is_empty() {
            bad.push("lattice `spacing_m` must be >= 0.5 m and `z_m` non-empty".into());
        }
        if self.lattice.footprint_channels.iter().any(|&c| c >= crate::raster::layout::N_MASKS) {
            bad.push("lattice `footprint_channels` must be BEV mask channels 0..=17".into());
        }
        if self.bev.channels.is_empty() || self.bev.channels.len() != self.bev.strides.len() {
            bad.push("bev `channels` and `strides` must be non-empty and of equal length".into());
        }
        if self.bev.strides.iter().any(|&s| s != 1 && s != 2) || 400 % self.bev_stride().max(1) != 0 {
            bad.push("bev `strides` must be 1 or 2 and divide 400".into());
        }
        if self.encoder.samples.len() != 3 || self.encoder.samples.contains(&0) {
            bad.push("encoder `samples` must be three positive counts [length, width, height]".into());
        }
        if self.train.class_boost.len() != crate::backend::layout::N_LABELS {
            bad.push("train `class_boost` must hold 9 multipliers (labels 0..=8)".into());
        }
        if self.split_length_m.is_nan() || self.split_length_m <= 0.0 || self.max_split == 0 {
            bad.push("`split_length_m` and `max_split` must be positive".into());
        }
        let t = &self.train;
        if t.batch == 0 || t.checkpoint_every == 0 {
            bad.push("train `batch` and `checkpoint_every` must be positive".into());
        }
        if t.crop != 0 && !(16..=400).contains(&t.crop) {
            bad.push(format!("train `crop` {} must be 0 (whole grid) or 16..=400", t.crop));
        }
        if !(0.0..1.0).contains(&t.val_fraction) {
            bad.push("train `val_fraction` must be in [0, 1)".into());
        }
        for s in [&t.autoencoder, &t.generator] {
            if !(s.lr > 0.0 && s.lr_min >= 0.0 && s.lr_min <= s.lr) {
                bad.push("stage `lr` must be positive and `lr_min` in [0, lr]".into());
            }
        }
        if bad.is_empty() { Ok(()) } else { Err(bad.join("; ")) }
    }
}
