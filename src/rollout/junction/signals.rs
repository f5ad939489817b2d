//! Traffic signals in the rollout: which signal each agent answers to (a vehicle, its approach
//! lane's head; a walker on a crosswalk, that crosswalk's walk signal), and each frame how far it
//! may go while its signal holds it. Scenes: `tests/signal-cases/`.

use crate::road::Map;
use crate::road::signals::{Light, arm_light, walk};
use crate::rollout::agent::{Actor, Drive, Face};
use crate::rollout::frame::Sim;
use crate::rollout::junction::right_of_way::YIELD_BRAKE;
use crate::rollout::kinematics::can_stop;

/// How near a crosswalk's walking line a crossing walker's kerb must be to cross on it, m.
const ON_CROSSWALK_M: f64 = 2.5;

/// Give each vehicle approaching the signalled junction its lane's head, and each walker
/// crossing on a crosswalk that crosswalk's walk signal (lit with the parallel green).
pub(crate) fn assign_signals(map: &Map, actors: &mut [Actor]) {
    let Some(plan) = &map.signals else { return };
    for a in actors.iter_mut() {
        if !matches!(a.drive, Drive::Mover) {
            continue;
        }
        let face = if a.vehicle {
            let lane = a.junction.map(|j| map.connectors[j.conn].from);
            plan.heads.iter().find(|h| Some(h.lane) == lane).map(|h| (h.id.arm, false))
        } else if let Some(kerb) = a.kerb {
            let (p, _) = a.path.point(kerb, 0.0);
            let on = |c: &&crate::road::map::Crosswalk| c.line.project(p).1.abs() < ON_CROSSWALK_M;
            map.crosswalks.iter().find(on).map(|c| (c.arm, true))
        } else {
            None
        };
        a.signal = face.map(|(arm, walk)| Face { cycle: plan.cycle, arm, walk });
    }
}

impl Sim<'_, '_> {
    /// How far agent `i`'s front may go while its signal holds it at `t`: a vehicle short of its
    /// stop line at a red it can stop for (within `YIELD_BRAKE` of its emergency braking), or at a
    /// yellow it can stop for comfortably; a walker at the kerb until the walk signal. `None`
    /// when it may go, and for `signal ignore`.
    pub(crate) fn signal_hold(&self, i: usize, t: f64) -> Option<f64> {
        let a = &self.actors[i];
        let face = a.signal?;
        let st = &self.cur[i];
        if !a.behaviour.signal || st.frozen || self.striking(i, t) {
            return None;
        }
        let shown = match face.walk {
            true if walk(&face.cycle, face.arm, t) => Light::Green,
            true => Light::Red,
            false => arm_light(&face.cycle, face.arm, t),
        };
        if shown == Light::Green {
            return None;
        }
        let (rem, brake) = match a.kerb {
            Some(kerb) => (kerb - (st.s + a.hl), a.lim.brake),
            None => {
                let rem = a.to_line(st)?;
                let brake = if shown == Light::Red { YIELD_BRAKE * a.lim.brake_max } else { a.lim.brake };
                (rem, brake)
            }
        };
        (rem > -0.05 && can_stop(st.v, rem, brake)).then_some(rem.max(0.0))
    }
}
