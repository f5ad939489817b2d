//! The controller and the frame loop. Agents are set up once (routes, goals, limits); every frame
//! then computes each agent's next state from everyone's current state (a Jacobi update, so the
//! result does not depend on agent order), undoes moves that would overlap, and latches crashes.

use super::path::{Hermite, Line, Path, Resampler};
use super::route::{Junction, RUN_OUT, chain, find_lane, side_lane};
use super::stage::{self, Plan};
use super::traffic;
use super::{ImpactRecord, Limits, TrackAgent, Tracks, limits};
use crate::check::scenario::{Class, EMERGENCY_KINDS, Keyframe, Lateral, Motion, Side, Stop, Turn};
use crate::diag::Diagnostic;
use crate::geom::{Obb, Projector, wrap_angle};
use crate::place::{Placed, Pose};
use crate::road::Map;
use crate::sample::Concrete;
use glam::DVec2;

/// Pace of a `cross` goal given no speed at all, m/s.
const WALK_SPEED: f64 = 1.4;
/// How much tighter than a vehicle's turning radius a junction path may turn before the turn is
/// refused (E0204). Up to it the vehicle swings wider across the junction area (a sedan's U-turn
/// on a four_way without median: its path turns on 1.7 m, the sedan on 4.0 m); beyond it (a bus
/// on 10.3 m) the arc leaves the road, as the template property test checks.
const TURN_SLACK: f64 = 3.0;
/// Lateral manoeuvre durations, s.
const LANE_CHANGE_S: f64 = 4.0;
const ASIDE_S: f64 = 2.5;

pub(super) enum Drive {
    Static,
    Replay(Vec<Keyframe>),
    Mover,
}

pub(super) enum Lat {
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

pub(super) enum StopGoal {
    None,
    /// Front bumper stops at this arc length.
    Front(f64),
    /// Queue behind agent (track index).
    Behind(usize),
    /// Centre stops at this arc length.
    Centre(f64),
}

pub(super) struct Actor {
    pub drive: Drive,
    /// Heading follows the path with bounded turning radius (vehicles, bicycles); otherwise
    /// holonomic.
    pub vehicle: bool,
    pub hl: f64,
    pub hw: f64,
    pub radius: f64,
    /// Smallest turning radius of the box centre, m (`super::min_turn_radius`); vehicles only.
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
    pub lateral: Lat,
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
}

/// How far a vehicle's box reaches beyond the band its path's centre sweeps through its first
/// junction, metre by metre along its route (`assign_bends`): a U-turn driven wide on an
/// ambulance's turning radius loops out 10 m and more at its apex, far beyond what the path's
/// curvature says, and not at all past it.
#[derive(Clone, Debug)]
pub(super) struct Bend {
    /// Route arc length of the first metre.
    pub from: f64,
    /// Per metre from `from`: the reach to the right and to the left.
    pub reach: Vec<(f64, f64)>,
    /// The widest reach to either side anywhere, at least the corners' swing in the tightest
    /// bend (`sweep`).
    pub widest: f64,
    /// The box stretched over its reach, a metre of path each, where it reaches beyond the band
    /// (`sweep_entry`), and their bounding box (lower and upper corners).
    pub slices: Vec<(f64, Obb)>,
    pub bounds: (DVec2, DVec2),
    /// `reach`'s widest over every run of `2^k` metres from each metre, for `k` from 1
    /// (`index`): `within` is asked per agent per frame over up to the look-ahead.
    pub spans: Vec<Vec<(f64, f64)>>,
    /// The run's box centre, step by step: route arc length, position, heading (`Bend::pose`).
    pub poses: Vec<(f64, DVec2, f64)>,
    /// The bounding box of the run's boxes (lower and upper corners; `touches`).
    pub run_bounds: (DVec2, DVec2),
}

impl Bend {
    /// The widest reach to the right and to the left between route arc lengths `lo` and `hi`.
    fn within(&self, lo: f64, hi: f64) -> (f64, f64) {
        let Some((a, b)) = self.metres(lo, hi) else { return (0.0, 0.0) };
        // The widest of a set of reaches is the same number whatever the order it is taken in
        // (each is 0 or above, never NaN): two overlapping spans cover the range.
        let k = (b - a + 1).ilog2() as usize;
        if k == 0 || k > self.spans.len() {
            return self.reach[a..=b].iter().fold((0.0, 0.0), |(r, l), &(x, y)| (f64::max(r, x), f64::max(l, y)));
        }
        let t = &self.spans[k - 1];
        let ((r0, l0), (r1, l1)) = (t[a], t[b + 1 - (1 << k)]);
        let widest = (f64::max(f64::max(0.0, r0), r1), f64::max(f64::max(0.0, l0), l1));
        debug_assert_eq!(
            widest,
            self.reach[a..=b].iter().fold((0.0, 0.0), |(r, l), &(x, y)| (f64::max(r, x), f64::max(l, y)))
        );
        widest
    }

    /// The indices into `reach` of the metres covering route arc lengths `lo` to `hi`, if any.
    fn metres(&self, lo: f64, hi: f64) -> Option<(usize, usize)> {
        let last = self.reach.len() as f64 - 1.0;
        // `max` and `min` take the number over a NaN: a and b are never NaN.
        let (a, b) = ((lo - self.from).floor().max(0.0), (hi - self.from).ceil().min(last));
        (a <= b).then_some((a as usize, b as usize))
    }

    /// Fill `spans` from `reach`.
    fn index(&mut self) {
        self.spans.clear();
        let mut h = 1;
        while 2 * h <= self.reach.len() {
            let prev = self.spans.last().unwrap_or(&self.reach);
            let next: Vec<(f64, f64)> = (0..=prev.len() - 1 - h)
                .map(|i| (f64::max(prev[i].0, prev[i + h].0), f64::max(prev[i].1, prev[i + h].1)))
                .collect();
            self.spans.push(next);
            h *= 2;
        }
    }

    /// The box centre's pose in the run where its centre is at route arc length `s`, `None`
    /// outside the run.
    fn pose(&self, s: f64) -> Option<(DVec2, f64)> {
        let k = self.poses.partition_point(|q| q.0 <= s);
        let (p, q) = (self.poses.get(k.checked_sub(1)?)?, self.poses.get(k)?);
        let t = (s - p.0) / (q.0 - p.0);
        Some((p.1.lerp(q.1, t), p.2 + wrap_angle(q.2 - p.2) * t))
    }

    /// The first route arc length from `lo` to `hi` at which the run's box of vehicle `a`
    /// (whose run it is) meets `theirs`, at the run's steps.
    fn touches(&self, a: &Actor, theirs: &Obb, lo: f64, hi: f64) -> Option<f64> {
        if clear_of(self.run_bounds, theirs) {
            return None;
        }
        let k = self.poses.partition_point(|q| q.0 < lo);
        let (length, width) = (2.0 * a.hl, 2.0 * a.hw);
        let reach = 0.5 * (length.hypot(width) + theirs.length.hypot(theirs.width));
        self.poses[k..]
            .iter()
            .take_while(|q| q.0 <= hi)
            .filter(|q| q.1.distance_squared(theirs.center) < reach * reach)
            .find(|q| Obb { center: q.1, yaw: q.2, length, width }.overlaps(theirs))
            .map(|q| q.0)
    }

    /// The route arc length of the first metre from `lo` to `hi` whose slice meets `theirs`.
    fn meets(&self, theirs: &Obb, lo: f64, hi: f64) -> Option<f64> {
        if clear_of(self.bounds, theirs) {
            return None;
        }
        let (c, r) = (theirs.center, 0.5 * theirs.length.hypot(theirs.width));
        let near = |q: &Obb| {
            let rq = r + 0.5 * q.length.hypot(q.width);
            q.center.distance_squared(c) < rq * rq
        };
        let (at, _) = self.slices.iter().find(|(s, q)| *s + 1.0 > lo && *s < hi && near(q) && q.overlaps(theirs))?;
        Some(*at)
    }
}

/// Whether box `theirs`, within its circumscribed circle, lies wholly outside the axis-aligned
/// `(lower, upper)` corners `bounds`: then nothing inside them can meet it.
fn clear_of((min, max): (DVec2, DVec2), theirs: &Obb) -> bool {
    let (c, r) = (theirs.center, 0.5 * theirs.length.hypot(theirs.width));
    c.x + r < min.x || c.x - r > max.x || c.y + r < min.y || c.y - r > max.y
}

/// The stretch that two vehicles' junction paths share, seen from one of them: route arc
/// lengths of its box centre between which its box may touch the other's path.
#[derive(Clone, Copy, Debug)]
pub(super) struct Crossing {
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

/// Two junction paths whose headings at a shared stretch differ by less than about 26 degrees
/// run on together there (`Crossing::merge`).
const MERGE_COS: f64 = 0.9;

/// Two paths running the same way count as one merging into the other only where they come
/// this near: one lane (a ring a car enters), not two lanes side by side.
const JOIN_M: f64 = 1.0;

/// How far ahead of an emergency vehicle the junction is cleared: this many seconds at its
/// speed, and at least `EMERGENCY_NEAR_M`.
const EMERGENCY_NEAR_S: f64 = 8.0;
const EMERGENCY_NEAR_M: f64 = 30.0;
/// Share of emergency braking a driver uses to hold for an emergency vehicle; closer than that
/// to the stop line, it goes on and clears the junction.
const YIELD_BRAKE: f64 = 0.75;

/// Whether one at speed `v`, `rem` metres short of a mark (up to 5 cm past it counts as at it),
/// can stop there braking at `brake`.
fn can_stop(v: f64, rem: f64, brake: f64) -> bool {
    rem > -0.05 && v * v / (2.0 * rem.max(1e-3)) <= brake
}

impl Actor {
    /// How far its front, at `st`, is short of where it halts for its junction (0.3 m before
    /// the stop line, else the junction entry); `None` without a junction.
    fn to_line(&self, st: &State) -> Option<f64> {
        self.junction.map(|j| j.stop - 0.3 - (st.s + self.hl))
    }

    /// Whether one clearing a junction for an emergency vehicle goes on past this vehicle,
    /// predicted to cross its way: it gives the junction to the emergency vehicle too (held at
    /// its line, or clearing), or it is still outside its junction, where the right-of-way rule
    /// holds it. Not one turning inside the junction that nothing holds: a car going straight to
    /// clear for an ambulance drove into a U-turn's loop at 7 m/s.
    fn cleared_past(&self, st: &State) -> bool {
        self.vehicle && (!self.yield_to.is_empty() || self.to_line(st).is_none_or(|line| line > -0.05))
    }

