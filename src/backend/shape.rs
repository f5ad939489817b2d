//! Class-specific solids. In: one box (class, kind name, l, w, h). Out: a short list of `Prim`s
//! in the box's local frame (u forward along the length, v left along the width, z up from the box
//! bottom) whose union is the object's solid. The voxeliser turns them into voxels; surface mode
//! keeps only the solid's shell.
//!
//! Every primitive answers one question per ground column: which z interval of this column lies
//! inside me? That keeps voxelisation at one evaluation per column per primitive instead of one
//! per voxel. Shapes (l, w, h are the box's extents):
//!
//! - vehicle, car-like (h < 2.3 m, 2.6 m <= l < 6.5 m): four wheel discs, a lower body from the
//!   ground clearance to 0.55 h over the whole footprint (corners slightly rounded), and a cabin
//!   (greenhouse) up to h, set back from the hood and inset from the sides;
//! - vehicle, tall or long (vans, ambulances, buses, trucks): wheels and one body from the
//!   clearance to h; below 8 m length a lower hood at the front (van / ambulance nose);
//! - vehicle shorter than 2.6 m (motorcycles) and bicycle: two wheel discs, a frame, a
//!   handlebar across the full width, and a rider (legs, torso, head) when h >= 1.3 m;
//! - pedestrian: a column of legs, torso (the full footprint, squircle) and head;
//! - traffic cone: a square base plate over the footprint and a tapering frustum;
//! - barrier: a wedge (trapezoid section) along the length;
//! - czone sign: feet, a post and a panel across the width in the top part;
//! - generic object: quadruped (legs, body, head) for animal kinds, else a rounded block;
//! - structure: tree (trunk + spheroid crown, wider than its box), pole (column), bush (rounded
//!   block), wall / building / anything else (the full box).
//!
//! Parts thinner than a voxel are widened to `THIN` (half-thickness) so a plate or a frame stays
//! a connected line of voxels at any yaw.

use crate::check::scenario::Class;

/// Minimum half-thickness of thin parts: half a voxel diagonal (0.25 / sqrt 2), so a strip keeps
/// a connected run of column centres whatever its heading.
pub const THIN: f64 = 0.18;

/// One primitive in the box's local frame. Heights are measured from the box bottom.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Prim {
    /// Extruded rectangle [u0, u1] x [v0, v1], z in [z0, z1].
    Rect { u0: f64, u1: f64, v0: f64, v1: f64, z0: f64, z1: f64 },
    /// Extruded superellipse |du/ru|^p + |dv/rv|^p <= 1 (p = 2 ellipse, larger p squarer).
    Round { cu: f64, cv: f64, ru: f64, rv: f64, p: i32, z0: f64, z1: f64 },
    /// Spheroid: horizontal radius a, vertical semi-axis c, centre (cu, cv, cz).
    Spheroid { cu: f64, cv: f64, cz: f64, a: f64, c: f64 },
    /// Circular frustum with radius r0 at z0 and r1 at z1.
    Frustum { cu: f64, cv: f64, r0: f64, r1: f64, z0: f64, z1: f64 },
    /// Trapezoid section across v: half-width b0 at z0, b1 at z1, extruded along u in [u0, u1].
    Wedge { u0: f64, u1: f64, b0: f64, b1: f64, z0: f64, z1: f64 },
    /// Disc in the (u, z) plane (a wheel): centre (cu, cz), radius r, |v - cv| <= t.
    Disc { cu: f64, cv: f64, cz: f64, r: f64, t: f64 },
}

impl Prim {
    /// Local bounds (u0, u1, v0, v1).
    pub fn bounds(&self) -> (f64, f64, f64, f64) {
        match *self {
            Prim::Rect { u0, u1, v0, v1, .. } => (u0, u1, v0, v1),
            Prim::Round { cu, cv, ru, rv, .. } => (cu - ru, cu + ru, cv - rv, cv + rv),
            Prim::Spheroid { cu, cv, a, .. } => (cu - a, cu + a, cv - a, cv + a),
            Prim::Frustum { cu, cv, r0, r1, .. } => {
                let r = r0.max(r1);
                (cu - r, cu + r, cv - r, cv + r)
            }
            Prim::Wedge { u0, u1, b0, b1, .. } => {
                let b = b0.max(b1);
                (u0, u1, -b, b)
            }
            Prim::Disc { cu, cv, r, t, .. } => (cu - r, cu + r, cv - t, cv + t),
        }
    }

