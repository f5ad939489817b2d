//! The conflict descriptor of the VLM route: who struck whom, how and where, as the model's
//! second (greedy) call states it. In: the reply text and the roster of the checked scene. Out:
//! a validated `Descriptor`, its `conflict { ... }` block, and the scene text with that block
//! merged in by AST span, every byte outside the block untouched.

use crate::check::scenario::{IMPACTS, Motion, POINTS, Scenario};
use crate::syntax::ast::{FieldValue, Item, ScenarioStmt};
use serde::Serialize;
use serde_json::{Value, json};

/// What the conflict call may name: the scene's agents and objects, and the clip length.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Roster {
    /// (name, kind, static) in declaration order.
    pub parties: Vec<(String, String, bool)>,
    pub duration_s: f64,
}

impl Roster {
    pub fn of(s: &Scenario) -> Roster {
        Roster {
            parties: s
                .agents
                .iter()
                .map(|a| {
                    let kind = a.kinds.first().cloned().unwrap_or_default();
                    (a.name.clone(), kind, a.is_object || a.motion == Motion::Static)
                })
                .collect(),
            duration_s: s.duration,
        }
    }
    pub fn movers(&self) -> Vec<&str> {
        self.parties.iter().filter(|p| !p.2).map(|p| p.0.as_str()).collect()
    }
    pub fn names(&self) -> Vec<&str> {
        self.parties.iter().map(|p| p.0.as_str()).collect()
    }
    /// `v1 (sedan), v2 (suv), obj1 (tree, fixed)`, for prompts.
    pub fn describe(&self) -> String {
        self.parties
            .iter()
            .map(|(n, k, st)| if *st { format!("{n} ({k}, fixed)") } else { format!("{n} ({k})") })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Descriptor {
    pub at_fault: String,
    pub struck: String,
    pub impact: String,
    pub point: String,
    /// Seconds into the clip; `None` leaves the checker's default.
    pub at_s: Option<f64>,
    /// Later contacts of the same crash, in time order (a chain: each strikes once, before it is
    /// struck; the checker enforces it).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub later: Vec<Descriptor>,
}

impl Descriptor {
    /// The block in canonical one-line form (`rocc fmt` keeps it on one line).
    pub fn block(&self) -> String {
        let at = self.at_s.map(|t| format!("; at {} s", crate::llm::schema::num(t))).unwrap_or_default();
        format!(
            "conflict {{ at_fault {}; struck {}; impact {}; point {}{at} }}",
            self.at_fault, self.struck, self.impact, self.point
        )
    }

    /// Every block, this one then the later ones, one per line at statement indent.
    pub fn blocks(&self) -> String {
        let mut all = vec![self.block()];
        all.extend(self.later.iter().map(Descriptor::block));
        all.join("\n    ")
    }

    pub fn to_json(&self) -> Value {
        let mut v =
            json!({"at_fault": self.at_fault, "struck": self.struck, "impact": self.impact, "point": self.point});
        if let Some(t) = self.at_s {
            v["at"] = json!(t);
        }
        if !self.later.is_empty() {
            v["later"] = Value::Array(self.later.iter().map(Descriptor::to_json).collect());
        }
        v
    }
}

/// The JSON schema the conflict reply is constrained by: names from the roster, words from the
/// checker's vocabularies.
pub fn json_schema(r: &Roster) -> Value {
    let mut one = one_schema(r);
    one["properties"]["later"] = json!({"type": "array", "maxItems": MAX_LATER, "items": one_schema(r)});
    one
}

/// Later contacts a reply may list.
const MAX_LATER: usize = 4;

/// The schema of one contact.
fn one_schema(r: &Roster) -> Value {
    json!({
        "type": "object",
        "properties": {
            "at_fault": {"type": "string", "enum": r.movers()},
            "struck": {"type": "string", "enum": r.names()},
            "impact": {"type": "string", "enum": IMPACTS.iter().map(|x| x.0).collect::<Vec<_>>()},
            "point": {"type": "string", "enum": POINTS.iter().map(|x| x.0).collect::<Vec<_>>()},
            "at": {"type": "number", "minimum": 0, "maximum": r.duration_s},
        },
        "required": ["at_fault", "struck", "impact", "point", "at"],
        "additionalProperties": false,
    })
}

/// Read a reply: one JSON object (code fences and chatter around it tolerated), or a DSL
/// `conflict { ... }` block. `Err` says what is wrong, in words the model gets back.
pub fn parse(reply: &str, r: &Roster) -> Result<Descriptor, String> {
    if let Some(v) = json_object(reply) {
        return from_json_all(&v, r);
    }
    let mut blocks = dsl_blocks(reply).into_iter();
    let Some(first) = blocks.next() else {
        return Err("the reply holds neither a JSON object nor a `conflict { ... }` block".to_string());
    };
    let mut d = validate(first?, r)?;
    for b in blocks {
        d.later.push(validate(b?, r)?);
    }
    check_later(&d)?;
    Ok(d)
}

/// One JSON answer and its `later` list.
fn from_json_all(v: &Value, r: &Roster) -> Result<Descriptor, String> {
    let mut d = validate(from_json(v)?, r)?;
    match v.get("later") {
        None | Some(Value::Null) => {}
        Some(Value::Array(list)) => {
            for (i, x) in list.iter().enumerate() {
                let raw = from_json(x).map_err(|e| format!("`later[{i}]`: {e}"))?;
                d.later.push(validate(raw, r).map_err(|e| format!("`later[{i}]`: {e}"))?);
            }
        }
        Some(other) => return Err(format!("`later` must be a list of contacts, not {other}")),
    }
    check_later(&d)?;
    Ok(d)
}

/// At most `MAX_LATER` later contacts, none before the first.
fn check_later(d: &Descriptor) -> Result<(), String> {
    if d.later.len() > MAX_LATER {
        return Err(format!("{} later contacts; at most {MAX_LATER}", d.later.len()));
    }
    let mut prev = d.at_s.unwrap_or(0.0);
    for (i, l) in d.later.iter().enumerate() {
        let t = l.at_s.unwrap_or(prev);
        if t < prev {
            return Err(format!("`later[{i}]` at {t} s comes before the contact listed ahead of it"));
        }
        prev = t;
    }
    Ok(())
}

/// Field values as the model wrote them, before validation.
struct Raw {
    at_fault: Option<String>,
    struck: Option<String>,
    impact: Option<String>,
    point: Option<String>,
    at: Option<Result<f64, String>>,
}

fn json_object(reply: &str) -> Option<Value> {
    let a = reply.find('{')?;
    let b = reply.rfind('}')?;
    if b < a {
        return None;
    }
    serde_json::from_str::<Value>(&reply[a..=b]).ok().filter(Value::is_object)
}

fn from_json(v: &Value) -> Result<Raw, String> {
    // The SAFE extraction format's names are accepted too: models trained on it use them.
    let get = |keys: &[&str]| -> Option<&Value> { keys.iter().find_map(|k| v.get(*k)).filter(|x| !x.is_null()) };
    let text = |keys: &[&str]| -> Result<Option<String>, String> {
        match get(keys) {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s.clone())),
            Some(other) => Err(format!("`{}` must be a string, not {other}", keys[0])),
        }
    };
    let at = get(&["at", "time", "at_s"]).map(|x| match x {
        Value::Number(n) => n.as_f64().ok_or_else(|| format!("`at` {n} is not a number")),
        Value::String(s) => seconds(s),
        other => Err(format!("`at` must be a number of seconds, not {other}")),
    });
    Ok(Raw {
        at_fault: text(&["at_fault", "at_fault_vehicle", "striking", "striking_vehicle"])?,
        struck: text(&["struck", "struck_vehicle", "struck_party"])?,
        impact: text(&["impact", "impact_type"])?,
        point: text(&["point", "point_of_impact"])?,
        at,
    })
}

