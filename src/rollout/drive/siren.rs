//! Making way for an emergency vehicle on the road (`Sim::siren_for`): a vehicle it closes in on
//! from behind, and on a two-lane road one it comes toward, pulls over and stops till it has
//! passed. At junctions cross traffic holds for it as well (`Actor::yield_to`).

use crate::rollout::agent::{Drive, Lat, Yield};
use crate::rollout::drive::{PASS_CLEARANCE, PASS_MAX_SHIFT};
use crate::rollout::frame::Sim;
use crate::rollout::path::Foot;

/// How far behind (or, oncoming, ahead) an emergency vehicle is heard and made way for, m; and
/// at least this many seconds away at the speed it closes in.
const HEARD_M: f64 = 60.0;
const HEARD_S: f64 = 6.0;
/// The speed a vehicle keeps at most while it moves over, before it stops, m/s.
pub(crate) const MOVE_OVER_SPEED: f64 = 8.0;

impl Sim<'_, '_> {
    /// The emergency vehicle, siren on and moving, that vehicle `i` makes way for this frame: the
    /// nearest that comes up behind it in its lane and has not yet passed, or on a two-lane road
    /// comes toward it. It moves right (onto the shoulder where there is one) and stops there
    /// (`Yield`). One in the next lane of a wider road leaves it be: the emergency vehicle
    /// passes in its own. `None` for emergency vehicles, agents of a staged conflict, vehicles with a
    /// lateral goal of their own, and vehicles in a junction.
    pub(crate) fn siren_for(&self, i: usize) -> Option<Yield> {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        if !a.vehicle || a.emergency || a.in_conflict || a.blocker || !matches!(a.lateral, Lat::Hold) {
            return None;
        }
        if !matches!(a.drive, Drive::Mover) || self.striker[i].is_some() {
            return None;
        }
        // From its stop line until it has left the junction it clears the junction instead
        // (`Sim::yield_state`): pulled over and stopped there, it would stand in the way.
        if let Some(j) = a.junction
            && st.s + a.hl > j.stop - 0.3
            && st.s - a.hl < j.exit
        {
            return None;
        }
        let fwd = self.facts.dirs[i];
        let mut best: Option<(f64, Yield)> = None;
        for &e in &self.facts.sirens {
            let (o, b) = (&self.cur[e], &self.actors[e]);
            if e == i || (o.v < 1.0 && b.v_goal < 1.0) {
                continue;
            }
            let dp = o.pos - st.pos;
            let along = dp.dot(fwd);
            let cos = self.facts.dirs[e].dot(fwd);
            let reach = HEARD_M.max(HEARD_S * (o.v + st.v)) + a.hl + b.hl;
            if dp.length_squared() > reach * reach || cos.abs() < 0.7 {
                continue;
            }
            let Foot { s: se, d: le, beyond, .. } = a.path.frenet(o.pos, st.s + along);
            // In our lane, not to our right (moving right would be moving toward it: one
            // passing on our right in the next lane drew the car in the inner lane over into its
            // way); or coming toward us in the next lane on a two-lane road.
            // Once over for it, we stay over till it has passed, wherever across it passes: it
            // swings out of our lane to get by, and a car that took that for leave to go on
            // steered back into its way (tests/rollout-cases/ambulance-passes-a-car-pulled-over-for-it.scn).
            let over_for = self.facts.siren_for[i].is_some_and(|y| y.to == e);
            let (lo, hi) = match (cos > 0.0, over_for) {
                (true, false) => (-0.5, a.lane_hw),
                (true, true) => (-0.5, f64::INFINITY),
                _ => (0.0, 3.0 * a.lane_hw),
            };
            if beyond > 0.5 || le - a.d0 < lo || le - a.d0 > hi {
                continue;
            }
            let ahead = se - st.s;
            // Behind us and not yet past (its rear ahead of our front); or coming toward us on
            // a two-lane road, not yet by.
            let heard = if cos > 0.0 { ahead < a.hl + b.hl + 1.0 } else { a.single && ahead > -(a.hl + b.hl) };
            // Coming up behind, it must find room to pass once we are over (`Sim::pass_offset`):
            // pulled over only a little (a bus in a lane without shoulder), we would stand in its
            // way, and it waits behind us; we go on instead.
            let room = cos < 0.0 || a.pull + a.hw + PASS_CLEARANCE + b.hw - le <= PASS_MAX_SHIFT;
            if heard && room && best.is_none_or(|(d, _)| ahead.abs() < d) {
                best = Some((ahead.abs(), Yield { to: e, offset: a.pull }));
            }
        }
        best.map(|(_, y)| y)
    }
}
