//! `expect { ... }`: what a scenario is for, stated on its tracks and evaluated after the rollout
//! by `rocc test` (`crate::expect`). Names and landmarks resolve as in goals; windows lie within
//! the clip (E1001); landmarks need an agent placed on a lane of a road that has them, and
//! `enters` one on an in-lane of a road with signals (E1002).

use super::scenario::*;
use super::units::Dim;
use super::{Checker, MAX_SPEED_MS, word};
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast;
use crate::syntax::fmt::expectation;
use serde::{Deserialize, Serialize};

impl Checker {
    /// Every expectation checked; `None` when one of them (or the agents they name) is wrong.
    pub(super) fn expects(
        &mut self,
        items: &[&ast::Expectation],
        order: &[&str],
        agents: &[Option<Agent>],
        road: Option<&Road>,
        duration: Option<f64>,
    ) -> Option<Vec<Expect>> {
        let out: Vec<Option<Expect>> = items.iter().map(|x| self.expect(x, order, agents, road, duration)).collect();
        out.into_iter().collect()
    }

    fn expect(
        &mut self,
        x: &ast::Expectation,
        order: &[&str],
        agents: &[Option<Agent>],
        road: Option<&Road>,
        duration: Option<f64>,
    ) -> Option<Expect> {
        let window = self.window(x.window.as_ref(), duration);
        let what = match &x.what {
            ast::ExpectWhat::Contact { a, b, side } => {
                let (a, b) = self.pair(a, b, order);
                let side = match side {
                    Some(s) => Some(word(self, s, &POINTS, "side of a box")?),
                    None => None,
                };
                ExpectWhat::Contact { a: a?, b: b?, side }
            }
            ast::ExpectWhat::NoContact { pair: None } => ExpectWhat::NoContact { pair: None },
            ast::ExpectWhat::NoContact { pair: Some((a, b)) } => {
                let (a, b) = self.pair(a, b, order);
                ExpectWhat::NoContact { pair: Some((a?, b?)) }
            }
            ast::ExpectWhat::Gap { a, b, bound, value } => {
                let (a, b) = self.pair(a, b, order);
                let metres = self.fixed(value, Dim::Length, "gap", 0.0, 1000.0, "0..1000 m");
                ExpectWhat::Gap { a: a?, b: b?, at_least: bound.at_least, metres: metres? }
            }
            ast::ExpectWhat::Speed { agent, bound, value } => {
                let i = self.resolve(agent, order);
                // Negative down to the fastest reverse: speeds are along the heading, a reversing
                // vehicle's below zero (`speed car at_most -1 m/s`).
                let lo = -crate::check::kerb::REVERSE_MAX_MS;
                let ms = self.fixed(value, Dim::Speed, "speed bound", lo, MAX_SPEED_MS, "-3 m/s..324 km/h");
                ExpectWhat::Speed { agent: i?, at_least: bound.at_least, ms: ms? }
            }
            ast::ExpectWhat::Stopped { agent, landmark } => {
                let (agent, lane, landmark) = self.on_lane(agent, landmark, order, agents, road)?;
                ExpectWhat::Stopped { agent, lane, landmark }
            }
            ast::ExpectWhat::Reach { agent, landmark } => {
                let (agent, lane, landmark) = self.on_lane(agent, landmark, order, agents, road)?;
                ExpectWhat::Reach { agent, lane, landmark }
            }
            ast::ExpectWhat::Enters { agent, light } => {
                let l = word(self, light, &LIGHTS, "light");
                let (agent, lane) = self.signalled_lane(agent, order, agents, road)?;
                ExpectWhat::Enters { agent, lane, light: l? }
            }
        };
        let (from, to) = window?;
        Some(Expect { what, from, to, text: expectation(x), span: x.span })
    }

    /// Two distinct agents.
    fn pair(&mut self, a: &ast::Ident, b: &ast::Ident, order: &[&str]) -> (Option<usize>, Option<usize>) {
        let (i, j) = (self.resolve(a, order), self.resolve(b, order));
        if i.is_some() && i == j {
            self.err(
                Diagnostic::error("E1003", format!("the expectation names `{}` twice", a.name))
                    .label(b.span, "the same agent again")
                    .help("an expectation on contacts or gaps relates two different agents"),
            );
            return (None, None);
        }
        (i, j)
    }

