//! The E0001 syntax error: the place pest could not go on, said in the language's words, with
//! "did you mean" for a misspelt keyword or unit, and the `{` that a missing `}` left open.

use super::rules::Rule;
use crate::diag::{self, Diagnostic};
use crate::source::{FileId, Span};

/// Words the grammar knows as keywords: a misspelt statement keyword gets "did you mean".
const KEYWORDS: &[&str] = &[
    "use",
    "kind",
    "scenario",
    "seed",
    "duration",
    "rate",
    "egos",
    "vehicles",
    "road",
    "traffic",
    "agent",
    "object",
    "row",
    "from",
    "to",
    "every",
    "one_of",
    "at",
    "speed",
    "length",
    "width",
    "height",
    "crosswalk",
    "sidewalk",
    "offset",
    "heading",
    "goal",
    "lateral",
    "away_from",
    "change_lane",
    "stop",
    "behind",
    "after",
    "before",
    "turn",
    "start",
    "track",
    "siren",
    "lights",
    "hazards",
    "beacons",
    "door",
    "yaw",
    "posture",
    "conflict",
    "at_fault",
    "struck",
    "impact",
    "point",
    "near_miss",
    "passer",
    "passed",
    "motion",
    "on",
    "off",
];

const UNITS: &[&str] = &["m", "cm", "km", "m/s", "km/h", "mph", "s", "ms", "deg", "rad", "Hz", "%"];

/// The literal words a rule accepts (for suggestions).
fn rule_words(r: &Rule) -> &'static [&'static str] {
    match r {
        Rule::size_key => &["length", "width", "height"],
        Rule::conflict_key => &["at_fault", "struck", "impact", "point", "at"],
        Rule::near_miss_key => &["passer", "passed", "gap", "side", "at"],
        Rule::lane_dir => &["in", "out"],
        Rule::rel => &["before", "after"],
        Rule::switch => &["on", "off"],
        Rule::unit => UNITS,
        Rule::exp_bound => &["at_least", "at_most"],
        Rule::exp_when => &["during", "by"],
        _ => KEYWORDS
            .iter()
            .find(|k| format!("{r:?}").strip_prefix("kw_") == Some(**k))
            .map_or(&[], std::slice::from_ref),
    }
}

fn rule_name(r: &Rule) -> Option<String> {
    let s = format!("{r:?}");
    if let Some(k) = s.strip_prefix("kw_") {
        return Some(format!("`{k}`"));
    }
    Some(
        match r {
            Rule::EOI => "end of file",
            Rule::file => "`scenario`, `kind` or `use`",
            Rule::ident => "a name",
            Rule::value | Rule::number | Rule::quantity | Rule::range => "a number",
            Rule::integer => "a whole number",
            Rule::unit => "a unit",
            Rule::string => "a quoted path",
            Rule::switch => "`on` or `off`",
            Rule::size_key => "`length`/`width`/`height`",
            Rule::lane_dir => "`in` or `out`",
            Rule::rel => "`before` or `after`",
            Rule::conflict_key => "a conflict field (at_fault, struck, impact, point, at)",
            Rule::placement | Rule::lane_place | Rule::world_place => "a placement",
            Rule::lane_ref => "a lane like `west.in[1]`",
            Rule::offset => "`offset`",
            Rule::heading => "`heading`",
            Rule::param => "a parameter",
            Rule::keyframe => "a keyframe `TIME: (X, Y) yaw ANGLE`",
            Rule::conflict_field => "a conflict field",
            Rule::near_miss_key => "a near_miss field (passer, passed, gap, side, at)",
            Rule::near_miss_field => "a near_miss field",
            Rule::exp_bound => "`at_least` or `at_most`",
            Rule::exp_when => "`during A..B s` or `by T s`",
            _ => return Some(s.replace('_', " ")),
        }
        .to_string(),
    )
}

