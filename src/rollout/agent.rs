//! The agents' plain data: what each agent is (`Actor`, set up once), where it is (`State`, one
//! per frame), and what joins two of them (`Conf`, a staged conflict; `Crossing`, a shared
//! junction zone). Nothing here decides anything.

use crate::check::scenario::{Behaviour, Keyframe, Trigger, Turn};
use crate::geom::Obb;
use crate::place::Pose;
use crate::road::route::Junction;
use crate::rollout::junction::bend::Bend;
use crate::rollout::path::Path;
use crate::rollout::room::Room;
use crate::rollout::{Limits, TrackAgent};
use glam::DVec2;

pub(crate) enum Drive {
    Static,
    Replay(Vec<Keyframe>),
    Mover,
}

pub(crate) enum Lat {
    Hold,
    Shift {
        target: f64,
        dur: f64,
    },
    /// Ease to `target` once agent `who` closes in from behind.
    Away {
        who: usize,
        target: f64,
        dur: f64,
    },
}

pub(crate) enum StopGoal {
    None,
    /// Front bumper stops at this arc length.
    Front(f64),
    /// Queue behind agent (track index).
    Behind(usize),
    /// Centre stops at this arc length.
    Centre(f64),
}

pub(crate) struct Actor {
    pub drive: Drive,
    /// Each door that moves, with its angle (degrees) per frame: an obstacle of its own while
    /// open (`drive/doors.rs`, `rollout/body.rs`).
    pub doors: Vec<(crate::check::scenario::Door, Vec<f64>)>,
    /// Heading follows the path with bounded turning radius (vehicles, bicycles); otherwise
    /// holonomic.
    pub vehicle: bool,
    pub hl: f64,
    pub hw: f64,
    pub radius: f64,
    /// Smallest turning radius of the box centre, m (`crate::rollout::min_turn_radius`); vehicles only.
    pub r_min: f64,
    pub lim: Limits,
    pub path: Path,
    pub init: Pose,
    pub s0: f64,
    pub d0: f64,
    pub v0: f64,
    pub v_goal: f64,
    pub v_hold: f64,
    pub start: f64,
    /// What starts its goal besides `start` (`rollout::trigger`), `who` a track index.
    pub trigger: Option<Trigger>,
    /// Attention and compliance: whether it gives way and holds at its stop line, its reaction
    /// time, its speeding.
    pub behaviour: Behaviour,
    /// Later goal phases, in order: a goal speed from each's start (`rollout::trigger`).
    pub phases: Vec<Stage>,
    pub lateral: Lat,
    /// The goal phase (`State::stage`) from which `Lat::Shift` runs: 0 for a lane change in the
    /// first goal, k for one in its k-th phase (the route is the target lane from the start).
    pub shift_stage: u8,
    pub stop: StopGoal,
    pub info: TrackAgent,
    /// An emergency vehicle (a kind in or derived from `EMERGENCY_KINDS`): cross traffic holds
    /// for it.
    pub emergency: bool,
    /// The first junction on the route, if any.
    pub junction: Option<Junction>,
    /// Emergency vehicles (track indices) whose junction path crosses this agent's: while one
    /// approaches or is inside the junction, this agent holds at its stop line.
    pub yield_to: Vec<usize>,
    /// Where a placed agent is declared (`None` for background traffic): E0204's and E0207's
    /// label.
    pub span: Option<crate::source::Span>,
    /// A vehicle's `turn` goal: `check_turns` refuses a turn whose swept box leaves the road.
    pub turn_goal: Option<Turn>,
    /// Vehicles whose junction path crosses or merges into this one's (`assign_crossings`): who
    /// enters the shared zone first is settled by the right-of-way rule (`Sim::gives_way`).
    pub crossings: Vec<Crossing>,
    /// A walker's `cross` goal: the arc length along its walk where its front reaches the road,
    /// where it waits for a gap (`Sim::kerb_hold`); `None` for everyone else and for walkers in
    /// a staged conflict.
    pub kerb: Option<f64>,
    /// One of the pair of a staged conflict: a latch may stop it dead, so followers keep the
    /// gap to stop behind it at once (`Sim::drive`).
    pub in_conflict: bool,
    /// The lane from which its route enters its first junction (vehicles with `crossings`):
    /// of those approaching through one lane, only the first can be next into the junction.
    pub approach: Option<usize>,
    /// A vehicle's sweep through its first junction (`assign_bends`).
    pub bend: Option<std::sync::Arc<Bend>>,
    /// The traffic signal it answers to (`assign_signals`).
    pub signal: Option<Face>,
    /// A flagger's stop/go program (`rollout::flagger`).
    pub flag: Option<Box<FlagRun>>,
    /// The flaggers ahead that this vehicle answers to (`assign_flaggers`).
    pub flaggers: Vec<Facing>,
    /// Stands where it is for good (an object, a static kind, a vehicle with neither speed nor
    /// a goal that moves it): vehicles pass it where there is room (`Sim::avoid`).
    pub blocker: bool,
    /// The paving round a blocker standing in a lane.
    pub room: Option<Room>,
    /// A vehicle's offset when it pulls over: onto the shoulder, or to the right of its lane.
    pub pull: f64,
    /// Half the width of a vehicle's start lane, m.
    pub lane_hw: f64,
    /// A vehicle's lane is the only one of its direction (a two-lane road).
    pub single: bool,
    /// Driven backwards (`drive::reverse`): its state's heading is the body's turned half round.
    pub reverse: bool,
}

