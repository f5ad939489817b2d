//! Raster pass (BEV). In: the world-frame `Map`, the ego `Pose` and the frame's `EgoBox`es. Out: a
//! `Bev` — `gt_bev_masks` int8 (18, 400, 400), `gt_aux_bev` int32 (7, 400, 400) and rocc's extra
//! `structure` int8 (400, 400) — exactly as SPEC.md "BEV (one frame)" lays them out.
//!
//! Axes are [channel, x, y]: index i <-> x = -50 + 0.25 i (forward), j <-> y = -50 + 0.25 j (left);
//! canvas u = 4 x + 200, v = 4 y + 200. Where a rule is not fixed by SPEC.md we follow the code
//! that produced nuPlan-Occ's BEVs, UniScene-v2 `nuplan_bev_dataset` (a copy of MagicDrive's
//! `LoadBEVSegmentationM`) and its `map_utils.visualize_bev_hdmap`:
//!
//! - Map polygons (ch 0-7) are cropped to the patch, mapped to canvas coordinates, rounded half to
//!   even (`np.round`) and filled one by one with cv2's `fillPoly` rules (`fill.rs`), as
//!   `mask_for_polygons` does; overlapping polygons therefore union, never cancel.
//! - Lines (ch 15 dividers, ch 16 crosswalk outlines) are cropped to the patch, their vertices
//!   *truncated* to pixels (`.astype(int)` in `visualize_bev_hdmap`), a radius-1 dot
//!   (`cv2.circle(.., 1, .., -1)`: a plus) at every vertex and a 1-px `cv2.line` between them.
//! - Ch 17 (boundary) is computed here, not drawn from a vector map: a pixel of
//!   (ch 7 U ch 0) with a 4-neighbour outside it. Pixels beyond the canvas count as inside, so the
//!   patch border never shows as a road edge (the reference crops its boundary lines there too).
//! - Agent footprints: the 4 bottom corners, rounded half to even, filled into the class channel
//!   (ch 8-14), or into `structure` for `Class::Structure`. The reference draws these with PIL's
//!   `ImageDraw.polygon`; we use the cv2 rules for every polygon, as SPEC.md asks (the two differ
//!   only on edge pixels of slanted sides).
//! - Aux (`_get_dynamic_aux_bbox`), over each footprint, in float32 then cast to int32 (the saver's
//!   `.astype(np.int32)`, i.e. truncation toward zero):
//!   - 0, 1: pixel index minus the box centre in canvas coordinates (u - u_c, v - v_c), with the
//!     centre unrounded, so a pixel just left of the centre gets -0.x -> 0;
//!   - 2: |front-face midpoint - centre| in px = 2 l (the source calls it "height");
//!   - 3: |side-face midpoint - centre| in px = 2 w;
//!   - 4, 5: the heading unit vector in canvas coordinates, (front - centre) /
//!     (|front - centre| + 1e-6), not scaled. Cast to float32 and truncated, it is 0 except for an
//!     exactly axis-aligned box with 2 l >= 34 px (l >= 17 m), where the component rounds to 1.0
//!     in float32 (checked with numpy). We reproduce that bit for bit: readers get what
//!     nuPlan-Occ's loaders get;
//!   - 6: box height in metres, truncated (a 1.6 m car stores 1).
//!
//!   Boxes are drawn in input order and each writes all 7 channels over its whole footprint, so
//!   where footprints overlap the later box wins (sequential assignment in the source). Structures
//!   get no aux: nuPlan's annotations hold no such boxes, and the aux channels describe the same
//!   boxes as ch 8-14.
//!
//! Cost: map geometry is transformed and clipped once per frame into reusable buffers; polygon
//! channels 0-7 are filled as bit planes of one row-major (v, u) byte canvas (cv2's scanlines are
//! rows of v), transposed once into [x, y]; lines and footprints write straight into the arrays.

mod clip;
pub mod fill;
pub mod layout;

