//! Animated previews and the contact sheet. In: per-frame `Bev`, `Occupancy` and `PointCloud`.
//! Out: 400 x 400 palette images (forward up, the ego's left on the image's left, 1 px = 0.25 m,
//! as `preview/bev.png`), `preview/{bev,occ,lidar}.gif` and `preview/sheet.png` (one row per
//! stage, a few frames across).
//!
//! Every image is drawn straight into indices of one fixed 256-colour palette (`palette`): GIF
//! needs a palette anyway, quantising RGB would cost more than drawing, and a fixed palette keeps
//! colours identical across runs and stages.

use super::preview::{BACKGROUND, CHANNEL_COLOURS, EGO_MARK, PAINT_ORDER, STRUCTURE_COLOUR, text};
use super::{OutputFile, write_atomic};
use crate::backend::Occupancy;
use crate::backend::layout::{FREE, K_GROUND, N_LABELS, NX, NY, NZ, ORIGIN, VOXEL};
use crate::lidar::PointCloud;
use crate::raster::Bev;
use crate::raster::layout::{GRID, N_MASKS};
use std::io;
use std::path::Path;
use std::sync::OnceLock;

/// Side of every preview image (px).
pub const SIDE: usize = GRID;

const I_BACKGROUND: u8 = 0;
const I_EGO: u8 = 1;
const I_TEXT: u8 = 2;
/// BEV channel `c` is index `I_BEV + c`; the structure mask follows them.
const I_BEV: u8 = 3;
const I_STRUCTURE: u8 = I_BEV + N_MASKS as u8;
/// Occupancy label `l` at height shade `s` (0 = ground .. SHADES - 1 = top of the grid).
const I_OCC: u8 = I_STRUCTURE + 1;
const SHADES: usize = 8;
/// LiDAR height ramp.
const I_LIDAR: u8 = I_OCC + (N_LABELS * SHADES) as u8;
const RAMP: usize = 32;
const _: () = assert!(I_LIDAR as usize + RAMP <= 256);

/// The preview palette: 256 RGB entries.
pub fn palette() -> &'static [[u8; 3]; 256] {
    static P: OnceLock<[[u8; 3]; 256]> = OnceLock::new();
    P.get_or_init(|| {
        let mut p = [[0u8; 3]; 256];
        p[I_BACKGROUND as usize] = BACKGROUND;
        p[I_EGO as usize] = EGO_MARK;
        p[I_TEXT as usize] = [230, 230, 230];
        for (c, col) in CHANNEL_COLOURS.iter().enumerate() {
            p[I_BEV as usize + c] = *col;
        }
        p[I_STRUCTURE as usize] = STRUCTURE_COLOUR;
        for l in 0..N_LABELS {
            let base = occ_colour(l as u8);
            for s in 0..SHADES {
                // Low voxels dark, high voxels bright: height reads at a glance from above.
                let f = 0.35 + 0.65 * s as f64 / (SHADES - 1) as f64;
                p[I_OCC as usize + l * SHADES + s] = base.map(|v| (v as f64 * f).round() as u8);
            }
        }
        for r in 0..RAMP {
            p[I_LIDAR as usize + r] = ramp(r as f64 / (RAMP - 1) as f64);
        }
        p
    })
}

/// Occupancy label colours: the BEV colour of the same class; background in stone grey.
fn occ_colour(label: u8) -> [u8; 3] {
    match label {
        0 => BACKGROUND,
        1 => [175, 175, 165],
        // Labels 2..=8 are the classes of BEV channels 8..=14, in the same order.
        l => CHANNEL_COLOURS[(l as usize + 6).min(14)],
    }
}

/// Blue -> cyan -> green -> yellow -> red.
fn ramp(t: f64) -> [u8; 3] {
    let stops =
        [[40.0, 60.0, 220.0], [0.0, 200.0, 220.0], [40.0, 210.0, 60.0], [250.0, 220.0, 30.0], [240.0, 40.0, 30.0]];
    let x = t.clamp(0.0, 1.0) * (stops.len() - 1) as f64;
    let i = (x.floor() as usize).min(stops.len() - 2);
    let f = x - i as f64;
    [0, 1, 2].map(|c| (stops[i][c] * (1.0 - f) + stops[i + 1][c] * f).round() as u8)
}

/// Pixel (row, col) of grid cell (i along +x, j along +y): forward up, left on the left.
#[inline]
fn px(i: usize, j: usize) -> usize {
    (SIDE - 1 - i) * SIDE + (SIDE - 1 - j)
}

fn mark_ego(img: &mut [u8]) {
    let c = (SIDE / 2) as i64;
    for (di, dj) in [(0i64, 0i64), (1, 0), (-1, 0), (0, 1), (0, -1), (2, 0)] {
        img[px((c + di) as usize, (c + dj) as usize)] = I_EGO;
    }
}

/// The BEV as palette indices, `SIDE * SIDE`, layers in `PAINT_ORDER`.
pub fn paint_bev(bev: &Bev, img: &mut [u8]) {
    img.fill(I_BACKGROUND);
    for layer in PAINT_ORDER {
        let (plane, col) = match layer {
            Some(ch) => (bev.masks.index_axis(ndarray::Axis(0), ch), I_BEV + ch as u8),
            None => (bev.structure.view(), I_STRUCTURE),
        };
        for ((i, j), &m) in plane.indexed_iter() {
            if m != 0 {
                img[px(i, j)] = col;
            }
        }
    }
    mark_ego(img);
}

