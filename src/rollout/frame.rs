//! The frame loop (`Sim`): every frame computes each agent's next state from everyone's
//! current state (a Jacobi update, so the result does not depend on agent order), undoes moves
//! that would overlap, and latches crashes.

use crate::geom::wrap_angle;
use crate::place::Pose;
use crate::rollout::Tracks;
use crate::rollout::agent::Rank;
use crate::rollout::agent::initial;
use crate::rollout::agent::{Actor, Blocking, Conf, Drive, Lat, State, Yield};
use crate::rollout::drive::index::{AlongIndexes, Near};
use crate::rollout::impact::bodies::Wrecks;
use crate::rollout::kinematics::{replay, steer};
use crate::rollout::path::Foot;
use crate::rollout::staging::plan::Plan;
use glam::DVec2;
use std::f64::consts::PI;

pub(crate) struct Sim<'a, 'b> {
    pub(crate) actors: &'a [Actor],
    pub(crate) confs: &'a [Conf],
    /// Per conflict (pass 2 only).
    pub(crate) plans: &'a [Option<Plan>],
    pub(crate) pass1: Option<&'a Tracks>,
    /// Per actor: the plan it strikes with, if any.
    pub(crate) striker: Vec<Option<usize>>,
    pub(crate) latched: Vec<bool>,
    pub(crate) prev_depth: Vec<f64>,
    /// Per near miss across a path, whether its passer has come to rest since the pass
    /// (`Sim::brake_across`).
    pub(crate) halted: Vec<bool>,
    pub(crate) dt: f64,
    pub(crate) cur: Vec<State>,
    pub(crate) next: Vec<State>,
    /// Per agent: a slot for its approach lane (`Actor::approach`), dense from 0.
    pub(crate) approach_slot: Vec<Option<usize>>,
    /// Per agent: where its crossings start in `Scratch::ranks`.
    pub(crate) cross_at: Vec<usize>,
    /// The largest bounding radius of any agent.
    pub(crate) max_radius: f64,
    /// This frame's facts, settled before any agent steps.
    pub(crate) facts: Facts,
    /// Where a resumed run starts, and where a first pass keeps its states.
    pub(crate) resume: Resume<'b>,
    /// The first move the overlap safety net undid at a speed the agent could not have braked
    /// from within its limits in one step: the agent stopped, the one it would have run into,
    /// and when.
    pub(crate) first_hard: Option<HardStop>,
    /// `overlap_pairs`' boxes and output, kept likewise.
    pub(crate) sweep: Vec<(DVec2, DVec2, usize)>,
    pub(crate) pairs: Vec<(usize, usize)>,
    /// Some agent starts on a trigger (`fire_triggers`).
    pub(crate) any_trigger: bool,
    /// Masses, and the bodies moving on from an impact (`rollout::impact`).
    pub(crate) wreck: Wrecks,
}