/// `4`, `4 s`, `4.5s`, `4000 ms`.
fn seconds(s: &str) -> Result<f64, String> {
    let t = s.trim();
    let (num, scale) = if let Some(n) = t.strip_suffix("ms") {
        (n, 1e-3)
    } else if let Some(n) = t.strip_suffix('s') {
        (n, 1.0)
    } else {
        (t, 1.0)
    };
    num.trim().parse::<f64>().map(|x| x * scale).map_err(|_| format!("`at` `{s}` is not a time such as `3 s`"))
}

/// Every `conflict { ... }` block of the reply, in order.
fn dsl_blocks(reply: &str) -> Vec<Result<Raw, String>> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(i) = reply[from..].find("conflict") {
        let start = from + i;
        let Some(close) = reply[start..].find('}') else { break };
        match dsl_block(&reply[start..=start + close]) {
            Some(b) => out.push(b),
            None => break,
        }
        from = start + close + 1;
    }
    out
}

/// A `conflict { ... }` block anywhere in the reply, read with the language's own parser.
fn dsl_block(reply: &str) -> Option<Result<Raw, String>> {
    let start = reply.find("conflict")?;
    let open = start + reply[start..].find('{')?;
    let close = open + reply[open..].find('}')?;
    let block = &reply[start..=close];
    let wrapped = format!("scenario x {{\n{block}\n}}\n");
    let file = match crate::syntax::parse(0, &wrapped) {
        Ok(f) => f,
        Err(d) => return Some(Err(format!("the conflict block does not parse: {}", d.message))),
    };
    let c = file.items.iter().find_map(|i| match i {
        Item::Scenario(s) => s.stmts.iter().find_map(|st| match st {
            ScenarioStmt::Conflict(c) => Some(c),
            _ => None,
        }),
        _ => None,
    })?;
    let mut raw = Raw { at_fault: None, struck: None, impact: None, point: None, at: None };
    for f in &c.fields {
        let text = wrapped[f.value_span().range()].to_string();
        let word = match &f.value {
            FieldValue::Ident(i) => Some(i.name.clone()),
            FieldValue::Value(_) => None,
        };
        match f.key.as_str() {
            "at_fault" => raw.at_fault = word.or(Some(text)),
            "struck" => raw.struck = word.or(Some(text)),
            "impact" => raw.impact = word.or(Some(text)),
            "point" => raw.point = word.or(Some(text)),
            _ => raw.at = Some(seconds(&text)),
        }
    }
    Some(Ok(raw))
}

