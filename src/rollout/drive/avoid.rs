//! Passing what stands in the lane for good (`Actor::blocker`: a wreck, a double-parked or
//! stalled car, a cone) or moves on slowly in it (`overtake`: a cyclist): a vehicle nudges over
//! within its lane, or moves into the next lane or onto the shoulder once the oncoming traffic
//! there leaves it time, and stops behind it only where the paving leaves no room
//! (`Sim::avoid`).

use crate::rollout::agent::Blocking;
use crate::rollout::drive::overtake::{MOVER_CLEARANCE, pass_time};
use crate::rollout::drive::pair::lane_change_gap;
use crate::rollout::drive::{PASS_CLEARANCE, PASS_LAT_RATE};
use crate::rollout::frame::Sim;
use crate::rollout::junction::dry_run::swing;
use crate::rollout::kinematics::slip_tan;
use crate::rollout::path::Foot;
use glam::DVec2;

/// How far the paving reaches either side of the lane's centre line where the paving round the
/// obstacle is unknown (in a junction: at least the next lane), m.
const OPEN_SHIFT: f64 = 5.0;
/// The margin kept round our box in the band the obstacle must leave (`drive`'s), m.
const BAND_MARGIN: f64 = 0.25;
/// Clearance kept from the paving's edge, m.
const EDGE_CLEAR: f64 = 0.1;
/// Time an oncoming vehicle must still be away from the end of the pass when we would be past
/// it, s.
const ONCOMING_GAP_S: f64 = 3.0;
/// How far beyond the end of what a pass clears a slow mover in its band is taken into the same
/// pass, m.
const CHAIN_M: f64 = 12.0;
/// Distance beyond the move's own length at which a pass sets out, m.
const SET_OUT_M: f64 = 5.0;
/// How far behind us a vehicle in the lane a pass moves into is looked at, m: beyond the gap
/// any speed on a road asks (`Sim::beside_clear`).
const BESIDE_BEHIND_M: f64 = 120.0;

impl Blocking {
    /// Whether it reaches into the offsets `lo..hi` of our route.
    fn meets(&self, (lo, hi): (f64, f64)) -> bool {
        self.lj - self.ext_lat < hi && self.lj + self.ext_lat > lo
    }
}

/// What `Sim::avoid` decides for one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Avoid {
    /// The offset the pass heads for, once it may go.
    pub target: Option<f64>,
    /// Held back by oncoming traffic: how far short of the obstacle to wait, so that the box
    /// can still steer out round it from a standstill, m (0 where there is no room at all).
    pub standoff: f64,
}

impl Sim<'_, '_> {
    /// How vehicle `i` gets past whatever stands for good in the band it drives, within `look`
    /// ahead: `None` where nothing does.
    pub(crate) fn avoid(&self, i: usize, look: f64, f: usize, seen: &mut Vec<Blocking>) -> Option<Avoid> {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        if !a.vehicle || a.in_conflict || a.blocker || (self.facts.blockers.is_empty() && self.facts.slow.is_empty()) {
            return None;
        }
        self.blocking(i, look, f, seen);
        self.slow_ahead(i, look, seen);
        let m = BAND_MARGIN;
        let here = (a.d0 - a.hw - m, a.d0 + a.hw + m);
        if !seen.iter().any(|b| b.meets(here)) {
            return None;
        }
        // Left first: on a tie, pass on the overtaking side.
        let pick = [1.0, -1.0]
            .into_iter()
            .filter_map(|side| self.pass_side(i, side, seen))
            .reduce(|p, q| if (q.0 - a.d0).abs() < (p.0 - a.d0).abs() - 1e-9 { q } else { p });
        let Some((target, need, far, near, v_obs)) = pick else {
            return Some(Avoid { target: None, standoff: 0.0 });
        };
        // Steering out from a standstill takes more than the slip angle's run (the heading has
        // to build up first).
        let standoff = 1.5 * need / slip_tan(a) + 2.0;
        // Set out so as to be over before car-following toward it slows us (the reference moves
        // over at `PASS_LAT_RATE`), not a long way back in the oncoming lane.
        // Closing on a slow mover, at the speed we close in.
        let set_out = (st.v - v_obs).max(0.0) * (target - st.d).abs() / PASS_LAT_RATE + standoff + SET_OUT_M;
        if near - (st.s + a.hl) > set_out {
            return Some(Avoid { target: None, standoff: 0.0 });
        }
        // Within our lane, or with the body already over the line: go. Short of the line a pass
        // that has set out still turns back for oncoming traffic.
        let go = match self.over_the_line(i, target) {
            None => true,
            Some((band, over)) => over || (self.oncoming_clear(i, band, far, v_obs) && self.beside_clear(i, band)),
        };
        Some(Avoid { target: go.then_some(target), standoff })
    }

