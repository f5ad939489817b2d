//! Occupancy scorer. In: pairs of (prediction, ground truth) label grids, uint8 (400, 400, 32)
//! labels 0..=8. Out: `OccScores` — per-class IoU accumulated over the whole set, mIoU_US,
//! fg-mIoU and occ-IoU exactly as SPEC.md "Metrics" defines them.
//!
//! One accumulator (`OccScorer`) serves every caller: `rocc eval occ`, the edit protocol and the
//! tests. Counts are summed over all frames first and divided once at the end — a per-frame mean
//! would weight a frame with three pedestrian voxels like one with three thousand.

use crate::backend::Occupancy;
use crate::backend::layout::{LABEL_NAMES, N_LABELS, NX, NY, NZ};
use ndarray::{Array3, ArrayD, IxDyn};
use ndarray_npy::{NpzReader, ReadNpyExt, ReadableElement};
use serde::Serialize;
use std::fs::File;
use std::io;
use std::path::Path;

/// Running per-class counts over a set of frames.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct OccScorer {
    /// Per label: voxels labelled c in both, in ground truth, in prediction.
    pub tp: [u64; N_LABELS],
    pub gt: [u64; N_LABELS],
    pub pred: [u64; N_LABELS],
    /// Occupied (label != 0) counterparts, for occ-IoU.
    pub occ_tp: u64,
    pub occ_gt: u64,
    pub occ_pred: u64,
    pub frames: u64,
}

/// One class's result.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ClassScore {
    pub label: u8,
    pub name: &'static str,
    /// Percent.
    pub iou: f64,
    /// True when the class never occurs in the ground truth of the set: its IoU is then 100 by
    /// the UniScene convention, whatever the prediction holds.
    pub absent_from_gt: bool,
    pub tp: u64,
    pub gt: u64,
    pub pred: u64,
}

/// The scorer's result over a set (all IoUs in percent).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OccScores {
    pub frames: u64,
    pub classes: Vec<ClassScore>,
    /// Mean over labels 0..=7 (free included, generic_object excluded).
    pub miou_us: f64,
    /// Mean over labels 2..=8 (the seven agent classes).
    pub fg_miou: f64,
    /// IoU of (label != 0).
    pub occ_iou: f64,
}

impl OccScorer {
    pub fn new() -> Self {
        Self::default()
    }

    /// Add one frame. Both grids must have the same shape. Labels above 8 are clamped to 8 here;
    /// `read_occ` rejects them before they get this far.
    pub fn add(&mut self, pred: &Array3<u8>, gt: &Array3<u8>) {
        debug_assert_eq!(pred.dim(), gt.dim());
        for (&p, &g) in pred.iter().zip(gt.iter()) {
            let (p, g) = ((p as usize).min(N_LABELS - 1), (g as usize).min(N_LABELS - 1));
            self.gt[g] += 1;
            self.pred[p] += 1;
            if p == g {
                self.tp[p] += 1;
            }
            let (po, go) = (p != 0, g != 0);
            self.occ_gt += go as u64;
            self.occ_pred += po as u64;
            self.occ_tp += (po && go) as u64;
        }
        self.frames += 1;
    }

    /// Fold another accumulator in (sets scored in parts).
    pub fn merge(&mut self, o: &OccScorer) {
        for c in 0..N_LABELS {
            self.tp[c] += o.tp[c];
            self.gt[c] += o.gt[c];
            self.pred[c] += o.pred[c];
        }
        self.occ_tp += o.occ_tp;
        self.occ_gt += o.occ_gt;
        self.occ_pred += o.occ_pred;
        self.frames += o.frames;
    }

    pub fn scores(&self) -> OccScores {
        let classes: Vec<ClassScore> = (0..N_LABELS)
            .map(|c| {
                let absent = self.gt[c] == 0;
                ClassScore {
                    label: c as u8,
                    name: LABEL_NAMES[c],
                    iou: if absent { 100.0 } else { 100.0 * iou(self.tp[c], self.gt[c], self.pred[c]) },
                    absent_from_gt: absent,
                    tp: self.tp[c],
                    gt: self.gt[c],
                    pred: self.pred[c],
                }
            })
            .collect();
        let mean = |r: std::ops::RangeInclusive<usize>| {
            let n = r.clone().count() as f64;
            r.map(|c| classes[c].iou).sum::<f64>() / n
        };
        let occ_iou = if self.occ_gt == 0 { 100.0 } else { 100.0 * iou(self.occ_tp, self.occ_gt, self.occ_pred) };
        OccScores { frames: self.frames, miou_us: mean(0..=7), fg_miou: mean(2..=8), occ_iou, classes }
    }
}

