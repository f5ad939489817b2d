//! A `ttc` near miss across the passed agent's path (a crossing at a junction, a car closing on
//! a walker crossing in front of it): where on its own route the passer must be at the pass,
//! and how fast, for the least time to collision of the two boxes to be the stated one at the
//! stated time, the passer braking as hard as it can from the pass (`Sim::brake_across`) and
//! stopping short (tests/near-miss/crossing-at-a-junction-within-a-second.scn).

use crate::geom::{Obb, wrap_angle};
use crate::rollout::Tracks;
use crate::rollout::agent::{Actor, Conf, Drive, Near, State, initial};
use crate::rollout::frame::Sim;
use crate::rollout::staging::near::box_ttc;
use crate::rollout::staging::plan::{AVOID_S, Plan, STRIKE_ACCEL, TAUS, WINDOW_S, requested_time};
use glam::DVec2;

/// How long the braking course after the pass is followed, s: a passer at the speeds a `ttc`
/// near miss allows has stopped by then, and the passed agent has gone by.
const COURSE_S: f64 = 4.0;
/// How near the braking course may bring the two boxes, m: the rollout's passer arrives at its
/// pass some centimetres off the plan, and stops as far off where it was planned to.
const CLEAR_M: f64 = 0.3;
/// Spacing of the places along its route where the passer's pass is tried, m.
const SCAN_M: f64 = 0.25;
/// How far the predicted least time to collision of a plan may be from the stated one, s.
const FIT_S: f64 = 0.03;
/// Braking from the pass lowers the least time to collision below the one at the pass by less
/// than this, s, at the speeds a `ttc` near miss allows: passes further off are not followed.
const BRAKING_DIP_S: f64 = 1.5;

/// The passer, box `a` at speed `v` along its heading, braking at `brake` from now while box
/// `b` moves on at `vb`: the least time to collision on the way and how long from now it comes,
/// s, or the first below `floor`; `None` where the two come within `CLEAR_M`.
fn braking_least(a: &Obb, v: f64, brake: f64, (b, vb): (&Obb, DVec2), dt: f64, floor: f64) -> Option<(f64, f64)> {
    let dir = DVec2::from_angle(a.yaw);
    let (mut least, mut when) = (f64::INFINITY, 0.0);
    let (mut x, mut u) = (0.0, v);
    for j in 0..=(COURSE_S / dt).ceil() as usize {
        let t = j as f64 * dt;
        let (aj, bj) = (Obb { center: a.center + dir * x, ..*a }, Obb { center: b.center + vb * t, ..*b });
        if aj.grown(CLEAR_M).overlaps(&bj) {
            return None;
        }
        let ttc = box_ttc(&aj, dir * u, &bj, vb);
        if ttc < least {
            (least, when) = (ttc, t);
        }
        if least < floor {
            break;
        }
        let u1 = (u - brake * dt).max(0.0);
        x += 0.5 * (u + u1) * dt;
        u = u1;
    }
    Some((least, when))
}

