//! `rocc ciren extract`: the VLM route. In: a CIREN case directory (the investigator's sketch
//! and the crash summary) and an OpenAI-compatible vision model. Out: checked `.scn` text whose
//! `conflict` block came from a separate greedy call, or the last failing attempt with its
//! diagnostics.
//!
//! Two calls, in this order:
//! 1. scene: sketch (an `image_url` part) + summary + the language reference + worked examples
//!    -> `.scn` text, checked and repaired exactly like `rocc text` (`llm::repair`). A conflict
//!    block the model writes here is dropped: the conflict is the second call's job.
//! 2. conflict: the accepted scene, the summary and the sketch -> a small JSON descriptor
//!    (temperature 0), merged into the scene text by AST span. Only the conflict call is
//!    repeated when the merged file fails to check, so a faithful scene is never re-sampled.

use super::descriptor::{self, Descriptor, Roster};
use crate::diag::Diagnostic;
use crate::llm::client::{self, Client, ClientConfig, Constraint, Exchange, Image, MAX_IMAGE_BYTES, message};
use crate::llm::{self, prompts, repair};
use crate::source::{SourceMap, Span};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Sketch file names looked for, in order (`sketch.jpeg` in CIREN case folders, `Sketch.jpg`
/// in the SAFE extraction folders).
pub const SKETCH_NAMES: [&str; 6] =
    ["sketch.jpeg", "sketch.jpg", "Sketch.jpg", "Sketch.jpeg", "sketch.png", "Sketch.png"];
/// A summary longer than this is refused (E0855): CIREN summaries are 1-3 KiB, and every byte
/// is paid again on each repair round.
pub const MAX_SUMMARY_BYTES: usize = 16 << 10;
/// `crash_report.xml` files larger than this are refused unread (E0855); real ones are ~100 KiB.
pub const MAX_REPORT_BYTES: u64 = 32 << 20;

const SCENE_PROMPT: &str = include_str!("../../prompts/ciren_scene.md");
const CONFLICT_PROMPT: &str = include_str!("../../prompts/ciren_conflict.md");

/// The worked examples under `prompts/ciren/` (compiled in; `--examples DIR` replaces them).
pub const EXAMPLES: &[(&str, &str)] = &[
    ("100237.scn", include_str!("../../prompts/ciren/100237.scn")),
    ("105165.scn", include_str!("../../prompts/ciren/105165.scn")),
];

pub fn scene_prompt() -> prompts::Prompt {
    prompts::load(SCENE_PROMPT)
}
pub fn conflict_prompt() -> prompts::Prompt {
    prompts::load(CONFLICT_PROMPT)
}

/// One case's inputs, read and validated.
#[derive(Clone, Debug)]
pub struct Case {
    /// `CaseID` of the report, else the directory name; only `[A-Za-z0-9_]`.
    pub id: String,
    pub sketch: PathBuf,
    pub image: Image,
    /// Whitespace runs collapsed to one space.
    pub summary: String,
    /// The file the summary came from.
    pub summary_from: PathBuf,
}

/// Why a case cannot be read; `sources` holds the report when a label points into it.
#[derive(Debug)]
pub struct CaseError {
    pub diag: Diagnostic,
    pub sources: SourceMap,
}

impl From<Diagnostic> for CaseError {
    fn from(diag: Diagnostic) -> Self {
        CaseError { diag, sources: SourceMap::default() }
    }
}

/// Read a case directory: the sketch and the summary (`Summary` of `crash_report.xml`, else
/// `Summary.txt`). Nothing is sent anywhere until both are usable.
pub fn read_case(dir: &Path) -> Result<Case, CaseError> {
    let shown = dir.display();
    if !dir.is_dir() {
        return Err(Diagnostic::error("E0850", format!("`{shown}` is not a case directory"))
            .help("pass a CIREN case folder holding sketch.jpeg and crash_report.xml (or Sketch.jpg and Summary.txt)")
            .into());
    }
    let Some(sketch) = SKETCH_NAMES.iter().map(|n| dir.join(n)).find(|p| p.is_file()) else {
        return Err(Diagnostic::error("E0850", format!("case `{shown}` has no sketch image"))
            .help(format!("looked for {}; the sketch is what the vision model reads", SKETCH_NAMES.join(", ")))
            .into());
    };
    let image = read_sketch(&sketch)?;
    let report = dir.join("crash_report.xml");
    let txt = dir.join("Summary.txt");
    let (summary, from, xml_id) = if report.is_file() {
        let (s, id) = summary_from_report(&report)?;
        (s, report, id)
    } else if txt.is_file() {
        (summary_from_text(&txt)?, txt, None)
    } else {
        return Err(Diagnostic::error("E0851", format!("case `{shown}` has no crash summary"))
            .help("the case needs crash_report.xml (its `Summary` element) or Summary.txt")
            .into());
    };
    let summary = summary.split_whitespace().collect::<Vec<_>>().join(" ");
    if summary.is_empty() {
        return Err(Diagnostic::error("E0851", format!("the crash summary in `{}` is empty", from.display()))
            .help("the VLM route needs the narrative; the coded fields alone go through `rocc ciren import`")
            .into());
    }
    if summary.len() > MAX_SUMMARY_BYTES {
        return Err(Diagnostic::error(
            "E0855",
            format!(
                "the crash summary in `{}` is {} bytes (at most {MAX_SUMMARY_BYTES})",
                from.display(),
                summary.len()
            ),
        )
        .help("a CIREN summary is a few paragraphs; shorten the file to the crash narrative")
        .into());
    }
    let raw_id =
        xml_id.unwrap_or_else(|| dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default());
    let id: String = raw_id.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    let id = if id.is_empty() { "case".to_string() } else { id };
    Ok(Case { id, sketch, image, summary, summary_from: from })
}

fn read_sketch(path: &Path) -> Result<Image, CaseError> {
    let shown = path.display();
    let unreadable = |e: std::io::Error| {
        Diagnostic::error("E0850", format!("cannot read `{shown}`: {e}")).help("check the file's permissions")
    };
    let len = std::fs::metadata(path).map_err(unreadable)?.len();
    // Checked before reading: a multi-gigabyte file is refused without loading it.
    if len > MAX_IMAGE_BYTES as u64 {
        return Err(Diagnostic::error("E0854", format!("sketch `{shown}` is {len} bytes (at most {MAX_IMAGE_BYTES})"))
            .help(
                "scale it down, e.g. `convert sketch.jpeg -resize 2048x2048 sketch.jpeg`; servers refuse larger images",
            )
            .into());
    }
    let bytes = std::fs::read(path).map_err(unreadable)?;
    let Some(mime) = Image::sniff(&bytes) else {
        return Err(Diagnostic::error("E0854", format!("sketch `{shown}` is not a JPEG, PNG, GIF or WebP image"))
            .help("its first bytes are not an image header; replace it with the case's scene diagram")
            .into());
    };
    Ok(Image::from_bytes(&bytes, mime))
}

fn utf8(path: &Path, bytes: Vec<u8>) -> Result<String, Diagnostic> {
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let raw = e.into_bytes();
        let line = raw[..at].iter().filter(|b| **b == b'\n').count() + 1;
        Diagnostic::error(
            "E0853",
            format!("`{}` is not UTF-8: byte 0x{:02X} at offset {at} (line {line})", path.display(), raw[at]),
        )
        .help(format!("convert it, e.g. `iconv -f latin1 -t utf-8 {0} > fixed && mv fixed {0}`", path.display()))
    })
}

