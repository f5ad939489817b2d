//! What a `track` may ask of a body: speed, acceleration, yaw rate and, for vehicles, no sideways
//! slip (E0131-E0134). The place pass (`place::track`) applies it once lane keyframes have world
//! poses and the box its sampled length, naming the keyframe with the measured value and the
//! limit. The limits are what the kind's body can physically do, not the controller's comfort (a
//! recorded hard brake is data): tests/invalid/track_*.scn holds one infeasible track per limit.
//!
//! Recorded boxes jitter (a few cm in position, a few degrees in yaw, frame to frame), so speeds
//! and yaw changes between two keyframes get a jitter allowance and accelerations are taken over
//! windows of at least `WINDOW_S` (tests/fixtures/import and scenarios/replayed_cut_in.scn check).

use super::Checker;
use super::scenario::{Along, Class, Dist, Keyframe, Motion, Place, Road};
use super::units::Dim;
use crate::diag::Diagnostic;
use crate::geom::wrap_angle;
use crate::syntax::ast;
use glam::DVec2;

/// What a body of some motion and class can do at most.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackLimits {
    /// m/s.
    pub speed: f64,
    /// Magnitude of the acceleration vector (braking and cornering included), m/s^2.
    pub accel: f64,
    /// rad/s where turning is not bounded by the wheels (walkers); vehicles: see `yaw_bound`.
    pub yaw_rate: f64,
    /// Whether the body rolls on wheels: it moves along its heading, never sideways.
    pub wheeled: bool,
}

/// Positions of recorded boxes jitter by about this much (m) between frames.
pub const JITTER_M: f64 = 0.3;
/// Recorded headings jitter by about this much (rad, 10 deg) between frames.
pub const YAW_JITTER: f64 = 0.175;
/// Accelerations are measured between mean velocities over at least this long (s).
pub const WINDOW_S: f64 = 0.5;
/// The most a wheeled body's direction of travel may differ from its heading (or its reverse).
pub const SLIP_MAX: f64 = 30.0 * std::f64::consts::PI / 180.0;
/// A vehicle turns no tighter than its wheelbase (0.6 of its length) at 45 degrees of lock.
pub const WHEELBASE_SHARE: f64 = 0.6;

/// The limits of a kind of `motion` and `class`. Vehicles: 324 km/h (the language's speed cap)
/// and 1.2 g of tyre grip; bicycles and scooters 30 m/s and 0.8 g; people a sprinter's 12 m/s
/// and 8 m/s^2; animals a deer's 25 m/s and 15 m/s^2. A static kind replaying a track is
/// carried (a cone on a pickup): a vehicle's speed and grip, turning as it is carried.
pub fn limits(motion: Motion, class: Class) -> TrackLimits {
    use std::f64::consts::TAU;
    match (motion, class) {
        (Motion::Vehicle, Class::Bicycle) => TrackLimits { speed: 30.0, accel: 8.0, yaw_rate: TAU, wheeled: true },
        (Motion::Vehicle, _) => TrackLimits { speed: super::MAX_SPEED_MS, accel: 12.0, yaw_rate: TAU, wheeled: true },
        (Motion::Holonomic, Class::Pedestrian) => {
            TrackLimits { speed: 12.0, accel: 8.0, yaw_rate: TAU, wheeled: false }
        }
        (Motion::Holonomic, _) => TrackLimits { speed: 25.0, accel: 15.0, yaw_rate: TAU, wheeled: false },
        (Motion::Static, _) => TrackLimits { speed: super::MAX_SPEED_MS, accel: 12.0, yaw_rate: TAU, wheeled: false },
    }
}

/// The most a body may turn (rad) between two keyframes `d` m and `dt` s apart. A wheeled body
/// turns along its path, no tighter than its turning radius `r_min` and no faster than its grip
/// allows at that speed (yaw rate x speed = lateral acceleration); a walker turns at `yaw_rate`.
pub fn yaw_bound(lim: &TrackLimits, r_min: f64, d: f64, dt: f64) -> f64 {
    let turn = if lim.wheeled {
        let v = d / dt;
        (d / r_min).min(if v > 1e-9 { lim.accel * dt / v } else { 0.0 })
    } else {
        lim.yaw_rate * dt
    };
    turn + YAW_JITTER
}

/// The first infeasible step of a track, if any: which check, the keyframe it ends at, the
/// measured value and the limit (in the units the message shows).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Violation {
    pub code: &'static str,
    /// Index of the keyframe the step ends at.
    pub key: usize,
    /// Index of the keyframe the step (or its window) starts at.
    pub from: usize,
    pub measured: f64,
    pub limit: f64,
}

