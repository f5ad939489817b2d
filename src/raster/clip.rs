//! Clipping to the BEV patch in ego-frame metres. In: polygons / polylines (ego frame). Out: the
//! parts inside the square [-r, r]^2, written into caller-owned buffers.
//!
//! The reference crops map geometry to the patch before drawing (`polygon.intersection(patch)` in
//! nuScenes' / nuPlan's `get_map_mask`, `line.intersection(patch)` in the vector-map pipeline), so
//! canvas coordinates never leave [0, 400] and cut points become vertices (and so get dots).

use glam::DVec2;

/// Sutherland-Hodgman against the square [-r, r]^2. For a concave polygon that leaves and
/// re-enters the patch, the pieces stay joined by zero-area slivers along the border where shapely
/// would split them; only border pixels can differ.
pub fn polygon(poly: &[DVec2], r: f64, out: &mut Vec<DVec2>, tmp: &mut Vec<DVec2>) {
    out.clear();
    out.extend_from_slice(poly);
    // (axis, sign): keep points with sign * p[axis] <= r.
    for (axis, sign) in [(0usize, 1.0f64), (0, -1.0), (1, 1.0), (1, -1.0)] {
        if out.is_empty() {
            return;
        }
        std::mem::swap(out, tmp);
        out.clear();
        let inside = |p: DVec2| sign * p[axis] <= r;
        let n = tmp.len();
        for i in 0..n {
            let (a, b) = (tmp[(i + n - 1) % n], tmp[i]);
            let (ia, ib) = (inside(a), inside(b));
            if ia != ib {
                let t = (sign * r - a[axis]) / (b[axis] - a[axis]);
                out.push(a + (b - a) * t);
            }
            if ib {
                out.push(b);
            }
        }
    }
}

/// Liang-Barsky on each segment of an open polyline; calls `piece` with every maximal run of the
/// polyline inside [-r, r]^2 (at least two points each).
pub fn polyline(pts: &[DVec2], r: f64, buf: &mut Vec<DVec2>, mut piece: impl FnMut(&[DVec2])) {
    buf.clear();
    for s in pts.windows(2) {
        let (a, b) = (s[0], s[1]);
        let Some((t0, t1)) = segment(a, b, r) else {
            if buf.len() >= 2 {
                piece(buf);
            }
            buf.clear();
            continue;
        };
        let (p, q) = (a + (b - a) * t0, a + (b - a) * t1);
        if t0 > 0.0 || buf.is_empty() {
            if buf.len() >= 2 {
                piece(buf);
            }
            buf.clear();
            buf.push(p);
        }
        buf.push(q);
        if t1 < 1.0 {
            if buf.len() >= 2 {
                piece(buf);
            }
            buf.clear();
        }
    }
    if buf.len() >= 2 {
        piece(buf);
    }
}

fn segment(a: DVec2, b: DVec2, r: f64) -> Option<(f64, f64)> {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [(-d.x, a.x + r), (d.x, r - a.x), (-d.y, a.y + r), (d.y, r - a.y)] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_overlapping_the_patch_is_cut_at_the_border() {
        let sq = [DVec2::new(40.0, -10.0), DVec2::new(60.0, -10.0), DVec2::new(60.0, 10.0), DVec2::new(40.0, 10.0)];
        let (mut out, mut tmp) = (Vec::new(), Vec::new());
        polygon(&sq, 50.0, &mut out, &mut tmp);
        assert_eq!(out.len(), 4);
        assert!(out.iter().all(|p| p.x <= 50.0 && p.x >= 40.0));
    }

    #[test]
    fn polyline_leaving_and_reentering_gives_two_pieces() {
        let l = [DVec2::new(0.0, 0.0), DVec2::new(60.0, 0.0), DVec2::new(60.0, 10.0), DVec2::new(0.0, 10.0)];
        let mut pieces = Vec::new();
        polyline(&l, 50.0, &mut Vec::new(), |p| pieces.push(p.to_vec()));
        assert_eq!(pieces.len(), 2);
        assert_eq!(pieces[0], vec![DVec2::new(0.0, 0.0), DVec2::new(50.0, 0.0)]);
        assert_eq!(pieces[1], vec![DVec2::new(50.0, 10.0), DVec2::new(0.0, 10.0)]);
    }
}
