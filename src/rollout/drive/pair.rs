//! One other agent in the way of one agent's step: whether it is in the band our box sweeps (our
//! corners' swing in a bend, our junction sweep, a box turned across our path, one coming toward
//! us over our sweep), predicted to cut into it, or beside a lateral move; and what that asks of
//! our step (`Constraint`). The step folds every agent's constraint by `min`.

use crate::geom::Obb;
use crate::rollout::Limits;
use crate::rollout::agent::{Actor, State, StopGoal};
use crate::rollout::drive::WALK_CLEAR;
use crate::rollout::drive::follow::{idm_interaction, stop_law};
use crate::rollout::frame::Sim;
use crate::rollout::junction::bend::{SLICE_MARGIN, SWEEP_MARGIN};
use crate::rollout::junction::dry_run::swing;
use crate::rollout::kinematics::{band_front, band_meets};
use crate::rollout::path::Foot;
use glam::DVec2;

/// The gap a lateral move into another lane accepts between the one behind (at `back` m/s)
/// and the one ahead (at `front`), m: 2 m, 0.8 s of the follower's speed, and a term for the
/// speed it closes in at.
pub(crate) fn lane_change_gap(back: f64, front: f64) -> f64 {
    2.0 + 0.8 * back + (back - front).max(0.0).powi(2) / 6.0
}

/// Agent `i`'s step as the pair loop reads it: settled before the loop, read-only in it.
#[derive(Clone, Copy)]
pub(crate) struct Step<'s> {
    pub i: usize,
    pub a: &'s Actor,
    pub st: State,
    pub t: f64,
    pub lim: Limits,
    pub dt: f64,
    /// Its goal has started (`start after`).
    pub active: bool,
    pub v_des: f64,
    /// The lateral reference after this step, and the offset the lateral goal heads for.
    pub d_next: f64,
    pub goal_d: f64,
    /// A lateral move past half way: the gap acceptance no longer holds it.
    pub half_done: bool,
    /// The band the box occupies now (a steering vehicle lags its reference).
    pub cur_lo: f64,
    pub cur_hi: f64,
    /// How far its nose, turned off the path while it moves sideways, reaches out of that band.
    pub nose_lo: f64,
    pub nose_hi: f64,
    /// The band it sweeps this step, and the margin kept round its box.
    pub lo: f64,
    pub hi: f64,
    pub margin: f64,
    pub look: f64,
    /// How far on our run through the bend ahead is searched beside us.
    pub sweep_to: f64,
    /// The least this step can advance braking at the limit.
    pub shortest: f64,
    /// The agent it queues behind (`stop behind`).
    pub named: Option<usize>,
    /// Clearing a junction for an emergency vehicle.
    pub clearing: bool,
    /// Held back from passing an obstacle: how far short of one to wait (`Avoid::standoff`).
    pub standoff: f64,
}

/// Agent `j` as seen from our route this step.
#[derive(Clone, Copy)]
pub(crate) struct Other<'s> {
    pub j: usize,
    pub o: &'s State,
    pub b: &'s Actor,
    /// Its centre's arc length and offset on our route.
    pub sj: f64,
    pub lj: f64,
    /// Cosine and sine of its heading relative to our path's there.
    pub cr: f64,
    pub sr: f64,
    /// Its box's half extents along and across our path.
    pub ext_lon: f64,
    pub ext_lat: f64,
    /// The one we queue behind, while it is on our way.
    pub is_named: bool,
    /// How far its centre is ahead of ours along the route.
    pub ds: f64,
}

/// Whether another agent is in the band our box sweeps, and from where (`Sim::way`).
pub(crate) struct Way {
    pub in_cur: bool,
    /// Found by our junction sweep's slices.
    pub swept: bool,
    /// The room between our front and it, m.
    pub gap: f64,
    /// The band, widened by our corners' swing in a bend.
    pub band_lo: f64,
    pub band_hi: f64,
    /// How far our centre may go before our run through the bend meets it, standing.
    pub touch_rem: f64,
}

/// What one other agent asks of a step; every agent's are folded by `Constraint::and`, which
/// takes the least of each bound, so their order does not matter.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Constraint {
    /// Acceleration at most, m/s2.
    pub acc: f64,
    /// How far the centre may go this step at most, m.
    pub hard: f64,
    /// How far the centre may go before its run through the bend ahead meets a standing box, m.
    pub touch_rem: f64,
    /// The lateral move waits where it is.
    pub side_blocked: bool,
    /// A walker's sides to step away to (-1 right, +1 left, summed).
    pub aside: f64,
}

