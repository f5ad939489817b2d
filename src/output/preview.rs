//! BEV preview. In: one `Bev`. Out: an RGB image (as `paint` draws it) with a legend of channel
//! colours, numbers and names; written as `preview/bev.png`.

use super::paint::{BACKGROUND, CHANNEL_COLOURS, EGO_MARK, STRUCTURE_COLOUR, paint_bev, palette, text};
use super::{OutputFile, write_atomic};
use crate::raster::Bev;
use crate::raster::layout::{GRID, MASK_NAMES, N_MASKS};
use std::io;
use std::path::Path;

const ROW_H: usize = 20;
const LEGEND_W: usize = 250;

/// Render `bev` as RGB: returns (width, height, pixels row-major).
pub fn render_preview(bev: &Bev) -> (u32, u32, Vec<u8>) {
    let (w, h) = (GRID + LEGEND_W, GRID.max(ROW_H * (N_MASKS + 2)));
    let mut img = vec![0u8; w * h * 3];
    for px in img.chunks_exact_mut(3) {
        px.copy_from_slice(&BACKGROUND);
    }
    let put = |img: &mut [u8], r: usize, c: usize, col: [u8; 3]| {
        let k = (r * w + c) * 3;
        img[k..k + 3].copy_from_slice(&col);
    };
    let mut idx = vec![0u8; GRID * GRID];
    paint_bev(bev, &mut idx);
    let pal = palette();
    for r in 0..GRID {
        for c in 0..GRID {
            put(&mut img, r, c, pal[idx[r * GRID + c] as usize]);
        }
    }
    // Legend.
    let x0 = GRID + 10;
    let entries = (0..N_MASKS)
        .map(|ch| (format!("{ch:>2} {}", MASK_NAMES[ch]), CHANNEL_COLOURS[ch]))
        .chain([("   structure".to_string(), STRUCTURE_COLOUR), ("   ego".to_string(), EGO_MARK)]);
    for (row, (label, col)) in entries.enumerate() {
        let y0 = 6 + row * ROW_H;
        for r in y0..y0 + 12 {
            for c in x0..x0 + 12 {
                if r < h {
                    put(&mut img, r, c, col);
                }
            }
        }
        text(&mut img, w, h, x0 + 18, y0 + 1, &label, [230, 230, 230]);
    }
    (w as u32, h as u32, img)
}

/// Write `dir/preview/bev.png`.
pub fn write_preview_png(dir: &Path, bev: &Bev) -> io::Result<OutputFile> {
    let (w, h, data) = render_preview(bev);
    let bytes = write_atomic(&dir.join("preview").join("bev.png"), |out| {
        let mut enc = png::Encoder::new(&mut *out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        let mut wr = enc.write_header().map_err(io::Error::other)?;
        wr.write_image_data(&data).map_err(io::Error::other)?;
        wr.finish().map_err(io::Error::other)
    })?;
    Ok(OutputFile { path: "preview/bev.png".to_string(), bytes })
}
