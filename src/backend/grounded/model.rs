//! The networks (burn modules). In: host batches (`HostBatch`: anchors, their features, padding;
//! plus ground truth for the autoencoder or the BEV for the generator). Out: per-voxel logits of a
//! `Region`, `[B * voxels, 9]`.
//!
//! - `Decoder`, shared: latents + anchor features -> transformer -> per latent `max_gaussians`
//!   raw Gaussians, of which the latent's class budget is splatted, plus a per-layer class bias
//!   (the empty scene: what every column holds before any latent speaks).
//! - `Autoencoder`: ground truth sampled around each anchor -> (mu, logvar) -> decoder.
//! - `Generator`: BEV (18 + 7 channels) -> 2D CNN -> each latent samples its feature bilinearly
//!   at its anchor -> latent -> decoder; plus the gated background residual head.

use super::attention::{Precision, Sets, encode};
use super::config::GroundedConfig;
use super::latents::{ANCHOR_FEATS, Anchor, budget, encoder_input};
use super::rows::{repeat_rows, take_rows};
use super::splat::{ActiveAnchors, PARAMS, Region, activate, splat};
use super::{conv, gelu, head};
use crate::backend::layout::{N_LABELS, NZ, ORIGIN, VOXEL};
use crate::raster::layout::{GRID, N_AUX, N_MASKS, RES};
use burn::module::{Initializer, Param};
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::nn::transformer::{TransformerEncoder, TransformerEncoderConfig};
use burn::nn::{Linear, LinearConfig, PaddingConfig2d};
use burn::prelude::*;
use burn::tensor::activation::gelu;
use ndarray::Array3;

/// Channels of the generator's input: 18 masks + 7 aux.
pub const BEV_CHANNELS: usize = N_MASKS + N_AUX;
/// Aux channels are scaled into O(1): offsets and half-sizes are pixels, heading is a truncated
/// unit vector, height metres.
const AUX_SCALE: [f32; N_AUX] = [1.0 / 20.0, 1.0 / 20.0, 1.0 / 20.0, 1.0 / 10.0, 1.0, 1.0, 0.5];

/// Initial weight of a latent's own class in its Gaussians' features (see `Decoder::class_feat`).
pub const CLASS_PRIOR: f32 = 8.0;

/// Shape constants the decoder needs at run time (not parameters).
#[derive(Clone, Debug)]
pub struct DecoderShape {
    pub gaussians: usize,
    pub offset_bound: f32,
    pub min_scale: f32,
    pub max_scale: f32,
    pub window: usize,
    pub budgets: [usize; N_LABELS],
    /// Where the transformer computes its matrix products (`--precision`).
    pub precision: Precision,
}

impl DecoderShape {
    pub fn new(cfg: &GroundedConfig) -> Self {
        DecoderShape {
            gaussians: cfg.max_gaussians(),
            offset_bound: cfg.gaussians.offset_bound,
            min_scale: cfg.gaussians.min_scale,
            max_scale: cfg.max_scale(),
            window: cfg.gaussians.window,
            budgets: std::array::from_fn(|l| budget(cfg, l as u8)),
            precision: Precision::Full,
        }
    }
}

/// A batch of latent sets, host side.
#[derive(Clone, Debug)]
pub struct HostBatch {
    pub anchors: Vec<Vec<Anchor>>,
    /// Padded length (the longest set; padding changes nothing, see `Decoder::raw`).
    pub q: usize,
    /// [b * q * ANCHOR_FEATS]
    pub feats: Vec<f32>,
    /// [b * q], true = padding.
    pub pad: Vec<bool>,
}