/// A goal phase as the rollout runs it: its goal speed, from its start time once its trigger
/// (its agent a track index) holds.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stage {
    pub v_goal: f64,
    pub start: f64,
    pub trigger: Option<Trigger>,
    /// Stops this far on from where the phase that states it starts (`State::stage_s`), m;
    /// later phases keep it.
    pub stop_after: Option<f64>,
    /// The phase states its own stop: `State::stage_s` is taken at its start.
    pub own_stop: bool,
    /// Pulls over (`Actor::pull`), from this phase on.
    pub pull: bool,
}

/// The stretch that two vehicles' junction paths share, seen from one of them: route arc
/// lengths of its box centre between which its box may touch the other's path.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Crossing {
    pub other: usize,
    /// This agent's zone on its own route: its centre from `enter` to `leave`.
    pub enter: f64,
    pub leave: f64,
    /// The other agent's zone on the other's route.
    pub other_enter: f64,
    pub other_leave: f64,
    /// Where the zone begins for each of the two before a sweep moved it back (`enter` and
    /// `other_enter` start where one's sweep first reaches over the other's approach): where
    /// their paths themselves come within reach of each other. Short of it one that can halt
    /// is not inside (`Sim::zone_rank`).
    pub meet: f64,
    pub other_meet: f64,
    /// Set where the two are placed too near their zones for either to stop short of its own
    /// (`order_crossings`): `Some(true)` when this agent gives way, braking as hard as it may,
    /// `Some(false)` when the other does; the rule's order otherwise.
    pub placed_yield: Option<bool>,
    /// One of the two is an emergency vehicle the other yields to (`Actor::yield_to`).
    pub emergency: bool,
    /// The two paths run on together here, the same way (a merge, a roundabout's ring), rather
    /// than cross: one that has gone in ahead is followed, not waited out.
    pub merge: bool,
}

impl Actor {
    /// How far its front, at `st`, is short of where it halts for its junction (0.3 m before
    /// the stop line, else the junction entry); `None` without a junction.
    pub(crate) fn to_line(&self, st: &State) -> Option<f64> {
        self.junction.map(|j| j.stop - 0.3 - (st.s + self.hl))
    }

    /// Whether one clearing a junction for an emergency vehicle goes on past this vehicle,
    /// predicted to cross its way: it gives the junction to the emergency vehicle too (held at
    /// its line, or clearing), or it is still outside its junction, where the right-of-way rule
    /// holds it. Not one turning inside the junction that nothing holds: a car going straight to
    /// clear for an ambulance drove into a U-turn's loop at 7 m/s.
    pub(crate) fn cleared_past(&self, st: &State) -> bool {
        self.vehicle && (!self.yield_to.is_empty() || self.to_line(st).is_none_or(|line| line > -0.05))
    }

    /// Whether its goal has started by `t`: its start time has come and its trigger, if any, has
    /// fired.
    #[inline]
    pub(crate) fn active(&self, st: &State, t: f64) -> bool {
        st.go && t >= self.start - 1e-9
    }

    /// Its goal speed in the phase it is in.
    #[inline]
    pub(crate) fn goal_speed(&self, st: &State) -> f64 {
        match st.stage {
            0 => self.v_goal,
            k => self.phases[k as usize - 1].v_goal,
        }
    }

    /// The goal phase it is in, if any.
    #[inline]
    pub(crate) fn stage(&self, st: &State) -> Option<&Stage> {
        st.stage.checked_sub(1).and_then(|k| self.phases.get(k as usize))
    }

