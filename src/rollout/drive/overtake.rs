//! Passing slow moving road users (a cyclist, a tractor): a vehicle that comes up behind one in
//! its lane, going at most half its own goal speed, passes it as it passes what stands in the
//! lane (`Sim::avoid`): into the next lane or across the centre line once oncoming traffic
//! leaves it time, keeping `MOVER_CLEARANCE` from its box, and back once a second ahead of it;
//! only on a straight run with `CLEAR_RUN_M` to spare ahead of it short of any junction.
//! Regression scenes: tests/rollout-cases/car-passes-a-slow-cyclist.scn,
//! tests/rollout-cases/car-behind-a-slow-cyclist-waits-for-an-oncoming-car.scn.

use crate::road::Map;
use crate::rollout::agent::{Actor, Blocking, Drive, Lat, StopGoal};
use crate::rollout::frame::Sim;
use crate::rollout::path::Foot;
use crate::rollout::room::room_at;
use glam::DVec2;

/// Side clearance kept while passing a moving road user (m): a cyclist sways.
pub(crate) const MOVER_CLEARANCE: f64 = 1.2;
/// A road user is slow for one whose goal speed is at least 1 / `SLOW_SHARE` times its speed and
/// `SLOW_DIFF` m/s more.
const SLOW_SHARE: f64 = 0.5;
const SLOW_DIFF: f64 = 3.0;
/// Slower than this (m/s) it is not moving at its own pace but stopping or queued.
const MIN_PACE: f64 = 1.0;
/// Time ahead of it, at its speed, at which a pass turns back in, s.
const RETURN_GAP_S: f64 = 1.0;
/// Below this share of its own goal speed it is held up, not slow by choice.
const PACE_SHARE: f64 = 0.7;
/// Straight road, short of any junction, that a pass needs beyond the slow mover's front, m.
const CLEAR_RUN_M: f64 = 50.0;

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

impl Sim<'_, '_> {
    /// Every slow mover going our way within `look` ahead of vehicle `i` (or beside it, till its
    /// rear is `RETURN_GAP_S` ahead of it), projected onto its route, pushed onto `seen`.
    pub(crate) fn slow_ahead(&self, i: usize, look: f64, seen: &mut Vec<Blocking>) {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let fwd = self.facts.dirs[i];
        for &j in &self.facts.slow {
            let (o, b) = (&self.cur[j], &self.actors[j]);
            let dp = o.pos - st.pos;
            let ahead = dp.dot(fwd);
            let slow = o.v >= MIN_PACE.max(PACE_SHARE * b.goal_speed(o))
                && o.v <= SLOW_SHARE * a.v_goal
                && a.v_goal - o.v >= SLOW_DIFF;
            if j == i
                || !slow
                || self.facts.dirs[j].dot(fwd) < 0.9
                || ahead < -(a.hl + b.hl + o.v * RETURN_GAP_S)
                || ahead > look + a.hl + b.radius
                || fwd.perp_dot(dp).abs() > a.lane_hw + b.radius + a.hw
                || self.exempt(i, j)
            {
                continue;
            }
            let (Foot { s: sj, d: lj, beyond, dir: th }, ext_lon, ext_lat) = self.on_route(i, j, ahead);
            let cr = self.facts.dirs[j].dot(th);
            // No pass toward a junction, nor out of sight round a bend.
            let clear_to = sj + ext_lon + CLEAR_RUN_M;
            let before_junction = a.junction.as_ref().is_some_and(|jn| st.s < jn.exit && clear_to > jn.stop);
            if beyond > 0.5 || before_junction || a.path.straight_run(st.s).is_none_or(|l| l.hi < clear_to) {
                continue;
            }
            // The paving round it, measured where it set out (on a straight road, the same
            // anywhere along it).
            let (lo, hi) = match b.room {
                Some(r) if r.dir.dot(th) > 0.7 => (lj - r.off - r.right, lj - r.off + r.left),
                _ => continue,
            };
            let ext_lon = ext_lon + o.v * RETURN_GAP_S;
            seen.push(Blocking { sj, lj, ext_lon, ext_lat, lo, hi, v: o.v * cr });
        }
    }
}

/// How long until our rear is past the end of an obstacle `dist` ahead of our centre that moves
/// on at `v_obs`, starting at `v` and accelerating at `acc` toward `top`, s (at most a minute).
pub(crate) fn pass_time(v: f64, acc: f64, top: f64, dist: f64, v_obs: f64) -> f64 {
    const STEP: f64 = 0.1;
    let (mut t, mut x, mut u) = (0.0, 0.0, v);
    while x < dist + v_obs * t && t < 60.0 {
        let u1 = (u + acc * STEP).min(top.max(u));
        x += 0.5 * (u + u1) * STEP;
        u = u1;
        t += STEP;
    }
    t
}