    fn obb(&self, st: &State) -> Obb {
        Obb { center: st.pos, yaw: st.yaw, length: 2.0 * self.hl, width: 2.0 * self.hw }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct State {
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
}

/// A conflict with its agents as track indices.
pub(super) struct Conf {
    pub index: usize,
    pub af: usize,
    pub st: usize,
    pub c: crate::check::scenario::Conflict,
}

/// Time margin by which a vehicle with the right of way must have left a shared zone before
/// one giving way to it arrives there for that one not to hold, s.
const CLEAR_MARGIN_S: f64 = 1.0;
/// Clearance kept to where a leader could stop (`Sim::safe_acc`), m.
const SAFE_MARGIN: f64 = 0.5;
/// Largest angle between a vehicle's heading and its lane while it moves sideways (rad).
const MAX_SLIP: f64 = 0.25;
/// How far a long vehicle's ends may swing out of its lane while it moves sideways (m): its
/// box turns about its centre, so at `MAX_SLIP` a bus's tail swung 0.9 m the other way.
const END_SWING: f64 = 0.65;

/// The tangent of the largest angle between vehicle `a`'s heading and its lane while it moves
/// sideways: `MAX_SLIP`, or less where its ends would swing out further than `END_SWING`.
fn slip_tan(a: &Actor) -> f64 {
    MAX_SLIP.tan().min(END_SWING / a.hl)
}
/// The least reach beyond the band a junction sweep's slice is kept for (`Bend::slices`), m:
/// the vehicle band's margin in `Sim::drive`.
const SLICE_MIN: f64 = 0.25;
/// Lateral clearance a walker keeps from another walking beside it, and how fast it steps aside
/// to keep it (m, m/s).
const WALK_CLEAR: f64 = 0.15;
const WALK_ASIDE: f64 = 0.2;
/// How far a vehicle's lateral reference may lead its body's offset (m).
const MAX_LEAD: f64 = 0.5;
/// Lateral speed of a vehicle squeezing past an agent that eases aside for it (m/s).
const PASS_LAT_RATE: f64 = 1.0;
/// Side clearance kept while passing it (m).
const PASS_CLEARANCE: f64 = 0.4;
/// The most a pass may move off the lane's centre line (m): half into the next lane.
const PASS_MAX_SHIFT: f64 = 2.5;

pub(super) fn run(c: &Concrete, map: &Map, placed: &Placed) -> Result<Tracks, Vec<Diagnostic>> {
    // Concrete agent index -> track index.
    let mut track_of = vec![None; c.agents.len()];
    for (i, p) in placed.agents.iter().enumerate() {
        if let Some(src) = p.source
            && src < track_of.len()
            && track_of[src].is_none()
        {
            track_of[src] = Some(i);
        }
    }
    let mut errs = vec![];
    // One resampling per distinct route (start lane, turn), shared by every agent on it.
    let mut routes = Routes::new();
    let mut actors: Vec<Actor> =
        placed.agents.iter().map(|p| build_actor(c, map, p, &track_of, &mut routes, &mut errs)).collect();
    if !errs.is_empty() {
        return Err(errs);
    }
    if let Some(t) = c.traffic {
        let boxes: Vec<(Obb, f64)> = actors.iter().map(|a| (a.obb(&initial(a)), initial(a).v)).collect();
        for s in traffic::spawn(map, &boxes, t, c.seed) {
            actors.push(background_actor(map, s, c.duration, &mut routes));
        }
    }
    let mut confs = vec![];
    for (index, k) in c.conflicts.iter().enumerate() {
        let (Some(Some(af)), Some(Some(st))) = (track_of.get(k.at_fault), track_of.get(k.struck)) else { continue };
        // An agent strikes once: a second conflict naming the same at-fault agent is not staged.
        if af == st || confs.iter().any(|x: &Conf| x.af == *af) {
            continue;
        }
        confs.push(Conf { index, af: *af, st: *st, c: k.clone() });
    }
    for k in &confs {
        face_the_striker(&mut actors, k);
    }
    let frames = c.frame_count();
    let dt = if c.rate > 0.0 { 1.0 / c.rate } else { 0.1 };
    assign_bends(map, &mut actors, dt);
    assign_yields(map, &mut actors, &confs);
    assign_crossings(map, &mut actors, &confs);
    order_crossings(&mut actors, &mut errs);
    if !errs.is_empty() {
        return Err(errs);
    }
    let mut out = empty_tracks(&actors, c.rate, frames);
    if confs.is_empty() {
        Sim::new(&actors, &confs, &[], None, dt).run(&mut out);
    } else {
        let mut pass1 = empty_tracks(&actors, c.rate, frames);
        let mut states = Vec::with_capacity(frames);
        Sim::new(&actors, &confs, &[], None, dt).keep_states(&mut states).run(&mut pass1);
        // A staging that misses or lands elsewhere than asked, or that has the overlap safety
        // net stop someone dead, is planned again away from the impact times tried (the plan
        // nearest the request may be the one a bystander spoils), up to `RESTAGE` times. The
        // first attempt that lands every crash as asked with everyone inside their limits is
        // kept; if none does, the first attempt (the plans nearest the request) stands: its
        // tracks, or its errors.
        let mut avoid: Vec<Vec<f64>> = vec![Vec::new(); confs.len()];
        // The first attempt's tracks (only where they are the answer should nothing do
        // better: its crashes landed) and its errors.
        let (mut first_tracks, mut first_failed, mut first_hard, mut first_forced) = (None, Vec::new(), None, None);
        let mut plans: Vec<Option<Plan>> =
            confs.iter().map(|k| stage::choose(k, &actors, &pass1, dt, c.duration, &[])).collect();
        for attempt in 0..=RESTAGE {
            // Pass 2 is pass 1 until a planned striker departs or a planned pair first
            // overlaps: those frames are copied, not simulated again.
            let start = pass2_start(&actors, &confs, &plans, &states, dt);
            out = empty_tracks(&actors, c.rate, frames);
            let report =
                Sim::new(&actors, &confs, &plans, Some(&pass1), dt).resume(&pass1, &states, start).run(&mut out);
            let failed = staging_errors(&actors, &confs, &plans, &out, &report.blocked_by, (dt, frames, c.duration));
            let forced = forced_braking(&actors, &confs, &plans, &out);
            if failed.is_empty() && report.first_hard.is_none() && forced.is_none() {
                break;
            }
            // Plan again the conflicts that failed; where none did, every one.
            let redo: Vec<usize> =
                if failed.is_empty() { (0..confs.len()).collect() } else { failed.iter().map(|f| f.0).collect() };
            if attempt == 0 {
                first_tracks = failed.is_empty().then(|| out.clone());
                first_failed = failed;
                first_hard = report.first_hard;
                first_forced = forced;
            }
            let mut replanned = false;
            if attempt < RESTAGE {
                for ki in redo {
                    let Some(tried) = plans[ki].as_ref().map(|p| p.t_impact) else { continue };
                    avoid[ki].push(tried);
                    if let Some(p) = stage::choose(&confs[ki], &actors, &pass1, dt, c.duration, &avoid[ki]) {
                        plans[ki] = Some(p);
                        replanned = true;
                    }
                }
            }
            if !replanned {
                // Landed, but only with the safety net stopping one of a staged pair dead: the
                // crash is not driven within the limits (a motorcycle striker's intercept ran
                // through a car standing at its line, and it was stopped from 19.8 m/s).
                let pair_stopped = first_hard.and_then(|(k, other, t)| {
                    confs.iter().position(|c| c.af == k || c.st == k).map(|ki| (ki, k, other, t))
                });
                match (first_tracks, pair_stopped, first_forced) {
                    (Some(_), Some((ki, k, other, t)), _) => errs.push(stopped_dead(&actors, &confs[ki], k, other, t)),
                    (Some(_), None, Some(f)) => errs.push(forced_error(&actors, &confs, f)),
                    (Some(tracks), None, None) => out = tracks,
                    (None, ..) => {}
                }
                errs.extend(first_failed.into_iter().map(|(_, d)| d));
                break;
            }
        }
    }
    check_turns(map, &actors, &confs, &out, &mut errs);
    if !errs.is_empty() {
        return Err(errs);
    }
    Ok(out)
}

/// How many times a staging that fails is planned again (`stage::choose` away from the impact
/// times already tried) before E0205.
const RESTAGE: usize = 3;

/// E0205 for each planned conflict whose crash does not happen near its time, or lands
/// elsewhere than asked, with its index into `confs`. (Without a plan the at-fault agent is not
/// ours to steer, e.g. a replayed track: nothing to check.)
fn staging_errors(
    actors: &[Actor],
    confs: &[Conf],
    plans: &[Option<Plan>],
    out: &Tracks,
    blocked_by: &[Option<(usize, f64)>],
    (dt, frames, duration): (f64, usize, f64),
) -> Vec<(usize, Diagnostic)> {
    let mut errs = vec![];
    for (ki, (k, _)) in confs.iter().zip(plans).enumerate().filter(|(_, (_, p))| p.is_some()) {
        let t_req = stage::requested_time(&k.c, dt, frames, duration);
        let rec = out.impacts.iter().find(|r| r.conflict == k.index);
        let hit = rec.map(|r| r.frame as f64 * dt);
        // Nor one that lands elsewhere than asked: a `rear_end` on `rear` that the struck
        // car, blocked by its striker standing in its lane, drives into front first is not
        // the crash the file describes, and its labels would say it is.
        let off = rec.and_then(|r| {
            let size = out.agents[r.at_fault].size;
            if r.depth < stage::MIN_DEPTH {
                return Some(format!("they only graze, {:.3} m deep", r.depth));
            }
            stage::wrong_struck_side(k.c.impact, k.c.point, r.struck_side)
                .map(|why| format!("`{}` is struck on its {why}", actors[k.st].info.name))
                .or_else(|| stage::off_striking_face(k.c.impact, r.at_fault_local, size))
        });
        let in_time = |t: f64| (t - t_req).abs() <= stage::WINDOW_S + 0.5 * dt;
        let (a, b) = (&actors[k.af].info.name, &actors[k.st].info.name);
        // What went wrong, its label, how the help joins a bystander's name to its advice, and
        // the help when no bystander held the striker back.
        let (what, label, met, unhindered) = match (hit.filter(|&t| in_time(t)), off) {
            (Some(_), None) => continue,
            (Some(t), Some(why)) => (
                format!("cannot be staged as asked: at {t:.1} s {why}"),
                "the crash lands elsewhere",
                ", and the two met otherwise:",
                format!(
                    "start `{a}` where its striking face can come at that side of `{b}` (behind it in its lane for \
                     `rear_end`, toward it for `head_on`), or ask for the side it can reach"
                ),
            ),
            (None, _) => (
                match hit {
                    Some(t) => format!("cannot be staged at {t_req:.1} s: they first touch at {t:.1} s"),
                    None => format!("cannot be staged at {t_req:.1} s: they never touch"),
                },
                "no contact near this time",
                ":",
                format!(
                    "`{a}` must be able to reach `{b}` within {:.1} s of `at` at its limits: \
                     start them closer, give them speeds that bring them together, or move `at`",
                    stage::WINDOW_S
                ),
            ),
        };
        let help = match blocked_by[k.af] {
            Some((j, t)) => {
                let by = &actors[j].info.name;
                format!(
                    "`{a}` slowed from {t:.1} s for `{by}` in its way (a striker never runs into a bystander){met} \
                     start `{a}` where its way to `{b}` is clear, keep `{by}` out of it, or move `at`"
                )
            }
            None => unhindered,
        };
        errs.push((
            ki,
            Diagnostic::error("E0205", format!("the conflict between `{a}` and `{b}` {what}"))
                .label(k.c.span, label)
                .help(help),
        ));
    }
    errs
}

/// Within this of a striker (box to box, m), an agent braking beyond its limit is braking for
/// the staged crash.
const FORCED_NEAR_M: f64 = 1.0;

/// A staged crash that makes someone brake beyond their limit: what the controller cannot
/// foresee of a striker that leaves its goal at speed (one cutting across a lane a few metres
/// ahead of a car, one swerving into a lane that a motorcycle is setting off in), measured on
/// the tracks. The first frame at which an agent's speed falls faster than its `brake_max`
/// while its box is within `FORCED_NEAR_M` of another's, either of the two a striker (the pair
/// up to their latched frame, where the crash stops them dead): the conflict, the braking
/// agent, the other, the time and the deceleration.
fn forced_braking(
    actors: &[Actor],
    confs: &[Conf],
    plans: &[Option<Plan>],
    out: &Tracks,
) -> Option<(usize, usize, usize, f64, f64)> {
    let dt = 1.0 / out.rate;
    let staged = |k: usize| confs.iter().zip(plans).position(|(c, p)| p.is_some() && c.af == k);
    let bx = |k: usize, f: usize| {
        let (p, s) = (out.poses[k][f], out.agents[k].size);
        Obb { center: DVec2::new(p.x, p.y), yaw: p.yaw, length: s[0], width: s[1] }.grown(0.5 * FORCED_NEAR_M)
    };
    let mut first: Option<(usize, usize, usize, f64, f64)> = None;
    for (i, a) in actors.iter().enumerate() {
        let end = out.impacts.iter().filter(|r| r.at_fault == i || r.struck == i).map(|r| r.frame).min();
        let end = end.unwrap_or(out.frames).min(first.map_or(out.frames, |f| (f.3 / dt).round() as usize));
        for f in 1..end {
            let acc = (out.speeds[i][f] - out.speeds[i][f - 1]) / dt;
            if acc >= -a.lim.brake_max - 1e-6 {
                continue;
            }
            let near = (0..actors.len()).find_map(|k| {
                let ki = staged(i).or(staged(k)).filter(|_| k != i)?;
                [f - 1, f].iter().any(|&g| bx(i, g).overlaps(&bx(k, g))).then_some((ki, k))
            });
            if let Some((ki, k)) = near {
                first = Some((ki, i, k, f as f64 * dt, acc));
                break;
            }
        }
    }
    first
}

/// E0205 for a staging whose every plan makes someone brake beyond their limit for the crash
/// (`forced_braking`).
fn forced_error(actors: &[Actor], confs: &[Conf], (ki, x, y, t, acc): (usize, usize, usize, f64, f64)) -> Diagnostic {
    let k = &confs[ki];
    let (a, b) = (&actors[k.af].info.name, &actors[k.st].info.name);
    let (xn, yn) = (&actors[x].info.name, &actors[y].info.name);
    let by = if x == k.af { y } else { x };
    Diagnostic::error(
        "E0205",
        format!(
            "the conflict between `{a}` and `{b}` cannot be staged within the agents' limits: at {t:.1} s `{xn}` \
             would have to brake at {:.1} m/s2 for `{yn}` (its limit is {:.1})",
            -acc, actors[x].lim.brake_max
        ),
    )
    .label(k.c.span, "no plan tried stages it within everyone's braking")
    .help(keep_out(actors, k, by, k.af))
}

/// The help of a staging refused for agent `by` in the way of `mover`.
fn keep_out(actors: &[Actor], k: &Conf, by: usize, mover: usize) -> String {
    let (a, b) = (&actors[k.af].info.name, &actors[k.st].info.name);
    format!(
        "keep `{}` out of the way `{}` takes ({}), start `{a}` where its way to `{b}` is clear, or move `at`",
        actors[by].info.name,
        actors[mover].info.name,
        if actors[by].info.background {
            "it is background traffic: lower `density`, or change the scenario's `seed`"
        } else {
            "start it elsewhere, or give it another goal"
        }
    )
}

/// E0205 for a staging whose first plan has the overlap safety net stop agent `stopped` of the
/// pair `k` dead at `t` (beyond its braking), short of running into `other`, and that no
/// re-planned one betters.
fn stopped_dead(actors: &[Actor], k: &Conf, stopped: usize, other: usize, t: f64) -> Diagnostic {
    let (a, b) = (&actors[k.af].info.name, &actors[k.st].info.name);
    let (x, y) = (&actors[stopped].info.name, &actors[other].info.name);
    Diagnostic::error(
        "E0205",
        format!(
            "the conflict between `{a}` and `{b}` cannot be staged within the agents' limits: at {t:.1} s `{x}` \
             would run into `{y}` and is stopped dead"
        ),
    )
    .label(k.c.span, "no plan tried stages it within everyone's braking")
    .help(keep_out(actors, k, other, stopped))
}

/// How far a turning vehicle's wheels may stray off the drivable surface in its junction, m:
/// one BEV pixel (0.25 m), the resolution at which the surface is drawn.
const TURN_OFF_ROAD_M: f64 = 0.25;

/// How far over its path's curve speed a vehicle may take a turn before E0204 blames the speed
/// (car-following settles onto the speed from just above it).
const TURN_SPEED_SLACK: f64 = 0.5;

/// E0204 for a turn the vehicle drives but cannot make on this road: the junction path is within
/// `TURN_SLACK` of its turning radius, yet its wheels leave the drivable surface by more than
/// `TURN_OFF_ROAD_M` while in the junction. The wheels span the box's width and its wheelbase
/// (`WHEELBASE_SHARE` of its length): the overhangs beyond the axles sweep over the kerb in a
/// tight turn, as real ones do, but tyres on the pavement are a turn the road does not offer.
/// Conflict agents are exempt: their crash may take them anywhere.
fn check_turns(map: &Map, actors: &[Actor], confs: &[Conf], out: &Tracks, errs: &mut Vec<Diagnostic>) {
    // A map drawn without a surface (a hand-built one) has nothing to check against.
    if map.drivable.is_empty() {
        return;
    }
    let boxes: Vec<(DVec2, DVec2)> = map
        .drivable
        .iter()
        .map(|poly| poly.iter().fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p))))
        .collect();
    let off_road = |q: DVec2| -> f64 {
        let near = || map.drivable.iter().zip(&boxes).filter(|(_, (lo, hi))| q.cmpge(*lo).all() && q.cmple(*hi).all());
        if near().any(|(poly, _)| crate::geom::point_in_polygon(q, poly)) {
            return 0.0;
        }
        map.drivable
            .iter()
            .flat_map(|poly| (0..poly.len()).map(move |k| (poly[k], poly[(k + 1) % poly.len()])))
            .map(|(a, b)| {
                let d = b - a;
                let t =
                    if d.length_squared() > 0.0 { ((q - a).dot(d) / d.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
                q.distance(a + d * t)
            })
            .fold(f64::INFINITY, f64::min)
    };
    for (i, a) in actors.iter().enumerate() {
        let (Some(turn), Some(span), Some(j)) = (a.turn_goal, a.span, a.junction) else { continue };
        if confs.iter().any(|k| k.af == i || k.st == i) {
            continue;
        }
        let Some(conn) = map.connectors.get(j.conn) else { continue };
        let (lo, hi) =
            conn.path.points.iter().fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let (lo, hi) = (lo - DVec2::splat(a.radius + 1.0), hi + DVec2::splat(a.radius + 1.0));
        let mut worst = (0.0, 0);
        // The most it went over the speed its path allows there (the turn's curve speed), and
        // where: it brakes for a turn at its comfortable braking only, so one placed too fast
        // and too close takes the turn wide.
        let mut over = (0.0, 0.0, 0.0);
        let mut guess = a.s0;
        for (f, p) in out.poses[i].iter().enumerate() {
            let c = DVec2::new(p.x, p.y);
            if !(c.cmpge(lo).all() && c.cmple(hi).all()) {
                continue;
            }
            let (s, ..) = a.path.frenet(c, guess);
            guess = s;
            let (v, cap) = (out.speeds[i][f], a.path.cap(s));
            if v - cap > over.0 {
                over = (v - cap, v, cap);
            }
            let obb = Obb { center: c, yaw: p.yaw, length: super::WHEELBASE_SHARE * 2.0 * a.hl, width: 2.0 * a.hw };
            for q in obb.corners() {
                let d = off_road(q);
                if d > worst.0 {
                    worst = (d, f);
                }
            }
        }
        if worst.0 > TURN_OFF_ROAD_M {
            let t = worst.1 as f64 / out.rate.max(1e-9);
            let mut message = format!(
                "`{}` ({}, turning radius {:.1} m) cannot turn {} here: its box leaves the road by {:.1} m at {t:.1} s",
                a.info.name,
                a.info.kind,
                a.r_min,
                turn_name(turn),
                worst.0
            );
            let mut help = String::from(
                "a wider road (lanes, lane_width, median, a roundabout's radius) or a smaller kind; long vehicles \
                 need room to swing through a turn (see README, Rollout)",
            );
            if over.0 > TURN_SPEED_SLACK {
                message += &format!(", driving it at {:.1} m/s where it allows {:.1} m/s", over.1, over.2);
                help = format!(
                    "a lower `speed`, or a start farther from the junction: it brakes for a turn at its comfortable \
                     braking ({:.1} m/s2) only; else {help}",
                    a.lim.brake
                );
            }
            errs.push(Diagnostic::error("E0204", message).label(span, "this goal").help(help));
        }
    }
}

/// A tree or a pole has no front: its yaw is whatever the placement gave it (the lane's heading),
/// so a requested `point front` in that frame could send the striker around the trunk to hit
/// its far face. Turn such a struck object (a static structure, roughly square or under 2 m) to face the
/// striker's start, so the requested side reads from the striker's approach: `front` is the face
/// it drives into, `left` the one on the striker's right as it comes. Walls and buildings keep
/// their yaw: their faces are real.
fn face_the_striker(actors: &mut [Actor], k: &Conf) {
    let (af, st) = (actors[k.af].init, &actors[k.st]);
    // A trunk or a pole: roughly square, or small whatever its sampled aspect (a 0.75 x 0.45 m
    // tree box is still a trunk; a car could not drive around it to a far face in any case).
    let trunk = st.hl.max(st.hw) <= 1.5 * st.hl.min(st.hw) || st.hl.max(st.hw) < 1.0;
    if !matches!(st.drive, Drive::Static) || st.info.class != Class::Structure || !trunk {
        return;
    }
    let to_striker = DVec2::new(af.x - st.init.x, af.y - st.init.y);
    if to_striker.length() > 1e-6 {
        actors[k.st].init.yaw = to_striker.y.atan2(to_striker.x);
    }
}

fn empty_tracks(actors: &[Actor], rate: f64, frames: usize) -> Tracks {
    Tracks {
        rate,
        frames,
        agents: actors.iter().map(|a| a.info.clone()).collect(),
        poses: actors.iter().map(|_| Vec::with_capacity(frames)).collect(),
        speeds: actors.iter().map(|_| Vec::with_capacity(frames)).collect(),
        impacts: vec![],
    }
}

fn initial(a: &Actor) -> State {
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
    }
}

// ---------------------------------------------------------------- set-up

fn base_actor(info: TrackAgent, pose: Pose, motion: Motion, class: Class, drive: Drive) -> Actor {
    let [l, w, _] = info.size;
    Actor {
        drive,
        vehicle: motion == Motion::Vehicle,
        hl: l / 2.0,
        hw: w / 2.0,
        radius: 0.5 * (l * l + w * w).sqrt(),
        r_min: super::min_turn_radius(class, l),
        lim: limits(class, motion),
        path: Path::default(),
        init: pose,
        s0: 0.0,
        d0: 0.0,
        v0: 0.0,
        v_goal: 0.0,
        v_hold: 0.0,
        start: 0.0,
        lateral: Lat::Hold,
        stop: StopGoal::None,
        emergency: false,
        junction: None,
        yield_to: vec![],
        span: None,
        turn_goal: None,
        crossings: vec![],
        kerb: None,
        in_conflict: false,
        approach: None,
        bend: None,
        info,
    }
}

fn build_actor(
    c: &Concrete,
    map: &Map,
    p: &crate::place::PlacedAgent,
    track_of: &[Option<usize>],
    routes: &mut Routes,
    errs: &mut Vec<Diagnostic>,
) -> Actor {
    let info = TrackAgent {
        name: p.name.clone(),
        kind: p.kind.clone(),
        class: p.class,
        motion: p.motion,
        size: p.size,
        background: false,
    };
    let ca = p.source.and_then(|i| c.agents.get(i));
    // A recorded track is what happened: it is replayed even for a kind that never moves by
    // itself (a cone carried on a pickup), so an imported clip reproduces its boxes exactly.
    if let Some(keys) = ca.filter(|_| !p.is_object).and_then(|ca| ca.track.as_ref()).filter(|k| !k.is_empty()) {
        return base_actor(info, p.pose, p.motion, p.class, Drive::Replay(keys.clone()));
    }
    let Some(ca) = ca.filter(|_| !p.is_object && p.motion != Motion::Static) else {
        return base_actor(info, p.pose, p.motion, p.class, Drive::Static);
    };
    let mut a = base_actor(info, p.pose, p.motion, p.class, Drive::Mover);
    a.span = Some(p.span);
    a.emergency = a.vehicle && is_emergency(c, &p.kind);
    let pos = DVec2::new(p.pose.x, p.pose.y);
    let goal = ca.goal.as_ref();
    let fail = |errs: &mut Vec<Diagnostic>, msg: String, help: &str| {
        errs.push(Diagnostic::error("E0204", msg).label(ca.span, "this goal").help(help.to_string()));
    };
    a.v0 = p.speed.max(0.0);
    a.v_hold = a.v0;
    a.start = goal.map(|g| g.start_after.max(0.0)).unwrap_or(0.0);
    let lateral = goal.map(|g| g.lateral).unwrap_or(Lateral::HoldLane);
    let mut limit = f64::INFINITY;
    let mut stop_line = None;
    let mut lane_here = None;
    if a.vehicle {
        let found = find_lane(map, pos, p.pose.yaw);
        let mut base = found.map(|(l, _, _)| l);
        if let Lateral::ChangeLane(side) = lateral {
            match base.and_then(|l| side_lane(map, l, side)) {
                Some(t) => base = Some(t),
                None => fail(
                    errs,
                    format!("`{}` cannot change lane {}: there is no lane on that side", ca.name, side_name(side)),
                    "lane 1 is nearest the centre line: `left` moves to index-1, `right` to index+1",
                ),
            }
        }
        match base {
            Some(l) => {
                let lane = &map.lanes[l];
                let turn = goal.and_then(|g| g.turn);
                let (pts, ok, junction) = chain(map, l, turn);
                a.junction = junction;
                if !ok {
                    fail(
                        errs,
                        format!(
                            "`{}` cannot turn {}: no junction connector of that kind leaves its lane",
                            ca.name,
                            turn.map(turn_name).unwrap_or("")
                        ),
                        "place the agent on an in-lane of a junction that offers this turn",
                    );
                }
                let (s, d) = lane.centre.project(pos);
                (a.s0, a.d0) = (s, d);
                let v_top = a.v0.max(goal.and_then(|g| g.speed).unwrap_or(0.0)).max(lane.speed_limit);
                a.path = route_path(routes, (l, turn), &pts, s.max(0.0) + reach(v_top, c.duration));
                // A turn tighter than the kind can steer (a bus's U-turn on a narrow junction)
                // would leave the road: refused, not driven wide.
                if let (Some(t), Some(j)) = (turn, a.junction) {
                    a.turn_goal = Some(t);
                    let k = junction_curvature(map, &a.path, j);
                    if k * a.r_min > TURN_SLACK {
                        fail(
                            errs,
                            format!(
                                "`{}` ({}, turning radius {:.1} m) cannot turn {} here: the junction's path turns on {:.1} m",
                                ca.name,
                                p.kind,
                                a.r_min,
                                turn_name(t),
                                1.0 / k
                            ),
                            "a wider road (lane_width, median) or a smaller kind; rocc derives the turning radius \
                             from the kind's length (see README, Rollout)",
                        );
                    }
                }
                limit = lane.speed_limit;
                stop_line = lane.stop_line_s.filter(|&sl| sl > a.s0);
                lane_here = Some(l);
            }
            None => {
                a.path = Path::straight(pos, p.pose.yaw, RUN_OUT * 2.0);
                if goal.is_some_and(|g| g.turn.is_some()) {
                    fail(errs, format!("`{}` is not on a lane, so it cannot turn", ca.name), "start it on a lane");
                }
            }
        }
    } else if lateral == Lateral::Cross {
        match cross_line(map, pos) {
            Some((yaw, len, kerb)) => {
                a.path = Path::straight(pos, yaw, len);
                a.kerb = Some(kerb);
            }
            None => {
                fail(errs, format!("`{}` has no road nearby to cross", ca.name), "place it beside a lane");
                a.path = Path::straight(pos, p.pose.yaw, 1.0);
            }
        }
    } else {
        a.path = Path::straight(pos, p.pose.yaw, RUN_OUT);
    }
    a.path.set_caps(a.lim.lat_acc, a.lim.yaw_rate, a.lim.brake);
    // An explicit goal speed may exceed the lane limit (an ambulance); a kept speed may not.
    // A route goal (a turn, a lane change, a crossing) means to go somewhere: started from rest
    // with no goal speed, it drives at the lane limit, or walks at an ordinary pace.
    let goes = goal.is_some_and(|g| g.turn.is_some() || matches!(g.lateral, Lateral::ChangeLane(_)));
    a.v_goal = match goal.and_then(|g| g.speed) {
        Some(v) => v.max(0.0),
        None if a.vehicle && goes && a.v0 < 0.05 && limit.is_finite() => limit,
        None if a.vehicle => a.v0.min(limit),
        None if lateral == Lateral::Cross && a.v0 < 0.05 => WALK_SPEED,
        None => a.v0,
    };
    let lane = lane_here.map(|l| &map.lanes[l]);
    let aside = |lane: Option<&crate::road::map::Lane>, hw: f64, d0: f64| -> f64 {
        let (w, sh) = lane.map(|l| (l.width, l.shoulder_right)).unwrap_or((3.5, 0.0));
        (-(w / 2.0 + sh - hw - 0.2)).min(d0)
    };
    a.lateral = match lateral {
        Lateral::HoldLane | Lateral::Cross => Lat::Hold,
        Lateral::ChangeLane(_) => Lat::Shift { target: 0.0, dur: LANE_CHANGE_S },
        Lateral::PullToShoulder => Lat::Shift { target: aside(lane, a.hw, a.d0), dur: LANE_CHANGE_S },
        Lateral::AwayFrom(k) => match track_of.get(k).copied().flatten() {
            Some(who) => Lat::Away { who, target: aside(lane, a.hw, a.d0), dur: ASIDE_S },
            None => Lat::Hold,
        },
    };
    a.stop = match goal.and_then(|g| g.stop) {
        None => StopGoal::None,
        Some(Stop::AtStopLine) => match stop_line {
            // Stop lines are painted across the lane; the front bumper halts just short of it.
            Some(sl) => StopGoal::Front(sl - 0.3),
            None => {
                fail(
                    errs,
                    format!("`{}` has no stop line ahead on its lane", ca.name),
                    "stop lines exist on the in-lanes of four_way, t_junction and roundabout roads",
                );
                StopGoal::None
            }
        },
        Some(Stop::Behind(k)) => match track_of.get(k).copied().flatten() {
            Some(t) => StopGoal::Behind(t),
            None => StopGoal::None,
        },
        Some(Stop::After(dist)) => StopGoal::Centre(a.s0 + dist.max(0.0)),
    };
    a
}

/// Resampled routes by start lane and turn (`chain`'s arguments, so one key is one chain).
type Routes = std::collections::HashMap<(usize, Option<Turn>), Resampler>;

/// `Path::new_until(pts, until)` for the chain `key`, reusing the resampling of agents before.
fn route_path(routes: &mut Routes, key: (usize, Option<Turn>), pts: &[DVec2], until: f64) -> Path {
    routes.entry(key).or_insert_with(|| Resampler::new(pts)).path(until)
}

/// Whether a kind drives with lights and siren: the checker resolved it through the kind's
/// ancestry (`kind my_amb: ambulance`); the stdlib names count even where the scenario's kind
/// table lacks them (a hand-built `Concrete`).
fn is_emergency(c: &Concrete, kind: &str) -> bool {
    EMERGENCY_KINDS.contains(&kind) || c.kinds.get(kind).is_some_and(|k| k.emergency)
}

/// How much of its route an agent can use within a clip of `duration` s: driving at up to 1.25
/// times `v` (at least 15 m/s) all the way, plus the longest look-ahead of the car-following
/// law at that speed and a margin. Nothing beyond can affect the clip.
fn reach(v: f64, duration: f64) -> f64 {
    let v = if v.is_finite() { v.max(15.0) * 1.25 } else { 40.0 };
    v * duration + v * v / (2.0 * 2.0) + 2.5 * v + 60.0
}

fn background_actor(map: &Map, s: traffic::Spawn, duration: f64, routes: &mut Routes) -> Actor {
    let lane = &map.lanes[s.lane];
    let (p, yaw) = lane.centre.pose_at(s.s);
    let info = TrackAgent {
        name: s.name,
        kind: s.kind.to_string(),
        class: Class::Vehicle,
        motion: Motion::Vehicle,
        size: s.size,
        background: true,
    };
    let mut a = base_actor(info, Pose { x: p.x, y: p.y, yaw }, Motion::Vehicle, Class::Vehicle, Drive::Mover);
    let (pts, _, junction) = chain(map, s.lane, None);
    a.junction = junction;
    a.path = route_path(routes, (s.lane, None), &pts, s.s.max(0.0) + reach(s.speed.max(s.target), duration));
    a.path.set_caps(a.lim.lat_acc, a.lim.yaw_rate, a.lim.brake);
    a.s0 = s.s;
    a.v0 = s.speed;
    a.v_hold = s.speed;
    a.v_goal = s.target;
    a
}

fn side_name(s: Side) -> &'static str {
    match s {
        Side::Left => "left",
        Side::Right => "right",
    }
}

fn turn_name(t: Turn) -> &'static str {
    match t {
        Turn::Left => "left",
        Turn::Right => "right",
        Turn::Straight => "straight",
        Turn::UTurn => "u_turn",
    }
}

/// Whether two junction paths cross or merge: some point of one lies within `gap` of the other,
/// away from their shared start (two paths from the same lane diverge; they do not cross).
fn paths_cross(map: &Map, a: usize, b: usize, gap: f64) -> bool {
    let (ca, cb) = (&map.connectors[a], &map.connectors[b]);
    if ca.from == cb.from {
        return false;
    }
    let (la, lb) = (ca.path.length(), cb.path.length());
    let n = (la / 0.5).ceil().max(1.0) as usize;
    let on_b = Projector::new(&cb.path);
    let mut hint = 0;
    (0..=n).any(|k| {
        // Farther than `gap` fails the test below in any case.
        let p = ca.path.point_at(la * k as f64 / n as f64);
        on_b.project_within(p, &mut hint, gap).is_ok_and(|(s, d)| s > -0.5 && s < lb + 0.5 && d.abs() < gap)
    })
}

/// Fill every agent's `yield_to`: the emergency vehicles whose junction path crosses its own.
/// Emergency vehicles and staged conflict agents (their goal is the crash) do not yield.
fn assign_yields(map: &Map, actors: &mut [Actor], confs: &[Conf]) {
    let em: Vec<usize> = (0..actors.len())
        .filter(|&e| actors[e].emergency && matches!(actors[e].drive, Drive::Mover) && actors[e].junction.is_some())
        .collect();
    if em.is_empty() {
        return;
    }
    for i in 0..actors.len() {
        let a = &actors[i];
        let Some(ji) = a.junction else { continue };
        if a.emergency || !a.vehicle || !matches!(a.drive, Drive::Mover) || confs.iter().any(|k| k.af == i || k.st == i)
        {
            continue;
        }
        let ys: Vec<usize> = em
            .iter()
            .copied()
            .filter(|&e| {
                let je = actors[e].junction.map(|j| j.conn).unwrap_or(ji.conn);
                paths_cross(map, ji.conn, je, a.hw + actors[e].hw + 0.5)
            })
            .collect();
        actors[i].yield_to = ys;
    }
}

