//! The controller of one agent for one step (`Sim::drive`): its lateral plan, the agents in its
//! way (`pair`, found by `neighbours`, answered by the car-following laws of `follow`), strikers'
//! contact poses ahead, its stop goals; then its body moved, a kinematic bicycle or a holonomic
//! step.

pub(crate) mod avoid;
mod doors;
pub(crate) mod follow;
pub(crate) mod index;
pub(crate) mod neighbours;
pub(crate) mod overtake;
pub(crate) mod pair;
pub(crate) mod reverse;
pub(crate) mod settle;
pub(crate) mod siren;
pub(crate) mod slow;
pub(crate) mod wrecks;

use crate::geom::{Obb, wrap_angle};
use crate::rollout::agent::{Lat, State, StopGoal};
use crate::rollout::drive::follow::{idm_free, stop_law};
use crate::rollout::drive::neighbours::Corridor;
use crate::rollout::drive::pair::{Constraint, Step};
use crate::rollout::drive::siren::MOVE_OVER_SPEED;
use crate::rollout::frame::{Scratch, Sim};
use crate::rollout::kinematics::{band_meets, look_ahead, pursuit, quintic, slip_tan, turn_toward};
use crate::rollout::path::Foot;
use glam::DVec2;

/// Lateral clearance a walker keeps from another walking beside it, and how fast it steps aside
/// to keep it (m, m/s).
const WALK_CLEAR: f64 = 0.15;
const WALK_ASIDE: f64 = 0.2;
/// How far a vehicle's lateral reference may lead its body's offset (m).
const MAX_LEAD: f64 = 0.5;
/// Lateral speed of a vehicle squeezing past an agent that eases aside for it (m/s).
pub(crate) const PASS_LAT_RATE: f64 = 1.0;
/// Side clearance kept while passing it (m).
pub(crate) const PASS_CLEARANCE: f64 = 0.4;
/// The most a pass may move off the lane's centre line (m): half into the next lane.
pub(crate) const PASS_MAX_SHIFT: f64 = 2.5;

/// A need to brake for others, m/s2 below zero, that a late reactor notices (`react`).
const BRAKE_NEED: f64 = -0.5;

/// What others ask of an agent with reaction time `reaction` (`others`, an acceleration), and how
/// long their need to brake has gone unanswered after this step: while it is shorter than the
/// reaction time, the need is not answered at all. A careful agent (no reaction time) answers at once.
fn react(reaction: f64, alarm: f64, others: f64, dt: f64) -> (f64, f64) {
    if reaction <= 0.0 {
        return (others, 0.0);
    }
    if others >= BRAKE_NEED {
        return (others, 0.0);
    }
    if alarm + 1e-9 >= reaction { (others, alarm + dt) } else { (f64::INFINITY, alarm + dt) }
}

/// Agent `i`'s lateral plan for one step (`Sim::lateral`).
#[derive(Clone, Copy)]
struct LateralPlan {
    /// The offset its lateral goal's profile heads for, once active (or triggered).
    target: Option<f64>,
    /// The profile's duration, s.
    dur: f64,
    triggered: bool,
    phase: f64,
    /// The reference offset after this step.
    d_next: f64,
    /// Where a pass of one easing aside for us (or of an obstacle) heads.
    pass_target: Option<f64>,
    /// Held back from passing an obstacle: how far short of it to wait (`Avoid::standoff`).
    standoff: f64,
}

