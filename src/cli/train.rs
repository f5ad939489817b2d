//! `rocc train`: train one stage of the grounded occupancy model (`rocc::learn::train`).

use super::Failure;
use clap::ValueEnum;
use rocc::diag::Diagnostic;
use rocc::learn::{Stage, TrainOptions};
use std::path::PathBuf;

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
    #[arg(long, value_enum, default_value = "cpu")]
    device: DeviceArg,
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

#[derive(Clone, Copy, ValueEnum)]
enum DeviceArg {
    /// burn's `flex` backend (pure Rust, every build).
    Cpu,
    /// wgpu (Vulkan/Metal/DX12); needs `--features wgpu`.
    Wgpu,
    /// CUDA device 0; needs `--features cuda`.
    Cuda,
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
    let opts = TrainOptions {
        stage,
        data: a.data,
        val: a.val,
        config,
        out: a.out,
        resume: a.resume,
        init: a.init,
        device: device(a.device)?,
        quiet: a.quiet,
        max_steps: a.max_steps,
        epochs: a.epochs,
    };
    let report = rocc::learn::train(&opts)?;
    if a.safetensors {
        let st = rocc::learn::export_safetensors(stage, &opts.config, &report.weights)?;
        if !a.quiet {
            eprintln!("wrote {}", st.display());
        }
    }
    Ok(())
}

fn device(d: DeviceArg) -> Result<burn::tensor::Device, Diagnostic> {
    match d {
        DeviceArg::Cpu => Ok(burn::tensor::Device::flex()),
        #[cfg(feature = "wgpu")]
        DeviceArg::Wgpu => Ok(burn::tensor::Device::wgpu(Default::default())),
        #[cfg(not(feature = "wgpu"))]
        DeviceArg::Wgpu => Err(Diagnostic::error("E0908", "this rocc was built without the `wgpu` device")
            .help("rebuild with `cargo build --release --features wgpu`, or train with `--device cpu`")),
        #[cfg(feature = "cuda")]
        DeviceArg::Cuda => Ok(burn::tensor::Device::cuda(0usize)),
        #[cfg(not(feature = "cuda"))]
        DeviceArg::Cuda => Err(Diagnostic::error("E0908", "this rocc was built without the `cuda` device")
            .help("rebuild with `cargo build --release --features cuda` (needs network access at build time), or use `--device wgpu|cpu`")),
    }
}