/// What every agent's step reads of this frame besides the states: derived from `Sim::cur`
/// before any agent steps, read-only while they do.
pub(crate) struct Facts {
    /// Unit heading of every agent in `cur`: pair checks use dot and cross products, not trig.
    pub(crate) dirs: Vec<DVec2>,
    /// The bits of the heading each of `dirs` was taken from.
    pub(crate) dir_yaw: Vec<Option<u64>>,
    /// Per agent, this frame: `yield_state`, with the right-of-way rule's hold folded in.
    pub(crate) yielding: Vec<(Option<f64>, bool)>,
    /// Per agent, this frame: held by the right-of-way rule or at the kerb (`right_of_way`).
    pub(crate) ruled: Vec<bool>,
    /// Per agent, this frame: how far it may go while holding for anyone (scratch).
    pub(crate) held: Vec<Option<f64>>,
    /// Per agent, this frame: another vehicle is ahead of it on its junction approach, not yet
    /// past its stop line (`queued`).
    pub(crate) behind: Vec<bool>,
    /// Per approach slot (`Sim::approach_slot`), this frame: the two least distances to the stop
    /// line among the agents `queued` counts there, with their indices (`queue_heads`).
    pub(crate) lane_least: Vec<[(f64, usize); 2]>,
    /// This frame: agents easing aside (`away_from`, triggered), for `pass_offset`.
    pub(crate) easing: Vec<usize>,
    /// Per agent, this frame: what `candidates` reads, packed.
    pub(crate) near: Vec<Near>,
    /// This frame: agents whose triggers fired (`fire_triggers`), and whether for a phase.
    pub(crate) fired: Vec<(usize, bool)>,
    /// Agents that stand for good (`Actor::blocker`), for `avoid`.
    pub(crate) blockers: Vec<usize>,
    /// Slow moving road users others may pass (`drive::overtake`), for `avoid`.
    pub(crate) slow: Vec<usize>,
    /// Emergency vehicles that drive (`Actor::emergency`), for `siren_for`.
    pub(crate) sirens: Vec<usize>,
    /// Per agent, this frame: the emergency vehicle it makes way for (`siren_for`).
    pub(crate) siren_for: Vec<Option<Yield>>,
    /// This frame: each body moving on from an impact, with the pose its slide ends at
    /// (`Sim::rest_pose`), for `Sim::wrecks_ahead`.
    pub(crate) sliding: Vec<(usize, DVec2, f64)>,
}

/// Where a run starts and what it keeps (`Sim::keep_states`, `Sim::resume`).
pub(crate) struct Resume<'b> {
    /// Where to keep every frame's states (pass 1, for `resume`).
    pub(crate) keep: Option<&'b mut Vec<Vec<State>>>,
    /// The first frame to simulate: earlier ones are already in the output.
    pub(crate) first: usize,
    /// Frames `..first` of the output, copied by `run`.
    pub(crate) prefix: Option<&'b Tracks>,
}

/// At most this many steps of a striker's braking course (`Sim::braking_course`).
pub(crate) const COURSE_STEPS: usize = 40;

/// What the agents' steps may write while the frame's states are read: buffers kept for their
/// allocations, and what strikers record of who held them back. Everything else a step reads is
/// `Sim`, immutable while the frame's steps run, so that each agent's next state depends on the
/// previous frame alone.
pub(crate) struct Scratch {
    /// Per crossing (from `Sim::cross_at`), this frame: its `zone_rank` once asked for
    /// (`Sim::rank`): each pair's rule asks for both of its zones' ranks from either side.
    pub(crate) ranks: Vec<Option<Rank>>,
    /// This frame: the along indexes `candidates` built, and the agents one ask yields.
    pub(crate) index: AlongIndexes,
    /// `candidates`' output, and `Path::frenet_near` of each.
    pub(crate) cand: Vec<usize>,
    pub(crate) proj: Vec<Foot<DVec2>>,
    /// A striker's braking course (`braking_course`).
    pub(crate) course: Vec<(f64, DVec2, f64)>,
    /// The obstacles `avoid` sees.
    pub(crate) blocking: Vec<Blocking>,
    /// Per striker, each bystander that held it back at full speed: when first, and for how
    /// many frames.
    pub(crate) blocked_by: Vec<Vec<(usize, f64, u32)>>,
}

impl Scratch {
    pub(crate) fn new(agents: usize, crossings: usize) -> Scratch {
        Scratch {
            ranks: vec![None; crossings],
            index: AlongIndexes { along: vec![], subset: Vec::with_capacity(agents) },
            cand: Vec::with_capacity(agents + 1),
            proj: Vec::with_capacity(agents + 1),
            course: Vec::with_capacity(COURSE_STEPS),
            blocking: Vec::with_capacity(16),
            blocked_by: vec![Vec::new(); agents],
        }
    }
}