/// Fill every vehicle's `crossings`: the other vehicles whose first junction path crosses or
/// merges into its own, with the zone each would share. Emergency vehicles and those yielding to
/// them are settled by `yield_to`; the two agents of a staged conflict are meant to meet. Marks
/// the conflict agents, and drops the kerb wait of a walker in a staged conflict.
fn assign_crossings(map: &Map, actors: &mut [Actor], confs: &[Conf]) {
    for k in confs {
        for x in [k.af, k.st] {
            actors[x].in_conflict = true;
            actors[x].kerb = None;
        }
    }
    let js: Vec<usize> = (0..actors.len())
        .filter(|&i| actors[i].vehicle && matches!(actors[i].drive, Drive::Mover) && actors[i].junction.is_some())
        .collect();
    // Many agents share a connector (background traffic on one lane): each pair of connectors
    // is sampled once.
    let mut profiles = std::collections::HashMap::new();
    let mut zones_of: std::collections::HashMap<(usize, usize, u64, u64), Zones> = std::collections::HashMap::new();
    // `sweep_entry` reads the sweep, the other's box size and its route's points from `lo` to
    // `hi`: where those points are its route's shared samples, agents on one route with one
    // sweep ask the same question.
    let mut entries: std::collections::HashMap<[u64; 6], Option<f64>> = std::collections::HashMap::new();
    let mut entry_of = |a: &Actor, b: &Actor, lo: f64, hi: f64| -> Option<f64> {
        let (Some(bend), Some(grid)) = (&a.bend, b.path.shared_upto(hi)) else { return sweep_entry(a, b, lo, hi) };
        let key = [
            std::sync::Arc::as_ptr(bend) as usize as u64,
            grid as u64,
            b.hl.to_bits(),
            b.hw.to_bits(),
            lo.to_bits(),
            hi.to_bits(),
        ];
        *entries.entry(key).or_insert_with(|| sweep_entry(a, b, lo, hi))
    };
    for (n, &i) in js.iter().enumerate() {
        for &j in &js[n + 1..] {
            let (a, b) = (&actors[i], &actors[j]);
            let (Some(ji), Some(jj)) = (a.junction, b.junction) else { continue };
            let emergency = a.yield_to.contains(&j) || b.yield_to.contains(&i);
            if confs.iter().any(|k| (k.af == i && k.st == j) || (k.af == j && k.st == i)) {
                continue;
            }
            // A long box swings wide of its path in a turn (a bus's front corner sweeps into the
            // next lane): the zone widens by each box's off-tracking.
            let gap = a.hw + b.hw + 0.5 + off_tracking(a) + off_tracking(b);
            let mut zones = |x: usize, y: usize, join: f64| {
                // A pure function of these (the profile's samples within `gap` are the same
                // whatever reach it was taken to): pairs of agents on the same connectors share it.
                let key = (x, y, gap.to_bits(), join.to_bits());
                zones_of
                    .entry(key)
                    .or_insert_with(|| shared_zones(map, (x, y), profile(&mut profiles, map, x, y, gap), gap, join))
                    .clone()
            };
            let za = zones(ji.conn, jj.conn, 2.0 * a.hl);
            let zb = zones(jj.conn, ji.conn, 2.0 * b.hl);
            let entry = |j: Junction| j.exit - map.connectors[j.conn].path.length();
            let (ei, ej) = (entry(ji), entry(jj));
            let (hi, hj) = (a.hl, b.hl);
            let first = actors[i].crossings.len();
            // Each stretch of ours goes with the stretch of theirs that its middle lies beside.
            for &(ai, ao, at, closest) in &za {
                let dist = |z: &(f64, f64, f64, f64)| (z.0 - at).max(at - z.1).max(0.0);
                let Some(&(bi, bo, ..)) = zb.iter().min_by(|x, y| dist(x).total_cmp(&dist(y))) else { continue };
                let (_, ha) = map.connectors[ji.conn].path.pose_at(0.5 * (ai + ao));
                let (_, hb) = map.connectors[jj.conn].path.pose_at(at);
                // Run on together: the same way, and into one lane. Two turning the same way
                // from side by side lanes into side by side lanes run the same way but apart,
                // and a long one's swing reaches over the other's lane: car-following along
                // our path does not see one in the next lane (a bus turning right behind a
                // sedan turning right beside it met the sedan's tail), so the two take turns.
                let merge = (ha - hb).cos() > MERGE_COS && closest < JOIN_M;
                let ci = Crossing {
                    other: j,
                    enter: ei + ai - hi,
                    leave: ei + ao + hi,
                    other_enter: ej + bi - hj,
                    other_leave: ej + bo + hj,
                    meet: ei + ai - hi,
                    other_meet: ej + bi - hj,
                    placed_yield: None,
                    emergency,
                    merge,
                };
                let cj = Crossing {
                    other: i,
                    enter: ci.other_enter,
                    leave: ci.other_leave,
                    other_enter: ci.enter,
                    other_leave: ci.leave,
                    meet: ci.other_meet,
                    other_meet: ci.meet,
                    placed_yield: None,
                    emergency,
                    merge,
                };
                actors[i].crossings.push(ci);
                actors[j].crossings.push(cj);
            }
            // Where one's sweep reaches over the other's approach short of their first shared
            // stretch, that stretch begins there for the other (it holds clear of the loop).
            let n_new = actors[i].crossings.len() - first;
            if n_new > 0 {
                let kj0 = actors[j].crossings.len() - n_new;
                // Ours moved back to their sweep, then theirs to ours.
                for ours in [true, false] {
                    let pick = |c: &Crossing| if ours { c.enter } else { c.other_enter };
                    let (sweeper, mover, lo) =
                        if ours { (j, i, ei - 2.0 * hi - 20.0) } else { (i, j, ej - 2.0 * hj - 20.0) };
                    let cs = &actors[i].crossings;
                    let Some(k) = (first..first + n_new).min_by(|&x, &y| pick(&cs[x]).total_cmp(&pick(&cs[y]))) else {
                        continue;
                    };
                    let Some(s) = entry_of(&actors[sweeper], &actors[mover], lo, pick(&cs[k])) else { continue };
                    let kj = kj0 + k - first;
                    if ours {
                        actors[i].crossings[k].enter = s;
                        actors[j].crossings[kj].other_enter = s;
                    } else {
                        actors[i].crossings[k].other_enter = s;
                        actors[j].crossings[kj].enter = s;
                    }
                }
            }
        }
    }
    for &i in &js {
        actors[i].approach = actors[i].junction.map(|j| map.connectors[j.conn].from);
    }
}

/// Two vehicles placed so near where their junction paths meet, and so fast, that neither can
/// stop short of its zone (`Crossing::enter`, which the other's sweep may move back from where
/// the paths come near) within its emergency braking: the right-of-way rule then has nobody to
/// hold (both are in or at their zone), and only the overlap safety net would part them (two
/// buses 6 m before their lines at 9 m/s, turning across each other, were stopped dead from
/// 9 m/s). Whichever of them can give way, braking as hard as it may while the other goes on at
/// its placed speed or slowed to a share of it (`GO_ON_KEEP`), without their boxes (grown by
/// `SWEEP_MARGIN`) meeting, does so (`Crossing::placed_yield`); where both can, the one clear
/// at every share, else the later to the paths' meeting. Where neither can, and braking both
/// they still meet or stand each in the other's way, no order keeps them apart: E0207. A
/// vehicle whose start is delayed, or whose stop goal lies short of the stretch, can hold; a
/// merge is followed, not crossed.
fn order_crossings(actors: &mut [Actor], errs: &mut Vec<Diagnostic>) {
    let holds = |a: &Actor, meet: f64| {
        !matches!(a.drive, Drive::Mover)
            || a.start > 1e-9
            || matches!(a.stop, StopGoal::Front(sf) | StopGoal::Centre(sf) if sf < meet + a.hl)
    };
    let mut set = vec![];
    for (i, a) in actors.iter().enumerate() {
        for (k, c) in a.crossings.iter().enumerate().filter(|(_, c)| c.other > i && !c.merge) {
            let b = &actors[c.other];
            if holds(a, c.meet)
                || holds(b, c.other_meet)
                || can_stop(a.v0, c.enter - 0.3 - a.s0, a.lim.brake_max)
                || can_stop(b.v0, c.other_enter - 0.3 - b.s0, b.lim.brake_max)
            {
                continue;
            }
            // When `y` gives way: the first contact with `o` going on at its placed speed, or
            // none if it does not touch `y` at that speed or at any share it may brake down to.
            let gives_way = |y: &Actor, o: &Actor, leave: f64| {
                let first = first_contact(y, o, 1.0, leave)?;
                GO_ON_KEEP[1..].iter().all(|&keep| first_contact(y, o, keep, leave).is_some()).then_some(first)
            };
            let (ta, tb) = (gives_way(a, b, c.other_leave), gives_way(b, a, c.leave));
            // Whether `a` is the later to where the paths meet at its placed speed (then the name).
            let later = |x: &Actor, meet: f64| (meet - x.s0).max(0.0) / x.v0.max(0.1);
            let a_later = || {
                later(a, c.meet).total_cmp(&later(b, c.other_meet)).then_with(|| a.info.name.cmp(&b.info.name)).is_gt()
            };
            match (ta, tb) {
                (None, Some(_)) => set.push((i, k, true)),
                (Some(_), None) => set.push((i, k, false)),
                // Either may give way: the one that stays clear whatever share of its speed the
                // other keeps, else the later to reach where the paths meet (then the name). Left
                // to the rule, one placed in the other's sweep short of the stretch counted as
                // inside, and an SUV beside a bus turning from the next lane went with it and met
                // its swinging tail.
                (None, None) => {
                    let clear = |y: &Actor, o: &Actor, leave: f64| {
                        GO_ON_KEEP.iter().all(|&keep| first_contact(y, o, keep, leave).is_none())
                    };
                    let a_yields = match (clear(a, b, c.other_leave), clear(b, a, c.leave)) {
                        (true, false) => true,
                        (false, true) => false,
                        _ => a_later(),
                    };
                    set.push((i, k, a_yields));
                }
                // Neither can give way while the other goes on: both brake, and where they then
                // stand clear of each other, the one not standing in the other's way goes first
                // (its car-following holds it short of the other where it must); left unordered,
                // two buses side by side turning away from each other both went, and each one's
                // tail swung into the other.
                (Some(ta), Some(tb)) => {
                    let both = first_contact(a, b, 0.0, f64::INFINITY);
                    match (both, standoff(a, b, (c.leave, c.other_leave))) {
                        (Some(_), _) | (None, (true, true)) => errs.push(no_order(a, b, [ta, tb], both)),
                        (None, (a_blocked, b_blocked)) => {
                            let a_yields = a_blocked || (!b_blocked && a_later());
                            set.push((i, k, a_yields));
                        }
                    }
                }
            }
        }
    }
    for (i, k, yields) in set {
        let c = &mut actors[i].crossings[k];
        c.placed_yield = Some(yields);
        let (j, enter, leave) = (c.other, c.enter, c.leave);
        let theirs =
            actors[j].crossings.iter_mut().find(|x| x.other == i && x.other_enter == enter && x.other_leave == leave);
        if let Some(x) = theirs {
            x.placed_yield = Some(!yields);
        }
    }
}

/// The first time at which `y`, braking at its emergency limit along its path from its placed
/// pose, is touched by `o`, which brakes as hard down to `keep` times its placed speed and goes
/// on at that along its own (`keep` 0: it brakes to a stand) while its centre is short of
/// `leave` on its route, within `ORDER_HORIZON_S`; boxes laid as `box_at` lays them.
fn first_contact(y: &Actor, o: &Actor, keep: f64, leave: f64) -> Option<f64> {
    let dt = 0.05;
    // Arc length after `t` braking at the emergency limit from `v0` down to `v1`, then at `v1`.
    let s_at = |a: &Actor, v1: f64, t: f64| {
        let (b, v0) = (a.lim.brake_max, a.v0);
        let tb = (v0 - v1) / b;
        a.s0 + if t < tb { v0 * t - 0.5 * b * t * t } else { (v0 * v0 - v1 * v1) / (2.0 * b) + v1 * (t - tb) }
    };
    let vo = keep * o.v0;
    // Braking both to a stand, nothing moves once both stand.
    let until = if keep > 0.0 { ORDER_HORIZON_S } else { (y.v0 / y.lim.brake_max).max(o.v0 / o.lim.brake_max) + dt };
    (1..)
        .map(|k| k as f64 * dt)
        .take_while(|&t| t <= until && s_at(o, vo, t - dt) <= leave)
        .find(|&t| box_at(y, s_at(y, 0.0, t)).overlaps(&box_at(o, s_at(o, vo, t)).grown(SWEEP_MARGIN)))
}

/// The speeds, as shares of its placed speed, down to which one that goes on may brake while
/// the other gives way (`order_crossings`).
const GO_ON_KEEP: [f64; 4] = [1.0, 0.75, 0.5, 0.25];

/// Where `x` and `y` are both braked to a stand as in `first_contact` without touching: whether
/// each stands in the other's way, `x` unable to go on along its path until its centre is past
/// `lx` without its box meeting `y`'s, standing (and `y` past `ly`). Both: a standoff.
fn standoff(x: &Actor, y: &Actor, (lx, ly): (f64, f64)) -> (bool, bool) {
    let stand = |a: &Actor| a.s0 + a.v0 * a.v0 / (2.0 * a.lim.brake_max);
    let (sx, sy) = (stand(x), stand(y));
    let blocked = |a: &Actor, from: f64, to: f64, theirs: &Obb| {
        let n = ((to - from) / 0.25).ceil().max(0.0) as usize;
        (0..=n).any(|k| box_at(a, from + k as f64 * 0.25).overlaps(theirs))
    };
    (blocked(x, sx, lx, &box_at(y, sy)), blocked(y, sy, ly, &box_at(x, sx)))
}

/// The box of vehicle `a` with its centre at route arc length `s`: through its junction where
/// its dry run steered it (`Bend::pose`); elsewhere on its path, at its placed offset.
fn box_at(a: &Actor, s: f64) -> Obb {
    let (center, yaw) = a.bend.as_ref().and_then(|b| b.pose(s)).unwrap_or_else(|| a.path.point(s, a.d0));
    Obb { center, yaw, length: 2.0 * a.hl, width: 2.0 * a.hw }
}

/// How far a box is grown all round where it is tested against a dry run's boxes
/// (`first_contact`, `Bend::touches`): a vehicle driven at other speeds than its dry run's
/// steers a few centimetres off it, and a bus's tail, clearing a car standing beside its turn by
/// a centimetre in the run, met it in the drive.
const SWEEP_MARGIN: f64 = 0.3;

/// `SWEEP_MARGIN` for the sweep's slices (`Bend::slices`), which already stretch each metre's
/// box over the widest reach there.
const SLICE_MARGIN: f64 = 0.1;

/// How long `first_contact` follows one that goes on, s.
const ORDER_HORIZON_S: f64 = 10.0;

fn no_order(a: &Actor, b: &Actor, [ta, tb]: [f64; 2], both: Option<f64>) -> Diagnostic {
    let (x, y) = (&a.info.name, &b.info.name);
    let mut d = Diagnostic::error(
        "E0207",
        format!(
            "`{x}` and `{y}` start too close to where their junction paths meet for either to give way to the other"
        ),
    );
    for (k, t) in [(a, ta), (b, tb)] {
        if let Some(span) = k.span {
            d = d.label(
                span,
                format!(
                    "`{}` cannot stop short of where the paths meet: giving way, braking as hard as it may, it is struck at {t:.1} s",
                    k.info.name
                ),
            );
        }
    }
    let both = match both {
        Some(t) => format!("with both braking as hard as they may, they meet at {t:.1} s"),
        None => "with both braking as hard as they may, each stands in the other's way".to_string(),
    };
    let fix = if [a, b].iter().any(|k| k.info.background) {
        "one of them is background traffic: lower `density`, or change the scenario's `seed`; or start the placed one further back or slower"
    } else {
        "start one of them further back or slower, so that it can hold while the other crosses, or delay it with `start after`; to stage their crash, write a `conflict`"
    };
    d.help(format!("{both}; {fix}"))
}

/// How far `a`'s box reaches out of its path's lane band anywhere through its junction
/// (`Bend::widest`).
fn off_tracking(a: &Actor) -> f64 {
    a.bend.as_ref().map_or(0.0, |b| b.widest)
}

/// Fill every vehicle's `bend` through its first junction by a dry run: the vehicle alone,
/// steered as `Sim::drive` steers (pure pursuit of its path, curvature bounded by its turning
/// radius and yaw rate) at its path's curve speed, from 10 m before the junction until it has
/// rejoined its path; each corner beyond the band is booked at its own place along the route.
/// Runs sharing a connector, start, box, turning radius, limits and route length (the curve
/// speeds it steers by brake toward the route's end) are done once.
fn assign_bends(map: &Map, actors: &mut [Actor], dt: f64) {
    // The first vehicle with each key runs; later ones take its bend.
    let mut runs: Vec<DryRun> = vec![];
    let mut run_of: Vec<Option<usize>> = vec![None; actors.len()];
    let mut keys: std::collections::HashMap<[u64; 10], usize> = std::collections::HashMap::new();
    for (i, a) in actors.iter().enumerate().filter(|(_, a)| a.vehicle) {
        let Some(j) = a.junction else { continue };
        let entry = j.exit - map.connectors[j.conn].path.length();
        let start = (entry - 10.0).max(a.s0.min(entry));
        let key = [
            j.conn as u64,
            start.to_bits(),
            j.exit.to_bits(),
            a.hl.to_bits(),
            a.hw.to_bits(),
            a.r_min.to_bits(),
            a.lim.yaw_rate.to_bits(),
            a.lim.lat_acc.to_bits(),
            a.lim.brake.to_bits(),
            a.path.length().to_bits(),
        ];
        run_of[i] = Some(*keys.entry(key).or_insert_with(|| {
            runs.push(DryRun::new(map, i, a, j, start));
            runs.len() - 1
        }));
    }
    // Each run is a long chain of dependent steps: the runs take a step each in turn, so that
    // their chains overlap. A run's steps read only its own state, so each is the run it
    // would be alone.
    let mut steps = 0;
    while steps < 2000 && runs.iter().any(|r| r.live) {
        for r in runs.iter_mut().filter(|r| r.live) {
            r.step(&actors[r.actor], dt);
        }
        steps += 1;
    }
    let bends: Vec<std::sync::Arc<Bend>> = runs.into_iter().map(|r| std::sync::Arc::new(r.finish(actors))).collect();
    for (a, r) in actors.iter_mut().zip(run_of) {
        if let Some(r) = r {
            a.bend = Some(bends[r].clone());
        }
    }
}

/// One dry run of `assign_bends`: its vehicle (track index), junction, the bend it fills, and
/// its state between steps.
struct DryRun {
    actor: usize,
    j: Junction,
    b: Bend,
    pos: DVec2,
    yaw: f64,
    s: f64,
    /// The unit heading of `yaw`, taken once per step: the corners' and the next step's.
    fwd: DVec2,
    live: bool,
}

impl DryRun {
    fn new(map: &Map, actor: usize, a: &Actor, j: Junction, start: f64) -> DryRun {
        let (kl, kr) = junction_bend(map, &a.path, j);
        let from = start - 2.0 * a.hl - 5.0;
        let mut b = Bend {
            from,
            reach: vec![],
            widest: sweep(a, kl.max(kr)),
            slices: vec![],
            bounds: (DVec2::INFINITY, DVec2::NEG_INFINITY),
            spans: vec![],
            poses: vec![],
            run_bounds: (DVec2::INFINITY, DVec2::NEG_INFINITY),
        };
        let (pos, yaw) = a.path.point(start, 0.0);
        b.poses.push((start, pos, yaw));
        DryRun { actor, j, b, pos, yaw, s: start, fwd: DVec2::from_angle(yaw), live: true }
    }

    /// One step of the run (`live` turns false at its end).
    #[inline]
    fn step(&mut self, a: &Actor, dt: f64) {
        let (j, from) = (self.j, self.b.from);
        let v = a.path.cap(self.s).clamp(1.0, 15.0);
        let k = pursuit(self.pos, self.fwd, a.path.point_fast_on(self.s + look_ahead(a, v)));
        let dist = v * dt;
        (self.pos, self.yaw) = steer(a, self.pos, self.yaw, k, dist, dt, 1.0);
        let (pos, yaw, fwd) = (self.pos, self.yaw, self.fwd);
        let [(s, off, _)] = a.path.frenet_many([pos], [self.s + dist]);
        self.s = s;
        let dir = DVec2::from_angle(yaw);
        let corners = Obb { center: pos, yaw, length: 2.0 * a.hl, width: 2.0 * a.hw }.corners_along(dir);
        let found = a.path.frenet_many(corners, corners.map(|q| s + (q - pos).dot(fwd)));
        let b = &mut self.b;
        // Arc lengths are kept increasing for `Bend::pose`'s search.
        if b.poses.last().is_none_or(|q| s > q.0) {
            b.poses.push((s, pos, yaw));
        }
        for (sq, dq, beyond) in found {
            if beyond > 0.0 || dq.abs() <= a.hw {
                continue;
            }
            let m = (sq - from).max(0.0) as usize;
            if b.reach.len() <= m {
                b.reach.resize(m + 1, (0.0, 0.0));
            }
            let (r, l) = &mut b.reach[m];
            if dq > 0.0 {
                *l = l.max(dq - a.hw);
            } else {
                *r = r.max(-dq - a.hw);
            }
            b.widest = b.widest.max(dq.abs() - a.hw);
        }
        self.fwd = dir;
        if (s > j.exit + a.hl && off.abs() < 0.05) || s >= a.path.length() - 1.0 {
            self.live = false;
        }
    }

    /// The bend, with its slices and spans.
    fn finish(self, actors: &[Actor]) -> Bend {
        let (a, mut b) = (&actors[self.actor], self.b);
        // Reaches within the band's margin are the band's business.
        for (m, &(r, l)) in b.reach.iter().enumerate() {
            if r > SLICE_MIN || l > SLICE_MIN {
                let (p, h) = a.path.point(b.from + m as f64 + 0.5, 0.5 * (l - r));
                let slice = Obb { center: p, yaw: h, length: 1.0, width: 2.0 * a.hw + r + l };
                for q in slice.corners() {
                    b.bounds = (b.bounds.0.min(q), b.bounds.1.max(q));
                }
                b.slices.push((b.from + m as f64, slice));
            }
        }
        let half = a.hl.hypot(a.hw);
        for &(_, p, _) in &b.poses {
            b.run_bounds = (b.run_bounds.0.min(p - half), b.run_bounds.1.max(p + half));
        }
        b.index();
        b
    }
}

/// The first centre position on `b`'s route from `lo` up to `hi` at which its box, half a metre
/// wider all round, meets `a`'s junction sweep beyond its path's band (`Bend::slices`): a U-turn
/// driven wide loops out over the cross street's approach, short of where the two connectors
/// come near each other.
fn sweep_entry(a: &Actor, b: &Actor, lo: f64, hi: f64) -> Option<f64> {
    let bend = a.bend.as_ref()?;
    let mut s = lo;
    while s < hi {
        let (p, h) = b.path.point(s, 0.0);
        let mine = Obb { center: p, yaw: h, length: 2.0 * b.hl + 1.0, width: 2.0 * b.hw + 1.0 };
        if bend.meets(&mine, f64::NEG_INFINITY, f64::INFINITY).is_some() {
            return Some(s);
        }
        s += 0.5;
    }
    None
}

/// How far `a`'s box reaches beyond the band its path's centre sweeps, on the outside of a bend
/// of curvature `k` (not signed): the corners' swing, and a bend tighter than the vehicle can
/// steer is driven wider, on its own turning radius.
fn sweep(a: &Actor, k: f64) -> f64 {
    let wide = if k > 1e-9 { (a.r_min - 1.0 / k).max(0.0) } else { 0.0 };
    swing(a.hl, k) + wide
}

/// The tightest curvature of `path` through its junction `j`, sampled every half metre.
fn junction_curvature(map: &Map, path: &Path, j: Junction) -> f64 {
    let (left, right) = junction_bend(map, path, j);
    left.max(right)
}

/// `junction_curvature` each way: the tightest left bend and the tightest right bend (both
/// positive, 0 where there is none).
fn junction_bend(map: &Map, path: &Path, j: Junction) -> (f64, f64) {
    let entry = j.exit - map.connectors[j.conn].path.length();
    let n = ((j.exit - entry) / 0.5).ceil().max(1.0) as usize;
    (0..=n)
        .map(|i| path.curvature(entry + (j.exit - entry) * i as f64 / n as f64))
        .fold((0.0, 0.0), |(l, r), k| (f64::max(l, k), f64::max(r, -k)))
}