    /// Where a pass to offset `tg` takes vehicle `i`'s box (and the band margin) over its lane's
    /// line: the offsets beyond the line it moves into, and whether its body is over the line
    /// already; `None` where the pass stays within the lane.
    fn over_the_line(&self, i: usize, tg: f64) -> Option<((f64, f64), bool)> {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let m = BAND_MARGIN;
        let left = (tg - a.d0).signum() > 0.0;
        let (lo, hi) = if left { (a.d0 + a.lane_hw, tg + a.hw + m) } else { (tg - a.hw - m, a.d0 - a.lane_hw) };
        let over = if left { st.off + a.hw > a.d0 + a.lane_hw } else { st.off - a.hw < a.d0 - a.lane_hw };
        (lo < hi).then_some(((lo, hi), over))
    }

    /// Every obstacle within `look` ahead of vehicle `i` (or beside it, till its rear is a metre
    /// past), projected onto its route; an open door is one of its own (frame `f`'s angle).
    fn blocking(&self, i: usize, look: f64, f: usize, seen: &mut Vec<Blocking>) {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let fwd = self.facts.dirs[i];
        seen.clear();
        for &j in &self.facts.blockers {
            let (o, b) = (&self.cur[j], &self.actors[j]);
            let dp = o.pos - st.pos;
            let ahead = dp.dot(fwd);
            if j == i
                || ahead < -(a.hl + b.radius + 1.0)
                || ahead > look + a.hl + b.radius
                || fwd.perp_dot(dp).abs() > 2.0 * OPEN_SHIFT + a.hw + b.radius
                || self.exempt(i, j)
            {
                continue;
            }
            let (Foot { s: sj, d: lj, beyond, dir: th }, ext_lon, ext_lat) = self.on_route(i, j, ahead);
            if beyond > 0.5 || sj + ext_lon < st.s - a.hl - 1.0 {
                continue;
            }
            // The paving round it in our offsets: its lane runs our way or the other.
            let (lo, hi) = match b.room {
                Some(r) if r.dir.dot(th) > 0.7 => (lj - r.off - r.right, lj - r.off + r.left),
                Some(r) if r.dir.dot(th) < -0.7 => (lj + r.off - r.left, lj + r.off + r.right),
                _ => (f64::NEG_INFINITY, f64::INFINITY),
            };
            seen.push(Blocking { sj, lj, ext_lon, ext_lat, lo, hi, v: 0.0 });
            if !b.doors.is_empty() {
                self.open_doors(i, j, f, (lo, hi), seen);
            }
        }
    }

    /// Agent `j` on vehicle `i`'s route, `ahead` m along it: the foot of its centre, and its box's
    /// half extents along and across the route.
    pub(crate) fn on_route(&self, i: usize, j: usize, ahead: f64) -> (Foot<DVec2>, f64, f64) {
        let (a, st, b) = (&self.actors[i], &self.cur[i], &self.actors[j]);
        let foot = a.path.frenet_dir(self.cur[j].pos, st.s + ahead);
        let th = foot.dir;
        let (cr, sr) = (self.facts.dirs[j].dot(th), th.perp_dot(self.facts.dirs[j]));
        (foot, b.hl * cr.abs() + b.hw * sr.abs(), b.hl * sr.abs() + b.hw * cr.abs())
    }

