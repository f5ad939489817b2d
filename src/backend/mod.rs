//! Occupancy pass. In: one frame's ego-frame boxes (`view::EgoBox`), its BEV (`raster::Bev`), the
//! scenario's world-fixed `Background`, the ego `Pose`, the seed and the frame index (`OccInput`).
//! Out: an `Occupancy`, uint8 (400, 400, 32) labels 0..=8 in the nuPlan-Occ layout of SPEC.md
//! "Occupancy (one frame)" (constants in `layout`), and its `.npy` file.
//!
//! Backends implement `OccupancyBackend`. `Procedural`, the default, needs no weights; the
//! learned (semantic-Gaussian) backend will implement the same trait from the same input.
//!
//! # Road surface and ground
//!
//! The ground is a labelled surface: the layer just below z = 0 (k = 11, z in [-0.25, 0)) is
//! `background` (1) in every column, road or not. Why: nuPlan-Occ is built from accumulated LiDAR
//! sweeps in which every static point, ground returns included, is labelled background, and
//! UniScene-v2's own `add_bev_layout.py` finds the road surface by looking for label 1 inside the
//! BEV's drivable columns (it relabels those voxels "road" in its 12+ class variant) — which only
//! works because the ground is there as background. The LiDAR ray caster needs no special case
//! either: ground returns are ordinary hits on the top face of k = 11 (z = 0), labelled
//! background, so "every point lies in or on a non-free voxel" holds for them too. Agents and
//! structures stand on it, from layer 12 up.
//!
//! # Agents and structures
//!
//! Each box becomes a class-specific solid (`shape`: vehicle body and cabin, pedestrian column,
//! bicycle frame, cone, barrier, sign, tree, ...), voxelised by voxel centre (`voxel`). In
//! `Mode::Surface` (default) only the shell is kept, as LiDAR-derived ground truth has it; in
//! `Mode::Solid` the whole solid. Structure-class boxes (the scenario's trees, poles, walls,
//! buildings) are drawn like agents with label background; the procedural `Background` is drawn
//! first and never where the BEV marks drivable area, walkway, crosswalk, junction or car park,
//! so the map layout has the last word on what is road. Agents are drawn last, over everything.
//!
//! Cost: one 5 MB clear per frame, then per object one evaluation per ground column per
//! primitive; no allocation per voxel or per object (`voxel::Voxelizer` keeps its scratch).

pub mod background;
pub mod flow;
pub mod grounded;
pub mod layout;
pub mod shape;
pub mod voxel;

pub use background::{Background, BgItem, BgKind, BgParams};
pub use voxel::Mode;

use crate::check::scenario::Class;
use crate::diag::Diagnostic;
use crate::place::Pose;
use crate::raster::Bev;
use crate::raster::layout::{CH_CARPARKS, CH_CROSSWALKS, CH_DRIVABLE, CH_INTERSECTIONS, CH_WALKWAYS};
use crate::view::EgoBox;
use layout::*;
use ndarray::Array3;
use shape::{Prim, ShapeKind, prims, shape_kind};
use std::cell::RefCell;
use std::io;
use std::path::{Path, PathBuf};
use voxel::{Obj, Voxelizer};

/// Everything a backend may read for one frame.
#[derive(Clone, Copy)]
pub struct OccInput<'a> {
    /// Every box of the frame in the ego frame, structures included.
    pub boxes: &'a [EgoBox],
    pub bev: &'a Bev,
    pub background: &'a Background,
    /// World pose of the ego at this frame (places the world-fixed background).
    pub ego: Pose,
    pub seed: u64,
    pub frame: usize,
}

/// One frame of semantic occupancy: labels (400, 400, 32), axes [x, y, z], standard layout.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Occupancy {
    pub labels: Array3<u8>,
}

impl Default for Occupancy {
    fn default() -> Self {
        Self::empty()
    }
}

impl Occupancy {
    /// All free.
    pub fn empty() -> Self {
        Occupancy { labels: Array3::zeros((NX, NY, NZ)) }
    }

    /// The labels as one slice, index `layout::flat(i, j, k)`; re-laid out if a caller replaced
    /// the array with a non-standard one.
    pub fn as_slice_mut(&mut self) -> &mut [u8] {
        if self.labels.dim() != (NX, NY, NZ) || !self.labels.is_standard_layout() {
            let fresh = if self.labels.dim() == (NX, NY, NZ) {
                self.labels.as_standard_layout().into_owned()
            } else {
                Array3::zeros((NX, NY, NZ))
            };
            self.labels = fresh;
        }
        self.labels.as_slice_mut().expect("standard layout was just ensured")
    }