fn read_capped(path: &Path, cap: u64) -> Result<Vec<u8>, Diagnostic> {
    let unreadable = |e: std::io::Error| {
        Diagnostic::error("E0851", format!("cannot read `{}`: {e}", path.display()))
            .help("check the file's permissions")
    };
    let len = std::fs::metadata(path).map_err(unreadable)?.len();
    if len > cap {
        return Err(Diagnostic::error("E0855", format!("`{}` is {len} bytes (at most {cap})", path.display()))
            .help("this is not a CIREN case file; real reports are about 100 KiB"));
    }
    std::fs::read(path).map_err(unreadable)
}

/// The `Summary` element's text and the report's `CaseID`.
fn summary_from_report(path: &Path) -> Result<(String, Option<String>), CaseError> {
    let text = utf8(path, read_capped(path, MAX_REPORT_BYTES)?)?;
    let shown = path.display().to_string();
    let doc = match roxmltree::Document::parse(&text) {
        Ok(d) => d,
        Err(e) => {
            let pos = e.pos();
            let offset = offset_of(&text, pos.row as usize, pos.col as usize);
            let mut sources = SourceMap::default();
            let file = sources.add(shown.clone(), text.clone());
            let end = text[offset..].chars().next().map_or(offset, |c| offset + c.len_utf8());
            let diag = Diagnostic::error("E0852", format!("`{shown}` is not well-formed XML: {e}"))
                .label(Span::new(file, offset, end), "here")
                .help("the file is damaged or not a CIREN case record; fetch it again");
            return Err(CaseError { diag, sources });
        }
    };
    let id = doc.root_element().attribute("CaseID").map(str::to_string).filter(|s| !s.trim().is_empty());
    let Some(node) = doc.descendants().find(|n| n.has_tag_name("Summary")) else {
        return Err(Diagnostic::error("E0851", format!("`{shown}` has no `Summary` element"))
            .help("the VLM route needs the crash narrative (CaseSummary/Summary); put it in Summary.txt beside the sketch")
            .into());
    };
    let summary: String = node.descendants().filter(|n| n.is_text()).filter_map(|n| n.text()).collect();
    Ok((summary, id))
}

