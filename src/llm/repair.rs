//! Check and repair, shared by every route that lets a model write `.scn` text (`rocc text`,
//! `rocc ciren extract`): check a candidate file (syntax, names, units, placement, rollout),
//! read scenario text out of a model's reply, keep rocc's own decisions (seed, sliders) in
//! whatever the model wrote, and loop: diagnostics back to the model, corrected file, check.

use super::Outcome;
use super::client::{Client, Constraint, Exchange, message};
use super::prompts;
use crate::diag::Diagnostic;
use crate::source::SourceMap;
use crate::syntax::ast::{Item, ScenarioStmt};
use std::path::Path;

/// A candidate's verdict: clean, or its diagnostics (spans into the map).
pub type Verdict = Result<(), (Vec<Diagnostic>, SourceMap)>;

/// The constraint for a reply that must be a whole `.scn` file: the decoding grammar where the
/// server takes one and constraints are on.
pub fn scn_constraint(client: &Client, constrain: bool) -> Constraint {
    if constrain && client.config().server.supports_grammar() {
        Constraint::Grammar(crate::grammar::print(
            &crate::grammar::for_decoding(crate::grammar::language()),
            crate::grammar::Format::Gbnf,
        ))
    } else {
        Constraint::None
    }
}

/// A model's reply read as a candidate file: its scenario text with `fix` applied and its
/// verdict, or the reply itself with E0610 when it holds no scenario.
pub fn candidate(reply: &str, fix: &dyn Fn(&str) -> String, name: &str, base: &Path) -> (String, Verdict) {
    match extract_scn(reply) {
        Some(t) => {
            let text = fix(&t);
            let verdict = check(name, &text, base);
            (text, verdict)
        }
        None => {
            let d = Diagnostic::error("E0610", "the reply holds no `scenario NAME { ... }` block")
                .help("answer with the whole corrected .scn file and nothing else");
            (reply.to_string(), Err((vec![d], SourceMap::default())))
        }
    }
}

/// One check-and-repair run: where requests go and what they are logged into.
pub struct Session<'a> {
    pub client: &'a Client,
    pub log: &'a mut Vec<Exchange>,
    /// Every candidate checked, in order; the caller has pushed the first.
    pub attempts: &'a mut Vec<String>,
    pub max_repairs: u32,
    /// Send the decoding grammar where the server takes one.
    pub constrain: bool,
    /// File name diagnostics use; `base` is where `use` imports resolve.
    pub name: &'a str,
    pub base: &'a Path,
    /// What the scene should show (the sentence, or a crash summary): the repair prompt's
    /// `{{sentence}}`.
    pub description: &'a str,
}

impl Session<'_> {
    /// Starting from a checked candidate, send its diagnostics back for a corrected file until
    /// one checks or `max_repairs` rounds are spent. `fix` re-imposes rocc's own decisions on
    /// every corrected file. A truncated or empty reply (E0606, E0605) spends a round and is
    /// reported to the model with the same file; other client errors end the run (`Err`).
    pub fn repair(
        self,
        mut text: String,
        mut verdict: Verdict,
        fix: &dyn Fn(&str) -> String,
    ) -> Result<Outcome, Diagnostic> {
        let constraint = scn_constraint(self.client, self.constrain);
        let mut round = 0;
        while let Err((diags, sources)) = verdict {
            if round == self.max_repairs {
                return Ok(Outcome::Rejected { text, diags, sources });
            }
            round += 1;
            let (system, user) = prompts::repair().render(&[
                ("dsl", prompts::dsl().text()),
                ("sentence", self.description),
                ("file", &text),
                ("diagnostics", &diagnostics_json(&diags, &sources)),
            ]);
            let messages = vec![message("system", &system, &[]), message("user", &user, &[])];
            match self.client.chat(&format!("repair {round}"), &messages, &constraint, self.log) {
                Ok(reply) => {
                    (text, verdict) = candidate(&reply, fix, self.name, self.base);
                    self.attempts.push(text.clone());
                }
                // A cut-off or empty reply is a failed round, not the end of the run: the same
                // file goes back with the reason first, while rounds are left.
                Err(d) if is_bad_reply(&d) => {
                    let mut diags: Vec<Diagnostic> = diags.into_iter().filter(|x| !is_bad_reply(x)).collect();
                    diags.insert(0, d);
                    verdict = Err((diags, sources));
                }
                Err(d) => return Err(d),
            }
        }
        Ok(Outcome::Accepted { text: crate::syntax::format_source(&text).unwrap_or(text) })
    }
}