    /// Label at an ego-frame point, `None` outside the grid.
    pub fn at(&self, p: [f64; 3]) -> Option<u8> {
        voxel_of(p).map(|[i, j, k]| self.labels[[i, j, k]])
    }

    /// Voxels per label.
    pub fn counts(&self) -> [u64; N_LABELS] {
        let mut c = [0u64; N_LABELS];
        for &v in self.labels.iter() {
            c[(v as usize).min(N_LABELS - 1)] += 1;
        }
        c
    }
}

/// A BEV + boxes -> occupancy generator. Implementations must be deterministic in their input.
pub trait OccupancyBackend: Send + Sync {
    /// Short name recorded in the manifest.
    fn name(&self) -> &str;

    fn occupancy(&self, input: &OccInput) -> Occupancy;

    /// Fill `out`, reusing its buffer where the backend can.
    fn occupancy_into(&self, input: &OccInput, out: &mut Occupancy) {
        *out = self.occupancy(input);
    }

    /// Frames this backend wants per `occupancy_batch` call; `None` (the default): one frame at
    /// a time, inside each frame's own work.
    fn batch(&self) -> Option<usize> {
        None
    }

    /// The occupancy of several frames at once; a failure (a GPU's) is a diagnostic.
    fn occupancy_batch(&self, inputs: &[OccInput], out: &mut [Occupancy]) -> Result<(), Diagnostic> {
        for (input, o) in inputs.iter().zip(out) {
            self.occupancy_into(input, o);
        }
        Ok(())
    }
}

/// A backend's diagnostic carried through the `io::Error` of the compile pipeline, so the
/// failed clip reports it instead of a write error.
#[derive(Debug)]
pub struct BackendFailure(pub Diagnostic);

impl std::fmt::Display for BackendFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for BackendFailure {}

/// The weight-free default backend (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Procedural {
    pub mode: Mode,
    /// Draw the ground layer (k = 11) as background.
    pub ground: bool,
}

impl Default for Procedural {
    fn default() -> Self {
        Procedural { mode: Mode::Surface, ground: true }
    }
}

thread_local! {
    static SCRATCH: RefCell<(Voxelizer, Vec<Prim>, Vec<bool>)> = RefCell::new(Default::default());
}

impl Procedural {
    pub fn new(mode: Mode) -> Self {
        Procedural { mode, ..Self::default() }
    }
}

impl OccupancyBackend for Procedural {
    fn name(&self) -> &str {
        match self.mode {
            Mode::Surface => "procedural-surface",
            Mode::Solid => "procedural-solid",
        }
    }

    fn occupancy(&self, input: &OccInput) -> Occupancy {
        let mut o = Occupancy::empty();
        self.occupancy_into(input, &mut o);
        o
    }

    fn occupancy_into(&self, input: &OccInput, out: &mut Occupancy) {
        let labels = out.as_slice_mut();
        labels.fill(FREE);
        if self.ground {
            for c in labels.chunks_exact_mut(NZ) {
                c[K_GROUND] = BACKGROUND;
            }
        }
        SCRATCH.with(|s| {
            let mut s = s.borrow_mut();
            let (vox, buf, keepout) = &mut *s;
            road_mask(input.bev, keepout);
            for (it, x, y, yaw) in input.background.in_view(input.ego) {
                buf.clear();
                prims(shape_kind(Class::Structure, it.kind.kind_name(), it.l, it.h), it.l, it.w, it.h, buf);
                let obj = Obj { prims: buf, x, y, yaw, z_bottom: 0.0, label: BACKGROUND };
                vox.draw(labels, &obj, self.mode, Some(keepout));
            }
            // Structures before agents, so a car that hit a tree shows as the car.
            let order = input
                .boxes
                .iter()
                .filter(|b| b.class == Class::Structure)
                .chain(input.boxes.iter().filter(|b| b.class != Class::Structure));
            for b in order {
                if !(b.l > 0.0 && b.w > 0.0 && b.h > 0.0) {
                    continue;
                }
                buf.clear();
                prims(box_shape(b), b.l, b.w, b.h, buf);
                let obj = Obj {
                    prims: buf,
                    x: b.x,
                    y: b.y,
                    yaw: b.yaw,
                    z_bottom: b.z - b.h / 2.0,
                    label: class_label(b.class),
                };
                vox.draw(labels, &obj, self.mode, None);
            }
        });
    }
}