/// Check `keys` (times strictly increasing) against `lim`; `length` is the box's (m), which gives
/// a wheeled body's turning radius.
pub fn first_violation(keys: &[Keyframe], lim: &TrackLimits, length: f64) -> Option<Violation> {
    let pos = |k: &Keyframe| DVec2::new(k.x, k.y);
    let r_min = (WHEELBASE_SHARE * length).max(0.5);
    for i in 1..keys.len() {
        let (a, b) = (&keys[i - 1], &keys[i]);
        let (d, dt) = (pos(b) - pos(a), b.t - a.t);
        let v = d.length() / dt;
        let allowed = lim.speed + JITTER_M / dt;
        let found = |code, measured, limit| Some(Violation { code, key: i, from: i - 1, measured, limit });
        if v > allowed {
            return found("E0131", v, lim.speed);
        }
        let turn = wrap_angle(b.yaw - a.yaw).abs();
        let bound = yaw_bound(lim, r_min, d.length(), dt);
        if turn > bound {
            return found("E0133", turn / dt, bound / dt);
        }
        if lim.wheeled && d.length() > JITTER_M {
            // Along an arc the chord points along the mean of the two headings.
            let mid = a.yaw + 0.5 * wrap_angle(b.yaw - a.yaw);
            let h = DVec2::from_angle(mid);
            let (along, side) = (d.dot(h).abs(), d.perp_dot(h).abs());
            if side > along * SLIP_MAX.tan() + JITTER_M {
                return found("E0134", side.atan2(along), SLIP_MAX);
            }
        }
    }
    // Accelerations between consecutive windows of at least WINDOW_S (or the whole track).
    let next = |i: usize| (i + 1..keys.len()).find(|&j| keys[j].t - keys[i].t >= WINDOW_S);
    let vel = |i: usize, j: usize| (pos(&keys[j]) - pos(&keys[i])) / (keys[j].t - keys[i].t);
    let mut i = 0;
    while let Some(j) = next(i) {
        let Some(k) = next(j) else { break };
        let (dt1, dt2) = (keys[j].t - keys[i].t, keys[k].t - keys[j].t);
        let acc = (vel(j, k) - vel(i, j)).length() / (0.5 * (dt1 + dt2));
        // Jitter moves each window's mean velocity by up to 2 JITTER_M over its length.
        let allowed = lim.accel + 2.0 * JITTER_M * (1.0 / dt1 + 1.0 / dt2) / (0.5 * (dt1 + dt2));
        if acc > allowed {
            return Some(Violation { code: "E0132", key: k, from: i, measured: acc, limit: lim.accel });
        }
        i = j;
    }
    None
}

impl Checker {
    /// A world keyframe's x, y (m) and yaw (rad).
    pub(super) fn world_key(&mut self, x: &ast::Value, y: &ast::Value, yaw: &ast::Value) -> Option<(f64, f64, f64)> {
        let x = self.fixed(x, Dim::Length, "x", -1000.0, 1000.0, "-1000..1000 m");
        let y = self.fixed(y, Dim::Length, "y", -1000.0, 1000.0, "-1000..1000 m");
        let pi4 = 4.0 * std::f64::consts::PI;
        let yaw = self.fixed(yaw, Dim::Angle, "yaw", -pi4, pi4, "-720..720 deg");
        Some((x?, y?, yaw?))
    }

    /// A keyframe in lane coordinates: a lane placement with one value for each distance and
    /// heading (a keyframe is a recorded or intended pose, not a distribution).
    pub(super) fn lane_key(
        &mut self,
        p: &ast::Placement,
        road: Option<&Road>,
        class: Option<Class>,
    ) -> Option<Place<f64>> {
        let place = self.placement(p, road, class)?;
        let fixed = |d: Dist| match d {
            Dist::Fixed(v) => Some(v),
            Dist::Uniform(..) => None,
        };
        let out = match place {
            Place::Lane { lane, along, offset, heading } => match (fixed(along.dist), heading.map(fixed)) {
                (Some(dist), None) => {
                    Some(Place::Lane { lane, along: Along { landmark: along.landmark, dist }, offset, heading: None })
                }
                (Some(dist), Some(Some(h))) => Some(Place::Lane {
                    lane,
                    along: Along { landmark: along.landmark, dist },
                    offset,
                    heading: Some(h),
                }),
                _ => None,
            },
            _ => None,
        };
        if out.is_none() {
            self.err(
                Diagnostic::error("E0117", "a keyframe's distance and heading cannot be ranges")
                    .label(p.span(), "a single pose is needed here")
                    .help("write one value, e.g. `2 s: west.in[1], 20 m before center`"),
            );
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(t: f64, x: f64, y: f64, yaw_deg: f64) -> Keyframe {
        Keyframe { t, x, y, yaw: yaw_deg.to_radians(), at: None, span: Default::default() }
    }

    #[test]
    fn a_sedan_jumping_90_m_sideways_in_one_second_slips() {
        let lim = limits(Motion::Vehicle, Class::Vehicle);
        let keys = [key(0.0, 0.0, 0.0, 0.0), key(1.0, 0.0, 90.0, 0.0)];
        let v = first_violation(&keys, &lim, 4.4).expect("infeasible");
        assert_eq!((v.code, v.key), ("E0134", 1));
    }

    #[test]
    fn a_straight_cruise_with_jitter_passes() {
        let lim = limits(Motion::Vehicle, Class::Vehicle);
        // 15 m/s east at 10 Hz, +-5 cm and +-2 deg of alternating jitter.
        let keys: Vec<Keyframe> = (0..50)
            .map(|i| {
                let s = if i % 2 == 0 { 1.0 } else { -1.0 };
                key(i as f64 * 0.1, 1.5 * i as f64 + 0.05 * s, 0.05 * s, 2.0 * s)
            })
            .collect();
        assert_eq!(first_violation(&keys, &lim, 4.4), None);
    }
}