/// A reply the client could not use as text: cut off at `--max-tokens` (E0606) or empty (E0605).
fn is_bad_reply(d: &Diagnostic) -> bool {
    matches!(d.code, "E0605" | "E0606")
}

/// Everything `rocc check` enforces: parse, check, and the front passes (sample, road, place,
/// rollout), so placement and rollout errors reach the repair loop too.
pub fn check(name: &str, text: &str, base: &Path) -> Verdict {
    let mut sources = SourceMap::default();
    match crate::check::check_text(name, text, base, &mut sources).and_then(|s| crate::compile::front(s, None)) {
        Ok(_) => Ok(()),
        Err(d) => Err((d, sources)),
    }
}

/// At most this many diagnostics go back per round: small models have small contexts, and the
/// first errors are the ones to fix first (later ones are often consequences).
pub const MAX_SENT_DIAGNOSTICS: usize = 8;

/// The diagnostics as `rocc check --message-format json` prints them, one object a line.
pub fn diagnostics_json(diags: &[Diagnostic], sources: &SourceMap) -> String {
    diags
        .iter()
        .take(MAX_SENT_DIAGNOSTICS)
        .map(|d| {
            let mut v = d.to_json(sources);
            v["type"] = "diagnostic".into();
            v.to_string()
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The scenario text of a reply: code fences and chatter before and after are cut. `None` when
/// the reply holds no `scenario` at all.
pub fn extract_scn(reply: &str) -> Option<String> {
    let mut text = reply;
    if let Some(open) = reply.find("```") {
        let after = &reply[open + 3..];
        let body_start = after.find('\n').map_or(after.len(), |i| i + 1);
        let body = &after[body_start..];
        text = body.find("```").map_or(body, |close| &body[..close]);
    }
    let starts = ["scenario", "use ", "kind ", "//"];
    let lines: Vec<&str> = text.lines().collect();
    let first = lines.iter().position(|l| starts.iter().any(|s| l.trim_start().starts_with(s)))?;
    let mut out = lines[first..].join("\n");
    if !out.contains("scenario") {
        return None;
    }
    if let Some(end) = out.rfind('}') {
        out.truncate(end + 1);
    }
    out.push('\n');
    Some(out)
}

/// Write the sliders into a file the model wrote: the seed always (rocc decided it), density
/// and randomness when the user gave them. A file that does not parse is left alone (the
/// checker reports it).
pub fn enforce(text: &str, seed: u64, density: Option<f64>, randomness: Option<f64>) -> String {
    let Ok(file) = crate::syntax::parse(0, text) else { return text.to_string() };
    let Some(sc) = file.items.iter().find_map(|i| if let Item::Scenario(s) = i { Some(s) } else { None }) else {
        return text.to_string();
    };
    // (start, end, replacement), applied back to front so earlier spans stay valid.
    let mut edits: Vec<(usize, usize, String)> = vec![];
    match sc.stmts.iter().find(|s| matches!(s, ScenarioStmt::Seed { .. })) {
        Some(s) => edits.push((s.span().start as usize, s.span().end as usize, format!("seed {seed}"))),
        None => {
            let open = sc.span.start as usize + text[sc.span.start as usize..].find('{').expect("a scenario has `{`");
            edits.push((open + 1, open + 1, format!("\n    seed {seed}")));
        }
    }
    if density.is_some() || randomness.is_some() {
        let num = super::schema::num;
        let traffic = sc.stmts.iter().find_map(|s| if let ScenarioStmt::Traffic(t) = s { Some(t) } else { None });
        let mut params: Vec<String> = vec![];
        let mut d = density.map(|d| format!("density {}", num(d)));
        let mut r = randomness.map(|r| format!("randomness {}", num(r)));
        if let Some(t) = traffic {
            for p in &t.params {
                let own = &text[p.span.start as usize..p.span.end as usize];
                match p.name.name.as_str() {
                    "density" => params.push(d.take().unwrap_or_else(|| own.to_string())),
                    "randomness" => params.push(r.take().unwrap_or_else(|| own.to_string())),
                    _ => params.push(own.to_string()),
                }
            }
        }
        params.extend(d);
        params.extend(r);
        let block = format!("traffic {{ {} }}", params.join("; "));
        match traffic {
            Some(t) => edits.push((t.span.start as usize, t.span.end as usize, block)),
            None => {
                let close = sc.span.end as usize - 1;
                edits.push((close, close, format!("    {block}\n")));
            }
        }
    }
    edits.sort_by_key(|e| std::cmp::Reverse(e.0));
    let mut out = text.to_string();
    for (a, b, s) in edits {
        out.replace_range(a..b, &s);
    }
    out
}