trait ValueSpan {
    fn value_span(&self) -> crate::source::Span;
}
impl ValueSpan for crate::syntax::ast::ConflictField {
    fn value_span(&self) -> crate::source::Span {
        match &self.value {
            FieldValue::Ident(i) => i.span,
            FieldValue::Value(v) => v.span,
        }
    }
}

/// `right side` -> `right`, `Rear-End` -> `rear_end`, `front left` -> `front_left`.
fn word(s: &str) -> String {
    let w = s.trim().to_ascii_lowercase();
    let w = w.strip_suffix(" side").or_else(|| w.strip_suffix("_side")).unwrap_or(&w);
    w.split([' ', '-', '_']).filter(|p| !p.is_empty()).collect::<Vec<_>>().join("_")
}

/// A roster name from what the model wrote: exact, case-folded, or `V1` / `Vehicle 1` /
/// `vehicle#1` for `v1`.
fn name<'r>(s: &str, r: &'r Roster) -> Option<&'r str> {
    let names = r.names();
    if let Some(n) = names.iter().find(|n| **n == s.trim()) {
        return Some(n);
    }
    let folded: String = s.trim().to_ascii_lowercase().chars().filter(|c| !c.is_whitespace()).collect();
    if let Some(n) = names.iter().find(|n| n.to_ascii_lowercase() == folded) {
        return Some(n);
    }
    let digits = ["vehicle#", "vehicle", "veh", "v"].iter().find_map(|p| folded.strip_prefix(p))?;
    let n: u32 = digits.parse().ok()?;
    names.into_iter().find(|x| *x == format!("v{n}"))
}

