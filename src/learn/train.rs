//! `rocc train autoencoder|generator`. In: a data directory (`data::scan`), a `GroundedConfig`,
//! an output directory. Out: `OUT/<stage>.bpk` (weights) and `OUT/<stage>.ron` (the config they
//! need), `OUT/checkpoint/` (model, optimiser and position, every `checkpoint_every` steps and
//! at each epoch's end; `--resume` continues from it), `OUT/<stage>-history.json` (per-epoch
//! loss and validation scores) and a `TrainReport`.
//!
//! Each epoch visits the training frames in a seeded shuffle, in batches; each step trains on
//! one crop of columns (`train.crop`) shared by the batch, with Adam under cosine decay.
//! Validation predicts the whole grid of held-out frames and scores it with the shared scorer
//! (`eval::occ`), next to a trivial baseline: every column gets the per-height-layer majority
//! label of the training set.

use super::data::{self, Frame, Sample};
use crate::backend::grounded::attention::Precision;
use crate::backend::grounded::config::{GroundedConfig, StageConfig};
use crate::backend::grounded::device::largest_buffer;
use crate::backend::grounded::latents::{self, GBox};
use crate::backend::grounded::load_weights;
use crate::backend::grounded::loss::{
    agent_predicted, bce_with_logits, class_weights, cross_entropy_and_probs, kl_divergence, lovasz_rows,
    lovasz_softmax,
};
use crate::backend::grounded::model::{Autoencoder, Generator, HostBatch, bev_batch};
use crate::backend::grounded::rows::take_rows;
use crate::backend::grounded::splat::Region;
use crate::backend::grounded::strips::rows_per_strip;
use crate::backend::layout::{N_LABELS, NX, NY, NZ};
use crate::diag::Diagnostic;
use crate::eval::occ::{OccScorer, OccScores};
use crate::sample::Rng;
use burn::module::Module;
use burn::optim::GradientsParams;
use burn::prelude::*;
use burn::store::ModuleSnapshot;
use ndarray::Array3;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Stage {
    Autoencoder,
    Generator,
}

impl Stage {
    pub fn name(self) -> &'static str {
        match self {
            Stage::Autoencoder => "autoencoder",
            Stage::Generator => "generator",
        }
    }
}

pub struct TrainOptions {
    pub stage: Stage,
    pub data: PathBuf,
    /// Held-out data; without it `train.val_fraction` of the clips of `data` is held out.
    pub val: Option<PathBuf>,
    pub config: GroundedConfig,
    pub out: PathBuf,
    pub resume: bool,
    /// Generator: autoencoder weights whose decoder it starts from (default OUT/autoencoder.bpk
    /// when that exists).
    pub init: Option<PathBuf>,
    /// Where to train; autodiff is added here.
    pub device: Device,
    pub quiet: bool,
    /// Stop after this many steps in all (a time-boxed run); the weights are still written.
    pub max_steps: Option<usize>,
    /// Override the stage's epoch count.
    pub epochs: Option<usize>,
    /// Where the decoder's transformer computes its matrix products (`--precision`).
    pub precision: Precision,
}

#[derive(Clone, Debug, Serialize)]
pub struct EpochReport {
    pub epoch: usize,
    pub steps: usize,
    pub mean_loss: f64,
    pub seconds: f64,
    pub val: Option<OccScores>,
}

#[derive(Clone, Debug, Serialize)]
pub struct TrainReport {
    pub stage: Stage,
    pub train_frames: usize,
    pub val_frames: usize,
    pub val_scenes: Vec<String>,
    pub class_weights: [f32; N_LABELS],
    /// The per-layer-majority baseline on the validation frames.
    pub baseline: Option<OccScores>,
    pub epochs: Vec<EpochReport>,
    pub weights: PathBuf,
    pub steps: usize,
    /// Each step of this run in parts, seconds: loading the frames and their labels, forward,
    /// loss, backward and the optimiser (the device synchronised at the end of each).
    pub step_phases: Vec<[f64; 4]>,
    /// `full` or `mixed`.
    pub precision: &'static str,
    /// Mixed precision: steps whose gradient overflowed half precision (skipped, the gradient
    /// scale halved).
    pub skipped_steps: u64,
}

