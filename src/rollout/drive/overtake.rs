//! Passing slow moving road users (a cyclist, a tractor): a vehicle that comes up behind one in
//! its lane, going at most half its own goal speed, passes it as it passes what stands in the
//! lane (`Sim::avoid`): into the next lane or across the centre line once oncoming traffic
//! leaves it time, keeping `MOVER_CLEARANCE` from its box, and back once a second ahead of it;
//! only on a straight run with `CLEAR_RUN_M` to spare ahead of it short of any junction.
//! Regression scenes: tests/rollout-cases/car-passes-a-slow-cyclist.scn,
//! tests/rollout-cases/car-behind-a-slow-cyclist-waits-for-an-oncoming-car.scn.

use crate::rollout::agent::Blocking;
use crate::rollout::frame::Sim;
use crate::rollout::path::Foot;

use super::slow::{MIN_PACE, SLOW_SHARE};

/// Slow also means at least this much slower than the passer's goal speed, m/s.
const SLOW_DIFF: f64 = 3.0;
/// Time ahead of it, at its speed, at which a pass turns back in, s.
const RETURN_GAP_S: f64 = 1.0;
/// Below this share of its own goal speed it is held up, not slow by choice.
const PACE_SHARE: f64 = 0.7;
/// Straight road, short of any junction, that a pass needs beyond the slow mover's front, m.
const CLEAR_RUN_M: f64 = 50.0;

/// Side clearance kept while passing a moving road user (m): a cyclist sways.
pub(crate) const MOVER_CLEARANCE: f64 = 1.2;

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