impl Constraint {
    pub const FREE: Constraint = Constraint {
        acc: f64::INFINITY,
        hard: f64::INFINITY,
        touch_rem: f64::INFINITY,
        side_blocked: false,
        aside: 0.0,
    };

    pub fn and(self, o: Constraint) -> Constraint {
        Constraint {
            acc: self.acc.min(o.acc),
            hard: self.hard.min(o.hard),
            touch_rem: self.touch_rem.min(o.touch_rem),
            side_blocked: self.side_blocked || o.side_blocked,
            aside: self.aside + o.aside,
        }
    }
}

impl Sim<'_, '_> {
    /// What agent `j`, its centre at `at` on our route (`Path::frenet_near`), asks of our step `s`.
    pub(crate) fn constraint(&self, s: &Step, j: usize, at: Foot<DVec2>) -> Constraint {
        self.constraint_of(s, j, &self.cur[j], self.facts.dirs[j], at)
    }

    /// What agent `j` asks of our step `s` in state `o` (its unit heading `dir`): as it is now
    /// (`constraint`), or where a wreck's slide will leave it (`Sim::wrecks_ahead`).
    pub(crate) fn constraint_of(&self, s: &Step, j: usize, o: &State, dir: DVec2, at: Foot<DVec2>) -> Constraint {
        let Foot { s: sj, d: lj, beyond, dir: th } = at;
        let Step { a, st, look, named, .. } = *s;
        let b = &self.actors[j];
        // cos and sin of the other's heading relative to the path's.
        let (cr, sr) = (dir.dot(th), th.perp_dot(dir));
        let ext_lon = b.hl * cr.abs() + b.hw * sr.abs();
        let ext_lat = b.hl * sr.abs() + b.hw * cr.abs();
        // The one we queue behind, while it is on our way: once a vehicle has turned off,
        // more than a lane from our path, or turned back toward us (a U-turn), there is no
        // queue to keep (its projection onto our route then says nothing of a gap; a car
        // queued behind a motorcycle's U-turn braked at -27 m/s2 for it coming back in the
        // next lane). A walker or an animal on the verge stays named.
        let is_named = named == Some(j) && (!b.vehicle || (lj.abs() - ext_lat < a.hw + 3.0 && cr > -0.5));
        if beyond > 0.5 && !is_named {
            return Constraint::FREE;
        }
        let ds = sj - st.s;
        let x = Other { j, o, b, sj, lj, cr, sr, ext_lon, ext_lat, is_named, ds };
        let mut c = Constraint::FREE;
        self.alongside(s, &x, &mut c);
        if ds <= 0.0 {
            c.touch_rem = self.tail_swing(s, &x);
            return c;
        }
        let gap = ds - a.hl - ext_lon;
        if gap > look && !is_named {
            return c;
        }
        let (v_lon, v_lat) = (o.v * cr, o.v * sr);
        let way = self.way(s, &x, gap, v_lon);
        self.respond(s, &x, &way, v_lon, v_lat).and(Constraint { touch_rem: way.touch_rem, ..c })
    }

    /// The lateral move's side of a pair: whether `x` beside us blocks the move (`side_blocked`),
    /// and the side a walker steps away to from one walking beside it (`aside`).
    fn alongside(&self, s: &Step, x: &Other, c: &mut Constraint) {
        let Step { a, st, active, v_des, d_next, goal_d, half_done, cur_lo, cur_hi, .. } = *s;
        let Other { o, b, lj, cr, ext_lon, ext_lat, ds, .. } = *x;
        if d_next != st.d && ds.abs() < a.hl + ext_lon + 0.5 {
            let (nlo, nhi) = (st.d.min(d_next) - a.hw - 0.1, st.d.max(d_next) + a.hw + 0.1);
            let (jlo, jhi) = (lj - ext_lat, lj + ext_lat);
            let now = jlo < cur_hi && jhi > cur_lo;
            if jlo < nhi && jhi > nlo && !now {
                c.side_blocked = true;
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
                if g < lane_change_gap(back, front) {
                    c.side_blocked = true;
                }
            }
        }
        // Also one about to walk: stopped by the overlap guard as it set off beside another, a
        // walker that stepped aside only once moving never moved again
        // (tests/rollout-cases/walkers-set-off-side-by-side.scn).
        if !a.vehicle && !b.vehicle && (st.v > 0.1 || (active && v_des > 0.1)) && ds.abs() < a.hl + ext_lon {
            let rel = lj - st.d;
            if rel.abs() - ext_lat - a.hw < WALK_CLEAR {
                c.aside -= rel.signum();
            }
        }
    }