use crate::check::scenario::Class;
use crate::place::Pose;
use crate::road::map::Map;
use crate::view::{EgoBox, EgoFrame};
use fill::{Filler, Px};
use glam::DVec2;
use layout::*;
use ndarray::{Array2, Array3};

/// One BEV frame in the nuPlan-Occ layout (see the module comment).
///
/// `Rasterizer::rasterize_into` clears only what its last call painted into this `Bev`: code
/// that writes the agent channels (8-14), `aux` or `structure` of a `Bev` it then hands back to
/// the rasterizer must build it with `Bev::from_arrays` (which forgets what was painted).
#[derive(Clone, Debug)]
pub struct Bev {
    /// `gt_bev_masks`: (18, 400, 400), values {0, 1}.
    pub masks: Array3<i8>,
    /// `gt_aux_bev`: (7, 400, 400).
    pub aux: Array3<i32>,
    /// rocc's extra channel: footprints of `Class::Structure` (trees, poles, walls, buildings).
    pub structure: Array2<i8>,
    /// Canvas rectangles the last `rasterize_into` painted agents into; `None`: unknown, so the
    /// next one clears everything.
    painted: Option<Vec<Rect>>,
}

/// Index ranges [i0, i1) x [j0, j1) of one footprint's bounding box, inside the grid.
type Rect = (usize, usize, usize, usize);

impl PartialEq for Bev {
    fn eq(&self, o: &Bev) -> bool {
        self.masks == o.masks && self.aux == o.aux && self.structure == o.structure
    }
}

impl Default for Bev {
    fn default() -> Self {
        Self::zeros()
    }
}

impl Bev {
    pub fn zeros() -> Self {
        Bev {
            masks: Array3::zeros((N_MASKS, GRID, GRID)),
            aux: Array3::zeros((N_AUX, GRID, GRID)),
            structure: Array2::zeros((GRID, GRID)),
            painted: Some(Vec::new()),
        }
    }

    /// A `Bev` of given arrays (read from a file, say).
    pub fn from_arrays(masks: Array3<i8>, aux: Array3<i32>, structure: Array2<i8>) -> Self {
        Bev { masks, aux, structure, painted: None }
    }

    fn reset(&mut self) {
        let fresh = self.masks.dim() != (N_MASKS, GRID, GRID)
            || self.aux.dim() != (N_AUX, GRID, GRID)
            || self.structure.dim() != (GRID, GRID)
            || !self.masks.is_standard_layout()
            || !self.aux.is_standard_layout()
            || !self.structure.is_standard_layout();
        if fresh {
            *self = Bev::zeros();
            return;
        }
        let (Some(masks), Some(aux), Some(structure)) =
            (self.masks.as_slice_mut(), self.aux.as_slice_mut(), self.structure.as_slice_mut())
        else {
            return;
        };
        // Channels 0-7 are overwritten whole by `polygons`; the line and boundary channels are
        // cleared whole (they are small); agents, aux and structure only where boxes were drawn.
        masks[CH_DIVIDER * N..].fill(0);
        let Some(rects) = self.painted.take() else {
            masks[8 * N..CH_DIVIDER * N].fill(0);
            aux.fill(0);
            structure.fill(0);
            self.painted = Some(Vec::new());
            return;
        };
        for &(i0, i1, j0, j1) in &rects {
            for i in i0..i1 {
                let row = i * GRID;
                for ch in 8..CH_DIVIDER {
                    masks[ch * N + row + j0..ch * N + row + j1].fill(0);
                }
                for ch in 0..N_AUX {
                    aux[ch * N + row + j0..ch * N + row + j1].fill(0);
                }
                structure[row + j0..row + j1].fill(0);
            }
        }
        let mut rects = rects;
        rects.clear();
        self.painted = Some(rects);
    }
}

/// Rasterise one frame. For many frames, keep a `Rasterizer` and a `Bev` and call
/// `Rasterizer::rasterize_into`, which reuses every buffer.
pub fn rasterize(map: &Map, ego: Pose, boxes: &[EgoBox]) -> Bev {
    let mut bev = Bev::zeros();
    Rasterizer::new().rasterize_into(map, ego, boxes, &mut bev);
    bev
}

