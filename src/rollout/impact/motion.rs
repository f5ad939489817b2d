//! The bodies after an impact: each slides and spins to rest under tyre friction (deceleration
//! `TYRE_FRICTION * G` against its velocity, its yaw rate decaying likewise about its radius of
//! gyration), no longer driven. Any contact it makes while it moves is resolved by the same
//! impact model, and two bodies that met may overlap (their crush) only inside the contact's
//! window: the impact and, while they still overlap, further impulses at the contact part them
//! at least fast enough to come clear before friction stops them (equal and opposite impulses:
//! the pair's momentum is untouched); a pair still pressed together as `WINDOW_S` ends (by a
//! third body) is set apart.

use crate::geom::{Obb, wrap_angle};
use crate::rollout::Tracks;
use crate::rollout::agent::{Actor, Conf, State};
use crate::rollout::frame::Sim;
use crate::rollout::impact::bodies::{Slide, Window};
use crate::rollout::impact::model::{Body, Coefficients, resolve};
use crate::rollout::impact::{AfterImpact, BODY_FRICTION, Contact, G, RESTITUTION, TYRE_FRICTION, WINDOW_S};
use crate::rollout::staging::plan;
use glam::DVec2;

/// How far `b` overlaps `a`: the least overlap over the four box axes and that axis, pointing
/// from `a` into `b`; `None` when they do not overlap.
pub(crate) fn penetration(a: &Obb, b: &Obb) -> Option<(DVec2, f64)> {
    let (ca, cb) = (a.corners(), b.corners());
    let span = |c: &[DVec2; 4], ax: DVec2| {
        c.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.dot(ax)), hi.max(p.dot(ax))))
    };
    let mut best: Option<(DVec2, f64)> = None;
    for ax in [DVec2::from_angle(a.yaw), DVec2::from_angle(b.yaw)] {
        for ax in [ax, ax.perp()] {
            let ((a0, a1), (b0, b1)) = (span(&ca, ax), span(&cb, ax));
            let d = a1.min(b1) - a0.max(b0);
            if d <= 0.0 {
                return None;
            }
            if best.is_none_or(|(_, e)| d < e) {
                let n = if (b.center - a.center).dot(ax) < 0.0 { -ax } else { ax };
                best = Some((n, d));
            }
        }
    }
    best
}

impl Sim<'_, '_> {
    /// Use the masses a file states (per actor; `None` keeps the class prior).
    /// The conflicts that follow an impact (`staging::follow`), resolved when their pair meets.
    pub(crate) fn follows(mut self, follows: &[Conf]) -> Self {
        self.wreck.follows = follows.to_vec();
        self
    }

    pub(crate) fn masses(mut self, stated: &[Option<f64>]) -> Self {
        for (i, m) in stated.iter().enumerate().take(self.actors.len()) {
            if let Some(m) = *m {
                self.wreck.set_mass(&self.actors[i], i, m);
            }
        }
        self
    }

    /// Move every body that moves on from an impact one frame (into `next`).
    pub(crate) fn slide(&mut self) {
        if !self.wreck.any {
            return;
        }
        for i in 0..self.actors.len() {
            if self.wreck.slide[i].is_some() {
                self.next[i] = self.slide_from(i, self.cur[i]);
            }
        }
    }

    /// Body `i`'s state one frame on from `st`, sliding; updates its slide.
    fn slide_from(&mut self, i: usize, st: State) -> State {
        let Some(s) = self.wreck.slide[i] else { return st };
        let (next, pos, yaw) = slide_step(&self.actors[i], s, st.pos, st.yaw, self.dt);
        self.wreck.slide[i] = Some(next);
        State { pos, yaw, v: next.vel.dot(DVec2::from_angle(yaw)), frozen: true, ..st }
    }

    /// Where body `i`, moving on from an impact, comes to rest if nothing stops it first: its
    /// slide (`slide_step`) run on to its end. What the drivers round it brake for
    /// (`Sim::wrecks_ahead`).
    pub(crate) fn rest_pose(&self, i: usize) -> (DVec2, f64) {
        let (a, st) = (&self.actors[i], &self.cur[i]);
        let (mut s, mut pos, mut yaw) = match self.wreck.slide[i] {
            Some(s) => (s, st.pos, st.yaw),
            None => return (st.pos, st.yaw),
        };
        // Each step takes `TYRE_FRICTION * G * dt` off the speed and a share of it off the spin:
        // a 60 m/s slide stops within 9 s; the bound only guards against a non-finite one.
        for _ in 0..(30.0 / self.dt) as usize {
            if s.vel == DVec2::ZERO && s.omega == 0.0 {
                break;
            }
            (s, pos, yaw) = slide_step(a, s, pos, yaw, self.dt);
        }
        (pos, yaw)
    }