/// A move the overlap safety net undid at a speed the agent could not have braked from within its
/// limits in one step: the agent stopped, the one it would have run into, and when.
#[derive(Clone, Copy, Debug)]
pub(crate) struct HardStop {
    pub agent: usize,
    pub other: usize,
    pub t: f64,
}

/// What a run saw besides its tracks.
pub(crate) struct Report {
    /// Per striker, the bystander that held it back longest at full speed, and from when.
    pub(crate) blocked_by: Vec<Option<(usize, f64)>>,
    /// The first move the overlap safety net undid beyond the mover's braking limit
    /// (`Sim::first_hard`).
    pub(crate) first_hard: Option<HardStop>,
}

pub(crate) fn empty_tracks(actors: &[Actor], rate: f64, frames: usize) -> Tracks {
    Tracks {
        rate,
        frames,
        agents: actors.iter().map(|a| a.info.clone()).collect(),
        poses: actors.iter().map(|_| Vec::with_capacity(frames)).collect(),
        speeds: actors.iter().map(|_| Vec::with_capacity(frames)).collect(),
        impacts: vec![],
        bodies: vec![],
        contacts: vec![],
        flags: crate::rollout::agent::flag_tracks(actors, frames),
    }
}

impl<'a, 'b> Sim<'a, 'b> {
    pub(crate) fn new(
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
        Sim {
            actors,
            confs,
            plans,
            pass1,
            striker,
            latched: vec![false; confs.len()],
            prev_depth: vec![0.0; confs.len()],
            halted: vec![false; confs.len()],
            dt,
            next: cur.clone(),
            facts: Facts {
                dirs: cur.iter().map(|s| DVec2::from_angle(s.yaw)).collect(),
                dir_yaw: vec![],
                yielding: vec![(None, false); actors.len()],
                ruled: vec![false; actors.len()],
                held: vec![None; actors.len()],
                behind: vec![false; actors.len()],
                lane_least: vec![[(f64::INFINITY, usize::MAX); 2]; lanes.len()],
                easing: Vec::with_capacity(actors.len()),
                near: Vec::with_capacity(actors.len()),
                fired: Vec::with_capacity(actors.len()),
                blockers: (0..actors.len()).filter(|&i| actors[i].blocker).collect(),
                slow: crate::rollout::drive::slow::slow_movers(actors),
                sirens: (0..actors.len())
                    .filter(|&i| actors[i].emergency && matches!(actors[i].drive, Drive::Mover))
                    .collect(),
                siren_for: vec![None; actors.len()],
                sliding: vec![],
            },
            wreck: Wrecks::new(actors),
            any_trigger: actors.iter().any(|a| a.trigger.is_some() || !a.phases.is_empty()),
            approach_slot,
            cross_at,
            max_radius: actors.iter().map(|a| a.radius).fold(0.0, f64::max),
            first_hard: None,
            sweep: Vec::with_capacity(actors.len()),
            pairs: vec![],
            cur,
            resume: Resume { keep: None, first: 1, prefix: None },
        }
    }

    pub(crate) fn keep_states(mut self, keep: &'b mut Vec<Vec<State>>) -> Self {
        self.resume.keep = Some(keep);
        self
    }

    /// Start at frame `first` from `states[first - 1]`, taking frames `..first` from `done`
    /// (the run that produced `states`). Nothing before `first` may be latched.
    pub(crate) fn resume(mut self, done: &'b Tracks, states: &[Vec<State>], first: usize) -> Self {
        if first > 1 && first <= states.len() {
            self.cur.clone_from(&states[first - 1]);
            self.resume.first = first;
            self.resume.prefix = Some(done);
        }
        self
    }