fn validate(raw: Raw, r: &Roster) -> Result<Descriptor, String> {
    let mut missing = vec![];
    for (k, v) in [("at_fault", &raw.at_fault), ("struck", &raw.struck), ("impact", &raw.impact), ("point", &raw.point)]
    {
        if v.is_none() {
            missing.push(k);
        }
    }
    let (Some(f), Some(s), Some(i), Some(p)) = (raw.at_fault, raw.struck, raw.impact, raw.point) else {
        return Err(format!("the answer has no {}", missing.join(", ")));
    };
    let names = r.names().join(", ");
    let at_fault = name(&f, r).ok_or_else(|| format!("`at_fault` `{f}` is not in the scene (its parties: {names})"))?;
    let struck = name(&s, r).ok_or_else(|| format!("`struck` `{s}` is not in the scene (its parties: {names})"))?;
    if !r.movers().contains(&at_fault) {
        return Err(format!("`at_fault` `{at_fault}` is a fixed object; the at-fault party must move"));
    }
    if at_fault == struck {
        return Err(format!("`at_fault` and `struck` are both `{at_fault}`; name two different parties"));
    }
    let impact = word(&i);
    if !IMPACTS.iter().any(|x| x.0 == impact) {
        let all: Vec<&str> = IMPACTS.iter().map(|x| x.0).collect();
        return Err(format!("`impact` `{i}` is not one of {}", all.join(", ")));
    }
    let point = word(&p);
    if !POINTS.iter().any(|x| x.0 == point) {
        let all: Vec<&str> = POINTS.iter().map(|x| x.0).collect();
        return Err(format!("`point` `{p}` is not one of {}", all.join(", ")));
    }
    if let (Some(&(_, imp)), Some(&(_, pt))) =
        (IMPACTS.iter().find(|x| x.0 == impact), POINTS.iter().find(|x| x.0 == point))
    {
        let fits = crate::check::points_for(imp);
        if !fits.contains(&pt) {
            let ok: Vec<&str> = POINTS.iter().filter(|x| fits.contains(&x.1)).map(|x| x.0).collect();
            return Err(format!(
                "`impact` {impact} cannot hit `point` {point} (E0120); with {impact} the point is one of {}",
                ok.join(", ")
            ));
        }
    }
    let at_s = match raw.at {
        None => None,
        Some(Err(e)) => return Err(e),
        Some(Ok(t)) if t.is_finite() && t > 0.0 && t <= r.duration_s => Some(t),
        Some(Ok(t)) => return Err(format!("`at` {t} is outside the clip (0 to {} s)", r.duration_s)),
    };
    Ok(Descriptor {
        at_fault: at_fault.to_string(),
        struck: struck.to_string(),
        impact,
        point,
        at_s,
        later: Vec::new(),
    })
}

/// Byte ranges of the scene's `conflict` blocks, in order, and where a new block goes when
/// there is none: just before the scenario's closing brace.
fn conflict_spans(scene: &str) -> Option<(Vec<(usize, usize)>, usize)> {
    let file = crate::syntax::parse(0, scene).ok()?;
    let sc = file.items.iter().find_map(|i| if let Item::Scenario(s) = i { Some(s) } else { None })?;
    let spans = sc
        .stmts
        .iter()
        .filter_map(|s| {
            if let ScenarioStmt::Conflict(c) = s { Some((c.span.start as usize, c.span.end as usize)) } else { None }
        })
        .collect();
    Some((spans, sc.span.end as usize - 1))
}