    /// Passing on `side` (+1 left, -1 right): the offset clear of every obstacle in the band
    /// swept on the way there, how far our box must move before the nearest leaves its band,
    /// where the first of them begins and the last ends along our route, and the fastest one's
    /// speed; `None` where that leaves the paving.
    fn pass_side(&self, i: usize, side: f64, seen: &[Blocking]) -> Option<(f64, f64, f64, f64, f64)> {
        let a = &self.actors[i];
        let m = BAND_MARGIN;
        let band =
            |tg: f64| if side > 0.0 { (a.d0 - a.hw - m, tg + a.hw + m) } else { (tg - a.hw - m, a.d0 + a.hw + m) };
        let mut target = a.d0;
        // What the pass takes in: what stands in the band it sweeps, and a slow mover there only
        // within `CHAIN_M` of what it clears already, from the nearest in our lane on; one
        // farther on is followed, not passed in the same move (a car passing a slow car
        // took in a slow one 30 m on in the next lane, found that pass off the paving and
        // swung to the other side, through the one it was passing:
        // `straight_road_regressions`, tests/rollout_properties.rs).
        let mut reach = seen.iter().filter(|b| b.meets(band(a.d0))).map(|b| b.sj - b.ext_lon).fold(f64::MAX, f64::min);
        let taken = |b: &Blocking, reach: f64, target: f64| {
            b.meets(band(target)) && (b.v <= 0.0 || b.sj - b.ext_lon <= reach + CHAIN_M)
        };
        // Each obstacle cleared may put the next one (a taper's cones) in the band: a few
        // rounds settle it.
        for _ in 0..6 {
            let (mut next, mut far) = (target, reach);
            for b in seen.iter().filter(|b| taken(b, reach, target)) {
                let d = b.lj + side * (b.ext_lat + a.hw + if b.v > 0.0 { MOVER_CLEARANCE } else { PASS_CLEARANCE });
                next = if side > 0.0 { next.max(d) } else { next.min(d) };
                far = far.max(b.sj + b.ext_lon);
            }
            reach = far;
            if next == target {
                break;
            }
            target = next;
        }
        let within = seen.iter().filter(|b| taken(b, reach, target));
        let (lo, hi) =
            within.clone().fold((a.d0 - OPEN_SHIFT, a.d0 + OPEN_SHIFT), |(l, h), b| (l.max(b.lo), h.min(b.hi)));
        if target - a.hw < lo + EDGE_CLEAR || target + a.hw > hi - EDGE_CLEAR {
            return None;
        }
        let need = within.clone().map(|b| side * (b.lj - a.d0) + b.ext_lat + a.hw + m).fold(0.0, f64::max);
        let far = within.clone().map(|b| b.sj + b.ext_lon).fold(f64::NEG_INFINITY, f64::max);
        let near = within.clone().map(|b| b.sj - b.ext_lon).fold(f64::INFINITY, f64::min);
        let v_obs = within.map(|b| b.v).fold(0.0, f64::max);
        Some((target, need, far, near, v_obs))
    }

    /// A pass's target offset `tg` for vehicle `i`, kept to its own lane while the band it would
    /// move into over the line is not clear beside it (`beside_clear`); with the body already
    /// over the line it goes on (whoever comes up behind in that lane follows it), as `avoid`.
    pub(crate) fn within_lane_while_beside(&self, i: usize, tg: f64) -> f64 {
        match self.over_the_line(i, tg) {
            Some((band, over)) if !over && !self.beside_clear(i, band) => {
                let a = &self.actors[i];
                let edge = (a.lane_hw - a.hw - BAND_MARGIN).max(0.0);
                tg.clamp(a.d0 - edge, a.d0 + edge)
            }
            _ => tg,
        }
    }

