//! The right-of-way rule, frame by frame: who holds short of a shared zone or a stop line for
//! whom, who holds for an emergency vehicle, and when a walker waits at the kerb.

use crate::rollout::agent::{Crossing, Drive, State, StopGoal};
use crate::rollout::agent::{Rank, ZoneRank};
use crate::rollout::frame::Sim;
use crate::rollout::kinematics::can_stop;
use crate::rollout::path::Foot;
use glam::DVec2;

/// How far ahead of an emergency vehicle the junction is cleared: this many seconds at its
/// speed, and at least `EMERGENCY_NEAR_M`.
pub(crate) const EMERGENCY_NEAR_S: f64 = 8.0;
pub(crate) const EMERGENCY_NEAR_M: f64 = 30.0;
/// Share of emergency braking a driver uses to hold for an emergency vehicle; closer than that
/// to the stop line, it goes on and clears the junction.
pub(crate) const YIELD_BRAKE: f64 = 0.75;

/// Time margin by which a vehicle with the right of way must have left a shared zone before
/// one giving way to it arrives there for that one not to hold, s.
pub(crate) const CLEAR_MARGIN_S: f64 = 1.0;

/// How far short of a vehicle's side a walker halted on the road stays to let it pass, m.
pub(crate) const STEP_CLEAR: f64 = 0.3;
/// Below this speed a walker on the road counts as halted, m/s.
const HALTED: f64 = 0.1;