    /// Run the frames into `out`; returns, per striker, the bystander that held it back longest,
    /// and from when (`blocked_by`): a car it slowed for once, in passing, did not make it miss.
    pub(crate) fn run(mut self, out: &mut Tracks) -> Report {
        let mut sc = Scratch::new(self.actors.len(), self.actors.iter().map(|a| a.crossings.len()).sum());
        if out.frames == 0 {
            return self.held_longest(sc);
        }
        match self.resume.prefix {
            Some(done) => {
                for (i, (p, v)) in done.poses.iter().zip(&done.speeds).enumerate() {
                    out.poses[i].extend_from_slice(&p[..self.resume.first]);
                    out.speeds[i].extend_from_slice(&v[..self.resume.first]);
                }
                for (o, d) in out.flags.iter_mut().zip(&done.flags) {
                    o.go.extend_from_slice(&d.go[..self.resume.first.min(d.go.len())]);
                }
            }
            None => self.record(out),
        }
        for f in self.resume.first..out.frames {
            let t = (f - 1) as f64 * self.dt;
            self.fire_triggers(t);
            self.fire_flags(t);
            // An agent whose heading has not changed (bit for bit) keeps its unit heading: the
            // same call on the same bits. Standing and straight-driving agents take no sine.
            self.facts.dirs.resize(self.cur.len(), DVec2::X);
            self.facts.dir_yaw.resize(self.cur.len(), None);
            for ((d, y), st) in self.facts.dirs.iter_mut().zip(&mut self.facts.dir_yaw).zip(&self.cur) {
                if *y != Some(st.yaw.to_bits()) {
                    (*d, *y) = (DVec2::from_angle(st.yaw), Some(st.yaw.to_bits()));
                }
            }
            if !self.facts.sirens.is_empty() {
                for i in 0..self.actors.len() {
                    self.facts.siren_for[i] = self.siren_for(i);
                }
            }
            self.facts.easing.clear();
            for (j, (o, b)) in self.cur.iter().zip(self.actors.iter()).enumerate() {
                if (o.triggered && matches!(b.lateral, Lat::Away { .. })) || self.facts.siren_for[j].is_some() {
                    self.facts.easing.push(j);
                }
            }
            // Emergency holds first: the right-of-way rule ranks one holding for an emergency
            // vehicle as not coming.
            for i in 0..self.actors.len() {
                self.facts.yielding[i] = self.yield_state(i);
                // A red (or a yellow it can stop for) holds it as an emergency vehicle would.
                if let Some(rem) = self.signal_hold(i, t).into_iter().chain(self.flag_hold(i, t)).reduce(f64::min) {
                    let y = &mut self.facts.yielding[i].0;
                    *y = Some(y.map_or(rem, |h| h.min(rem)));
                }
            }
            self.queue_heads();
            sc.ranks.fill(None);
            for i in 0..self.actors.len() {
                let rule = self.right_of_way(&mut sc.ranks, i, t);
                self.facts.ruled[i] = rule.is_some();
                self.facts.held[i] = match (self.facts.yielding[i].0, rule) {
                    (Some(x), Some(y)) => Some(x.min(y)),
                    (x, y) => x.or(y),
                };
            }
            for i in 0..self.actors.len() {
                self.facts.yielding[i].0 = self.facts.held[i];
            }
            // Packed after the holds are final: `candidates` reads them as `drive` does.
            self.facts.near.clear();
            for ((st, a), (&dir, y)) in
                self.cur.iter().zip(self.actors).zip(self.facts.dirs.iter().zip(&self.facts.yielding))
            {
                self.facts.near.push(Near::new(st, a, dir, y.0.is_some()));
            }
            self.facts.sliding.clear();
            if self.wreck.any {
                for j in 0..self.actors.len() {
                    if self.wreck.moving(j) {
                        let (pos, yaw) = self.rest_pose(j);
                        self.facts.sliding.push((j, pos, yaw));
                    }
                }
            }
            sc.index.along.clear();
            for i in 0..self.actors.len() {
                self.next[i] = self.step(&mut sc, i, t, f);
            }
            self.slide();
            self.resolve_overlaps(f);
            self.latch(f, out);
            self.collide(f, out);
            std::mem::swap(&mut self.cur, &mut self.next);
            self.record(out);
        }
        self.held_longest(sc)
    }