    /// Resolve the impact of `i` and `j` (the normal from `i` into `j`) with coefficients `k`:
    /// at frame `f` on their `next` boxes, or, where `at_next` is false, at frame `f - 1` on
    /// their `cur` boxes (a graze whose deepest frame has passed), their `next` states then the
    /// first step of the rebound. Returns the frame of the impact.
    pub(crate) fn hit(&mut self, out: &mut Tracks, (i, j): (usize, usize), f: usize, at_next: bool, k: Hit) -> usize {
        let dt = self.dt;
        let g = if at_next { f } else { f - 1 };
        // The velocities that brought each body to the contact: a sliding body's own, a driven
        // one's from its poses.
        let body = |x: usize| {
            let (now, yaw, before) = if at_next {
                (self.next[x].pos, self.next[x].yaw, Some((self.cur[x].pos, self.cur[x].yaw)))
            } else {
                let back = f.checked_sub(2).map(|h| out.poses[x][h]);
                (self.cur[x].pos, self.cur[x].yaw, back.map(|p| (DVec2::new(p.x, p.y), p.yaw)))
            };
            let (vel, omega) = match (self.wreck.slide[x], before) {
                (Some(s), _) => (s.vel, s.omega),
                (None, Some((p, y))) => ((now - p) / dt, wrap_angle(yaw - y) / dt),
                (None, None) => (DVec2::from_angle(yaw) * self.cur[x].v, 0.0),
            };
            self.body(x, now, vel, omega)
        };
        let (ba, bb) = (body(i), body(j));
        let state = |x: usize| if at_next { self.next[x] } else { self.cur[x] };
        let (oa, ob) = (self.actors[i].obb(&state(i)), self.actors[j].obb(&state(j)));
        let (normal, depth) =
            penetration(&oa, &ob).unwrap_or_else(|| ((ob.center - oa.center).normalize_or(DVec2::X), 0.0));
        let point = plan::contact_centroid(&oa, &ob).unwrap_or((oa.center + ob.center) / 2.0);
        let o = resolve(&ba, &bb, point, normal, k.coefficients, parting(depth));
        for (x, b, (vel, omega)) in [(i, ba, o.a), (j, bb, o.b)] {
            if b.inv_mass <= 0.0 {
                continue;
            }
            self.wreck.slide[x] = Some(Slide { vel, omega, moving: true });
            if at_next {
                let n = &mut self.next[x];
                (n.frozen, n.v) = (true, vel.dot(DVec2::from_angle(n.yaw)));
            } else {
                self.next[x] = self.slide_from(x, self.cur[x]);
            }
        }
        self.wreck.any = true;
        let until = g + (WINDOW_S / dt).round().max(1.0) as usize;
        self.wreck.windows.retain(|w| (w.a, w.b) != (i, j) && (w.a, w.b) != (j, i));
        self.wreck.windows.push(Window { a: i, b: j, until });
        out.contacts.push(Contact {
            frame: g,
            a: i,
            b: j,
            conflict: k.conflict,
            point: [point.x, point.y],
            normal: [normal.x, normal.y],
            impulse: [o.impulse.x, o.impulse.y],
        });
        g
    }

    /// Body `x` for the impact model at `centre` moving at `vel`, `omega`: immovable where it
    /// does not move when struck or is a pair held at its contact (`after latch`).
    fn body(&self, x: usize, centre: DVec2, vel: DVec2, omega: f64) -> Body {
        let held = self.cur[x].frozen && self.wreck.slide[x].is_none();
        let (inv_mass, inv_inertia) =
            if held { (0.0, 0.0) } else { (self.wreck.inv_mass[x], self.wreck.inv_inertia[x]) };
        Body { centre, vel, omega, inv_mass, inv_inertia }
    }

    /// Two bodies still overlapping inside their contact's window: while they close or part too
    /// slowly to be clear by its end, the contact pushes them apart with a further impulse.
    fn persist(&mut self, (a, b): (usize, usize), normal: DVec2, bias: f64) {
        let velocity = |x: usize| match self.wreck.slide[x] {
            Some(s) => (s.vel, s.omega),
            None => ((self.next[x].pos - self.cur[x].pos) / self.dt, 0.0),
        };
        let (oa, ob) = (self.actors[a].obb(&self.next[a]), self.actors[b].obb(&self.next[b]));
        let point = plan::contact_centroid(&oa, &ob).unwrap_or((oa.center + ob.center) / 2.0);
        let ((va, wa), (vb, wb)) = (velocity(a), velocity(b));
        let (ba, bb) = (self.body(a, oa.center, va, wa), self.body(b, ob.center, vb, wb));
        let o = resolve(&ba, &bb, point, normal, self.coefficients_of(a, b).coefficients, bias);
        for (x, body, (vel, omega)) in [(a, ba, o.a), (b, bb, o.b)] {
            if body.inv_mass > 0.0 && o.impulse != DVec2::ZERO {
                self.wreck.slide[x] = Some(Slide { vel, omega, moving: true });
                self.next[x].frozen = true;
            }
        }
    }

