//! Agent and object blocks: kind, placement, speed, size and goal, or a replayed track in place of placement and goal.

use super::scenario::*;
use super::units::Dim;
use super::{Checker, MAX_DURATION_S, MAX_SPEED_MS};
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast;
use std::collections::BTreeMap;

impl Checker {
    pub(super) fn agent(
        &mut self,
        a: &ast::Agent,
        road: Option<&Road>,
        order: &[&str],
        duration: Option<f64>,
        used: &mut BTreeMap<String, Kind>,
    ) -> Option<Agent> {
        let kind = self.kind_ref(&a.kind, used);
        let class = kind.as_ref().map(|k| k.1);
        let motion = kind.as_ref().map(|k| k.2);
        let is_static = a.is_object || motion == Some(Motion::Static);
        let mut place: Option<(&ast::Placement, Span)> = None;
        let mut speed: Option<(&ast::Value, Span)> = None;
        let mut sizes: [Option<(&ast::Value, Span)>; 3] = [None; 3];
        let mut goal: Option<&ast::Goal> = None;
        let mut track: Option<&ast::Track> = None;
        let mut posture: Option<(&ast::Ident, Span)> = None;
        let mut behaviour: Option<&ast::Behaviour> = None;
        let mut phases: Vec<&ast::Goal> = vec![];
        let mut siren: Option<(&ast::Ident, Span)> = None;
        let mut body = super::body::BodyStmts::default();
        let mut mass: Option<(&ast::Value, Span)> = None;
        for st in &a.stmts {
            let (slot_first, what): (Option<Span>, &str) = match st {
                ast::AgentStmt::At { place: p, span } => (place.replace((p, *span)).map(|x| x.1), "placement `at`"),
                ast::AgentStmt::Speed { value, span } => (speed.replace((value, *span)).map(|x| x.1), "`speed`"),
                ast::AgentStmt::Size(s) => {
                    (sizes[s.key as usize].replace((&s.value, s.span)).map(|x| x.1), s.key.as_str())
                }
                // A later goal block is a phase that takes over on its own start (`phase`).
                ast::AgentStmt::Goal(g) if goal.is_some() => {
                    phases.push(g);
                    (None, "`goal`")
                }
                ast::AgentStmt::Goal(g) => (goal.replace(g).map(|x| x.span), "`goal`"),
                ast::AgentStmt::Track(t) => (track.replace(t).map(|x| x.span), "`track`"),
                ast::AgentStmt::Posture { word, span } => (posture.replace((word, *span)).map(|x| x.1), "`posture`"),
                ast::AgentStmt::Behaviour(b) => (behaviour.replace(b).map(|x| x.span), "`behaviour`"),
                ast::AgentStmt::Siren { value, span } => (siren.replace((value, *span)).map(|x| x.1), "`siren`"),
                ast::AgentStmt::Lamp { key, value, span } => {
                    body.lamps.push((key, value, *span));
                    (None, "lamp")
                }
                ast::AgentStmt::Door(d) => {
                    body.doors.push(d);
                    (None, "`door`")
                }
                ast::AgentStmt::Mass { value, span } => (mass.replace((value, *span)).map(|x| x.1), "`mass`"),
                // Read with the other agents (`Checker::flaggers`).
                ast::AgentStmt::Flag(_) => (None, "`flag`"),
            };
            if let Some(first) = slot_first {
                self.dup(what, first, st.span());
            }
        }
        let what = if a.is_object { "object" } else { "agent" };
        if is_static {
            let label = if a.is_object {
                "an object never moves".to_string()
            } else {
                format!("a {} never moves", class.map_or("static kind", |c| c.name()))
            };
            if let Some(g) = goal {
                self.err(
                    Diagnostic::error("E0113", format!("`{}` cannot have a goal: {label}", a.name.name))
                        .label(g.span, "goal on a static thing")
                        .help("remove the goal, or declare a moving kind with `agent`"),
                );
            }
            if let Some((v, span)) = speed
                && (v.lo.value != 0.0 || v.hi.is_some())
            {
                self.err(
                    Diagnostic::error("E0113", format!("`{}` cannot have a speed: {label}", a.name.name))
                        .label(span, "speed on a static thing")
                        .help("remove the speed"),
                );
            }
        }
        let track_keys = track.and_then(|t| self.track(t, duration, road, class));
        let place = match (place, track) {
            (Some((p, _)), Some(t)) => {
                self.err(
                    Diagnostic::error("E0117", format!("`{}` has both a placement and a track", a.name.name))
                        .label(t.span, "the track gives the pose")
                        .label(p.span(), "placement")
                        .help("remove `at ...`: the first keyframe places the agent"),
                );
                None
            }
            (None, Some(_)) => Some(Place::Track),
            // A static thing (a wreck) may lie anywhere on or near the map, a sidewalk included.
            (Some((p, _)), None) => self.placement(p, road, class.filter(|_| !is_static)),
            (None, None) => {
                self.err(
                    Diagnostic::error("E0106", format!("{what} `{}` has no placement", a.name.name))
                        .label(a.name.span, "where does it start?")
                        .help("add `at LANE, DIST before|after LANDMARK`, e.g. `at west.in[1], 20 m before center`"),
                );
                None
            }
        };
        if let (Some(_), Some(g)) = (track, goal) {
            self.err(
                Diagnostic::error("E0117", format!("`{}` replays a track and cannot also have a goal", a.name.name))
                    .label(g.span, "goal")
                    .help("a replayed agent follows its keyframes; remove the goal"),
            );
        }
        let speed_d = match speed {
            None => Some(Dist::Fixed(0.0)),
            Some((v, _)) => self.bounded(v, Dim::Speed, "speed", 0.0, MAX_SPEED_MS, "0..324 km/h"),
        };
        let mut size = [None; 3];
        for (i, s) in sizes.iter().enumerate() {
            if let Some((v, _)) = s {
                let what = ["length", "width", "height"][i];
                size[i] = Some(self.bounded(v, Dim::Length, what, 0.05, 40.0, "0.05..40 m"));
            }
        }
        let goal_c = match (goal, motion, track.and_then(|t| t.when.as_ref())) {
            (Some(g), Some(m), _) if !is_static => self.goal(g, m, class?, place.as_ref(), road, order, &a.name),
            (None, _, Some(w)) => self.track_trigger(w, order),
            _ => Some(None),
        };
        if let (Some(Some(g)), Some(d), Some((v, _))) = (&goal_c, &speed_d, speed)
            && g.reverse.is_some()
            && d.hi() > 0.0
        {
            self.err(
                Diagnostic::error("E0251", "a reversing vehicle starts from rest")
                    .label(v.span, "initial speed")
                    .help("remove `speed` from the agent; its goal's `speed` (at most 3 m/s) is its reverse pace"),
            );
            return None;
        }
        let posture = self.posture(posture, class, motion);
        let span = a.span;
        let place_span = place.as_ref().and(a.stmts.iter().find_map(|s| match s {
            ast::AgentStmt::At { place, .. } => Some(place.span()),
            ast::AgentStmt::Track(t) => Some(t.span),
            _ => None,
        }));
        let phases_c: Option<Vec<Phase>> = match (is_static || track.is_some(), phases.first()) {
            (_, None) => Some(vec![]),
            (true, Some(g)) => {
                self.err(
                    Diagnostic::error("E0155", format!("`{}` has a goal phase but no goal to follow", a.name.name))
                        .label(g.span, "second goal block")
                        .help("phases follow the first goal of a moving agent; remove it"),
                );
                None
            }
            (false, _) => {
                let vehicle = motion == Some(Motion::Vehicle);
                phases.iter().map(|g| self.phase(g, order, vehicle)).collect::<Vec<_>>().into_iter().collect()
            }
        };
        // A phase pulls over from its lane: not from a lane change, a crossing or an easing aside.
        if let (Some(Some(g)), Some(ps)) = (&goal_c, &phases_c)
            && g.lateral != Lateral::HoldLane
            && let Some(k) = ps.iter().position(|p| p.pull_over)
        {
            self.err(
                Diagnostic::error(
                    "E0155",
                    format!("`{}` pulls over in a goal phase after another lateral move", a.name.name),
                )
                .label(phases[k].span, "pulls over here")
                .help("a phase pulls over from a goal that holds its lane; drop one of the two lateral moves"),
            );
        }
        if let (Some(Some(g)), Some(ps)) = (&goal_c, &phases_c) {
            let nowhere =
                ps.iter().find_map(|p| p.change).and_then(|s| super::goal::no_lane_beside(place.as_ref(), road, s));
            self.phase_lane_change(&a.name.name, g, ps, &phases, nowhere);
        }
        let behaviour_c = match behaviour {
            Some(b) => self.behaviour(b, &a.name.name, motion, is_static, goal),
            None => Some(Behaviour::default()),
        };
        let (kinds, class, motion) = kind?;
        let siren = self.siren(siren, &kinds, is_static);
        let body = self.body(&body, class, &kinds, order);
        let mass = match mass {
            Some((v, span)) => self.mass(v, span, &a.name.name, is_static).map(Some),
            None => Some(None),
        };
        Some(Agent {
            name: a.name.name.clone(),
            kinds,
            class,
            motion: if a.is_object { Motion::Static } else { motion },
            is_object: a.is_object,
            length: size[0].flatten(),
            width: size[1].flatten(),
            height: size[2].flatten(),
            place: place?,
            speed: speed_d?,
            goal: goal_c?,
            track: track_keys.clone(),
            posture: posture?,
            behaviour: behaviour_c?,
            phases: phases_c?,
            siren: siren?,
            body: body?,
            mass: mass?,
            span,
            place_span: place_span.unwrap_or(span),
        })
        // A size or track that was given but invalid has been reported: no agent then.
        .filter(|_| size.iter().all(|s| s.is_none_or(|x| x.is_some())))
        .filter(|_| track.is_none() || track_keys.is_some())
    }

