//! Grammar export. In: `grammar/scn.pest` (compiled in, read with pest's own grammar reader).
//! Out: the same language as GBNF (llama.cpp, vLLM/xgrammar) or Lark (llguidance, vLLM's
//! `guidance` backend), for grammar-constrained decoding of `.scn` text by a language model.
//!
//! The export is derived, never hand-maintained: `lower` turns the PEG into a context-free
//! grammar (`Cfg`), and `gbnf` / `lark` print it. Two PEG features have no CFG counterpart:
//!
//! - implicit whitespace: pest inserts `(WHITESPACE | COMMENT)*` between the parts of every
//!   non-atomic rule; the lowering writes it out as an explicit `ws` rule;
//! - lookahead: `!X ~ ANY` (any character but X) becomes a negated character class; the word
//!   boundaries after keywords (`!ident_char`) are dropped. The exported grammar therefore
//!   accepts every file pest accepts and a few it rejects (`speed5 m/s` glued words); the
//!   checker reports those as E0001 and the repair loop fixes them.
//!
//! Invariant: a test proves the GBNF accepts every bundled and shared example and rejects the
//! shared syntax-error example (`tests/llm.rs`).

mod gbnf;
mod lark;
mod lower;

pub use lower::{Cfg, ClassItem, Node};

/// The pest source of the language, the single definition every export derives from.
pub const PEST_SOURCE: &str = include_str!("../../grammar/scn.pest");

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Gbnf,
    Lark,
}

/// The whole language (`file` is the pest entry rule) as a context-free grammar.
pub fn language() -> Cfg {
    lower::lower(PEST_SOURCE, "file").expect("grammar/scn.pest lowers to a CFG (tested)")
}

/// The language restricted to one pest rule as the start symbol (e.g. `goal` for the goal stage),
/// with every rule it reaches.
pub fn rule(name: &str) -> Result<Cfg, String> {
    lower::lower(PEST_SOURCE, name)
}

/// Print a grammar in `format`.
pub fn print(cfg: &Cfg, format: Format) -> String {
    match format {
        Format::Gbnf => gbnf::print(cfg),
        Format::Lark => lark::print(cfg),
    }
}

/// Longest whitespace run the decoding grammar allows between two tokens.
pub const DECODING_MAX_WS: usize = 12;

/// The grammar a model decodes under: the same rules, but the whitespace between tokens is at
/// most `DECODING_MAX_WS` characters and comments are not offered. A language of files rocc
/// accepts (minus comments), in which a small model cannot fill `--max-tokens` with blank lines
/// or `//` lines (it did, against a real llama.cpp server).
pub fn for_decoding(mut cfg: Cfg) -> Cfg {
    let space = || Node::Class {
        negated: false,
        items: vec![ClassItem::Char(' '), ClassItem::Char('\t'), ClassItem::Char('\n')],
    };
    // Right-nested optionals: one way to match each run, so no ambiguity for the decoder.
    let mut ws = Node::Empty;
    for _ in 0..DECODING_MAX_WS {
        ws = Node::Opt(Box::new(if ws == Node::Empty { space() } else { Node::Seq(vec![space(), ws]) }));
    }
    for (name, node) in &mut cfg.rules {
        if name == lower::WS {
            *node = ws.clone();
        }
    }
    cfg.rules.retain(|(n, _)| n != "COMMENT" && n != "WHITESPACE");
    // Each road parameter at most once, in a fixed order (a subset of what the parser takes,
    // as for goal blocks): a small model looped `lanes 2; speed_limit 50 km/h;` until
    // --max-tokens under the open `(param sep*)*`.
    if let Some((_, node)) = cfg.rules.iter_mut().find(|(n, _)| n == "road_body") {
        let ws = || Node::Ref(lower::WS.into());
        let mut seq = vec![Node::Lit("{".into()), ws()];
        seq.extend(crate::check::ROAD_PARAMS.iter().map(|p| {
            Node::Opt(Box::new(Node::Seq(vec![
                Node::Lit((*p).into()),
                ws(),
                Node::Ref("param_value".into()),
                ws(),
                Node::Opt(Box::new(Node::Seq(vec![Node::Ref("sep".into()), ws()]))),
            ])))
        }));
        // Then up to two parking lanes and two driveways, bounded for the same reason.
        for rule in ["parking_decl", "parking_decl", "driveway_decl", "driveway_decl"] {
            seq.push(Node::Opt(Box::new(Node::Seq(vec![
                Node::Ref(rule.into()),
                ws(),
                Node::Opt(Box::new(Node::Seq(vec![Node::Ref("sep".into()), ws()]))),
            ]))));
        }
        seq.push(Node::Lit("}".into()));
        *node = Node::Seq(seq);
    }
    cfg
}

/// `rocc grammar --format F`: the whole language.
pub fn export(format: Format) -> String {
    print(&language(), format)
}