pub(super) fn syntax_error(file: FileId, text: &str, e: pest::error::Error<Rule>) -> Diagnostic {
    let pos = match e.location {
        pest::error::InputLocation::Pos(p) => p,
        pest::error::InputLocation::Span((s, _)) => s,
    };
    let expected = match &e.variant {
        pest::error::ErrorVariant::ParsingError { positives, .. } => positives.clone(),
        pest::error::ErrorVariant::CustomError { .. } => vec![],
    };
    let word = word_at(text, pos);
    let braces = Braces::scan(text, pos);
    // A block keyword where a statement of the enclosing block was expected means the block
    // above was never closed (inside the scenario block is where such statements belong).
    if braces.open.len() >= 2
        && let Some(next) = block_statement_at(text, pos, word)
    {
        return unclosed_block(file, text, &braces.culprit(text), Some(next));
    }
    // The file ends where a statement could begin, with a block still open.
    let at_end = text.get(pos..).is_none_or(|rest| rest.trim().is_empty());
    if at_end && !braces.open.is_empty() && expected.iter().any(begins_statement) {
        return unclosed_block(file, text, &braces.culprit(text), None);
    }
    let found = if pos >= text.len() {
        "end of file".to_string()
    } else if word.is_empty() {
        format!("`{}`", text[pos..].chars().next().unwrap_or(' '))
    } else {
        format!("`{word}`")
    };
    let mut names: Vec<String> = expected.iter().filter_map(rule_name).collect();
    names.sort();
    names.dedup();
    if braces.open.len() >= 2 {
        names.push("`}`".to_string());
    }
    let message = if names.is_empty() {
        format!("unexpected {found}")
    } else {
        format!("expected {}, found {found}", join_or(&names))
    };
    let width =
        if word.is_empty() { text[pos.min(text.len())..].chars().next().map_or(0, char::len_utf8) } else { word.len() };
    let end = (pos + width).min(text.len());
    let d = Diagnostic::error("E0001", message).label(Span::new(file, pos, end), "here");
    // Prefer the words that are valid right here; fall back to every keyword.
    let here: Vec<&str> = expected.iter().flat_map(rule_words).copied().collect();
    let help = if !word.is_empty() && word.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        let unit_expected = expected.contains(&Rule::unit);
        let candidates: &[&str] = if unit_expected { UNITS } else { KEYWORDS };
        let spelled = if unit_expected { unit_respelling(word, statement_keyword(text, pos)) } else { None };
        match spelled
            .or_else(|| diag::suggest(word, here.iter().copied()))
            .or_else(|| diag::suggest(word, candidates.iter().copied()))
        {
            Some(s) => format!("did you mean `{s}`?"),
            None if unit_expected => {
                format!("units: {}", UNITS.join(", "))
            }
            None if !here.is_empty() => {
                format!("`{word}` is none of these; docs/language.md lists the statements of each block")
            }
            None => "docs/language.md describes each statement and the values it takes".to_string(),
        }
    } else {
        "statements are separated by newlines or `;`; docs/language.md describes each statement".to_string()
    };
    d.help(help)
}

/// A block whose `}` is missing.
struct Unclosed {
    /// Offset of its `{`.
    open: usize,
    /// Offset of the `}` that was read as its end, written for the block around it.
    taken: Option<usize>,
}

/// A statement of an enclosing block that the parser met inside a block.
struct Statement<'t> {
    start: usize,
    keyword: &'t str,
}

/// The parse error for a block left open, and the statement of the enclosing block met inside
/// it (none at the end of the file).
fn unclosed_block(file: FileId, text: &str, block: &Unclosed, next: Option<Statement<'_>>) -> Diagnostic {
    let line = |at: usize| text[..at].matches('\n').count() + 1;
    let open = block.open;
    let before = next.as_ref().map_or("end of file".to_string(), |n| format!("`{}`", n.keyword));
    let what = if block.taken.is_some() { "this block has no `}` of its own" } else { "this block is never closed" };
    let d = Diagnostic::error("E0001", format!("unclosed `{{`: expected `}}` before {before}"))
        .label(Span::new(file, open, open + 1), what)
        .help(format!("add `}}` to close the block opened on line {}", line(open)));
    match (block.taken, next) {
        (Some(close), _) => d
            .label(Span::new(file, close, close + 1), "taken as its `}`, though indented for the block around it")
            .and_help(format!(
                "the `}}` on line {} is indented for the block around it, which is left open",
                line(close)
            )),
        (None, Some(Statement { start, keyword })) => {
            d.label(Span::new(file, start, start + keyword.len()), "the next statement begins here").and_help(format!(
                "the `}}` goes before `{keyword}` on line {}, where the next statement begins",
                line(start)
            ))
        }
        (None, None) => d,
    }
}

/// The block keyword that begins the statement the parser stopped in: the word at the error, or
/// the word just before it when the parser took the keyword for a name (`agent b: sedan` read
/// as a road parameter called `agent`) and it stands where a statement can begin.
fn block_statement_at<'t>(text: &'t str, pos: usize, word: &'t str) -> Option<Statement<'t>> {
    if is_block_keyword(word) {
        return Some(Statement { start: pos, keyword: word });
    }
    let before = text[..pos.min(text.len())].trim_end();
    let start = last_word_start(before);
    let previous = &before[start..];
    let lead = text[..start].trim_end_matches([' ', '\t']);
    let begins_statement = lead.is_empty() || lead.ends_with(['\n', ';', '{', '}']);
    (is_block_keyword(previous) && begins_statement).then_some(Statement { start, keyword: previous })
}

/// A rule that begins a statement of some block (a keyword, a size key, a conflict field).
fn begins_statement(r: &Rule) -> bool {
    matches!(
        r,
        Rule::kw_seed
            | Rule::kw_duration
            | Rule::kw_rate
            | Rule::kw_egos
            | Rule::kw_road
            | Rule::kw_traffic
            | Rule::kw_agent
            | Rule::kw_object
            | Rule::kw_row
            | Rule::kw_conflict
            | Rule::kw_at
            | Rule::kw_speed
            | Rule::size_key
            | Rule::kw_goal
            | Rule::kw_track
            | Rule::kw_posture
            | Rule::kw_siren
            | Rule::lamp_key
            | Rule::kw_door
            | Rule::kw_lateral
            | Rule::kw_stop
            | Rule::kw_turn
            | Rule::kw_start
            | Rule::kw_motion
            | Rule::conflict_key
            | Rule::kw_near_miss
            | Rule::near_miss_key
            | Rule::kw_scenario
            | Rule::kw_kind
            | Rule::kw_use
    )
}