impl Sim<'_, '_> {
    /// The state of agent `i` at `t + dt` under the controller: IDM toward its goal speed under
    /// the curve-speed cap, bounded by every agent in its way (each a `Constraint`, folded by
    /// `min`), by strikers' contact poses ahead, its stop goals, holds and the end of its path;
    /// then its body moved.
    pub(crate) fn drive(&self, sc: &mut Scratch, i: usize, t: f64) -> State {
        let (a, st, dt) = (&self.actors[i], self.cur[i], self.dt);
        let lim = a.lim;
        if st.stopped {
            return State { v: 0.0, ..st };
        }
        let active = a.active(&st, t);
        let mut v_des = if active { a.goal_speed(&st) } else { a.v_hold }.min(a.path.cap(st.s));
        // Making way for an emergency vehicle: over at a moderate pace, then stopped till it
        // has passed.
        if let Some(y) = self.facts.siren_for[i] {
            let over = (st.off - y.offset).abs() < 0.3;
            v_des = if over { 0.0 } else { v_des.min(st.v.max(3.0)).min(MOVE_OVER_SPEED) };
        }
        let lateral = self.lateral(sc, i, active, t);
        let LateralPlan { target, triggered, mut phase, mut d_next, pass_target, standoff, .. } = lateral;
        let margin = if a.vehicle { 0.25 } else { 0.1 };
        // Till the reference is there: the profile's clock runs out while a creeping car's
        // reference is held back by its body (`MAX_LEAD`), and the target lane must still be
        // watched (a car creeping alongside in it was driven into).
        let goal_d = target.filter(|&tg| st.phase < 1.0 || (st.d - tg).abs() > 1e-3).or(pass_target).unwrap_or(st.d);
        // The band the box occupies now: a steering vehicle lags its reference offset.
        let (cur_lo, cur_hi) = (st.d.min(st.off) - a.hw, st.d.max(st.off) + a.hw);
        // Turned off the path while it moves sideways, our nose reaches out of that band on the
        // side it points: a bus easing into the inner lane at 0.12 rad put its front corner on the
        // centre line, into the nose of an oncoming bus doing the same
        // (tests/rollout-cases/buses-changing-into-their-inner-lanes-nose-to-nose.scn).
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
        let sweep_to = st.s + 2.0 * a.hl + look;
        // The least this step can advance braking at the limit.
        let shortest = (st.v * dt - 0.5 * lim.brake_max * dt * dt).max(0.0);
        let named = match a.stop {
            StopGoal::Behind(k) if active => Some(k),
            _ => None,
        };
        let (yield_rem, clearing) = self.facts.yielding[i];
        let s = Step {
            i,
            a,
            st,
            t,
            lim,
            dt,
            active,
            v_des,
            d_next,
            goal_d,
            half_done,
            cur_lo,
            cur_hi,
            nose_lo,
            nose_hi,
            lo,
            hi,
            margin,
            look,
            sweep_to,
            shortest,
            named,
            clearing,
            standoff,
        };
        let way = self.in_the_way(sc, &s);
        // What others ask of us (the agents in our way, strikers ahead, our holds) is answered
        // only once our reaction time has passed (`Behaviour::reaction`).
        let mut others = way.acc.min(self.strikers_ahead(&s));
        hard = hard.min(way.hard);
        let Constraint { touch_rem, side_blocked, aside, .. } = way;
        let mut stop_rem = None;
        if active {
            stop_rem = match a.stop {
                StopGoal::Front(sf) => Some(sf - (st.s + a.hl)),
                StopGoal::Centre(sc) => Some(sc - st.s),
                _ => None,
            };
            // A goal phase's `stop after`, counted from where that phase started.
            if let Some(d) = a.stage(&st).and_then(|p| p.stop_after) {
                stop_rem = Some(stop_rem.map_or(f64::INFINITY, |r: f64| r).min(st.stage_s + d - st.s));
            }
        }
        if let Some(rem) = stop_rem {
            acc = acc.min(stop_law(st.v, rem, lim, dt));
            // A stop target is a goal, not an obstacle: one closer than the braking distance is
            // overrun by what the brakes cannot absorb, never met by braking past the limit.
            hard = hard.min(rem.max(shortest));
        }
        for rem in yield_rem.into_iter().chain((touch_rem < f64::INFINITY).then_some(touch_rem)) {
            others = others.min(stop_law(st.v, rem, lim, dt));
            hard = hard.min(rem.max(shortest));
        }
        let (others, alarm) = react(a.behaviour.reaction, st.alarm, others, dt);
        acc = acc.min(others);
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
        let give_way = self.facts.ruled[i];
        let next = State { v, d: d_next, phase, triggered, stopped, frozen: false, give_way, alarm, ..st };
        self.move_body(i, next, adv, &lateral, side_blocked, aside)
    }