    /// One level with or behind our centre: where our centre must stop short (`touch_rem`) so that
    /// our box on its run through the bend ahead stays clear of where it stands.
    fn tail_swing(&self, s: &Step, x: &Other) -> f64 {
        let Step { a, st, sweep_to, .. } = *s;
        let Other { j, o, b, ds, .. } = *x;
        let mut touch_rem = f64::INFINITY;
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
            // At the latest: where its braking limit halts it, past a goal it cannot stop short of
            // (a van at 9.8 m/s 6 m before its line,
            // tests/rollout-cases/bus-turning-beside-a-van-overrunning-its-line.scn).
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
            && self.sweep_laid(s, b)
            && let Some(bd) = &a.bend
            && let Some(at) = stands()
                .iter()
                .flatten()
                .filter_map(|q| bd.touches((a.hl, a.hw), &q.grown(SWEEP_MARGIN), st.s, sweep_to))
                .reduce(f64::min)
        {
            touch_rem = touch_rem.min(at - st.s - 0.2);
        }
        touch_rem
    }

    /// Whether `x`, `gap` ahead of our front and moving at `v_lon` along our path, is in the band
    /// our box sweeps (its corners' swing in a bend and our junction sweep included), and then
    /// from where.
    fn way(&self, s: &Step, x: &Other, gap: f64, v_lon: f64) -> Way {
        let Step { a, st, cur_lo, cur_hi, nose_lo, nose_hi, margin, .. } = *s;
        let Other { j, o, sj, lj, cr, ext_lat, .. } = *x;
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
            o.v < 0.5 || self.facts.yielding[j].0.is_some() || cr < -0.5 || (v_lon > 0.0 && v_lon < 0.5 * st.v);
        let (mut band_lo, mut band_hi) = (cur_lo - margin - nose_lo, cur_hi + margin + nose_hi);
        if a.vehicle && in_sweep && gap > 0.0 {
            let (k0, k1) = (a.path.curvature(sj), a.path.curvature(sj - a.hl));
            band_lo -= swing(a.hl, k0.max(k1).max(0.0));
            band_hi += swing(a.hl, (-k0).max(-k1).max(0.0));
        }
        let in_cur = lj - ext_lat < band_hi && lj + ext_lat > band_lo;
        let mut way = Way { in_cur, gap, swept: false, band_lo, band_hi, touch_rem: f64::INFINITY };
        self.sweep_hits(s, x, in_sweep, &mut way);
        self.turned_box(s, x, &mut way);
        self.bent_box(s, x, &mut way);
        self.bent_band(s, x, &mut way);
        self.oncoming_over_sweep(s, x, v_lon, &mut way);
        way
    }

    /// Whether our junction sweep, laid along our lane's centre line, is where we drive past `b`:
    /// not while we pass round it, off that line, as round a car stalled in the junction
    /// (tests/rollout-cases/car-stalled-in-a-junction-cross-traffic-drives-around.scn).
    fn sweep_laid(&self, s: &Step, b: &Actor) -> bool {
        !b.blocker || (s.st.d - s.a.d0).abs() < 0.3
    }

