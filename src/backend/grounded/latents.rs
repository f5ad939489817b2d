//! The grounded latent set (section 3.4). In: one frame's boxes (`GBox`, ego frame) and its BEV
//! masks. Out: `Anchor`s — one per box (long vehicles split along their heading), then a regular
//! background lattice over the map footprint — at most `latents` of them, and the plain features
//! every latent carries into the decoder. No tensors here.

use super::config::GroundedConfig;
use crate::backend::layout::{
    BACKGROUND, BARRIER, BICYCLE, CZONE_SIGN, GENERIC_OBJECT, N_LABELS, ORIGIN, PEDESTRIAN, TRAFFIC_CONE, VEHICLE,
    VOXEL,
};
use crate::raster::layout::{GRID, RES};
use ndarray::Array3;

/// One box in the ego frame with its occupancy label (2..=8, or 1 for structures).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GBox {
    pub label: u8,
    /// Centre (m).
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub l: f64,
    pub w: f64,
    pub h: f64,
    pub yaw: f64,
}

/// Where a latent lives and what it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anchor {
    /// Ego frame (m).
    pub pos: [f64; 3],
    pub yaw: f64,
    /// Length, width, height of what it stands for (m): the box piece, or the lattice cell.
    pub ext: [f64; 3],
    pub label: u8,
    pub foreground: bool,
}

/// Width of `anchor_features`.
pub const ANCHOR_FEATS: usize = 9 + N_LABELS + 16;

impl Anchor {
    /// Continuous voxel coordinates of the anchor (voxel i spans [i, i + 1)).
    pub fn voxel(&self) -> [f32; 3] {
        [0, 1, 2].map(|a| ((self.pos[a] - ORIGIN[a]) / VOXEL) as f32)
    }

    /// Position (scaled), heading, extents, foreground flag, class one-hot and Fourier
    /// features of (x, y): what the decoder knows of a latent besides its channels.
    pub fn features(&self, out: &mut Vec<f32>) {
        let [x, y, z] = self.pos;
        out.extend([
            (x / 50.0) as f32,
            (y / 50.0) as f32,
            (z / 4.0) as f32,
            self.yaw.cos() as f32,
            self.yaw.sin() as f32,
            (self.ext[0] / 10.0) as f32,
            (self.ext[1] / 5.0) as f32,
            (self.ext[2] / 5.0) as f32,
            self.foreground as u8 as f32,
        ]);
        out.extend((0..N_LABELS).map(|c| (c == self.label as usize) as u8 as f32));
        for f in [1.0, 2.0, 4.0, 8.0] {
            let (a, b) = (std::f64::consts::PI * f * x / 50.0, std::f64::consts::PI * f * y / 50.0);
            out.extend([a.sin() as f32, a.cos() as f32, b.sin() as f32, b.cos() as f32]);
        }
    }
}

/// Gaussians a latent of this label splats (App. A: vehicles 96, mid-size 48, background 32,
/// small 24 in the paper's configuration).
pub fn budget(cfg: &GroundedConfig, label: u8) -> usize {
    let g = &cfg.gaussians;
    let b = match label {
        VEHICLE => g.vehicle,
        BICYCLE | BARRIER | GENERIC_OBJECT => g.mid,
        PEDESTRIAN | TRAFFIC_CONE | CZONE_SIGN => g.small,
        _ => g.background,
    };
    b.min(cfg.max_gaussians())
}

/// Height of one lattice cell (m): the 8 m grid shared among the lattice layers.
pub fn lattice_cell_height(cfg: &GroundedConfig) -> f64 {
    8.0 / cfg.lattice.z_m.len() as f64
}