/// The `gt_bev_masks` channels that come from the map, not from boxes: static layers 0-7 and the
/// divider layers 15-17. Box edits and `--static-bev` swap exactly these (paper, App. E).
pub const STATIC_CHANNELS: [usize; 11] = [0, 1, 2, 3, 4, 5, 6, 7, CH_DIVIDER, CH_PED_CROSSING, CH_BOUNDARY];

/// Copy the static and divider layers of `from` into `into`, leaving agents, aux and structure.
pub fn keep_static(from: &Bev, into: &mut Bev) {
    for ch in STATIC_CHANNELS {
        if ch < from.masks.dim().0 && ch < into.masks.dim().0 && from.masks.dim() == into.masks.dim() {
            into.masks.index_axis_mut(ndarray::Axis(0), ch).assign(&from.masks.index_axis(ndarray::Axis(0), ch));
        }
    }
}

const G: i64 = GRID as i64;
const N: usize = GRID * GRID;

/// Reusable scratch for rasterising frame after frame without allocating.
#[derive(Debug)]
pub struct Rasterizer {
    /// Row-major (v, u) canvas; bit c = polygon channel c (0..=7).
    planes: Vec<u8>,
    /// `planes` transposed to (u, v) = (i, j).
    planes_t: Vec<u8>,
    filler: Filler,
    ego_pts: Vec<DVec2>,
    clipped: Vec<DVec2>,
    tmp: Vec<DVec2>,
    px: Vec<Px>,
}

impl Default for Rasterizer {
    fn default() -> Self {
        Self::new()
    }
}

impl Rasterizer {
    pub fn new() -> Self {
        Rasterizer {
            planes: vec![0; N],
            planes_t: vec![0; N],
            filler: Filler::default(),
            ego_pts: Vec::new(),
            clipped: Vec::new(),
            tmp: Vec::new(),
            px: Vec::new(),
        }
    }

    /// Rasterise one frame into `out` (cleared first).
    pub fn rasterize_into(&mut self, map: &Map, ego: Pose, boxes: &[EgoBox], out: &mut Bev) {
        out.reset();
        let frame = EgoFrame::new(ego);
        self.polygons(map, &frame, out);
        self.lines(map, &frame, out);
        self.agents(boxes, out);
    }

    fn polygons(&mut self, map: &Map, frame: &EgoFrame, out: &mut Bev) {
        self.planes.fill(0);
        let layers: [(usize, &[Vec<DVec2>]); 8] = [
            (CH_INTERSECTIONS, &map.intersections),
            (CH_DRIVABLE, &map.drivable),
            (CH_WALKWAYS, &map.walkways),
            (CH_CARPARKS, &map.carparks),
            (CH_CROSSWALKS, &map.crosswalk_polygons),
            (CH_LANE_GROUP_CONNECTORS, &map.lane_group_connectors),
            (CH_LANE_GROUPS, &map.lane_groups),
            (CH_ROAD_SEGMENTS, &map.road_segments),
        ];
        for (ch, polys) in layers {
            let bit = 1u8 << ch;
            for poly in polys {
                if !poly.iter().all(|p| p.is_finite()) {
                    continue;
                }
                self.ego_pts.clear();
                self.ego_pts.extend(poly.iter().map(|&p| frame.point(p)));
                clip::polygon(&self.ego_pts, HALF_EXTENT_M, &mut self.clipped, &mut self.tmp);
                if self.clipped.len() < 3 {
                    continue;
                }
                self.px.clear();
                self.px.extend(
                    self.clipped
                        .iter()
                        .map(|p| (to_canvas(p.x).round_ties_even() as i64, to_canvas(p.y).round_ties_even() as i64)),
                );
                let planes = &mut self.planes;
                self.filler.fill_poly(G, G, &self.px, &mut |v, u0, u1| {
                    let row = v as usize * GRID;
                    for b in &mut planes[row + u0 as usize..=row + u1 as usize] {
                        *b |= bit;
                    }
                });
            }
        }
        transpose(&self.planes, &mut self.planes_t);

        let masks = out.masks.as_slice_mut().expect("reset() leaves Bev arrays in standard layout");
        for ch in 0..8 {
            let dst = &mut masks[ch * N..(ch + 1) * N];
            for (d, &b) in dst.iter_mut().zip(&self.planes_t) {
                *d = ((b >> ch) & 1) as i8;
            }
        }
        // Boundary: union of road segments and intersections, reused in `planes`.
        let road = (1u8 << CH_ROAD_SEGMENTS) | (1u8 << CH_INTERSECTIONS);
        for (u, &b) in self.planes.iter_mut().zip(&self.planes_t) {
            *u = ((b & road) != 0) as u8;
        }
        let un = &self.planes;
        let dst = &mut masks[CH_BOUNDARY * N..(CH_BOUNDARY + 1) * N];
        for i in 0..GRID {
            for j in 0..GRID {
                let k = i * GRID + j;
                if un[k] == 0 {
                    continue;
                }
                let edge = (i > 0 && un[k - GRID] == 0)
                    || (i + 1 < GRID && un[k + GRID] == 0)
                    || (j > 0 && un[k - 1] == 0)
                    || (j + 1 < GRID && un[k + 1] == 0);
                dst[k] = edge as i8;
            }
        }
    }

