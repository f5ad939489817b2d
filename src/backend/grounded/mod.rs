//! The learned occupancy backend, `--backend grounded --weights FILE` (the paper's section 3.4
//! and appendix A). In: an `OccInput` (the frame's ego-frame boxes and its BEV). Out: an
//! `Occupancy` in the same layout as the procedural backend.
//!
//! The scene is a set of grounded latents (`latents`): one per box (long vehicles split along
//! their heading), then a background lattice over the map footprint. The generator (`model`)
//! encodes the 25-channel BEV with a 2D CNN, gives each latent the feature sampled at its anchor
//! (plus its box), and the shared transformer decoder turns each latent into a class-dependent
//! budget of anisotropic 3D Gaussians, splatted (`splat`) into per-voxel class logits with free
//! space on its own channel; a zero-initialised, foreground-gated background head adds a
//! residual. Inference (`infer`) is a deterministic forward pass over a few frames at once, on
//! burn's `flex` CPU backend or a GPU (`device`; failures there are diagnostics, `guard`);
//! labels are the per-voxel argmax. Training lives in `crate::learn`.
//!
//! Weights: burnpack `.bpk` (what `rocc train` writes) or `.safetensors` (tensor names as burn's
//! module paths, e.g. `decoder.head.weight`), plus the RON config the model was built from
//! (`configs/*.ron`; by default the `.ron` next to the weights file, which `rocc train` writes).

pub mod attention;
pub mod config;
pub mod conv;
pub mod cross_entropy;
pub mod device;
pub mod expf;
pub mod gelu;
pub mod guard;
pub mod head;
pub mod heap;
mod host_read;
mod ids;
mod infer;
pub mod latents;
pub mod loss;
pub mod model;
mod par;
pub mod rows;
pub mod softmax;
pub mod splat;
pub mod strips;

pub use config::GroundedConfig;
pub use device::DeviceKind;
pub use infer::FrameIn;
pub use latents::{Anchor, GBox};
pub use model::{Autoencoder, BEV_CHANNELS, Generator, HostBatch};

use super::layout::class_label;
use crate::diag::Diagnostic;
use crate::view::EgoBox;
use attention::Precision;
use burn::module::Module;
use burn::prelude::*;
use std::path::{Path, PathBuf};

impl GBox {
    pub fn from_ego(b: &EgoBox) -> Self {
        GBox { label: class_label(b.class), x: b.x, y: b.y, z: b.z, l: b.l, w: b.w, h: b.h, yaw: b.yaw }
    }
}

/// The CPU device (`--device cpu`, the default).
pub fn cpu() -> Device {
    Device::flex()
}

/// Weight formats rocc reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WeightFormat {
    Burnpack,
    Safetensors,
}

impl WeightFormat {
    pub fn of(path: &Path) -> Option<Self> {
        match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
            Some("bpk") => Some(WeightFormat::Burnpack),
            Some("safetensors") => Some(WeightFormat::Safetensors),
            _ => None,
        }
    }
}

/// The config that goes with a weights file: `explicit`, else `W.ron` beside `W`.
pub fn config_path(weights: &Path, explicit: Option<&Path>) -> PathBuf {
    explicit.map(Path::to_path_buf).unwrap_or_else(|| weights.with_extension("ron"))
}

/// Read and validate a config file (E0902 on failure).
pub fn load_config(path: &Path) -> Result<GroundedConfig, Diagnostic> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        Diagnostic::error("E0902", format!("cannot read grounded config `{}`: {e}", path.display())).help(
            "pass `--grounded-config FILE` (e.g. configs/cpu-small.ron), or keep the `.ron` that `rocc train` \
             writes next to the weights",
        )
    })?;
    GroundedConfig::from_ron(&text).map_err(|e| {
        Diagnostic::error("E0902", format!("grounded config `{}`: {e}", path.display()))
            .help("start from configs/cpu-small.ron or configs/paper.ron; `rocc explain E0902` lists the fields")
    })
}

/// Load weights into `module` (built from the matching config): E0901 missing file, E0903
/// tensors missing, unexpected or of the wrong shape, E0904 unknown format.
pub fn load_weights<M: Module + burn::store::ModuleSnapshot>(module: M, path: &Path) -> Result<M, Diagnostic> {
    if !path.is_file() {
        return Err(missing_weights(path));
    }
    let mismatch = |why: String| {
        Diagnostic::error("E0903", format!("weights `{}` do not fit the configured model: {why}", path.display())).help(
            "use the config the weights were trained with (the `.ron` `rocc train` wrote beside them); an \
             autoencoder checkpoint is not a generator",
        )
    };
    match WeightFormat::of(path) {
        Some(WeightFormat::Burnpack) => module.try_load_file(path).map_err(|e| mismatch(e.to_string())),
        Some(WeightFormat::Safetensors) => {
            let mut module = module;
            let mut store = burn::store::SafetensorsStore::from_file(path).validate(true).allow_partial(false);
            let res = module.load_from(&mut store).map_err(|e| mismatch(e.to_string()))?;
            if !res.errors.is_empty() || !res.missing.is_empty() {
                let mut parts: Vec<String> = res.errors.iter().take(3).map(|e| format!("{e:?}")).collect();
                parts.extend(res.missing.iter().take(3).map(|(p, _)| format!("missing `{p}`")));
                return Err(mismatch(parts.join("; ")));
            }
            if !res.unused.is_empty() {
                return Err(mismatch(format!(
                    "{} tensor(s) the model does not have, e.g. `{}`",
                    res.unused.len(),
                    res.unused[0]
                )));
            }
            Ok(module)
        }
        None => Err(Diagnostic::error(
            "E0904",
            format!("`{}`: unknown weights format (expected `.bpk` or `.safetensors`)", path.display()),
        )
        .help("rocc reads burnpack (`.bpk`, what `rocc train` writes) and safetensors")),
    }
}