fn iou(tp: u64, gt: u64, pred: u64) -> f64 {
    let union = gt + pred - tp;
    if union == 0 { 1.0 } else { tp as f64 / union as f64 }
}

impl OccScores {
    /// The terminal table.
    pub fn table(&self) -> String {
        let mut s = format!("{:<16} {:>8}  {:>12} {:>12} {:>12}\n", "class", "IoU %", "TP", "GT", "pred");
        for c in &self.classes {
            s += &format!(
                "{:<16} {:>8.2}{} {:>12} {:>12} {:>12}\n",
                format!("{} {}", c.label, c.name),
                c.iou,
                if c.absent_from_gt { "*" } else { " " },
                c.tp,
                c.gt,
                c.pred
            );
        }
        s += &format!(
            "\nmIoU_US (0-7) {:.2}   fg-mIoU (2-8) {:.2}   occ-IoU {:.2}   over {} frame(s)\n",
            self.miou_us, self.fg_miou, self.occ_iou, self.frames
        );
        if self.classes.iter().any(|c| c.absent_from_gt) {
            s += "* absent from the ground truth of the whole set: scored 100 (UniScene convention)\n";
        }
        s
    }
}

/// Read one occupancy frame: our `.npy` (uint8 (400, 400, 32)), nuPlan-Occ's dense `.npy` (any
/// integer dtype, same shape) or a sparse `.npz` holding an (N, 4) array of `[i, j, k, label]`
/// rows (voxels not listed are free; the first array in the archive is used, or the one named
/// `occ`, `semantics` or `arr_0` when present). Errors are messages for a diagnostic.
pub fn read_occ(path: &Path) -> Result<Array3<u8>, String> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let arr = match ext.as_str() {
        "npy" => {
            let f = File::open(path).map_err(|e| format!("cannot open: {e}"))?;
            read_npy_any(f)?
        }
        "npz" => read_npz_any(path)?,
        _ => return Err("not an occupancy file (expected .npy or .npz)".into()),
    };
    match arr.ndim() {
        3 => dense(arr),
        2 if arr.shape()[1] == 4 => sparse(arr),
        _ => Err(format!(
            "array of shape {:?} is neither a dense ({NX}, {NY}, {NZ}) grid nor sparse (N, 4) [i, j, k, label] rows",
            arr.shape()
        )),
    }
}

/// The grid as `Occupancy` (for backends and coverage).
pub fn read_occupancy(path: &Path) -> Result<Occupancy, String> {
    read_occ(path).map(|labels| Occupancy { labels })
}

fn dense(arr: ArrayD<i64>) -> Result<Array3<u8>, String> {
    if arr.shape() != [NX, NY, NZ] {
        return Err(format!("dense grid has shape {:?}, expected ({NX}, {NY}, {NZ})", arr.shape()));
    }
    let mut out = Array3::<u8>::zeros((NX, NY, NZ));
    for (o, &v) in out.iter_mut().zip(arr.iter()) {
        *o = label(v)?;
    }
    Ok(out)
}

fn sparse(arr: ArrayD<i64>) -> Result<Array3<u8>, String> {
    let rows = arr.into_dimensionality::<ndarray::Ix2>().map_err(|e| e.to_string())?;
    let mut out = Array3::<u8>::zeros((NX, NY, NZ));
    for (n, r) in rows.outer_iter().enumerate() {
        let (i, j, k) = (r[0], r[1], r[2]);
        if !(0..NX as i64).contains(&i) || !(0..NY as i64).contains(&j) || !(0..NZ as i64).contains(&k) {
            return Err(format!("sparse row {n}: voxel ({i}, {j}, {k}) is outside the ({NX}, {NY}, {NZ}) grid"));
        }
        out[[i as usize, j as usize, k as usize]] = label(r[3]).map_err(|e| format!("sparse row {n}: {e}"))?;
    }
    Ok(out)
}

fn label(v: i64) -> Result<u8, String> {
    if (0..N_LABELS as i64).contains(&v) {
        Ok(v as u8)
    } else {
        Err(format!("label {v} is outside 0..=8 (SPEC.md occupancy labels)"))
    }
}

