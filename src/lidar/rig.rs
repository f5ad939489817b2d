//! LiDAR rig description. In: RON text (`rigs/nuplan.ron` is compiled in as the default). Out: a
//! validated `Rig`: sensors (mounting pose, beam elevations, azimuth sector, horizontal
//! resolution) and the return model (range limits, reflectivity per label, intensity, drop and
//! noise parameters). Angles are degrees in the file and converted where used.

use crate::backend::layout::N_LABELS;
use crate::diag::Diagnostic;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The nuPlan rig shipped with rocc (SPEC.md "LiDAR").
pub const NUPLAN_RON: &str = include_str!("../../rigs/nuplan.ron");

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rig {
    pub name: String,
    /// Azimuth step between firings (deg), for every sensor that does not set its own.
    pub horizontal_resolution_deg: f64,
    /// Returns nearer than this (the sensor's blind zone, the ego's own body) or farther than
    /// `max_range` are not reported (m).
    pub min_range: f64,
    pub max_range: f64,
    /// Reflectivity in [0, 1] per occupancy label 0..=8.
    pub reflectivity: Vec<f64>,
    pub intensity: Intensity,
    pub drop: Drop,
    pub noise: Noise,
    /// The frame the sensors' `origin`s are given in (see `Mount`). Absent: rocc's own ego frame.
    #[serde(default)]
    pub mount: Mount,
    pub sensors: Vec<Sensor>,
}

