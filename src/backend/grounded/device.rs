//! Where the learned backend runs: `--device cpu|wgpu|cuda` of `rocc train` and `rocc compile`.
//! In: the option's text. Out: a burn `Device`, or E0908 where this build lacks the device's
//! feature and E0910 where the feature is built but no device answers (a probe runs first, so
//! the failure comes before any work is done).

use super::guard::guarded;
use crate::diag::Diagnostic;
use burn::prelude::*;
use std::str::FromStr;

/// A device rocc can run the model on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DeviceKind {
    /// burn's `flex` backend: pure Rust, every build.
    #[default]
    Cpu,
    /// wgpu (Vulkan, Metal, DX12): the `wgpu` feature.
    Wgpu,
    /// CUDA device 0: the `cuda` feature.
    Cuda,
}

impl FromStr for DeviceKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "cpu" => Ok(DeviceKind::Cpu),
            "wgpu" => Ok(DeviceKind::Wgpu),
            "cuda" => Ok(DeviceKind::Cuda),
            _ => Err(format!("unknown device `{s}` (expected cpu, wgpu or cuda)")),
        }
    }
}

impl std::fmt::Display for DeviceKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl DeviceKind {
    pub fn name(self) -> &'static str {
        match self {
            DeviceKind::Cpu => "cpu",
            DeviceKind::Wgpu => "wgpu",
            DeviceKind::Cuda => "cuda",
        }
    }

    pub fn is_gpu(self) -> bool {
        self != DeviceKind::Cpu
    }

    /// Frames per forward pass when `--grounded-batch` is not given: one on the CPU (frames
    /// run side by side on the cores instead), a few on a GPU.
    pub fn default_batch(self) -> usize {
        if self.is_gpu() { 4 } else { 1 }
    }

    /// The device, probed: a GPU that cannot be reached is E0910 here, not a panic later.
    pub fn open(self) -> Result<Device, Diagnostic> {
        let device = self.device()?;
        if self.is_gpu() {
            // Whatever stops two floats from making the round trip leaves the device unusable.
            guarded(|| {
                let t = Tensor::<1>::from_data(TensorData::new(vec![1.0f32, 2.0], [2]), &device);
                (t * 2.0).to_data()
            })
            .map_err(|d| match d.code {
                "E0913" => Diagnostic::error("E0910", format!("the {self} device failed a first test: {}", d.message))
                    .help("check the GPU driver (`vulkaninfo`, `nvidia-smi`), or use `--device cpu`"),
                _ => d,
            })?;
        }
        Ok(device)
    }

    /// The device without the probe (E0908 where this build lacks its feature).
    fn device(self) -> Result<Device, Diagnostic> {
        match self {
            DeviceKind::Cpu => Ok(Device::flex()),
            #[cfg(feature = "wgpu")]
            DeviceKind::Wgpu => Ok(Device::wgpu(Default::default())),
            #[cfg(not(feature = "wgpu"))]
            DeviceKind::Wgpu => Err(Diagnostic::error("E0908", "this rocc was built without the `wgpu` device")
                .help("rebuild with `cargo build --release --features wgpu`, or use `--device cpu`")),
            #[cfg(feature = "cuda")]
            DeviceKind::Cuda => Ok(Device::cuda(0usize)),
            #[cfg(not(feature = "cuda"))]
            DeviceKind::Cuda => Err(Diagnostic::error("E0908", "this rocc was built without the `cuda` device").help(
                "rebuild with `cargo build --release --features cuda` (needs network access at build time), \
                     or use `--device wgpu|cpu`",
            )),
        }
    }
}

/// The largest buffer `device` allocates and binds, in bytes (`None` on the CPU, which has no such
/// limit): what `strips` sizes inference by.
pub fn largest_buffer(device: &Device) -> Option<u64> {
    #[cfg(any(feature = "wgpu", feature = "cuda"))]
    if let burn::backend::DispatchDevice::Cube(d) = device.as_dispatch() {
        return Some(d.client().properties().memory.max_page_size);
    }
    let _ = device;
    None
}