impl HostBatch {
    pub fn new(anchors: Vec<Vec<Anchor>>) -> Self {
        let q = anchors.iter().map(Vec::len).max().unwrap_or(0).max(1);
        let mut feats = Vec::with_capacity(anchors.len() * q * ANCHOR_FEATS);
        let mut pad = Vec::with_capacity(anchors.len() * q);
        for set in &anchors {
            for a in set {
                a.features(&mut feats);
                pad.push(false);
            }
            feats.resize(feats.len() + (q - set.len()) * ANCHOR_FEATS, 0.0);
            // An all-padding row would make attention's softmax 0/0: one padding slot stays
            // visible (it emits nothing: only real anchors get Gaussians).
            pad.extend((set.len()..q).map(|i| !(set.is_empty() && i == 0)));
        }
        HostBatch { anchors, q, feats, pad }
    }

    pub fn b(&self) -> usize {
        self.anchors.len()
    }

    /// Each set's rows in the decoder (`Decoder::raw`): its latents, or the one visible slot of
    /// an empty set.
    pub fn lens(&self) -> Vec<usize> {
        self.anchors.iter().map(|a| a.len().max(1)).collect()
    }

    /// Where each set's rows start in the decoder's output.
    pub fn starts(&self) -> Vec<usize> {
        super::attention::starts(&self.lens())
    }

    pub fn feats_tensor(&self, device: &Device) -> Tensor<3> {
        Tensor::from_data(TensorData::new(self.feats.clone(), [self.b(), self.q, ANCHOR_FEATS]), device)
    }

    pub fn pad_tensor(&self, device: &Device) -> Tensor<2, Bool> {
        Tensor::from_data(TensorData::new(self.pad.clone(), [self.b(), self.q]), device)
    }
}

#[derive(Module, Debug)]
pub struct Decoder {
    pub input: Linear,
    pub transformer: TransformerEncoder,
    pub head: Linear,
    /// [NZ, 9]: the logits of an empty scene per height layer.
    pub layer_bias: Param<Tensor<2>>,
    /// [9, 9]: added to the features of every Gaussian of a latent of class (row): a latent
    /// starts out speaking for its own class (`CLASS_PRIOR` on it, half that against free).
    pub class_feat: Param<Tensor<2>>,
    #[module(skip)]
    pub shape: DecoderShape,
}

impl Decoder {
    pub fn new(cfg: &GroundedConfig, device: &Device) -> Self {
        let d = &cfg.decoder;
        let shape = DecoderShape::new(cfg);
        let head = LinearConfig::new(d.width, shape.gaussians * PARAMS)
            .with_initializer(Initializer::Normal { mean: 0.0, std: 0.02 })
            .init(device);
        // Start as "free everywhere": a clear free margin, so untouched voxels read free.
        let mut bias = vec![0f32; NZ * N_LABELS];
        for k in 0..NZ {
            bias[k * N_LABELS] = 2.0;
        }
        let mut cf = vec![0f32; N_LABELS * N_LABELS];
        for c in 1..N_LABELS {
            cf[c * N_LABELS + c] = CLASS_PRIOR;
            cf[c * N_LABELS] = -CLASS_PRIOR / 2.0;
        }
        Decoder {
            class_feat: Param::from_tensor(Tensor::from_data(TensorData::new(cf, [N_LABELS, N_LABELS]), device)),
            input: LinearConfig::new(cfg.latent_dim + ANCHOR_FEATS, d.width).init(device),
            transformer: TransformerEncoderConfig::new(d.width, d.ff, d.heads, d.blocks)
                .with_dropout(0.0)
                .with_norm_first(true)
                .init(device),
            head,
            layer_bias: Param::from_tensor(Tensor::from_data(TensorData::new(bias, [NZ, N_LABELS]), device)),
            shape,
        }
    }

