//! LiDAR set metrics. In: two sets of point clouds (x, y, z per point). Out: MMD and JSD in the
//! LiDARGen / LidarDM convention that UniScene-v2 evaluates with (SPEC.md "Metrics"):
//!
//! 1. each cloud is voxelised over [-51.2, 51.2]^2 x [-5, 3] m at (0.15625, 0.15625, 0.2) m into a
//!    binary 656 x 656 x 40 grid (a voxel is 1 if any point falls in it; index = floor((p - lo) /
//!    step), points outside dropped);
//! 2. the grid is collapsed to a 656 x 656 bird's-eye map by summing the binary voxels of each
//!    column (occupied voxels per column), then average-pooled to 100 x 100 with PyTorch's
//!    `adaptive_avg_pool2d` bins (656 is not a multiple of 100: bin a spans
//!    [floor(656 a / 100), ceil(656 (a + 1) / 100)));
//! 3. JSD: the maps of each set are summed, each sum normalised to 1, and the Jensen-Shannon
//!    *distance* taken as scipy's `jensenshannon` does (square root of the divergence, natural
//!    log);
//! 4. MMD: each map normalised to sum 1, then the biased estimate of MMD^2 with a Gaussian kernel
//!    k(a, b) = exp(-|a - b|^2 / (2 sigma^2)), sigma = 0.5.
//!
//! Optionally only points with 3 < |p| < 50 m (Euclidean range from the sensor origin, as
//! LiDARGen's range images measure it) are kept. This is not LiDM's "minimum matching distance".

use std::path::Path;

pub const LO: [f64; 3] = [-51.2, -51.2, -5.0];
pub const STEP: [f64; 3] = [0.15625, 0.15625, 0.2];
pub const DIMS: [usize; 3] = [656, 656, 40];
pub const POOL: usize = 100;
pub const SIGMA: f64 = 0.5;
/// The optional range filter (m).
pub const RANGE: (f64, f64) = (3.0, 50.0);

/// One cloud's pooled 100 x 100 map, row-major [x bin][y bin].
pub fn bev_map(points: &[[f32; 3]], range_filter: bool) -> Vec<f64> {
    // 40 z bins fit one u64 per column.
    let mut cols = vec![0u64; DIMS[0] * DIMS[1]];
    for p in points {
        let (x, y, z) = (p[0] as f64, p[1] as f64, p[2] as f64);
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            continue;
        }
        if range_filter {
            let r = (x * x + y * y + z * z).sqrt();
            if !(r > RANGE.0 && r < RANGE.1) {
                continue;
            }
        }
        let idx = |v: f64, a: usize| {
            let i = ((v - LO[a]) / STEP[a]).floor();
            (i >= 0.0 && i < DIMS[a] as f64).then_some(i as usize)
        };
        if let (Some(i), Some(j), Some(k)) = (idx(x, 0), idx(y, 1), idx(z, 2)) {
            cols[i * DIMS[1] + j] |= 1 << k;
        }
    }
    let bins = |a: usize, n: usize| ((a * n) / POOL, ((a + 1) * n).div_ceil(POOL));
    let mut out = vec![0.0; POOL * POOL];
    for a in 0..POOL {
        let (i0, i1) = bins(a, DIMS[0]);
        for b in 0..POOL {
            let (j0, j1) = bins(b, DIMS[1]);
            let mut s = 0u64;
            for i in i0..i1 {
                for j in j0..j1 {
                    s += cols[i * DIMS[1] + j].count_ones() as u64;
                }
            }
            out[a * POOL + b] = s as f64 / ((i1 - i0) * (j1 - j0)) as f64;
        }
    }
    out
}

fn normalised(m: &[f64]) -> Vec<f64> {
    let s: f64 = m.iter().sum();
    if s > 0.0 { m.iter().map(|v| v / s).collect() } else { m.to_vec() }
}