    /// A pass's offset `tg` for vehicle `i` (or its way back to its lane) short of every vehicle
    /// level with it on the side it moves to: the move never closes on one to under
    /// `PASS_CLEARANCE`, and one already closer holds its offset. A pass that lost its side
    /// beside the slow car it was passing (one farther on took that lane) swung to the car's
    /// other side, through it (`straight_road_regressions`, tests/rollout_properties.rs).
    pub(crate) fn clear_of_beside(&self, i: usize, tg: f64) -> f64 {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let fwd = self.facts.dirs[i];
        let side = tg - st.d;
        if side == 0.0 {
            return tg;
        }
        let mut tg = tg;
        for (k, n) in self.facts.near.iter().enumerate() {
            let ahead = (n.pos - st.pos).dot(fwd);
            if k == i || !self.actors[k].vehicle || ahead.abs() > a.hl + n.radius + 1.0 {
                continue;
            }
            let (Foot { s: sk, d: lk, beyond, .. }, ext_lon, ext_lat) = self.on_route(i, k, ahead);
            if beyond > 0.5 || (sk - st.s).abs() > a.hl + ext_lon + 0.5 || side * (lk - st.d) <= 0.0 {
                continue;
            }
            let limit = lk - side.signum() * (ext_lat + a.hw + PASS_CLEARANCE);
            tg = if side > 0.0 { tg.min(limit.max(st.d)) } else { tg.max(limit.min(st.d)) };
        }
        tg
    }

    /// Whether no vehicle going our way in the offsets `band` of vehicle `i`'s route (the ends of
    /// its box swinging out in a bend included) is beside us, or behind us nearer than a lane
    /// change's gap acceptance asks (`Sim::alongside`): a pass over the line moves into its
    /// lane. One ahead of our front is followed once we are over. An ambulance nudging past a
    /// stopped motorcycle on a curve put its front corner on the tail of a bus beside it in
    /// the next lane (tests/rollout-cases/ambulance-passes-beside-a-bus-on-a-curve.scn).
    fn beside_clear(&self, i: usize, band: (f64, f64)) -> bool {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let fwd = self.facts.dirs[i];
        self.facts.near.iter().enumerate().all(|(k, n)| {
            if k == i || !self.actors[k].vehicle || self.actors[k].blocker || n.dir.dot(fwd) < 0.5 {
                return true;
            }
            let ahead = (n.pos - st.pos).dot(fwd);
            // Its rear clear ahead of our front, or farther behind than any gap asked below.
            if ahead - n.hl > a.hl + 1.0 || ahead + n.hl < -a.hl - BESIDE_BEHIND_M {
                return true;
            }
            let Foot { s: sk, d: lk, beyond, .. } = a.path.frenet(n.pos, st.s + ahead);
            let out = swing(n.hl, a.path.curvature(sk).abs());
            if beyond > 0.5 || lk + n.hw + out < band.0 || lk - n.hw - out > band.1 {
                return true;
            }
            (st.s - a.hl) - (sk + n.hl) >= lane_change_gap(n.v, st.v)
        })
    }

    /// Whether no vehicle coming toward vehicle `i` in the offsets `band` of its route would
    /// reach the end of its pass (`far`, arc length, moving on at `v_obs`) before it is past,
    /// with `ONCOMING_GAP_S` to spare, accelerating toward its goal speed.
    fn oncoming_clear(&self, i: usize, band: (f64, f64), far: f64, v_obs: f64) -> bool {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let fwd = self.facts.dirs[i];
        let dist = far + a.hl + 1.0 - st.s;
        let (v, acc, top) = (st.v, a.lim.accel, a.v_goal.max(1.0));
        let t_us = if v_obs > 0.0 {
            pass_time(v, acc, top, dist, v_obs)
        } else if v >= top {
            dist / v
        } else {
            let (t1, d1) = ((top - v) / acc, (top * top - v * v) / (2.0 * acc));
            if d1 >= dist { ((v * v + 2.0 * acc * dist).sqrt() - v) / acc } else { t1 + (dist - d1) / top }
        };
        // A moving obstacle carries the end of the pass on with it.
        let far = far + v_obs * t_us;
        self.facts.near.iter().enumerate().all(|(k, n)| {
            let dp = n.pos - st.pos;
            let ahead = dp.dot(fwd);
            if k == i || !self.actors[k].vehicle || n.dir.dot(fwd) > -0.5 || ahead < 0.0 || self.actors[k].blocker {
                return true;
            }
            let Foot { s: sk, d: lk, beyond, .. } = a.path.frenet(n.pos, st.s + ahead);
            if beyond > 0.5 || lk + n.hw < band.0 || lk - n.hw > band.1 {
                return true;
            }
            let front = sk - n.hl - far;
            front > 2.0 && front / n.v.max(0.1) > t_us + ONCOMING_GAP_S
        })
    }
}
