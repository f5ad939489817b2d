//! The occupancy format's numbers in one place. In: nothing. Out: grid size, voxel size, origin,
//! the label ids and the class -> label map that every occupancy reader and writer in rocc (the
//! backends, the LiDAR ray caster, the scorer) must agree on.
//!
//! Format: docs/output.md, "Occupancy", as read from UniScene-v2's nuPlan-Occ
//! loaders: uint8 (400, 400, 32), axes [x, y, z], 0.25 m on every axis, x, y in [-50, 50),
//! z in [-3, 5), index = floor((p - [-50, -50, -3]) / 0.25). The ego origin (box centre on the
//! ground) is the corner between voxels 199 and 200 in x and y and the k = 12 boundary in z.

use crate::check::scenario::Class;

/// Voxels along x and along y.
pub const NX: usize = 400;
pub const NY: usize = 400;
/// Voxels along z.
pub const NZ: usize = 32;
/// Voxel edge (m), the same on every axis (SPEC: the code's 0.25 m wins over the paper's 0.4 m).
pub const VOXEL: f64 = 0.25;
/// Lower corner of the grid in the ego frame (m).
pub const ORIGIN: [f64; 3] = [-50.0, -50.0, -3.0];
/// Upper corner (exclusive).
pub const UPPER: [f64; 3] = [50.0, 50.0, 5.0];
/// Layer whose lower face is the ground (z = 0).
pub const K_GROUND_TOP: usize = 12;
/// The layer just below z = 0 that holds the ground surface (see the module doc of `backend`).
pub const K_GROUND: usize = K_GROUND_TOP - 1;

pub const FREE: u8 = 0;
pub const BACKGROUND: u8 = 1;
pub const VEHICLE: u8 = 2;
pub const BICYCLE: u8 = 3;
pub const PEDESTRIAN: u8 = 4;
pub const TRAFFIC_CONE: u8 = 5;
pub const BARRIER: u8 = 6;
pub const CZONE_SIGN: u8 = 7;
pub const GENERIC_OBJECT: u8 = 8;
/// Number of labels (0..=8).
pub const N_LABELS: usize = 9;

/// Label names in id order (SPEC).
pub const LABEL_NAMES: [&str; N_LABELS] = [
    "free",
    "background",
    "vehicle",
    "bicycle",
    "pedestrian",
    "traffic_cone",
    "barrier",
    "czone_sign",
    "generic_object",
];

/// The occupancy label of a scenario class. Structures (trees, poles, walls, buildings) are
/// static scene structure, which nuPlan-Occ labels `background`.
pub fn class_label(c: Class) -> u8 {
    match c {
        Class::Vehicle => VEHICLE,
        Class::Bicycle => BICYCLE,
        Class::Pedestrian => PEDESTRIAN,
        Class::TrafficCone => TRAFFIC_CONE,
        Class::Barrier => BARRIER,
        Class::CzoneSign => CZONE_SIGN,
        Class::GenericObject => GENERIC_OBJECT,
        Class::Structure => BACKGROUND,
    }
}

/// Flat index of voxel (i, j, k) in a standard-layout (400, 400, 32) array.
#[inline]
pub fn flat(i: usize, j: usize, k: usize) -> usize {
    (i * NY + j) * NZ + k
}

/// Voxel index of an ego-frame point, `None` outside the grid.
#[inline]
pub fn voxel_of(p: [f64; 3]) -> Option<[usize; 3]> {
    let n = [NX, NY, NZ];
    let mut out = [0usize; 3];
    for a in 0..3 {
        let f = ((p[a] - ORIGIN[a]) / VOXEL).floor();
        if !(f >= 0.0 && f < n[a] as f64) {
            return None;
        }
        out[a] = f as usize;
    }
    Some(out)
}

/// Centre of voxel index `i` along axis `a` (m).
#[inline]
pub fn centre(a: usize, i: usize) -> f64 {
    ORIGIN[a] + VOXEL * (i as f64 + 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ego_origin_is_the_corner_the_spec_names() {
        assert_eq!(voxel_of([0.0, 0.0, 0.0]), Some([200, 200, 12]));
        assert_eq!(voxel_of([-1e-9, -1e-9, -1e-9]), Some([199, 199, 11]));
        assert_eq!(voxel_of([50.0, 0.0, 0.0]), None);
        assert_eq!(voxel_of([-50.0, -50.0, -3.0]), Some([0, 0, 0]));
        assert_eq!(voxel_of([0.0, 0.0, 5.0]), None);
        assert_eq!(centre(2, K_GROUND), -0.125);
    }
}
