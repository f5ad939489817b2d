//! The learned backend's test model: small enough for unit tests on the CPU.

use rocc::backend::grounded::config::GroundedConfig;

/// A model small enough for unit tests.
pub fn tiny() -> GroundedConfig {
    let mut c = GroundedConfig::from_ron(include_str!("../../configs/cpu-small.ron")).unwrap();
    c.name = "tiny".into();
    c.latents = 64;
    c.max_foreground = 32;
    c.latent_dim = 8;
    c.decoder = rocc::backend::grounded::config::DecoderConfig { width: 16, blocks: 1, heads: 2, ff: 32 };
    c.gaussians.vehicle = 6;
    c.gaussians.mid = 4;
    c.gaussians.small = 3;
    c.gaussians.background = 2;
    c.lattice.spacing_m = 10.0;
    c.encoder.samples = vec![3, 2, 2];
    c.encoder.hidden = 16;
    c.bev.channels = vec![4, 8];
    c.bev.strides = vec![2, 2];
    c.bev.hidden = 16;
    c
}