    /// Latents [b, q, C] -> raw Gaussian parameters [N * G, PARAMS], the sets' latents one after
    /// another (`HostBatch::starts`; N = the sum of `HostBatch::lens`).
    ///
    /// Each set passes the decoder at its own length and attends within itself alone: the sets'
    /// rows run one after another through the row-wise layers (one pass for the batch) and each
    /// set's attention is its own (`Sets::ragged`). A frame's outputs do not depend on the frames
    /// batched with it, no score matrix holds more than one set (`paper`: 6 heads x 4096^2,
    /// inside a GPU buffer at batch 6), and nothing is spent on padding, where sets within a
    /// batch vary (the bench corpus's at `paper`: 830 to 2,846 latents; padding them all to the
    /// longest costs up to 4x the attention's arithmetic).
    pub fn raw(&self, latents: Tensor<3>, hb: &HostBatch) -> Tensor<2> {
        let device = latents.device();
        let x = Tensor::cat(vec![latents, hb.feats_tensor(&device)], 2);
        let lens = hb.lens();
        let rows =
            Tensor::cat(lens.iter().enumerate().map(|(i, &len)| x.clone().slice([i..i + 1, 0..len])).collect(), 1);
        let y = encode(&self.transformer, self.input.forward(rows), &Sets::ragged(&lens), &self.shape.precision);
        let n: usize = lens.iter().sum();
        self.head.forward(y).reshape([n * self.shape.gaussians, PARAMS])
    }

    /// Active Gaussians of the batch that can reach `region`: row indices into `raw` and their
    /// anchors.
    pub fn active(&self, hb: &HostBatch, region: Region) -> (Vec<i64>, ActiveAnchors, Vec<i64>) {
        let g = self.shape.gaussians;
        let reach = self.shape.offset_bound + 3.0 * self.shape.window as f32 + 2.0;
        let (lo_i, hi_i) = (region.i0 as f32 - reach, (region.i0 + region.ni) as f32 + reach);
        let (lo_j, hi_j) = (region.j0 as f32 - reach, (region.j0 + region.nj) as f32 + reach);
        let mut rows = Vec::new();
        let mut labels = Vec::new();
        let mut aa = ActiveAnchors::default();
        for ((b, set), start) in hb.anchors.iter().enumerate().zip(hb.starts()) {
            for (q, a) in set.iter().enumerate() {
                let v = a.voxel();
                if v[0] < lo_i || v[0] > hi_i || v[1] < lo_j || v[1] > hi_j {
                    continue;
                }
                let n = self.shape.budgets[(a.label as usize).min(N_LABELS - 1)];
                let (c, s) = (a.yaw.cos() as f32, a.yaw.sin() as f32);
                for k in 0..n {
                    rows.push(((start + q) * g + k) as i64);
                    labels.push((a.label as usize).min(N_LABELS - 1) as i64);
                    aa.pos.push(v);
                    aa.cos.push(c);
                    aa.sin.push(s);
                    aa.batch.push(b);
                }
            }
        }
        (rows, aa, labels)
    }

    /// Latents -> logits of `region` [b * voxels, 9]: splatted Gaussians plus the layer bias.
    pub fn forward(&self, latents: Tensor<3>, hb: &HostBatch, region: Region) -> Tensor<2> {
        let cols = hb.b() * region.ni * region.nj;
        self.splatted(latents, hb, region) + self.bias_grid(cols)
    }

    /// The layer bias repeated over `cols` columns: `[cols * NZ, 9]`.
    pub fn bias_grid(&self, cols: usize) -> Tensor<2> {
        repeat_rows(self.layer_bias.val().reshape([1, NZ * N_LABELS]), cols).reshape([cols * NZ, N_LABELS])
    }

    /// Latents -> the splatted Gaussians of `region` [b * voxels, 9], without the layer bias.
    pub fn splatted(&self, latents: Tensor<3>, hb: &HostBatch, region: Region) -> Tensor<2> {
        self.splat_raw(self.raw(latents, hb), hb, region)
    }

    /// `raw`'s Gaussians -> the splat of `region` (no layer bias): one transformer pass serves
    /// every strip of a grid (`strips`).
    pub fn splat_raw(&self, raw: Tensor<2>, hb: &HostBatch, region: Region) -> Tensor<2> {
        let device = raw.device();
        let (rows, aa, labels) = self.active(hb, region);
        let b = hb.b();
        if rows.is_empty() {
            Tensor::zeros([b * region.voxels(), N_LABELS], &device)
        } else {
            let n = rows.len();
            let sel = take_rows(raw, rows);
            let prior = take_rows(self.class_feat.val(), labels);
            let sel = sel + Tensor::cat(vec![Tensor::zeros([n, PARAMS - N_LABELS], &device), prior], 1);
            let g = activate(sel, &aa, self.shape.offset_bound, self.shape.min_scale, self.shape.max_scale);
            splat(&g, region, b, self.shape.window)
        }
    }
}

