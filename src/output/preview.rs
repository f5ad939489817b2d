//! BEV preview. In: one `Bev`. Out: an RGB image (forward up, the ego's left on the image's left,
//! 1 px = 0.25 m) with a legend of channel colours, numbers and names; written as
//! `preview/bev.png`.
//!
//! Colours are fixed (`CHANNEL_COLOURS`) so previews of different runs compare by eye. Layers are
//! painted surfaces first, markings next, agents last (`PAINT_ORDER`), so a later channel hides an
//! earlier one where both are set. Text uses a built-in 3x5 bitmap font drawn at 2x.

use super::anim::{paint_bev, palette};
use crate::raster::Bev;
use crate::raster::layout::{GRID, MASK_NAMES, N_MASKS};
use std::io;
use std::path::Path;

/// RGB per `gt_bev_masks` channel.
pub const CHANNEL_COLOURS: [[u8; 3]; N_MASKS] = [
    [110, 95, 140],  // 0 intersections
    [58, 58, 64],    // 1 generic_drivable_areas
    [150, 128, 96],  // 2 walkways
    [70, 100, 130],  // 3 carpark_areas
    [205, 205, 205], // 4 crosswalks
    [92, 78, 118],   // 5 lane_group_connectors
    [72, 84, 100],   // 6 lane_groups_polygons
    [84, 84, 90],    // 7 road_segments
    [30, 144, 255],  // 8 vehicle
    [255, 140, 0],   // 9 bicycle
    [230, 30, 70],   // 10 pedestrian
    [255, 215, 0],   // 11 traffic_cone
    [170, 90, 50],   // 12 barrier
    [255, 0, 255],   // 13 czone_sign
    [0, 206, 209],   // 14 generic_object
    [255, 255, 255], // 15 divider
    [255, 250, 140], // 16 ped_crossing
    [0, 220, 90],    // 17 boundary
];
/// The extra `structure` mask.
pub const STRUCTURE_COLOUR: [u8; 3] = [40, 120, 40];
pub(super) const BACKGROUND: [u8; 3] = [18, 18, 22];
pub(super) const EGO_MARK: [u8; 3] = [255, 60, 60];
/// `None` = the structure mask.
pub(super) const PAINT_ORDER: [Option<usize>; N_MASKS + 1] = [
    Some(1),
    Some(7),
    Some(6),
    Some(5),
    Some(0),
    Some(3),
    Some(2),
    Some(4),
    Some(17),
    Some(15),
    Some(16),
    None,
    Some(8),
    Some(9),
    Some(10),
    Some(11),
    Some(12),
    Some(13),
    Some(14),
];

const SCALE: usize = 2;
const GLYPH_W: usize = 3;
const GLYPH_H: usize = 5;
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
pub fn write_preview_png(dir: &Path, bev: &Bev) -> io::Result<super::OutputFile> {
    let (w, h, data) = render_preview(bev);
    let bytes = super::write_atomic(&dir.join("preview").join("bev.png"), |out| {
        let mut enc = png::Encoder::new(&mut *out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut wr = enc.write_header().map_err(io::Error::other)?;
        wr.write_image_data(&data).map_err(io::Error::other)?;
        wr.finish().map_err(io::Error::other)
    })?;
    Ok(super::OutputFile { path: "preview/bev.png".to_string(), bytes })
}

pub(super) fn text(img: &mut [u8], w: usize, h: usize, x: usize, y: usize, s: &str, col: [u8; 3]) {
    for (n, ch) in s.chars().enumerate() {
        let g = glyph(ch);
        let gx = x + n * (GLYPH_W + 1) * SCALE;
        for r in 0..GLYPH_H {
            for c in 0..GLYPH_W {
                if g >> (14 - (r * GLYPH_W + c)) & 1 == 0 {
                    continue;
                }
                for dy in 0..SCALE {
                    for dx in 0..SCALE {
                        let (py, px) = (y + r * SCALE + dy, gx + c * SCALE + dx);
                        if py < h && px < w {
                            let k = (py * w + px) * 3;
                            img[k..k + 3].copy_from_slice(&col);
                        }
                    }
                }
            }
        }
    }
}

/// 3x5 glyph, rows top to bottom, 3 bits each, most significant first. Lower case draws as upper.
fn glyph(c: char) -> u16 {
    let rows: [u8; 5] = match c.to_ascii_uppercase() {
        'A' => [0b010, 0b101, 0b111, 0b101, 0b101],
        'B' => [0b110, 0b101, 0b110, 0b101, 0b110],
        'C' => [0b011, 0b100, 0b100, 0b100, 0b011],
        'D' => [0b110, 0b101, 0b101, 0b101, 0b110],
        'E' => [0b111, 0b100, 0b110, 0b100, 0b111],
        'F' => [0b111, 0b100, 0b110, 0b100, 0b100],
        'G' => [0b011, 0b100, 0b101, 0b101, 0b011],
        'H' => [0b101, 0b101, 0b111, 0b101, 0b101],
        'I' => [0b111, 0b010, 0b010, 0b010, 0b111],
        'J' => [0b001, 0b001, 0b001, 0b101, 0b010],
        'K' => [0b101, 0b101, 0b110, 0b101, 0b101],
        'L' => [0b100, 0b100, 0b100, 0b100, 0b111],
        'M' => [0b101, 0b111, 0b111, 0b101, 0b101],
        'N' => [0b110, 0b101, 0b101, 0b101, 0b101],
        'O' => [0b010, 0b101, 0b101, 0b101, 0b010],
        'P' => [0b110, 0b101, 0b110, 0b100, 0b100],
        'Q' => [0b010, 0b101, 0b101, 0b110, 0b011],
        'R' => [0b110, 0b101, 0b110, 0b101, 0b101],
        'S' => [0b011, 0b100, 0b010, 0b001, 0b110],
        'T' => [0b111, 0b010, 0b010, 0b010, 0b010],
        'U' => [0b101, 0b101, 0b101, 0b101, 0b111],
        'V' => [0b101, 0b101, 0b101, 0b101, 0b010],
        'W' => [0b101, 0b101, 0b111, 0b111, 0b101],
        'X' => [0b101, 0b101, 0b010, 0b101, 0b101],
        'Y' => [0b101, 0b101, 0b010, 0b010, 0b010],
        'Z' => [0b111, 0b001, 0b010, 0b100, 0b111],
        '0' => [0b111, 0b101, 0b101, 0b101, 0b111],
        '1' => [0b010, 0b110, 0b010, 0b010, 0b111],
        '2' => [0b110, 0b001, 0b010, 0b100, 0b111],
        '3' => [0b110, 0b001, 0b010, 0b001, 0b110],
        '4' => [0b101, 0b101, 0b111, 0b001, 0b001],
        '5' => [0b111, 0b100, 0b110, 0b001, 0b110],
        '6' => [0b011, 0b100, 0b111, 0b101, 0b111],
        '7' => [0b111, 0b001, 0b010, 0b010, 0b010],
        '8' => [0b111, 0b101, 0b111, 0b101, 0b111],
        '9' => [0b111, 0b101, 0b111, 0b001, 0b110],
        '_' => [0, 0, 0, 0, 0b111],
        '-' => [0, 0, 0b111, 0, 0],
        '.' => [0, 0, 0, 0, 0b010],
        ':' => [0, 0b010, 0, 0b010, 0],
        _ => [0; 5],
    };
    rows.iter().fold(0u16, |acc, &r| (acc << 3) | r as u16)
}