/// scipy's `jensenshannon(p, q)` (natural log): inputs are normalised first.
pub fn js_distance(p: &[f64], q: &[f64]) -> f64 {
    let (p, q) = (normalised(p), normalised(q));
    let rel = |x: f64, y: f64| {
        if x > 0.0 && y > 0.0 {
            x * (x / y).ln()
        } else if x == 0.0 {
            0.0
        } else {
            f64::INFINITY
        }
    };
    let mut js = 0.0;
    for (&a, &b) in p.iter().zip(&q) {
        let m = 0.5 * (a + b);
        js += rel(a, m) + rel(b, m);
    }
    (js / 2.0).max(0.0).sqrt()
}

/// JSD between two sets of maps: their sums, compared.
pub fn jsd(pred: &[Vec<f64>], gt: &[Vec<f64>]) -> f64 {
    let sum = |set: &[Vec<f64>]| {
        let mut s = vec![0.0; POOL * POOL];
        for m in set {
            for (a, b) in s.iter_mut().zip(m) {
                *a += b;
            }
        }
        s
    };
    js_distance(&sum(pred), &sum(gt))
}

/// Biased MMD^2 with a Gaussian kernel (sigma 0.5) between two sets of maps, each normalised to 1.
pub fn mmd(pred: &[Vec<f64>], gt: &[Vec<f64>]) -> f64 {
    if pred.is_empty() || gt.is_empty() {
        return f64::NAN;
    }
    let (x, y): (Vec<Vec<f64>>, Vec<Vec<f64>>) =
        (pred.iter().map(|m| normalised(m)).collect(), gt.iter().map(|m| normalised(m)).collect());
    let k = |a: &[f64], b: &[f64]| {
        let d2: f64 = a.iter().zip(b).map(|(u, v)| (u - v) * (u - v)).sum();
        (-d2 / (2.0 * SIGMA * SIGMA)).exp()
    };
    let mean = |a: &[Vec<f64>], b: &[Vec<f64>]| {
        let mut s = 0.0;
        for u in a {
            for v in b {
                s += k(u, v);
            }
        }
        s / (a.len() * b.len()) as f64
    };
    (mean(&x, &x) + mean(&y, &y) - 2.0 * mean(&x, &y)).max(0.0)
}

/// Read the xyz of a KITTI-style `.bin` (float32 x, y, z, intensity per point), a `.pcd` (see
/// `read_pcd`) or a `.npy` of shape (N, >= 3) (float32 or float64).
pub fn read_points(path: &Path) -> Result<Vec<[f32; 3]>, String> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    match ext.as_str() {
        "bin" => {
            let bytes = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
            if bytes.len() % 16 != 0 {
                return Err(format!("{} bytes is not a whole number of float32 x 4 points", bytes.len()));
            }
            Ok(bytes
                .chunks_exact(16)
                .map(|c| {
                    let f = |o: usize| f32::from_le_bytes([c[o], c[o + 1], c[o + 2], c[o + 3]]);
                    [f(0), f(4), f(8)]
                })
                .collect())
        }
        "npy" => {
            use ndarray_npy::ReadNpyExt;
            let f = || std::fs::File::open(path).map_err(|e| format!("cannot open: {e}"));
            let a: ndarray::Array2<f64> = match ndarray::Array2::<f32>::read_npy(f()?) {
                Ok(a) => a.mapv(f64::from),
                Err(_) => ndarray::Array2::<f64>::read_npy(f()?)
                    .map_err(|e| format!("not a float32/float64 (N, >= 3) array: {e}"))?,
            };
            if a.ncols() < 3 {
                return Err(format!("array has {} columns, need x, y, z", a.ncols()));
            }
            Ok(a.outer_iter().map(|r| [r[0] as f32, r[1] as f32, r[2] as f32]).collect())
        }
        "pcd" => read_pcd(&std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?),
        _ => Err("not a point cloud file (expected .bin, .pcd or .npy)".into()),
    }
}

