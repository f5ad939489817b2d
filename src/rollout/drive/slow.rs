//! Which road users are slow movers that others may pass (`drive/overtake.rs`), decided once at
//! set-up from goals and goal speeds.

use crate::road::Map;
use crate::rollout::agent::{Actor, Drive, Lat, StopGoal};
use crate::rollout::room::room_at;
use glam::DVec2;

/// A road user is slow for one whose goal speed is at least 1 / `SLOW_SHARE` times its speed (and
/// `overtake::SLOW_DIFF` m/s more).
pub(crate) const SLOW_SHARE: f64 = 0.5;
/// Slower than this (m/s) it is not moving at its own pace but stopping or queued.
pub(crate) const MIN_PACE: f64 = 1.0;

/// Whether `b` may be passed as a slow mover where the fastest vehicle's goal speed is
/// `fastest`: a vehicle or bicycle that drives on in its lane at a goal speed of its own (no
/// stop goal, no turn, no lateral move, no staged crash), at most half that speed.
fn slow(b: &Actor, fastest: f64) -> bool {
    b.vehicle
        && matches!(b.drive, Drive::Mover)
        && !b.blocker
        && !b.emergency
        && !b.in_conflict
        && matches!((&b.lateral, &b.stop), (Lat::Hold, StopGoal::None))
        && b.turn_goal.is_none()
        && b.v_goal >= MIN_PACE
        && b.v_goal <= SLOW_SHARE * fastest
}

fn fastest(actors: &[Actor]) -> f64 {
    actors.iter().filter(|a| a.vehicle).map(|a| a.v_goal).fold(0.0, f64::max)
}

/// The paving round every slow mover where it starts (`Actor::room`), at set-up.
pub(crate) fn measure_rooms(map: &Map, actors: &mut [Actor]) {
    let top = fastest(actors);
    for b in actors.iter_mut().filter(|b| b.room.is_none() && slow(b, top)) {
        b.room = room_at(map, DVec2::new(b.init.x, b.init.y));
    }
}

/// Agents that may be passed as slow movers (`slow`), from a lane whose paving was measured.
pub(crate) fn slow_movers(actors: &[Actor]) -> Vec<usize> {
    let top = fastest(actors);
    (0..actors.len()).filter(|&j| actors[j].room.is_some() && slow(&actors[j], top)).collect()
}