/// Occupancy from above: the top non-free voxel of each column, coloured by label and shaded by
/// its height (the ground layer is the darkest shade).
pub fn paint_occ(occ: &Occupancy, img: &mut [u8]) {
    img.fill(I_BACKGROUND);
    for i in 0..NX {
        for j in 0..NY {
            let col = occ.labels.slice(ndarray::s![i, j, ..]);
            if let Some(k) = (0..NZ).rev().find(|&k| col[k] != FREE) {
                let s = (k.saturating_sub(K_GROUND) * SHADES / (NZ - K_GROUND)).min(SHADES - 1);
                let l = (col[k] as usize).min(N_LABELS - 1);
                img[px(i, j)] = I_OCC + (l * SHADES + s) as u8;
            }
        }
    }
    mark_ego(img);
}

/// Points from above, coloured by height (-1 m blue .. 4 m red); the highest point of a pixel wins.
pub fn paint_lidar(pc: &PointCloud, img: &mut [u8]) {
    img.fill(I_BACKGROUND);
    let mut top = vec![f32::NEG_INFINITY; SIDE * SIDE];
    for p in &pc.points {
        let fi = ((p.x as f64 - ORIGIN[0]) / VOXEL).floor();
        let fj = ((p.y as f64 - ORIGIN[1]) / VOXEL).floor();
        if fi < 0.0 || fj < 0.0 || fi >= SIDE as f64 || fj >= SIDE as f64 {
            continue;
        }
        let k = px(fi as usize, fj as usize);
        if p.z > top[k] {
            top[k] = p.z;
            let t = ((p.z as f64 + 1.0) / 5.0).clamp(0.0, 1.0);
            img[k] = I_LIDAR + (t * (RAMP - 1) as f64).round() as u8;
        }
    }
    mark_ego(img);
}

/// Write an animated GIF of `frames` (each `SIDE * SIDE` palette indices), looping, `delay_cs`
/// hundredths of a second per frame.
pub fn write_gif(dir: &Path, name: &str, frames: &[Vec<u8>], delay_cs: u16) -> io::Result<OutputFile> {
    let rel = format!("preview/{name}");
    let flat: Vec<u8> = palette().iter().flatten().copied().collect();
    let bytes = write_atomic(&dir.join(&rel), |out| {
        let mut enc = gif::Encoder::new(&mut *out, SIDE as u16, SIDE as u16, &flat).map_err(io::Error::other)?;
        enc.set_repeat(gif::Repeat::Infinite).map_err(io::Error::other)?;
        for f in frames {
            let frame = gif::Frame {
                width: SIDE as u16,
                height: SIDE as u16,
                delay: delay_cs,
                buffer: std::borrow::Cow::Borrowed(f),
                ..Default::default()
            };
            enc.write_frame(&frame).map_err(io::Error::other)?;
        }
        enc.into_inner().map_err(io::Error::other)?;
        Ok(())
    })?;
    Ok(OutputFile { path: rel, bytes })
}

const LABEL_H: usize = 24;
const GAP: usize = 4;

/// `preview/sheet.png`: one row per stage (`rows[r].0` names it), one column per sampled frame
/// (`frames` gives their indices for the captions).
pub fn write_sheet(dir: &Path, frames: &[usize], rows: &[(&str, Vec<Vec<u8>>)]) -> io::Result<OutputFile> {
    let cols = frames.len().max(1);
    let w = cols * (SIDE + GAP) + GAP;
    let h = rows.len() * (SIDE + LABEL_H + GAP) + GAP;
    let mut idx = vec![I_BACKGROUND; w * h];
    for (r, (name, imgs)) in rows.iter().enumerate() {
        let y0 = GAP + r * (SIDE + LABEL_H + GAP);
        for (c, img) in imgs.iter().enumerate() {
            let x0 = GAP + c * (SIDE + GAP);
            let caption = format!("{name} frame {}", frames.get(c).copied().unwrap_or(0));
            text_indexed(&mut idx, w, h, x0 + 2, y0 + 6, &caption);
            for row in 0..SIDE {
                let dst = (y0 + LABEL_H + row) * w + x0;
                idx[dst..dst + SIDE].copy_from_slice(&img[row * SIDE..(row + 1) * SIDE]);
            }
        }
    }
    let pal = palette();
    let rgb: Vec<u8> = idx.iter().flat_map(|&i| pal[i as usize]).collect();
    let rel = "preview/sheet.png".to_string();
    let bytes = write_atomic(&dir.join(&rel), |out| {
        let mut enc = png::Encoder::new(&mut *out, w as u32, h as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc.write_header().map_err(io::Error::other)?;
        wr.write_image_data(&rgb).map_err(io::Error::other)?;
        wr.finish().map_err(io::Error::other)
    })?;
    Ok(OutputFile { path: rel, bytes })
}

/// Captions through the RGB glyph painter: draw into a scratch RGB strip, copy lit pixels back.
fn text_indexed(idx: &mut [u8], w: usize, h: usize, x: usize, y: usize, s: &str) {
    let strip_h = 12;
    let strip_w = (s.len() * 8 + 4).min(w.saturating_sub(x));
    let mut rgb = vec![0u8; strip_w * strip_h * 3];
    text(&mut rgb, strip_w, strip_h, 0, 0, s, [255, 255, 255]);
    for r in 0..strip_h {
        for c in 0..strip_w {
            if rgb[(r * strip_w + c) * 3] != 0 && y + r < h {
                idx[(y + r) * w + x + c] = I_TEXT;
            }
        }
    }
}