impl Sim<'_, '_> {
    /// The right-of-way rule for agent `i`: how far its front may still go (to its stop line, or
    /// short of the zone it shares with another vehicle's junction path) while it gives way, or,
    /// for a walker about to cross, to the kerb while no vehicle could stop for it comfortably.
    pub(crate) fn right_of_way(&self, ranks: &mut [Option<Rank>], i: usize, t: f64) -> Option<f64> {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        if st.frozen || st.stopped || !matches!(a.drive, Drive::Mover) || self.striking(i, t) {
            return None;
        }
        // `yield never`: it goes regardless; a walker darts out without waiting for a gap.
        if !a.behaviour.yields {
            return None;
        }
        if let Some(kerb) = a.kerb {
            return self.kerb_hold(i, kerb, t);
        }
        let mut hold: Option<f64> = None;
        for c in &a.crossings {
            if let Some(rem) = self.gives_way(ranks, i, c, t) {
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
    pub(crate) fn zone_rank(&self, i: usize, enter: f64, meet: f64, leave: f64, t: f64) -> Rank {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        // One standing for good (`Actor::blocker`) takes no turn: it is driven around
        // (tests/rollout-cases/car-stalled-in-a-junction-cross-traffic-drives-around.scn).
        if st.s > leave || st.frozen || st.stopped || a.blocker {
            return None;
        }
        if let StopGoal::Front(sf) | StopGoal::Centre(sf) = a.stop
            && sf < enter + a.hl
            && a.active(st, t)
        {
            return None;
        }
        let to_zone = enter - 0.3 - st.s;
        // `stop_line ignore`: it holds short of the zone itself, past its line.
        let rem = match a.to_line(st) {
            Some(line) if line > -0.05 && a.behaviour.stop_line => line.min(to_zone),
            _ => to_zone,
        };
        // Short of where the paths come near (`meet`), in the stretch the other's sweep moved
        // the zone's start back over, one that can halt where it is holds there: a van placed
        // standing at its line beside a bus turning from the next lane, its nose in the reach
        // of the bus's swinging tail, counted as inside, set off and met the tail.
        let rem = if st.s >= enter && st.s < meet { rem.max(0.0) } else { rem };
        if st.s >= meet || (st.s >= enter && !can_stop(st.v, rem, a.lim.brake_max)) || self.striking(i, t) {
            return Some(ZoneRank { order: 0, eta: 0.0, rem });
        }
        // Giving way may take up to the emergency braking: within the limits, and it leaves the
        // fewest pairs where neither can stop (both then go, and only the safety net is left).
        if !can_stop(st.v, rem, a.lim.brake_max) {
            return Some(ZoneRank { order: 1, eta: 0.0, rem });
        }
        let dist = (enter - st.s).max(0.0);
        let acc = a.lim.accel;
        let eta = ((st.v * st.v + 2.0 * acc * dist).sqrt() - st.v) / acc;
        // Stopped, or holding for an emergency vehicle, for anything but this rule, or queued
        // behind another approaching the junction: not coming next.
        let not_next = (st.v < 0.3 && !st.give_way) || self.facts.yielding[i].0.is_some() || self.facts.behind[i];
        let rank = if not_next { 3 } else { 2 };
        Some(ZoneRank { order: rank, eta, rem: rem.max(0.0) })
    }

    /// `zone_rank(i, enter, meet, leave, t)`, taken once per frame for each of `i`'s crossings (the
    /// zone with these bounds): what it reads (`cur`, `behind`, the emergency holds) is settled
    /// before the right-of-way rule runs, and `ranks` is cleared each frame.
    pub(crate) fn rank(&self, ranks: &mut [Option<Rank>], i: usize, enter: f64, meet: f64, leave: f64, t: f64) -> Rank {
        // Keyed by all three bounds: two crossings may share `enter` and `leave` and differ in
        // `meet` (a car passing a standing one beside a turning bus met a stale rank).
        let same = |c: &Crossing| {
            c.enter.to_bits() == enter.to_bits()
                && c.meet.to_bits() == meet.to_bits()
                && c.leave.to_bits() == leave.to_bits()
        };
        let Some(k) = self.actors[i].crossings.iter().position(same) else {
            return self.zone_rank(i, enter, meet, leave, t);
        };
        let slot = self.cross_at[i] + k;
        if let Some(r) = ranks[slot] {
            debug_assert_eq!(r, self.zone_rank(i, enter, meet, leave, t), "stale zone rank for agent {i}");
            return r;
        }
        let r = self.zone_rank(i, enter, meet, leave, t);
        ranks[slot] = Some(r);
        r
    }

    /// `behind[i] = queued(i)` for every agent, in one pass over everyone and one over the agents
    /// instead of one over everyone per agent: someone else is queued ahead of `i` exactly when
    /// the least distance to the stop line among the others counted on its lane (the least, or
    /// the second least where the least is `i`'s own) is below `i`'s, the same floats compared.
    pub(crate) fn queue_heads(&mut self) {
        self.facts.lane_least.fill([(f64::INFINITY, usize::MAX); 2]);
        for (k, (b, o)) in self.actors.iter().zip(&self.cur).enumerate() {
            let Some(slot) = self.approach_slot[k] else { continue };
            let to_stop = b.junction.map_or(f64::NEG_INFINITY, |jb| jb.stop - (o.s + b.hl));
            let counted = !o.frozen && to_stop > -0.5;
            if !counted {
                continue;
            }
            let least = &mut self.facts.lane_least[slot];
            if to_stop < least[0].0 {
                least[1] = least[0];
                least[0] = (to_stop, k);
            } else if to_stop < least[1].0 {
                least[1] = (to_stop, k);
            }
        }
        for i in 0..self.actors.len() {
            let (a, st) = (&self.actors[i], &self.cur[i]);
            self.facts.behind[i] = match (self.approach_slot[i], a.junction) {
                (Some(slot), Some(j)) => {
                    let mine = j.stop - (st.s + a.hl);
                    let least = self.facts.lane_least[slot];
                    let other = if least[0].1 == i { least[1].0 } else { least[0].0 };
                    other < mine
                }
                _ => false,
            };
            debug_assert_eq!(self.facts.behind[i], self.queued(i), "queue_heads differs from queued for agent {i}");
        }
    }

    /// Whether another vehicle approaches agent `i`'s junction through the same lane ahead of it,
    /// its front not yet past its stop line.
    pub(crate) fn queued(&self, i: usize) -> bool {
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
    pub(crate) fn gives_way(&self, ranks: &mut [Option<Rank>], i: usize, c: &Crossing, t: f64) -> Option<f64> {
        // Between an emergency vehicle and one yielding to it, the yield (`yield_state`) rules;
        // but one already too far into the junction to hold when the emergency vehicle came near
        // is clearing it, and the emergency vehicle takes its turn with it by this rule.
        if c.emergency && !(self.actors[i].emergency && self.facts.yielding[c.other].1) {
            return None;
        }
        let ZoneRank { order: ri, eta: ei, rem } = self.rank(ranks, i, c.enter, c.meet, c.leave, t)?;
        let ZoneRank { order: rj, eta: ej, .. } =
            self.rank(ranks, c.other, c.other_enter, c.other_meet, c.other_leave, t)?;
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
        // Too near our line to hold there, but the other is inside, or as near: we still give way
        // short of the zone where we can. Let go because the bus beside it was already inside, a
        // motorcycle 6 m before its line at 8.8 m/s, turning right with it, met the bus's swinging
        // front (tests/rollout-cases/motorcycle-too-near-its-line-beside-a-bus-turning-right.scn).
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
    pub(crate) fn gone(&self, c: &Crossing, eta: f64) -> bool {
        let o = &self.cur[c.other];
        o.v > 0.5 && (c.other_leave - o.s) / o.v + CLEAR_MARGIN_S < eta
    }

    /// Whether agent `k` can still stop short of its zone from `enter` within its emergency
    /// braking: then how far its front may go, and its time to the zone at its present speed.
    pub(crate) fn short_of(&self, k: usize, enter: f64) -> Option<(f64, f64)> {
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
    pub(crate) fn committed_gives_way(&self, i: usize, c: &Crossing) -> Option<f64> {
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

    /// A walker about to cross (`Actor::kerb`) waits while a vehicle whose route crosses its walk
    /// could not stop comfortably before it: at the kerb, and, halted on the road by something
    /// else, short of each lane it has not yet stepped into (`STEP_CLEAR` from that vehicle's
    /// side), so it does not step out of its stand in front of a car that cannot stop
    /// (tests/rollout-cases/walker-halted-on-the-road-waits-for-a-sedan.scn). Walking on the
    /// road, or too close to the kerb to stop, it goes on (vehicles yield to a walker on the road).
    pub(crate) fn kerb_hold(&self, i: usize, kerb: f64, t: f64) -> Option<f64> {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        if !a.active(st, t) {
            return None;
        }
        let front = st.s + a.hl;
        let on_road = front > kerb;
        let firm = if st.give_way { a.lim.brake_max } else { a.lim.brake };
        let goes_on = if on_road { st.v > HALTED } else { !can_stop(st.v, kerb - front, firm) };
        if goes_on {
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
        let walk = a.goal_speed(st).max(0.5);
        let mut hold: Option<f64> = None;
        for (j, (b, o)) in self.actors.iter().zip(&self.cur).enumerate() {
            if j == i || !b.vehicle || !matches!(b.drive, Drive::Mover) || o.frozen {
                continue;
            }
            let fwd = DVec2::from_angle(o.yaw);
            let Foot { s: sj, d: lj, beyond, .. } = b.path.frenet(mid, o.s + (mid - o.pos).dot(fwd));
            let ahead = sj - o.s;
            if beyond > 0.5 || lj.abs() > half + b.hw + clear || ahead < -(b.hl + clear) {
                continue;
            }
            let room = ahead - b.hl - clear;
            let brake = if self.striking(j, t) { 0.0 } else { b.lim.brake };
            if room > 0.0 && o.v * o.v <= 2.0 * brake * room {
                continue;
            }
            // Where its path meets our walk (`s_x`), and where our front stops for it: at the
            // kerb, or on the road short of its side (past that, in its lane, we go on).
            let (x, _) = b.path.point(sj, 0.0);
            let Foot { s: s_x, .. } = a.path.frenet(x, s_mid);
            let side = s_x - b.hw;
            if on_road && front >= side {
                continue;
            }
            let rem = if on_road { side - STEP_CLEAR - front } else { kerb - front }.max(0.0);
            // It could not stop: wait only if it would pass while we are in its lane, with a
            // second's margin either side.
            let lane = b.hw + clear;
            let t_in = (s_x - lane - front).max(0.0) / walk;
            let t_out = (s_x + lane - (st.s - a.hl)).max(0.0) / walk;
            let (t_arr, t_gone) = if o.v < 0.1 {
                (if room <= 0.0 { 0.0 } else { f64::INFINITY }, f64::INFINITY)
            } else {
                (room.max(0.0) / o.v, (ahead + b.hl + clear) / o.v)
            };
            if t_arr < t_out + 1.0 && t_gone > t_in - 1.0 {
                hold = Some(hold.map_or(rem, |h: f64| h.min(rem)));
            }
        }
        hold
    }

    /// Where agent `j`, holding (at its line, short of a zone), will stand: as now, its front
    /// moved on to where it holds.
    pub(crate) fn held_at(&self, j: usize) -> Option<State> {
        let o = &self.cur[j];
        self.facts.yielding[j].0.map(|rem| State { pos: o.pos + self.facts.dirs[j] * rem, ..*o })
    }

    /// How agent `i` gives the junction to an emergency vehicle on a crossing path: short of the
    /// stop line, it holds there (the distance left to it); past it, or too close to stop firmly,
    /// it clears the junction without waiting for the emergency vehicle's predicted path (`true`).
    pub(crate) fn yield_state(&self, i: usize) -> (Option<f64>, bool) {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let Some(j) = a.junction else { return (None, false) };
        // It holds for an emergency vehicle at its stop line: one that does not give way, or
        // ignores its line, does not hold.
        if !a.behaviour.yields || !a.behaviour.stop_line || !a.yield_to.iter().any(|&e| self.emergency_near(e)) {
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
    pub(crate) fn emergency_near(&self, e: usize) -> bool {
        let (a, st) = (&self.actors[e], &self.cur[e]);
        let Some(j) = a.junction else { return false };
        if st.frozen || st.stopped || (a.goal_speed(st) < 0.5 && st.v < 0.5) {
            return false;
        }
        // One that means to stop short of the junction's far side does not need it cleared.
        if let StopGoal::Front(sf) | StopGoal::Centre(sf) = a.stop
            && sf < j.exit
        {
            return false;
        }
        let to_stop = j.stop - (st.s + a.hl);
        st.s - a.hl < j.exit && to_stop < EMERGENCY_NEAR_M.max(st.v.max(a.goal_speed(st)) * EMERGENCY_NEAR_S)
    }
}