/// Where a run stands, for `--resume`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
struct Position {
    epoch: usize,
    /// Next batch within the epoch.
    batch: usize,
    step: usize,
}

/// Everything one training step produces.
pub struct StepOut {
    pub logits: Tensor<2>,
    pub kl: Option<Tensor<1>>,
    pub background: Option<Tensor<2>>,
}

/// A training step's input as the host builds it (the latent sets and the model's input: the
/// BEV for the generator, the sampled ground truth for the autoencoder), built on the loading
/// thread while the step before runs.
pub struct StepIn {
    pub hb: HostBatch,
    pub input: Vec<f32>,
}

/// The two trainable models behind one loop.
pub trait Net: Module + ModuleSnapshot + Clone + Sized {
    fn build(cfg: &GroundedConfig, device: &Device) -> Self;
    fn decoder_mut(&mut self) -> &mut crate::backend::grounded::model::Decoder;
    /// The host side of a step over `frames` (no model needed).
    fn step_input(cfg: &GroundedConfig, frames: &[Frame]) -> StepIn;
    fn step(&self, cfg: &GroundedConfig, input: StepIn, region: Region, rng: &mut Rng) -> StepOut;
    /// Whole-grid labels (a model on a plain device).
    fn predict(&self, cfg: &GroundedConfig, frame: &Frame) -> Array3<u8>;
}

fn anchors(cfg: &GroundedConfig, f: &Frame) -> Vec<latents::Anchor> {
    latents::build(cfg, &f.boxes, &f.masks)
}

impl Net for Autoencoder {
    fn build(cfg: &GroundedConfig, device: &Device) -> Self {
        Autoencoder::new(cfg, device)
    }

    fn decoder_mut(&mut self) -> &mut crate::backend::grounded::model::Decoder {
        &mut self.decoder
    }

    fn step_input(cfg: &GroundedConfig, frames: &[Frame]) -> StepIn {
        let hb = HostBatch::new(frames.iter().map(|f| anchors(cfg, f)).collect());
        let labels: Vec<&Array3<u8>> = frames.iter().map(|f| &f.labels).collect();
        let input = Autoencoder::encoder_input(cfg, &hb, &labels);
        StepIn { hb, input }
    }

    fn step(&self, cfg: &GroundedConfig, input: StepIn, region: Region, rng: &mut Rng) -> StepOut {
        let StepIn { hb, input: enc } = input;
        let noise = (0..hb.b() * hb.q * cfg.latent_dim).map(|_| rng.normal() as f32).collect();
        let out = self.forward(enc, &hb, region, Some(noise));
        StepOut { logits: out.logits, kl: Some(kl_divergence(out.mu, out.logvar)), background: None }
    }

    fn predict(&self, cfg: &GroundedConfig, frame: &Frame) -> Array3<u8> {
        let hb = HostBatch::new(vec![anchors(cfg, frame)]);
        let enc = Autoencoder::encoder_input(cfg, &hb, &[&frame.labels]);
        let rows = rows_per_strip(1, largest_buffer(&self.decoder.layer_bias.val().device()));
        let labels = self.labels_in_strips(enc, &hb, rows);
        Array3::from_shape_vec((NX, NY, NZ), labels).unwrap_or_else(|_| Array3::zeros((NX, NY, NZ)))
    }
}

impl Net for Generator {
    fn build(cfg: &GroundedConfig, device: &Device) -> Self {
        Generator::new(cfg, device)
    }

    fn decoder_mut(&mut self) -> &mut crate::backend::grounded::model::Decoder {
        &mut self.decoder
    }

    fn step_input(cfg: &GroundedConfig, frames: &[Frame]) -> StepIn {
        let hb = HostBatch::new(frames.iter().map(|f| anchors(cfg, f)).collect());
        StepIn { hb, input: bev_batch(&frames.iter().map(|f| (&f.masks, &f.aux)).collect::<Vec<_>>()) }
    }

    fn step(&self, _cfg: &GroundedConfig, input: StepIn, region: Region, _rng: &mut Rng) -> StepOut {
        let StepIn { hb, input: bev } = input;
        let out = self.forward(bev, &hb, region);
        StepOut { logits: out.logits, kl: None, background: out.background }
    }

