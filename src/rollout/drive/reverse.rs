//! The reverse goal (`reverse 8 m`, `reverse into east.out[1]`): a vehicle driven backwards,
//! rear first, at reverse speed.
//!
//! Inside the rollout a reversing vehicle's state carries the heading it moves along (its own
//! heading turned half round), so the controller, the kinematic bicycle and everyone's view of
//! it (a box turned half round is the same box; its velocity is its direction of motion) work
//! unchanged: the same arcs, bounded by the same turning radius, with the rear leading. The
//! tracks get the body's heading back and a negative speed (`Sim::record`): the velocity is
//! opposite the heading. Regression scene: scenarios/rare/reversing_from_driveway.scn.

use crate::check::kerb::{REVERSE_MAX_MS, REVERSE_SPEED_MS};
use crate::check::scenario::Reverse;
use crate::diag::Diagnostic;
use crate::geom::wrap_angle;
use crate::road::Map;
use crate::rollout::agent::{Actor, Lat, StopGoal};
use crate::rollout::path::Hermite;
use crate::rollout::path::Path;
use glam::DVec2;
use std::f64::consts::PI;

/// A reversing vehicle's acceleration, m/s2: a gentle pull away backwards.
const REVERSE_ACCEL: f64 = 1.0;
/// How far past its reverse a path runs (the controller slows onto its stop well short), m.
const RUN_ON: f64 = 20.0;
/// How far along the lane `reverse into` backs once its rear has swung in, to end straight, m.
const SETTLE: f64 = 2.0;

/// Vehicle `a` (set up as a forward driver) turned into one reversing toward `r` at
/// `speed` (its goal speed, if any).
pub(crate) fn setup(map: &Map, a: &mut Actor, r: Reverse, speed: Option<f64>, errs: &mut Vec<Diagnostic>) {
    let pos = DVec2::new(a.init.x, a.init.y);
    let back = wrap_angle(a.init.yaw + PI);
    let (path, stop) = match r {
        Reverse::Dist(d) => (Path::straight(pos, back, d + RUN_ON), d),
        Reverse::Into(id) => match map.lane(id).and_then(|l| into_lane(pos, back, l, a.r_min)) {
            Some(p) => p,
            None => {
                if let Some(span) = a.span {
                    errs.push(
                        Diagnostic::error(
                            "E0253",
                            format!("`{}` cannot reverse into that lane from here", a.info.name),
                        )
                        .label(span, "reversing vehicle")
                        .help("start it beside the lane, in a driveway or a parking slot along it"),
                    );
                }
                (Path::straight(pos, back, RUN_ON), 0.0)
            }
        },
    };
    a.reverse = true;
    a.init.yaw = back;
    a.path = path;
    a.path.set_caps(a.lim.lat_acc, a.lim.yaw_rate, a.lim.brake);
    (a.s0, a.d0, a.v0, a.v_hold) = (0.0, 0.0, 0.0, 0.0);
    a.v_goal = speed.unwrap_or(REVERSE_SPEED_MS).clamp(0.0, REVERSE_MAX_MS);
    a.lim.accel = a.lim.accel.min(REVERSE_ACCEL);
    a.stop = StopGoal::Centre(stop);
    a.lateral = Lat::Hold;
    // Its route is its own: no junction ahead, no turn, no signal.
    (a.junction, a.turn_goal) = (None, None);
}

/// The path of one backing out of a driveway or a parking slot into `lane`: its rear swings in
/// on a curve it can steer (a Hermite curve, lengthened until its curvature is within the
/// turning radius), then runs on along the lane against its direction of travel, so the body
/// ends aligned with the lane, facing the way it goes. Its stop: `SETTLE` m past the curve.
fn into_lane(pos: DVec2, back: f64, lane: &crate::road::map::Lane, r_min: f64) -> Option<(Path, f64)> {
    let (s_here, off) = lane.centre.project(pos);
    let against = |s: f64| {
        let (q, yaw) = lane.centre.pose_at(s);
        (q, yaw + PI)
    };
    let mut swing = off.abs().max(r_min);
    let curve = loop {
        let s_join = s_here - swing;
        if s_join < 1.0 {
            return None;
        }
        let (q, yaw) = against(s_join);
        let h = Hermite::new(pos, back, q, yaw);
        if h.max_curvature() * r_min <= 1.0 || swing > 60.0 {
            break (h, s_join, yaw);
        }
        swing += 1.0;
    };
    let (h, s_join, yaw) = curve;
    let mut pts: Vec<DVec2> = (0..=48).map(|k| h.at(h.length() * f64::from(k) / 48.0, yaw).0).collect();
    let mut s = s_join - 1.0;
    while s > (s_join - RUN_ON).max(0.0) {
        pts.push(against(s).0);
        s -= 1.0;
    }
    Some((Path::new(&pts), h.length() + SETTLE))
}
