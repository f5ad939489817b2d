//! Bodies moving on from an impact, as the drivers round them see them (`Sim::wrecks_ahead`): a
//! wreck sliding to rest is no agent to follow or give way to, and its contacts are impacts
//! (`impact::motion`), so the pair loop passes it over (`Sim::exempt`); but a driver sees the
//! crash and brakes for the wreck where it is and where it will come to rest. Passed over
//! till it stopped, a wreck came to rest in a junction 5 m ahead of a van at 8 m/s, which then
//! stopped at -46 m/s2 (tests/rollout-cases/angle-crash-wreck-in-junction-van-brakes-late.scn).

use crate::rollout::agent::State;
use crate::rollout::drive::pair::{Constraint, Step};
use crate::rollout::frame::Sim;
use glam::DVec2;

impl Sim<'_, '_> {
    /// What the bodies sliding from an impact ask of step `s`: each seen standing, as it is now
    /// and as its slide will leave it (`Facts::sliding`), the stricter of the two. `window` and
    /// `reach` bound the projection onto our route as for the pair loop's candidates. A wreck
    /// that slides into our way may be beyond our brakes: we then brake at their limit and meet
    /// it (an impact), never stop short of it harder than they can.
    pub(crate) fn wrecks_ahead(&self, s: &Step, window: (f64, f64), reach: f64) -> Constraint {
        let Step { i, a, st, look, shortest, .. } = *s;
        let mut c = Constraint::FREE;
        if self.facts.sliding.is_empty() || self.wreck.moving(i) {
            return c;
        }
        let fwd = self.facts.dirs[i];
        for &(j, rest, rest_yaw) in &self.facts.sliding {
            if j == i || self.conflict_pair(i, j) {
                continue;
            }
            let b = &self.actors[j];
            let now = self.cur[j];
            let r = look + a.radius + b.radius;
            let poses = [(now.pos, now.yaw, self.facts.dirs[j]), (rest, rest_yaw, DVec2::from_angle(rest_yaw))];
            for (pos, yaw, dir) in poses {
                let dp = pos - st.pos;
                if dp.length_squared() > r * r {
                    continue;
                }
                let o = State { pos, yaw, v: 0.0, ..now };
                let at = a.path.frenet_near(pos, st.s + dp.dot(fwd), window, st.s, reach);
                let k = self.constraint_of(s, j, &o, dir, at);
                c = c.and(Constraint { hard: k.hard.max(shortest), ..k });
            }
        }
        c
    }
}
