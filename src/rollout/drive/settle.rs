//! A vehicle steering back toward its lane's line (after pulling over for an emergency vehicle,
//! after passing an obstacle) moves sideways only until it is there: others predict it no
//! farther. Predicted on at its sideways speed, a van coming back off the shoulder 1 m short
//! of the centre line braked a car in the other lane from 10 to 3 m/s
//! (scenarios/rare/fire_truck_from_behind.scn).

use crate::rollout::agent::Lat;
use crate::rollout::frame::Sim;

/// Pure pursuit's overshoot of the line it settles onto, m.
const OVERSHOOT: f64 = 0.3;
/// Out of its line by less than this (m), a vehicle is tracking its route, not settling back.
const MIN_OUT: f64 = 0.05;
/// Cosine of the largest angle between two routes taken as parallel (2 degrees), here and this
/// far (m) along its route either way: a ramp's taper converges on our lane, and a vehicle
/// out of a turn still lags its route.
const PARALLEL: f64 = 0.9994;
const RUN_AHEAD: f64 = 20.0;

impl Sim<'_, '_> {
    /// How far vehicle `j` may still move sideways while it settles back toward its lane's line:
    /// its body's distance from that line (plus pure pursuit's overshoot) when its lateral
    /// reference is nearer the line than its body is; `None` while it moves out (a lane change,
    /// a pass, pulling over) or holds no lane.
    /// Only where its route runs parallel to ours (`our_dir`, our route's heading beside it),
    /// here, behind and ahead: on a ramp or out of a turn its sideways motion is the route's.
    pub(crate) fn settle_reach(&self, j: usize, our_dir: f64) -> Option<f64> {
        let (b, o) = (&self.actors[j], &self.cur[j]);
        let settling = b.vehicle
            && matches!(b.lateral, Lat::Hold)
            && self.facts.siren_for[j].is_none()
            && (o.off - b.d0).abs() > MIN_OUT
            && (o.d - b.d0).abs() + 1e-6 < (o.off - b.d0).abs();
        let parallel = |ahead: f64| (b.path.point((o.s + ahead).max(0.0), b.d0).1 - our_dir).cos().abs() >= PARALLEL;
        if !settling || !parallel(-RUN_AHEAD) || !parallel(0.0) || !parallel(RUN_AHEAD) {
            return None;
        }
        Some((o.off - b.d0).abs() + OVERSHOOT)
    }
}
