//! What every preview image is drawn with. In: a `Bev`, an `Occupancy` or a `PointCloud`. Out:
//! 400 x 400 images of indices into one fixed 256-colour palette (`palette`), forward up, the
//! ego's left on the image's left, 1 px = 0.25 m; and a built-in 3x5 bitmap font drawn at 2x.
//!
//! Colours are fixed (`CHANNEL_COLOURS`) so previews of different runs compare by eye. BEV layers
//! are painted surfaces first, markings next, agents last (`PAINT_ORDER`), so a later channel
//! hides an earlier one where both are set. Images are drawn straight into palette indices: GIF
//! needs a palette anyway, quantising RGB would cost more than drawing, and a fixed palette keeps
//! colours identical across runs and stages.

use crate::backend::Occupancy;
use crate::backend::layout::{FREE, K_GROUND, N_LABELS, NX, NY, NZ, ORIGIN, VOXEL};
use crate::lidar::PointCloud;
use crate::raster::Bev;
use crate::raster::layout::{GRID, N_MASKS};
use std::sync::OnceLock;

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
const PAINT_ORDER: [Option<usize>; N_MASKS + 1] = [
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

/// Side of every preview image (px).
pub const SIDE: usize = GRID;

pub(super) const I_BACKGROUND: u8 = 0;
const I_EGO: u8 = 1;
pub(super) const I_TEXT: u8 = 2;
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

/// Pixels painted through all layers at a time by `paint_bev`.
const STRIP: usize = 4096;

/// The BEV as palette indices, `SIDE * SIDE`, layers in `PAINT_ORDER`.
pub fn paint_bev(bev: &Bev, img: &mut [u8]) {
    // `px` maps cell (i, j) to SIDE * SIDE - 1 - (i SIDE + j): the image is the grid in reverse.
    // Painting in grid order lets each layer be one branch-free pass over two slices.
    img.fill(I_BACKGROUND);
    let planes = PAINT_ORDER.map(|layer| match layer {
        Some(ch) => (bev.masks.index_axis(ndarray::Axis(0), ch), I_BEV + ch as u8),
        None => (bev.structure.view(), I_STRUCTURE),
    });
    let cells: Option<Vec<(&[i8], u8)>> = planes.iter().map(|(p, col)| Some((p.as_slice()?, *col))).collect();
    match cells {
        // A strip of the image at a time through every layer, so the strip stays in cache.
        Some(cells) => {
            for (n, strip) in img[..SIDE * SIDE].chunks_mut(STRIP).enumerate() {
                for &(plane, col) in &cells {
                    for (d, &m) in strip.iter_mut().zip(&plane[n * STRIP..]) {
                        *d = if m != 0 { col } else { *d };
                    }
                }
            }
        }
        None => {
            for (plane, col) in &planes {
                for ((i, j), &m) in plane.indexed_iter() {
                    if m != 0 {
                        img[i * SIDE + j] = *col;
                    }
                }
            }
        }
    }
    img[..SIDE * SIDE].reverse();
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

/// The font: 3x5 glyphs drawn at 2x.
const SCALE: usize = 2;
const GLYPH_W: usize = 3;
const GLYPH_H: usize = 5;

/// Draw `s` into the RGB image `img` (`w` x `h`) with its top left at (`x`, `y`); what falls
/// outside is clipped.
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
