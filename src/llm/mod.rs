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
pub mod goals;
pub mod prompts;
pub mod repair;
pub mod schema;

use crate::diag::Diagnostic;
use crate::source::SourceMap;
use client::{Client, ClientConfig, Constraint, Exchange};
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

/// An image for the schema stage (the CIREN sketch route), already encoded.
#[derive(Clone, Debug)]
pub struct Image {
    pub data_url: String,
}

/// Images larger than this are refused (E0614): servers reject them anyway.
pub const MAX_IMAGE_BYTES: usize = 20 << 20;

impl Image {
    pub fn from_file(path: &Path) -> Result<Image, Diagnostic> {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        let mime = match ext.as_str() {
            "png" => "image/png",
            "jpg" | "jpeg" => "image/jpeg",
            "webp" => "image/webp",
            "gif" => "image/gif",
            _ => {
                return Err(Diagnostic::error(
                    "E0614",
                    format!("--image `{}` is not PNG, JPEG, WebP or GIF", path.display()),
                )
                .help("pass a .png, .jpg, .webp or .gif file"));
            }
        };
        let bytes = std::fs::read(path).map_err(|e| {
            Diagnostic::error("E0614", format!("cannot read --image `{}`: {e}", path.display())).help("check the path")
        })?;
        if bytes.len() > MAX_IMAGE_BYTES {
            return Err(Diagnostic::error("E0614", format!("--image `{}` is {} bytes", path.display(), bytes.len()))
                .help("scale the sketch down below 20 MiB"));
        }
        Ok(Image { data_url: format!("data:{mime};base64,{}", base64(&bytes)) })
    }
}

/// Standard base64 with padding (RFC 4648): the only encoding data URLs need.
pub fn base64(bytes: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n =
            (u32::from(c[0]) << 16) | (u32::from(*c.get(1).unwrap_or(&0)) << 8) | u32::from(*c.get(2).unwrap_or(&0));
        for (i, shift) in [18, 12, 6, 0].into_iter().enumerate() {
            out.push(if i <= c.len() { T[(n >> shift) as usize & 63] as char } else { '=' });
        }
    }
    out
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
            "exchanges": self.exchanges,
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
                KindStmt::Size(_) => None,
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
        let user_content = match &self.opts.image {
            None => json!(user),
            Some(img) => json!([
                {"type": "text", "text": user},
                {"type": "image_url", "image_url": {"url": img.data_url}},
            ]),
        };
        let messages =
            vec![json!({"role": "system", "content": system}), json!({"role": "user", "content": user_content})];
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
        let mut text = crate::syntax::format_source(&emitted).unwrap_or(emitted);
        let mut verdict = repair::check(name, &text, base);
        self.run.attempts.push(text.clone());
        let mut round = 0;
        while let Err((diags, sources)) = verdict {
            if round == self.opts.max_repairs {
                return Ok(Outcome::Rejected { text, diags, sources });
            }
            round += 1;
            let (system, user) = prompts::repair().render(&[
                ("dsl", prompts::dsl().text()),
                ("sentence", sentence.trim()),
                ("file", &text),
                ("diagnostics", &repair::diagnostics_json(&diags, &sources)),
            ]);
            let messages = vec![json!({"role": "system", "content": system}), json!({"role": "user", "content": user})];
            let constraint = self.grammar(|| {
                crate::grammar::print(
                    &crate::grammar::for_decoding(crate::grammar::language()),
                    crate::grammar::Format::Gbnf,
                )
            });
            let reply =
                self.client.chat(&format!("repair {round}"), &messages, &constraint, &mut self.run.exchanges)?;
            match repair::extract_scn(&reply) {
                Some(t) => {
                    text = repair::enforce(&t, seed, o.density, o.randomness);
                    verdict = repair::check(name, &text, base);
                }
                None => {
                    text = reply;
                    let d = Diagnostic::error("E0610", "the reply holds no `scenario NAME { ... }` block")
                        .help("answer with the whole corrected .scn file and nothing else");
                    verdict = Err((vec![d], SourceMap::default()));
                }
            }
            self.run.attempts.push(text.clone());
        }
        Ok(Outcome::Accepted { text: crate::syntax::format_source(&text).unwrap_or(text) })
    }

    fn goals(&mut self, s: &Schema) -> Result<Vec<Option<String>>, Diagnostic> {
        let mut goals: Vec<Option<String>> = vec![None; s.agents.len()];
        let movers: Vec<usize> = (0..s.agents.len()).filter(|i| !self.is_static(&s.agents[*i].kind)).collect();
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
                        .filter_map(|(j, g)| g.as_ref().map(|g| format!("{}: {g}", s.agents[j].name)))
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