/// How far the corners of a box of half length `hl`, tangent to an arc of curvature `k`, reach
/// beyond the band its centre sweeps (at most `hl`).
fn swing(hl: f64, k: f64) -> f64 {
    (0.5 * hl * hl * k).min(hl)
}

/// Connector `a` sampled every half metre against connector `b`'s path: arc length along `a`,
/// distance to `b` (infinite where the nearest point is beyond `b`'s ends, or where the two leave
/// the same lane: paths from one lane diverge, they do not cross), arc length along `b`. Taken
/// for `shared_zones`' test `distance < gap`: a distance beyond the profile's reach (at least
/// the gap asked for) reads infinite, its arc length NaN, as do paths from one lane.
type Profile = Vec<(f64, f64, f64)>;

/// The reach of a profile at least: wider than two cars' gap on bends (~3 m), so one profile
/// per pair of connectors serves most pairs of agents on them; a wider gap (a long vehicle's
/// off-tracking) recomputes it. Farther samples cost a bounding-box test, nearer ones a scan.
const PROFILE_REACH: f64 = 4.0;

fn profile<'p>(
    cache: &'p mut std::collections::HashMap<(usize, usize), (f64, Profile)>,
    map: &Map,
    a: usize,
    b: usize,
    gap: f64,
) -> &'p Profile {
    let entry = cache.entry((a, b)).or_insert((f64::NEG_INFINITY, vec![]));
    // Only the samples within the reach are projected; farther ones fail the test anyway.
    let covers = entry.0 >= gap;
    if !covers {
        let reach = gap.max(PROFILE_REACH);
        let (ca, cb) = (&map.connectors[a], &map.connectors[b]);
        let (la, lb) = (ca.path.length(), cb.path.length());
        let n = (la / 0.5).ceil().max(1.0) as usize;
        let on_b = Projector::new(&cb.path);
        let mut hint = 0;
        let (strict, mut seg) = (ca.path.strictly_increasing(), None);
        // A sample `x` along `a` from one at `floor` from `b` lies at least `floor - x` from it:
        // the samples up to where that reaches within `reach` (a margin short) are not taken.
        let mut far_until = f64::NEG_INFINITY;
        let samples = (0..=n)
            .map(|k| {
                let sa = la * k as f64 / n as f64;
                // Paths from one lane diverge: they do not cross.
                if ca.from == cb.from || sa < far_until {
                    return (sa, f64::INFINITY, f64::NAN);
                }
                let (s, d) = match on_b.project_within(ca.path.point_at_walk(sa, &mut seg, strict), &mut hint, reach) {
                    Ok(x) => x,
                    Err(floor) => {
                        far_until = sa + (floor - reach - 0.01);
                        return (sa, f64::INFINITY, f64::NAN);
                    }
                };
                let near = s > -0.5 && s < lb + 0.5;
                (sa, if near { d.abs() } else { f64::INFINITY }, s)
            })
            .collect();
        *entry = (reach, samples);
    }
    &entry.1
}

/// `shared_zones`' answer: per stretch, its first and last arc length, where its middle
/// projects onto the other connector, and how near the other path comes within it.
type Zones = Vec<(f64, f64, f64, f64)>;

/// The stretches of connector `a` (arc lengths along it) whose samples in `profile` lie within
/// `gap` of the other path, those less than `join` apart taken as one; with each, where its
/// middle projects onto `b`. Two paths can meet twice (a roundabout exit beside
/// another's entry, then the ring).
fn shared_zones(map: &Map, (a, b): (usize, usize), profile: &Profile, gap: f64, join: f64) -> Zones {
    let mut zones: Zones = vec![];
    for &(sa, d, _) in profile {
        if d < gap {
            match zones.last_mut() {
                Some(z) if sa - z.1 <= join => {
                    z.1 = sa;
                    z.3 = z.3.min(d);
                }
                _ => zones.push((sa, sa, 0.0, d)),
            }
        }
    }
    for z in &mut zones {
        // `pose_at`'s point, without the heading's arctangent.
        let p = map.connectors[a].path.point_at(0.5 * (z.0 + z.1));
        z.2 = map.connectors[b].path.project(p).0;
    }
    zones
}

/// Heading and length of a walk straight across the nearest road from `p`: perpendicular to
/// the nearest lane, toward it, ending 2 m past the last lane or shoulder met; and how far along
/// it the road begins.
fn cross_line(map: &Map, p: DVec2) -> Option<(f64, f64, f64)> {
    let mut near: Option<(usize, f64, f64)> = None;
    for (i, l) in map.lanes.iter().enumerate() {
        if l.centre.points.len() < 2 {
            continue;
        }
        let (s, d) = l.centre.project(p);
        if near.is_none_or(|b| d.abs() < b.2.abs()) {
            near = Some((i, s, d));
        }
    }
    let (i, s, d) = near?;
    let (_, h) = map.lanes[i].centre.pose_at(s);
    let dir = DVec2::from_angle(h).perp() * if d > 0.0 { -1.0 } else { 1.0 };
    // A lane holds q only within its half width and shoulder of its centre line: where the box
    // of that line, grown by as much and a millimetre (far above rounding), does not hold q,
    // the projection (this loop's cost) would say no, so it is not made.
    let boxes: Vec<(DVec2, DVec2)> = map
        .lanes
        .iter()
        .map(|l| {
            let grow = DVec2::splat(l.width / 2.0 + l.shoulder_right.max(0.0) + 1e-3);
            let (lo, hi) = l
                .centre
                .points
                .iter()
                .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &q| (lo.min(q), hi.max(q)));
            (lo - grow, hi + grow)
        })
        .collect();
    let on_road = |q: DVec2| {
        map.lanes.iter().zip(&boxes).any(|(l, (lo, hi))| {
            if q.x < lo.x || q.x > hi.x || q.y < lo.y || q.y > hi.y {
                return false;
            }
            let (s, d) = l.centre.project(q);
            s > 0.0 && s < l.centre.length() && d.abs() <= l.width / 2.0 + if d < 0.0 { l.shoulder_right } else { 0.0 }
        })
    };
    let (mut first, mut last) = (None, None);
    for k in 0..=160 {
        let dist = k as f64 * 0.5;
        if on_road(p + dir * dist) {
            first = first.or(Some(dist));
            last = Some(dist);
        } else if last.is_some_and(|l| dist - l > 4.0) {
            break;
        }
    }
    Some((dir.y.atan2(dir.x), last? + 2.0, (first? - 0.5).max(0.0)))
}

/// The first frame at which pass 2 can differ from pass 1: the first whose step starts at or
/// after a planned striker's departure (`Sim::step`), or an earlier one at which a planned pair
/// overlaps (`Sim::latch` looks at those). Before it both passes run the same steps on the same
/// states, so pass 2 resumes from pass 1's state there.
fn pass2_start(actors: &[Actor], confs: &[Conf], plans: &[Option<Plan>], states: &[Vec<State>], dt: f64) -> usize {
    let frames = states.len();
    let mut start = frames.max(1);
    for (k, plan) in confs.iter().zip(plans).filter_map(|(k, p)| p.as_ref().map(|p| (k, p))) {
        // The same test as `Sim::step`, frame by frame, so the float comparison is the same one.
        if let Some(f) = (1..frames).find(|&f| (f - 1) as f64 * dt >= plan.t_depart - 1e-9) {
            start = start.min(f);
        }
        if let Some(f) = (1..start).find(|&f| {
            let s = &states[f];
            actors[k.af].obb(&s[k.af]).overlaps(&actors[k.st].obb(&s[k.st]))
        }) {
            start = start.min(f);
        }
    }
    start
}

// ---------------------------------------------------------------- the frame loop

/// Agent `j` as `Sim::candidates` sees it this frame: copies of its state's and actor's fields
/// (same bits), packed so that scanning everyone reads 72 contiguous bytes per agent, not its
/// whole state and actor.
#[derive(Clone, Copy, Debug)]
struct Near {
    pos: DVec2,
    /// Unit heading (`Sim::dirs`).
    dir: DVec2,
    v: f64,
    radius: f64,
    hl: f64,
    hw: f64,
    /// Holding at its stop line for an emergency vehicle (`Sim::yield_state`).
    gives_way: bool,
    /// A vehicle that one clearing a junction for an emergency vehicle does not wait for
    /// (`Actor::cleared_past`).
    cleared_past: bool,
}

impl Near {
    fn new(st: &State, a: &Actor, dir: DVec2, gives_way: bool) -> Near {
        Near {
            pos: st.pos,
            dir,
            v: st.v,
            radius: a.radius,
            hl: a.hl,
            hw: a.hw,
            gives_way,
            cleared_past: a.cleared_past(st),
        }
    }
}

/// What `Sim::candidates` needs of agent `i`'s step in `Sim::drive`.
struct Corridor {
    look: f64,
    /// The lateral band the agent sweeps this step.
    lo: f64,
    hi: f64,
    /// Holding its offset (no lateral move this step).
    holding: bool,
    /// The straight run of its route it is on, when holding.
    line: Option<Line>,
    /// Clearing a junction for an emergency vehicle.
    clearing: bool,
    /// The agent it queues behind.
    named: Option<usize>,
    /// How far behind its centre along a straight run an agent is still kept: its tail may
    /// swing over one beside it in a bend within reach (`Bend::touches`), else 0.
    back: f64,
}

/// How far inside the look-ahead's bounds `candidate` counts an agent on a straight run, m.
const LINE_EPS: f64 = 1e-3;
/// From this many agents on, `candidates` asks `AlongIndex` for the agents near a straight run
/// instead of testing everyone (below, building it costs more than it saves: measured slower
/// at 42 agents on `highway_merge`, with its many lane directions, faster at 50 on one road).
const ALONG_MIN_AGENTS: usize = 48;
/// Coordinates up to which `ALONG_MARGIN` bounds the rounding of the index's bounds.
const ALONG_FAR: f64 = 1e6;
const ALONG_MARGIN: f64 = 0.01;
/// Width of `AlongIndex`'s lanes across the direction, m.
const ALONG_BIN: f64 = 2.0;

/// Every agent's place along (`pos . dir`) and across (`dir x pos`) one direction, in bins
/// across it, each sorted along: the agents near a stretch of a straight run are a few ranges.
struct AlongIndex {
    key: (u64, u64),
    /// The first bin across, and where each bin's agents start in `along` / `agent`.
    min_bin: i64,
    starts: Vec<usize>,
    along: Vec<f64>,
    agent: Vec<usize>,
    /// Agents whose speed across the direction `candidate` counts as moving across it (or
    /// that it cannot tell), not holding at a line.
    crossing: Vec<usize>,
    /// Every coordinate finite and within `ALONG_FAR`, and not too many bins.
    tame: bool,
}

impl AlongIndex {
    fn new(near: &[Near], dir: DVec2) -> AlongIndex {
        let mut ix = AlongIndex {
            key: (dir.x.to_bits(), dir.y.to_bits()),
            min_bin: 0,
            starts: vec![],
            along: vec![],
            agent: vec![],
            crossing: vec![],
            tame: near.iter().all(|b| b.pos.x.abs() < ALONG_FAR && b.pos.y.abs() < ALONG_FAR),
        };
        if !ix.tame {
            return ix;
        }
        let bin = |b: &Near| (dir.perp_dot(b.pos) / ALONG_BIN).floor() as i64;
        let (lo, hi) = near.iter().fold((i64::MAX, i64::MIN), |(l, h), b| (l.min(bin(b)), h.max(bin(b))));
        if near.is_empty() || hi - lo > 4 * near.len() as i64 + 64 {
            ix.tame = false;
            return ix;
        }
        // A counting sort by bin, then each bin along.
        ix.min_bin = lo;
        let mut starts = vec![0usize; (hi - lo + 2) as usize];
        for b in near {
            starts[(bin(b) - lo + 1) as usize] += 1;
        }
        for k in 1..starts.len() {
            starts[k] += starts[k - 1];
        }
        let mut fill = starts.clone();
        let mut items = vec![(0.0, 0usize); near.len()];
        for (j, b) in near.iter().enumerate() {
            let k = &mut fill[(bin(b) - lo) as usize];
            items[*k] = (b.pos.dot(dir), j);
            *k += 1;
            // As `candidate` takes it, with room for rounding.
            let v_lat = b.v * dir.perp_dot(b.dir);
            let steady = v_lat.abs() < 0.3 - LINE_EPS - 1e-6;
            if !steady && !b.gives_way {
                ix.crossing.push(j);
            }
        }
        for w in starts.windows(2) {
            items[w[0]..w[1]].sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
        }
        (ix.along, ix.agent) = items.into_iter().unzip();
        ix.starts = starts;
        ix
    }

    /// Append the agents placed along within `lo..=hi` in the bins holding `l_lo..=l_hi` across.
    fn collect(&self, lo: f64, hi: f64, l_lo: f64, l_hi: f64, out: &mut Vec<usize>) {
        let nbins = self.starts.len() as i64 - 1;
        let b_lo = ((l_lo / ALONG_BIN).floor() as i64 - self.min_bin).max(0);
        let b_hi = ((l_hi / ALONG_BIN).floor() as i64 - self.min_bin).min(nbins - 1);
        for b in b_lo..=b_hi {
            let (s, e) = (self.starts[b as usize], self.starts[b as usize + 1]);
            let first = s + self.along[s..e].partition_point(|&x| x < lo);
            let last = first + self.along[first..e].partition_point(|&x| x <= hi);
            out.extend_from_slice(&self.agent[first..last]);
        }
    }
}

/// `Sim::zone_rank`'s answer.
type Rank = Option<(u8, f64, f64)>;

struct Sim<'a, 'b> {
    actors: &'a [Actor],
    confs: &'a [Conf],
    /// Per conflict (pass 2 only).
    plans: &'a [Option<Plan>],
    pass1: Option<&'a Tracks>,
    /// Per actor: the plan it strikes with, if any.
    striker: Vec<Option<usize>>,
    latched: Vec<bool>,
    prev_depth: Vec<f64>,
    dt: f64,
    cur: Vec<State>,
    next: Vec<State>,
    /// Unit heading of every agent in `cur`: pair checks use dot and cross products, not trig.
    dirs: Vec<DVec2>,
    /// The bits of the heading each of `dirs` was taken from.
    dir_yaw: Vec<Option<u64>>,
    /// Per agent, this frame: `yield_state`, with the right-of-way rule's hold folded in.
    yielding: Vec<(Option<f64>, bool)>,
    /// Per agent, this frame: held by the right-of-way rule or at the kerb (`right_of_way`).
    ruled: Vec<bool>,
    /// Per agent, this frame: how far it may go while holding for anyone (scratch).
    held: Vec<Option<f64>>,
    /// Per agent, this frame: another vehicle is ahead of it on its junction approach, not yet
    /// past its stop line (`queued`).
    behind: Vec<bool>,
    /// Per agent: a slot for its approach lane (`Actor::approach`), dense from 0; and per slot,
    /// this frame, the two least distances to the stop line among the agents `queued` counts
    /// there, with their indices (`queue_heads`).
    approach_slot: Vec<Option<usize>>,
    lane_least: Vec<[(f64, usize); 2]>,
    /// Per agent: where its crossings start in `ranks`; and per crossing, this frame, its
    /// `zone_rank` once asked for (`rank`): each pair's rule asks for both of its zones' ranks
    /// from either side.
    cross_at: Vec<usize>,
    ranks: std::cell::RefCell<Vec<Option<Rank>>>,
    /// This frame: agents easing aside (`away_from`, triggered), for `pass_offset`.
    easing: Vec<usize>,
    /// Per agent, this frame: what `candidates` reads, packed.
    near: Vec<Near>,
    /// This frame: everyone placed along and across each straight-run direction `candidates`
    /// asked about (`AlongIndex`), built on the first ask; and the agents one ask yields.
    along: std::cell::RefCell<Vec<AlongIndex>>,
    subset: std::cell::RefCell<Vec<usize>>,
    /// The largest bounding radius of any agent.
    max_radius: f64,
    /// `candidates`' output, and `Path::frenet_near` of each, kept to reuse their allocations.
    cand: std::cell::RefCell<Vec<usize>>,
    proj: std::cell::RefCell<Vec<(f64, f64, f64, DVec2)>>,
    /// A striker's braking course (`braking_course`), kept between frames for its capacity.
    course: std::cell::RefCell<Vec<(f64, DVec2, f64)>>,
    /// Per striker, each bystander that held it back at full speed: when first, and for how
    /// many frames.
    blocked_by: std::cell::RefCell<Vec<Vec<(usize, f64, u32)>>>,
    /// The first move the overlap safety net undid at a speed the agent could not have braked
    /// from within its limits in one step: the agent stopped, the one it would have run into,
    /// and when.
    first_hard: Option<(usize, usize, f64)>,
    /// `overlap_pairs`' boxes and output, kept likewise.
    sweep: Vec<(DVec2, DVec2, usize)>,
    pairs: Vec<(usize, usize)>,
    /// Where to keep every frame's states (pass 1, for `resume`).
    keep: Option<&'b mut Vec<Vec<State>>>,
    /// The first frame to simulate: earlier ones are already in the output (`resume`).
    first: usize,
    /// Frames `..first` of the output, copied by `run`.
    prefix: Option<&'b Tracks>,
}

/// What a run saw besides its tracks.
struct Report {
    /// Per striker, the bystander that held it back longest at full speed, and from when.
    blocked_by: Vec<Option<(usize, f64)>>,
    /// The first move the overlap safety net undid beyond the mover's braking limit
    /// (`Sim::first_hard`).
    first_hard: Option<(usize, usize, f64)>,
}

impl<'a, 'b> Sim<'a, 'b> {
    fn new(
        actors: &'a [Actor],
        confs: &'a [Conf],
        plans: &'a [Option<Plan>],
        pass1: Option<&'a Tracks>,
        dt: f64,
    ) -> Self {
        let mut striker = vec![None; actors.len()];
        for (k, p) in plans.iter().enumerate() {
            if p.is_some() {
                striker[confs[k].af] = Some(k);
            }
        }
        let cur: Vec<State> = actors.iter().map(initial).collect();
        let mut lanes: Vec<usize> = actors.iter().filter_map(|a| a.approach).collect();
        lanes.sort_unstable();
        lanes.dedup();
        let approach_slot = actors.iter().map(|a| a.approach.and_then(|l| lanes.binary_search(&l).ok())).collect();
        let cross_at: Vec<usize> = actors
            .iter()
            .scan(0, |n, a| {
                *n += a.crossings.len();
                Some(*n - a.crossings.len())
            })
            .collect();
        let crossings = actors.iter().map(|a| a.crossings.len()).sum();
        Sim {
            actors,
            confs,
            plans,
            pass1,
            striker,
            latched: vec![false; confs.len()],
            prev_depth: vec![0.0; confs.len()],
            dt,
            next: cur.clone(),
            dirs: cur.iter().map(|s| DVec2::from_angle(s.yaw)).collect(),
            dir_yaw: vec![],
            yielding: vec![(None, false); actors.len()],
            ruled: vec![false; actors.len()],
            held: vec![None; actors.len()],
            behind: vec![false; actors.len()],
            approach_slot,
            lane_least: vec![[(f64::INFINITY, usize::MAX); 2]; lanes.len()],
            cross_at,
            ranks: std::cell::RefCell::new(vec![None; crossings]),
            easing: Vec::with_capacity(actors.len()),
            near: Vec::with_capacity(actors.len()),
            along: std::cell::RefCell::new(vec![]),
            subset: std::cell::RefCell::new(Vec::with_capacity(actors.len())),
            max_radius: actors.iter().map(|a| a.radius).fold(0.0, f64::max),
            cand: std::cell::RefCell::new(Vec::with_capacity(actors.len() + 1)),
            proj: std::cell::RefCell::new(Vec::with_capacity(actors.len() + 1)),
            course: std::cell::RefCell::new(Vec::with_capacity(COURSE_STEPS)),
            blocked_by: std::cell::RefCell::new(vec![Vec::new(); actors.len()]),
            first_hard: None,
            sweep: Vec::with_capacity(actors.len()),
            pairs: vec![],
            cur,
            keep: None,
            first: 1,
            prefix: None,
        }
    }

    fn keep_states(mut self, keep: &'b mut Vec<Vec<State>>) -> Self {
        self.keep = Some(keep);
        self
    }

    /// Start at frame `first` from `states[first - 1]`, taking frames `..first` from `done`
    /// (the run that produced `states`). Nothing before `first` may be latched.
    fn resume(mut self, done: &'b Tracks, states: &[Vec<State>], first: usize) -> Self {
        if first > 1 && first <= states.len() {
            self.cur.clone_from(&states[first - 1]);
            self.first = first;
            self.prefix = Some(done);
        }
        self
    }

    /// Run the frames into `out`; returns, per striker, the bystander that held it back longest,
    /// and from when (`blocked_by`): a car it slowed for once, in passing, did not make it miss.
    fn run(mut self, out: &mut Tracks) -> Report {
        if out.frames == 0 {
            return self.held_longest();
        }
        match self.prefix {
            Some(done) => {
                for (i, (p, v)) in done.poses.iter().zip(&done.speeds).enumerate() {
                    out.poses[i].extend_from_slice(&p[..self.first]);
                    out.speeds[i].extend_from_slice(&v[..self.first]);
                }
            }
            None => self.record(out),
        }
        for f in self.first..out.frames {
            let t = (f - 1) as f64 * self.dt;
            // An agent whose heading has not changed (bit for bit) keeps its unit heading: the
            // same call on the same bits. Standing and straight-driving agents take no sine.
            self.dirs.resize(self.cur.len(), DVec2::X);
            self.dir_yaw.resize(self.cur.len(), None);
            for ((d, y), st) in self.dirs.iter_mut().zip(&mut self.dir_yaw).zip(&self.cur) {
                if *y != Some(st.yaw.to_bits()) {
                    (*d, *y) = (DVec2::from_angle(st.yaw), Some(st.yaw.to_bits()));
                }
            }
            self.easing.clear();
            for (j, (o, b)) in self.cur.iter().zip(self.actors.iter()).enumerate() {
                if o.triggered && matches!(b.lateral, Lat::Away { .. }) {
                    self.easing.push(j);
                }
            }
            // Emergency holds first: the right-of-way rule ranks one holding for an emergency
            // vehicle as not coming.
            for i in 0..self.actors.len() {
                self.yielding[i] = self.yield_state(i);
            }
            self.queue_heads();
            self.ranks.get_mut().fill(None);
            for i in 0..self.actors.len() {
                let rule = self.right_of_way(i, t);
                self.ruled[i] = rule.is_some();
                self.held[i] = match (self.yielding[i].0, rule) {
                    (Some(x), Some(y)) => Some(x.min(y)),
                    (x, y) => x.or(y),
                };
            }
            for i in 0..self.actors.len() {
                self.yielding[i].0 = self.held[i];
            }
            // Packed after the holds are final: `candidates` reads them as `drive` does.
            self.near.clear();
            for ((st, a), (&dir, y)) in self.cur.iter().zip(self.actors).zip(self.dirs.iter().zip(&self.yielding)) {
                self.near.push(Near::new(st, a, dir, y.0.is_some()));
            }
            self.along.get_mut().clear();
            for i in 0..self.actors.len() {
                self.next[i] = self.step(i, t, f);
            }
            self.resolve_overlaps(f);
            self.latch(f, out);
            std::mem::swap(&mut self.cur, &mut self.next);
            self.record(out);
        }
        self.held_longest()
    }