fn summary_from_text(path: &Path) -> Result<String, CaseError> {
    Ok(utf8(path, read_capped(path, MAX_SUMMARY_BYTES as u64 * 4)?)?)
}

/// Byte offset of a 1-based (row, column-in-characters) position.
fn offset_of(text: &str, row: usize, col: usize) -> usize {
    let line_start = text.split_inclusive('\n').take(row.saturating_sub(1)).map(str::len).sum::<usize>();
    let line = &text[line_start.min(text.len())..];
    line_start + line.char_indices().nth(col.saturating_sub(1)).map_or(line.len(), |(i, _)| i)
}

/// A worked example: a faithful `.scn` recreation of a case, with its conflict block.
#[derive(Clone, Debug)]
pub struct Example {
    pub name: String,
    pub text: String,
    pub roster: Roster,
    pub descriptor: Descriptor,
}

impl Example {
    /// The example, or why it is unusable: it must check and have a conflict block.
    pub fn new(name: &str, text: &str) -> Result<Example, String> {
        let mut sources = SourceMap::default();
        let base = std::env::temp_dir();
        let s = crate::check::check_text(name, text, &base, &mut sources).map_err(|d| {
            d.first().map_or_else(|| "it does not check".to_string(), |d| format!("{}: {}", d.code, d.message))
        })?;
        let roster = Roster::of(&s);
        let descriptor =
            descriptor::of_scene(text, &roster).ok_or_else(|| "it has no usable `conflict` block".to_string())?;
        Ok(Example { name: name.to_string(), text: text.to_string(), roster, descriptor })
    }
}

/// The compiled-in examples of `prompts/ciren/`.
pub fn builtin_examples() -> Vec<Example> {
    EXAMPLES.iter().filter_map(|(n, t)| Example::new(n, t).ok()).collect()
}

/// Every `.scn` file of a directory, sorted by name, each checked (E0858 when one is unusable).
pub fn load_examples(dir: &Path) -> Result<Vec<Example>, Diagnostic> {
    let bad = |m: String| Diagnostic::error("E0858", m);
    let rd = std::fs::read_dir(dir).map_err(|e| {
        bad(format!("cannot read --examples `{}`: {e}", dir.display())).help("pass a directory of .scn files")
    })?;
    let mut paths: Vec<PathBuf> =
        rd.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|x| x == "scn")).collect();
    paths.sort();
    if paths.is_empty() {
        return Err(bad(format!("--examples `{}` holds no .scn file", dir.display()))
            .help("e.g. the output directory of `rocc ciren import`"));
    }
    let mut out = vec![];
    for p in paths {
        let text = std::fs::read_to_string(&p).map_err(|e| {
            bad(format!("cannot read example `{}`: {e}", p.display())).help("examples are UTF-8 .scn files")
        })?;
        let name = p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let ex = Example::new(&name, &text).map_err(|why| {
            bad(format!("example `{}` is unusable: {why}", p.display()))
                .help("an example must pass `rocc check` and carry a `conflict` block")
        })?;
        out.push(ex);
    }
    Ok(out)
}

/// The examples as the scene call sees them: whole files, conflict blocks removed.
fn scene_examples(ex: &[Example]) -> String {
    ex.iter().map(|e| descriptor::strip(&e.text).trim().to_string()).collect::<Vec<_>>().join("\n\n")
}

/// The examples as the conflict call sees them: the file's notes, its parties, the answer.
fn conflict_examples(ex: &[Example]) -> String {
    ex.iter()
        .map(|e| {
            let notes: Vec<&str> = e
                .text
                .lines()
                .take_while(|l| !l.trim_start().starts_with("scenario"))
                .filter_map(|l| l.trim().strip_prefix("//"))
                .map(str::trim)
                .collect();
            format!("Notes: {}\nAgents: {}\nAnswer: {}", notes.join(" "), e.roster.describe(), e.descriptor.to_json())
        })
        .collect::<Vec<_>>()
        .join("\n\n")
}