/// The autoencoder's encoder: a two-layer MLP over each anchor's sampled ground truth.
#[derive(Module, Debug)]
pub struct LatentEncoder {
    pub l1: Linear,
    pub l2: Linear,
    #[module(skip)]
    pub latent_dim: usize,
}

#[derive(Module, Debug)]
pub struct Autoencoder {
    pub encoder: LatentEncoder,
    pub decoder: Decoder,
}

/// What the autoencoder returns: logits and the posterior for the KL term.
pub struct AeOut {
    pub logits: Tensor<2>,
    /// [real latents, C]
    pub mu: Tensor<2>,
    pub logvar: Tensor<2>,
}

impl Autoencoder {
    pub fn new(cfg: &GroundedConfig, device: &Device) -> Self {
        let s: usize = cfg.encoder_samples() * N_LABELS;
        let model = Autoencoder {
            encoder: LatentEncoder {
                l1: LinearConfig::new(s + ANCHOR_FEATS, cfg.encoder.hidden).init(device),
                l2: LinearConfig::new(cfg.encoder.hidden, 2 * cfg.latent_dim).init(device),
                latent_dim: cfg.latent_dim,
            },
            decoder: Decoder::new(cfg, device),
        };
        super::ids::stable(model, "autoencoder")
    }

    /// The encoder's input for a batch: per latent the one-hot samples of `labels[b]`.
    pub fn encoder_input(cfg: &GroundedConfig, hb: &HostBatch, labels: &[&Array3<u8>]) -> Vec<f32> {
        let s = cfg.encoder_samples() * N_LABELS;
        let mut out = Vec::with_capacity(hb.b() * hb.q * s);
        for (b, set) in hb.anchors.iter().enumerate() {
            for a in set {
                encoder_input(cfg, a, labels[b], &mut out);
            }
            out.resize(out.len() + (hb.q - set.len()) * s, 0.0);
        }
        out
    }

    /// The posterior of every latent: `(mu, logvar)`, each `[b, q, C]`.
    fn posterior(&self, enc_in: Vec<f32>, hb: &HostBatch) -> (Tensor<3>, Tensor<3>) {
        let device = self.decoder.layer_bias.val().device();
        let (b, q, c) = (hb.b(), hb.q, self.encoder.latent_dim);
        let s = enc_in.len() / (b * q).max(1);
        let x = Tensor::<3>::from_data(TensorData::new(enc_in, [b, q, s]), &device);
        let x = Tensor::cat(vec![x, hb.feats_tensor(&device)], 2);
        let h = self.encoder.l2.forward(gelu(self.encoder.l1.forward(x)));
        let mu = h.clone().slice([0..b, 0..q, 0..c]);
        (mu, h.slice([0..b, 0..q, c..2 * c]).clamp(-8.0, 8.0))
    }

    /// Labels of the whole grid from the posterior means, `[b * NX * NY * NZ]`, splatted a strip
    /// of `rows` grid rows at a time (`strips`).
    pub fn labels_in_strips(&self, enc_in: Vec<f32>, hb: &HostBatch, rows: usize) -> Vec<u8> {
        let raw = self.decoder.raw(self.posterior(enc_in, hb).0, hb);
        super::strips::labels(hb.b(), rows, |r| {
            self.decoder.splat_raw(raw.clone(), hb, r) + self.decoder.bias_grid(hb.b() * r.ni * r.nj)
        })
    }