    /// A local point surely inside the primitive (its axis), for the one-column fallback.
    pub fn centre(&self) -> (f64, f64) {
        let (u0, u1, v0, v1) = self.bounds();
        match *self {
            Prim::Wedge { u0, u1, .. } => ((u0 + u1) / 2.0, 0.0),
            _ => ((u0 + u1) / 2.0, (v0 + v1) / 2.0),
        }
    }

    /// The z interval (from the box bottom) inside the primitive over local point (u, v).
    #[inline]
    pub fn column(&self, u: f64, v: f64) -> Option<(f64, f64)> {
        match *self {
            Prim::Rect { u0, u1, v0, v1, z0, z1 } => (u >= u0 && u <= u1 && v >= v0 && v <= v1).then_some((z0, z1)),
            Prim::Round { cu, cv, ru, rv, p, z0, z1 } => {
                let a = ((u - cu) / ru).abs();
                let b = ((v - cv) / rv).abs();
                (a.powi(p) + b.powi(p) <= 1.0).then_some((z0, z1))
            }
            Prim::Spheroid { cu, cv, cz, a, c } => {
                let d2 = ((u - cu) * (u - cu) + (v - cv) * (v - cv)) / (a * a);
                (d2 <= 1.0).then(|| {
                    let dz = c * (1.0 - d2).sqrt();
                    (cz - dz, cz + dz)
                })
            }
            Prim::Frustum { cu, cv, r0, r1, z0, z1 } => {
                let d = ((u - cu) * (u - cu) + (v - cv) * (v - cv)).sqrt();
                taper(d, r0, r1, z0, z1)
            }
            Prim::Wedge { u0, u1, b0, b1, z0, z1 } => {
                if u < u0 || u > u1 {
                    return None;
                }
                taper(v.abs(), b0, b1, z0, z1)
            }
            Prim::Disc { cu, cv, cz, r, t } => {
                if (v - cv).abs() > t {
                    return None;
                }
                let du = u - cu;
                (du.abs() <= r).then(|| {
                    let dz = (r * r - du * du).sqrt();
                    (cz - dz, cz + dz)
                })
            }
        }
    }
}

/// The z interval where a radius varying linearly from r0 (at z0) to r1 (at z1) is >= d.
#[inline]
fn taper(d: f64, r0: f64, r1: f64, z0: f64, z1: f64) -> Option<(f64, f64)> {
    if d > r0.max(r1) {
        return None;
    }
    if (r0 - r1).abs() < 1e-12 {
        return Some((z0, z1));
    }
    // r(z) = r0 + (r1 - r0) s, s in [0, 1]; r(z) >= d where s is on one side of s*.
    let s = ((d - r0) / (r1 - r0)).clamp(0.0, 1.0);
    let zs = z0 + s * (z1 - z0);
    Some(if r0 > r1 { (z0, zs) } else { (zs, z1) })
}

/// Which shape a box gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeKind {
    Car,
    TallVehicle,
    TwoWheeler,
    Pedestrian,
    Cone,
    Barrier,
    Sign,
    Quadruped,
    Block,
    Tree,
    Pole,
    Bush,
    Slab,
}

/// Kind names (rocc prelude and common user kinds) that get the quadruped shape.
const ANIMAL_KINDS: [&str; 8] = ["animal", "dog", "deer", "horse", "cow", "moose", "elk", "sheep"];

/// Pick the shape of a box from its class, kind name and size.
pub fn shape_kind(class: Class, kind: &str, l: f64, h: f64) -> ShapeKind {
    match class {
        Class::Vehicle if l < 2.6 => ShapeKind::TwoWheeler,
        Class::Vehicle if h >= 2.3 || l >= 6.5 => ShapeKind::TallVehicle,
        Class::Vehicle => ShapeKind::Car,
        Class::Bicycle => ShapeKind::TwoWheeler,
        Class::Pedestrian => ShapeKind::Pedestrian,
        Class::TrafficCone => ShapeKind::Cone,
        Class::Barrier => ShapeKind::Barrier,
        Class::CzoneSign => ShapeKind::Sign,
        Class::GenericObject if ANIMAL_KINDS.contains(&kind) => ShapeKind::Quadruped,
        Class::GenericObject => ShapeKind::Block,
        Class::Structure => match kind {
            k if k.contains("tree") => ShapeKind::Tree,
            k if k.contains("pole") || k.contains("post") || k.contains("lamp") => ShapeKind::Pole,
            k if k.contains("bush") || k.contains("hedge") => ShapeKind::Bush,
            _ => ShapeKind::Slab,
        },
    }
}