/// The shape a box gets (class, kind name and size).
pub fn box_shape(b: &EgoBox) -> ShapeKind {
    shape_kind(b.class, &b.kind, b.l, b.h)
}

/// Columns the BEV marks as road or walkway, where procedural background must not stand.
fn road_mask(bev: &Bev, out: &mut Vec<bool>) {
    out.clear();
    out.resize(NX * NY, false);
    if bev.masks.dim().1 != NX || bev.masks.dim().2 != NY {
        return;
    }
    for ch in [CH_DRIVABLE, CH_WALKWAYS, CH_CROSSWALKS, CH_INTERSECTIONS, CH_CARPARKS] {
        if ch >= bev.masks.dim().0 {
            continue;
        }
        for ((i, j), &v) in bev.masks.index_axis(ndarray::Axis(0), ch).indexed_iter() {
            if v != 0 {
                out[i * NY + j] = true;
            }
        }
    }
}

/// Box coverage (SPEC.md "Metrics"): the fraction of the box's ground-plane columns that hold
/// `label` within the box's vertical extent. Columns are those whose centre lies inside the
/// footprint (the BEV's rule), or the column holding the box centre when none does; the vertical
/// extent is every layer the box overlaps. `None` when no such column is inside the grid.
pub fn box_coverage(occ: &Occupancy, b: &EgoBox, label: u8) -> Option<f64> {
    let (c, s) = (b.yaw.cos(), b.yaw.sin());
    let (hl, hw) = (b.l / 2.0, b.w / 2.0);
    let r = hl.hypot(hw);
    let idx = |m: f64, a: usize| ((m - ORIGIN[a]) / VOXEL).floor();
    let z0 = b.z - b.h / 2.0;
    let k0 = idx(z0, 2).max(0.0);
    let k1 = (((z0 + b.h - ORIGIN[2]) / VOXEL).ceil() - 1.0).min((NZ - 1) as f64);
    if k0.partial_cmp(&k1).is_none_or(|o| o == std::cmp::Ordering::Greater) {
        return None;
    }
    let (k0, k1) = (k0 as usize, k1 as usize);
    let mut cols = Vec::new();
    let (i0, i1) = (idx(b.x - r, 0).max(0.0), idx(b.x + r, 0).min((NX - 1) as f64));
    let (j0, j1) = (idx(b.y - r, 1).max(0.0), idx(b.y + r, 1).min((NY - 1) as f64));
    if i0 <= i1 && j0 <= j1 {
        for i in i0 as usize..=i1 as usize {
            for j in j0 as usize..=j1 as usize {
                let (dx, dy) = (centre(0, i) - b.x, centre(1, j) - b.y);
                let (u, v) = (dx * c + dy * s, -dx * s + dy * c);
                if u.abs() <= hl && v.abs() <= hw {
                    cols.push((i, j));
                }
            }
        }
    }
    if cols.is_empty() {
        let [i, j, _] = voxel_of([b.x, b.y, 0.0])?;
        cols.push((i, j));
    }
    let hit = cols.iter().filter(|&&(i, j)| (k0..=k1).any(|k| occ.labels[[i, j, k]] == label)).count();
    Some(hit as f64 / cols.len() as f64)
}

/// `dir/occ/NNNNNN.npy` for frame `frame` (SPEC output layout).
pub fn occ_frame_path(dir: &Path, frame: usize) -> PathBuf {
    dir.join("occ").join(format!("{frame:06}.npy"))
}

/// Read an occupancy `.npy` back (any uint8 (400, 400, 32) array, e.g. nuPlan-Occ's dense form).
pub fn read_npy(path: &Path) -> io::Result<Occupancy> {
    use ndarray_npy::ReadNpyExt;
    let f = std::fs::File::open(path)?;
    let labels = Array3::<u8>::read_npy(f).map_err(|e| io::Error::other(format!("npy: {e}")))?;
    if labels.dim() != (NX, NY, NZ) {
        return Err(io::Error::new(io::ErrorKind::InvalidData, format!("occupancy shape {:?}", labels.dim())));
    }
    Ok(Occupancy { labels })
}
