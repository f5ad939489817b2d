//! Camera rig description for `mask_camera`. In: RON text (`rigs/nuplan_cameras.ron`, nominal
//! values, is compiled in as the default). Out: a validated `CameraRig` and the pixel rays of
//! each camera in the ego frame.

use crate::diag::Diagnostic;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// nuPlan's eight cameras at nominal poses (the file's header says why and how to replace it).
pub const NUPLAN_CAMERAS_RON: &str = include_str!("../../rigs/nuplan_cameras.ron");

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraRig {
    pub name: String,
    /// One ray per `ray_stride_px` x `ray_stride_px` block of pixels, through its centre.
    pub ray_stride_px: u32,
    pub cameras: Vec<Camera>,
}

/// A pinhole camera with square pixels, in the ego frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    pub name: String,
    /// Optical centre (m), ego frame.
    pub origin: (f64, f64, f64),
    /// Optical axis counter-clockwise from +x (deg).
    pub yaw_deg: f64,
    /// Optical axis tilt, positive looking down (deg).
    #[serde(default)]
    pub pitch_deg: f64,
    /// Horizontal field of view (deg).
    pub hfov_deg: f64,
    /// Image size (pixels).
    pub width: u32,
    pub height: u32,
}

impl CameraRig {
    /// The compiled-in nominal nuPlan rig.
    pub fn nuplan() -> CameraRig {
        // Part of the binary and parsed by a test, so this cannot fail at run time.
        CameraRig::from_ron(NUPLAN_CAMERAS_RON).expect("rigs/nuplan_cameras.ron is valid")
    }

    /// The text of the bundled rig, to start a file of one's own from.
    pub fn nuplan_ron() -> &'static str {
        NUPLAN_CAMERAS_RON
    }

    pub fn from_ron(text: &str) -> Result<CameraRig, String> {
        let rig: CameraRig = ron::from_str(text).map_err(|e| e.to_string())?;
        rig.validate()?;
        Ok(rig)
    }

    /// The rig of `--camera-rig PATH` (the bundled one when `None`); E0431 when the file cannot
    /// be read or describes cameras rocc cannot cast rays from.
    pub fn load(path: Option<&Path>) -> Result<CameraRig, Diagnostic> {
        let Some(p) = path else { return Ok(CameraRig::nuplan()) };
        let text = std::fs::read_to_string(p)
            .map_err(|e| Diagnostic::error("E0431", format!("cannot read camera rig `{}`: {e}", p.display())))?;
        CameraRig::from_ron(&text).map_err(|e| {
            Diagnostic::error("E0431", format!("camera rig `{}`: {e}", p.display()))
                .help("start from rigs/nuplan_cameras.ron; `rocc explain E0431` lists the fields")
        })
    }

    /// Reject rigs the caster cannot run (a user's file is input like any other).
    pub fn validate(&self) -> Result<(), String> {
        if self.cameras.is_empty() {
            return Err("no cameras".into());
        }
        for c in &self.cameras {
            let n = &c.name;
            let o = c.origin;
            if [o.0, o.1, o.2, c.yaw_deg, c.pitch_deg].iter().any(|v| !v.is_finite()) {
                return Err(format!("camera {n}: origin, yaw_deg and pitch_deg must be finite"));
            }
            if !(1.0..=170.0).contains(&c.hfov_deg) {
                return Err(format!("camera {n}: hfov_deg {} is not in [1, 170]", c.hfov_deg));
            }
            if !(1..=16384).contains(&c.width) || !(1..=16384).contains(&c.height) {
                return Err(format!("camera {n}: width and height must be 1 to 16384 pixels"));
            }
            if self.ray_stride_px == 0 || self.ray_stride_px > c.width.min(c.height) {
                return Err(format!("ray_stride_px {} must be 1 to camera {n}'s smaller side", self.ray_stride_px));
            }
        }
        Ok(())
    }
}

impl Camera {
    /// The unit direction, in the ego frame, of the ray through pixel (u, v) (pixel units from
    /// the image's top-left corner).
    pub fn ray(&self, u: f64, v: f64) -> [f64; 3] {
        let f = 0.5 * self.width as f64 / (0.5 * self.hfov_deg.to_radians()).tan();
        // Camera axes: forward, left, up.
        let (x, y, z) = (1.0, -(u - 0.5 * self.width as f64) / f, -(v - 0.5 * self.height as f64) / f);
        let n = (x * x + y * y + z * z).sqrt();
        let (x, y, z) = (x / n, y / n, z / n);
        // Pitch down about the camera's left axis, then yaw about z.
        let (sp, cp) = self.pitch_deg.to_radians().sin_cos();
        let (x, z) = (cp * x + sp * z, -sp * x + cp * z);
        let (sy, cy) = self.yaw_deg.to_radians().sin_cos();
        [cy * x - sy * y, sy * x + cy * y, z]
    }

    /// Every ray of the camera at `stride` pixels, through each block's centre.
    pub fn rays(&self, stride: u32) -> impl Iterator<Item = [f64; 3]> + '_ {
        let s = stride as f64;
        let (nu, nv) = (self.width / stride, self.height / stride);
        (0..nv).flat_map(move |b| (0..nu).map(move |a| self.ray((a as f64 + 0.5) * s, (b as f64 + 0.5) * s)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bundled_rig_parses_and_covers_the_full_turn() {
        let rig = CameraRig::nuplan();
        assert_eq!(rig.cameras.len(), 8);
        for az in 0..360 {
            let a = az as f64;
            let seen = rig.cameras.iter().any(|c| {
                let off = (a - c.yaw_deg + 540.0).rem_euclid(360.0) - 180.0;
                off.abs() < 0.5 * c.hfov_deg
            });
            assert!(seen, "azimuth {a} deg is in no camera");
        }
    }

    #[test]
    fn the_centre_pixel_looks_along_the_optical_axis_and_the_edge_at_half_the_fov() {
        let c = Camera {
            name: "c".into(),
            origin: (0.0, 0.0, 1.0),
            yaw_deg: 90.0,
            pitch_deg: 0.0,
            hfov_deg: 90.0,
            width: 200,
            height: 100,
        };
        let d = c.ray(100.0, 50.0);
        assert!(d[0].abs() < 1e-12 && (d[1] - 1.0).abs() < 1e-12 && d[2].abs() < 1e-12, "{d:?}");
        // A camera facing +y has +x on its right: the right edge looks 45 deg that way.
        let d = c.ray(200.0, 50.0);
        assert!((d[0] - 0.5f64.sqrt()).abs() < 1e-12 && (d[1] - 0.5f64.sqrt()).abs() < 1e-12, "{d:?}");
        let down = Camera { pitch_deg: 10.0, ..c };
        assert!(down.ray(100.0, 50.0)[2] < 0.0);
    }

    #[test]
    fn bad_rigs_are_rejected() {
        let ok = CameraRig::nuplan();
        let mut r = ok.clone();
        r.cameras[0].hfov_deg = 0.0;
        assert!(r.validate().is_err());
        let mut r = ok.clone();
        r.ray_stride_px = 0;
        assert!(r.validate().is_err());
        let mut r = ok.clone();
        r.cameras.clear();
        assert!(r.validate().is_err());
        assert!(CameraRig::from_ron("CameraRig(name: \"x\")").is_err());
    }
}