/// The latent set of one frame: foreground first (nearest the ego first, capped at
/// `max_foreground`), then the background lattice (nearest first), `latents` in all.
pub fn build(cfg: &GroundedConfig, boxes: &[GBox], masks: &Array3<i8>) -> Vec<Anchor> {
    let mut fg = Vec::new();
    let mut order: Vec<&GBox> =
        boxes.iter().filter(|b| b.l > 0.0 && b.w > 0.0 && b.h > 0.0 && b.x.is_finite() && b.y.is_finite()).collect();
    order.sort_by(|a, b| a.x.hypot(a.y).total_cmp(&b.x.hypot(b.y)));
    for b in order {
        let n = ((b.l / cfg.split_length_m).ceil() as usize).clamp(1, cfg.max_split);
        let piece = b.l / n as f64;
        let (c, s) = (b.yaw.cos(), b.yaw.sin());
        for p in 0..n {
            let t = (p as f64 + 0.5) * piece - b.l / 2.0;
            fg.push(Anchor {
                pos: [b.x + c * t, b.y + s * t, b.z],
                yaw: b.yaw,
                ext: [piece, b.w, b.h],
                label: b.label,
                foreground: true,
            });
        }
    }
    fg.truncate(cfg.max_foreground);
    let room = cfg.latents.saturating_sub(fg.len());
    let mut bg = lattice(cfg, masks);
    bg.sort_by(|a, b| a.pos[0].hypot(a.pos[1]).total_cmp(&b.pos[0].hypot(b.pos[1])));
    bg.truncate(room);
    fg.extend(bg);
    fg
}

/// Lattice points whose cell holds any footprint pixel, in raster order, one per height layer.
fn lattice(cfg: &GroundedConfig, masks: &Array3<i8>) -> Vec<Anchor> {
    let sp = cfg.lattice.spacing_m;
    let n = (100.0 / sp).floor() as usize;
    let cell_px = (sp / RES).round().max(1.0) as usize;
    let dz = lattice_cell_height(cfg);
    let (nc, nx, ny) = masks.dim();
    let mut out = Vec::new();
    for a in 0..n {
        for b in 0..n {
            let (x, y) = (-50.0 + sp * (a as f64 + 0.5), -50.0 + sp * (b as f64 + 0.5));
            let (i0, j0) = (((x - sp / 2.0 + 50.0) / RES) as usize, ((y - sp / 2.0 + 50.0) / RES) as usize);
            let hit = (i0..(i0 + cell_px).min(GRID.min(nx))).step_by(2).any(|i| {
                (j0..(j0 + cell_px).min(GRID.min(ny)))
                    .step_by(2)
                    .any(|j| cfg.lattice.footprint_channels.iter().any(|&ch| ch < nc && masks[[ch, i, j]] != 0))
            });
            if hit {
                for &z in &cfg.lattice.z_m {
                    out.push(Anchor {
                        pos: [x, y, z],
                        yaw: 0.0,
                        ext: [sp, sp, dz],
                        label: BACKGROUND,
                        foreground: false,
                    });
                }
            }
        }
    }
    out
}

/// The autoencoder's view of the ground truth around one anchor: the label at each of
/// `samples` points spread over the anchor's extents (x 1.25, so the box's surface is inside),
/// in its own frame, one-hot. Points outside the grid read free.
pub fn encoder_input(cfg: &GroundedConfig, a: &Anchor, labels: &Array3<u8>, out: &mut Vec<f32>) {
    let (sx, sy, sz) = (cfg.encoder.samples[0], cfg.encoder.samples[1], cfg.encoder.samples[2]);
    let (c, s) = (a.yaw.cos(), a.yaw.sin());
    for u in 0..sx {
        for v in 0..sy {
            for w in 0..sz {
                let lu = ((u as f64 + 0.5) / sx as f64 - 0.5) * a.ext[0] * 1.25;
                let lv = ((v as f64 + 0.5) / sy as f64 - 0.5) * a.ext[1] * 1.25;
                let lw = ((w as f64 + 0.5) / sz as f64 - 0.5) * a.ext[2] * 1.25;
                let p = [a.pos[0] + c * lu - s * lv, a.pos[1] + s * lu + c * lv, a.pos[2] + lw];
                let l = crate::backend::layout::voxel_of(p).map(|[i, j, k]| labels[[i, j, k]]).unwrap_or(0);
                out.extend((0..N_LABELS).map(|k| (k == l as usize) as u8 as f32));
            }
        }
    }
}