    fn predict(&self, cfg: &GroundedConfig, frame: &Frame) -> Array3<u8> {
        let g = crate::backend::grounded::Grounded::from_model(cfg.clone(), self.clone(), "training");
        g.predict(&frame.boxes, &frame.masks, &frame.aux)
    }
}

/// Ground-truth labels of `region` for each frame, in the splat's flat order.
fn region_labels(frames: &[Frame], region: Region) -> Vec<u8> {
    let mut t = Vec::with_capacity(frames.len() * region.voxels());
    for f in frames {
        for i in region.i0..region.i0 + region.ni {
            // A row of columns is contiguous in the (standard layout) labels.
            let row = f.labels.slice(ndarray::s![i, region.j0..region.j0 + region.nj, ..]);
            match row.as_slice() {
                Some(r) => t.extend_from_slice(r),
                None => t.extend(row.iter().copied()),
            }
        }
    }
    t
}

/// The step's loss, and `[5]`: the loss, then its parts (ce, lovasz, kl, background aux) for
/// the progress line, detached: one tensor, read back once (on a GPU every read is a round
/// trip that waits for the device), after the backward pass and the update are queued.
pub fn step_loss(
    cfg: &GroundedConfig,
    out: StepOut,
    target: &[u8],
    weights: &[f32; N_LABELS],
    rng: &mut Rng,
) -> (Tensor<1>, Tensor<1>) {
    use rayon::prelude::*;
    let t = &cfg.train;
    // Lovász over every voxel an agent class claims (truth or prediction) plus a uniform draw.
    let n = target.len();
    let draws: Vec<usize> = (0..t.lovasz_samples.min(n)).map(|_| rng.index(n)).collect();
    let idx = lovasz_rows(target, agent_predicted(&out.logits), &draws);
    let sel_t: Vec<u8> = idx.par_iter().map(|&v| target[v]).collect();
    // The background head's rows, only where there is one (the rows move into the loss).
    let sel: Option<Vec<i64>> = out.background.is_some().then(|| idx.par_iter().map(|&v| v as i64).collect());
    let (ce, probs) = cross_entropy_and_probs(out.logits, target, weights, idx);
    let lov = lovasz_softmax(probs, &sel_t);
    let mut total = ce.clone() * t.ce_weight + lov.clone() * t.lovasz_weight;
    let zero = Tensor::<1>::zeros([1], &ce.device());
    let (mut kl_part, mut aux_part) = (zero.clone(), zero);
    if let Some(kl) = out.kl {
        kl_part = kl.clone().detach();
        total = total + kl * t.kl_weight;
    }
    if let (Some(bg), Some(sel)) = (out.background, sel) {
        let m = sel.len();
        let aux = bce_with_logits(take_rows(bg, sel).reshape([m]), &sel_t.iter().map(|&l| l == 1).collect::<Vec<_>>());
        aux_part = aux.clone().detach();
        total = total + aux * t.background_aux_weight;
    }
    let parts = Tensor::cat(vec![total.clone().detach(), ce.detach(), lov.detach(), kl_part, aux_part], 0);
    (total, parts)
}

fn scalar(t: &Tensor<1>) -> f64 {
    t.to_data().iter::<f32>().next().unwrap_or(f32::NAN) as f64
}

/// `step_loss`'s `[5]` read back: the loss and its four parts.
fn read_parts(t: Tensor<1>) -> (f64, [f64; 4]) {
    let v: Vec<f64> = t.into_data().iter::<f32>().map(|v| v as f64).collect();
    let at = |i: usize| v.get(i).copied().unwrap_or(f64::NAN);
    (at(0), [at(1), at(2), at(3), at(4)])
}

/// Cosine decay from `lr` to `lr_min` over `total` steps.
pub fn cosine_lr(s: &StageConfig, step: usize, total: usize) -> f64 {
    let p = (step as f64 / total.max(1) as f64).min(1.0);
    s.lr_min + 0.5 * (s.lr - s.lr_min) * (1.0 + (std::f64::consts::PI * p).cos())
}

/// A seeded permutation of 0..n for `epoch`.
fn shuffled(n: usize, seed: u64, epoch: usize) -> Vec<usize> {
    let mut v: Vec<usize> = (0..n).collect();
    let mut rng = Rng::stream(seed, &format!("shuffle:{epoch}"));
    for i in (1..n).rev() {
        v.swap(i, rng.index(i + 1));
    }
    v
}

