//! Flaggers (`flag { ... }`): a standing person whose stop/go state is a signal for the
//! approach it faces. The program's words and times are checked here; whether it faces an
//! approach is known once it is placed on the map (`rollout::flagger`, E0272).

use super::Checker;
use super::MAX_DURATION_S;
use super::scenario::{Agent, Class, FlagStep, Flagger, Motion};
use super::units::Dim;
use crate::diag::{Diagnostic, did_you_mean};
use crate::source::Span;
use crate::syntax::ast;

/// The most states one program lists (the rollout counts its step in a byte).
const MAX_STEPS: usize = 32;

impl Checker {
    /// Every `flag` block of `agents_ast` (whose checked agents are `agents`); `None` once
    /// something was reported.
    pub(super) fn flaggers(
        &mut self,
        agents_ast: &[&ast::Agent],
        agents: &[Option<Agent>],
        order: &[&str],
        duration: Option<f64>,
    ) -> Option<Vec<Flagger>> {
        let mut out = Some(vec![]);
        for (i, a) in agents_ast.iter().enumerate() {
            let flags: Vec<&ast::Flag> =
                a.stmts.iter().filter_map(|s| if let ast::AgentStmt::Flag(f) = s { Some(f) } else { None }).collect();
            let Some(&flag) = flags.first() else { continue };
            for f in &flags[1..] {
                self.dup("`flag`", flag.span, f.span);
            }
            let stands = agents[i].as_ref().is_none_or(|ag| self.flagger_stands(a, ag, flag.span));
            let steps = self.flag_steps(flag, order, duration);
            match (stands, steps, &mut out) {
                (true, Some((steps, cycle)), Some(v)) if flags.len() == 1 => v.push(Flagger { agent: i, steps, cycle }),
                _ => out = None,
            }
        }
        out
    }

    /// A flagger is a person who stands where it is placed: no goal, speed or track (E0270).
    fn flagger_stands(&mut self, a: &ast::Agent, ag: &Agent, flag: Span) -> bool {
        let what = if ag.class != Class::Pedestrian || ag.motion != Motion::Holonomic || ag.is_object {
            Some(format!("a {} cannot direct traffic", ag.kinds.first().map_or("kind", String::as_str)))
        } else if ag.goal.is_some() || ag.track.is_some() || !ag.phases.is_empty() {
            Some("a flagger stands where it is placed: it has no goal or track".to_string())
        } else if ag.speed.hi() > 0.0 {
            Some("a flagger stands where it is placed: it has no speed".to_string())
        } else {
            None
        };
        let Some(msg) = what else { return true };
        self.err(
            Diagnostic::error("E0270", msg)
                .label(flag, "`flag` makes this agent a flagger")
                .label(a.name.span, "declared here")
                .help("a flagger is a standing person (`agent f: pedestrian { at ...; flag { ... } }`)"),
        );
        false
    }

    /// The steps of a `flag` block and whether they cycle (E0271 for a program that cannot run).
    fn flag_steps(&mut self, flag: &ast::Flag, order: &[&str], duration: Option<f64>) -> Option<(Vec<FlagStep>, bool)> {
        let Some(first) = flag.steps.first() else {
            self.err(
                Diagnostic::error("E0271", "a `flag` block with no state")
                    .label(flag.span, "shows nothing")
                    .help("e.g. `flag { stop; go after 8 s }` or `flag { stop 20 s; go 15 s }`"),
            );
            return None;
        };
        if flag.steps.len() > MAX_STEPS {
            self.err(
                Diagnostic::error("E0271", format!("a `flag` block shows at most {MAX_STEPS} states"))
                    .label(flag.span, format!("{} states", flag.steps.len()))
                    .help("a repeating pattern is a cycle: `flag { stop 20 s; go 15 s }`"),
            );
            return None;
        }
        let cycle = matches!(first.when, ast::FlagWhen::For(_));
        let mut steps = Vec::with_capacity(flag.steps.len());
        let mut last_at = 0.0;
        let mut ok = true;
        for (k, st) in flag.steps.iter().enumerate() {
            let go = match st.state.name.as_str() {
                "go" => true,
                "stop" => false,
                w => {
                    self.err(
                        Diagnostic::error("E0271", format!("`{w}` is no flag state"))
                            .label(st.state.span, "not a state")
                            .help(did_you_mean(w, &["stop", "go"], "state")),
                    );
                    ok = false;
                    continue;
                }
            };
            let bad = |msg: &str, help: &str| {
                Diagnostic::error("E0271", msg.to_string()).label(st.span, "here").help(help.to_string())
            };
            let step = match (&st.when, cycle, k) {
                (ast::FlagWhen::Start, false, 0) => Some(FlagStep { go, at: 0.0, trigger: None }),
                (ast::FlagWhen::For(v), true, _) => {
                    let t = self.fixed(v, Dim::Time, "flag step", 0.1, MAX_DURATION_S, "0.1..120 s");
                    t.map(|at| FlagStep { go, at, trigger: None })
                }
                (ast::FlagWhen::After(v), false, k) if k > 0 => {
                    let t = self.fixed(v, Dim::Time, "flag time", 0.0, MAX_DURATION_S, "0..120 s");
                    if let Some(t) = t
                        && (t < last_at || duration.is_some_and(|d| t >= d))
                    {
                        let past = if t < last_at { "before the step above it" } else { "after the clip ends" };
                        self.err(bad(
                            &format!("a flag step at {t} s comes {past}"),
                            "steps are listed in the order they are shown, within the clip",
                        ));
                        None
                    } else {
                        last_at = t.unwrap_or(last_at);
                        t.map(|at| FlagStep { go, at, trigger: None })
                    }
                }
                (ast::FlagWhen::When(w), false, k) if k > 0 => {
                    self.trigger(w, order).map(|tr| FlagStep { go, at: last_at, trigger: Some(tr) })
                }
                (_, false, 0) => {
                    self.err(bad(
                        "the first flag state is shown from the start",
                        "write the first state alone, e.g. `flag { stop; go after 8 s }`",
                    ));
                    None
                }
                (_, true, _) => {
                    self.err(bad(
                        "a flag cycle gives every state a length",
                        "e.g. `flag { stop 20 s; go 15 s }`; or use `after` and `when` for every step after the first",
                    ));
                    None
                }
                (_, false, _) => {
                    self.err(bad(
                        "after the first state, a flag step starts `after` a time or `when` a condition",
                        "e.g. `go after 8 s` or `go when car within 20 m`",
                    ));
                    None
                }
            };
            match step {
                Some(s) => steps.push(s),
                None => ok = false,
            }
        }
        ok.then_some((steps, cycle))
    }
}
