//! Traffic signals at a junction: one head per approach lane at its stop line, and the cycle
//! that lights them: two phases (north-south first, then east-west: green, yellow, all red each)
//! or a green stated per approach (a leading or protected phase); and the walk signals of the
//! crosswalks, lit with the green parallel to them.

pub use crate::check::scenario::Light;
use crate::check::scenario::{Arm, LaneId, Signals};
use crate::road::Map;
use serde::{Deserialize, Serialize};

/// The signal of one approach lane, at its stop line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SignalHead {
    /// Index into `Map::lanes`.
    pub lane: usize,
    pub id: LaneId,
    /// 0: north-south approaches, 1: east-west (the two-phase cycle).
    pub phase: u8,
    /// The stop line's ends, world frame.
    pub a: [f64; 2],
    pub b: [f64; 2],
}

/// A junction's signals: the cycle and a head per approach lane.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SignalPlan {
    pub cycle: Signals,
    pub heads: Vec<SignalHead>,
}

/// The phase that gives approaches on `arm` their green.
pub fn phase_of(arm: Arm) -> u8 {
    match arm {
        Arm::North | Arm::South => 0,
        _ => 1,
    }
}

/// What the heads of phase `phase` show at `t` s into the clip.
pub fn light(c: &Signals, phase: u8, t: f64) -> Light {
    let half = c.green + c.yellow + c.all_red;
    let at = (t + c.offset).rem_euclid(2.0 * half) - f64::from(phase) * half;
    let at = if at < 0.0 { at + 2.0 * half } else { at };
    if at < c.green {
        Light::Green
    } else if at < c.green + c.yellow {
        Light::Yellow
    } else {
        Light::Red
    }
}

/// The index of approach `arm` in `Signals::windows` (north, east, south, west).
fn slot(arm: Arm) -> Option<usize> {
    [Arm::North, Arm::East, Arm::South, Arm::West].iter().position(|a| *a == arm)
}

/// The two arms whose traffic crosses that of `arm`.
pub fn crossing(arm: Arm) -> [Arm; 2] {
    match arm {
        Arm::North | Arm::South => [Arm::East, Arm::West],
        _ => [Arm::North, Arm::South],
    }
}

/// What the heads of the approaches on `arm` show at `t`: their own green, then yellow, then red
/// for the rest of the cycle where greens are stated per approach, else their phase's light.
pub fn arm_light(c: &Signals, arm: Arm, t: f64) -> Light {
    if c.two_phase() {
        return light(c, phase_of(arm), t);
    }
    let Some([on, off]) = slot(arm).and_then(|k| c.windows[k]) else { return Light::Red };
    let at = (t + c.offset).rem_euclid(c.period);
    if (on..off).contains(&at) {
        Light::Green
    } else if (off..off + c.yellow).contains(&at) {
        Light::Yellow
    } else {
        Light::Red
    }
}

/// Whether walkers on the crosswalk across arm `arm` have the walk signal at `t`: while the
/// traffic parallel to them has green and the arm they cross shows red.
pub fn walk(c: &Signals, arm: Arm, t: f64) -> bool {
    if c.two_phase() {
        return light(c, 1 - phase_of(arm), t) == Light::Green;
    }
    arm_light(c, arm, t) == Light::Red && crossing(arm).iter().any(|a| arm_light(c, *a, t) == Light::Green)
}

/// The heads of `map`'s stop lines under cycle `cycle`.
pub fn plan(cycle: Signals, map: &Map) -> SignalPlan {
    let heads = map
        .stop_lines
        .iter()
        .filter_map(|s| {
            let l = map.lanes.get(s.lane)?;
            Some(SignalHead { lane: s.lane, id: l.id, phase: phase_of(l.id.arm), a: [s.a.x, s.a.y], b: [s.b.x, s.b.y] })
        })
        .collect();
    SignalPlan { cycle, heads }
}

impl SignalPlan {
    /// Every head's light at `t`, in `heads` order.
    pub fn lights(&self, t: f64) -> impl Iterator<Item = (&SignalHead, Light)> {
        self.heads.iter().map(move |h| (h, arm_light(&self.cycle, h.id.arm, t)))
    }
}