/// The batch's crop: around a random box of its first frame 80 % of the time, else uniform.
fn pick_region(cfg: &GroundedConfig, frames: &[Frame], rng: &mut Rng) -> Region {
    let c = cfg.train.crop;
    if c == 0 || c >= NX {
        return Region::full();
    }
    let boxes: Vec<&GBox> = frames
        .first()
        .map(|f| f.boxes.iter().filter(|b| b.x.abs() < 50.0 && b.y.abs() < 50.0).collect())
        .unwrap_or_default();
    let (ci, cj) = if !boxes.is_empty() && rng.unit() < 0.8 {
        let b = boxes[rng.index(boxes.len())];
        (((b.x + 50.0) / 0.25) as usize, ((b.y + 50.0) / 0.25) as usize)
    } else {
        (rng.index(NX), rng.index(NY))
    };
    let i0 = ci.saturating_sub(c / 2).min(NX - c);
    let j0 = cj.saturating_sub(c / 2).min(NY - c);
    Region { i0, j0, ni: c, nj: c }
}

/// Distinct scene names of a set.
pub fn scenes(s: &[Sample]) -> Vec<String> {
    let mut v: Vec<String> = s.iter().map(|s| s.scene.clone()).collect();
    v.sort();
    v.dedup();
    v
}

fn io_err(what: &str, path: &Path, e: impl std::fmt::Display) -> Diagnostic {
    Diagnostic::error("E0906", format!("cannot {what} `{}`: {e}", path.display()))
        .help("check that the output directory is writable and the disk not full")
}

/// A batch ready for its step: the step's random stream (after the region's draw), the region,
/// its ground truth in the splat's order and the step's host input.
struct Batch {
    rng: Rng,
    region: Region,
    target: Vec<u8>,
    input: StepIn,
}

/// A batch loaded and prepared on a thread of its own while the step before runs: on a GPU the
/// host work of a step (about 0.1 s for `paper` at batch 6: the BEV as floats, the labels in the
/// splat's order) would otherwise leave the device idle between steps.
struct Prefetch(std::thread::JoinHandle<Result<Batch, String>>);

impl Prefetch {
    fn start<M: Net>(samples: Vec<Sample>, cfg: &GroundedConfig, stream: String) -> Self {
        let cfg = cfg.clone();
        Prefetch(std::thread::spawn(move || {
            let frames = samples.iter().map(data::load).collect::<Result<Vec<Frame>, String>>()?;
            let mut rng = Rng::stream(cfg.train.seed, &stream);
            let region = pick_region(&cfg, &frames, &mut rng);
            let target = region_labels(&frames, region);
            Ok(Batch { rng, region, target, input: M::step_input(&cfg, &frames) })
        }))
    }

    fn wait(self) -> Result<Batch, String> {
        self.0.join().unwrap_or_else(|_| Err("the thread loading a batch stopped".into()))
    }
}

fn data_err(m: String) -> Diagnostic {
    Diagnostic::error("E0905", m).help(
        "pass a directory that `rocc compile --stage occ` wrote, or the nuPlan-Occ layout of docs/learned-backend.md \
         (\"Training on nuPlan-Occ\")",
    )
}

fn save_module<M: Module>(m: &M, path: &Path) -> Result<(), Diagnostic> {
    let bytes = m.clone().into_record().into_bytes().map_err(|e| io_err("serialise weights for", path, e))?;
    crate::fsio::write_atomic(path, |w| w.write_all(&bytes)).map_err(|e| io_err("write", path, e))?;
    Ok(())
}

fn write_text(path: &Path, text: &str) -> Result<(), Diagnostic> {
    crate::fsio::write_atomic(path, |w| w.write_all(text.as_bytes())).map_err(|e| io_err("write", path, e))?;
    Ok(())
}

/// Score `predict` over `frames` (at most `max`; 0 = all) with the shared scorer.
pub fn score(
    frames: &[Sample],
    max: usize,
    mut predict: impl FnMut(&Frame) -> Array3<u8>,
) -> Result<OccScores, Diagnostic> {
    let mut sc = OccScorer::new();
    let take = if max == 0 { frames.len() } else { max.min(frames.len()) };
    for s in evenly(frames, take) {
        let f = data::load(s).map_err(data_err)?;
        let p = predict(&f);
        sc.add(&p, &f.labels);
    }
    Ok(sc.scores())
}

