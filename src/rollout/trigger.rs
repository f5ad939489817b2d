//! Triggers (`start when ...`): each frame, before anyone steps, the conditions of agents whose
//! goal has not started are read on the frame's states, and those that hold start their goals.
//! All are read before any is set, so the order of agents does not matter.

use crate::check::scenario::{Mark, Trigger};
use crate::rollout::agent::Actor;
use crate::rollout::frame::Sim;
use glam::DVec2;

/// Trigger `t` with its agent turned from a scenario index into a track index; `None` where
/// that agent has no track.
pub(crate) fn on_tracks(t: Trigger, track_of: &[Option<usize>]) -> Option<Trigger> {
    let who = track_of.get(t.who()).copied().flatten()?;
    Some(match t {
        Trigger::Within { m, .. } => Trigger::Within { who, m },
        Trigger::Ttc { s, .. } => Trigger::Ttc { who, s },
        Trigger::Headway { s, .. } => Trigger::Headway { who, s },
        Trigger::Reaches { mark, .. } => Trigger::Reaches { who, mark },
        Trigger::Starts { .. } => Trigger::Starts { who },
    })
}

impl Sim<'_, '_> {
    /// Start the goals whose triggers hold on this frame's states (`State::go`), and the goal
    /// phases whose start has come (`State::stage`).
    pub(crate) fn fire_triggers(&mut self, t: f64) {
        if !self.any_trigger {
            return;
        }
        let fired = &mut self.facts.fired;
        fired.clear();
        for (i, (a, st)) in self.actors.iter().zip(&self.cur).enumerate() {
            if let Some(tr) = a.trigger
                && !st.go
                && holds(self.actors, &self.cur, i, tr, t)
            {
                fired.push((i, false));
            }
            // The next phase, once the goal before it has started: one phase per step.
            if let Some(p) = a.phases.get(st.stage as usize)
                && a.active(st, t)
                && t >= p.start - 1e-9
                && p.trigger.is_none_or(|tr| holds(self.actors, &self.cur, i, tr, t))
            {
                fired.push((i, true));
            }
        }
        for &(i, phase) in &self.facts.fired {
            if phase {
                let st = &mut self.cur[i];
                st.stage += 1;
                if self.actors[i].stage(st).is_some_and(|p| p.own_stop) {
                    st.stage_s = st.s;
                }
            } else {
                self.cur[i].go = true;
                self.cur[i].since = t;
            }
        }
    }
}

/// Whether agent `i`'s trigger `tr` holds on `states` at `t`.
fn holds(actors: &[Actor], states: &[crate::rollout::agent::State], i: usize, tr: Trigger, t: f64) -> bool {
    let who = tr.who();
    let (a, me, b, o) = (&actors[i], &states[i], &actors[who], &states[who]);
    let d = me.pos - o.pos;
    let dist = d.length();
    match tr {
        Trigger::Within { m, .. } => dist <= m,
        Trigger::Ttc { s, .. } => {
            // Closing speed along the line between them; the gap is between bounding circles.
            let gap = (dist - a.radius - b.radius).max(0.0);
            let rel = DVec2::from_angle(o.yaw) * o.v - DVec2::from_angle(me.yaw) * me.v;
            let closing = if dist > 1e-9 { rel.dot(d) / dist } else { 0.0 };
            closing > 1e-6 && gap <= s * closing
        }
        Trigger::Headway { s, .. } => {
            // We must be ahead of it, within its width and ours of its line of travel.
            let fwd = DVec2::from_angle(o.yaw);
            let (along, side) = (d.dot(fwd), d.perp_dot(fwd).abs());
            let gap = (along - b.hl - a.hl).max(0.0);
            along > 0.0 && side <= a.radius + b.hw && o.v > 0.05 && gap <= s * o.v
        }
        Trigger::Reaches { mark: Mark::StopLine, .. } => b.junction.is_some_and(|j| o.s + b.hl >= j.stop - 0.5),
        Trigger::Reaches { mark: Mark::Kerb, .. } => b.kerb.is_some_and(|k| o.s + b.hl >= k - 0.1),
        Trigger::Starts { .. } => b.active(o, t),
    }
}