    fn held_longest(self) -> Report {
        let longest = |held: Vec<(usize, f64, u32)>| {
            // The first of equals: the list is in order of first hold.
            held.into_iter().rev().max_by_key(|h| h.2).map(|(j, t, _)| (j, t))
        };
        Report {
            blocked_by: self.blocked_by.into_inner().into_iter().map(longest).collect(),
            first_hard: self.first_hard,
        }
    }

    fn record(&mut self, out: &mut Tracks) {
        if let Some(keep) = self.keep.as_deref_mut() {
            keep.push(self.cur.clone());
        }
        for (i, st) in self.cur.iter().enumerate() {
            out.poses[i].push(Pose { x: st.pos.x, y: st.pos.y, yaw: st.yaw });
            out.speeds[i].push(st.v);
        }
    }

    /// Conflict pairs may come close and overlap; nobody else may.
    #[inline]
    fn exempt(&self, i: usize, j: usize) -> bool {
        self.confs.iter().any(|k| (k.af == i && k.st == j) || (k.af == j && k.st == i))
    }

    /// The state of agent `i` at `t + dt`, from everyone's state at `t` (frame `f - 1`).
    fn step(&self, i: usize, t: f64, f: usize) -> State {
        let a = &self.actors[i];
        let st = self.cur[i];
        match &a.drive {
            Drive::Static => st,
            Drive::Replay(keys) => {
                let (p, yaw) = replay(keys, t + self.dt);
                State { pos: p, yaw, v: p.distance(st.pos) / self.dt, ..st }
            }
            Drive::Mover if st.frozen => State { v: 0.0, ..st },
            Drive::Mover => match self.striker[i].and_then(|k| self.plans[k].as_ref().map(|p| (k, p))) {
                Some((k, plan)) if t >= plan.t_depart - 1e-9 && !self.latched[k] => self.intercept(i, plan, t, f),
                _ => self.drive(i, t),
            },
        }
    }