    /// After the frame's moves and staged contacts: keep apart the pairs inside a contact's
    /// window, and resolve every new contact of a body moving on from an impact.
    pub(crate) fn collide(&mut self, f: usize, out: &mut Tracks) {
        if !self.wreck.any {
            return;
        }
        let mut w = 0;
        while w < self.wreck.windows.len() {
            let Window { a, b, until } = self.wreck.windows[w];
            let (oa, ob) = (self.actors[a].obb(&self.next[a]), self.actors[b].obb(&self.next[b]));
            let Some((n, depth)) = penetration(&oa, &ob) else {
                self.wreck.windows.remove(w);
                continue;
            };
            if f < until {
                self.persist((a, b), n, parting(depth));
                w += 1;
                continue;
            }
            // Still overlapping as the window closes (pressed together by a third body): set
            // apart, each by its share of the inverse masses, and looked at again for contacts
            // this frame.
            let (ia, ib) = (self.wreck.inv_mass[a], self.wreck.inv_mass[b]);
            if ia + ib > 0.0 {
                self.next[a].pos -= n * ((depth + 1e-3) * ia / (ia + ib));
                self.next[b].pos += n * ((depth + 1e-3) * ib / (ia + ib));
            }
            for x in [a, b] {
                if let Some(s) = self.wreck.slide[x].as_mut() {
                    s.moving = true;
                }
            }
            self.wreck.windows.remove(w);
        }
        let n = self.actors.len();
        for i in 0..n {
            if !self.wreck.moving(i) {
                continue;
            }
            for j in 0..n {
                if j == i || (j < i && self.wreck.moving(j)) || self.paired(i, j) || self.contact_pending(i, j) {
                    continue;
                }
                let r = self.actors[i].radius + self.actors[j].radius;
                if self.next[i].pos.distance_squared(self.next[j].pos) >= r * r {
                    continue;
                }
                if self.actors[i].obb(&self.next[i]).overlaps(&self.actors[j].obb(&self.next[j])) {
                    let k = self.coefficients_of(i, j);
                    self.hit(out, (i, j), f, true, k);
                }
            }
        }
    }

    /// `i` and `j` are inside a contact's window.
    fn paired(&self, i: usize, j: usize) -> bool {
        self.wreck.windows.iter().any(|w| (w.a, w.b) == (i, j) || (w.a, w.b) == (j, i))
    }

    /// `i` and `j` are a staged pair whose contact is still to come (`latch` resolves it).
    fn contact_pending(&self, i: usize, j: usize) -> bool {
        self.confs.iter().enumerate().any(|(k, c)| {
            c.near.is_none()
                && ((c.af, c.st) == (i, j) || (c.af, c.st) == (j, i))
                && !self.latched[k]
                && self.plans.get(k).is_some_and(|p| p.is_some())
        })
    }

    /// The coefficients of a contact between `i` and `j`: a staged pair's own, or the defaults.
    fn coefficients_of(&self, i: usize, j: usize) -> Hit {
        let pair = |c: &&Conf| (c.af, c.st) == (i, j) || (c.af, c.st) == (j, i);
        if let Some(c) = self.wreck.follows.iter().find(pair) {
            return Hit { coefficients: coefficients(&c.c.after), conflict: Some(c.index) };
        }
        let after = self
            .confs
            .iter()
            .find(|c| c.near.is_none() && ((c.af, c.st) == (i, j) || (c.af, c.st) == (j, i)))
            .map_or(AfterImpact::default(), |c| c.c.after);
        Hit { coefficients: coefficients(&after), conflict: None }
    }
}

/// One frame of a slide from `pos`, `yaw`: the linear speed falls by `TYRE_FRICTION * G * dt`,
/// the spin by as much about the box's radius of gyration (friction spread over the
/// footprint); the pose moves on by the mean of the two frames' rates.
fn slide_step(a: &Actor, s: Slide, pos: DVec2, yaw: f64, dt: f64) -> (Slide, DVec2, f64) {
    let dv = TYRE_FRICTION * G * dt;
    let speed = s.vel.length();
    let vel = if speed <= dv { DVec2::ZERO } else { s.vel * (1.0 - dv / speed) };
    let gyration = ((a.hl * a.hl + a.hw * a.hw) / 3.0).sqrt().max(0.1);
    let dw = dv / gyration;
    let omega = if s.omega.abs() <= dw { 0.0 } else { s.omega - dw * s.omega.signum() };
    let moving = speed > 0.0 || s.omega != 0.0;
    let next = Slide { vel, omega, moving };
    (next, pos + (s.vel + vel) * (0.5 * dt), wrap_angle(yaw + 0.5 * (s.omega + omega) * dt))
}

/// The least speed, m/s, at which two bodies overlapping by `depth` metres must part to come
/// apart before the tyres' friction stops the one that moves: `sqrt(2 mu g depth)`, with a
/// centimetre to spare.
fn parting(depth: f64) -> f64 {
    (2.0 * TYRE_FRICTION * G * (depth + 0.01)).sqrt()
}

/// An impact's coefficients and, for a staged one, its conflict (index into
/// `Concrete::conflicts`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hit {
    pub coefficients: Coefficients,
    pub conflict: Option<usize>,
}

/// The coefficients a conflict states, or the defaults.
pub(crate) fn coefficients(after: &AfterImpact) -> Coefficients {
    Coefficients {
        restitution: after.restitution.unwrap_or(RESTITUTION),
        friction: after.friction.unwrap_or(BODY_FRICTION),
    }
}