    /// `noise` [b * q * C] (standard normal) samples the posterior; `None` takes its mean.
    pub fn forward(&self, enc_in: Vec<f32>, hb: &HostBatch, region: Region, noise: Option<Vec<f32>>) -> AeOut {
        let device = self.decoder.layer_bias.val().device();
        let (b, q, c) = (hb.b(), hb.q, self.encoder.latent_dim);
        let (mu, logvar) = self.posterior(enc_in, hb);
        let z = match noise {
            Some(eps) => {
                let eps = Tensor::<3>::from_data(TensorData::new(eps, [b, q, c]), &device);
                mu.clone() + (logvar.clone() * 0.5).exp() * eps
            }
            None => mu.clone(),
        };
        let logits = self.decoder.forward(z, hb, region);
        // The KL term covers real latents only.
        let real: Vec<i64> =
            (0..b * q).filter(|&i| !hb.pad[i] && i % q < hb.anchors[i / q].len()).map(|i| i as i64).collect();
        let n = real.len();
        if n == 0 {
            // No anchor at all (an empty map and no boxes): nothing to regularise.
            let z = Tensor::<2>::zeros([1, c], &device);
            return AeOut { logits, mu: z.clone(), logvar: z };
        }
        let idx = Tensor::<1, Int>::from_data(TensorData::new(real, [n]), &device);
        let mu = mu.reshape([b * q, c]).select(0, idx.clone());
        let logvar = logvar.reshape([b * q, c]).select(0, idx);
        AeOut { logits, mu, logvar }
    }
}

/// 2D BEV encoder: 3x3 convolutions with GELU.
#[derive(Module, Debug)]
pub struct BevEncoder {
    pub convs: Vec<Conv2d>,
}

#[derive(Module, Debug)]
pub struct Generator {
    pub bev: BevEncoder,
    pub cond1: Linear,
    pub cond2: Linear,
    pub decoder: Decoder,
    pub bg_hidden: Option<Conv2d>,
    /// Zero-initialised: the residual starts at nothing and grows where it helps.
    pub bg_out: Option<Conv2d>,
    #[module(skip)]
    pub stride: usize,
}

/// What the generator returns: final logits, and the background residual (before gating) for
/// the auxiliary term.
pub struct GenOut {
    pub logits: Tensor<2>,
    pub background: Option<Tensor<2>>,
}

/// The BEV of each frame as the generator reads it, concatenated: `[frames, 25, 400, 400]`
/// floats, masks 0/1, aux scaled; a channel missing from a frame (or of another size) is zeros.
/// Written on all cores (16 M values at batch 2).
pub fn bev_batch(frames: &[(&Array3<i8>, &Array3<i32>)]) -> Vec<f32> {
    let px = GRID * GRID;
    // Each frame's channels as contiguous slices (a copy only for a non-standard layout).
    let masks: Vec<_> = frames.iter().map(|(m, _)| m.as_standard_layout()).collect();
    let aux: Vec<_> = frames.iter().map(|(_, a)| a.as_standard_layout()).collect();
    super::par::par_vec(frames.len() * BEV_CHANNELS * px, |start, part| {
        let mut pos = start;
        let mut rest = part;
        while !rest.is_empty() {
            let (f, c, p0) = (pos / (BEV_CHANNELS * px), pos / px % BEV_CHANNELS, pos % px);
            let n = rest.len().min(px - p0);
            let (out, tail) = rest.split_at_mut(n);
            if c < N_MASKS {
                copy_channel(&masks[f], c, p0, out, |v| (v != 0) as u8 as f32);
            } else {
                let scale = AUX_SCALE[c - N_MASKS];
                copy_channel(&aux[f], c - N_MASKS, p0, out, |v| v as f32 * scale);
            }
            (rest, pos) = (tail, pos + n);
        }
    })
}

/// Channel `c` of `a` from pixel `p0` on into `out`, through `f`; nothing where `a` lacks the
/// channel or has another size (`bev_batch`'s parts arrive zeroed).
fn copy_channel<T: Copy>(
    a: &ndarray::CowArray<T, ndarray::Ix3>,
    c: usize,
    p0: usize,
    out: &mut [f32],
    f: impl Fn(T) -> f32,
) {
    let whole = c < a.dim().0 && a.dim().1 == GRID && a.dim().2 == GRID;
    if let Some(a) = a.as_slice().filter(|_| whole) {
        for (o, &v) in out.iter_mut().zip(&a[c * GRID * GRID + p0..]) {
            *o = f(v);
        }
    }
}