/// Save `module` as safetensors (tensor names = module paths).
pub fn save_safetensors<M: Module + burn::store::ModuleSnapshot>(module: &M, path: &Path) -> Result<(), String> {
    // One metadata entry: burn keeps its entries in a hash map, whose order (and so the file's
    // bytes) changes from process to process.
    let mut store = burn::store::SafetensorsStore::from_file(path)
        .clear_metadata()
        .metadata("producer", concat!("rocc ", env!("CARGO_PKG_VERSION")));
    module.save_into(&mut store).map_err(|e| e.to_string())
}

/// The learned backend: a generator on a device (`infer` runs it).
pub struct Grounded {
    pub config: GroundedConfig,
    pub model: Generator,
    name: String,
    /// The files it was loaded from (`None` for a model built in memory), recorded in the
    /// manifest so `rocc edit` can rerun the same model.
    files: Option<(PathBuf, PathBuf)>,
    /// Where the model lives, and how many frames one forward pass takes.
    kind: DeviceKind,
    batch: usize,
}

impl Grounded {
    /// Load `weights` with its config (`config` or the `.ron` beside the weights), on the CPU.
    pub fn load(weights: &Path, config: Option<&Path>) -> Result<Self, Diagnostic> {
        Self::load_on(weights, config, DeviceKind::Cpu, None, false)
    }

    /// Load onto `kind` (probed first: E0908, E0910), running `batch` frames per forward pass
    /// (default `DeviceKind::default_batch`).
    pub fn load_on(
        weights: &Path,
        config: Option<&Path>,
        kind: DeviceKind,
        batch: Option<usize>,
        mixed: bool,
    ) -> Result<Self, Diagnostic> {
        if !weights.is_file() {
            return Err(missing_weights(weights));
        }
        let cfg_path = config_path(weights, config);
        let cfg = load_config(&cfg_path)?;
        let device = kind.open()?;
        let precision = if mixed { Precision::Mixed(Default::default()) } else { Precision::Full };
        attention::check(&precision, &device)?;
        let mut model = guard::guarded(|| load_weights(Generator::new(&cfg, &device), weights))??;
        model.decoder.shape.precision = precision;
        let bytes = std::fs::read(weights).map_err(|e| {
            Diagnostic::error("E0901", format!("cannot read weights `{}`: {e}", weights.display()))
                .help("check the path and its permissions")
        })?;
        let hash = crate::fsio::input_hash(&bytes);
        let short = hash.rsplit(':').next().unwrap_or(&hash);
        Ok(Grounded {
            // Mixed precision changes the labels' last bits: it is another backend for a manifest.
            name: format!(
                "grounded-{}-{}{}",
                cfg.name,
                &short[..short.len().min(12)],
                if mixed { "-mixed" } else { "" }
            ),
            config: cfg,
            model,
            files: Some((weights.to_path_buf(), cfg_path)),
            kind,
            batch: batch.unwrap_or(kind.default_batch()).max(1),
        })
    }

    /// Wrap a model in memory (tests, benchmarks); `kind` is the device the model was built on.
    pub fn from_model(config: GroundedConfig, model: Generator, name: &str) -> Self {
        Grounded { config, model, name: name.to_string(), files: None, kind: DeviceKind::Cpu, batch: 1 }
    }

    /// The same model on `kind`, `batch` frames per forward pass (benchmarks and tests).
    pub fn on(mut self, kind: DeviceKind, batch: usize) -> Result<Self, Diagnostic> {
        let device = kind.open()?;
        self.model = guard::guarded(|| self.model.to_device(&device))?;
        self.kind = kind;
        self.batch = batch.max(1);
        Ok(self)
    }

    /// The device the model runs on.
    pub fn device(&self) -> DeviceKind {
        self.kind
    }

    /// The weights and config files it was loaded from (as given), if loaded from files.
    pub fn files(&self) -> Option<(&Path, &Path)> {
        self.files.as_ref().map(|(w, c)| (w.as_path(), c.as_path()))
    }
}

fn missing_weights(path: &Path) -> Diagnostic {
    Diagnostic::error("E0901", format!("weights file `{}` does not exist", path.display()))
        .help("train one with `rocc train generator --data DIR --config FILE --out DIR` (it writes DIR/generator.bpk)")
}