/// The plan of a crossing `ttc` near miss from pass 1's tracks: of departure and pass frames
/// within `WINDOW_S` of the requested time, the one of least cost whose pass puts the passer on
/// its own route at the place and speed where braking from there brings the two to `ttc` and
/// no closer, that least coming at the requested time.
pub(crate) fn choose(
    k: &Conf,
    actors: &[Actor],
    p1: &Tracks,
    (dt, duration): (f64, f64),
    avoid: &[f64],
) -> Option<Plan> {
    let Some(Near::Across(ttc)) = k.near else { return None };
    let (af, st) = (&actors[k.af], &actors[k.st]);
    // A walker's intercept does not hold its course (it turned round on the kerb): the vehicle
    // closing on it is the passer (E0871).
    if !matches!(af.drive, Drive::Mover) || !af.vehicle || p1.frames < 4 {
        return None;
    }
    let pa = &p1.poses[k.af];
    // The passer's place along its route at each frame of pass 1.
    let mut s_at = Vec::with_capacity(p1.frames);
    let mut s = initial(af).s;
    for f in 0..p1.frames {
        if f > 0 {
            s += DVec2::new(pa[f].x - pa[f - 1].x, pa[f].y - pa[f - 1].y).length();
        }
        s_at.push(s);
    }
    let t_req = requested_time(&k.c, dt, p1.frames, duration);
    let c = Candidates { k, af, st, p1, s_at, ttc, t_req, dt };
    let lo = ((t_req - WINDOW_S) / dt).round().max(2.0) as usize;
    let hi = (((t_req + WINDOW_S) / dt).round() as usize).min(p1.frames - 1);
    let mut best: Option<(f64, Plan)> = None;
    for fi in lo..=hi {
        let t_imp = fi as f64 * dt;
        if avoid.iter().any(|&t| (t_imp - t).abs() <= AVOID_S) {
            continue;
        }
        for tau in TAUS {
            let fd = ((t_imp - tau) / dt).round().max(0.0) as usize;
            if fd + 3 > fi {
                continue;
            }
            if let Some((cost, plan)) = c.cost(fi, fd)
                && best.as_ref().is_none_or(|(b, _)| cost < *b)
            {
                best = Some((cost, plan));
            }
        }
    }
    best.map(|(_, p)| p)
}

/// What the candidate plans of one crossing near miss share: the pair, pass 1, the passer's
/// place along its route at each frame of it, the stated time to collision and the requested
/// time.
struct Candidates<'a> {
    k: &'a Conf,
    af: &'a Actor,
    st: &'a Actor,
    p1: &'a Tracks,
    s_at: Vec<f64>,
    ttc: f64,
    t_req: f64,
    dt: f64,
}

impl Candidates<'_> {
    /// The cost and plan of departing at frame `fd` for a pass at frame `fi`, if some place
    /// along the route within reach fits.
    fn cost(&self, fi: usize, fd: usize) -> Option<(f64, Plan)> {
        let (k, af, p1, ttc, dt) = (self.k, self.af, self.p1, self.ttc, self.dt);
        let (t_imp, tau) = (fi as f64 * dt, (fi - fd) as f64 * dt);
        let b = p1.poses[k.st][fi];
        let bdir = DVec2::from_angle(b.yaw);
        let bbox = Obb { center: DVec2::new(b.x, b.y), yaw: b.yaw, length: 2.0 * self.st.hl, width: 2.0 * self.st.hw };
        let vb = bdir * p1.speeds[k.st][fi];
        let (v, s_d, lim) = (p1.speeds[k.af][fd], self.s_at[fd], af.lim);
        // The pass at arc length `s`: the box there, its speed on arrival, and the least time
        // to collision braking from there with when it comes.
        let pass = |s: f64| {
            let v_end = 2.0 * (s - s_d) / tau - v;
            let (p, h) = af.path.at(s);
            let a = Obb { center: p, yaw: h, length: 2.0 * af.hl, width: 2.0 * af.hw };
            if v_end < 1.0 {
                return (a, v_end, None);
            }
            // The least on the braking course is at most the one at the pass: where that is
            // already below, or far above, the course is not followed.
            let now = box_ttc(&a, DVec2::from_angle(h) * v_end, &bbox, vb);
            let least = if now < ttc - FIT_S || now > ttc + BRAKING_DIP_S {
                Some((now, 0.0))
            } else {
                braking_least(&a, v_end, lim.brake_max, (&bbox, vb), dt, ttc - FIT_S)
            };
            (a, v_end, least)
        };
        let (a, v_end, when) = fit(pass, s_d, (v * tau + STRIKE_ACCEL * lim.accel * tau * tau / 2.0, ttc))?;
        let acc = (v_end - v) / tau;
        let mut cost = 3.0 * (t_imp + when - self.t_req).abs() + acc.abs() / lim.accel;
        if acc > STRIKE_ACCEL * lim.accel || acc < -lim.brake_max {
            cost += 20.0 + acc.abs();
        }
        let plan = Plan {
            struck: k.st,
            rel_pos: (a.center - bbox.center).rotate(DVec2::new(bdir.x, -bdir.y)),
            rel_yaw: wrap_angle(a.yaw - b.yaw),
            t_depart: fd as f64 * dt,
            t_impact: t_imp,
            frame: fi,
            delta: 0.0,
        };
        Some((cost, plan))
    }
}

