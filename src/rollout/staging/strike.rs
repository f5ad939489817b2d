//! The striker of a staged conflict: its intercept toward the contact pose, kept out of
//! bystanders' stopping envelopes, and the contact
//! that resolves the crash (moving on from it, or held there `after latch`).

use crate::geom::{Obb, wrap_angle};
use crate::place::Pose;
use crate::rollout::agent::State;
use crate::rollout::drive::follow::SAFE_MARGIN;
use crate::rollout::frame::{COURSE_STEPS, Scratch, Sim};
use crate::rollout::impact::motion::{Hit, coefficients};
use crate::rollout::kinematics::pursuit;
use crate::rollout::path::Hermite;
use crate::rollout::staging::plan;
use crate::rollout::staging::plan::Plan;
use crate::rollout::{ImpactRecord, Tracks};
use glam::DVec2;

/// A striker's trial step in its intercept: where it would be and how fast, how far short of its
/// contact pose, and that pose.
#[derive(Clone, Copy)]
pub(crate) struct Trial {
    pub pos: DVec2,
    pub yaw: f64,
    pub v: f64,
    pub left: f64,
    pub goal: (DVec2, f64),
}

impl Sim<'_, '_> {
    /// The partner of agent `j` in a staged conflict whose striker has set off and not yet
    /// struck (pass 2): once the two touch, the latch stops both dead.
    pub(crate) fn crash_partner(&self, j: usize, t: f64) -> Option<usize> {
        self.confs.iter().zip(self.plans).enumerate().find_map(|(k, (c, p))| {
            let pending = c.near.is_none() && !self.latched[k] && p.as_ref().is_some_and(|p| t >= p.t_depart - 1e-9);
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
    pub(crate) fn strike_reach(&self, j: usize, t: f64) -> Option<f64> {
        let (g, _, moves) = self.strike_pose(j, t)?;
        Some(self.cur[j].pos.distance(g) + moves)
    }

    /// Striker `j`'s contact pose, on its intercept now, taken on its target where it is, and
    /// how far the target may still move by the planned impact.
    pub(crate) fn strike_pose(&self, j: usize, t: f64) -> Option<(DVec2, f64, f64)> {
        if !self.striking(j, t) {
            return None;
        }
        let plan = self.plans[self.striker[j]?].as_ref()?;
        let so = &self.cur[plan.struck];
        let (g, gyaw) = plan::compose(Pose { x: so.pos.x, y: so.pos.y, yaw: so.yaw }, plan.rel_pos, plan.rel_yaw);
        Some((g, gyaw, so.v * (plan.t_impact - t).max(0.0)))
    }

    /// Whether agent `i` is a striker on its intercept now (it follows its plan, not the rules).
    pub(crate) fn striking(&self, i: usize, t: f64) -> bool {
        self.striker[i]
            .and_then(|k| self.plans[k].as_ref().map(|p| (k, p)))
            .is_some_and(|(k, p)| t >= p.t_depart - 1e-9 && !self.latched[k])
    }

    /// One step of an at-fault agent's intercept: a Hermite curve from where it is to the pose
    /// that makes contact, re-planned every frame against the struck agent's predicted pose,
    /// traversed with the constant acceleration that arrives at the impact time.
    pub(crate) fn intercept(&self, sc: &mut Scratch, i: usize, plan: &Plan, t: f64, f: usize) -> State {
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
        let (g, gyaw) = plan::compose(target, plan.rel_pos, plan.rel_yaw);
        let tau = remaining.max(dt);
        let curve = Hermite::new(st.pos, st.yaw, g, gyaw);
        let len = curve.length();
        let acc = (2.0 * (len - st.v * tau) / (tau * tau)).clamp(-lim.brake_max, plan::STRIKE_ACCEL * lim.accel);
        // Keep rolling (an intercept that stalls never makes contact), within the strike's
        // acceleration.
        let v = (st.v + acc * dt).max(1.0f64.min(st.v + plan::STRIKE_ACCEL * lim.accel * dt));
        let step = |v: f64| {
            let adv = 0.5 * (st.v + v) * dt;
            // The arc from here through the curve's point `adv` ahead: the curve itself wherever
            // the car can follow it; a wider arc where the curve turns tighter than the car can.
            // In the last metres the contact point itself: the curve's end heading matters less
            // than reaching its end, and a short re-planned curve can bend tighter than the car.
            let aim = if len <= 3.0 * adv { g } else { curve.at(adv, gyaw).0 };
            let (pos, yaw) = self.advance(a, &st, pursuit(st.pos, self.facts.dirs[i], aim), adv, plan::STRIKE_YAW);
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
            let trial = Trial { pos: next.0, yaw: next.1, v: vk, left: next.2, goal: (g, gyaw) };
            match self.strike_blocked(&mut sc.course, i, plan.struck, trial) {
                None => {
                    pick = (vk, next);
                    break;
                }
                Some(j) if k == 0 => match sc.blocked_by[i].iter_mut().find(|h| h.0 == j) {
                    Some(h) => h.2 += 1,
                    None => sc.blocked_by[i].push((j, t, 1)),
                },
                Some(_) => {}
            }
        }
        let (v, (pos, yaw, _)) = pick;
        State { pos, yaw, v, ..st }
    }

    /// Striker `i`'s poses, a step apart, were it to brake at its emergency braking from its
    /// `trial` pose and speed, steering for its contact pose as `intercept` does, up to the
    /// contact (`left` metres on): the time from now, and the pose. A curve re-planned every
    /// step and a heading that turns no faster than the car can is not the curve it plans: at
    /// speed the car runs wide of it.
    pub(crate) fn braking_course(&self, i: usize, trial: Trial, out: &mut Vec<(f64, DVec2, f64)>) {
        let Trial { pos, yaw, v, left, goal } = trial;
        let (a, dt) = (&self.actors[i], self.dt);
        out.clear();
        let (mut st, mut went, mut t) = (State { pos, yaw, v, ..self.cur[i] }, 0.0, 0.0);
        while st.v > 0.0 && went < left && out.len() < COURSE_STEPS {
            let v2 = (st.v - a.lim.brake_max * dt).max(0.0);
            let adv = (0.5 * (st.v + v2) * dt).min(left - went);
            let curve = Hermite::new(st.pos, st.yaw, goal.0, goal.1);
            let aim = if curve.length() <= 3.0 * adv { goal.0 } else { curve.at(adv, goal.1).0 };
            (st.pos, st.yaw) =
                self.advance(a, &st, pursuit(st.pos, DVec2::from_angle(st.yaw), aim), adv, plan::STRIKE_YAW);
            st.v = v2;
            went += adv;
            t += dt;
            out.push((t, st.pos, st.yaw));
        }
    }

    /// Whether striker `i` at its `trial` pose and speed, `left` metres short of its contact pose,
    /// would be inside a bystander's stopping envelope (its box stretched ahead by the distance it
    /// needs to stop at its emergency braking), or have its own envelope (up to the contact pose)
    /// reach a bystander's. A bystander following the striker is left to its own safe speed.
    pub(crate) fn strike_blocked(
        &self,
        course: &mut Vec<(f64, DVec2, f64)>,
        i: usize,
        struck: usize,
        trial: Trial,
    ) -> Option<usize> {
        let Trial { pos, yaw, v, left, .. } = trial;
        let a = &self.actors[i];
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
                    self.braking_course(i, trial, course);
                    built = true;
                }
                let vel = self.facts.dirs[j] * o.v;
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
            let fwd = self.facts.dirs[j];
            if b.vehicle && o.v > 0.05 && DVec2::from_angle(yaw).dot(fwd) < -0.5 && fwd.dot(pos - o.pos) > 0.0 {
                if !built {
                    self.braking_course(i, trial, course);
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

    /// Resolve each staged conflict at its deepest overlap: once the boxes meet, the frame where
    /// the planned penetration is reached (or the impact time passes, or the overlap starts to
    /// shrink) is the impact. The pair moves on from it (`Sim::hit`), or, `after latch`, holds
    /// there.
    pub(crate) fn latch(&mut self, f: usize, out: &mut Tracks) {
        let t = f as f64 * self.dt;
        let (confs, plans) = (self.confs, self.plans);
        for (k, conf) in confs.iter().enumerate() {
            let Some(plan) = plans.get(k).and_then(|p| p.as_ref()) else { continue };
            if self.latched[k] {
                self.note_halt(k);
                continue;
            }
            // A near miss has no contact to latch: at the pass its passer drives on.
            if conf.near.is_some() {
                if t >= plan.t_impact - 0.5 * self.dt {
                    self.release(k);
                }
                continue;
            }
            let (af, st) = (conf.af, conf.st);
            let (mut a, mut b) = (self.actors[af].obb(&self.next[af]), self.actors[st].obb(&self.next[st]));
            let grazed = !a.overlaps(&b);
            if grazed {
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
            let depth = plan::depth(&a, &b);
            if depth >= 0.8 * plan.delta || t >= plan.t_impact - 0.5 * self.dt || depth <= self.prev_depth[k] {
                self.latched[k] = true;
                let frame = if conf.c.after.latch {
                    self.next[af].frozen = true;
                    self.next[st].frozen = true;
                    f
                } else {
                    let hit = Hit { coefficients: coefficients(&conf.c.after), conflict: Some(conf.index) };
                    self.hit(out, (af, st), f, !grazed, hit)
                };
                let p = plan::contact_centroid(&a, &b).unwrap_or((a.center + b.center) / 2.0);
                let local = |o: &Obb| {
                    let q = (p - o.center).rotate(DVec2::from_angle(-o.yaw));
                    [q.x, q.y]
                };
                let sl = local(&b);
                out.impacts.push(ImpactRecord {
                    conflict: conf.index,
                    frame,
                    at_fault: af,
                    struck: st,
                    point_world: [p.x, p.y],
                    at_fault_local: local(&a),
                    struck_local: sl,
                    struck_side: plan::side_of(DVec2::new(sl[0], sl[1]), b.length, b.width),
                    depth,
                });
            } else {
                self.prev_depth[k] = depth;
            }
        }
    }
}
