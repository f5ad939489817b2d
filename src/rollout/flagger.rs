//! Flaggers in the rollout: which vehicles each flagger holds (those whose route passes it, on
//! or beside their lane, driving toward its face), the state it shows each frame, and how far a
//! held vehicle may go. A stop acts as a red: a vehicle that can stop short of the flagger
//! (within three quarters of its emergency braking) holds there; a go lets it on. Scene:
//! `scenarios/rare/flagger_work_zone.scn`.

use crate::check::scenario::{FlagStep, Flagger};
use crate::diag::Diagnostic;
use crate::road::Map;
use crate::rollout::agent::{Actor, Drive};
use crate::rollout::agent::{Facing, FlagRun};
use crate::rollout::frame::Sim;
use crate::rollout::junction::right_of_way::YIELD_BRAKE;
use crate::rollout::kinematics::can_stop;
use crate::rollout::trigger::{holds, on_tracks};
use glam::DVec2;

/// How far short of the flagger a held vehicle's front stops, m.
pub(crate) const STANDOFF_M: f64 = 2.0;
/// How far beside a lane's paving (its half width and any shoulder) a flagger still faces it, m.
const BESIDE_M: f64 = 1.0;
/// A flagger faces traffic whose heading is within 60 degrees of straight at it.
const FACING_COS: f64 = -0.5;

impl FlagRun {
    /// Whether it shows go at `t`, at step `step` of a program that is not a cycle.
    pub(crate) fn go(&self, step: u8, t: f64) -> bool {
        if !self.cycle {
            return self.steps.get(step as usize).is_some_and(|s| s.go);
        }
        let mut at = t.rem_euclid(self.period);
        for s in &self.steps {
            if at < s.at {
                return s.go;
            }
            at -= s.at;
        }
        self.steps.last().is_some_and(|s| s.go)
    }
}

/// Give each flagger its program and each vehicle that drives toward a flagger's face, with it
/// ahead, that flagger; a flagger that faces no lane of the map is E0272.
pub(crate) fn assign_flaggers(
    flaggers: &[Flagger],
    map: &Map,
    actors: &mut [Actor],
    track_of: &[Option<usize>],
    errs: &mut Vec<Diagnostic>,
) {
    for fl in flaggers {
        let Some(j) = track_of.get(fl.agent).copied().flatten() else { continue };
        let (p, face) = (DVec2::new(actors[j].init.x, actors[j].init.y), DVec2::from_angle(actors[j].init.yaw));
        let faces = faced_lanes(map, p, face);
        if faces.is_empty() {
            let mut d = Diagnostic::error("E0272", format!("flagger `{}` faces no approach", actors[j].info.name))
                .help("stand it on a lane or its shoulder, facing the traffic it directs: e.g. `at west.in[1], 20 m before center offset 3 m right heading 180 deg` on a straight road");
            if let Some(span) = actors[j].span {
                d = d.label(span, "no lane runs toward this flagger's face here");
            }
            errs.push(d);
            continue;
        }
        let steps: Vec<FlagStep> = fl
            .steps
            .iter()
            .map(|s| FlagStep { trigger: s.trigger.and_then(|t| on_tracks(t, track_of)), ..*s })
            .collect();
        let period = if fl.cycle { steps.iter().map(|s| s.at).sum() } else { 0.0 };
        actors[j].flag = Some(Box::new(FlagRun { steps, cycle: fl.cycle, period, faces }));
        for a in actors.iter_mut() {
            if !a.vehicle || !matches!(a.drive, Drive::Mover) {
                continue;
            }
            // Newton steps from the nearest of points 2 m apart: a route may bend back near p.
            let len = a.path.length();
            let near = |s: &f64| a.path.at(*s).0.distance_squared(p);
            let guess = (0..=(len / 2.0) as usize).map(|k| 2.0 * k as f64).min_by(|x, y| near(x).total_cmp(&near(y)));
            let foot = a.path.frenet(p, guess.unwrap_or(0.0));
            let ahead = foot.s > a.s0 + a.hl && foot.beyond.abs() < 1e-6;
            if ahead && foot.d.abs() <= a.lane_hw + 3.0 && DVec2::from_angle(foot.dir).dot(face) < FACING_COS {
                a.flaggers.push(Facing { flagger: j, at: foot.s });
            }
        }
    }
}

/// The lanes of `map` running toward a flagger at `p` facing `face`, with it on them or beside
/// their paving.
fn faced_lanes(map: &Map, p: DVec2, face: DVec2) -> Vec<String> {
    let mut out = vec![];
    for l in &map.lanes {
        let (s, d) = l.centre.project(p);
        let len = l.centre.length();
        if s <= 0.0 || s >= len || d.abs() > 0.5 * l.width + l.shoulder_right + BESIDE_M {
            continue;
        }
        let dir = (l.centre.point_at((s + 0.5).min(len)) - l.centre.point_at((s - 0.5).max(0.0))).normalize_or_zero();
        if dir.dot(face) < FACING_COS {
            let dir = if l.id.dir == crate::check::scenario::Dir::In { "in" } else { "out" };
            out.push(format!("{}.{dir}[{}]", l.id.arm.name(), l.id.index));
        }
    }
    out
}

impl Sim<'_, '_> {
    /// Move each flagger that is not on a cycle to its next step once that step's time has come
    /// and its condition holds on this frame's states: one step per frame.
    pub(crate) fn fire_flags(&mut self, t: f64) {
        for i in 0..self.actors.len() {
            let Some(run) = self.actors[i].flag.as_deref() else { continue };
            let k = self.cur[i].flag as usize + 1;
            if let Some(next) = run.steps.get(k).filter(|_| !run.cycle)
                && t >= next.at - 1e-9
                && next.trigger.is_none_or(|tr| holds(self.actors, &self.cur, i, tr, t))
            {
                self.cur[i].flag += 1;
            }
        }
    }

    /// How far vehicle `i`'s front may go while a flagger ahead shows stop at `t`: short of the
    /// flagger while it can stop there within `YIELD_BRAKE` of its emergency braking. `None`
    /// when it may go, and for `signal ignore`.
    pub(crate) fn flag_hold(&self, i: usize, t: f64) -> Option<f64> {
        let a = &self.actors[i];
        if a.flaggers.is_empty() || !a.behaviour.signal {
            return None;
        }
        let st = &self.cur[i];
        if st.frozen || self.striking(i, t) {
            return None;
        }
        let mut hold: Option<f64> = None;
        for f in &a.flaggers {
            let run = self.actors[f.flagger].flag.as_deref()?;
            if run.go(self.cur[f.flagger].flag, t) {
                continue;
            }
            let rem = f.at - STANDOFF_M - (st.s + a.hl);
            if rem > -0.05 && can_stop(st.v, rem, YIELD_BRAKE * a.lim.brake_max) {
                hold = Some(hold.map_or(rem.max(0.0), |h| h.min(rem.max(0.0))));
            }
        }
        hold
    }

    /// Append each flagger's state at this frame's states to `out` (`Tracks::flags`).
    pub(crate) fn record_flags(&self, out: &mut crate::rollout::Tracks, t: f64) {
        for ft in &mut out.flags {
            let go = self.actors[ft.agent].flag.as_deref().is_some_and(|r| r.go(self.cur[ft.agent].flag, t));
            ft.go.push(go);
        }
    }
}