    /// `siren on|off`: only an emergency vehicle (a kind in or derived from `EMERGENCY_KINDS`,
    /// every kind of a `one_of`) carries one. `Some(None)` where none is stated.
    fn siren(&mut self, siren: Option<(&ast::Ident, Span)>, kinds: &[String], is_static: bool) -> Option<Option<bool>> {
        let Some((word, span)) = siren else { return Some(None) };
        let on = super::word(self, word, &[("on", true), ("off", false)], "siren setting")?;
        let emergency = |k: &String| {
            EMERGENCY_KINDS.contains(&k.as_str()) || self.kinds.get(k).is_some_and(|(kind, _)| kind.emergency)
        };
        if is_static || !kinds.iter().all(emergency) {
            let none = kinds.iter().find(|k| is_static || !emergency(k)).map_or("", String::as_str);
            self.err(
                Diagnostic::error("E0170", format!("`{none}` has no siren"))
                    .label(span, "siren on a kind that is not an emergency vehicle")
                    .help("only ambulance, fire_truck, police_car and kinds derived from them carry a siren"),
            );
            return None;
        }
        Some(Some(on))
    }

    /// `track when NAME CONDITION`: its trigger, carried as the `start when` of an otherwise
    /// empty goal, so that triggers read it like any start (cycles E0151, E0154) and the
    /// rollout starts the replay when it fires.
    fn track_trigger(&mut self, w: &ast::Trigger, order: &[&str]) -> Option<Option<Goal>> {
        let start_when = Some(self.trigger(w, order)?);
        Some(Some(Goal { start_when, ..Goal::default() }))
    }