    /// `(from, to)` in seconds: the whole clip without a window.
    fn window(&mut self, w: Option<&ast::Window>, duration: Option<f64>) -> Option<(f64, f64)> {
        let clip = duration.unwrap_or(f64::INFINITY);
        let Some(w) = w else { return Some((0.0, clip)) };
        let d = self.quantity(&w.value, Dim::Time, "expectation window")?;
        let (from, to) = if w.by { (0.0, d.hi()) } else { (d.lo(), d.hi()) };
        if w.by && d.lo() != d.hi() {
            self.err(
                Diagnostic::error("E1001", "`by` takes one time")
                    .label(w.span, "a range here")
                    .help("write `by 8 s`, or `during 2..8 s` for a window"),
            );
            return None;
        }
        if from < 0.0 || to > clip + 1e-9 {
            let shown = duration.map_or(String::new(), |d| format!("0..{} s", d));
            self.err(
                Diagnostic::error("E1001", "the expectation's time lies outside the clip")
                    .label(w.span, format!("the clip runs {shown}"))
                    .help("keep the window within the scenario's `duration`, or lengthen the clip"),
            );
            return None;
        }
        Some((from, to))
    }

    /// An agent placed on a lane, and a landmark of that lane.
    fn on_lane(
        &mut self,
        agent: &ast::Ident,
        landmark: &ast::Ident,
        order: &[&str],
        agents: &[Option<Agent>],
        road: Option<&Road>,
    ) -> Option<(usize, LaneId, Landmark)> {
        let i = self.resolve(agent, order);
        let l = word(self, landmark, &LANDMARKS, "landmark")?;
        let i = i?;
        let a = agents.get(i)?.as_ref()?;
        let Place::Lane { lane, .. } = a.place else {
            self.err(
                Diagnostic::error("E1002", format!("`{}` is not placed on a lane", agent.name))
                    .label(landmark.span, "measured along the agent's lane")
                    .help("landmarks are measured along the lane an agent starts in: place it `at ARM.in[N], ...`"),
            );
            return None;
        };
        let template = road.map(|r| r.template)?;
        let bad = match l {
            Landmark::Junction if !template.has_junction() => {
                Some(format!("a {} road has no junction", template.name()))
            }
            Landmark::StopLine if !template.has_stop_lines() => {
                Some(format!("a {} road has no stop lines", template.name()))
            }
            Landmark::StopLine if lane.dir == Dir::Out => Some(format!("`{}` starts on an out-lane", agent.name)),
            _ => None,
        };
        if let Some(msg) = bad {
            self.err(
                Diagnostic::error("E1002", msg).label(landmark.span, "no such landmark on this agent's lane").help(
                    "stop lines are on in-lanes of four_way, t_junction and roundabout roads; `center` is everywhere",
                ),
            );
            return None;
        }
        Some((i, lane, l))
    }

    /// An agent placed on an in-lane of a road with traffic signals: the lane whose signal
    /// `enters` reads.
    fn signalled_lane(
        &mut self,
        agent: &ast::Ident,
        order: &[&str],
        agents: &[Option<Agent>],
        road: Option<&Road>,
    ) -> Option<(usize, LaneId)> {
        let i = self.resolve(agent, order)?;
        let a = agents.get(i)?.as_ref()?;
        let bad = match (&a.place, road) {
            (_, None) => "the scenario has no road, so no traffic signals".to_string(),
            (_, Some(r)) if r.signals.is_none() => format!("the {} road has no traffic signals", r.template.name()),
            (Place::Lane { lane, .. }, _) if lane.dir == Dir::Out => {
                format!("`{}` starts on an out-lane, which has no signal", agent.name)
            }
            (Place::Lane { lane, .. }, _) => return Some((i, *lane)),
            _ => format!("`{}` is not placed on a lane", agent.name),
        };
        self.err(
            Diagnostic::error("E1002", bad)
                .label(agent.span, "read at this agent's own stop line")
                .help("`enters` needs an agent placed `at ARM.in[N], ...` on a road with `signals on`"),
        );
        None
    }
}

// ---- the checked expectations (re-exported by `scenario`) ----

/// One checked expectation: agents are indices into `Scenario::agents` (= track indices), the
/// window is in seconds within the clip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Expect {
    pub what: ExpectWhat,
    pub from: f64,
    pub to: f64,
    /// The line as written, canonically formatted: the name the report and the snapshot use.
    pub text: String,
    #[serde(skip)]
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ExpectWhat {
    /// The boxes of `a` and `b` overlap; `side` is on `b`'s box.
    Contact { a: usize, b: usize, side: Option<Point> },
    /// No two boxes overlap (or not these two).
    NoContact { pair: Option<(usize, usize)> },
    /// The least distance between the two boxes over the window, m.
    Gap { a: usize, b: usize, at_least: bool, metres: f64 },
    /// Comes to a stop with its front short of `landmark` on `lane`, and never passes it.
    Stopped { agent: usize, lane: LaneId, landmark: Landmark },
    /// Its front passes `landmark` on `lane` within the window.
    Reach { agent: usize, lane: LaneId, landmark: Landmark },
    /// Its speed within the window, m/s.
    Speed { agent: usize, at_least: bool, ms: f64 },
    /// Its front passes the stop line of `lane` within the window while that lane's signal
    /// shows `light`.
    Enters { agent: usize, lane: LaneId, light: Light },
}