    /// Our junction sweep (the dry run's) reaching `x`: through its slices, or its exact boxes where
    /// the slices miss one standing.
    fn sweep_hits(&self, s: &Step, x: &Other, in_sweep: bool, way: &mut Way) {
        let Step { a, st, lim, .. } = *s;
        let Other { j, o, b, sj, ext_lon, ds, .. } = *x;
        // Our sweep through the junction (the dry run's, `Bend::slices`) where it lies on the road:
        // one it reaches is in our way from the first metre that reaches it; one holding at its
        // line, also where it will stand there (rolling up to it, it was found only once inside).
        // Laid out in the straight frame at the other's projection, a U-turn's loop reached over
        // cars holding well clear of it. Also one whose centre is ahead of ours but whose box the
        // straight frame puts beside us: in a turn our box heads elsewhere than the path at its
        // projection, and a car standing across an ambulance's wide U-turn lay straight ahead of
        // the box and 6 m beside the path (tests/rollout-cases/ambulance-u-turn-sedan-in-loop.scn).
        // The slices are then searched at least two box lengths on.
        let sweep_hi = (sj + ext_lon + a.hl + 2.0 * b.hl).max(st.s + 2.0 * (a.hl + b.hl) + 5.0);
        if !way.in_cur
            && self.sweep_laid(s, b)
            && a.vehicle
            && in_sweep
            && ds > 0.0
            && let Some(bd) = &a.bend
            && let Some(at) = {
                // One still moving, too close to stop for within our braking: we are committed
                // (as to a junction zone), and it sees our box. So is where one will stand
                // once it holds: a prediction, which it keeps short of us. A van braking to
                // hold short of a zone for an ambulance dropped below 0.5 m/s 1.2 s in and its
                // hold ahead was found 0.1 m from the front of a van committed to its right
                // turn, which stopped at -56 m/s2
                // (tests/rollout-cases/van-turning-right-meets-the-hold-of-one-giving-way.scn).
                let can_stop = |at: f64| st.v * st.v <= 2.0 * lim.brake_max * (at - st.s - a.hl);
                let meets = |q: &State| bd.meets(&b.obb(q).grown(SLICE_MARGIN), st.s, sweep_hi);
                let held = self.held_at(j).and_then(|q| meets(&q)).filter(|&at| can_stop(at));
                let now = meets(o).filter(|&at| o.v < 0.5 || can_stop(at));
                held.into_iter().chain(now).reduce(f64::min)
            }
        {
            way.in_cur = true;
            way.swept = true;
            way.gap = at - st.s - a.hl;
        }
        // Standing where the sweep's slices miss it: laid a metre each along the path, they lose
        // the corner of a nose swinging round a tight U-turn loop (a sedan's, over the front of a
        // bus at its stop line, tests/rollout-cases/u-turn-loop-over-a-bus-at-its-line.scn). The
        // run's own boxes are exact; met there, we go no further than the last pose clear of it, as
        // for our tail.
        if !way.in_cur
            && !way.swept
            && self.sweep_laid(s, b)
            && a.vehicle
            && o.v < 0.5
            && let Some(bd) = &a.bend
            && let Some(at) = bd.touches((a.hl, a.hw), &b.obb(o).grown(SLICE_MARGIN), st.s, sweep_hi)
        {
            way.touch_rem = way.touch_rem.min(at - st.s - 0.2);
        }
    }