/// `score`, saying the inference time per frame (median after the first, which compiles the
/// device's kernels).
fn timed_score(
    frames: &[Sample],
    max: usize,
    say: &impl Fn(String),
    mut predict: impl FnMut(&Frame) -> Array3<u8>,
) -> Result<OccScores, Diagnostic> {
    let mut times = Vec::new();
    let scores = score(frames, max, |f| {
        let t0 = Instant::now();
        let p = predict(f);
        times.push(t0.elapsed().as_secs_f64());
        p
    })?;
    if times.len() > 1 {
        say(format!(
            "validation: {} frame(s), inference median {:.0} ms per frame after the first ({:.0} ms)",
            times.len(),
            median(times[1..].iter().copied()) * 1e3,
            times[0] * 1e3
        ));
    }
    Ok(scores)
}

/// The median of a non-empty sequence (the upper one of an even count).
fn median(v: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = v.collect();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// `k` samples spread evenly over `v` (deterministic).
fn evenly<T>(v: &[T], k: usize) -> impl Iterator<Item = &T> {
    let n = v.len();
    (0..k).map(move |i| &v[i * n / k.max(1)])
}

/// The baseline: per height layer, the most frequent label of the training set, everywhere.
pub fn layer_majority(counts: &[[u64; N_LABELS]; NZ]) -> Array3<u8> {
    let mut out = Array3::<u8>::zeros((NX, NY, NZ));
    for (k, c) in counts.iter().enumerate() {
        let l = (0..N_LABELS).max_by_key(|&l| (c[l], std::cmp::Reverse(l))).unwrap_or(0) as u8;
        out.slice_mut(ndarray::s![.., .., k]).fill(l);
    }
    out
}

pub fn train(opts: &TrainOptions) -> Result<TrainReport, Diagnostic> {
    match opts.stage {
        Stage::Autoencoder => run::<Autoencoder>(opts, |m, _| Ok((m, false))),
        Stage::Generator => run::<Generator>(opts, |mut g, device| {
            let init = opts.init.clone().or_else(|| Some(opts.out.join("autoencoder.bpk")).filter(|p| p.is_file()));
            match init {
                Some(p) => {
                    let ae = load_weights(Autoencoder::new(&opts.config, device), &p)?;
                    g.decoder = ae.decoder;
                    if !opts.quiet {
                        eprintln!("decoder warm-started from {}", p.display());
                    }
                    return Ok((g, true));
                }
                None if !opts.quiet => eprintln!("no autoencoder weights (--init): the decoder starts from scratch"),
                None => {}
            }
            Ok((g, false))
        }),
    }
}

/// "N steps: median X s per step after the first (Y s): loading A, forward B, loss C, backward and
/// update D" over the steps after the first (which compiles the device's kernels and warms its
/// allocator), `None` before any step.
pub fn step_summary(phases: &[[f64; 4]]) -> Option<String> {
    let (first, rest) = phases.split_first()?;
    let total = |p: &[f64; 4]| p.iter().sum::<f64>();
    if rest.is_empty() {
        return Some(format!("1 step in {:.3} s", total(first)));
    }
    let part = |k: usize| median(rest.iter().map(|p| p[k]));
    Some(format!(
        "{} steps: median {:.3} s per step after the first ({:.3} s): loading {:.3}, forward {:.3}, loss {:.3}, \
         backward and update {:.3}",
        phases.len(),
        median(rest.iter().map(total)),
        total(first),
        part(0),
        part(1),
        part(2),
        part(3)
    ))
}

/// Write a stage's trained `weights` (`.bpk`) again as `.safetensors` beside them; returns that
/// file.
pub fn export_safetensors(stage: Stage, config: &GroundedConfig, weights: &Path) -> Result<PathBuf, Diagnostic> {
    use crate::backend::grounded::{cpu, save_safetensors};
    let st = weights.with_extension("safetensors");
    let res = match stage {
        Stage::Autoencoder => save_safetensors(&load_weights(Autoencoder::new(config, &cpu()), weights)?, &st),
        Stage::Generator => save_safetensors(&load_weights(Generator::new(config, &cpu()), weights)?, &st),
    };
    res.map_err(|e| {
        Diagnostic::error("E0906", format!("cannot write `{}`: {e}", st.display())).help("check the output directory")
    })?;
    Ok(st)
}

fn run<M: Net>(
    opts: &TrainOptions,
    init: impl FnOnce(M, &Device) -> Result<(M, bool), Diagnostic>,
) -> Result<TrainReport, Diagnostic> {
    let cfg = &opts.config;
    let tc = &cfg.train;
    let stage_cfg = match opts.stage {
        Stage::Autoencoder => &tc.autoencoder,
        Stage::Generator => &tc.generator,
    };
    let say = |s: String| {
        if !opts.quiet {
            eprintln!("{s}");
        }
    };
    let samples = data::scan(&opts.data).map_err(data_err)?;
    let (train, val) = match &opts.val {
        Some(v) => (samples, data::scan(v).map_err(data_err)?),
        None => data::split(samples, tc.val_fraction, tc.seed),
    };
    if train.is_empty() {
        return Err(data_err(format!("every clip of `{}` was held out for validation", opts.data.display())));
    }
    let ck = opts.out.join("checkpoint");
    std::fs::create_dir_all(&ck).map_err(|e| io_err("create", &ck, e))?;
    let stage = opts.stage.name();
    say(format!(
        "{stage}: {} training frame(s) from {} scene(s), {} validation frame(s) from {} held-out scene(s) [{}]; config `{}`",
        train.len(),
        scenes(&train).len(),
        val.len(),
        scenes(&val).len(),
        scenes(&val).join(", "),
        cfg.name
    ));

    // One pass over the training labels: class weights and the baseline.
    let mut layers = [[0u64; N_LABELS]; NZ];
    for s in &train {
        let f = data::load(s).map_err(data_err)?;
        data::layer_counts(&f.labels, &mut layers);
    }
    let mut counts = [0u64; N_LABELS];
    for l in &layers {
        for c in 0..N_LABELS {
            counts[c] += l[c];
        }
    }
    let weights = class_weights(&counts, tc.weight_power, tc.weight_clip, &tc.class_boost);
    let baseline_grid = layer_majority(&layers);
    let baseline = if val.is_empty() { None } else { Some(score(&val, tc.val_max_frames, |_| baseline_grid.clone())?) };
    if let Some(b) = &baseline {
        say(format!(
            "baseline (per-layer majority of the training set): fg-mIoU {:.2}  mIoU_US {:.2}  occ-IoU {:.2}",
            b.fg_miou, b.miou_us, b.occ_iou
        ));
    }

    let device = opts.device.clone().autodiff();
    device.seed(tc.seed);
    if opts.device == crate::backend::grounded::cpu() {
        crate::backend::grounded::heap::keep_freed_memory();
    }
    let (mut model, warm) = init(M::build(cfg, &device), &device)?;
    model.decoder_mut().shape.precision = opts.precision.clone();
    if !warm {
        // The empty-scene prior starts at the training set's per-layer log frequencies: the
        // model begins as the baseline and the latents learn what differs from it.
        let prior: Vec<f32> = layers
            .iter()
            .flat_map(|c| {
                let t = c.iter().sum::<u64>() as f64 + N_LABELS as f64;
                c.iter().map(move |&n| ((n as f64 + 1.0) / t).ln() as f32).collect::<Vec<_>>()
            })
            .collect();
        // The parameter keeps its id (`ids.rs`: the same bytes for the same weights).
        let bias = &mut model.decoder_mut().layer_bias;
        let id = bias.id;
        *bias = burn::module::Param::from_tensor(Tensor::from_data(TensorData::new(prior, [NZ, N_LABELS]), &device));
        bias.id = id;
    }
    let mut optim = super::adam::FusedAdam::init();
    let state_path = ck.join(format!("{stage}-state.ron"));
    let (model_ck, optim_ck) = (ck.join(format!("{stage}-model.bpk")), ck.join(format!("{stage}-optim.bpk")));
    let mut pos = Position::default();
    if opts.resume && state_path.is_file() {
        let text = std::fs::read_to_string(&state_path).map_err(|e| io_err("read", &state_path, e))?;
        pos = ron::from_str(&text).map_err(|e| io_err("parse", &state_path, e))?;
        model = load_weights(model, &model_ck)?;
        optim = optim.load(&optim_ck).map_err(|e| io_err("load the optimiser state", &optim_ck, e))?;
        say(format!("resumed at epoch {} batch {} (step {})", pos.epoch + 1, pos.batch, pos.step));
    }
    let epochs = opts.epochs.unwrap_or(stage_cfg.epochs);
    let per_epoch = train.len().div_ceil(tc.batch);
    let total = epochs * per_epoch;
    let limit = opts.max_steps.map_or(total, |m| m.min(total));
    let pb = if opts.quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(limit as u64)
    };
    pb.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} steps {elapsed_precise} (eta {eta}) {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    pb.set_position(pos.step as u64);

    let save = |model: &M, optim: &burn::optim::ModuleOptimizer, p: Position| -> Result<(), Diagnostic> {
        save_module(model, &model_ck)?;
        let bytes = optim.into_bytes().map_err(|e| io_err("serialise the optimiser for", &optim_ck, e))?;
        crate::fsio::write_atomic(&optim_ck, |w| w.write_all(&bytes)).map_err(|e| io_err("write", &optim_ck, e))?;
        write_text(&state_path, &ron::to_string(&p).unwrap_or_default())
    };

    let mut reports = Vec::new();
    let (run_t0, first_step) = (Instant::now(), pos.step);
    let mut step_phases = Vec::new();
    let mut history_path = opts.out.join(format!("{stage}-history.json"));
    if opts.resume && history_path.is_file() {
        history_path = opts.out.join(format!("{stage}-history.json"));
    }
    'epochs: for epoch in pos.epoch..epochs {
        let order = shuffled(train.len(), tc.seed, epoch);
        let t0 = Instant::now();
        let (mut sum, mut steps) = (0.0f64, 0usize);
        let batch = |bi: usize| -> Vec<Sample> {
            order[bi * tc.batch..((bi + 1) * tc.batch).min(train.len())].iter().map(|&i| train[i].clone()).collect()
        };
        // The next batch loads and is prepared on a thread of its own while this step runs.
        let mut next: Option<Prefetch> = None;
        let start = |bi: usize| Prefetch::start::<M>(batch(bi), cfg, format!("step:{epoch}:{bi}"));
        for bi in pos.batch..per_epoch {
            if pos.step >= limit {
                break 'epochs;
            }
            let step_t0 = Instant::now();
            let Batch { mut rng, region, target, input } =
                next.take().unwrap_or_else(|| start(bi)).wait().map_err(data_err)?;
            if bi + 1 < per_epoch && pos.step + 1 < limit {
                next = Some(start(bi + 1));
            }
            let t_loaded = step_t0.elapsed().as_secs_f64();
            let out = model.step(cfg, input, region, &mut rng);
            let _ = device.sync();
            let t_forward = step_t0.elapsed().as_secs_f64();
            let (loss, parts) = step_loss(cfg, out, &target, &weights, &mut rng);
            let _ = device.sync();
            let t_loss = step_t0.elapsed().as_secs_f64();
            let grads = loss.backward();
            // Mixed precision: an overflow anywhere in the transformer's half-precision regions
            // reaches every gradient below it, the decoder's input layer's included; such a step
            // is skipped.
            let take = match &opts.precision {
                Precision::Full => true,
                Precision::Mixed(scale) => {
                    let g = model.decoder_mut().input.weight.val().grad(&grads);
                    scale.after_backward(g.is_none_or(|g| scalar(&g.sum()).is_finite()))
                }
            };
            if take {
                let grads = GradientsParams::from_grads(grads, &model);
                model = optim.step(cosine_lr(stage_cfg, pos.step, total), model, grads);
            }
            // The step's one read: it waits for the device to finish the step (the timings
            // need that too). A diverged step's update is never saved: the run stops here.
            let (l, parts) = read_parts(parts);
            if !l.is_finite() {
                return Err(Diagnostic::error("E0907", format!("training diverged at step {} (loss {l})", pos.step))
                    .help("lower the stage's `lr` in the config, or resume from the last checkpoint with `--resume`"));
            }
            let _ = device.sync();
            let t_done = step_t0.elapsed().as_secs_f64();
            step_phases.push([t_loaded, t_forward - t_loaded, t_loss - t_forward, t_done - t_loss]);
            pos.step += 1;
            pos.batch = bi + 1;
            sum += l;
            steps += 1;
            pb.set_position(pos.step as u64);
            pb.set_message(format!(
                "epoch {} loss {l:.4} (ce {:.3} lovasz {:.3} kl {:.2} bg {:.3})",
                epoch + 1,
                parts[0],
                parts[1],
                parts[2],
                parts[3]
            ));
            if pos.step % tc.checkpoint_every == 0 {
                save(&model, &optim, pos)?;
            }
        }
        pos = Position { epoch: epoch + 1, batch: 0, step: pos.step };
        // Saved before validation: a validation the device cannot run loses no training.
        save(&model, &optim, pos)?;
        let valid = model.valid();
        let scores = if val.is_empty() {
            None
        } else {
            Some(timed_score(&val, tc.val_max_frames, &say, |f| valid.predict(cfg, f))?)
        };
        let rep = EpochReport {
            epoch: epoch + 1,
            steps,
            mean_loss: if steps > 0 { sum / steps as f64 } else { f64::NAN },
            seconds: t0.elapsed().as_secs_f64(),
            val: scores,
        };
        pb.suspend(|| {
            say(match &rep.val {
                Some(s) => format!(
                    "epoch {}/{epochs}: loss {:.4} over {} step(s) in {:.0} s; validation fg-mIoU {:.2}  mIoU_US {:.2}  occ-IoU {:.2}",
                    rep.epoch, rep.mean_loss, rep.steps, rep.seconds, s.fg_miou, s.miou_us, s.occ_iou
                ),
                None => format!("epoch {}/{epochs}: loss {:.4} over {} step(s) in {:.0} s", rep.epoch, rep.mean_loss, rep.steps, rep.seconds),
            })
        });
        reports.push(rep);
    }
    pb.finish_and_clear();
    // A time-boxed run that stopped mid-epoch still gets a validation line.
    if reports.last().is_none_or(|r| r.epoch != pos.epoch || pos.batch != 0) && pos.step > 0 {
        let per_step = run_t0.elapsed().as_secs_f64() / (pos.step - first_step).max(1) as f64;
        save(&model, &optim, pos)?;
        let valid = model.valid();
        let scores = if val.is_empty() {
            None
        } else {
            Some(timed_score(&val, tc.val_max_frames, &say, |f| valid.predict(cfg, f))?)
        };
        if let Some(s) = &scores {
            say(format!(
                "stopped at step {} ({:.2} s per step): validation fg-mIoU {:.2}  mIoU_US {:.2}  occ-IoU {:.2}",
                pos.step, per_step, s.fg_miou, s.miou_us, s.occ_iou
            ));
        }
        reports.push(EpochReport { epoch: pos.epoch + 1, steps: 0, mean_loss: f64::NAN, seconds: 0.0, val: scores });
    }
    if let Some(line) = step_summary(&step_phases) {
        say(line);
    }
    let skipped_steps = match &opts.precision {
        Precision::Full => 0,
        Precision::Mixed(scale) => {
            say(format!(
                "mixed precision: gradient scale {}, {} step(s) skipped for a gradient beyond half precision",
                scale.value(),
                scale.skipped()
            ));
            scale.skipped()
        }
    };
    let weights_path = opts.out.join(format!("{stage}.bpk"));
    save_module(&model.valid(), &weights_path)?;
    write_text(&weights_path.with_extension("ron"), &cfg.to_ron())?;
    let report = TrainReport {
        stage: opts.stage,
        train_frames: train.len(),
        val_frames: val.len(),
        val_scenes: scenes(&val),
        class_weights: weights,
        baseline,
        epochs: reports,
        weights: weights_path,
        steps: pos.step,
        step_phases,
        precision: opts.precision.name(),
        skipped_steps,
    };
    write_text(&history_path, &serde_json::to_string_pretty(&report).unwrap_or_default())?;
    say(format!("wrote {} (+ .ron)", report.weights.display()));
    Ok(report)
}