    fn track(
        &mut self,
        t: &ast::Track,
        duration: Option<f64>,
        road: Option<&Road>,
        class: Option<Class>,
    ) -> Option<Vec<Keyframe>> {
        let _ = duration;
        if t.keys.is_empty() {
            self.err(
                Diagnostic::error("E0117", "a track needs at least one keyframe")
                    .label(t.span, "empty track")
                    .help("write keyframes as `0 s: (12.0 m, -3.5 m) yaw 90 deg`"),
            );
            return None;
        }
        let mut out = vec![];
        let mut prev: Option<(f64, Span)> = None;
        for k in &t.keys {
            let tt = self.fixed(&k.t, Dim::Time, "keyframe time", 0.0, MAX_DURATION_S, "0..120 s");
            let (pose, at) = match &k.pose {
                ast::KeyPose::World { x, y, yaw } => (self.world_key(x, y, yaw), None),
                ast::KeyPose::Lane(p) => {
                    let at = self.lane_key(p, road, class);
                    (at.is_some().then_some((0.0, 0.0, 0.0)), at)
                }
            };
            let (Some(tt), Some((x, y, yaw))) = (tt, pose) else { return None };
            if let Some((pt, pspan)) = prev
                && tt <= pt
            {
                self.err(
                    Diagnostic::error("E0117", "keyframe times must strictly increase")
                        .label(k.t.span, format!("{tt} s is not after {pt} s"))
                        .label(pspan, "previous keyframe")
                        .help("sort the keyframes by time and drop duplicates"),
                );
                return None;
            }
            prev = Some((tt, k.t.span));
            out.push(Keyframe { t: tt, x, y, yaw, at, span: k.span });
        }
        Some(out)
    }
}
