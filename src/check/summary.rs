//! What `rocc check` says about a scenario that checks. In: a checked `Scenario`. Out: its name,
//! road, agent counts, egos and length, as one line for people or one JSON object.

use super::scenario::{Motion, Scenario};
use serde_json::{Value, json};

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Summary {
    pub scenario: String,
    pub road: &'static str,
    pub agents: usize,
    /// Agents that move: neither objects nor static.
    pub movers: usize,
    pub egos: Vec<String>,
    pub frames: usize,
}

impl Summary {
    pub fn of(s: &Scenario) -> Summary {
        Summary {
            scenario: s.name.clone(),
            road: s.road.template.name(),
            agents: s.agents.len(),
            movers: s.agents.iter().filter(|a| !a.is_object && a.motion != Motion::Static).count(),
            egos: s.egos.iter().map(|i| s.agents[*i].name.clone()).collect(),
            frames: s.frame_count(),
        }
    }

    /// `ok  FILE: scenario `NAME` on ROAD road, N agents (M moving), egos [A, B], F frames`.
    pub fn line(&self, file: &str) -> String {
        format!(
            "ok  {file}: scenario `{}` on {} road, {} agents ({} moving), egos [{}], {} frames",
            self.scenario,
            self.road,
            self.agents,
            self.movers,
            self.egos.join(", "),
            self.frames
        )
    }

    /// `{"type": "summary", "file", "ok": true, "scenario", "road", "agents", "movers", "egos",
    /// "frames"}`: the line `rocc check --message-format json` prints.
    pub fn json(&self, file: &str) -> Value {
        json!({"type": "summary", "file": file, "ok": true, "scenario": self.scenario, "road": self.road,
            "agents": self.agents, "movers": self.movers, "egos": self.egos, "frames": self.frames})
    }
}
