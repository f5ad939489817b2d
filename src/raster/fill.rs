//! Scan conversion with OpenCV's integer rules. In: integer canvas vertices (u = column, v = row,
//! as cv2 sees an image) and an `emit(v, u0, u1)` callback. Out: calls to `emit` with inclusive,
//! in-canvas pixel runs — nothing is allocated per pixel.
//!
//! Mirrors `cv::fillPoly` / `cv::line` / `cv::circle` (drawing.cpp, LINE_8, shift 0) so our masks
//! match nuPlan-Occ's, which `NuPlanMapExplorer.get_map_mask` fills with `cv2.fillPoly`:
//! - every polygon edge is first drawn as an 8-connected line (`Line` in `CollectPolyEdges`);
//! - the interior is filled by `FillEdgeCollection`: edges in 16.16 fixed point from the (clipped)
//!   integer end points, `dx` by truncating integer division, rows [y0, y1) per edge, crossings
//!   sorted and paired, each run from ceil(x_left) to floor(x_right) inclusive;
//! - edges with an end off the canvas are re-based on cv2's `clipLine` result and extrapolated
//!   back to the original first row ("correct starting point for clipped lines").
//!
//! This is the rasteriser of current OpenCV (4.x `drawing.cpp` after the clipped-edge fix, and
//! 5.0); `tests/bev.rs` checks it pixel for pixel against the installed `cv2` when there is one.
//! Older OpenCV releases started edges half a pixel to the right and rounded run ends differently,
//! which moves slanted edges by at most one pixel.
//!
//! Runs may repeat a pixel (outline and fill overlap); every writer here is idempotent.

const XY_SHIFT: u32 = 16;
const XY_ONE: i64 = 1 << XY_SHIFT;

/// A pixel in canvas coordinates: (u, v) = (column, row) in cv2's image convention.
pub type Px = (i64, i64);

#[inline]
fn outside(w: i64, h: i64, p: Px) -> bool {
    p.0 < 0 || p.0 >= w || p.1 < 0 || p.1 >= h
}

/// `cv::clipLine` on a `w` x `h` image: moves the ends onto the image border; false when the
/// segment misses the image (the ends may still have moved, exactly as in cv2).
pub fn clip_line(w: i64, h: i64, p1: &mut Px, p2: &mut Px) -> bool {
    let (right, bottom) = (w - 1, h - 1);
    if w <= 0 || h <= 0 {
        return false;
    }
    let code = |p: Px| (p.0 < 0) as i32 + (p.0 > right) as i32 * 2 + (p.1 < 0) as i32 * 4 + (p.1 > bottom) as i32 * 8;
    let (mut c1, mut c2) = (code(*p1), code(*p2));
    if (c1 & c2) == 0 && (c1 | c2) != 0 {
        if c1 & 12 != 0 {
            let a = if c1 < 8 { 0 } else { bottom };
            p1.0 += ((a - p1.1) as f64 * (p2.0 - p1.0) as f64 / (p2.1 - p1.1) as f64) as i64;
            p1.1 = a;
            c1 = (p1.0 < 0) as i32 + (p1.0 > right) as i32 * 2;
        }
        if c2 & 12 != 0 {
            let a = if c2 < 8 { 0 } else { bottom };
            p2.0 += ((a - p2.1) as f64 * (p2.0 - p1.0) as f64 / (p2.1 - p1.1) as f64) as i64;
            p2.1 = a;
            c2 = (p2.0 < 0) as i32 + (p2.0 > right) as i32 * 2;
        }
        if (c1 & c2) == 0 && (c1 | c2) != 0 {
            if c1 != 0 {
                let a = if c1 == 1 { 0 } else { right };
                p1.1 += ((a - p1.0) as f64 * (p2.1 - p1.1) as f64 / (p2.0 - p1.0) as f64) as i64;
                p1.0 = a;
                c1 = 0;
            }
            if c2 != 0 {
                let a = if c2 == 1 { 0 } else { right };
                p2.1 += ((a - p2.0) as f64 * (p2.1 - p1.1) as f64 / (p2.0 - p1.0) as f64) as i64;
                p2.0 = a;
                c2 = 0;
            }
        }
    }
    (c1 | c2) == 0
}

/// `cv::line`, thickness 1, LINE_8: Bresenham from the left end, clipped like cv2's
/// `LineIterator`.
pub fn line(w: i64, h: i64, mut p1: Px, mut p2: Px, emit: &mut impl FnMut(i64, i64, i64)) {
    if (outside(w, h, p1) || outside(w, h, p2)) && !clip_line(w, h, &mut p1, &mut p2) {
        return;
    }
    let (mut dx, mut dy) = (p2.0 - p1.0, p2.1 - p1.1);
    if dx < 0 {
        dx = -dx;
        dy = -dy;
        std::mem::swap(&mut p1, &mut p2);
    }
    let sy = if dy < 0 { -1 } else { 1 };
    dy = dy.abs();
    let vert = dy > dx;
    let (major, minor) = if vert { (dy, dx) } else { (dx, dy) };
    let mut err = major - 2 * minor;
    let (mut u, mut v) = p1;
    for _ in 0..=major {
        // Clipping keeps the run inside; the check only guards against arithmetic surprises.
        if !outside(w, h, (u, v)) {
            emit(v, u, u);
        }
        let diag = err < 0;
        err += -2 * minor + if diag { 2 * major } else { 0 };
        if vert {
            v += sy;
            u += diag as i64;
        } else {
            u += 1;
            v += if diag { sy } else { 0 };
        }
    }
}