/// Horizontal crown radius of a tree of height h (m): wider than its trunk box, like real crowns.
pub fn crown_radius(h: f64) -> f64 {
    (0.3 * h).clamp(1.2, 3.5)
}

/// The primitives of a box of size (l, w, h), appended to `out`.
pub fn prims(kind: ShapeKind, l: f64, w: f64, h: f64, out: &mut Vec<Prim>) {
    let (hl, hw) = (l / 2.0, w / 2.0);
    let rect = |u0: f64, u1: f64, v0: f64, v1: f64, z0: f64, z1: f64| Prim::Rect { u0, u1, v0, v1, z0, z1 };
    match kind {
        ShapeKind::Car => {
            let clear = (0.12 * h).clamp(0.12, 0.3);
            let rw = (0.22 * h).clamp(0.28, 0.4);
            let axle = 0.3 * l;
            for cu in [-axle, axle] {
                for cv in [-(hw - 0.15), hw - 0.15] {
                    out.push(Prim::Disc { cu, cv, cz: rw, r: rw, t: 0.13 });
                }
            }
            out.push(Prim::Round { cu: 0.0, cv: 0.0, ru: hl, rv: hw, p: 10, z0: clear, z1: 0.55 * h });
            out.push(rect(-hl + 0.12 * l, hl - 0.3 * l, -hw + 0.08 * w, hw - 0.08 * w, 0.55 * h, h));
        }
        ShapeKind::TallVehicle => {
            let clear = (0.1 * h).clamp(0.15, 0.4);
            let rw = (0.15 * h).clamp(0.35, 0.55);
            let front = hl - (0.2 * l).max(1.0);
            let rear = -(hl - (0.22 * l).max(1.0));
            for cu in [rear, front] {
                for cv in [-(hw - 0.2), hw - 0.2] {
                    out.push(Prim::Disc { cu, cv, cz: rw, r: rw, t: 0.15 });
                }
            }
            if l < 8.0 {
                let hood = 0.15 * l;
                out.push(rect(-hl, hl - hood, -hw, hw, clear, h));
                out.push(rect(hl - hood, hl, -hw, hw, clear, 0.5 * h));
            } else {
                out.push(rect(-hl, hl, -hw, hw, clear, h));
            }
        }
        ShapeKind::TwoWheeler => {
            let r = (0.19 * l).clamp(0.2, 0.35);
            let hub = (hl - r).max(0.0);
            for cu in [-hub, hub] {
                out.push(Prim::Disc { cu, cv: 0.0, cz: r, r, t: THIN });
            }
            out.push(rect(-hub, hub, -THIN, THIN, 0.8 * r, (2.0 * r + 0.15).min(h)));
            let bar = if h >= 1.3 { (0.95, 1.1) } else { (0.75 * h, 0.85 * h) };
            out.push(rect(hub - 0.15, (hub + 0.1).min(hl), -hw, hw, bar.0.min(h), bar.1.min(h)));
            if h >= 1.3 {
                let rv = hw.clamp(THIN, 0.22);
                out.push(rect(-0.15 * l, 0.1 * l, -rv, rv, r, 0.55 * h));
                out.push(Prim::Round { cu: -0.05 * l, cv: 0.0, ru: 0.2, rv, p: 4, z0: 0.55 * h, z1: 0.88 * h });
                out.push(Prim::Round { cu: -0.05 * l, cv: 0.0, ru: THIN, rv: THIN, p: 2, z0: 0.88 * h, z1: h });
            }
        }
        ShapeKind::Pedestrian => {
            let (ru, rv) = (hl.max(THIN), hw.max(THIN));
            out.push(Prim::Round { cu: 0.0, cv: 0.0, ru: 0.8 * ru, rv: 0.8 * rv, p: 4, z0: 0.0, z1: 0.47 * h });
            out.push(Prim::Round { cu: 0.0, cv: 0.0, ru, rv, p: 4, z0: 0.47 * h, z1: 0.82 * h });
            let head = 0.12_f64.max(THIN).min(ru.min(rv));
            out.push(Prim::Round { cu: 0.0, cv: 0.0, ru: head, rv: head, p: 2, z0: 0.82 * h, z1: h });
        }
        ShapeKind::Cone => {
            out.push(rect(-hl, hl, -hw, hw, 0.0, 0.04 * h));
            let r0 = hl.min(hw).max(THIN);
            out.push(Prim::Frustum { cu: 0.0, cv: 0.0, r0, r1: 0.04, z0: 0.0, z1: h });
        }
        ShapeKind::Barrier => {
            let b0 = hw.max(THIN);
            out.push(Prim::Wedge { u0: -hl, u1: hl, b0, b1: (0.4 * b0).max(THIN), z0: 0.0, z1: h });
        }
        ShapeKind::Sign => {
            let t = hl.max(THIN);
            out.push(rect(-t, t, -0.9 * hw, 0.9 * hw, 0.0, 0.1));
            out.push(rect(-THIN, THIN, -THIN, THIN, 0.0, h));
            let panel = (0.5 * h).min(0.9);
            out.push(rect(-(hl / 2.0).max(THIN), (hl / 2.0).max(THIN), -hw, hw, h - panel, h));
        }
        ShapeKind::Quadruped => {
            for cu in [-0.35 * l, 0.35 * l] {
                for cv in [-0.3 * w, 0.3 * w] {
                    out.push(Prim::Round { cu, cv, ru: THIN, rv: THIN, p: 2, z0: 0.0, z1: 0.55 * h });
                }
            }
            out.push(Prim::Round {
                cu: -0.05 * l,
                cv: 0.0,
                ru: 0.4 * l,
                rv: hw.max(THIN),
                p: 4,
                z0: 0.5 * h,
                z1: 0.85 * h,
            });
            let head = (0.12 * l).max(THIN);
            out.push(Prim::Round {
                cu: hl - head,
                cv: 0.0,
                ru: head,
                rv: head.min(hw.max(THIN)),
                p: 2,
                z0: 0.6 * h,
                z1: h,
            });
        }
        ShapeKind::Block | ShapeKind::Bush => {
            out.push(Prim::Round { cu: 0.0, cv: 0.0, ru: hl.max(THIN), rv: hw.max(THIN), p: 4, z0: 0.0, z1: h });
        }
        ShapeKind::Tree => {
            let r = (hl.min(hw)).max(THIN);
            out.push(Prim::Round { cu: 0.0, cv: 0.0, ru: r, rv: r, p: 2, z0: 0.0, z1: 0.5 * h });
            out.push(Prim::Spheroid { cu: 0.0, cv: 0.0, cz: 0.65 * h, a: crown_radius(h), c: 0.35 * h });
        }
        ShapeKind::Pole => {
            let r = (hl.min(hw)).max(THIN);
            out.push(Prim::Round { cu: 0.0, cv: 0.0, ru: r, rv: r, p: 2, z0: 0.0, z1: h });
        }
        ShapeKind::Slab => out.push(rect(-hl, hl, -hw.max(THIN), hw.max(THIN), 0.0, h)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn taper_intervals_match_the_geometry() {
        // A cone 1 m tall, radius 0.5 at the base to 0 at the top: at d = 0.25 it is 0.5 m tall.
        let (a, b) = taper(0.25, 0.5, 0.0, 0.0, 1.0).expect("inside");
        assert!((a - 0.0).abs() < 1e-12 && (b - 0.5).abs() < 1e-12);
        assert!(taper(0.6, 0.5, 0.0, 0.0, 1.0).is_none());
        let p = Prim::Spheroid { cu: 0.0, cv: 0.0, cz: 5.0, a: 2.0, c: 1.0 };
        assert_eq!(p.column(0.0, 0.0), Some((4.0, 6.0)));
        assert!(p.column(2.1, 0.0).is_none());
    }

    #[test]
    fn every_shape_has_its_centre_inside_a_primitive() {
        for k in [
            ShapeKind::Car,
            ShapeKind::TallVehicle,
            ShapeKind::TwoWheeler,
            ShapeKind::Pedestrian,
            ShapeKind::Cone,
            ShapeKind::Barrier,
            ShapeKind::Sign,
            ShapeKind::Quadruped,
            ShapeKind::Block,
            ShapeKind::Tree,
            ShapeKind::Pole,
            ShapeKind::Bush,
            ShapeKind::Slab,
        ] {
            let mut v = Vec::new();
            prims(k, 1.8, 0.6, 1.7, &mut v);
            for p in &v {
                let (u, w) = p.centre();
                assert!(p.column(u, w).is_some(), "{k:?} {p:?}");
            }
        }
    }
}