#[derive(Clone, Debug)]
pub struct Options {
    pub client: ClientConfig,
    pub max_repairs: u32,
    /// Send grammar / JSON-schema constraints where the server takes them.
    pub constrain: bool,
    /// Scenario seed; default the case id.
    pub seed: Option<u64>,
    pub examples: Vec<Example>,
}

/// How a run ended.
#[derive(Debug)]
pub enum Outcome {
    /// The scene with its conflict, checked.
    Accepted { text: String },
    /// The scene never checked; `text` is its last attempt.
    SceneRejected { text: String, diags: Vec<Diagnostic>, sources: SourceMap },
    /// The scene checked but no conflict did: `text` is the last merged attempt (the bare scene
    /// when no reply held a usable descriptor).
    ConflictRejected { text: String, diags: Vec<Diagnostic>, sources: SourceMap },
    /// A client error or an unusable case.
    Failed(Diagnostic),
}

/// Everything that happened, for the CLI's messages and `--transcript`.
#[derive(Debug, Default)]
pub struct Run {
    pub exchanges: Vec<Exchange>,
    /// Scene files checked, in order.
    pub attempts: Vec<String>,
    /// The accepted scene, before the merge.
    pub scene: Option<String>,
    /// Replies of the conflict call, in order.
    pub conflict_replies: Vec<String>,
    /// Merged files checked, in order.
    pub merged: Vec<String>,
    pub descriptor: Option<Descriptor>,
}

impl Run {
    pub fn transcript(&self, case: &Case, opts: &Options, seed: u64) -> Value {
        let c = &opts.client;
        let versions: serde_json::Map<String, Value> =
            [scene_prompt(), conflict_prompt(), prompts::repair(), prompts::dsl()]
                .iter()
                .map(|p| (p.name.to_string(), json!(p.version)))
                .collect();
        json!({
            "rocc_version": env!("CARGO_PKG_VERSION"),
            "prompts": versions,
            "examples": opts.examples.iter().map(|e| e.name.clone()).collect::<Vec<_>>(),
            "case": case.id,
            "sketch": case.sketch.display().to_string(),
            "summary_from": case.summary_from.display().to_string(),
            "summary": case.summary,
            "server": c.server,
            "endpoint": c.endpoint,
            "model": c.model,
            "max_repairs": opts.max_repairs,
            "seed": seed,
            "scene_attempts": self.attempts,
            "scene": self.scene,
            "conflict_replies": self.conflict_replies,
            "descriptor": self.descriptor,
            "merged_attempts": self.merged,
            "exchanges": client::redact_images(&json!(self.exchanges)),
        })
    }
}

/// The scenario seed of a case: its number when the id is one, else a hash of it.
pub fn default_seed(id: &str) -> u64 {
    id.parse::<u64>().unwrap_or_else(|_| crate::fsio::fnv1a(id.as_bytes()))
}

/// rocc's decisions, re-imposed on every scene the model writes: no conflict block (the
/// conflict call writes it), the seed, the scenario name.
fn fix_scene(text: &str, seed: u64, name: &str) -> String {
    let t = repair::enforce(&descriptor::strip(text), seed, None, None);
    let Ok(file) = crate::syntax::parse(0, &t) else { return t };
    let Some(sc) =
        file.items.iter().find_map(|i| if let crate::syntax::ast::Item::Scenario(s) = i { Some(s) } else { None })
    else {
        return t;
    };
    let mut out = t.clone();
    out.replace_range(sc.name.span.range(), name);
    out
}

/// Case -> checked scenario text with its conflict. `name` is the file name diagnostics use
/// (the `-o` file's), `base` the directory `use` imports resolve against.
pub fn extract(case: &Case, opts: &Options, name: &str, base: &Path) -> (Outcome, Run) {
    let mut run = Run::default();
    let mut client = match Client::new(opts.client.clone()) {
        Ok(c) => c,
        Err(d) => return (Outcome::Failed(d), run),
    };
    let outcome = match go(&mut client, case, opts, name, base, &mut run) {
        Ok(o) => o,
        Err(d) => Outcome::Failed(d),
    };
    (outcome, run)
}