impl Generator {
    pub fn new(cfg: &GroundedConfig, device: &Device) -> Self {
        let mut convs = Vec::new();
        let mut ch = BEV_CHANNELS;
        for (&c, &s) in cfg.bev.channels.iter().zip(&cfg.bev.strides) {
            convs.push(
                Conv2dConfig::new([ch, c], [3, 3])
                    .with_stride([s, s])
                    .with_padding(PaddingConfig2d::Explicit(1, 1, 1, 1))
                    .init(device),
            );
            ch = c;
        }
        let f = cfg.bev_features();
        let (bg_hidden, bg_out) = if cfg.bev.background_head {
            (
                Some(
                    Conv2dConfig::new([f, f], [3, 3]).with_padding(PaddingConfig2d::Explicit(1, 1, 1, 1)).init(device),
                ),
                Some(Conv2dConfig::new([f, NZ], [1, 1]).with_initializer(Initializer::Zeros).init(device)),
            )
        } else {
            (None, None)
        };
        let model = Generator {
            bev: BevEncoder { convs },
            cond1: LinearConfig::new(f + ANCHOR_FEATS, cfg.bev.hidden).init(device),
            cond2: LinearConfig::new(cfg.bev.hidden, cfg.latent_dim).init(device),
            decoder: Decoder::new(cfg, device),
            bg_hidden,
            bg_out,
            stride: cfg.bev_stride(),
        };
        super::ids::stable(model, "generator")
    }

    fn features(&self, bev: Tensor<4>) -> Tensor<4> {
        let mut x = bev;
        for c in &self.bev.convs {
            x = gelu::gelu(conv::forward(c, x));
        }
        x
    }

    /// `bev` is the frames' `bev_batch`.
    pub fn forward(&self, bev: Vec<f32>, hb: &HostBatch, region: Region) -> GenOut {
        self.region_out(&self.prepare(bev, hb, region), hb, region)
    }

    /// `forward` of `region` from a pass `prepare`d for it (or for a region holding it).
    pub fn region_out(&self, prep: &Prepared, hb: &HostBatch, region: Region) -> GenOut {
        let b = hb.b();
        let splatted = self.decoder.splat_raw(prep.raw.clone(), hb, region);
        let Some(r) = prep.residual.clone() else {
            let logits = splatted + self.decoder.bias_grid(b * region.ni * region.nj);
            return GenOut { logits, background: None };
        };
        let device = splatted.device();
        let cols = feature_columns(region, b, prep.residual_rect, self.stride);
        let nc = cols.len();
        let r = take_rows(r, cols).reshape([nc * NZ, 1]);
        let bias = self.decoder.layer_bias.val();
        let logits = if device == Device::flex() {
            head::head(splatted, bias, r.clone())
        } else {
            head::head_tensor_ops(splatted, bias, r.clone())
        };
        GenOut { logits, background: Some(r) }
    }

    /// Per-voxel labels of `region` (the argmax of `forward`'s logits, the same bits), computed
    /// on the host from the splat, the layer bias and the background head at feature resolution:
    /// none of the grid-sized tensors of `forward` is built. For a model on the CPU.
    pub fn labels(&self, bev: Vec<f32>, hb: &HostBatch, region: Region) -> Vec<u8> {
        let b = hb.b();
        let prep = self.prepare(bev, hb, region);
        let splatted = self.decoder.splat_raw(prep.raw, hb, region);
        let host = |t: Tensor<2>| t.into_data().try_into_vec::<f32>().unwrap_or_default();
        let bias = host(self.decoder.layer_bias.val());
        let residual = prep.residual.map(|r| (host(r), feature_columns(region, b, prep.residual_rect, self.stride)));
        let residual = residual.as_ref().map(|(r, cols)| head::Residual { values: r, columns: cols });
        head::labels(&host(splatted), &bias, residual)
    }

