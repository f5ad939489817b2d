//! Triggers (`start when NAME CONDITION`): the condition's words and value, then, once every
//! agent is known, what the condition watches and whether triggers wait on each other in a cycle.

use super::scenario::*;
use super::units::Dim;
use super::{Checker, MAX_DURATION_S, MAX_SPEED_MS};
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
    /// A later goal block: the `start` that hands over to it, and what changes then: a goal
    /// `speed`, a stop (`stop after DIST`, from where the phase starts) or, for a vehicle,
    /// `lateral pull_to_shoulder` (E0155 for anything else: a phase keeps the route).
    pub(super) fn phase(&mut self, g: &ast::Goal, order: &[&str], vehicle: bool) -> Option<Phase> {
        let mut speed = None;
        let mut start: Option<(f64, Option<Trigger>)> = None;
        let (mut stop_after, mut pull_over, mut change) = (None, false, None);
        let mut ok = true;
        for st in &g.stmts {
            match st {
                ast::GoalStmt::Stop { stop: ast::Stop::After(v), .. } if stop_after.is_none() => {
                    stop_after = self.fixed(v, Dim::Length, "stop distance", 0.0, 2000.0, "0..2000 m");
                    ok &= stop_after.is_some();
                }
                ast::GoalStmt::Lateral { lateral: ast::Lateral::Word(w), .. }
                    if w.name == "pull_to_shoulder" && vehicle && !pull_over && change.is_none() =>
                {
                    pull_over = true;
                }
                ast::GoalStmt::Lateral { lateral: ast::Lateral::ChangeLane(side), .. }
                    if vehicle && !pull_over && change.is_none() =>
                {
                    change = super::word(self, side, &SIDES, "side");
                    ok &= change.is_some();
                }
                ast::GoalStmt::Speed { value, .. } if speed.is_none() => {
                    speed = self.bounded(value, Dim::Speed, "goal speed", 0.0, MAX_SPEED_MS, "0..324 km/h");
                    ok &= speed.is_some();
                }
                ast::GoalStmt::Start { after, .. } if start.is_none() => {
                    let t = self.fixed(after, Dim::Time, "start delay", 0.0, MAX_DURATION_S, "0..120 s");
                    ok &= t.is_some();
                    start = Some((t.unwrap_or(0.0), None));
                }
                ast::GoalStmt::StartWhen { trigger, .. } if start.is_none() => {
                    let t = self.trigger(trigger, order);
                    ok &= t.is_some();
                    start = Some((0.0, t));
                }
                other => {
                    self.err(
                        Diagnostic::error(
                            "E0155",
                            format!(
                                "a goal phase changes the speed, stops (`stop after`), pulls over or (a vehicle) changes lane, not `{}` here",
                                other.keyword()
                            ),
                        )
                        .label(other.span(), "not in a later goal block")
                        .help(if matches!(other, ast::GoalStmt::Turn { .. }) {
                            "a turn sets the route from the start: write it in the first goal block, and let the phase change the speed"
                        } else {
                            "crossings and other stops belong to the first goal block; a phase makes one lateral move"
                        }),
                    );
                    ok = false;
                }
            }
        }
        let changes = speed.is_some() || stop_after.is_some() || pull_over || change.is_some();
        let (true, Some((start_after, start_when))) = (changes, start) else {
            if ok {
                self.err(
                    Diagnostic::error("E0155", "a goal phase needs a `start` and something to change")
                        .label(g.span, "second goal block")
                        .help("e.g. `goal { speed 0 km/h; start when ego within 15 m }` or `goal { stop after 20 m; start after 3 s }`"),
                );
            }
            return None;
        };
        ok.then_some(Phase { speed, start_after, start_when, stop_after, pull_over, change })
    }

    /// A lane change in a phase (E0156): to a lane that exists; the route moves to the next lane
    /// mid-clip, so the goal before it holds its lane and does not turn, and the agent makes no
    /// other lateral move in a phase (tests/behaviour-cases/car-changes-lane-on-a-trigger.scn).
    pub(super) fn phase_lane_change(
        &mut self,
        name: &str,
        g: &Goal,
        ps: &[Phase],
        blocks: &[&ast::Goal],
        nowhere: Option<String>,
    ) {
        let Some(k) = ps.iter().position(|p| p.change.is_some()) else { return };
        let nowhere = nowhere.map(|n| format!("but {n}"));
        let why = if let Some(n) = &nowhere {
            n.as_str()
        } else if g.lateral != Lateral::HoldLane {
            "after another lateral move in its first goal"
        } else if g.turn.is_some() || g.reverse.is_some() {
            "on a goal that turns or reverses"
        } else if ps.iter().filter(|p| p.change.is_some() || p.pull_over).count() > 1 {
            "and makes another lateral move in a phase"
        } else {
            return;
        };
        self.err(
            Diagnostic::error("E0156", format!("`{name}` changes lane in a goal phase {why}"))
                .label(blocks[k].span, "changes lane here")
                .help("a phase changes lane from a first goal that holds its lane and does not turn, once"),
        );
    }

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
        let triggers = |i: usize| -> Vec<Trigger> {
            let Some(a) = &agents[i] else { return vec![] };
            a.goal.iter().filter_map(|g| g.start_when).chain(a.phases.iter().filter_map(|p| p.start_when)).collect()
        };
        for (i, a) in agents.iter().enumerate() {
            let Some(a) = a else { continue };
            for t in triggers(i) {
                let Some(other) = &agents[t.who()] else { continue };
                if let Some(why) = cannot_happen(t, other, road) {
                    self.err(
                        Diagnostic::error(
                            "E0154",
                            format!("`{}` starts on a condition that cannot happen: {why}", a.name),
                        )
                        .label(trigger_span(asts[i], &other.name), "never holds")
                        .help("watch an agent that moves there, or use another condition (`within`, `ttc`)"),
                    );
                }
            }
        }
        // Only first goals start an agent: a phase's owner is already under way when its trigger
        // is read, so a phase's trigger closes no cycle.
        let edges: Vec<Vec<usize>> = (0..agents.len())
            .map(|i| {
                agents[i].as_ref().and_then(|a| a.goal.as_ref()?.start_when).map(|t| t.who()).into_iter().collect()
            })
            .collect();
        let mut seen = std::collections::BTreeSet::new();
        for start in 0..agents.len() {
            let Some(path) = cycle_from(&edges, start) else { continue };
            let mut key = path.clone();
            key.sort_unstable();
            if !seen.insert(key) {
                continue;
            }
            let names: Vec<String> = path.iter().filter_map(|&k| agents[k].as_ref().map(|a| a.name.clone())).collect();
            let msg = if path.len() == 1 {
                format!("`{}` waits for itself to start", names[0])
            } else {
                format!("triggers wait on each other in a cycle: {} -> {}", names.join(" -> "), names[0])
            };
            let mut d = Diagnostic::error("E0151", msg);
            for (n, &k) in path.iter().enumerate() {
                d = d.label(trigger_span(asts[k], &names[(n + 1) % names.len()]), "waits here");
            }
            self.err(d.help("a cycle has no first cause: let one of them start on time or on another agent"));
        }
    }
}