fn go(
    client: &mut Client,
    case: &Case,
    opts: &Options,
    name: &str,
    base: &Path,
    run: &mut Run,
) -> Result<Outcome, Diagnostic> {
    let seed = opts.seed.unwrap_or_else(|| default_seed(&case.id));
    let scenario_name = format!("ciren_{}", case.id);
    let images = std::slice::from_ref(&case.image);

    // ---- 1. scene: sketch + summary -> .scn, checked and repaired like `rocc text` ----
    let (system, user) = scene_prompt().render(&[
        ("dsl", prompts::dsl().text()),
        ("case", &case.id),
        ("examples", &scene_examples(&opts.examples)),
        ("summary", &case.summary),
    ]);
    let messages = vec![message("system", &system, &[]), message("user", &user, images)];
    let reply = client.chat("scene", &messages, &repair::scn_constraint(client, opts.constrain), &mut run.exchanges)?;
    let fix = |t: &str| fix_scene(t, seed, &scenario_name);
    let (text, verdict) = repair::candidate(&reply, &fix, name, base);
    run.attempts.push(text.clone());
    let session = repair::Session {
        client,
        log: &mut run.exchanges,
        attempts: &mut run.attempts,
        max_repairs: opts.max_repairs,
        constrain: opts.constrain,
        name,
        base,
        description: &case.summary,
    };
    let scene = match session.repair(text, verdict, &fix)? {
        llm::Outcome::Accepted { text } => text,
        llm::Outcome::Rejected { text, diags, sources } => return Ok(Outcome::SceneRejected { text, diags, sources }),
        llm::Outcome::Failed(d) => return Err(d),
    };
    run.scene = Some(scene.clone());

    // ---- 2. conflict: one greedy call, merged by span; only this call is repeated ----
    let mut sources = SourceMap::default();
    let checked = match crate::check::check_text(name, &scene, base, &mut sources) {
        Ok(s) => s,
        // Formatting never changes meaning (tested), so this is only a guard.
        Err(diags) => return Ok(Outcome::SceneRejected { text: scene, diags, sources }),
    };
    let roster = Roster::of(&checked);
    if roster.movers().is_empty() {
        let d = Diagnostic::error("E0857", "the extracted scene has no moving agent to be at fault")
            .help("the scene call wrote only fixed objects; run again or use a stronger model");
        return Ok(Outcome::ConflictRejected { text: scene, diags: vec![d], sources: SourceMap::default() });
    }
    let (system, user) = conflict_prompt().render(&[
        ("movers", &roster.movers().join(", ")),
        ("names", &roster.names().join(", ")),
        ("duration", &crate::llm::schema::num(roster.duration_s)),
        ("examples", &conflict_examples(&opts.examples)),
        ("summary", &case.summary),
        ("scene", scene.trim()),
    ]);
    let mut messages = vec![message("system", &system, &[]), message("user", &user, images)];
    let constraint = if opts.constrain { Constraint::Json(descriptor::json_schema(&roster)) } else { Constraint::None };
    // Greedy, whatever --temperature says: the same scene and case give the same conflict.
    client.set_temperature(0.0);
    client.set_max_tokens(opts.client.max_tokens.min(256));
    let mut round = 0;
    loop {
        let stage = if round == 0 { "conflict".to_string() } else { format!("conflict repair {round}") };
        let reply = client.chat(&stage, &messages, &constraint, &mut run.exchanges)?;
        run.conflict_replies.push(reply.clone());
        let (diags, sources, feedback, kept) = match descriptor::parse(&reply, &roster) {
            Ok(d) => {
                let merged = descriptor::merge(&scene, &d.blocks()).unwrap_or_else(|| scene.clone());
                run.merged.push(merged.clone());
                match repair::check(name, &merged, base) {
                    Ok(()) => {
                        run.descriptor = Some(d);
                        return Ok(Outcome::Accepted { text: merged });
                    }
                    Err((diags, sources)) => {
                        let fb = format!(
                            "the scene with `{}` fails the checker:\n{}",
                            d.blocks(),
                            repair::diagnostics_json(&diags, &sources)
                        );
                        (diags, sources, fb, merged)
                    }
                }
            }
            Err(why) => {
                let d = Diagnostic::error("E0857", format!("the conflict reply cannot be used: {why}"))
                    .help(format!("the model's last reply: `{}`; `rocc explain E0857`", client::excerpt(&reply, 200)));
                (vec![d], SourceMap::default(), why, scene.clone())
            }
        };
        if round == opts.max_repairs {
            return Ok(Outcome::ConflictRejected { text: kept, diags, sources });
        }
        round += 1;
        messages.push(message("assistant", &reply, &[]));
        messages.push(message(
            "user",
            &format!("That answer cannot be used: {feedback}\nAnswer again with the JSON object only."),
            &[],
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worked_examples_check_and_carry_their_conflict() {
        let ex = builtin_examples();
        assert_eq!(ex.len(), EXAMPLES.len(), "every file of prompts/ciren/ is a usable example");
        let blocks: Vec<String> = ex.iter().map(|e| e.descriptor.block()).collect();
        assert_eq!(
            blocks,
            [
                "conflict { at_fault v2; struck v1; impact angle; point right; at 4 s }",
                "conflict { at_fault v1; struck obj1; impact object; point front; at 4 s }",
            ]
        );
        let shown = scene_examples(&ex);
        assert!(!shown.contains("conflict {") && shown.contains("scenario ciren_100237"), "{shown}");
        let shown = conflict_examples(&ex);
        assert!(
            shown.contains(r#"Answer: {"at":4.0,"at_fault":"v2","impact":"angle","point":"right","struck":"v1"}"#),
            "{shown}"
        );
        assert!(shown.contains("Agents: obj1 (tree, fixed), v1 (sedan)"), "{shown}");
    }

    #[test]
    fn worked_examples_stage_the_coded_contact() {
        // 100237: V2's front into V1's right side (coded); 105165: V1's front into the tree.
        for file in ["100237.scn", "105165.scn"] {
            let ex = builtin_examples().into_iter().find(|e| e.name == file).unwrap();
            let mut sources = SourceMap::default();
            let s = crate::check::check_text(file, &ex.text, Path::new("."), &mut sources).unwrap();
            let front = crate::compile::front(s, None).unwrap();
            let hit = front.tracks.impacts.first().unwrap_or_else(|| panic!("{file}: no impact staged"));
            let names = (&front.tracks.agents[hit.at_fault].name, &front.tracks.agents[hit.struck].name);
            assert_eq!(
                (names.0.as_str(), names.1.as_str()),
                (ex.descriptor.at_fault.as_str(), ex.descriptor.struck.as_str())
            );
            // A trunk is narrower than a bumper, so its contact "side" is a corner of a 0.5 m
            // box; the coded side of a tree crash is the striker's (AreaOfDamage = Front).
            if ex.descriptor.impact != "object" {
                let side = crate::check::scenario::POINTS.iter().find(|p| p.1 == hit.struck_side).unwrap().0;
                assert_eq!(side, ex.descriptor.point, "{file}: contact on the struck party's {side}");
            }
            let half = front.tracks.agents[hit.at_fault].size[0] / 2.0;
            assert!(
                hit.at_fault_local[0] > 0.5 * half,
                "{file}: the striker's front makes contact: {:?}",
                hit.at_fault_local
            );
        }
    }

    #[test]
    fn every_example_file_is_compiled_in() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("prompts/ciren");
        let mut on_disk: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".scn"))
            .collect();
        on_disk.sort();
        let listed: Vec<&str> = EXAMPLES.iter().map(|e| e.0).collect();
        assert_eq!(on_disk, listed, "add new example files to EXAMPLES");
        assert_eq!(load_examples(&dir).unwrap().len(), listed.len());
    }

    #[test]
    fn prompts_have_versions_and_user_parts() {
        for p in [scene_prompt(), conflict_prompt()] {
            assert!(p.version.starts_with('v'), "{}", p.name);
            let (_, user) = p.render(&[("summary", "S")]);
            assert!(user.contains('S'), "{} has no `## user` part with the summary", p.name);
        }
    }

    #[test]
    fn fix_scene_sets_seed_and_name_and_drops_conflicts() {
        let t = "scenario x {\n    seed 3\n    duration 4 s\n    conflict { at_fault a; struck b; impact angle; point left }\n}\n";
        assert_eq!(fix_scene(t, 7, "ciren_1"), "scenario ciren_1 {\n    seed 7\n    duration 4 s\n}\n");
        assert_eq!(default_seed("100237"), 100237);
        assert_ne!(default_seed("abc"), default_seed("abd"));
    }

    #[test]
    fn xml_positions_become_byte_offsets() {
        assert_eq!(offset_of("ab\ncdé\nx", 2, 3), 5);
        assert_eq!(offset_of("ab\ncdé\nx", 3, 1), 8);
        assert_eq!(offset_of("ab", 9, 9), 2);
    }
}
