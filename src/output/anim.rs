//! Animated previews and the contact sheet. In: per-frame images drawn by `paint`. Out:
//! `preview/{bev,occ,lidar}.gif` and `preview/sheet.png` (one row per stage, a few frames across).

use super::paint::{I_BACKGROUND, I_TEXT, SIDE, palette, text};
use super::{OutputFile, write_atomic};
use std::io;
use std::path::Path;

/// One GIF frame, LZW-coded by the thread that drew it, so a clip's frames code in parallel and
/// `write_gif` only copies them (the bytes are those `gif` writes from the indices).
pub struct GifFrame(gif::Frame<'static>);

/// Code `img` (`SIDE * SIDE` palette indices) as a GIF frame shown `delay_cs` hundredths of a
/// second.
pub fn gif_frame(img: &[u8], delay_cs: u16) -> GifFrame {
    let mut frame = gif::Frame {
        width: SIDE as u16,
        height: SIDE as u16,
        delay: delay_cs,
        buffer: std::borrow::Cow::Owned(img.to_vec()),
        ..Default::default()
    };
    frame.make_lzw_pre_encoded();
    GifFrame(frame)
}

/// Write an animated GIF of `frames`, looping.
pub fn write_gif(dir: &Path, name: &str, frames: &[&GifFrame]) -> io::Result<OutputFile> {
    let rel = format!("preview/{name}");
    let flat: Vec<u8> = palette().iter().flatten().copied().collect();
    let bytes = write_atomic(&dir.join(&rel), |out| {
        let mut enc = gif::Encoder::new(&mut *out, SIDE as u16, SIDE as u16, &flat).map_err(io::Error::other)?;
        enc.set_repeat(gif::Repeat::Infinite).map_err(io::Error::other)?;
        for f in frames {
            enc.write_lzw_pre_encoded_frame(&f.0).map_err(io::Error::other)?;
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
    let flat: Vec<u8> = palette().iter().flatten().copied().collect();
    let rel = "preview/sheet.png".to_string();
    let bytes = write_atomic(&dir.join(&rel), |out| {
        // Palette indices as drawn: a third of the RGB bytes, and no colour is lost.
        let mut enc = png::Encoder::new(&mut *out, w as u32, h as u32);
        enc.set_color(png::ColorType::Indexed);
        enc.set_palette(flat);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        let mut wr = enc.write_header().map_err(io::Error::other)?;
        wr.write_image_data(&idx).map_err(io::Error::other)?;
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