/// The scene with `block` as its only conflict: the first existing block is replaced in place,
/// later ones are removed with their lines, and without one the block is inserted on its own
/// line before the scenario's closing brace. Nothing else changes. `None` when the scene does
/// not parse (it always does here: it has passed the checker).
pub fn merge(scene: &str, block: &str) -> Option<String> {
    let (spans, close) = conflict_spans(scene)?;
    let mut out = scene.to_string();
    match spans.split_first() {
        Some((first, rest)) => {
            for &(a, b) in rest.iter().rev() {
                let (a, b) = whole_lines(scene, a, b);
                out.replace_range(a..b, "");
            }
            out.replace_range(first.0..first.1, block);
        }
        None => {
            let line_start = scene[..close].rfind('\n').map_or(0, |i| i + 1);
            if scene[line_start..close].trim().is_empty() {
                // The canonical layout: a blank line, the block indented like any statement.
                out.insert_str(line_start, &format!("\n    {block}\n"));
            } else {
                out.insert_str(close, &format!("; {block} "));
            }
        }
    }
    Some(out)
}

/// Widen `a..b` to whole lines when nothing else shares them, so a removed block leaves no
/// blank line behind.
fn whole_lines(text: &str, a: usize, b: usize) -> (usize, usize) {
    let ls = text[..a].rfind('\n').map_or(0, |i| i + 1);
    let le = text[b..].find('\n').map_or(text.len(), |i| b + i + 1);
    if text[ls..a].trim().is_empty() && text[b..le].trim().is_empty() { (ls, le) } else { (a, b) }
}

/// The byte range of the first conflict block of a scene, for tests and messages.
pub fn first_conflict_span(scene: &str) -> Option<(usize, usize)> {
    conflict_spans(scene)?.0.first().copied()
}

/// The scene with every conflict block removed (the scene call's reply, whose conflict is the
/// conflict call's job; the worked examples shown to the scene call).
pub fn strip(scene: &str) -> String {
    let Some((spans, _)) = conflict_spans(scene) else { return scene.to_string() };
    let mut out = scene.to_string();
    for &(a, b) in spans.iter().rev() {
        let (a, b) = whole_lines(scene, a, b);
        out.replace_range(a..b, "");
    }
    out
}

