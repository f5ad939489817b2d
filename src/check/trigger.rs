//! Triggers (`start when NAME CONDITION`): the condition's words and value, then, once every
//! agent is known, what the condition watches and whether triggers wait on each other in a cycle.

use super::Checker;
use super::goal::find_goal_span;
use super::scenario::*;
use super::units::Dim;
use crate::diag::{Diagnostic, did_you_mean};
use crate::syntax::ast;

/// The condition words, with what each takes after it.
const CONDITIONS: [(&str, &str); 5] = [
    ("within", "a distance: `start when ego within 20 m`"),
    ("ttc", "a time: `start when ego ttc under 3 s`"),
    ("headway", "a time: `start when ego headway under 1.5 s`"),
    ("reaches", "a mark: `start when ego reaches stop_line` (or `kerb` for a walker)"),
    ("starts", "nothing: `start when lead starts`"),
];

impl Checker {
    /// One `start when ...`: its agent resolved, its condition word known and given what it takes.
    pub(super) fn trigger(&mut self, w: &ast::Trigger, order: &[&str]) -> Option<Trigger> {
        let who = self.resolve(&w.who, order);
        let cond = w.cond.name.as_str();
        let Some(&(_, takes)) = CONDITIONS.iter().find(|c| c.0 == cond) else {
            let names: Vec<&str> = CONDITIONS.iter().map(|c| c.0).collect();
            self.err(
                Diagnostic::error("E0150", format!("unknown trigger condition `{cond}`"))
                    .label(w.cond.span, "not a condition")
                    .help(did_you_mean(cond, &names, "condition")),
            );
            return None;
        };
        let shape_ok = match cond {
            "within" | "ttc" | "headway" => w.value.is_some(),
            "reaches" => w.landmark.is_some(),
            _ => w.value.is_none() && w.landmark.is_none(),
        };
        if !shape_ok {
            self.err(
                Diagnostic::error("E0150", format!("`{cond}` takes {}", takes.split(':').next().unwrap_or(takes)))
                    .label(w.span, "condition written here")
                    .help(format!("`{cond}` takes {takes}")),
            );
            return None;
        }
        let t = match cond {
            "within" => {
                let m = self.fixed(w.value.as_ref()?, Dim::Length, "trigger distance", 0.0, 500.0, "0..500 m")?;
                Trigger::Within { who: who?, m }
            }
            "ttc" | "headway" => {
                let s = self.fixed(w.value.as_ref()?, Dim::Time, "trigger time", 0.0, 30.0, "0..30 s")?;
                if cond == "ttc" { Trigger::Ttc { who: who?, s } } else { Trigger::Headway { who: who?, s } }
            }
            "reaches" => {
                let l = w.landmark.as_ref()?;
                let Some(&(_, mark)) = MARKS.iter().find(|m| m.0 == l.name) else {
                    let names: Vec<&str> = MARKS.iter().map(|m| m.0).collect();
                    self.err(
                        Diagnostic::error("E0150", format!("`reaches` takes a mark, not `{}`", l.name))
                            .label(l.span, "unknown mark")
                            .help(did_you_mean(&l.name, &names, "mark")),
                    );
                    return None;
                };
                Trigger::Reaches { who: who?, mark }
            }
            _ => Trigger::Starts { who: who? },
        };
        Some(t)
    }

    /// Once every agent is checked: each trigger watches something that can happen (E0154), and
    /// no agent's start waits, through other triggers, on itself (E0151).
    pub(super) fn trigger_refs(&mut self, agents: &[Option<Agent>], asts: &[&ast::Agent], road: Option<&Road>) {
        let trigger_of = |i: usize| agents[i].as_ref().and_then(|a| a.goal.as_ref()).and_then(|g| g.start_when);
        for (i, a) in agents.iter().enumerate() {
            let (Some(a), Some(t)) = (a, trigger_of(i)) else { continue };
            let Some(other) = &agents[t.who()] else { continue };
            if let Some(why) = cannot_happen(t, other, road) {
                self.err(
                    Diagnostic::error("E0154", format!("`{}` starts on a condition that cannot happen: {why}", a.name))
                        .label(find_goal_span(asts[i], "start"), "never holds")
                        .help("watch an agent that moves there, or use another condition (`within`, `ttc`)"),
                );
            }
        }
        // Each agent has at most one trigger: following them from any agent either ends or
        // comes back round; a cycle is reported once, from its first agent.
        for start in 0..agents.len() {
            let mut path = vec![start];
            let mut at = start;
            while let Some(t) = trigger_of(at) {
                at = t.who();
                if at == start || path.contains(&at) {
                    break;
                }
                path.push(at);
            }
            if at != start || trigger_of(start).is_none() || path.iter().any(|&k| k < start) {
                continue;
            }
            let names: Vec<String> = path.iter().filter_map(|&k| agents[k].as_ref().map(|a| a.name.clone())).collect();
            let msg = if path.len() == 1 {
                format!("`{}` waits for itself to start", names[0])
            } else {
                format!("triggers wait on each other in a cycle: {} -> {}", names.join(" -> "), names[0])
            };
            let mut d = Diagnostic::error("E0151", msg);
            for &k in &path {
                d = d.label(find_goal_span(asts[k], "start"), "waits here");
            }
            self.err(d.help("a cycle has no first cause: let one of them start on time or on another agent"));
        }
    }
}

/// Why trigger `t` can never fire, watching `other`; `None` when it can.
fn cannot_happen(t: Trigger, other: &Agent, road: Option<&Road>) -> Option<String> {
    let still = other.motion == Motion::Static || other.is_object;
    match t {
        Trigger::Headway { .. } | Trigger::Starts { .. } if still => Some(format!("`{}` never moves", other.name)),
        Trigger::Reaches { mark: Mark::StopLine, .. } => {
            let on_in_lane = matches!(other.place, Place::Lane { lane, .. } if lane.dir == Dir::In);
            let lines = road.is_some_and(|r| r.template.has_stop_lines());
            (other.motion != Motion::Vehicle || !on_in_lane || !lines)
                .then(|| format!("`{}` has no stop line ahead to reach", other.name))
        }
        Trigger::Reaches { mark: Mark::Kerb, .. } => {
            let crosses = other.goal.as_ref().is_some_and(|g| g.lateral == Lateral::Cross);
            (!crosses).then(|| format!("`{}` does not `cross`, so it has no kerb to reach", other.name))
        }
        _ => None,
    }
}