    /// A box turned across our path: only its part inside our band counts, from its nearest point.
    fn turned_box(&self, s: &Step, x: &Other, way: &mut Way) {
        let Step { a, st, .. } = *s;
        let Other { o, b, lj, cr, sr, ext_lat, is_named, ds, .. } = *x;
        // A box turned across our path (a long vehicle turning beside us): its extents along
        // and across the path put corners where it has none. Only the part of it inside our
        // band counts, and only its nearest point there.
        // Within reach of the band: its frame is straight while our path may bend.
        let near_band = lj - ext_lat < way.band_hi + 1.5 && lj + ext_lat > way.band_lo - 1.5;
        if !way.swept && !is_named && sr.abs() > 0.05 && near_band && (way.in_cur || way.gap > 0.0) {
            if way.in_cur {
                match band_front(lj, cr, sr, b.hl, b.hw, way.band_lo, way.band_hi) {
                    Some(x) => way.gap = ds + x - a.hl,
                    None => way.in_cur = false,
                }
            }
            // That frame is straight, our path may bend: a long box's far end lies where the
            // path has turned under it (a standing ambulance's corner inside the bend of our
            // left turn), in the band though its frame puts it beside. A corner that projected
            // onto our path where it is lies in the band ahead of us counts too.
            if !way.in_cur {
                self.corner_in_band(s, x, way);
            }
            // That part alongside us, not ahead: the frame at its projection is turned by our
            // bend, which can put a corner of a box driving straight beside us into our band.
            // Measured across our path where we are, it must still reach into the band.
            if way.in_cur && way.gap <= 0.0 {
                let (p0, h0) = a.path.point(st.s, 0.0);
                let n0 = DVec2::from_angle(h0).perp();
                let (lo_c, hi_c) = b
                    .obb(o)
                    .corners()
                    .iter()
                    .map(|&q| n0.dot(q - p0))
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), d| (l.min(d), h.max(d)));
                way.in_cur = lo_c < way.band_hi && hi_c > way.band_lo;
            }
        }
    }

    /// A box lying along its lane on a bend: the straight frame at its foot puts all of it
    /// beside its lane's line, but its ends lie toward the bend's outside by hl^2 k / 2 (a bus
    /// standing pulled over on a curve of 60 m reaches 0.3 m over the line, and an ambulance
    /// passing toward it ran a corner into it:
    /// tests/rollout-cases/ambulance-passes-toward-a-bus-pulled-over-on-a-curve.scn). Beside the
    /// band by less than that swing, a corner found in the band ahead of us counts.
    fn bent_box(&self, s: &Step, x: &Other, way: &mut Way) {
        let Other { b, sj, lj, sr, ext_lat, is_named, .. } = *x;
        if way.in_cur || way.swept || is_named || way.gap <= 0.0 || sr.abs() > 0.05 {
            return;
        }
        let reach = swing(b.hl, s.a.path.curvature(sj).abs());
        if reach > 0.02 && lj - ext_lat < way.band_hi + reach && lj + ext_lat > way.band_lo - reach {
            self.corner_in_band(s, x, way);
        }
    }

    /// The nearest corner of `x`'s box that lies, projected onto our path where it is, in the
    /// band ahead of our front: the box is then in our way from there.
    fn corner_in_band(&self, s: &Step, x: &Other, way: &mut Way) {
        let Step { a, st, .. } = *s;
        let fwd = DVec2::from_angle(st.yaw);
        for q in x.b.obb(x.o).corners() {
            let Foot { s: sq, d: dq, beyond, .. } = a.path.frenet_dir(q, st.s + (q - st.pos).dot(fwd));
            let ahead = sq - st.s - a.hl;
            if beyond <= 0.0 && dq > way.band_lo && dq < way.band_hi && ahead > 0.0 {
                way.gap = if way.in_cur { way.gap.min(ahead) } else { ahead };
                way.in_cur = true;
            }
        }
    }

    /// Our band laid along the path itself where it bends before a turned box `x`: the straight
    /// frame at its projection misplaces it (a bus driving straight past our right turn lies in
    /// the band there, and clear of it on the road), so the band is laid a metre at a time, and
    /// only a box it meets counts, from where it first meets it.
    fn bent_band(&self, s: &Step, x: &Other, way: &mut Way) {
        let Step { a, st, cur_lo, cur_hi, .. } = *s;
        let Other { o, b, sj, lj, sr, ext_lon, ext_lat, is_named, .. } = *x;
        let bend_reach = || {
            let reach = (sj + ext_lon + a.hl + 1.0).min(a.path.length());
            a.path.straight_run(st.s).is_none_or(|ln| ln.hi < reach).then_some(reach)
        };
        if way.in_cur
            && !way.swept
            && !is_named
            && sr.abs() > 0.05
            && let Some(reach) = bend_reach()
        {
            match band_meets(a, st.s, reach, (way.band_lo, way.band_hi), &b.obb(o)) {
                Some(s_hit) => way.gap = s_hit - st.s,
                None => way.in_cur = false,
            }
        }
        // One standing beside the band where it projects, square to our path there, but
        // reaching over it where the path bends before it: a bus that overran its line
        // stands with its nose in the arc of a car turning left past it, and lay one lane
        // over on the street the car turns into (the car met the nose at 5.8 m/s).
        if !way.in_cur
            && !way.swept
            && !is_named
            && a.vehicle
            && o.v < 0.5
            && way.gap > 0.0
            && lj - ext_lat < way.band_hi + 2.0
            && lj + ext_lat > way.band_lo - 2.0
            && let Some(reach) = bend_reach()
            && let Some(s_hit) = band_meets(a, st.s, reach, (cur_lo, cur_hi), &b.obb(o))
        {
            way.in_cur = true;
            way.gap = s_hit - st.s;
        }
    }

    /// One driving toward us in its lane beside our path, over which our turn sweeps out.
    fn oncoming_over_sweep(&self, s: &Step, x: &Other, v_lon: f64, way: &mut Way) {
        let Step { a, st, lim, cur_lo, cur_hi, margin, .. } = *s;
        let Other { o, b, sj, lj, cr, ext_lon, ext_lat, is_named, ds, .. } = *x;
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
            && way.gap > 0.0
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
                way.in_cur = true;
                way.gap = way.gap.min(short(at));
            }
        }
    }

    /// How `x`, in our way now or predicted to cut into it (`way`), bounds our acceleration and
    /// how far our centre may go this step.
    fn respond(&self, s: &Step, x: &Other, way: &Way, v_lon: f64, v_lat: f64) -> Constraint {
        let Step { i, a, st, t, lim, dt, lo, hi, margin, shortest, clearing, .. } = *s;
        let Other { j, o, b, lj, ext_lat, is_named, .. } = *x;
        let (mut acc, mut hard) = (f64::INFINITY, f64::INFINITY);
        let in_now = way.in_cur || (way.gap > 0.0 && lj - ext_lat < hi && lj + ext_lat > lo);
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
            out / v_lat.abs().max(0.1) + 1.0 < way.gap.max(0.0) / st.v.max(1.0)
        };
        let gives_way = self.facts.yielding[j].0.is_some() || (clearing && (b.cleared_past(o) || crossed_first()));
        if !obstacle && a.vehicle && v_lat.abs() > 0.3 && !gives_way {
            // A walker or an animal heading for the road gets two more seconds of slack:
            // drivers brake for someone stepping off the kerb, not only for someone already
            // in their lane, and a walker's path is the least predictable.
            let slack = if b.vehicle { 1.0 } else { 3.0 };
            let horizon = (way.gap.max(0.0) / st.v.max(1.0)).min(4.0) + slack;
            let mut l2 = lj + v_lat * horizon;
            // Parallel to us and settling back into its lane, it stops there (`settle_reach`).
            if let Some(r) = self.settle_reach(j, a.path.point(x.sj, 0.0).1) {
                l2 = lj + (l2 - lj).clamp(-r, r);
            }
            obstacle = lj.min(l2) - ext_lat < hi && lj.max(l2) + ext_lat > lo;
        }
        if !obstacle {
            return Constraint::FREE;
        }
        // Waiting to pass an obstacle, far enough back to steer out round it from a standstill.
        let s0 = if is_named {
            2.0
        } else if b.blocker {
            lim.min_gap.max(s.standoff)
        } else {
            lim.min_gap
        };
        // A striker coming at us does not stop for us: it comes on to its target, where the
        // latch stops it. Braking for it where it is now, a motorcycle met a bus overtaking
        // into its lane at 18 m/s and stopped at 13 m/s2. The reach only slows us: where we
        // may still move (`hard`) is where it is.
        let reach = if v_lon < -0.5 && !a.in_conflict { self.strike_reach(j, t) } else { None };
        let acc_gap = reach.map_or(way.gap, |r| way.gap - r);
        acc = acc.min(idm_interaction(st.v, v_lon.max(0.0), acc_gap, s0, lim));
        if v_lon < 0.5 {
            acc = acc.min(stop_law(st.v, acc_gap - s0, lim, dt));
        }
        // Only into the band's margin (a standing car's corner at arm's length from our
        // side, the band's edge shifting by millimetres as we steer): brake for it, but no
        // stop dead, which only a box in our way itself calls for.
        let margin_only =
            !way.swept && !is_named && (lj - ext_lat >= way.band_hi - margin || lj + ext_lat <= way.band_lo + margin);
        if (way.in_cur && !margin_only) || is_named {
            let lead_move = (v_lon * dt - 0.5 * lim.brake_max * dt * dt).max(0.0);
            // A walker stops within its own braking: one stepping into another's way just
            // ahead (two crossing side by side on converging lines, a hand's breadth apart)
            // slows and lets the other draw away; it is not stopped dead. Nor is anyone for
            // one alongside (no gap ahead to keep: stopping dead opens none, a car passing
            // close by in the lane we edge toward goes by all the same).
            // The 0.2 m kept short of it is a margin, not a wall: where it lets the step stay
            // within the braking limit, the step may use it, short of touching (a box
            // swinging into the band left 0.1 m less than the limit's shortest step).
            let keep = way.gap - 0.2 + lead_move;
            hard = hard.min(if a.vehicle && way.gap > 0.0 {
                keep.max(shortest.min(way.gap + lead_move - 0.02))
            } else {
                keep.max(shortest)
            });
            acc = acc.min(self.safe_acc(i, j, acc_gap, v_lon, t));
        } else if way.gap > 0.0 && !a.in_conflict && self.crash_partner(j, t).is_some() {
            // One about to crash, only predicted into our lane ahead, stops dead where it
            // meets its partner: followed as a lead at its speed, it leaves us no room. On
            // its own this did not mend the bus that cut into a car's lane 4.7 m ahead and
            // stood there (-19 m/s2): the striker's contact pose below did.
            acc = acc.min(self.safe_acc(i, j, acc_gap, v_lon, t));
        }
        Constraint { acc, hard, ..Constraint::FREE }
    }
}