/// Where the frame of the mounting poses sits in rocc's ego frame (SPEC.md "Frames": origin at
/// the ego box's centre projected to the ground, x forward, y left, z up). Calibration files
/// rarely use that point: nuPlan gives its extrinsics relative to the rear axle, at axle height.
/// A rig states its frame here instead of having its numbers rewritten, so the file keeps the
/// published values and the conversion is one documented offset. Axes stay parallel (a mounting
/// frame is always the vehicle's own x forward, y left, z up); only the origin moves.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mount {
    /// Free text naming the frame (recorded for people; not interpreted).
    #[serde(default)]
    pub frame: String,
    /// Position of the mounting frame's origin in rocc's ego frame (m). A sensor at `origin`
    /// in the mounting frame sits at `frame_origin + origin` in the ego frame.
    pub frame_origin: (f64, f64, f64),
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Intensity {
    /// Share of the return following Lambert's cosine law (the rest does not depend on angle).
    pub lambert: f64,
    /// Two-way attenuation exp(-2 alpha r), alpha in 1/m.
    pub attenuation_per_m: f64,
    /// Relative standard deviation of multiplicative Gaussian noise.
    pub noise: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Drop {
    /// P(drop) = base + incidence (1 - cos i)^2 + range (r / max_range)^2, clamped to [0, 1].
    pub base: f64,
    pub incidence: f64,
    pub range: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Noise {
    /// Range noise sigma = sigma_m + sigma_per_m r (m).
    pub sigma_m: f64,
    pub sigma_per_m: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sensor {
    /// Written into every point's `lidar` field.
    pub id: u8,
    pub name: String,
    /// Mounting position (m) in the rig's mounting frame (`Rig::mount`; by default the ego frame).
    /// Use `Rig::sensor_origin` for the position in the ego frame.
    pub origin: (f64, f64, f64),
    /// Mounting rotation (roll, pitch, yaw) in degrees, applied as Rz(yaw) Ry(pitch) Rx(roll) to
    /// the sensor's own axes; zero means aligned with the ego frame.
    #[serde(default)]
    pub rotation_deg: (f64, f64, f64),
    /// Beam elevations (deg); index = `ring`.
    pub elevations_deg: Vec<f64>,
    /// Swept from .0 counter-clockwise to .1 (deg, sensor frame); equal values: a full turn.
    pub azimuth_deg: (f64, f64),
    /// Overrides the rig's horizontal resolution for this sensor.
    #[serde(default)]
    pub horizontal_resolution_deg: Option<f64>,
}

#[derive(Debug, thiserror::Error)]
pub enum RigError {
    #[error("rig file: {0}")]
    Parse(#[from] ron::error::SpannedError),
    #[error("rig: {0}")]
    Invalid(String),
}

impl Rig {
    /// The compiled-in nuPlan rig.
    pub fn nuplan() -> Rig {
        // The file is part of the binary and parsed by a test, so this cannot fail at run time.
        Rig::from_ron(NUPLAN_RON).expect("rigs/nuplan.ron is valid")
    }

    pub fn from_ron(text: &str) -> Result<Rig, RigError> {
        let rig: Rig = ron::from_str(text)?;
        rig.validate()?;
        Ok(rig)
    }

    /// The rig of `--rig PATH --lidar-resolution DEG`: the file (the bundled nuPlan rig when
    /// `None`), with every sensor stepping `resolution` degrees when that is given. E0304 when
    /// the file cannot be read or the rig is not one the ray caster can run.
    pub fn load(path: Option<&Path>, resolution: Option<f64>) -> Result<Rig, Diagnostic> {
        let mut rig = match path {
            None => Rig::nuplan(),
            Some(p) => {
                let text = std::fs::read_to_string(p)
                    .map_err(|e| Diagnostic::error("E0304", format!("cannot read rig `{}`: {e}", p.display())))?;
                Rig::from_ron(&text).map_err(|e| {
                    Diagnostic::error("E0304", format!("rig `{}`: {e}", p.display()))
                        .help("start from rigs/nuplan.ron; `rocc explain E0304` lists the fields")
                })?
            }
        };
        if let Some(r) = resolution {
            rig.horizontal_resolution_deg = r;
            for s in &mut rig.sensors {
                s.horizontal_resolution_deg = None;
            }
            rig.validate().map_err(|e| {
                Diagnostic::error("E0304", format!("--lidar-resolution {r}: {e}"))
                    .help("use a step like 0.1 to 2 degrees")
            })?;
        }
        Ok(rig)
    }

    /// Where `sensor` sits in rocc's ego frame: its mounting position moved by the rig's frame.
    pub fn sensor_origin(&self, sensor: &Sensor) -> [f64; 3] {
        let f = self.mount.frame_origin;
        [f.0 + sensor.origin.0, f.1 + sensor.origin.1, f.2 + sensor.origin.2]
    }

    /// Per sensor, the cosine and sine of each azimuth it sweeps (every beam sweeps the same).
    pub fn azimuth_trig(&self) -> Vec<Vec<(f64, f64)>> {
        self.sensors
            .iter()
            .map(|s| s.azimuths(self.horizontal_resolution_deg).map(|az| (az.cos(), az.sin())).collect())
            .collect()
    }

    pub fn to_ron(&self) -> String {
        // Plain data with no maps keyed by non-strings: serialisation cannot fail.
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default()).expect("a rig serialises")
    }

    /// Reject rigs the ray caster cannot run (a user's file is input like any other).
    pub fn validate(&self) -> Result<(), RigError> {
        let bad = |m: String| Err(RigError::Invalid(m));
        let res_ok = |r: f64| (0.01..=360.0).contains(&r);
        if !res_ok(self.horizontal_resolution_deg) {
            return bad(format!("horizontal_resolution_deg {} is not in [0.01, 360]", self.horizontal_resolution_deg));
        }
        if !(self.min_range >= 0.0 && self.max_range > self.min_range && self.max_range.is_finite()) {
            return bad(format!("need 0 <= min_range < max_range, got {} and {}", self.min_range, self.max_range));
        }
        if self.reflectivity.len() != N_LABELS || self.reflectivity.iter().any(|r| !(0.0..=1.0).contains(r)) {
            return bad(format!("reflectivity needs {N_LABELS} values in [0, 1] (one per label)"));
        }
        let finite = [
            self.intensity.lambert,
            self.intensity.attenuation_per_m,
            self.intensity.noise,
            self.drop.base,
            self.drop.incidence,
            self.drop.range,
            self.noise.sigma_m,
            self.noise.sigma_per_m,
        ];
        if finite.iter().any(|v| !v.is_finite() || *v < 0.0) {
            return bad("intensity, drop and noise parameters must be finite and >= 0".into());
        }
        let f = self.mount.frame_origin;
        if [f.0, f.1, f.2].iter().any(|v| !v.is_finite()) {
            return bad("mount.frame_origin must be finite".into());
        }
        if self.sensors.is_empty() {
            return bad("no sensors".into());
        }
        for s in &self.sensors {
            if s.elevations_deg.is_empty() || s.elevations_deg.len() > u16::MAX as usize {
                return bad(format!("sensor {}: needs 1..=65535 beams", s.name));
            }
            if s.elevations_deg.iter().any(|e| !(-90.0..=90.0).contains(e)) {
                return bad(format!("sensor {}: elevations must be in [-90, 90] deg", s.name));
            }
            let o = [s.origin.0, s.origin.1, s.origin.2, s.rotation_deg.0, s.rotation_deg.1, s.rotation_deg.2];
            if o.iter().any(|v| !v.is_finite()) || !s.azimuth_deg.0.is_finite() || !s.azimuth_deg.1.is_finite() {
                return bad(format!("sensor {}: non-finite pose or azimuth", s.name));
            }
            if let Some(r) = s.horizontal_resolution_deg
                && !res_ok(r)
            {
                return bad(format!("sensor {}: horizontal_resolution_deg {r} is not in [0.01, 360]", s.name));
            }
        }
        Ok(())
    }
}

impl Sensor {
    /// Firing azimuths (rad, sensor frame) for a horizontal step of `res_deg`.
    pub fn azimuths(&self, res_deg: f64) -> impl Iterator<Item = f64> + use<> {
        let res = self.horizontal_resolution_deg.unwrap_or(res_deg);
        let (a, b) = self.azimuth_deg;
        let span = (b - a).rem_euclid(360.0);
        // A full turn fires n times without repeating its start; a sector includes both ends.
        let n = if span < 1e-9 {
            (360.0 / res).round().max(1.0) as usize
        } else {
            (span / res + 1e-9).floor() as usize + 1
        };
        (0..n).map(move |m| (a + res * m as f64).to_radians())
    }

    /// The sensor-to-ego rotation as a row-major 3x3 matrix.
    pub fn rotation(&self) -> [[f64; 3]; 3] {
        let (r, p, y) =
            (self.rotation_deg.0.to_radians(), self.rotation_deg.1.to_radians(), self.rotation_deg.2.to_radians());
        let (cr, sr, cp, sp, cy, sy) = (r.cos(), r.sin(), p.cos(), p.sin(), y.cos(), y.sin());
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nuplan_rig_matches_the_spec_table_and_round_trips() {
        let rig = Rig::nuplan();
        let beams: Vec<usize> = rig.sensors.iter().map(|s| s.elevations_deg.len()).collect();
        assert_eq!(beams, [40, 40, 40, 20, 20]);
        let top = &rig.sensors[0];
        assert_eq!(top.origin, (1.5283, -0.0081, 1.6157));
        // The published poses are rear-axle relative; the rig moves them onto the box centre.
        assert_eq!(rig.mount.frame_origin, (-1.461, 0.0, 0.369));
        let o = rig.sensor_origin(top);
        assert!((o[0] - 0.0673).abs() < 1e-9 && (o[2] - 1.9847).abs() < 1e-9, "{o:?}");
        let (lo, hi) = top.elevations_deg.iter().fold((f64::MAX, f64::MIN), |(a, b), e| (a.min(*e), b.max(*e)));
        assert_eq!((lo, hi), (-25.0, 15.0));
        assert_eq!(top.azimuths(0.4).count(), 900);
        // 280 deg sectors with both ends.
        assert_eq!(rig.sensors[1].azimuths(0.4).count(), 701);
        assert_eq!(rig.sensors[2].azimuths(0.4).count(), 701);
        let back = Rig::from_ron(&rig.to_ron()).expect("round trip");
        assert_eq!(back, rig);
    }

    #[test]
    fn bad_rigs_are_errors_not_panics() {
        let mut rig = Rig::nuplan();
        rig.horizontal_resolution_deg = 0.0;
        assert!(rig.validate().is_err());
        assert!(Rig::from_ron("Rig(name: \"x\")").is_err());
        let mut rig = Rig::nuplan();
        rig.reflectivity.pop();
        assert!(Rig::from_ron(&rig.to_ron()).is_err());
        let mut rig = Rig::nuplan();
        rig.mount.frame_origin.2 = f64::NAN;
        assert!(rig.validate().is_err());
    }

    #[test]
    fn a_rig_without_a_mount_is_in_the_ego_frame() {
        let text = NUPLAN_RON.replace("mount:", "_unused:");
        // A misspelt field is an error, not a silently defaulted frame.
        assert!(Rig::from_ron(&text).is_err());
        // The shipped file less its `mount` block.
        let start = NUPLAN_RON.find("    mount: (").expect("the shipped rig states its frame");
        let end = start + NUPLAN_RON[start..].find("\n    ),\n").expect("block end") + 8;
        let without = format!("{}{}", &NUPLAN_RON[..start], &NUPLAN_RON[end..]);
        let back = Rig::from_ron(&without).expect("mount is optional");
        assert_eq!(back.mount, Mount::default());
        assert_eq!(back.sensor_origin(&back.sensors[4]), [4.0223, -0.0238, 0.0084]);
    }

    #[test]
    fn output_doc_sensor_table_matches_the_rig() {
        // docs/output.md, "Frames", lists each sensor's published pose and where rocc puts it.
        let doc = include_str!("../../docs/output.md");
        let rig = Rig::nuplan();
        let triple = |cell: &str| -> Vec<f64> {
            cell.trim()
                .trim_matches(|c| c == '(' || c == ')')
                .split(',')
                .map(|v| v.trim().parse().expect("number"))
                .collect()
        };
        let mut rows = 0;
        for line in doc.lines().filter(|l| l.starts_with("| ") && l.contains(") | (")) {
            let cells: Vec<&str> = line.split('|').collect();
            let id: usize = cells[1].split_whitespace().next().and_then(|v| v.parse().ok()).expect("sensor id");
            let s = &rig.sensors[id];
            assert_eq!(triple(cells[2]), vec![s.origin.0, s.origin.1, s.origin.2], "{line}");
            let ego = rig.sensor_origin(s);
            for (a, b) in triple(cells[3]).iter().zip(ego) {
                assert!((a - b).abs() < 5e-5, "{line}: rig says {ego:?}");
            }
            rows += 1;
        }
        assert_eq!(rows, rig.sensors.len());
    }
}