/// The xyz of a PCD v0.7 file (`DATA ascii` or `binary`; `binary_compressed` is refused) whose
/// fields include float x, y and z.
pub fn read_pcd(bytes: &[u8]) -> Result<Vec<[f32; 3]>, String> {
    let mut fields: Vec<String> = Vec::new();
    let (mut size, mut kind, mut count): (Vec<usize>, Vec<char>, Vec<usize>) = (vec![], vec![], vec![]);
    let mut points: Option<usize> = None;
    let mut at = 0;
    let data = loop {
        let end =
            bytes[at..].iter().position(|&b| b == b'\n').map(|i| at + i).ok_or("PCD header has no `DATA` line")?;
        let line = std::str::from_utf8(&bytes[at..end]).map_err(|_| "PCD header is not text")?.trim();
        at = end + 1;
        let mut w = line.split_whitespace();
        let key = w.next().unwrap_or("");
        let rest: Vec<&str> = w.collect();
        let nums = |v: &[&str]| -> Result<Vec<usize>, String> {
            v.iter().map(|x| x.parse::<usize>().map_err(|_| format!("PCD `{line}`"))).collect()
        };
        match key.to_ascii_uppercase().as_str() {
            "FIELDS" => fields = rest.iter().map(|s| s.to_string()).collect(),
            "SIZE" => size = nums(&rest)?,
            "TYPE" => kind = rest.iter().map(|s| s.chars().next().unwrap_or('?')).collect(),
            "COUNT" => count = nums(&rest)?,
            "POINTS" => points = rest.first().and_then(|p| p.parse().ok()),
            "DATA" => break rest.first().map(|s| s.to_ascii_lowercase()).unwrap_or_default(),
            _ => {}
        }
    };
    let n = fields.len();
    if count.is_empty() {
        count = vec![1; n];
    }
    if size.len() != n || kind.len() != n || count.len() != n {
        return Err("PCD header: FIELDS, SIZE, TYPE and COUNT disagree in length".into());
    }
    let col = |name: &str| -> Result<usize, String> {
        let i = fields.iter().position(|f| f == name).ok_or(format!("PCD has no `{name}` field"))?;
        if kind[i] != 'F' || !(size[i] == 4 || size[i] == 8) {
            return Err(format!("PCD field `{name}` is not float32 or float64"));
        }
        Ok(i)
    };
    let xyz = [col("x")?, col("y")?, col("z")?];
    let points = points.ok_or("PCD header has no `POINTS`")?;
    match data.as_str() {
        "ascii" => {
            // One value per (field, count) slot on each line.
            let offs: Vec<usize> = (0..n).scan(0, |o, i| Some(std::mem::replace(o, *o + count[i]))).collect();
            let text = std::str::from_utf8(&bytes[at..]).map_err(|_| "PCD ascii data is not text")?;
            let mut out = Vec::with_capacity(points);
            for line in text.lines().filter(|l| !l.trim().is_empty()).take(points) {
                let v: Vec<&str> = line.split_whitespace().collect();
                let get = |i: usize| -> Result<f32, String> {
                    v.get(offs[i]).and_then(|s| s.parse::<f32>().ok()).ok_or(format!("PCD ascii line `{line}`"))
                };
                out.push([get(xyz[0])?, get(xyz[1])?, get(xyz[2])?]);
            }
            if out.len() != points {
                return Err(format!("PCD says {points} points, the data holds {}", out.len()));
            }
            Ok(out)
        }
        "binary" => {
            let offs: Vec<usize> = (0..n).scan(0, |o, i| Some(std::mem::replace(o, *o + size[i] * count[i]))).collect();
            let stride: usize = (0..n).map(|i| size[i] * count[i]).sum();
            let body = &bytes[at..];
            if stride == 0 || body.len() < points * stride {
                return Err(format!(
                    "PCD binary data is {} bytes, {points} points need {}",
                    body.len(),
                    points * stride
                ));
            }
            let get = |rec: &[u8], i: usize| -> f32 {
                let o = offs[i];
                if size[i] == 4 {
                    f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]])
                } else {
                    let mut b = [0u8; 8];
                    b.copy_from_slice(&rec[o..o + 8]);
                    f64::from_le_bytes(b) as f32
                }
            };
            Ok(body
                .chunks_exact(stride)
                .take(points)
                .map(|r| [get(r, xyz[0]), get(r, xyz[1]), get(r, xyz[2])])
                .collect())
        }
        other => Err(format!("PCD `DATA {other}` is not supported (ascii or binary)")),
    }
}

/// The set-level result.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LidarScores {
    pub pred_clouds: usize,
    pub gt_clouds: usize,
    pub mmd: f64,
    pub jsd: f64,
    pub range_filter: bool,
}