    /// Everything `forward` computes before the grid: the decoder's Gaussians and the background
    /// head's residual at feature resolution (over the feature pixels `region` reads on the
    /// CPU, the whole map on a GPU).
    pub fn prepare(&self, bev: Vec<f32>, hb: &HostBatch, region: Region) -> Prepared {
        let device = self.decoder.layer_bias.val().device();
        let b = hb.b();
        let x = Tensor::<4>::from_data(TensorData::new(bev, [b, BEV_CHANNELS, GRID, GRID]), &device);
        let fmap = self.features(x);
        let [_, f, h, w] = fmap.dims();
        let rows = fmap.clone().permute([0, 2, 3, 1]).reshape([b * h * w, f]);
        // Bilinear sampling at each anchor: feature pixel a's centre is BEV pixel (a + 0.5) * stride.
        let cell = RES * self.stride as f64;
        let mut idx = Vec::with_capacity(b * hb.q * 4);
        let mut wts = Vec::with_capacity(b * hb.q * 4);
        for (bi, set) in hb.anchors.iter().enumerate() {
            for qi in 0..hb.q {
                let Some(a) = set.get(qi) else {
                    idx.extend([0i64; 4]);
                    wts.extend([0f32; 4]);
                    continue;
                };
                let fa = ((a.pos[0] + 50.0) / cell - 0.5).clamp(0.0, (h - 1) as f64);
                let fb = ((a.pos[1] + 50.0) / cell - 0.5).clamp(0.0, (w - 1) as f64);
                let (a0, b0) = (fa.floor() as usize, fb.floor() as usize);
                let (a1, b1) = ((a0 + 1).min(h - 1), (b0 + 1).min(w - 1));
                let (ta, tb) = ((fa - a0 as f64) as f32, (fb - b0 as f64) as f32);
                for (ai, bj, wt) in [
                    (a0, b0, (1.0 - ta) * (1.0 - tb)),
                    (a1, b0, ta * (1.0 - tb)),
                    (a0, b1, (1.0 - ta) * tb),
                    (a1, b1, ta * tb),
                ] {
                    idx.push(((bi * h + ai) * w + bj) as i64);
                    wts.push(wt);
                }
            }
        }
        let n = idx.len();
        let sampled = take_rows(rows, idx);
        let wts = Tensor::<3>::from_data(TensorData::new(wts, [n / 4, 4, 1]), &device);
        let sampled = (sampled.reshape([n / 4, 4, f]) * wts).sum_dim(1).reshape([b, hb.q, f]);
        let z = self.cond2.forward(gelu(self.cond1.forward(Tensor::cat(vec![sampled, hb.feats_tensor(&device)], 2))));
        let raw = self.decoder.raw(z, hb);
        // The background head at feature resolution, on the CPU over the feature pixels the
        // region's columns read (a GPU runs it over the whole map).
        let rect = if device == Device::flex() {
            FeatureRect::covering(region, [h, w], self.stride)
        } else {
            FeatureRect::covering(Region::full(), [h, w], self.stride)
        };
        let residual = match (&self.bg_hidden, &self.bg_out) {
            (Some(hid), Some(out)) => {
                let [hh, ww] = rect.size;
                let hidden = gelu::gelu(cropped_conv(hid, fmap, rect));
                Some(out.forward(hidden).permute([0, 2, 3, 1]).reshape([b * hh * ww, NZ]))
            }
            _ => None,
        };
        Prepared { raw, residual, residual_rect: rect }
    }
}

/// A rectangle of feature pixels: `origin` (row, column) and `size`, inside a map of `full`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FeatureRect {
    pub origin: [usize; 2],
    pub size: [usize; 2],
    pub full: [usize; 2],
}