/// The shortest cycle of trigger edges through `start` (agents in order, `start` first).
fn cycle_from(edges: &[Vec<usize>], start: usize) -> Option<Vec<usize>> {
    // Breadth-first from `start`, remembering how each agent was reached.
    let mut from = vec![usize::MAX; edges.len()];
    let mut queue = std::collections::VecDeque::from([start]);
    while let Some(k) = queue.pop_front() {
        for &n in &edges[k] {
            if n == start {
                let mut path = vec![k];
                while *path.last()? != start {
                    path.push(from[*path.last()?]);
                }
                path.reverse();
                return Some(path);
            }
            if from[n] == usize::MAX {
                from[n] = k;
                queue.push_back(n);
            }
        }
    }
    None
}

/// The `start when` of agent `a` (any goal block), or its `track when`, that names `who`.
fn trigger_span(a: &ast::Agent, who: &str) -> crate::source::Span {
    let track = a.stmts.iter().find_map(|s| match s {
        ast::AgentStmt::Track(t) => t.when.as_ref().filter(|w| w.who.name == who).map(|w| w.span),
        _ => None,
    });
    if let Some(span) = track {
        return span;
    }
    a.stmts
        .iter()
        .filter_map(|s| match s {
            ast::AgentStmt::Goal(g) => Some(g),
            _ => None,
        })
        .flat_map(|g| &g.stmts)
        .find_map(|s| match s {
            ast::GoalStmt::StartWhen { trigger, span } if trigger.who.name == who => Some(*span),
            _ => None,
        })
        .unwrap_or(a.span)
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