    /// Lateral: where the profile would put us next, and where a pass of one easing aside for
    /// us heads.
    fn lateral(&self, sc: &mut Scratch, i: usize, active: bool, t: f64) -> LateralPlan {
        let (a, st, dt) = (&self.actors[i], self.cur[i], self.dt);
        let lim = a.lim;
        let mut triggered = st.triggered;
        let (target, dur) = match a.lateral {
            Lat::Hold => (None, 1.0),
            Lat::Shift { target, dur } => ((active && st.stage >= a.shift_stage).then_some(target), dur),
            Lat::Away { who, target, dur } => {
                // Away from something standing: eased to the far side of our lane from it once it
                // is near ahead.
                let stands = self.actors[who].blocker;
                let mut to = target;
                if (active && !triggered) || stands {
                    let o = &self.cur[who];
                    let Foot { s: sk, d: lk, beyond, .. } =
                        a.path.frenet(o.pos, st.s + (o.pos - st.pos).dot(DVec2::from_angle(st.yaw)));
                    let behind = st.s - sk;
                    let closing = o.v - st.v;
                    if stands {
                        to = if lk < a.d0 { a.d0 + (a.lane_hw - a.hw - 0.2).max(0.0) } else { a.pull };
                    }
                    triggered = triggered
                        || (active
                            && beyond < 1.0
                            && (lk - st.d).abs() < 4.0
                            && if stands {
                                -behind > 0.0 && -behind < 40.0f64.max(st.v * 5.0)
                            } else {
                                behind > 0.0 && behind < 40.0f64.max(closing * 5.0) && (closing > 0.0 || behind < 15.0)
                            });
                }
                (triggered.then_some(to), dur)
            }
        };
        let mut phase = st.phase;
        let mut d_next = st.d;
        let mut pass_target = None;
        let mut standoff = 0.0;
        if let Some(tg) = target {
            phase = (st.phase + dt / dur).min(1.0);
            d_next = a.d0 + (tg - a.d0) * quintic(phase);
        } else if a.vehicle && matches!(a.lateral, Lat::Hold) && !a.reverse {
            // Pull over for an emergency vehicle; squeeze past whoever is easing aside for us
            // (`away_from`, or for our siren) or round what stands in our lane; then settle back.
            let look = st.v * st.v / (2.0 * lim.brake) + 2.5 * st.v + 15.0;
            let tg = if let Some(y) = self.facts.siren_for[i] {
                y.offset
            } else if active && a.stage(&st).is_some_and(|p| p.pull) {
                // A goal phase that pulls over: onto the shoulder, as for a siren.
                a.pull
            } else if let Some(tg) = self.pass_offset(i, look) {
                self.within_lane_while_beside(i, tg)
            } else {
                // The frame of the states read now (`t`), for the angle of an open door.
                let now = (t / self.dt).round() as usize;
                let avoid = self.avoid(i, look, now, &mut sc.blocking);
                standoff = avoid.map_or(0.0, |v| if v.target.is_none() { v.standoff } else { 0.0 });
                self.clear_of_beside(i, avoid.and_then(|v| v.target).unwrap_or(a.d0))
            };
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
        LateralPlan { target, dur, triggered, phase, d_next, pass_target, standoff }
    }

    /// Every agent in the way of step `s`, each one's `Constraint` folded.
    fn in_the_way(&self, sc: &mut Scratch, s: &Step) -> Constraint {
        let Step { i, a, st, d_next, lo, hi, margin, look, named, clearing, .. } = *s;
        let fwd = self.facts.dirs[i];
        // On a straight stretch of our route, an agent's route coordinates are its coordinates
        // along the line: those that provably change nothing below are passed over without the
        // projection (the pair loop's main cost). Only when holding our offset: lateral moves
        // look at everyone alongside.
        let line = if d_next == st.d { a.path.straight_run(st.s) } else { None };
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
        self.candidates(i, &corridor, &mut sc.index, &mut sc.cand);
        // Their projections onto our route first, in a loop of their own: each is a chain of
        // dependent steps, and independent chains overlap there (below, every decision waits
        // on its own).
        sc.proj.clear();
        // Where the Newton search does not settle (near a U-turn's loop), the first foot ahead of
        // our centre within the corridor's reach, searched over the stretch anyone could meet us on
        // (`Path::frenet_near`): an unsettled projection put a car crossing 18 m from an
        // ambulance's loop a quarter metre off its path, and stopped it dead
        // (tests/rollout-cases/ambulance-u-turn-crossing-car-off-loop.scn).
        let window = (st.s - a.hl - 2.0 * self.max_radius, st.s + a.hl + look + 2.0 * self.max_radius);
        let reach = c_lo.abs().max(c_hi.abs()) + self.max_radius;
        sc.proj.extend(sc.cand.iter().map(|&j| {
            let p = self.cur[j].pos;
            a.path.frenet_near(p, st.s + (p - st.pos).dot(fwd), window, st.s, reach)
        }));
        let c =
            sc.cand.iter().zip(sc.proj.iter()).fold(Constraint::FREE, |c, (&j, &at)| c.and(self.constraint(s, j, at)));
        c.and(self.wrecks_ahead(s, window, reach))
    }

    // A striker stops dead where it meets its target (the latch): there it stands in our
    // way, though it only passes through our band now. A bus overtaking a car at 19 m/s cut
    // diagonally into the lane of another 4.7 m ahead of it and stood there, 2 m on (-19
    // m/s2). Ahead of us only: one already where it will stand moves on out of its way.
    fn strikers_ahead(&self, s: &Step) -> f64 {
        let Step { a, st, t, lim, dt, lo, hi, look, .. } = *s;
        let mut acc = f64::INFINITY;
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
        acc
    }

    /// Agent `i`'s body moved `adv` along its route toward the lateral reference in `next`:
    /// walkers and animals step onto it holonomically, vehicles follow it as kinematic bicycles.
    fn move_body(&self, i: usize, next: State, adv: f64, lat: &LateralPlan, side_blocked: bool, aside: f64) -> State {
        let (a, st, dt) = (&self.actors[i], self.cur[i], self.dt);
        let lim = a.lim;
        let (v, d_next, phase) = (next.v, next.d, next.phase);
        let LateralPlan { target, dur, pass_target, .. } = *lat;
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
            // kept crabbing toward the car passing in the lane it had been moving into, its nose
            // 0.4 m over (on a curve,
            // tests/rollout-cases/bus-blocked-changing-lane-beside-a-motorcycle.scn), and one 0.05
            // m past it steered back, its tail swinging out at the car following in that lane
            // (tests/rollout-cases/bus-blocked-changing-lane-swings-its-tail-at-a-follower.scn).
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
        let k = pursuit(st.pos, self.facts.dirs[i], aim);
        let (pos, yaw) = self.advance(a, &st, k, adv, 1.0);
        let Foot { s, d: off, .. } = a.path.frenet_dir(pos, st.s + adv);
        State { pos, yaw, s, off, ..next }
    }

    /// The lateral offset at which agent `i` clears an agent ahead that is easing aside for it
    /// (`away_from i`, already triggered), on the side that agent leaves free; `None` when there
    /// is none, or when passing would take more than `PASS_MAX_SHIFT` out of the lane.
    pub(crate) fn pass_offset(&self, i: usize, look: f64) -> Option<f64> {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let fwd = self.facts.dirs[i];
        let mut best: Option<f64> = None;
        for &j in &self.facts.easing {
            let (o, b) = (&self.cur[j], &self.actors[j]);
            // Easing for us: by its goal, or for our siren when it goes our way.
            let by_goal = matches!(b.lateral, Lat::Away { who, .. } if who == i);
            let by_siren = self.facts.siren_for[j].is_some_and(|y| y.to == i) && self.facts.dirs[j].dot(fwd) > 0.0;
            if j == i || !(by_goal || by_siren) {
                continue;
            }
            let ahead = (o.pos - st.pos).dot(fwd);
            // Until our rear has cleared its front.
            if ahead < -(a.hl + b.hl + 1.0) || ahead > look {
                continue;
            }
            let Foot { d: lj, beyond, dir: h, .. } = a.path.frenet(o.pos, st.s + ahead);
            if beyond > 0.5 {
                continue;
            }
            let rel = o.yaw - h;
            let ext_lat = b.hl * rel.sin().abs() + b.hw * rel.cos().abs();
            // It eases toward its right (negative offsets); pass on the side it leaves.
            let side = if lj > a.d0 + 0.05 { -1.0 } else { 1.0 };
            let mut d = lj + side * (ext_lat + a.hw + PASS_CLEARANCE);
            if by_siren {
                // Only one in our way asks us over, and never toward it (one in the next lane
                // moving off to its far side, or onto the shoulder, leaves us our lane).
                if lj - ext_lat > a.d0 + a.hw + 0.25 || lj + ext_lat < a.d0 - a.hw - 0.25 {
                    continue;
                }
                d = if side > 0.0 { d.max(a.d0) } else { d.min(a.d0) };
            }
            if (d - a.d0).abs() > PASS_MAX_SHIFT {
                continue;
            }
            best = Some(best.map_or(d, |b: f64| if side > 0.0 { b.max(d) } else { b.min(d) }));
        }
        best
    }
}