impl FeatureRect {
    /// The feature pixels the columns of `region` read (`feature_columns`) in a map of `[h, w]`
    /// at `stride`.
    pub fn covering(region: Region, [h, w]: [usize; 2], stride: usize) -> Self {
        let span = |lo: usize, n: usize, len: usize| {
            let a = (lo / stride).min(len - 1);
            let b = ((lo + n.max(1) - 1) / stride).min(len - 1);
            (a, b + 1 - a)
        };
        let (a0, ha) = span(region.i0, region.ni, h);
        let (b0, wb) = span(region.j0, region.nj, w);
        FeatureRect { origin: [a0, b0], size: [ha, wb], full: [h, w] }
    }

    fn is_full(&self) -> bool {
        self.origin == [0, 0] && self.size == self.full
    }
}

/// `conv` over the whole map `x` `[b, c, h, w]`, kept only on `rect`: the convolution runs on
/// `rect` plus the kernel's reach (the map's own zero padding where the rectangle meets its
/// edge), so every kept pixel sees exactly the inputs it sees over the whole map: `cpu-small`'s
/// 128-column training crop reads a ninth of the feature map.
fn cropped_conv(conv: &Conv2d, x: Tensor<4>, rect: FeatureRect) -> Tensor<4> {
    let [b, c, h, w] = x.dims();
    let [kh, kw] = conv.kernel_size;
    let m = kh / 2;
    let same = kh == kw
        && kh % 2 == 1
        && conv.stride == [1, 1]
        && conv.dilation == [1, 1]
        && matches!(conv.padding, PaddingConfig2d::Explicit(t, l, bo, r) if [t, l, bo, r] == [m; 4]);
    let ([r0, c0], [nr, nc]) = (rect.origin, rect.size);
    if rect.is_full() {
        return conv::forward(conv, x);
    }
    if !same {
        let y = conv::forward(conv, x);
        let o = y.dims()[1];
        return y.slice([0..b, 0..o, r0..r0 + nr, c0..c0 + nc]);
    }
    let (s0, e0) = (r0.saturating_sub(m), (r0 + nr + m).min(h));
    let (s1, e1) = (c0.saturating_sub(m), (c0 + nc + m).min(w));
    let y = conv::forward(conv, x.slice([0..b, 0..c, s0..e0, s1..e1]));
    let o = y.dims()[1];
    y.slice([0..b, 0..o, r0 - s0..r0 - s0 + nr, c0 - s1..c0 - s1 + nc])
}

/// What the generator computes before the grid (`Generator::prepare`): it serves the region it
/// was prepared for and any region inside it.
pub struct Prepared {
    /// The decoder's raw Gaussians (`Decoder::raw`).
    raw: Tensor<2>,
    /// The background head's residual per feature pixel of `residual_rect` and layer, `[pixels, NZ]`.
    residual: Option<Tensor<2>>,
    /// The feature pixels `residual` covers (`[b * rows * columns]` of them).
    residual_rect: FeatureRect,
}

/// The feature pixel each column of `region` reads (nearest), for each of `b` frames: indices
/// into `[b * rect rows * rect columns]`, in the splat's column order.
fn feature_columns(region: Region, b: usize, rect: FeatureRect, stride: usize) -> Vec<i64> {
    let ([h, w], [a0, c0], [hh, ww]) = (rect.full, rect.origin, rect.size);
    let mut cols = Vec::with_capacity(b * region.ni * region.nj);
    for bi in 0..b {
        for li in 0..region.ni {
            for lj in 0..region.nj {
                let (a, c) = ((region.i0 + li) / stride, (region.j0 + lj) / stride);
                let (a, c) = (a.min(h - 1) - a0, c.min(w - 1) - c0);
                cols.push(((bi * hh + a) * ww + c) as i64);
            }
        }
    }
    cols
}

/// Voxel (continuous) -> ego frame metres, for documentation and tests.
pub fn voxel_to_metres(v: [f32; 3]) -> [f64; 3] {
    [0, 1, 2].map(|a| ORIGIN[a] + VOXEL * v[a] as f64)
}