    fn drive(&self, i: usize, t: f64) -> State {
        let (a, st, dt) = (&self.actors[i], self.cur[i], self.dt);
        let lim = a.lim;
        if st.stopped {
            return State { v: 0.0, ..st };
        }
        let active = t >= a.start - 1e-9;
        let v_des = if active { a.v_goal } else { a.v_hold }.min(a.path.cap(st.s));

        // Lateral: where the profile would put us next, and the band we sweep meanwhile.
        let mut triggered = st.triggered;
        let (target, dur) = match a.lateral {
            Lat::Hold => (None, 1.0),
            Lat::Shift { target, dur } => (active.then_some(target), dur),
            Lat::Away { who, target, dur } => {
                if active && !triggered {
                    let o = &self.cur[who];
                    let (sk, lk, beyond, _) =
                        a.path.frenet(o.pos, st.s + (o.pos - st.pos).dot(DVec2::from_angle(st.yaw)));
                    let behind = st.s - sk;
                    let closing = o.v - st.v;
                    triggered = beyond < 1.0
                        && behind > 0.0
                        && behind < 40.0f64.max(closing * 5.0)
                        && (lk - st.d).abs() < 4.0
                        && (closing > 0.0 || behind < 15.0);
                }
                (triggered.then_some(target), dur)
            }
        };
        let mut phase = st.phase;
        let mut d_next = st.d;
        let mut pass_target = None;
        if let Some(tg) = target {
            phase = (st.phase + dt / dur).min(1.0);
            d_next = a.d0 + (tg - a.d0) * quintic(phase);
        } else if a.vehicle && matches!(a.lateral, Lat::Hold) {
            // Squeeze past whoever is easing aside for us (`away_from`), then settle back.
            let look = st.v * st.v / (2.0 * lim.brake) + 2.5 * st.v + 15.0;
            let tg = self.pass_offset(i, look).unwrap_or(a.d0);
            pass_target = Some(tg);
            d_next = st.d + (tg - st.d).clamp(-PASS_LAT_RATE * dt, PASS_LAT_RATE * dt);
        }
        if a.vehicle {
            // A vehicle drifts sideways only as fast as its heading can follow (below 3 m/s the
            // bound stays at its 3 m/s value, so a car creeping in a queue still changes lane):
            // a slow lane change takes longer than its nominal duration instead of crabbing.
            let max_step = st.v.max(3.0) * slip_tan(a) * dt;
            d_next = st.d + (d_next - st.d).clamp(-max_step, max_step);
            // Nor does the reference run ahead of the box: a car creeping at walking pace would
            // otherwise finish its lane change on paper, seconds before its body has moved, and
            // point its nose ever more steeply into the next lane, past the gap acceptance.
            d_next = d_next.clamp(st.d.min(st.off - MAX_LEAD), st.d.max(st.off + MAX_LEAD));
        }
        let margin = if a.vehicle { 0.25 } else { 0.1 };
        // Till the reference is there: the profile's clock runs out while a creeping car's
        // reference is held back by its body (`MAX_LEAD`), and the target lane must still be
        // watched (a car creeping alongside in it was driven into).
        let goal_d = target.filter(|&tg| st.phase < 1.0 || (st.d - tg).abs() > 1e-3).or(pass_target).unwrap_or(st.d);
        // The band the box occupies now: a steering vehicle lags its reference offset.
        let (cur_lo, cur_hi) = (st.d.min(st.off) - a.hw, st.d.max(st.off) + a.hw);
        // Turned off the path while it moves sideways, our nose reaches out of that band on the
        // side it points: a bus easing into the inner lane at 0.12 rad put its front corner on
        // the centre line, into the nose of an oncoming bus doing the same (seed 654).
        let (nose_lo, nose_hi) = match target {
            Some(_) if a.vehicle => {
                let th = wrap_angle(st.yaw - a.path.point(st.s, st.off).1);
                let reach = (a.hl * th.sin().abs() - a.hw * (1.0 - th.cos())).max(0.0);
                if th > 0.0 { (0.0, reach) } else { (reach, 0.0) }
            }
            _ => (0.0, 0.0),
        };
        let (lo, hi) = (cur_lo.min(goal_d - a.hw) - margin - nose_lo, cur_hi.max(goal_d + a.hw) + margin + nose_hi);

        // Half done once the profile and the body itself are half way over.
        let half_done = st.phase >= 0.5 && target.is_none_or(|tg| (st.off - a.d0).abs() >= 0.5 * (tg - a.d0).abs());
        let fwd = self.dirs[i];
        let look = st.v * st.v / (2.0 * lim.brake) + 2.5 * st.v + 15.0;
        let mut acc = idm_free(st.v, v_des, lim, dt);
        // Over the curve-speed profile (it falls toward each bend at the comfortable braking),
        // brake down onto it: IDM's free term alone brakes about 0.5 m/s2 when 5% over, and a
        // motorcycle entering its U-turn a fifth over ran 1.7 m wide into the next lane.
        if a.vehicle {
            let cap_next = a.path.cap(st.s + st.v * dt);
            if st.v > cap_next {
                acc = acc.min(((cap_next - st.v) / dt).max(-lim.brake));
            }
        }
        let mut hard = f64::INFINITY;
        // How far our centre may go before our box on its run through the bend ahead meets one
        // standing (`Bend::touches`): beside us, where our tail swings, or ahead where the
        // slices miss it; and how far on that is looked for beside us.
        let mut touch_rem = f64::INFINITY;
        let sweep_to = st.s + 2.0 * a.hl + look;
        // The least this step can advance braking at the limit.
        let shortest = (st.v * dt - 0.5 * lim.brake_max * dt * dt).max(0.0);
        let mut side_blocked = false;
        // Walkers beside each other on converging lines (side by side on a curve's sidewalk):
        // each steps away from the other (sum of sides, -1 right, +1 left).
        let mut aside = 0.0f64;
        let named = match a.stop {
            StopGoal::Behind(k) if active => Some(k),
            _ => None,
        };
        let (yield_rem, clearing) = self.yielding[i];
        // On a straight stretch of our route, an agent's route coordinates are its coordinates
        // along the line: those that provably change nothing below are passed over without the
        // projection (the pair loop's main cost). Only when holding our offset: lateral moves
        // look at everyone alongside.
        let line = if d_next == st.d { a.path.straight_run(st.s) } else { None };
        let mut cand = self.cand.borrow_mut();
        // Our sweep through the junction ahead (`Bend`, read in the loop below at each one's
        // place) and the reach of the corner test for turned boxes there widen the band in which
        // `candidates` may not pass anyone over.
        let (c_lo, c_hi, back) = match &a.bend {
            Some(b) => match b.within(st.s - 2.0, st.s + a.hl + look + self.max_radius + 2.0) {
                (0.0, 0.0) => (lo, hi, 0.0),
                (r, l) => (
                    lo.min(st.d - a.hw - margin - r) - 1.5,
                    hi.max(st.d + a.hw + margin + l) + 1.5,
                    a.hl + self.max_radius,
                ),
            },
            None => (lo, hi, 0.0),
        };
        let corridor = Corridor { look, lo: c_lo, hi: c_hi, holding: d_next == st.d, line, clearing, named, back };
        self.candidates(i, &corridor, &mut cand);
        // Their projections onto our route first, in a loop of their own: each is a chain of
        // dependent steps, and independent chains overlap there (below, every decision waits
        // on its own).
        let mut proj = self.proj.borrow_mut();
        proj.clear();
        // Where the Newton search does not settle (near a U-turn's loop), the first foot ahead
        // of our centre within the corridor's reach, searched over the stretch anyone could
        // meet us on (`Path::frenet_near`): an unsettled projection put a car crossing 18 m
        // from an ambulance's loop a quarter metre off its path, and stopped it dead (seed 649).
        let window = (st.s - a.hl - 2.0 * self.max_radius, st.s + a.hl + look + 2.0 * self.max_radius);
        let reach = c_lo.abs().max(c_hi.abs()) + self.max_radius;
        proj.extend(cand.iter().map(|&j| {
            let p = self.cur[j].pos;
            a.path.frenet_near(p, st.s + (p - st.pos).dot(fwd), window, st.s, reach)
        }));
        for (&j, &(sj, lj, beyond, th)) in cand.iter().zip(proj.iter()) {
            let (o, b) = (&self.cur[j], &self.actors[j]);
            // cos and sin of the other's heading relative to the path's.
            let (cr, sr) = (self.dirs[j].dot(th), th.perp_dot(self.dirs[j]));
            let ext_lon = b.hl * cr.abs() + b.hw * sr.abs();
            let ext_lat = b.hl * sr.abs() + b.hw * cr.abs();
            // The one we queue behind, while it is on our way: once a vehicle has turned off,
            // more than a lane from our path, or turned back toward us (a U-turn), there is no
            // queue to keep (its projection onto our route then says nothing of a gap; a car
            // queued behind a motorcycle's U-turn braked at -27 m/s2 for it coming back in the
            // next lane). A walker or an animal on the verge stays named.
            let is_named = named == Some(j) && (!b.vehicle || (lj.abs() - ext_lat < a.hw + 3.0 && cr > -0.5));
            if beyond > 0.5 && !is_named {
                continue;
            }
            let ds = sj - st.s;
            if d_next != st.d && ds.abs() < a.hl + ext_lon + 0.5 {
                let (nlo, nhi) = (st.d.min(d_next) - a.hw - 0.1, st.d.max(d_next) + a.hw + 0.1);
                let (jlo, jhi) = (lj - ext_lat, lj + ext_lat);
                let now = jlo < cur_hi && jhi > cur_lo;
                if jlo < nhi && jhi > nlo && !now {
                    side_blocked = true;
                }
            }
            // Gap acceptance: a lateral move not yet half done waits while the target band has
            // someone too close ahead or closing from behind.
            if d_next != st.d && !half_done {
                let (jlo, jhi) = (lj - ext_lat, lj + ext_lat);
                let in_target = jlo < goal_d + a.hw + 0.1 && jhi > goal_d - a.hw - 0.1;
                let in_current = jlo < cur_hi && jhi > cur_lo;
                if in_target && !in_current {
                    let v_j = o.v * cr;
                    let g = ds.abs() - a.hl - ext_lon;
                    let (back, front) = if ds < 0.0 { (v_j, st.v) } else { (st.v, v_j) };
                    if g < 2.0 + 0.8 * back + (back - front).max(0.0).powi(2) / 6.0 {
                        side_blocked = true;
                    }
                }
            }
            // Also one about to walk: stopped by the overlap guard as it set off beside another,
            // a walker that stepped aside only once moving never moved again (seed 1237).
            if !a.vehicle && !b.vehicle && (st.v > 0.1 || (active && v_des > 0.1)) && ds.abs() < a.hl + ext_lon {
                let rel = lj - st.d;
                if rel.abs() - ext_lat - a.hw < WALK_CLEAR {
                    aside -= rel.signum();
                }
            }
            if ds <= 0.0 {
                // Standing beside us where our tail will swing over it in the bend ahead (a bus
                // turning right from the outer of two lanes, a bus standing in the inner one):
                // the slices, laid where the corners project, put the hit behind our front, and
                // we turned into it. Found on the dry run's boxes, our centre goes no further
                // than its last place clear of it.
                // Also where one still rolling will stand: holding (at its line, short of a
                // zone) or at its stop goal (a car stopping at its line beside a bus that had
                // set off was found standing in the tail's way only once the bus could no
                // longer stop short).
                let stands = || {
                    // At the latest: where its braking limit halts it, past a goal it cannot
                    // stop short of (a van at 9.8 m/s 6 m before its line, seed 819).
                    let goal = match b.stop {
                        StopGoal::Front(sf) => Some(sf - b.hl),
                        StopGoal::Centre(sc) => Some(sc),
                        _ => None,
                    }
                    .map(|g| g.max(o.s + o.v * o.v / (2.0 * b.lim.brake_max)))
                    .filter(|&g| g > o.s);
                    [
                        (o.v < 0.5).then(|| b.obb(o)),
                        self.held_at(j).map(|q| b.obb(&q)),
                        goal.map(|sc| {
                            let (pos, yaw) = b.path.point(sc, o.d);
                            b.obb(&State { pos, yaw, ..*o })
                        }),
                    ]
                };
                if a.vehicle
                    && ds > -(a.hl + b.hl)
                    && let Some(bd) = &a.bend
                    && let Some(at) = stands()
                        .iter()
                        .flatten()
                        .filter_map(|q| bd.touches(a, &q.grown(SWEEP_MARGIN), st.s, sweep_to))
                        .reduce(f64::min)
                {
                    touch_rem = touch_rem.min(at - st.s - 0.2);
                }
                continue;
            }
            let gap = ds - a.hl - ext_lon;
            if gap > look && !is_named {
                continue;
            }
            let (v_lon, v_lat) = (o.v * cr, o.v * sr);
            // In the lane we are in now; or in the band we are moving into, and then only when
            // ahead of our front (alongside is the gap acceptance's business).
            // In a bend our box's corners swing out of the band its centre sweeps (a bus turning
            // at a junction reaches into the next lane): widen the band by that off-tracking
            // (`Bend`), for one standing there, holding at its line or coming toward us (one
            // crossing or going our way will have gone by when we sweep past), and only ahead of
            // our front. Taken where it stands on our route, also while we are still on the
            // straight before the bend: found only once in the bend, it may be too close to stop
            // for within our limits. Only outward: in a left bend the corners reach out to the
            // right, while on the inside the middle of the box's side is its innermost point (a
            // car waiting beside the lane a bus turns into is not in its way). One going our way
            // at under half our speed is caught up with in the sweep: it counts as standing (a
            // bus slowing for walkers counted only below 0.5 m/s, and the bus turning in behind
            // it was stopped dead).
            let in_sweep =
                o.v < 0.5 || self.yielding[j].0.is_some() || cr < -0.5 || (v_lon > 0.0 && v_lon < 0.5 * st.v);
            let (mut band_lo, mut band_hi) = (cur_lo - margin - nose_lo, cur_hi + margin + nose_hi);
            if a.vehicle && in_sweep && gap > 0.0 {
                let (k0, k1) = (a.path.curvature(sj), a.path.curvature(sj - a.hl));
                band_lo -= swing(a.hl, k0.max(k1).max(0.0));
                band_hi += swing(a.hl, (-k0).max(-k1).max(0.0));
            }
            let mut in_cur = lj - ext_lat < band_hi && lj + ext_lat > band_lo;
            let mut gap = gap;
            // Our sweep through the junction (the dry run's, `Bend::slices`) where it lies on the
            // road: one it reaches is in our way from the first metre that reaches it; one
            // holding at its line, also where it will stand there (rolling up to it, it was found
            // only once inside). Laid out in the straight frame at the other's projection, a
            // U-turn's loop reached over cars holding well clear of it.
            // Also one whose centre is ahead of ours but whose box the straight frame puts beside
            // us: in a turn our box heads elsewhere than the path at its projection, and a car
            // standing across an ambulance's wide U-turn lay straight ahead of the box and 6 m
            // beside the path (seed 522). The slices are then searched at least two box lengths
            // on.
            let mut swept = false;
            let sweep_hi = (sj + ext_lon + a.hl + 2.0 * b.hl).max(st.s + 2.0 * (a.hl + b.hl) + 5.0);
            if !in_cur
                && a.vehicle
                && in_sweep
                && ds > 0.0
                && let Some(bd) = &a.bend
                && let Some(at) = self
                    .held_at(j)
                    .into_iter()
                    .chain([*o])
                    .filter_map(|q| bd.meets(&b.obb(&q).grown(SLICE_MARGIN), st.s, sweep_hi))
                    .reduce(f64::min)
                    // One still moving, too close to stop for within our braking: we are
                    // committed (as to a junction zone), and it sees our box.
                    .filter(|&at| o.v < 0.5 || st.v * st.v <= 2.0 * lim.brake_max * (at - st.s - a.hl))
            {
                in_cur = true;
                swept = true;
                gap = at - st.s - a.hl;
            }
            // Standing where the sweep's slices miss it: laid a metre each along the path, they
            // lose the corner of a nose swinging round a tight U-turn loop (a sedan's, over the
            // front of a bus at its stop line, seed 161). The run's own boxes are exact; met
            // there, we go no further than the last pose clear of it, as for our tail.
            if !in_cur
                && !swept
                && a.vehicle
                && o.v < 0.5
                && let Some(bd) = &a.bend
                && let Some(at) = bd.touches(a, &b.obb(o).grown(SLICE_MARGIN), st.s, sweep_hi)
            {
                touch_rem = touch_rem.min(at - st.s - 0.2);
            }
            // A box turned across our path (a long vehicle turning beside us): its extents along
            // and across the path put corners where it has none. Only the part of it inside our
            // band counts, and only its nearest point there.
            // Within reach of the band: its frame is straight while our path may bend.
            let near_band = lj - ext_lat < band_hi + 1.5 && lj + ext_lat > band_lo - 1.5;
            if !swept && !is_named && sr.abs() > 0.05 && near_band && (in_cur || gap > 0.0) {
                if in_cur {
                    match band_front(lj, cr, sr, b.hl, b.hw, band_lo, band_hi) {
                        Some(x) => gap = ds + x - a.hl,
                        None => in_cur = false,
                    }
                }
                // That frame is straight, our path may bend: a long box's far end lies where the
                // path has turned under it (a standing ambulance's corner inside the bend of our
                // left turn), in the band though its frame puts it beside. A corner that projected
                // onto our path where it is lies in the band ahead of us counts too.
                if !in_cur {
                    let fwd = DVec2::from_angle(st.yaw);
                    for q in b.obb(o).corners() {
                        let (sq, dq, beyond, _) = a.path.frenet_dir(q, st.s + (q - st.pos).dot(fwd));
                        let ahead = sq - st.s - a.hl;
                        if beyond <= 0.0 && dq > band_lo && dq < band_hi && ahead > 0.0 {
                            gap = if in_cur { gap.min(ahead) } else { ahead };
                            in_cur = true;
                        }
                    }
                }
                // That part alongside us, not ahead: the frame at its projection is turned by our
                // bend, which can put a corner of a box driving straight beside us into our band.
                // Measured across our path where we are, it must still reach into the band.
                if in_cur && gap <= 0.0 {
                    let (p0, h0) = a.path.point(st.s, 0.0);
                    let n0 = DVec2::from_angle(h0).perp();
                    let (lo_c, hi_c) = b
                        .obb(o)
                        .corners()
                        .iter()
                        .map(|&q| n0.dot(q - p0))
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), d| (l.min(d), h.max(d)));
                    in_cur = lo_c < band_hi && hi_c > band_lo;
                }
            }
            // Where our path bends between here and a turned box, the straight frame at its
            // projection misplaces it (a bus driving straight past our right turn lies in the
            // band there, and clear of it on the road): our band is laid along the path itself,
            // a metre at a time, and only a box it meets counts, from where it first meets it.
            // How far on our band is laid for it, where our path bends before that.
            let bend_reach = || {
                let reach = (sj + ext_lon + a.hl + 1.0).min(a.path.length());
                a.path.straight_run(st.s).is_none_or(|ln| ln.hi < reach).then_some(reach)
            };
            if in_cur
                && !swept
                && !is_named
                && sr.abs() > 0.05
                && let Some(reach) = bend_reach()
            {
                match band_meets(a, st.s, reach, (band_lo, band_hi), &b.obb(o)) {
                    Some(s_hit) => gap = s_hit - st.s,
                    None => in_cur = false,
                }
            }
            // One standing beside the band where it projects, square to our path there, but
            // reaching over it where the path bends before it: a bus that overran its line
            // stands with its nose in the arc of a car turning left past it, and lay one lane
            // over on the street the car turns into (the car met the nose at 5.8 m/s).
            if !in_cur
                && !swept
                && !is_named
                && a.vehicle
                && o.v < 0.5
                && gap > 0.0
                && lj - ext_lat < band_hi + 2.0
                && lj + ext_lat > band_lo - 2.0
                && let Some(reach) = bend_reach()
                && let Some(s_hit) = band_meets(a, st.s, reach, (cur_lo, cur_hi), &b.obb(o))
            {
                in_cur = true;
                gap = s_hit - st.s;
            }
            // One driving toward us in its lane beside our path meets us wherever our turn
            // sweeps out over its way between it and us (a bus's front corner swinging into the
            // oncoming lane as it turns right): found only once there, it is on us. We hold
            // short of the first such metre, as of something standing there, till it has passed.
            // Its way is its route ahead of it as far as it is from us: the lane beside our path
            // where we stand is another lane once our path has turned (a bus turning right, its
            // corner over the lane beside its approach, held for a car coming the other way on
            // the street it turns into, braked hard, and let go again once that car was farther
            // than its look-ahead, frame after frame).
            let (jlo, jhi) = (lj - ext_lat, lj + ext_lat);
            let beside = jlo >= cur_hi + margin || jhi <= cur_lo - margin;
            if a.vehicle
                && beside
                && !is_named
                && cr < -0.5
                && v_lon < -0.5
                && gap > 0.0
                && let Some(bd) = &a.bend
            {
                let (ahead, step) = (ds + a.hl, 2.0 * b.hl.max(1.0));
                let mut hit: Option<f64> = None;
                let mut k = 0.5 * step;
                while k < ahead + step {
                    let (p, h) = b.path.point(o.s + k, o.d);
                    let way = Obb { center: p, yaw: h, length: 2.0 * b.hl + step, width: 2.0 * b.hw };
                    if let Some(at) = bd.meets(&way, st.s, sj + ext_lon + a.hl) {
                        hit = Some(hit.map_or(at, |h| h.min(at)));
                    }
                    k += step;
                }
                // Too close to hold short at a comfortable braking, we are committed (as to a
                // junction zone, `zone_rank`): the other sees our box and keeps clear.
                let short = |at: f64| at - st.s - a.hl - 0.5;
                if let Some(at) = hit.filter(|&at| st.v * st.v < 2.0 * lim.brake * short(at)) {
                    in_cur = true;
                    gap = gap.min(short(at));
                }
            }
            let in_now = in_cur || (gap > 0.0 && lj - ext_lat < hi && lj + ext_lat > lo);
            let mut obstacle = in_now || is_named;
            // Someone about to cut across our corridor (a crossing pedestrian, a car in the
            // junction, a lane changer) counts as in it. Walkers do not wait for predicted
            // vehicles: vehicles yield to them, which keeps the two from waiting on each other.
            // One holding at its stop line for an emergency vehicle stays out of the junction;
            // one clearing the junction for it has the right of way over predicted vehicles
            // (`Actor::cleared_past`), so the two never wait on each other; not over a walker,
            // who steps off the kerb in front of any car that could stop for them.
            // Nor over one that will have crossed our band a second before we get there.
            let crossed_first = || {
                let out = if v_lat > 0.0 { hi - (lj - ext_lat) } else { lj + ext_lat - lo };
                out / v_lat.abs().max(0.1) + 1.0 < gap.max(0.0) / st.v.max(1.0)
            };
            let gives_way = self.yielding[j].0.is_some() || (clearing && (b.cleared_past(o) || crossed_first()));
            if !obstacle && a.vehicle && v_lat.abs() > 0.3 && !gives_way {
                // A walker or an animal heading for the road gets two more seconds of slack:
                // drivers brake for someone stepping off the kerb, not only for someone already
                // in their lane, and a walker's path is the least predictable.
                let slack = if b.vehicle { 1.0 } else { 3.0 };
                let horizon = (gap.max(0.0) / st.v.max(1.0)).min(4.0) + slack;
                let l2 = lj + v_lat * horizon;
                obstacle = lj.min(l2) - ext_lat < hi && lj.max(l2) + ext_lat > lo;
            }
            if !obstacle {
                continue;
            }
            let s0 = if is_named { 2.0 } else { lim.min_gap };
            // A striker coming at us does not stop for us: it comes on to its target, where the
            // latch stops it. Braking for it where it is now, a motorcycle met a bus overtaking
            // into its lane at 18 m/s and stopped at 13 m/s2. The reach only slows us: where we
            // may still move (`hard`) is where it is.
            let reach = if v_lon < -0.5 && !a.in_conflict { self.strike_reach(j, t) } else { None };
            let acc_gap = reach.map_or(gap, |r| gap - r);
            acc = acc.min(idm_interaction(st.v, v_lon.max(0.0), acc_gap, s0, lim));
            if v_lon < 0.5 {
                acc = acc.min(stop_law(st.v, acc_gap - s0, lim, dt));
            }
            // Only into the band's margin (a standing car's corner at arm's length from our
            // side, the band's edge shifting by millimetres as we steer): brake for it, but no
            // stop dead, which only a box in our way itself calls for.
            let margin_only =
                !swept && !is_named && (lj - ext_lat >= band_hi - margin || lj + ext_lat <= band_lo + margin);
            if (in_cur && !margin_only) || is_named {
                let lead_move = (v_lon * dt - 0.5 * lim.brake_max * dt * dt).max(0.0);
                // A walker stops within its own braking: one stepping into another's way just
                // ahead (two crossing side by side on converging lines, a hand's breadth apart)
                // slows and lets the other draw away; it is not stopped dead. Nor is anyone for
                // one alongside (no gap ahead to keep: stopping dead opens none, a car passing
                // close by in the lane we edge toward goes by all the same).
                // The 0.2 m kept short of it is a margin, not a wall: where it lets the step stay
                // within the braking limit, the step may use it, short of touching (a box
                // swinging into the band left 0.1 m less than the limit's shortest step).
                let keep = gap - 0.2 + lead_move;
                hard = hard.min(if a.vehicle && gap > 0.0 {
                    keep.max(shortest.min(gap + lead_move - 0.02))
                } else {
                    keep.max(shortest)
                });
                acc = acc.min(self.safe_acc(i, j, acc_gap, v_lon, t));
            } else if gap > 0.0 && !a.in_conflict && self.crash_partner(j, t).is_some() {
                // One about to crash, only predicted into our lane ahead, stops dead where it
                // meets its partner: followed as a lead at its speed, it leaves us no room. On
                // its own this did not mend the bus that cut into a car's lane 4.7 m ahead and
                // stood there (-19 m/s2): the striker's contact pose below did.
                acc = acc.min(self.safe_acc(i, j, acc_gap, v_lon, t));
            }
        }
        // A striker stops dead where it meets its target (the latch): there it stands in our
        // way, though it only passes through our band now. A bus overtaking a car at 19 m/s cut
        // diagonally into the lane of another 4.7 m ahead of it and stood there, 2 m on (-19
        // m/s2). Ahead of us only: one already where it will stand moves on out of its way.
        if a.vehicle && !a.in_conflict {
            for c in self.confs {
                let Some((g, gyaw, moves)) = self.strike_pose(c.af, t) else { continue };
                let b = &self.actors[c.af];
                let there = Obb { center: g, yaw: gyaw, length: 2.0 * b.hl + moves, width: 2.0 * b.hw };
                let to = (st.s + look + 2.0 * a.hl).min(a.path.length());
                if let Some(s_hit) = band_meets(a, st.s + 0.5, to, (lo, hi), &there) {
                    acc = acc.min(stop_law(st.v, s_hit - st.s - lim.min_gap, lim, dt));
                }
            }
        }
        let mut stop_rem = None;
        if active {
            stop_rem = match a.stop {
                StopGoal::Front(sf) => Some(sf - (st.s + a.hl)),
                StopGoal::Centre(sc) => Some(sc - st.s),
                _ => None,
            };
        }
        if let Some(rem) = stop_rem {
            acc = acc.min(stop_law(st.v, rem, lim, dt));
            // A stop target is a goal, not an obstacle: one closer than the braking distance is
            // overrun by what the brakes cannot absorb, never met by braking past the limit.
            hard = hard.min(rem.max(shortest));
        }
        for rem in yield_rem.into_iter().chain((touch_rem < f64::INFINITY).then_some(touch_rem)) {
            acc = acc.min(stop_law(st.v, rem, lim, dt));
            hard = hard.min(rem.max(shortest));
        }
        // Do not run off the end of the path (a walker's crossing ends there): slow down onto it.
        let to_end = a.path.length() - st.s;
        acc = acc.min(stop_law(st.v, to_end, lim, dt));
        hard = hard.min(to_end);

        let acc = acc.clamp(-lim.brake_max, lim.accel);
        let mut v = (st.v + acc * dt).max(0.0);
        let mut adv = 0.5 * (st.v + v) * dt;
        if adv > hard.max(0.0) {
            adv = hard.max(0.0);
            v = v.min(adv / dt);
        }
        if side_blocked {
            phase = st.phase;
            d_next = st.d;
        }
        let stopped = stop_rem.is_some_and(|r| r - adv < 0.3) && v < 0.05;
        let give_way = self.ruled[i];
        let next = State { v, d: d_next, phase, triggered, stopped, frozen: false, give_way, ..st };
        if !a.vehicle {
            // Holonomic: walkers and animals step onto the reference and face where they go
            // (a step aside from a neighbour does not turn them).
            let step_aside = if aside == 0.0 { 0.0 } else { aside.signum() * WALK_ASIDE * dt };
            let s = st.s + adv;
            let (pos, h) = a.path.point(s, d_next + step_aside);
            let d_rate = (d_next - st.d) / dt;
            let yaw = if adv > 1e-4 || d_rate.abs() > 1e-4 { h + d_rate.atan2(v.max(1.0)) } else { st.yaw };
            let d = d_next + step_aside;
            return State { pos, yaw: turn_toward(st.yaw, yaw, lim.yaw_rate, dt), s, d, off: d, ..next };
        }
        // Kinematic bicycle: pure pursuit of the reference (the route shifted by the lateral
        // goal's offset, taken where the profile will be when the car gets there), curvature
        // bounded by the turning radius and the yaw rate, position integrated along the heading.
        let l_d = look_ahead(a, v);
        let horizon = l_d / v.max(1.0);
        let d_look = if side_blocked {
            // Where the body is, not the held reference: aimed at that, a bus 0.1 m short of it
            // kept crabbing toward the car passing in the lane it had been moving into, its
            // nose 0.4 m over (on a curve, seed 129), and one 0.05 m past it steered back, its
            // tail swinging out at the car following in that lane (seed 104).
            st.off
        } else if let Some(tg) = target {
            a.d0 + (tg - a.d0) * quintic((phase + horizon / dur).min(1.0))
        } else if let Some(tg) = pass_target {
            d_next + (tg - d_next).clamp(-PASS_LAT_RATE * horizon, PASS_LAT_RATE * horizon)
        } else {
            d_next
        };
        let slip = v.max(3.0) * slip_tan(a) * horizon;
        let d_look = d_next + (d_look - d_next).clamp(-slip, slip);
        // Aimed no steeper than the slip angle from where the body is (a creeping car noses out
        // gently instead of turning broadside into the next lane).
        let reach = l_d * slip_tan(a);
        let d_look = d_look.clamp(d_next.min(st.off - reach), d_next.max(st.off + reach));
        let aim = a.path.point_fast(st.s + l_d, d_look);
        let k = pursuit(st.pos, self.dirs[i], aim);
        let (pos, yaw) = self.advance(a, &st, k, adv, 1.0);
        let (s, off, _, _) = a.path.frenet_dir(pos, st.s + adv);
        State { pos, yaw, s, off, ..next }
    }

    /// The agents `drive`'s pair loop looks at for agent `i`, in the order it visits them: every
    /// agent in index order, and the one queued behind (`named`) once more (every effect there
    /// is a min or an or, so seeing it twice is harmless), less those that provably change
    /// nothing there: itself, its conflict partner, and (except `named`) agents beyond the
    /// look-ahead, well behind, or off its corridor on a straight stretch. It reads the packed
    /// per-frame `near` data. The look-ahead (up to ~240 m at highway speed) spans whole maps,
    /// so a grid finds nearly everyone; but on a straight run the corridor is a thin strip along
    /// it: with many agents, those to test come from `AlongIndex` (`corridor_subset`), in index
    /// order, the same ones the scan of everyone keeps.
    fn candidates(&self, i: usize, c: &Corridor, out: &mut Vec<usize>) {
        out.clear();
        let me = (i, &self.actors[i], &self.cur[i], self.dirs[i]);
        if self.near.len() >= ALONG_MIN_AGENTS
            && let Some(ln) = c.line
            && self.corridor_subset(i, c, ln)
        {
            for &j in self.subset.borrow().iter() {
                if self.candidate(me, c, j) {
                    out.push(j);
                }
            }
        } else {
            for j in 0..self.near.len() {
                if self.candidate(me, c, j) {
                    out.push(j);
                }
            }
        }
        if let Some(j) = c.named
            && j != i
            && !self.exempt(i, j)
        {
            out.push(j);
        }
    }

    /// Whether `candidates` keeps agent `j` for agent `i`'s pair loop (`me`: `i`, its actor,
    /// state and heading).
    #[inline(always)]
    fn candidate(&self, me: (usize, &Actor, &State, DVec2), c: &Corridor, j: usize) -> bool {
        let (i, a, st, fwd) = me;
        let look = c.look;
        let b = &self.near[j];
        if j == i {
            return false;
        }
        if c.named == Some(j) {
            return !self.exempt(i, j);
        }
        let dp = b.pos - st.pos;
        let r = look + a.radius + b.radius;
        if dp.length_squared() > r * r {
            return false;
        }
        let ahead = dp.dot(fwd);
        // Well behind us and not beside a lateral move: cannot be in our way.
        if ahead < -(a.hl + b.radius + 1.0) && c.holding {
            return false;
        }
        if let Some(ln) = c.line {
            let guess = st.s + ahead;
            let rel = b.pos - ln.origin;
            let s_line = ln.s0 + rel.dot(ln.dir);
            // (Its projection a half length inside the run: `drive` widens the band by our
            // swing, read from the curvature there and a half length behind it.)
            if guess > ln.lo && guess < ln.hi && s_line - a.hl > ln.lo && s_line < ln.hi {
                // `frenet_dir` would give s_line, this offset and this tangent to float
                // noise (1 mm is far above it), hence the extents below too.
                let l_line = ln.dir.perp_dot(rel);
                let (cr, sr) = (b.dir.dot(ln.dir), ln.dir.perp_dot(b.dir));
                let ext_lon = b.hl * cr.abs() + b.hw * sr.abs();
                let ext_lat = b.hl * sr.abs() + b.hw * cr.abs();
                let behind = s_line - st.s < -LINE_EPS - c.back;
                let too_far = s_line - st.s - a.hl - ext_lon > look + LINE_EPS;
                let aside = l_line - ext_lat > c.hi + LINE_EPS || l_line + ext_lat < c.lo - LINE_EPS;
                // Nor would it be predicted to cut across (see `obstacle` in `drive`).
                let v_lat = b.v * sr;
                let steady =
                    !a.vehicle || v_lat.abs() < 0.3 - LINE_EPS || b.gives_way || (c.clearing && b.cleared_past);
                if behind || too_far || (aside && steady) {
                    return false;
                }
            }
        }
        // Last: a pure test like the others, and the rarest to hold.
        !self.exempt(i, j)
    }

    /// Fill `subset` with, in index order, every agent that `candidate` can keep for agent `i`
    /// on the straight run `ln` (and maybe others): those whose place along the run lies in
    /// the corridor ahead and across it near our band, those moving across the run, and
    /// `named`. `false` (subset unset) where that cannot be bounded: the run ending within
    /// reach ahead or close behind (there `candidate` does not use the run), a lateral move, or
    /// coordinates beyond `ALONG_FAR`.
    fn corridor_subset(&self, i: usize, c: &Corridor, ln: Line) -> bool {
        const FAR: f64 = ALONG_FAR;
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let rmax = self.max_radius;
        // Everyone `candidate` keeps lies within `reach` of us (its circle test), and (holding
        // our offset) no farther behind than `back` along our heading, so along the run too
        // but for the turn `g` of our heading from it: then its guess and its place along the
        // run are inside the run, where `candidate` uses it. The margin covers rounding (below
        // 1e-8 m within `FAR`) and a unit vector's length.
        let m = ALONG_MARGIN;
        let reach = c.look + a.radius + rmax;
        let back = a.hl + rmax + 1.0;
        let g = reach * (self.dirs[i] - ln.dir).length();
        let s_here = ln.s0 + (st.pos - ln.origin).dot(ln.dir);
        let inside = st.s - back - m > ln.lo
            && s_here - back - g - a.hl - m > ln.lo
            && st.s + reach + m < ln.hi
            && s_here + reach + m < ln.hi;
        let sizes = [reach, g, s_here, st.s, ln.s0, ln.origin.x, ln.origin.y, st.pos.x, st.pos.y, c.lo, c.hi, a.hl];
        if !c.holding || !inside || !sizes.iter().all(|x| x.abs() < FAR) {
            return false;
        }
        let mut along = self.along.borrow_mut();
        let key = (ln.dir.x.to_bits(), ln.dir.y.to_bits());
        let k = match along.iter().position(|x| x.key == key) {
            Some(k) => k,
            None => {
                along.push(AlongIndex::new(&self.near, ln.dir));
                along.len() - 1
            }
        };
        let ix = &along[k];
        if !ix.tame {
            return false;
        }
        // Inside the run `candidate` keeps an agent only where it is not behind, not beyond the
        // look-ahead (its extents are within `rmax`), and beside our band, or moving across.
        let (o_along, o_across) = (ln.origin.dot(ln.dir), ln.dir.perp_dot(ln.origin));
        let lo = st.s - ln.s0 + o_along - LINE_EPS - m - c.back;
        let hi = st.s - ln.s0 + o_along + a.hl + rmax + c.look + LINE_EPS + m;
        let (l_lo, l_hi) = (c.lo - rmax - LINE_EPS - m + o_across, c.hi + rmax + LINE_EPS + m + o_across);
        let mut sub = self.subset.borrow_mut();
        sub.clear();
        ix.collect(lo, hi, l_lo, l_hi, &mut sub);
        if a.vehicle {
            // Clearing the junction for an emergency vehicle, we predict walkers only.
            sub.extend(ix.crossing.iter().filter(|&&j| !c.clearing || !self.near[j].cleared_past));
        }
        sub.extend(c.named.filter(|&j| j < self.near.len()));
        sub.sort_unstable();
        sub.dedup();
        true
    }

    /// Gipps's safe speed behind leader `j`, `gap` ahead at `v_lon` along our path, as an
    /// acceleration: after this step we must still be able to stop at our emergency braking
    /// behind the point where the leader stops at its own. A conflict agent whose striker has
    /// set off may instead be stopped dead by the crash latch, but only on touching its
    /// partner: it stops no sooner than the clearance between the two. With every agent inside
    /// its limits this keeps the overlap safety net from ever braking anyone harder than that.
    fn safe_acc(&self, i: usize, j: usize, gap: f64, v_lon: f64, t: f64) -> f64 {
        let (a, st, dt) = (&self.actors[i], &self.cur[i], self.dt);
        let b = a.lim.brake_max;
        let lead = &self.actors[j];
        let mut lead_stop = if v_lon <= 0.0 { 0.0 } else { v_lon * v_lon / (2.0 * lead.lim.brake_max) };
        // A vehicle coming toward us in our band (a bus turning across the corner our own turn
        // swings over) closes the gap while both brake: it comes on by its own emergency stop,
        // taken a step late. Counted as standing, it closed 0.7 m a frame on a bus that then
        // had to stop at 13 m/s2. Staged pairs and their partners keep their plans.
        if v_lon < -0.5 && lead.vehicle && !lead.in_conflict && !a.in_conflict {
            lead_stop = v_lon * dt - v_lon * v_lon / (2.0 * lead.lim.brake_max);
        }
        if lead.in_conflict
            && let Some(p) = self.crash_partner(j, t)
        {
            let clearance = self.cur[j].pos.distance(self.cur[p].pos) - lead.radius - self.actors[p].radius;
            lead_stop = lead_stop.min(clearance.max(0.0));
        }
        // Room left after this step's own travel at the current speed (the half step at `v`).
        let room = gap - SAFE_MARGIN + lead_stop - 0.5 * st.v * dt;
        let v_safe = if room <= 0.0 { 0.0 } else { 0.5 * (-b * dt + (b * b * dt * dt + 8.0 * b * room).sqrt()) };
        (v_safe - st.v) / dt
    }

    /// The partner of agent `j` in a staged conflict whose striker has set off and not yet
    /// struck (pass 2): once the two touch, the latch stops both dead.
    fn crash_partner(&self, j: usize, t: f64) -> Option<usize> {
        self.confs.iter().zip(self.plans).enumerate().find_map(|(k, (c, p))| {
            let pending = !self.latched[k] && p.as_ref().is_some_and(|p| t >= p.t_depart - 1e-9);
            match (pending, c.af == j, c.st == j) {
                (true, true, _) => Some(c.st),
                (true, _, true) => Some(c.af),
                _ => None,
            }
        })
    }

    /// How far striker `j`, on its intercept now, may still come before it touches its target:
    /// to its contact pose taken on the target where it is, and as far again as the target may
    /// move by the planned impact.
    fn strike_reach(&self, j: usize, t: f64) -> Option<f64> {
        let (g, _, moves) = self.strike_pose(j, t)?;
        Some(self.cur[j].pos.distance(g) + moves)
    }

    /// Striker `j`'s contact pose, on its intercept now, taken on its target where it is, and
    /// how far the target may still move by the planned impact.
    fn strike_pose(&self, j: usize, t: f64) -> Option<(DVec2, f64, f64)> {
        if !self.striking(j, t) {
            return None;
        }
        let plan = self.plans[self.striker[j]?].as_ref()?;
        let so = &self.cur[plan.struck];
        let (g, gyaw) = stage::compose(Pose { x: so.pos.x, y: so.pos.y, yaw: so.yaw }, plan.rel_pos, plan.rel_yaw);
        Some((g, gyaw, so.v * (plan.t_impact - t).max(0.0)))
    }

    /// Whether agent `i` is a striker on its intercept now (it follows its plan, not the rules).
    fn striking(&self, i: usize, t: f64) -> bool {
        self.striker[i]
            .and_then(|k| self.plans[k].as_ref().map(|p| (k, p)))
            .is_some_and(|(k, p)| t >= p.t_depart - 1e-9 && !self.latched[k])
    }

    /// The right-of-way rule for agent `i`: how far its front may still go (to its stop line, or
    /// short of the zone it shares with another vehicle's junction path) while it gives way, or,
    /// for a walker about to cross, to the kerb while no vehicle could stop for it comfortably.
    fn right_of_way(&self, i: usize, t: f64) -> Option<f64> {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        if st.frozen || st.stopped || !matches!(a.drive, Drive::Mover) || self.striking(i, t) {
            return None;
        }
        if let Some(kerb) = a.kerb {
            return self.kerb_hold(i, kerb, t);
        }
        let mut hold: Option<f64> = None;
        for c in &a.crossings {
            if let Some(rem) = self.gives_way(i, c, t) {
                hold = Some(hold.map_or(rem, |h: f64| h.min(rem)));
            }
        }
        hold
    }

    /// Agent `i`'s standing toward its shared zone `(enter, leave)` (`Crossing::meet` where the
    /// paths come near, `enter` moved back from it by the other's sweep): its rank (0 inside, 1 too
    /// close to stop, 2 approaching, 3 stopped by anything but this rule) and its time to the
    /// zone; `None` once it has left the zone, or when it means to stop short of it. Also how
    /// far its front may go while it holds (stop line, else short of the zone).
    fn zone_rank(&self, i: usize, enter: f64, meet: f64, leave: f64, t: f64) -> Option<(u8, f64, f64)> {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        if st.s > leave || st.frozen || st.stopped {
            return None;
        }
        if let StopGoal::Front(sf) | StopGoal::Centre(sf) = a.stop
            && sf < enter + a.hl
            && t >= a.start - 1e-9
        {
            return None;
        }
        let to_zone = enter - 0.3 - st.s;
        let rem = match a.to_line(st) {
            Some(line) if line > -0.05 => line.min(to_zone),
            _ => to_zone,
        };
        // Short of where the paths come near (`meet`), in the stretch the other's sweep moved
        // the zone's start back over, one that can halt where it is holds there: a van placed
        // standing at its line beside a bus turning from the next lane, its nose in the reach
        // of the bus's swinging tail, counted as inside, set off and met the tail.
        let rem = if st.s >= enter && st.s < meet { rem.max(0.0) } else { rem };
        if st.s >= meet || (st.s >= enter && !can_stop(st.v, rem, a.lim.brake_max)) || self.striking(i, t) {
            return Some((0, 0.0, rem));
        }
        // Giving way may take up to the emergency braking: within the limits, and it leaves the
        // fewest pairs where neither can stop (both then go, and only the safety net is left).
        if !can_stop(st.v, rem, a.lim.brake_max) {
            return Some((1, 0.0, rem));
        }
        let dist = (enter - st.s).max(0.0);
        let acc = a.lim.accel;
        let eta = ((st.v * st.v + 2.0 * acc * dist).sqrt() - st.v) / acc;
        // Stopped, or holding for an emergency vehicle, for anything but this rule, or queued
        // behind another approaching the junction: not coming next.
        let not_next = (st.v < 0.3 && !st.give_way) || self.yielding[i].0.is_some() || self.behind[i];
        let rank = if not_next { 3 } else { 2 };
        Some((rank, eta, rem.max(0.0)))
    }

    /// `zone_rank(i, enter, meet, leave, t)`, taken once per frame for each of `i`'s crossings (the
    /// zone with these bounds): what it reads (`cur`, `behind`, the emergency holds) is settled
    /// before the right-of-way rule runs, and `ranks` is cleared each frame.
    fn rank(&self, i: usize, enter: f64, meet: f64, leave: f64, t: f64) -> Rank {
        let same = |c: &Crossing| c.enter.to_bits() == enter.to_bits() && c.leave.to_bits() == leave.to_bits();
        let Some(k) = self.actors[i].crossings.iter().position(same) else {
            return self.zone_rank(i, enter, meet, leave, t);
        };
        let slot = self.cross_at[i] + k;
        if let Some(r) = self.ranks.borrow()[slot] {
            debug_assert_eq!(r, self.zone_rank(i, enter, meet, leave, t), "stale zone rank for agent {i}");
            return r;
        }
        let r = self.zone_rank(i, enter, meet, leave, t);
        self.ranks.borrow_mut()[slot] = Some(r);
        r
    }

    /// `behind[i] = queued(i)` for every agent, in one pass over everyone and one over the agents
    /// instead of one over everyone per agent: someone else is queued ahead of `i` exactly when
    /// the least distance to the stop line among the others counted on its lane (the least, or
    /// the second least where the least is `i`'s own) is below `i`'s, the same floats compared.
    fn queue_heads(&mut self) {
        self.lane_least.fill([(f64::INFINITY, usize::MAX); 2]);
        for (k, (b, o)) in self.actors.iter().zip(&self.cur).enumerate() {
            let Some(slot) = self.approach_slot[k] else { continue };
            let to_stop = b.junction.map_or(f64::NEG_INFINITY, |jb| jb.stop - (o.s + b.hl));
            let counted = !o.frozen && to_stop > -0.5;
            if !counted {
                continue;
            }
            let least = &mut self.lane_least[slot];
            if to_stop < least[0].0 {
                least[1] = least[0];
                least[0] = (to_stop, k);
            } else if to_stop < least[1].0 {
                least[1] = (to_stop, k);
            }
        }
        for i in 0..self.actors.len() {
            let (a, st) = (&self.actors[i], &self.cur[i]);
            self.behind[i] = match (self.approach_slot[i], a.junction) {
                (Some(slot), Some(j)) => {
                    let mine = j.stop - (st.s + a.hl);
                    let least = self.lane_least[slot];
                    let other = if least[0].1 == i { least[1].0 } else { least[0].0 };
                    other < mine
                }
                _ => false,
            };
            debug_assert_eq!(self.behind[i], self.queued(i), "queue_heads differs from queued for agent {i}");
        }
    }

    /// Whether another vehicle approaches agent `i`'s junction through the same lane ahead of it,
    /// its front not yet past its stop line.
    fn queued(&self, i: usize) -> bool {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let (Some(lane), Some(j)) = (a.approach, a.junction) else { return false };
        let mine = j.stop - (st.s + a.hl);
        self.actors.iter().zip(&self.cur).enumerate().any(|(k, (b, o))| {
            let to_stop = b.junction.map_or(f64::NEG_INFINITY, |jb| jb.stop - (o.s + b.hl));
            k != i && b.approach == Some(lane) && !o.frozen && to_stop > -0.5 && to_stop < mine
        })
    }

    /// Whether agent `i` gives way to the other agent of crossing `c`, and then how far its
    /// front may go. The rule is a strict order on (rank, time to the zone, name) of the two,
    /// the same seen from either side, so exactly one of two waiting agents goes first: inside
    /// the zone goes before too close to stop, before approaching, before stopped by something
    /// else (so nobody waits for a car that waits for something else); the earlier arrival next.
    fn gives_way(&self, i: usize, c: &Crossing, t: f64) -> Option<f64> {
        // Between an emergency vehicle and one yielding to it, the yield (`yield_state`) rules;
        // but one already too far into the junction to hold when the emergency vehicle came near
        // is clearing it, and the emergency vehicle takes its turn with it by this rule.
        if c.emergency && !(self.actors[i].emergency && self.yielding[c.other].1) {
            return None;
        }
        let (ri, ei, rem) = self.rank(i, c.enter, c.meet, c.leave, t)?;
        let (rj, ej, _) = self.rank(c.other, c.other_enter, c.other_meet, c.other_leave, t)?;
        // Placed with one order only (`order_crossings`): it holds till the other has left.
        if let Some(yields) = c.placed_yield {
            return yields.then_some(rem);
        }
        // Where the two run on together, one whose whole box is in the stretch is ahead of us
        // there: car-following keeps our gap to it (a car entering a roundabout behind one
        // circulating, or one circulating behind one that entered, used to wait till the other
        // had left the ring).
        if c.merge && self.cur[c.other].s >= c.other_enter + 2.0 * self.actors[c.other].hl {
            return None;
        }
        // One clearing the junction for us (we are the emergency vehicle) does not hold for us
        // (`yield_state`): we hold for it while we can, unless it is stopped for something else.
        // Taking turns by the order below, an ambulance 6 m from its line went first, and the
        // car clearing in front of it went too.
        if c.emergency {
            return match (ri, rj) {
                (0, _) | (_, 3) => None,
                (1, _) => self.short_of(i, c.enter).map(|(rem, _)| rem),
                _ => (!self.gone(c, ei)).then_some(rem),
            };
        }
        // Too near our line to hold there, but the other is inside, or as near: we still give
        // way short of the zone where we can. Let go because the bus beside it was already
        // inside, a motorcycle 6 m before its line at 8.8 m/s, turning right with it, met the
        // bus's swinging front (seed 338).
        if ri == 1 && rj <= 1 {
            return self.committed_gives_way(i, c);
        }
        if ri <= 1 {
            return None;
        }
        let (ni, nj) = (&self.actors[i].info.name, &self.actors[c.other].info.name);
        // Of two approaching, one already past its line (circulating in a roundabout, turning
        // inside a junction) goes before one still outside: entering traffic gives way.
        let outside = |k: usize| self.actors[k].to_line(&self.cur[k]).is_none_or(|line| line > -0.05);
        let (oi, oj) = (outside(i), outside(c.other));
        let first = (rj, oj, ej).partial_cmp(&(ri, oi, ei)).is_some_and(|o| o.then(nj.cmp(ni)).is_lt());
        (first && !self.gone(c, ei)).then_some(rem)
    }

    /// No need to hold for the other of crossing `c` when it will have left the zone, at its
    /// present speed, a `CLEAR_MARGIN_S` before we could reach it (`eta`).
    fn gone(&self, c: &Crossing, eta: f64) -> bool {
        let o = &self.cur[c.other];
        o.v > 0.5 && (c.other_leave - o.s) / o.v + CLEAR_MARGIN_S < eta
    }

    /// Whether agent `k` can still stop short of its zone from `enter` within its emergency
    /// braking: then how far its front may go, and its time to the zone at its present speed.
    fn short_of(&self, k: usize, enter: f64) -> Option<(f64, f64)> {
        let (a, st) = (&self.actors[k], &self.cur[k]);
        let rem = enter - 0.3 - st.s;
        can_stop(st.v, rem, a.lim.brake_max).then_some((rem.max(0.0), (enter - st.s) / st.v.max(0.1)))
    }

    /// Of a vehicle too close to hold at its line (rank 1) and one as close or already inside
    /// (rank 1 or 0; the rule above lets both go): whether `i` still gives way, short of the
    /// zone itself, and then how far its front may go. One that can stop short of the zone
    /// within its emergency braking gives way to one that cannot; of two that can, the later to
    /// reach it at its present speed (then the name), the same order seen from either side.
    /// Two cars 6 m before their lines at 9 m/s, one going straight and one turning across it,
    /// were both let go: only their car-following kept them apart, once the turner's sideways
    /// motion showed.
    fn committed_gives_way(&self, i: usize, c: &Crossing) -> Option<f64> {
        let (rem, ti) = self.short_of(i, c.enter)?;
        let first = match self.short_of(c.other, c.other_enter) {
            None => true,
            Some((_, tj)) => {
                let (ni, nj) = (&self.actors[i].info.name, &self.actors[c.other].info.name);
                tj.partial_cmp(&ti).is_some_and(|o| o.then(nj.cmp(ni)).is_lt())
            }
        };
        first.then_some(rem)
    }

    /// A walker at the kerb (`Actor::kerb`) waits there while a vehicle whose route crosses its
    /// walk could not stop comfortably before it; once its front is on the road, or too close to
    /// the kerb to stop, it goes on (vehicles yield to a walker on the road).
    fn kerb_hold(&self, i: usize, kerb: f64, t: f64) -> Option<f64> {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        if t < a.start - 1e-9 {
            return None;
        }
        let rem = kerb - (st.s + a.hl);
        let firm = if st.give_way { a.lim.brake_max } else { a.lim.brake };
        if !can_stop(st.v, rem, firm) {
            return None;
        }
        let end = a.path.length() - 2.0;
        if end <= kerb {
            return None;
        }
        let s_mid = 0.5 * (kerb + end);
        let (mid, _) = a.path.point(s_mid, 0.0);
        let half = 0.5 * (end - kerb);
        let clear = a.hw + 1.0;
        let walk = a.v_goal.max(0.5);
        let waits = (0..self.actors.len()).any(|j| {
            let (b, o) = (&self.actors[j], &self.cur[j]);
            if j == i || !b.vehicle || !matches!(b.drive, Drive::Mover) || o.frozen {
                return false;
            }
            let fwd = DVec2::from_angle(o.yaw);
            let (sj, lj, beyond, _) = b.path.frenet(mid, o.s + (mid - o.pos).dot(fwd));
            let ahead = sj - o.s;
            if beyond > 0.5 || lj.abs() > half + b.hw + clear || ahead < -(b.hl + clear) {
                return false;
            }
            let room = ahead - b.hl - clear;
            let brake = if self.striking(j, t) { 0.0 } else { b.lim.brake };
            if room > 0.0 && o.v * o.v <= 2.0 * brake * room {
                return false;
            }
            // It could not stop: wait only if it would pass while we are in its lane (its path
            // meets our walk at `s_x`), with a second's margin either side.
            let (x, _) = b.path.point(sj, 0.0);
            let (s_x, _, _, _) = a.path.frenet(x, s_mid);
            let lane = b.hw + clear;
            let t_in = (s_x - lane - (st.s + a.hl)).max(0.0) / walk;
            let t_out = (s_x + lane - (st.s - a.hl)).max(0.0) / walk;
            let (t_arr, t_gone) = if o.v < 0.1 {
                (if room <= 0.0 { 0.0 } else { f64::INFINITY }, f64::INFINITY)
            } else {
                (room.max(0.0) / o.v, (ahead + b.hl + clear) / o.v)
            };
            t_arr < t_out + 1.0 && t_gone > t_in - 1.0
        });
        waits.then_some(rem.max(0.0))
    }

    /// Move vehicle `a` from `st` by `dist` along a circular arc of curvature `k`, bounded by its
    /// turning radius and by `yaw_scale` times its class yaw rate at the step's mean speed.
    fn advance(&self, a: &Actor, st: &State, k: f64, dist: f64, yaw_scale: f64) -> (DVec2, f64) {
        steer(a, st.pos, st.yaw, k, dist, self.dt, yaw_scale)
    }

    /// Where agent `j`, holding (at its line, short of a zone), will stand: as now, its front
    /// moved on to where it holds.
    fn held_at(&self, j: usize) -> Option<State> {
        let o = &self.cur[j];
        self.yielding[j].0.map(|rem| State { pos: o.pos + self.dirs[j] * rem, ..*o })
    }

    /// How agent `i` gives the junction to an emergency vehicle on a crossing path: short of the
    /// stop line, it holds there (the distance left to it); past it, or too close to stop firmly,
    /// it clears the junction without waiting for the emergency vehicle's predicted path (`true`).
    fn yield_state(&self, i: usize) -> (Option<f64>, bool) {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let Some(j) = a.junction else { return (None, false) };
        if !a.yield_to.iter().any(|&e| self.emergency_near(e)) {
            return (None, false);
        }
        let rem = j.stop - 0.3 - (st.s + a.hl);
        if can_stop(st.v, rem, YIELD_BRAKE * a.lim.brake_max) {
            (Some(rem.max(0.0)), false)
        } else {
            (None, st.s - a.hl < j.exit)
        }
    }

    /// Whether emergency vehicle `e` is close to its junction or inside it: within
    /// `EMERGENCY_NEAR_S` of its stop point, its rear not yet out of the junction.
    fn emergency_near(&self, e: usize) -> bool {
        let (a, st) = (&self.actors[e], &self.cur[e]);
        let Some(j) = a.junction else { return false };
        if st.frozen || st.stopped || (a.v_goal < 0.5 && st.v < 0.5) {
            return false;
        }
        // One that means to stop short of the junction's far side does not need it cleared.
        if let StopGoal::Front(sf) | StopGoal::Centre(sf) = a.stop
            && sf < j.exit
        {
            return false;
        }
        let to_stop = j.stop - (st.s + a.hl);
        st.s - a.hl < j.exit && to_stop < EMERGENCY_NEAR_M.max(st.v.max(a.v_goal) * EMERGENCY_NEAR_S)
    }

    /// The lateral offset at which agent `i` clears an agent ahead that is easing aside for it
    /// (`away_from i`, already triggered), on the side that agent leaves free; `None` when there
    /// is none, or when passing would take more than `PASS_MAX_SHIFT` out of the lane.
    fn pass_offset(&self, i: usize, look: f64) -> Option<f64> {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let fwd = self.dirs[i];
        let mut best: Option<f64> = None;
        for &j in &self.easing {
            let (o, b) = (&self.cur[j], &self.actors[j]);
            if j == i || !matches!(b.lateral, Lat::Away { who, .. } if who == i) {
                continue;
            }
            let ahead = (o.pos - st.pos).dot(fwd);
            // Until our rear has cleared its front.
            if ahead < -(a.hl + b.hl + 1.0) || ahead > look {
                continue;
            }
            let (_, lj, beyond, h) = a.path.frenet(o.pos, st.s + ahead);
            if beyond > 0.5 {
                continue;
            }
            let rel = o.yaw - h;
            let ext_lat = b.hl * rel.sin().abs() + b.hw * rel.cos().abs();
            // It eases toward its right (negative offsets); pass on the side it leaves.
            let side = if lj > a.d0 + 0.05 { -1.0 } else { 1.0 };
            let d = lj + side * (ext_lat + a.hw + PASS_CLEARANCE);
            if (d - a.d0).abs() > PASS_MAX_SHIFT {
                continue;
            }
            best = Some(best.map_or(d, |b: f64| if side > 0.0 { b.max(d) } else { b.min(d) }));
        }
        best
    }

    /// One step of an at-fault agent's intercept: a Hermite curve from where it is to the pose
    /// that makes contact, re-planned every frame against the struck agent's predicted pose,
    /// traversed with the constant acceleration that arrives at the impact time.
    fn intercept(&self, i: usize, plan: &Plan, t: f64, f: usize) -> State {
        let (a, st, dt) = (&self.actors[i], self.cur[i], self.dt);
        let lim = a.lim;
        let so = self.cur[plan.struck];
        let remaining = plan.t_impact - t;
        let target = match self.pass1 {
            // Where pass 1 put the struck agent at the impact frame, shifted by how far it now is
            // from where pass 1 had it: bystanders may have delayed it.
            Some(p1) if remaining > 1e-9 => {
                let now = p1.poses[plan.struck][(f - 1).min(p1.frames - 1)];
                let then = p1.poses[plan.struck][plan.frame.min(p1.frames - 1)];
                Pose {
                    x: then.x + so.pos.x - now.x,
                    y: then.y + so.pos.y - now.y,
                    yaw: then.yaw + wrap_angle(so.yaw - now.yaw),
                }
            }
            _ => Pose { x: so.pos.x, y: so.pos.y, yaw: so.yaw },
        };
        let (g, gyaw) = stage::compose(target, plan.rel_pos, plan.rel_yaw);
        let tau = remaining.max(dt);
        let curve = Hermite::new(st.pos, st.yaw, g, gyaw);
        let len = curve.length();
        let acc = (2.0 * (len - st.v * tau) / (tau * tau)).clamp(-lim.brake_max, stage::STRIKE_ACCEL * lim.accel);
        // Keep rolling (an intercept that stalls never makes contact), within the strike's
        // acceleration.
        let v = (st.v + acc * dt).max(1.0f64.min(st.v + stage::STRIKE_ACCEL * lim.accel * dt));
        let step = |v: f64| {
            let adv = 0.5 * (st.v + v) * dt;
            // The arc from here through the curve's point `adv` ahead: the curve itself wherever
            // the car can follow it; a wider arc where the curve turns tighter than the car can.
            // In the last metres the contact point itself: the curve's end heading matters less
            // than reaching its end, and a short re-planned curve can bend tighter than the car.
            let aim = if len <= 3.0 * adv { g } else { curve.at(adv, gyaw).0 };
            let (pos, yaw) = self.advance(a, &st, pursuit(st.pos, self.dirs[i], aim), adv, stage::STRIKE_YAW);
            (pos, yaw, (len - adv).max(0.0))
        };
        // Reckless toward the struck agent only: it slows, within its emergency braking, rather
        // than cut into a bystander's stopping distance or come closer to one than its own.
        let v_min = (st.v - lim.brake_max * dt).max(0.0);
        let mut pick = (v_min, step(v_min));
        for k in 0..=8 {
            let vk = v - (v - v_min) * k as f64 / 8.0;
            let next = step(vk);
            if vk <= v_min {
                pick = (vk, next);
                break;
            }
            match self.strike_blocked(i, plan.struck, (next.0, next.1), vk, next.2, (g, gyaw)) {
                None => {
                    pick = (vk, next);
                    break;
                }
                Some(j) if k == 0 => {
                    let mut held = self.blocked_by.borrow_mut();
                    match held[i].iter_mut().find(|h| h.0 == j) {
                        Some(h) => h.2 += 1,
                        None => held[i].push((j, t, 1)),
                    }
                }
                Some(_) => {}
            }
        }
        let (v, (pos, yaw, _)) = pick;
        State { pos, yaw, v, ..st }
    }

    /// Striker `i`'s poses, a step apart, were it to brake at its emergency braking from `pos`,
    /// `yaw` and `v`, steering for its contact pose `goal` as `intercept` does, up to the
    /// contact (`left` metres on): the time from now, and the pose. A curve re-planned every
    /// step and a heading that turns no faster than the car can is not the curve it plans: at
    /// speed the car runs wide of it.
    fn braking_course(
        &self,
        i: usize,
        (pos, yaw): (DVec2, f64),
        v: f64,
        left: f64,
        goal: (DVec2, f64),
        out: &mut Vec<(f64, DVec2, f64)>,
    ) {
        let (a, dt) = (&self.actors[i], self.dt);
        out.clear();
        let (mut st, mut went, mut t) = (State { pos, yaw, v, ..self.cur[i] }, 0.0, 0.0);
        while st.v > 0.0 && went < left && out.len() < COURSE_STEPS {
            let v2 = (st.v - a.lim.brake_max * dt).max(0.0);
            let adv = (0.5 * (st.v + v2) * dt).min(left - went);
            let curve = Hermite::new(st.pos, st.yaw, goal.0, goal.1);
            let aim = if curve.length() <= 3.0 * adv { goal.0 } else { curve.at(adv, goal.1).0 };
            (st.pos, st.yaw) =
                self.advance(a, &st, pursuit(st.pos, DVec2::from_angle(st.yaw), aim), adv, stage::STRIKE_YAW);
            st.v = v2;
            went += adv;
            t += dt;
            out.push((t, st.pos, st.yaw));
        }
    }

    /// Whether striker `i` at `pos`, `yaw` and speed `v`, `left` metres short of its contact pose,
    /// would be inside a bystander's stopping envelope (its box stretched ahead by the distance it
    /// needs to stop at its emergency braking), or have its own envelope (up to the contact pose)
    /// reach a bystander's. A bystander following the striker is left to its own safe speed.
    fn strike_blocked(
        &self,
        i: usize,
        struck: usize,
        (pos, yaw): (DVec2, f64),
        v: f64,
        left: f64,
        goal: (DVec2, f64),
    ) -> Option<usize> {
        let a = &self.actors[i];
        let mut course = self.course.borrow_mut();
        let mut built = false;
        let envelope = |c: DVec2, yaw: f64, hl: f64, hw: f64, ext: f64| {
            let dir = DVec2::from_angle(yaw);
            Obb { center: c + dir * (0.5 * ext), yaw, length: 2.0 * hl + ext, width: 2.0 * hw }
        };
        let own_ext = (v * v / (2.0 * a.lim.brake_max) + SAFE_MARGIN).min(left);
        let mine = envelope(pos, yaw, a.hl, a.hw, own_ext);
        (0..self.actors.len()).find(|&j| {
            if j == i || j == struck || self.exempt(i, j) {
                return false;
            }
            let (b, o) = (&self.actors[j], &self.cur[j]);
            let r = a.radius + b.radius + own_ext + o.v * o.v / (2.0 * b.lim.brake_max) + o.v * self.dt + SAFE_MARGIN;
            if pos.distance_squared(o.pos) > r * r {
                return false;
            }
            let theirs_box = b.obb(o);
            if mine.overlaps(&theirs_box) {
                return true;
            }
            // Along the course we would brake on, not only straight on, against where it will
            // be by then at its present speed: a striker turning back at 22 m/s around the car
            // it is to meet saw a walker stepping into that car's lane only once it had turned
            // toward it, 4 m off.
            if !b.vehicle {
                if !built {
                    self.braking_course(i, (pos, yaw), v, left, goal, &mut course);
                    built = true;
                }
                let vel = self.dirs[j] * o.v;
                if course.iter().any(|&(t, p, h)| {
                    let ours = Obb { center: p, yaw: h, length: 2.0 * a.hl + SAFE_MARGIN, width: 2.0 * a.hw };
                    ours.overlaps(&Obb { center: theirs_box.center + vel * t, ..theirs_box })
                }) {
                    return true;
                }
            }
            // Coming the other way: the gap closes from both ends, so neither stopping distance
            // alone says whether it can stop short of where we will stand (we stop at the
            // contact, latched). Our braking course, held at its end, against where it will be
            // braking at its emergency braking from one step on: a bus swerving into the
            // oncoming lane at 20 m/s to sideswipe a car left the car coming the other way 1.3 m
            // to stop in from 5 m/s.
            let fwd = self.dirs[j];
            if b.vehicle && o.v > 0.05 && DVec2::from_angle(yaw).dot(fwd) < -0.5 && fwd.dot(pos - o.pos) > 0.0 {
                if !built {
                    self.braking_course(i, (pos, yaw), v, left, goal, &mut course);
                    built = true;
                }
                let dt = self.dt;
                let stop = o.v / b.lim.brake_max;
                let went = |t: f64| {
                    let tb = (t - dt).clamp(0.0, stop);
                    o.v * t.min(dt) + o.v * tb - 0.5 * b.lim.brake_max * tb * tb
                };
                let last = course.last().map_or((pos, yaw), |&(_, p, h)| (p, h));
                let steps = ((dt + stop) / dt).ceil() as usize + 1;
                // Along its route, not straight on: on a curve a car in the next lane, taken
                // straight on over its stopping distance, crosses into ours.
                let off = o.pos - b.path.point(o.s, o.d).0;
                if (1..=steps.max(course.len())).any(|k| {
                    let (p, h) = course.get(k - 1).map_or(last, |&(_, p, h)| (p, h));
                    let ours = Obb { center: p, yaw: h, length: 2.0 * a.hl + SAFE_MARGIN, width: 2.0 * a.hw };
                    let (q, qh) = b.path.point(o.s + went(k as f64 * dt), o.d);
                    ours.overlaps(&Obb { center: q + off, yaw: qh, ..theirs_box })
                }) {
                    return true;
                }
            }
            // Already ahead of it in its lane and heading its way: it follows us, at its own
            // safe speed. Cutting in from beside is not following.
            let now = self.cur[i].pos - o.pos;
            let follows =
                now.dot(fwd) > b.hl && fwd.perp_dot(now).abs() < a.hw + b.hw && DVec2::from_angle(yaw).dot(fwd) > 0.7;
            if follows || o.v < 0.05 {
                return false;
            }
            // Its envelope as its car-following sees us: our box's extent along and across its
            // heading, against its band (its width and the margin it watches, and more) from
            // its rear to where it could stop after one more step at its speed.
            let (rel, (sn, c)) = (pos - o.pos, (yaw - o.yaw).sin_cos());
            let (c, sn) = (c.abs(), sn.abs());
            let (lon, lat) = (rel.dot(fwd), fwd.perp_dot(rel).abs());
            let (ext_lon, ext_lat) = (a.hl * c + a.hw * sn, a.hl * sn + a.hw * c);
            let reach = b.hl + o.v * o.v / (2.0 * b.lim.brake_max) + o.v * self.dt + SAFE_MARGIN + 0.3;
            lon - ext_lon < reach && lon + ext_lon > -b.hl && lat - ext_lat < b.hw + 0.4
        })
    }

    /// Undo moves until no two boxes overlap (conflict pairs excepted). Undoing every move
    /// restores the previous frame, which had no overlap, so this always ends. `f` is the frame
    /// being simulated.
    fn resolve_overlaps(&mut self, f: usize) {
        let n = self.actors.len();
        let pairs = self.overlap_pairs();
        // Each pass undoes at least one turn or move: two per agent at most.
        for _ in 0..=2 * n {
            let mut changed = false;
            // The pairs (i, j > i) in index order (undoing a move changes later pairs'
            // outcome), bounding circles first.
            for &(i, j) in &pairs {
                let (ai, aj) = (&self.actors[i], &self.actors[j]);
                let (si, sj) = (&self.next[i], &self.next[j]);
                let r = ai.radius + aj.radius;
                if si.pos.distance_squared(sj.pos) >= r * r || self.exempt(i, j) {
                    continue;
                }
                if !ai.obb(si).overlaps(&aj.obb(sj)) {
                    continue;
                }
                // A walker turning on the spot sweeps its corners out to its half-diagonal:
                // beside another (two crossing side by side) it keeps its heading and steps on
                // sideways, rather than standing there for good. Turns are undone first, moves
                // only if the pair still overlaps without them.
                let turning = |k: usize| {
                    let (nk, ck) = (self.next[k], self.cur[k]);
                    !self.actors[k].vehicle
                        && matches!(self.actors[k].drive, Drive::Mover)
                        && nk.yaw != ck.yaw
                        && nk.pos != ck.pos
                };
                let turns = [(i, turning(i)), (j, turning(j))];
                if turns.iter().any(|t| t.1) {
                    for (k, _) in turns.into_iter().filter(|t| t.1) {
                        self.next[k].yaw = self.cur[k].yaw;
                    }
                    changed = true;
                    continue;
                }
                for k in [i, j] {
                    let (nk, ck) = (self.next[k], self.cur[k]);
                    let moved = nk.pos != ck.pos || nk.yaw != ck.yaw;
                    if matches!(self.actors[k].drive, Drive::Mover) && moved {
                        if self.cur[k].v > self.actors[k].lim.brake_max * self.dt + 1e-6 {
                            let other = if k == i { j } else { i };
                            self.first_hard.get_or_insert((k, other, f as f64 * self.dt));
                        }
                        self.next[k] = State { v: 0.0, ..self.cur[k] };
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        self.pairs = pairs;
    }

    /// The pairs (i, j > i), in index order, whose bounding circles may meet in
    /// `resolve_overlaps`: there an agent is at its `next` position or, once its move is undone,
    /// at its `cur` one, so a pair whose boxes around both positions (circle plus `MARGIN`) do
    /// not meet fails the circle test in every pass and changes nothing. A sweep over the boxes
    /// sorted by x, instead of every pair; with a position beyond `FAR` or not finite, where the
    /// margin might not cover float rounding, every pair.
    fn overlap_pairs(&mut self) -> Vec<(usize, usize)> {
        // Far above the rounding of coordinates below `FAR` (~1e-7 m).
        const MARGIN: f64 = 0.01;
        const FAR: f64 = 1e9;
        let n = self.actors.len();
        let mut pairs = std::mem::take(&mut self.pairs);
        pairs.clear();
        self.sweep.clear();
        let mut tame = true;
        for k in 0..n {
            let (p, q, r) = (self.next[k].pos, self.cur[k].pos, self.actors[k].radius);
            // Compared one by one: `max_element` would pass over a NaN.
            tame &= [p.x, p.y, q.x, q.y, r].iter().all(|c| c.abs() < FAR);
            let r = DVec2::splat(r + MARGIN);
            self.sweep.push((p.min(q) - r, p.max(q) + r, k));
        }
        if !tame {
            pairs.extend((0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))));
            return pairs;
        }
        self.sweep.sort_unstable_by(|a, b| a.0.x.total_cmp(&b.0.x));
        for (x, &(lo, hi, k)) in self.sweep.iter().enumerate() {
            for &(lo2, hi2, k2) in &self.sweep[x + 1..] {
                if lo2.x > hi.x {
                    break;
                }
                if lo2.y <= hi.y && hi2.y >= lo.y {
                    pairs.push((k.min(k2), k.max(k2)));
                }
            }
        }
        pairs.sort_unstable();
        pairs
    }

    /// Latch each staged conflict at its deepest overlap: once the boxes meet, the frame where
    /// the planned penetration is reached (or the impact time passes, or the overlap starts to
    /// shrink) freezes both agents there.
    fn latch(&mut self, f: usize, out: &mut Tracks) {
        let t = f as f64 * self.dt;
        for (k, conf) in self.confs.iter().enumerate() {
            let Some(plan) = self.plans.get(k).and_then(|p| p.as_ref()) else { continue };
            if self.latched[k] {
                continue;
            }
            let (af, st) = (conf.af, conf.st);
            let (mut a, mut b) = (self.actors[af].obb(&self.next[af]), self.actors[st].obb(&self.next[st]));
            if !a.overlaps(&b) {
                if self.prev_depth[k] <= 0.0 {
                    continue;
                }
                // They touched last frame and come apart now (a graze ahead of the planned
                // impact): that was the crash, deepest last frame. The pair stays where it was.
                for x in [af, st] {
                    self.next[x] = State { v: 0.0, ..self.cur[x] };
                }
                (a, b) = (self.actors[af].obb(&self.next[af]), self.actors[st].obb(&self.next[st]));
            }
            let depth = stage::depth(&a, &b);
            if depth >= 0.8 * plan.delta || t >= plan.t_impact - 0.5 * self.dt || depth <= self.prev_depth[k] {
                self.latched[k] = true;
                self.next[af].frozen = true;
                self.next[st].frozen = true;
                let p = stage::contact_centroid(&a, &b).unwrap_or((a.center + b.center) / 2.0);
                let local = |o: &Obb| {
                    let q = (p - o.center).rotate(DVec2::from_angle(-o.yaw));
                    [q.x, q.y]
                };
                let sl = local(&b);
                out.impacts.push(ImpactRecord {
                    conflict: conf.index,
                    frame: f,
                    at_fault: af,
                    struck: st,
                    point_world: [p.x, p.y],
                    at_fault_local: local(&a),
                    struck_local: sl,
                    struck_side: stage::side_of(DVec2::new(sl[0], sl[1]), b.length, b.width),
                    depth,
                });
            } else {
                self.prev_depth[k] = depth;
            }
        }
    }
}

/// At most this many steps of a striker's braking course (`Sim::braking_course`).
const COURSE_STEPS: usize = 40;

/// The first centre arc length from `from` (to within a quarter metre, never past the
/// true one) at which the box of `a`, stretched across its path to the offsets `band`,
/// meets `theirs`, following its path up to `to`.
fn band_meets(a: &Actor, from: f64, to: f64, band: (f64, f64), theirs: &Obb) -> Option<f64> {
    let (mid, width) = (0.5 * (band.0 + band.1), band.1 - band.0);
    // The box for every centre position in [s, s + step].
    let meets = |s: f64, step: f64| {
        let (p, h) = a.path.point(s + 0.5 * step, mid);
        Obb { center: p, yaw: h, length: 2.0 * a.hl + step, width }.overlaps(theirs)
    };
    let mut s = from;
    while s < to {
        if meets(s, 1.0) {
            return (0..4).map(|k| s + 0.25 * k as f64).find(|&q| meets(q, 0.25)).or(Some(s + 0.75));
        }
        s += 1.0;
    }
    None
}

/// The nearest longitudinal point, relative to its centre, of the part of a box lying inside the
/// lateral band `lo..hi` of a path frame (the box centred at lateral offset `lat`, its heading at
/// cosine `cr` and sine `sr` to the path's, half sizes `hl`, `hw`); `None` when no part does.
fn band_front(lat: f64, cr: f64, sr: f64, hl: f64, hw: f64, lo: f64, hi: f64) -> Option<f64> {
    let (ax, ay) = (DVec2::new(cr, sr), DVec2::new(-sr, cr));
    let c = DVec2::new(0.0, lat);
    let mut poly = vec![c + ax * hl + ay * hw, c - ax * hl + ay * hw, c - ax * hl - ay * hw, c + ax * hl - ay * hw];
    // Sutherland-Hodgman against y >= lo, then y <= hi.
    for (bound, keep_above) in [(lo, true), (hi, false)] {
        let inside = |p: DVec2| if keep_above { p.y >= bound } else { p.y <= bound };
        let mut out = Vec::with_capacity(poly.len() + 2);
        for k in 0..poly.len() {
            let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
            if inside(p) {
                out.push(p);
            }
            if inside(p) != inside(q) {
                let u = (bound - p.y) / (q.y - p.y);
                out.push(p + (q - p) * u);
            }
        }
        poly = out;
        if poly.is_empty() {
            return None;
        }
    }
    poly.iter().map(|p| p.x).reduce(f64::min)
}

/// Smooth 0..1 profile with zero velocity and acceleration at both ends.
fn quintic(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)
}