/// A unit written without its slash or in another case or common spelling (`kmh`, `kph`,
/// `MPS`, `hz`): edit distance alone would offer `km` for `kmh`, a unit of the wrong dimension.
/// Miles after a speed keyword are miles per hour (there is no unit of miles).
fn unit_respelling(word: &str, keyword: &str) -> Option<&'static str> {
    let w = word.to_ascii_lowercase();
    let speed = matches!(keyword, "speed" | "speed_limit");
    let alias = match w.as_str() {
        "mi" | "mile" | "miles" if speed => Some("mph"),
        "kph" | "kmph" => Some("km/h"),
        "mps" => Some("m/s"),
        "sec" | "secs" | "seconds" => Some("s"),
        "degree" | "degrees" => Some("deg"),
        "meter" | "meters" | "metre" | "metres" => Some("m"),
        _ => None,
    };
    alias.or_else(|| {
        UNITS.iter().copied().find(|u| u.len() > 1 && u.replace('/', "").to_ascii_lowercase() == w && *u != word)
    })
}

/// The word that begins the statement whose value ends at `pos` (`speed` in `speed 30 mi`).
fn statement_keyword(text: &str, pos: usize) -> &str {
    let value = text[..pos.min(text.len())].trim_end();
    let before = value.trim_end_matches(|c: char| c.is_ascii_digit() || c == '.' || c == '-').trim_end();
    if before.len() < value.len() { &before[last_word_start(before)..] } else { "" }
}

/// Where the word of identifier characters that ends `text` begins (`text.len()` if none does).
fn last_word_start(text: &str) -> usize {
    text.char_indices()
        .rev()
        .take_while(|(_, c)| c.is_ascii_alphanumeric() || *c == '_')
        .last()
        .map_or(text.len(), |(i, _)| i)
}

fn is_block_keyword(w: &str) -> bool {
    matches!(
        w,
        "agent" | "object" | "row" | "road" | "conflict" | "near_miss" | "traffic" | "scenario" | "kind" | "use"
    )
}

/// The braces before a position, comments and strings skipped.
struct Braces {
    /// Offsets of the `{`s still open, outermost first.
    open: Vec<usize>,
    /// (`{`, `}`) offsets of the pairs closed, in the order they closed.
    closed: Vec<(usize, usize)>,
}

impl Braces {
    fn scan(text: &str, pos: usize) -> Braces {
        let bytes = text.as_bytes();
        let (mut open, mut closed) = (Vec::new(), Vec::new());
        let mut i = 0;
        while i < pos.min(bytes.len()) {
            match bytes[i] {
                b'/' if bytes.get(i + 1) == Some(&b'/') => {
                    while i < bytes.len() && bytes[i] != b'\n' {
                        i += 1;
                    }
                    continue;
                }
                b'"' => {
                    i += 1;
                    while i < bytes.len() && bytes[i] != b'"' && bytes[i] != b'\n' {
                        i += 1;
                    }
                }
                b'{' => open.push(i),
                b'}' => {
                    if let Some(o) = open.pop() {
                        closed.push((o, i));
                    }
                }
                _ => {}
            }
            i += 1;
        }
        Braces { open, closed }
    }

    /// The `{` whose `}` is missing (some `{` must be open), and the `}` read as its end if one
    /// was. A `}` on a line of its own indented less than the line of the `{` it closes was
    /// written for an enclosing block: the first such one inside the innermost open block
    /// closed the block that lacks its `}` (a `goal` left open takes its agent's `}`). Else the
    /// innermost open `{` is the one.
    fn culprit(&self, text: &str) -> Unclosed {
        let inner = *self.open.last().expect("a block is open");
        let misindented = |o: usize, c: usize| {
            let (lo, lc) = (line_start(text, o), line_start(text, c));
            let indent = |from: usize| text[from..].len() - text[from..].trim_start_matches([' ', '\t']).len();
            lo != lc && lc + indent(lc) == c && indent(lc) < indent(lo)
        };
        match self.closed.iter().find(|&&(o, c)| o > inner && misindented(o, c)) {
            Some(&(open, close)) => Unclosed { open, taken: Some(close) },
            None => Unclosed { open: inner, taken: None },
        }
    }
}

fn line_start(text: &str, at: usize) -> usize {
    text[..at].rfind('\n').map_or(0, |i| i + 1)
}

fn word_at(text: &str, pos: usize) -> &str {
    if pos >= text.len() {
        return "";
    }
    let rest = &text[pos..];
    let end = rest.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(rest.len());
    &rest[..end]
}

fn join_or(items: &[String]) -> String {
    match items.len() {
        0 => String::new(),
        1 => items[0].clone(),
        n if n > 8 => format!("{}, ... ({} choices)", items[..6].join(", "), n),
        n => format!("{} or {}", items[..n - 1].join(", "), items[n - 1]),
    }
}