/// `cv::circle(img, c, 1, color, -1)`: the centre and its 4 neighbours (checked against cv2).
pub fn dot(w: i64, h: i64, c: Px, emit: &mut impl FnMut(i64, i64, i64)) {
    for (du, dv) in [(0, -1), (-1, 0), (0, 0), (1, 0), (0, 1)] {
        let p = (c.0 + du, c.1 + dv);
        if !outside(w, h, p) {
            emit(p.1, p.0, p.0);
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct Edge {
    y0: i64,
    y1: i64,
    x: i64,
    dx: i64,
}

/// Reusable buffers for `fill_poly`, so filling allocates only while they grow.
#[derive(Default, Debug)]
pub struct Filler {
    edges: Vec<Edge>,
    xs: Vec<i64>,
}

impl Filler {
    /// `cv::fillPoly` of one polygon (outline included) on a `w` x `h` image.
    pub fn fill_poly(&mut self, w: i64, h: i64, pts: &[Px], emit: &mut impl FnMut(i64, i64, i64)) {
        let n = pts.len();
        if n == 0 {
            return;
        }
        self.edges.clear();
        let mut pt0 = pts[n - 1];
        for &pt1 in pts {
            line(w, h, pt0, pt1, emit);
            let (mut t0, mut t1) = (pt0, pt1);
            let (mut c0y, mut c1y) = (pt0.1, pt1.1);
            if outside(w, h, pt0) || outside(w, h, pt1) {
                clip_line(w, h, &mut t0, &mut t1);
                if t0.1 != t1.1 {
                    (c0y, c1y) = (t0.1, t1.1);
                }
            }
            let (c0x, c1x) = (t0.0 << XY_SHIFT, t1.0 << XY_SHIFT);
            if pt0.1 != pt1.1 {
                let dx = (c1x - c0x) / (c1y - c0y);
                self.edges.push(if pt0.1 < pt1.1 {
                    Edge { y0: pt0.1, y1: pt1.1, x: c0x + (pt0.1 - c0y) * dx, dx }
                } else {
                    Edge { y0: pt1.1, y1: pt0.1, x: c1x + (pt1.1 - c1y) * dx, dx }
                });
            }
            pt0 = pt1;
        }
        if self.edges.len() < 2 {
            return;
        }
        let (mut y_min, mut y_max) = (i64::MAX, i64::MIN);
        let (mut x_min, mut x_max) = (i64::MAX, i64::MIN);
        for e in &self.edges {
            let x1 = e.x + (e.y1 - e.y0) * e.dx;
            y_min = y_min.min(e.y0);
            y_max = y_max.max(e.y1);
            x_min = x_min.min(e.x).min(x1);
            x_max = x_max.max(e.x).max(x1);
        }
        if y_max < 0 || y_min >= h || x_max < 0 || x_min >= (w << XY_SHIFT) {
            return;
        }
        for y in y_min.max(0)..y_max.min(h) {
            self.xs.clear();
            for e in &self.edges {
                if e.y0 <= y && y < e.y1 {
                    self.xs.push(e.x + (y - e.y0) * e.dx);
                }
            }
            self.xs.sort_unstable();
            for pair in self.xs.chunks_exact(2) {
                let (x1, x2) = ((pair[0] + XY_ONE - 1) >> XY_SHIFT, pair[1] >> XY_SHIFT);
                if x1 < w && x2 >= 0 && x1 <= x2 {
                    emit(y, x1.max(0), x2.min(w - 1));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn render(w: i64, h: i64, f: impl FnOnce(&mut dyn FnMut(i64, i64, i64))) -> Vec<Vec<u8>> {
        let mut img = vec![vec![0u8; w as usize]; h as usize];
        f(&mut |v, u0, u1| {
            for u in u0..=u1 {
                img[v as usize][u as usize] = 1;
            }
        });
        img
    }

    #[test]
    fn line_matches_cv2_bresenham() {
        // cv2.line(np.zeros((12, 12)), (1, 1), (9, 4), 1, 1)
        let img = render(12, 12, |e| line(12, 12, (1, 1), (9, 4), &mut |v, a, b| e(v, a, b)));
        let on: Vec<(usize, usize)> =
            (0..12).flat_map(|v| (0..12).map(move |u| (u, v))).filter(|&(u, v)| img[v][u] == 1).collect();
        assert_eq!(on, vec![(1, 1), (2, 1), (3, 2), (4, 2), (5, 2), (6, 3), (7, 3), (8, 4), (9, 4)]);
    }

    #[test]
    fn rectangle_fill_includes_its_edges() {
        let mut f = Filler::default();
        let img =
            render(30, 30, |e| f.fill_poly(30, 30, &[(2, 3), (18, 3), (18, 11), (2, 11)], &mut |v, a, b| e(v, a, b)));
        let total: usize = img.iter().flatten().map(|&x| x as usize).sum();
        assert_eq!(total, 17 * 9);
    }
}
