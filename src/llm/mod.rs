//! LLM front end (`rocc text`). In: a sentence (and optionally a sketch image) and an
//! OpenAI-compatible endpoint. Out: checked `.scn` text, or the last failing attempt with its
//! diagnostics. The pipeline follows the paper's appendix C:
//!
//! 1. schema: the sentence becomes a JSON scene schema (road, roster with placements, brief);
//!    `--density`, `--randomness`, `--seed` then override it; rocc writes the skeleton.
//! 2. goals ("traffic director"): each mover, described in words, gets a goal block from the
//!    goal vocabulary, in one call (`joint`) or agent by agent with earlier goals in context
//!    (`hierarchical`).
//! 3. check (parse, check, place, roll out); on errors the JSON diagnostics go back to the
//!    model for a corrected file, up to `max_repairs` rounds.
//!
//! Invariant: nothing the model says is executed. Replies are parsed as JSON or as `.scn` text
//! and everything goes through the checker; where the server supports it, decoding is
//! constrained by the grammar exported from `grammar/scn.pest`.

pub mod client;
pub mod control;
pub mod goals;
pub mod prompts;
pub mod repair;
pub mod schema;
pub mod spec;

use crate::diag::Diagnostic;
use crate::source::SourceMap;
use client::{Client, ClientConfig, Constraint, Exchange};
pub use client::{Image, MAX_IMAGE_BYTES, base64};
use schema::{Overrides, Schema};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plan {
    /// One call decides every agent's goal.
    Joint,
    /// One call per agent, earlier decisions in context.
    Hierarchical,
}

#[derive(Clone, Debug)]
pub struct Options {
    pub client: ClientConfig,
    pub plan: Plan,
    pub max_repairs: u32,
    pub overrides: Overrides,
    /// Send grammar / JSON-schema constraints where the server takes them.
    pub constrain: bool,
    pub image: Option<Image>,
}

/// How a run ended.
#[derive(Debug)]
pub enum Outcome {
    /// Checked scenario text, canonically formatted.
    Accepted { text: String },
    /// The last attempt still fails; `diags` are its diagnostics (spans into `sources`).
    Rejected { text: String, diags: Vec<Diagnostic>, sources: SourceMap },
    /// No scenario could be produced (client errors, an unusable schema).
    Failed(Diagnostic),
}

/// Everything that happened, for the CLI's messages and `--transcript`.
#[derive(Debug, Default)]
pub struct Run {
    pub exchanges: Vec<Exchange>,
    /// Non-fatal problems (a goal reply that could not be used...).
    pub warnings: Vec<Diagnostic>,
    /// Files checked, in order: the emitted one, then one per repair round.
    pub attempts: Vec<String>,
    pub schema: Option<Schema>,
}

impl Run {
    pub fn transcript(&self, sentence: &str, opts: &Options) -> Value {
        let c = &opts.client;
        json!({
            "rocc_version": env!("CARGO_PKG_VERSION"),
            "prompts": prompts::versions().into_iter().collect::<BTreeMap<_, _>>(),
            "sentence": sentence,
            "server": c.server,
            "endpoint": c.endpoint,
            "model": c.model,
            "plan": match opts.plan { Plan::Joint => "joint", Plan::Hierarchical => "hierarchical" },
            "max_repairs": opts.max_repairs,
            "schema": self.schema,
            "attempts": self.attempts,
            "exchanges": client::redact_images(&json!(self.exchanges)),
        })
    }
}

/// Kinds of the stdlib prelude and whether each is static (an `object`, no goal).
pub fn stdlib_kinds() -> Vec<(String, bool)> {
    use crate::syntax::ast::{Item, KindStmt};
    let file = crate::syntax::parse(0, crate::check::load::STDLIB_KINDS).expect("the stdlib parses");
    let moving_classes = ["vehicle", "bicycle", "pedestrian"];
    file.items
        .iter()
        .filter_map(|i| if let Item::Kind(k) = i { Some(k) } else { None })
        .map(|k| {
            let motion = k.stmts.iter().find_map(|s| match s {
                KindStmt::Motion { motion, .. } => Some(motion.name.as_str()),
                KindStmt::Size(_) | KindStmt::Mass { .. } => None,
            });
            let stat = match motion {
                Some(m) => m == "static",
                None => !moving_classes.contains(&k.class.name.as_str()),
            };
            (k.name.name.clone(), stat)
        })
        .collect()
}