/// Rotate `from` toward `to`, bounded by a yaw rate (holonomic agents turn on the spot).
fn turn_toward(from: f64, to: f64, rate: f64, dt: f64) -> f64 {
    let step = wrap_angle(to - from).clamp(-rate * dt, rate * dt);
    wrap_angle(from + step)
}

/// Pure pursuit: the curvature of the circle through `p`, tangent to the unit heading `fwd`
/// there, and through `aim` (0 when `aim` is on the heading line or at `p`).
fn pursuit(p: DVec2, fwd: DVec2, aim: DVec2) -> f64 {
    let rel = aim - p;
    let l2 = rel.length_squared();
    if l2 < 1e-12 { 0.0 } else { 2.0 * fwd.perp_dot(rel) / l2 }
}

/// `Sim::advance` from a bare pose (the dry run of `assign_bends` steers as the rollout does).
fn steer(a: &Actor, pos: DVec2, yaw: f64, k: f64, dist: f64, dt: f64, yaw_scale: f64) -> (DVec2, f64) {
    if dist <= 0.0 {
        return (pos, yaw);
    }
    let k_max = (1.0 / a.r_min).min(yaw_scale * a.lim.yaw_rate * dt / dist);
    arc(pos, yaw, k.clamp(-k_max, k_max), dist)
}