    pub(crate) fn held_longest(self, sc: Scratch) -> Report {
        let longest = |held: Vec<(usize, f64, u32)>| {
            // The first of equals: the list is in order of first hold.
            held.into_iter().rev().max_by_key(|h| h.2).map(|(j, t, _)| (j, t))
        };
        Report { blocked_by: sc.blocked_by.into_iter().map(longest).collect(), first_hard: self.first_hard }
    }

    pub(crate) fn record(&mut self, out: &mut Tracks) {
        if let Some(keep) = self.resume.keep.as_deref_mut() {
            keep.push(self.cur.clone());
        }
        if !out.flags.is_empty() {
            let f = out.poses.first().map_or(0, Vec::len);
            self.record_flags(out, f as f64 * self.dt);
        }
        for (i, st) in self.cur.iter().enumerate() {
            // A reversing vehicle moves along its state's heading, its body turned half round.
            let (yaw, v) = if self.actors[i].reverse { (wrap_angle(st.yaw + PI), -st.v) } else { (st.yaw, st.v) };
            out.poses[i].push(Pose { x: st.pos.x, y: st.pos.y, yaw });
            out.speeds[i].push(v);
        }
    }

    /// Conflict pairs may come close and overlap; nobody else may, except where one moves on
    /// from an impact (its contacts are impacts: `collide`). A `ttc` near miss's pair is one
    /// only until the pass: then its passer brakes behind the passed agent like any follower
    /// (tests/near-miss/rear-approach-at-under-a-second.scn). Across a path the pair stays one:
    /// the passed agent drives on as it would, and the passer stops short (`Sim::brake_across`).
    #[inline]
    pub(crate) fn exempt(&self, i: usize, j: usize) -> bool {
        self.wreck.moving(i) || self.wreck.moving(j) || self.conflict_pair(i, j)
    }

    /// `i` and `j` are a conflict's pair, free to come close (see `exempt`).
    #[inline]
    pub(crate) fn conflict_pair(&self, i: usize, j: usize) -> bool {
        self.confs.iter().enumerate().any(|(n, k)| {
            ((k.af == i && k.st == j) || (k.af == j && k.st == i))
                && !(self.latched[n] && matches!(k.near, Some(crate::rollout::agent::Near::Ttc(_))))
        })
    }

    /// The state of agent `i` at `t + dt`, from everyone's state at `t` (frame `f - 1`).
    pub(crate) fn step(&self, sc: &mut Scratch, i: usize, t: f64, f: usize) -> State {
        let a = &self.actors[i];
        let st = self.cur[i];
        match &a.drive {
            Drive::Static => st,
            // A track on a trigger stands at its first keyframe till the trigger fires.
            Drive::Replay(_) if !st.go => State { v: 0.0, ..st },
            Drive::Replay(keys) => {
                let (p, yaw) = replay(keys, t + self.dt - st.since);
                State { pos: p, yaw, v: p.distance(st.pos) / self.dt, ..st }
            }
            Drive::Mover if st.frozen => State { v: 0.0, ..st },
            Drive::Mover => match self.striker[i].and_then(|k| self.plans[k].as_ref().map(|p| (k, p))) {
                Some((k, plan)) if t >= plan.t_depart - 1e-9 && !self.latched[k] => self.intercept(sc, i, plan, t, f),
                _ => {
                    let d = self.drive(sc, i, t);
                    self.brake_across(i, d)
                }
            },
        }
    }

    /// Move vehicle `a` from `st` by `dist` along a circular arc of curvature `k`, bounded by its
    /// turning radius and by `yaw_scale` times its class yaw rate at the step's mean speed.
    pub(crate) fn advance(&self, a: &Actor, st: &State, k: f64, dist: f64, yaw_scale: f64) -> (DVec2, f64) {
        steer(a, st.pos, st.yaw, k, dist, self.dt, yaw_scale)
    }
}
