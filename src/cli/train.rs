//! `rocc train`: train one stage of the grounded occupancy model (`rocc::learn::train`).

use super::Failure;
use clap::ValueEnum;
use rocc::backend::grounded::DeviceKind;
use rocc::backend::grounded::attention::{Precision, check};
use rocc::backend::grounded::guard::guarded;
use rocc::diag::Diagnostic;
use rocc::learn::{Stage, TrainOptions};
use std::path::PathBuf;
use std::str::FromStr;

#[derive(clap::Args)]
pub struct Args {
    #[arg(value_enum)]
    what: TrainWhat,
    /// Training data: `rocc compile --stage occ` output, or bev/ occ/ boxes/ per token.
    #[arg(long)]
    data: PathBuf,
    /// Model and training config (RON), e.g. configs/cpu-small.ron or configs/paper.ron.
    #[arg(long)]
    config: PathBuf,
    /// Output directory: weights, config copy, checkpoints, history.
    #[arg(short, long)]
    out: PathBuf,
    /// Held-out data (default: `val_fraction` of the clips of --data, by the config's seed).
    #[arg(long)]
    val: Option<PathBuf>,
    /// Continue from OUT/checkpoint.
    #[arg(long)]
    resume: bool,
    /// Generator: autoencoder weights to start the decoder from (default OUT/autoencoder.bpk).
    #[arg(long)]
    init: Option<PathBuf>,
    /// cpu (every build), wgpu (Vulkan/Metal/DX12; `--features wgpu`) or cuda (`--features cuda`).
    #[arg(long, default_value = "cpu", value_parser = DeviceKind::from_str)]
    device: DeviceKind,
    /// full (f32 throughout) or mixed (the transformer's products in f16, for GPUs with tensor
    /// cores; docs/learned-backend.md).
    #[arg(long, default_value = "full", value_parser = Precision::from_str)]
    precision: Precision,
    /// Override the stage's epoch count.
    #[arg(long)]
    epochs: Option<usize>,
    /// Stop after this many steps in all (weights and a validation line are still written).
    #[arg(long)]
    max_steps: Option<usize>,
    /// Also export the final weights as OUT/<stage>.safetensors.
    #[arg(long)]
    safetensors: bool,
    #[arg(short, long)]
    quiet: bool,
}

#[derive(Clone, Copy, ValueEnum)]
enum TrainWhat {
    /// Occupancy -> grounded latents -> decoder (pretrains the shared decoder).
    Autoencoder,
    /// BEV + boxes -> grounded latents -> decoder (warm-started from the autoencoder).
    Generator,
}

pub fn run(a: Args) -> Result<(), Failure> {
    let config = rocc::backend::grounded::load_config(&a.config)?;
    let stage = match a.what {
        TrainWhat::Autoencoder => Stage::Autoencoder,
        TrainWhat::Generator => Stage::Generator,
    };
    if let Some(p) = &a.init
        && !p.is_file()
    {
        return Err(Diagnostic::error("E0901", format!("`--init {}` does not exist", p.display()))
            .help("pass the autoencoder weights `rocc train autoencoder` wrote (OUT/autoencoder.bpk)")
            .into());
    }
    let device = a.device.open()?;
    check(&a.precision, &device)?;
    let opts = TrainOptions {
        stage,
        data: a.data,
        val: a.val,
        config,
        out: a.out,
        resume: a.resume,
        init: a.init,
        device,
        quiet: a.quiet,
        max_steps: a.max_steps,
        epochs: a.epochs,
        precision: a.precision,
    };
    // On a GPU, a device failure (memory, a buffer limit) is a diagnostic; checkpoints
    // already written stay, so `--resume` continues after the cause is fixed.
    let report = if a.device.is_gpu() { guarded(|| rocc::learn::train(&opts))?? } else { rocc::learn::train(&opts)? };
    if a.safetensors {
        let st = rocc::learn::export_safetensors(stage, &opts.config, &report.weights)?;
        if !a.quiet {
            eprintln!("wrote {}", st.display());
        }
    }
    Ok(())
}