/// Read a `.npy` of any integer (or integral float) dtype as i64.
fn read_npy_any<R: io::Read + io::Seek>(mut r: R) -> Result<ArrayD<i64>, String> {
    fn attempt<T: ReadableElement + Copy, R: io::Read + io::Seek>(
        r: &mut R,
        cast: fn(T) -> Option<i64>,
    ) -> Option<Result<ArrayD<i64>, String>> {
        r.seek(io::SeekFrom::Start(0)).ok()?;
        let a = ArrayD::<T>::read_npy(&mut *r).ok()?;
        Some(to_i64(a, cast))
    }
    macro_rules! try_types {
        ($($t:ty => $c:expr),*) => {{
            $(if let Some(x) = attempt::<$t, R>(&mut r, $c) { return x; })*
        }};
    }
    try_types!(
        u8 => |v| Some(v as i64), i8 => |v| Some(v as i64), u16 => |v| Some(v as i64),
        i16 => |v| Some(v as i64), u32 => |v| Some(v as i64), i32 => |v| Some(v as i64),
        i64 => Some, u64 => |v| i64::try_from(v).ok(), f32 => float_int, f64 => float_int
    );
    Err("not a readable .npy array (supported dtypes: integers, integral floats; C or Fortran order)".into())
}

fn float_int<F: Into<f64>>(v: F) -> Option<i64> {
    let v: f64 = v.into();
    (v.fract() == 0.0 && v.abs() < 1e15).then_some(v as i64)
}

fn to_i64<T: Copy>(a: ArrayD<T>, cast: fn(T) -> Option<i64>) -> Result<ArrayD<i64>, String> {
    let shape = a.shape().to_vec();
    let std = a.as_standard_layout();
    let mut v = Vec::with_capacity(std.len());
    for &x in std.iter() {
        v.push(cast(x).ok_or("a value is not an integer")?);
    }
    ArrayD::from_shape_vec(IxDyn(&shape), v).map_err(|e| e.to_string())
}

fn read_npz_any(path: &Path) -> Result<ArrayD<i64>, String> {
    let f = File::open(path).map_err(|e| format!("cannot open: {e}"))?;
    let mut npz = NpzReader::new(f).map_err(|e| format!("not a .npz archive: {e}"))?;
    let names = npz.names().map_err(|e| format!("cannot list the archive: {e}"))?;
    let pick = ["occ", "semantics", "arr_0"]
        .iter()
        .find_map(|w| names.iter().find(|n| n.trim_end_matches(".npy") == *w))
        .or(names.first())
        .cloned()
        .ok_or("the archive holds no array")?;
    npz_member(&mut npz, &pick)
}

fn npz_member(npz: &mut NpzReader<File>, name: &str) -> Result<ArrayD<i64>, String> {
    // ndarray-npy hands out typed arrays only: try each dtype a label array may have.
    macro_rules! try_types {
        ($($t:ty => $c:expr),*) => {{
            $(if let Ok(a) = npz.by_name::<ndarray::OwnedRepr<$t>, IxDyn>(name) { return to_i64(a, $c); })*
        }};
    }
    try_types!(
        u8 => |v| Some(v as i64), i8 => |v| Some(v as i64), u16 => |v| Some(v as i64),
        i16 => |v| Some(v as i64), u32 => |v| Some(v as i64), i32 => |v| Some(v as i64),
        i64 => Some, u64 => |v| i64::try_from(v).ok(), f32 => float_int, f64 => float_int
    );
    Err(format!("member `{name}` is not a numeric array"))
}

/// False for a readable `.npz` that holds no occupancy-shaped array (sparse (N, 4) rows or a
/// dense grid), such as a compiled clip's `bev/*.npz`: a recursive scan of a clip directory
/// must not read BEV maps as occupancy. An unreadable archive is kept, so its error is reported.
pub fn npz_may_hold_occupancy(path: &Path) -> bool {
    let Ok(f) = File::open(path) else { return true };
    let Ok(mut npz) = NpzReader::new(f) else { return true };
    let Ok(names) = npz.names() else { return true };
    // rocc's and UniScene's BEV archives, known by their keys without decompressing them.
    if names.iter().any(|n| matches!(n.trim_end_matches(".npy"), "gt_bev_masks" | "gt_aux_bev")) {
        return false;
    }
    names.iter().any(|n| match npz_member(&mut npz, n) {
        Ok(a) => (a.ndim() == 2 && a.shape()[1] == 4) || a.shape() == [NX, NY, NZ],
        Err(_) => false,
    })
}