/// The descriptor of a scene's conflict blocks (the first, then the later ones), as the
/// conflict call would answer it (for the worked examples of the conflict prompt).
pub fn of_scene(scene: &str, r: &Roster) -> Option<Descriptor> {
    let (spans, _) = conflict_spans(scene)?;
    let mut all = spans.iter().map(|&(a, b)| dsl_block(&scene[a..b])?.ok().and_then(|raw| validate(raw, r).ok()));
    let mut d = all.next()??;
    for l in all {
        d.later.push(l?);
    }
    Some(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn roster() -> Roster {
        Roster {
            parties: vec![
                ("v1".into(), "sedan".into(), false),
                ("v2".into(), "suv".into(), false),
                ("obj1".into(), "tree".into(), true),
            ],
            duration_s: 6.0,
        }
    }

    #[test]
    fn json_dsl_and_safe_names_are_read() {
        let r = roster();
        let want = Descriptor {
            at_fault: "v2".into(),
            struck: "v1".into(),
            impact: "angle".into(),
            point: "right".into(),
            at_s: Some(3.0),
            later: Vec::new(),
        };
        let j = r#"Sure: ```json
{"at_fault": "v2", "struck": "v1", "impact": "angle", "point": "right", "at": 3}
```"#;
        assert_eq!(parse(j, &r).unwrap(), want);
        assert_eq!(parse("conflict { at_fault v2; struck v1; impact angle; point right; at 3 s }", &r).unwrap(), want);
        let safe = r#"{"at_fault_vehicle": "V2", "struck_vehicle": "Vehicle 1", "impact_type": "Angle",
            "point_of_impact": "Right side", "at": "3000 ms"}"#;
        assert_eq!(parse(safe, &r).unwrap(), want);
        assert_eq!(want.block(), "conflict { at_fault v2; struck v1; impact angle; point right; at 3 s }");
    }

    #[test]
    fn bad_answers_say_what_is_wrong() {
        let r = roster();
        let bad = |s: &str| parse(s, &r).unwrap_err();
        assert!(bad("the red car hit the blue one").contains("neither"));
        assert!(bad(r#"{"at_fault": "v2", "struck": "v1"}"#).contains("no impact, point"));
        assert!(bad(r#"{"at_fault": "v9", "struck": "v1", "impact": "angle", "point": "right"}"#).contains("v9"));
        assert!(bad(r#"{"at_fault": "obj1", "struck": "v1", "impact": "object", "point": "front"}"#).contains("fixed"));
        assert!(
            bad(r#"{"at_fault": "v1", "struck": "v1", "impact": "angle", "point": "right"}"#).contains("different")
        );
        assert!(bad(r#"{"at_fault": "v1", "struck": "v2", "impact": "tbone", "point": "right"}"#).contains("impact"));
        assert!(bad(r#"{"at_fault": "v1", "struck": "v2", "impact": "angle", "point": "top"}"#).contains("point"));
        assert!(
            bad(r#"{"at_fault": "v1", "struck": "v2", "impact": "angle", "point": "left", "at": 60}"#).contains("clip")
        );
        assert!(bad(r#"{"at_fault": 1, "struck": "v2", "impact": "angle", "point": "left"}"#).contains("string"));
    }

    #[test]
    fn later_contacts_are_read_from_json_and_from_several_blocks() {
        let r = roster();
        let j = r#"{"at_fault": "v2", "struck": "v1", "impact": "angle", "point": "right", "at": 3,
            "later": [{"at_fault": "v1", "struck": "obj1", "impact": "object", "point": "front", "at": 4}]}"#;
        let d = parse(j, &r).unwrap();
        assert_eq!(d.later.len(), 1);
        assert_eq!(
            d.blocks(),
            "conflict { at_fault v2; struck v1; impact angle; point right; at 3 s }\n    \
             conflict { at_fault v1; struck obj1; impact object; point front; at 4 s }"
        );
        assert_eq!(parse(&d.blocks(), &r).unwrap(), d, "the blocks read back");
        assert_eq!(from_json_all(&d.to_json(), &r).unwrap(), d, "the JSON reads back");
        let early = j.replace("\"at\": 4", "\"at\": 2");
        assert!(parse(&early, &r).unwrap_err().contains("before"));
        let bad = j.replace("obj1", "v9");
        assert!(parse(&bad, &r).unwrap_err().contains("later[0]"));
        assert!(json_schema(&r)["properties"]["later"]["items"]["properties"]["at_fault"].is_object());
    }

    const SCENE: &str =
        "// head\nscenario s {\n    seed 1\n    agent a: sedan { at west.in[1], 5 m before center }\n}\n";

    #[test]
    fn merge_inserts_replaces_and_touches_nothing_else() {
        let block = "conflict { at_fault a; struck b; impact angle; point left }";
        let inserted = merge(SCENE, block).unwrap();
        let (a, b) = first_conflict_span(&inserted).unwrap();
        assert_eq!(&inserted[a..b], block);
        let at = SCENE.rfind('}').unwrap();
        assert_eq!(&inserted[..at], &SCENE[..at], "bytes before the insertion point");
        assert!(inserted.ends_with(&format!("    {block}\n}}\n")), "{inserted}");

        let other = "conflict { at_fault b; struck a; impact rear_end; point rear; at 2 s }";
        let replaced = merge(&inserted, other).unwrap();
        assert_eq!(replaced, inserted.replace(block, other), "only the block changes");
        // Extra blocks go, with their lines.
        let two = merge(&format!("{}    {other}\n}}\n", &inserted[..inserted.rfind('}').unwrap()]), block).unwrap();
        assert_eq!(two, inserted);
        assert_eq!(strip(&inserted), format!("{}\n}}\n", &SCENE[..at]));
        // A one-line scene gets the block before its brace.
        let one = merge("scenario s { seed 1 }", block).unwrap();
        assert_eq!(one, format!("scenario s {{ seed 1 ; {block} }}"));
        assert!(crate::syntax::parse(0, &one).is_ok());
        assert!(merge("not a scene", block).is_none());
    }
}