/// Along the passer's route from `s_d` to `reach` ahead, the pass (`pass(s)`: box, speed, least
/// time to collision and when) whose least time to collision is `ttc` within `FIT_S`: each
/// place `SCAN_M` apart, then between two either side of `ttc` the one interpolated.
fn fit(
    pass: impl Fn(f64) -> (Obb, f64, Option<(f64, f64)>),
    s_d: f64,
    (reach, ttc): (f64, f64),
) -> Option<(Obb, f64, f64)> {
    let mut best: Option<(f64, (Obb, f64, f64))> = None;
    let mut keep = |(a, v, least): (Obb, f64, Option<(f64, f64)>)| {
        if let Some((m, when)) = least {
            let off = (m - ttc).abs();
            if off <= FIT_S && best.as_ref().is_none_or(|(o, _)| off < *o) {
                best = Some((off, (a, v, when)));
            }
        }
        least.map(|l| l.0)
    };
    let mut prev: Option<(f64, f64)> = None;
    let n = (reach / SCAN_M).floor() as usize;
    for j in 1..=n {
        let s = s_d + j as f64 * SCAN_M;
        let m = keep(pass(s));
        if let (Some((s0, m0)), Some(m1)) = (prev, m)
            && (m0 - ttc) * (m1 - ttc) < 0.0
            && m0.is_finite()
            && m1.is_finite()
        {
            keep(pass(s0 + (ttc - m0) / (m1 - m0) * (s - s0)));
        }
        prev = m.map(|m| (s, m));
    }
    best.map(|b| b.1)
}

impl Sim<'_, '_> {
    /// After the pass of near miss `k` across a path, whether its passer has come to rest.
    pub(crate) fn note_halt(&mut self, k: usize) {
        if matches!(self.confs[k].near, Some(Near::Across(_))) && self.next[self.confs[k].af].v <= 0.0 {
            self.halted[k] = true;
        }
    }

    /// Agent `i`'s step `d` by the rules, unless it is the passer of a crossing near miss past
    /// its pass: then it brakes as hard as it can along the same way till it comes to rest (as
    /// `braking_least` predicts), and after that whenever it would close on the passed agent
    /// at their speeds now. Its rules do not see the passed agent (`Sim::exempt`).
    pub(crate) fn brake_across(&self, i: usize, d: State) -> State {
        let Some(k) = self.striker[i] else { return d };
        let conf = &self.confs[k];
        if !matches!(conf.near, Some(Near::Across(_))) || !self.latched[k] {
            return d;
        }
        let (a, b) = (&self.actors[i], &self.actors[conf.st]);
        let (sa, sb) = (&self.cur[i], &self.cur[conf.st]);
        let (va, vb) = (DVec2::from_angle(sa.yaw) * d.v, DVec2::from_angle(sb.yaw) * sb.v);
        if self.halted[k] && !box_ttc(&a.obb(sa), va, &b.obb(sb), vb).is_finite() {
            return d;
        }
        let v = (sa.v - a.lim.brake_max * self.dt).max(0.0);
        if d.v <= v {
            return d;
        }
        // The same way as the rules' step, shortened to the distance braking covers.
        let moved = 0.5 * (sa.v + d.v);
        let f = if moved > 1e-9 { 0.5 * (sa.v + v) / moved } else { 0.0 };
        State {
            pos: sa.pos + (d.pos - sa.pos) * f,
            yaw: sa.yaw + wrap_angle(d.yaw - sa.yaw) * f,
            s: sa.s + (d.s - sa.s) * f,
            v,
            ..d
        }
    }
}