/// Pure pursuit's look-ahead distance for vehicle `a` at speed `v`, m.
fn look_ahead(a: &Actor, v: f64) -> f64 {
    (0.8 * v).max(2.0 + 0.25 * a.r_min).min(20.0)
}

/// Exact integration of the kinematic bicycle over a step of length `dist` at curvature `k`:
/// the box moves along a circular arc tangent to its heading (no sideways slip).
fn arc(p: DVec2, yaw: f64, k: f64, dist: f64) -> (DVec2, f64) {
    let dyaw = k * dist;
    let chord = if dyaw.abs() < 1e-9 { dist } else { 2.0 * (0.5 * dyaw).sin() / k };
    (p + DVec2::from_angle(yaw + 0.5 * dyaw) * chord, wrap_angle(yaw + dyaw))
}

fn idm_free(v: f64, v0: f64, lim: Limits, dt: f64) -> f64 {
    if v0 < 0.05 {
        return -(v / dt).min(lim.brake);
    }
    (lim.accel * (1.0 - (v / v0).powi(4))).max(-lim.brake)
}

/// Keyframe time tolerance (s) of `replay`; see there.
pub const KEY_SNAP_S: f64 = 1e-6;

fn idm_interaction(v: f64, v_lead: f64, gap: f64, s0: f64, lim: Limits) -> f64 {
    let s_star = s0 + (v * lim.headway + v * (v - v_lead) / (2.0 * (lim.accel * lim.brake).sqrt())).max(0.0);
    let g = gap.max(0.05);
    lim.accel * (1.0 - (s_star / g) * (s_star / g))
}

/// Constant deceleration that halts exactly `rem` metres ahead, engaged once it reaches half the
/// comfortable braking or the mark is near (so approach is at speed, and the stop lands on it).
fn stop_law(v: f64, rem: f64, lim: Limits, dt: f64) -> f64 {
    if rem <= 0.05 {
        return -v / dt;
    }
    let b = v * v / (2.0 * rem);
    // Close to the mark, always: car-following alone only creeps up on a standstill gap.
    if b >= 0.5 * lim.brake || rem < 2.0 { -b } else { f64::INFINITY }
}

/// Keyframe interpolation: linear in position, shortest arc in yaw, held beyond either end.
/// At a keyframe's own time (within `KEY_SNAP_S`, the float noise of `f * dt`) the keyframe is
/// returned exactly, so recorded frames replay bit for bit (the importer's lossless guarantee).
fn replay(keys: &[Keyframe], t: f64) -> (DVec2, f64) {
    if let Some(k) = keys.iter().find(|k| (k.t - t).abs() <= KEY_SNAP_S) {
        return (DVec2::new(k.x, k.y), k.yaw);
    }
    let k = keys.partition_point(|k| k.t <= t);
    if k == 0 {
        let f = &keys[0];
        return (DVec2::new(f.x, f.y), f.yaw);
    }
    if k >= keys.len() {
        let l = &keys[keys.len() - 1];
        return (DVec2::new(l.x, l.y), l.yaw);
    }
    let (a, b) = (&keys[k - 1], &keys[k]);
    let u = if b.t > a.t { (t - a.t) / (b.t - a.t) } else { 1.0 };
    let p = DVec2::new(a.x, a.y).lerp(DVec2::new(b.x, b.y), u);
    (p, wrap_angle(a.yaw + wrap_angle(b.yaw - a.yaw) * u))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reproducible stream of numbers in [0, 1) (a 64-bit LCG's top 53 bits).
    fn lcg(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// `n` vehicle actors of random size (1 m to `1 + extra` m long) at the origin.
    fn random_boxes(n: usize, extra: f64, rnd: &mut impl FnMut() -> f64) -> Vec<Actor> {
        (0..n)
            .map(|k| {
                let info = TrackAgent {
                    name: format!("a{k}"),
                    kind: "sedan".into(),
                    class: Class::Vehicle,
                    motion: Motion::Vehicle,
                    size: [1.0 + extra * rnd(), 0.5 + 2.0 * rnd(), 1.5],
                    background: false,
                };
                base_actor(info, Pose { x: 0.0, y: 0.0, yaw: 0.0 }, Motion::Vehicle, Class::Vehicle, Drive::Mover)
            })
            .collect()
    }

    /// A striker `a0` (staged against `a2`) passing `a1`; `a1` slows by `drop` m/s in one frame
    /// with its box `gap` m from the striker's. `forced_braking` names `a1` exactly when the drop
    /// is beyond its 8 m/s2 and the boxes are within 1 m; the striker's own stop dead at its
    /// latched frame is the crash, not braking.
    #[test]
    fn forced_braking_is_braking_beyond_the_limit_next_to_a_striker() {
        use crate::check::scenario::{Conflict, Impact, Point};
        let case = |drop: f64, gap: f64| {
            let actors = random_boxes(3, 0.0, &mut lcg(7));
            let (frames, dt) = (10, 0.1);
            let mut out = empty_tracks(&actors, 1.0 / dt, frames);
            for f in 0..frames {
                let (l0, l1) = (actors[0].info.size[0], actors[1].info.size[0]);
                out.poses[0].push(Pose { x: 0.0, y: 0.0, yaw: 0.0 });
                out.poses[1].push(Pose { x: 0.5 * (l0 + l1) + gap, y: 0.0, yaw: 0.0 });
                out.poses[2].push(Pose { x: -20.0, y: 0.0, yaw: 0.0 });
                out.speeds[0].push(if f < 8 { 5.0 } else { 0.0 });
                out.speeds[1].push(if f < 5 { 5.0 } else { 5.0 - drop });
                out.speeds[2].push(0.0);
            }
            out.impacts.push(ImpactRecord {
                conflict: 0,
                frame: 8,
                at_fault: 0,
                struck: 2,
                point_world: [0.0; 2],
                at_fault_local: [0.0; 2],
                struck_local: [0.0; 2],
                struck_side: Point::Rear,
                depth: 0.25,
            });
            let c = Conflict {
                at_fault: 0,
                struck: 2,
                impact: Impact::RearEnd,
                point: Point::Rear,
                at: None,
                span: Default::default(),
            };
            let confs = [Conf { index: 0, af: 0, st: 2, c }];
            let plan = Plan {
                struck: 2,
                rel_pos: DVec2::ZERO,
                rel_yaw: 0.0,
                t_depart: 0.0,
                t_impact: 0.8,
                frame: 8,
                delta: 0.25,
            };
            forced_braking(&actors, &confs, &[Some(plan)], &out).map(|f| (f, forced_error(&actors, &confs, f)))
        };
        let Some(((k, who, by, t, acc), d)) = case(1.5, 0.5) else { panic!("15 m/s2 beside the striker passed") };
        assert_eq!((k, who, by), (0, 1, 0));
        assert!((t - 0.5).abs() < 1e-9 && (acc + 15.0).abs() < 1e-6, "{t} {acc}");
        assert_eq!(d.code, "E0205");
        assert!(
            d.message.contains("at 0.5 s `a1` would have to brake at 15.0 m/s2 for `a0` (its limit is 8.0)"),
            "{}",
            d.message
        );
        assert!(
            d.help.as_deref().is_some_and(|h| h.starts_with("keep `a1` out of the way `a0` takes")),
            "{:?}",
            d.help
        );
        assert!(case(1.5, 1.2).is_none(), "1.2 m from the striker is not its doing");
        assert!(case(0.75, 0.5).is_none(), "7.5 m/s2 is within the limit");
    }

    /// `candidates` through the along index must give exactly the agents (and order) of the scan
    /// of everyone, for agents on a straight run among others ahead, behind, beside, far off,
    /// crossing it, walking, holding at a line, with and without a named leader; and the index
    /// must answer most asks, or the test proves nothing.
    #[test]
    fn along_index_keeps_every_candidate() {
        let mut rnd = lcg(11);
        let n = 160;
        let mut actors = random_boxes(n, 11.0, &mut rnd);
        for a in actors.iter_mut().step_by(9) {
            a.vehicle = false;
        }
        let road = Path::straight(DVec2::new(-300.0, 40.0), 0.37, 3000.0);
        let mut sim = Sim::new(&actors, &[], &[], None, 0.1);
        for k in 0..n {
            let s = 500.0 + 700.0 * rnd();
            let lat = (rnd() - 0.5) * 40.0;
            let (p, h) = road.point(s, lat);
            let turn = match k % 7 {
                0 => 1.2,
                1 => std::f64::consts::PI,
                _ => (rnd() - 0.5) * 0.03,
            };
            sim.cur[k] = State { pos: p, yaw: h + turn, v: 35.0 * rnd(), s, d: lat, off: lat, ..sim.cur[k] };
        }
        sim.dirs = sim.cur.iter().map(|s| DVec2::from_angle(s.yaw)).collect();
        sim.near = (0..n).map(|k| Near::new(&sim.cur[k], &actors[k], sim.dirs[k], k % 11 == 0)).collect();
        let (mut asked, mut indexed) = (0, 0);
        for (i, ai) in actors.iter().enumerate() {
            let st = sim.cur[i];
            let Some(line) = road.straight_run(st.s) else { continue };
            for (k, look) in [15.0, 60.0, 240.0].into_iter().enumerate() {
                let wide = 2.0 * rnd();
                let c = Corridor {
                    look,
                    lo: st.d - ai.hw - wide,
                    hi: st.d + ai.hw + 0.1,
                    holding: true,
                    line: Some(line),
                    clearing: k == 1 && i % 2 == 0,
                    named: (k == 2).then_some((i * 7 + 3) % n),
                    back: if k == 1 { 8.0 } else { 0.0 },
                };
                let mut got = vec![];
                sim.candidates(i, &c, &mut got);
                let me = (i, ai, &sim.cur[i], sim.dirs[i]);
                let mut want: Vec<usize> = (0..n).filter(|&j| sim.candidate(me, &c, j)).collect();
                want.extend(c.named.filter(|&j| j != i));
                assert_eq!(got, want, "agent {i}, look {look}");
                asked += 1;
                indexed += usize::from(sim.corridor_subset(i, &c, line));
            }
        }
        assert!(indexed * 10 > asked * 9, "the index answered {indexed} of {asked}");
    }

    /// `overlap_pairs` may leave out only pairs whose bounding circles cannot meet at any mix of
    /// the positions `resolve_overlaps` can give them (`next`, or `cur` once undone), and must
    /// list the rest once each in (i, j) order; with a position it cannot bound, every pair.
    #[test]
    fn overlap_pairs_keep_every_pair_that_can_meet() {
        let mut rnd = lcg(7);
        let n = 120;
        let actors = random_boxes(n, 6.0, &mut rnd);
        let mut sim = Sim::new(&actors, &[], &[], None, 0.1);
        for k in 0..n {
            // Clusters of touching and nearly touching boxes, moves up to 4 m, a few far away.
            let base = if k % 10 == 0 { DVec2::new(5e3 * rnd(), -3e3) } else { DVec2::new(60.0 * rnd(), 8.0 * rnd()) };
            sim.cur[k].pos = base;
            sim.next[k].pos = base + DVec2::new(4.0 * rnd() - 2.0, 4.0 * rnd() - 2.0);
        }
        let can_meet = |sim: &Sim, i: usize, j: usize| {
            let r = actors[i].radius + actors[j].radius;
            [sim.next[i].pos, sim.cur[i].pos]
                .iter()
                .any(|p| [sim.next[j].pos, sim.cur[j].pos].iter().any(|q| p.distance_squared(*q) < r * r))
        };
        let pairs = sim.overlap_pairs();
        assert!(pairs.windows(2).all(|w| w[0] < w[1]) && pairs.iter().all(|&(i, j)| i < j && j < n));
        let meeting: Vec<(usize, usize)> =
            (0..n).flat_map(|i| (i + 1..n).map(move |j| (i, j))).filter(|&(i, j)| can_meet(&sim, i, j)).collect();
        assert!(meeting.len() > 50, "the case must have meeting pairs: {}", meeting.len());
        assert!(meeting.iter().all(|p| pairs.binary_search(p).is_ok()));
        assert!(pairs.len() < n * (n - 1) / 4, "the sweep should leave most pairs out: {}", pairs.len());
        sim.next[3].pos.x = f64::NAN;
        assert_eq!(sim.overlap_pairs().len(), n * (n - 1) / 2);
        sim.next[3].pos.x = 2e9;
        assert_eq!(sim.overlap_pairs().len(), n * (n - 1) / 2);
    }
}