    fn lines(&mut self, map: &Map, frame: &EgoFrame, out: &mut Bev) {
        let masks = out.masks.as_slice_mut().expect("reset() leaves Bev arrays in standard layout");
        let (div, ped) = masks.split_at_mut(CH_PED_CROSSING * N);
        let div = &mut div[CH_DIVIDER * N..];
        let ped = &mut ped[..N];
        for line in &map.dividers {
            self.ego_pts.clear();
            self.ego_pts.extend(line.iter().map(|&p| frame.point(p)));
            draw_polyline(&self.ego_pts, &mut self.clipped, div);
        }
        for poly in &map.crosswalk_polygons {
            let Some(&first) = poly.first() else { continue };
            self.ego_pts.clear();
            self.ego_pts.extend(poly.iter().chain([&first]).map(|&p| frame.point(p)));
            draw_polyline(&self.ego_pts, &mut self.clipped, ped);
        }
    }

    fn agents(&mut self, boxes: &[EgoBox], out: &mut Bev) {
        let masks = out.masks.as_slice_mut().expect("reset() leaves Bev arrays in standard layout");
        let aux = out.aux.as_slice_mut().expect("reset() leaves Bev arrays in standard layout");
        let structure = out.structure.as_slice_mut().expect("reset() leaves Bev arrays in standard layout");
        for b in boxes {
            // A non-finite pose would cast to pixel 0 and paint a phantom corner box.
            if ![b.x, b.y, b.yaw, b.l, b.w, b.h].iter().all(|v| v.is_finite()) {
                continue;
            }
            let obb = crate::geom::Obb { center: DVec2::new(b.x, b.y), yaw: b.yaw, length: b.l, width: b.w };
            let corners = obb.corners();
            self.px.clear();
            self.px.extend(corners.iter().map(|p| {
                // Saturating casts keep absurd poses far off the canvas instead of overflowing.
                let c = |m: f64| (to_canvas(m).round_ties_even().clamp(-1e9, 1e9)) as i64;
                (c(p.x), c(p.y))
            }));
            let (lo, hi) = self.px.iter().fold(((i64::MAX, i64::MAX), (i64::MIN, i64::MIN)), |(lo, hi), p| {
                ((lo.0.min(p.0), lo.1.min(p.1)), (hi.0.max(p.0), hi.1.max(p.1)))
            });
            if hi.0 < 0 || hi.1 < 0 || lo.0 >= G || lo.1 >= G {
                continue;
            }
            let span = |a: i64, b: i64| (a.max(0) as usize, (b + 1).min(G) as usize);
            let ((i0, i1), (j0, j1)) = (span(lo.0, hi.0), span(lo.1, hi.1));
            out.painted.get_or_insert_with(Vec::new).push((i0, i1, j0, j1));
            let Some(ch) = layout::class_channel(b.class) else {
                debug_assert_eq!(b.class, Class::Structure);
                self.filler.fill_poly(G, G, &self.px, &mut |v, u0, u1| {
                    for u in u0..=u1 {
                        structure[u as usize * GRID + v as usize] = 1;
                    }
                });
                continue;
            };
            let a = Aux::of(b);
            let plane = &mut masks[ch * N..(ch + 1) * N];
            self.filler.fill_poly(G, G, &self.px, &mut |v, u0, u1| {
                for u in u0..=u1 {
                    let k = u as usize * GRID + v as usize;
                    plane[k] = 1;
                    aux[AUX_OFFSET_X * N + k] = (u as f64 - a.uc) as f32 as i32;
                    aux[AUX_OFFSET_Y * N + k] = (v as f64 - a.vc) as f32 as i32;
                    aux[AUX_HALF_LENGTH * N + k] = a.half_l;
                    aux[AUX_HALF_WIDTH * N + k] = a.half_w;
                    aux[AUX_HEADING_X * N + k] = a.head.0;
                    aux[AUX_HEADING_Y * N + k] = a.head.1;
                    aux[AUX_HEIGHT * N + k] = a.height;
                }
            });
        }
    }
}