    pub(crate) fn obb(&self, st: &State) -> Obb {
        Obb { center: st.pos, yaw: st.yaw, length: 2.0 * self.hl, width: 2.0 * self.hw }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct State {
    pub pos: DVec2,
    pub yaw: f64,
    pub v: f64,
    /// Arc length along the route (of the box centre's projection, for vehicles).
    pub s: f64,
    /// Lateral offset the lateral goal asks for now (m, left of the route).
    pub d: f64,
    /// Lateral offset the agent is actually at; a vehicle steers toward `d` and lags it.
    pub off: f64,
    pub phase: f64,
    pub triggered: bool,
    pub stopped: bool,
    pub frozen: bool,
    /// Holding back for another agent under the right-of-way rule (at its stop line or short of
    /// the shared zone) or at the kerb: waiting by choice, ready to go, not blocked.
    pub give_way: bool,
    /// Its trigger has fired (always, for one without a trigger).
    pub go: bool,
    /// How long a need to brake for someone has gone unanswered, s (`Behaviour::reaction`).
    pub alarm: f64,
    /// How many of its goal phases have started (`Actor::phases`).
    pub stage: u8,
    /// When its trigger fired, s (0 without one): a triggered track counts its keyframe times
    /// from it.
    pub since: f64,
    /// Arc length where the goal phase with the stop it keeps started (`Stage::stop_after`).
    pub stage_s: f64,
    /// A flagger's step (`Sim::fire_flags`).
    pub flag: u8,
}

/// A conflict with its agents as track indices.
#[derive(Clone)]
pub(crate) struct Conf {
    pub index: usize,
    pub af: usize,
    pub st: usize,
    pub c: crate::check::scenario::Conflict,
    /// A near miss (`rollout::staging::near`): `c` then carries the pair, the side and the time;
    /// it is staged without contact.
    pub near: Option<Near>,
}

/// What a near miss asks of its passer (`af`) at the pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Near {
    /// Alongside `st`, its box this far from `st`'s, m.
    Gap(f64),
    /// Behind `st` in its line, closing to this constant-velocity time to collision, s.
    Ttc(f64),
    /// Across `st`'s path, closing to this constant-velocity time to collision, s
    /// (`staging::across`).
    Across(f64),
}

pub(crate) fn initial(a: &Actor) -> State {
    let v = match a.drive {
        Drive::Mover => a.v0,
        _ => 0.0,
    };
    State {
        pos: DVec2::new(a.init.x, a.init.y),
        yaw: a.init.yaw,
        v,
        s: a.s0,
        d: a.d0,
        off: a.d0,
        phase: 0.0,
        triggered: false,
        stopped: false,
        frozen: false,
        give_way: false,
        go: a.trigger.is_none(),
        since: 0.0,
        stage_s: 0.0,
        alarm: 0.0,
        stage: 0,
        flag: 0,
    }
}

/// `Sim::zone_rank`'s answer.
pub(crate) type Rank = Option<ZoneRank>;

/// An agent's standing toward a zone it shares (`Sim::zone_rank`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ZoneRank {
    /// 0 inside, 1 too close to stop, 2 approaching, 3 stopped by anything but this rule.
    pub order: u8,
    /// Its time to the zone, s.
    pub eta: f64,
    /// How far its front may go while it holds, m.
    pub rem: f64,
}

/// One obstacle seen from our route.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Blocking {
    /// Its station and offset on our route, m.
    pub sj: f64,
    pub lj: f64,
    /// Its half extents along and across our route, m.
    pub ext_lon: f64,
    pub ext_lat: f64,
    /// The paving round it, as offsets on our route.
    pub lo: f64,
    pub hi: f64,
    /// Its speed along our route: 0 standing, a slow mover's pace (`drive::overtake`), m/s.
    pub v: f64,
}

/// How a vehicle makes way for an emergency vehicle (`Sim::siren_for`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Yield {
    /// The emergency vehicle.
    pub to: usize,
    /// The offset it moves over to.
    pub offset: f64,
}

/// The signal an agent answers to: the cycle, and the arm whose approach's light lets a
/// vehicle go, or whose crosswalk's walk signal lets a walker cross.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Face {
    pub cycle: crate::check::scenario::Signals,
    pub arm: crate::check::scenario::Arm,
    pub walk: bool,
}

// ---- flaggers: plain data here, run by `rollout::flagger` ----

/// A flagger's program as the rollout runs it: its steps (triggers on track indices).
#[derive(Clone, Debug)]
pub(crate) struct FlagRun {
    pub steps: Vec<crate::check::scenario::FlagStep>,
    pub cycle: bool,
    /// A cycle's length, s.
    pub period: f64,
    /// The lanes it faces, as a placement names them (`west.in[1]`).
    pub faces: Vec<String>,
}

/// A flagger a vehicle answers to: its track index and its station on the vehicle's route.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Facing {
    pub flagger: usize,
    pub at: f64,
}

/// An empty record per flagger of `actors` (`Tracks::flags`).
pub(crate) fn flag_tracks(actors: &[Actor], frames: usize) -> Vec<crate::rollout::FlagTrack> {
    let of = |(i, a): (usize, &Actor)| {
        let run = a.flag.as_deref()?;
        Some(crate::rollout::FlagTrack { agent: i, faces: run.faces.clone(), go: Vec::with_capacity(frames) })
    };
    actors.iter().enumerate().filter_map(of).collect()
}