struct Pipeline<'a> {
    client: Client,
    opts: &'a Options,
    run: Run,
    kinds: Vec<(String, bool)>,
}

/// Sentence -> checked scenario text. `name` is the file name diagnostics use (the `-o` file's
/// name), `base` the directory `use` imports resolve against.
pub fn text_to_scenario(sentence: &str, opts: &Options, name: &str, base: &Path) -> (Outcome, Run) {
    if sentence.trim().is_empty() {
        let d = Diagnostic::error("E0614", "the sentence is empty")
            .help("describe the scene: rocc text \"a deer crosses a rural road\" -o deer.scn");
        return (Outcome::Failed(d), Run::default());
    }
    let client = match Client::new(opts.client.clone()) {
        Ok(c) => c,
        Err(d) => return (Outcome::Failed(d), Run::default()),
    };
    let mut p = Pipeline { client, opts, run: Run::default(), kinds: stdlib_kinds() };
    let outcome = match p.go(sentence, name, base) {
        Ok(o) => o,
        Err(d) => Outcome::Failed(d),
    };
    (outcome, p.run)
}

impl Pipeline<'_> {
    fn is_static(&self, kind: &str) -> bool {
        self.kinds.iter().any(|(k, s)| k == kind && *s)
    }

    fn grammar(&self, g: impl FnOnce() -> String) -> Constraint {
        if self.opts.constrain && self.opts.client.server.supports_grammar() {
            Constraint::Grammar(g())
        } else {
            Constraint::None
        }
    }

    /// Ask until `read` accepts a reply, telling the model what was wrong each time, at most
    /// `max_repairs` corrections. Client errors end the run; `Ok(Err)` is the last complaint.
    fn ask<T>(
        &mut self,
        stage: &str,
        mut messages: Vec<Value>,
        constraint: &Constraint,
        read: impl Fn(&str) -> Result<T, String>,
    ) -> Result<Result<T, (String, String)>, Diagnostic> {
        let mut round = 0;
        loop {
            let reply = self.client.chat(stage, &messages, constraint, &mut self.run.exchanges)?;
            match read(&reply) {
                Ok(t) => return Ok(Ok(t)),
                Err(why) if round < self.opts.max_repairs => {
                    round += 1;
                    messages.push(json!({"role": "assistant", "content": reply}));
                    messages.push(json!({"role": "user", "content": format!("That reply cannot be used: {why}. Answer again, in the required form only.")}));
                }
                Err(why) => return Ok(Err((reply, why))),
            }
        }
    }

    fn go(&mut self, sentence: &str, name: &str, base: &Path) -> Result<Outcome, Diagnostic> {
        // ---- 1. schema ----
        let kind_names: Vec<String> = self.kinds.iter().map(|(k, _)| k.clone()).collect();
        let (system, user) =
            prompts::schema().render(&[("kinds", &kind_names.join(", ")), ("sentence", sentence.trim())]);
        let messages =
            vec![client::message("system", &system, &[]), client::message("user", &user, self.opts.image.as_slice())];
        let constraint =
            if self.opts.constrain { Constraint::Json(schema::json_schema(&kind_names)) } else { Constraint::None };
        let mut s = match self.ask("schema", messages, &constraint, schema::parse)? {
            Ok(s) => s,
            Err((reply, why)) => {
                return Err(Diagnostic::error("E0611", format!("no usable scene schema: {why}")).help(format!(
                    "the model's last reply: `{}`; `rocc explain E0611`",
                    client::excerpt(&reply, 200)
                )));
            }
        };
        schema::apply(&mut s, &self.opts.overrides, sentence);
        self.run.schema = Some(s.clone());

        // ---- 2. goals ----
        // A goal line is a few dozen tokens; a tight budget stops a looping model early.
        let full = self.client.config().max_tokens;
        let movers = s.agents.iter().filter(|a| !self.is_static(&a.kind)).count() as u32;
        self.client.set_max_tokens(full.min(64 * movers.max(1) + 64));
        let goals = self.goals(&s);
        self.client.set_max_tokens(full);
        let goals = match goals {
            Ok(g) => g,
            // A truncated goal reply costs the goals, not the run: the checker still decides.
            Err(d) if d.code == "E0606" => {
                self.run.warnings.push(
                    Diagnostic::warning("E0612", format!("goal stage: {}", d.message))
                        .help("the agents keep their initial speed; the checker has the last word"),
                );
                vec![None; s.agents.len()]
            }
            Err(d) => return Err(d),
        };

        // ---- 3. emit, check, repair ----
        let is_static = |k: &str| self.is_static(k);
        let emitted = schema::emit(&s, &goals, &is_static);
        let seed = s.seed.expect("schema::apply sets the seed");
        let o = self.opts.overrides;
        let text = crate::syntax::format_source(&emitted).unwrap_or(emitted);
        let verdict = repair::check(name, &text, base);
        self.run.attempts.push(text.clone());
        let session = repair::Session {
            client: &self.client,
            log: &mut self.run.exchanges,
            attempts: &mut self.run.attempts,
            max_repairs: self.opts.max_repairs,
            constrain: self.opts.constrain,
            name,
            base,
            description: sentence.trim(),
        };
        session.repair(text, verdict, &|t| repair::enforce(t, seed, o.density, o.randomness))
    }

    fn goals(&mut self, s: &Schema) -> Result<Vec<Option<String>>, Diagnostic> {
        let mut goals: Vec<Option<String>> = vec![None; s.agents.len()];
        // Flaggers stand: they get no goal.
        let movers: Vec<usize> = (0..s.agents.len())
            .filter(|i| !self.is_static(&s.agents[*i].kind) && s.agents[*i].flag.is_none())
            .collect();
        if movers.is_empty() {
            return Ok(goals);
        }
        let road = format!(
            "{}, {} lane(s) each way{}",
            s.road.template.replace('_', " "),
            s.road.lanes,
            s.road.speed_limit_kmh.map(|v| format!(", limit {} km/h", schema::num(v))).unwrap_or_default()
        );
        let roster: String =
            s.agents.iter().map(|a| format!("- {}", schema::describe(s, a))).collect::<Vec<_>>().join("\n");
        let names: Vec<String> = movers.iter().map(|i| s.agents[*i].name.clone()).collect();
        let brief = if s.brief.trim().is_empty() { "(none)".to_string() } else { s.brief.clone() };
        match self.opts.plan {
            Plan::Joint => {
                let (system, user) =
                    prompts::goals_joint().render(&[("brief", &brief), ("road", &road), ("agents", &roster)]);
                let messages =
                    vec![json!({"role": "system", "content": system}), json!({"role": "user", "content": user})];
                let constraint = self.grammar(|| goals::joint_grammar(&names));
                let all: Vec<String> = s.agents.iter().map(|a| a.name.clone()).collect();
                match self.ask("goals", messages, &constraint, |r| goals::parse_joint(r, &all))? {
                    Ok(found) => {
                        for (i, g) in found {
                            if movers.contains(&i) {
                                goals[i] = Some(g);
                            }
                        }
                    }
                    Err((_, why)) => self.run.warnings.push(
                        Diagnostic::warning("E0612", format!("no usable goals: {why}"))
                            .help("the agents keep their initial speed; the checker has the last word"),
                    ),
                }
            }
            Plan::Hierarchical => {
                for &i in &movers {
                    let decided: Vec<String> = goals
                        .iter()
                        .enumerate()
                        .filter_map(|(j, g)| {
                            g.as_ref().map(|g| format!("{}: {}", s.agents[j].name, g.replace('\n', " ")))
                        })
                        .collect();
                    let decided = if decided.is_empty() { "(none yet)".to_string() } else { decided.join("\n") };
                    let name = &s.agents[i].name;
                    let (system, user) = prompts::goals_agent().render(&[
                        ("brief", &brief),
                        ("road", &road),
                        ("agents", &roster),
                        ("decided", &decided),
                        ("agent", name),
                    ]);
                    let messages =
                        vec![json!({"role": "system", "content": system}), json!({"role": "user", "content": user})];
                    let constraint = self.grammar(goals::single_grammar);
                    match self.ask(&format!("goal {name}"), messages, &constraint, goals::parse_single)? {
                        Ok(g) => goals[i] = Some(g),
                        Err((_, why)) => self.run.warnings.push(
                            Diagnostic::warning("E0612", format!("no usable goal for `{name}`: {why}"))
                                .help("the agent keeps its initial speed; the checker has the last word"),
                        ),
                    }
                }
            }
        }
        Ok(goals)
    }
}