/// The per-box aux values, computed the way `_get_dynamic_aux_bbox` does (float64 geometry,
/// stored as float32, saved as int32).
struct Aux {
    uc: f64,
    vc: f64,
    half_l: i32,
    half_w: i32,
    head: (i32, i32),
    height: i32,
}

impl Aux {
    fn of(b: &EgoBox) -> Aux {
        let c = DVec2::new(to_canvas(b.x), to_canvas(b.y));
        let (s, co) = b.yaw.sin_cos();
        let front = DVec2::new(to_canvas(b.x + co * b.l / 2.0), to_canvas(b.y + s * b.l / 2.0));
        let side = DVec2::new(to_canvas(b.x - s * b.w / 2.0), to_canvas(b.y + co * b.w / 2.0));
        let f = front - c;
        let v = f / (f.length() + 1e-6);
        let t = |x: f64| x as f32 as i32;
        Aux {
            uc: c.x,
            vc: c.y,
            half_l: t(f.length()),
            half_w: t((side - c).length()),
            head: (t(v.x), t(v.y)),
            height: t(b.h),
        }
    }
}

/// Crop an ego-frame polyline to the patch and draw it into one (x, y) plane: truncated vertices,
/// a dot at each, 1-px lines between.
fn draw_polyline(pts: &[DVec2], buf: &mut Vec<DVec2>, plane: &mut [i8]) {
    if !pts.iter().all(|p| p.is_finite()) {
        return;
    }
    let mut set = |v: i64, u0: i64, u1: i64| {
        for u in u0..=u1 {
            plane[u as usize * GRID + v as usize] = 1;
        }
    };
    clip::polyline(pts, HALF_EXTENT_M, buf, |piece| {
        // `as i64` truncates toward zero like numpy's `.astype(int)`.
        let px = |p: DVec2| (to_canvas(p.x) as i64, to_canvas(p.y) as i64);
        for &p in piece {
            fill::dot(G, G, px(p), &mut set);
        }
        for s in piece.windows(2) {
            fill::line(G, G, px(s[0]), px(s[1]), &mut set);
        }
    });
}

/// Square transpose of a GRID x GRID byte image, in cache-sized tiles.
fn transpose(src: &[u8], dst: &mut [u8]) {
    const T: usize = 16;
    for bi in (0..GRID).step_by(T) {
        for bj in (0..GRID).step_by(T) {
            for i in bi..(bi + T).min(GRID) {
                for j in bj..(bj + T).min(GRID) {
                    dst[j * GRID + i] = src[i * GRID + j];
                }
            }
        }
    }
}
