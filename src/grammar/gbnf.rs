//! GBNF (llama.cpp's grammar format, also read by vLLM's xgrammar backend).

use super::lower::{Cfg, ClassItem, Node};

/// GBNF names allow `[a-zA-Z0-9-]`; the start rule must be called `root`.
fn name(n: &str) -> String {
    n.to_ascii_lowercase().replace('_', "-")
}

pub fn print(cfg: &Cfg) -> String {
    let mut out = String::from(
        "# The rocc .scn language, exported from grammar/scn.pest by `rocc grammar --format gbnf`.\n\
         # Lookaheads are dropped, so this accepts a superset of what `rocc check` parses.\n",
    );
    out.push_str(&format!("root ::= {}\n", name(&cfg.root)));
    for (n, node) in &cfg.rules {
        out.push_str(&format!("{} ::= {}\n", name(n), expr(node)));
    }
    out
}

fn expr(n: &Node) -> String {
    match n {
        Node::Alt(alts) => alts.iter().map(seq).collect::<Vec<_>>().join(" | "),
        n => seq(n),
    }
}

fn seq(n: &Node) -> String {
    match n {
        Node::Seq(parts) => {
            let parts: Vec<String> = parts.iter().filter(|p| **p != Node::Empty).map(atom).collect();
            if parts.is_empty() { "\"\"".to_string() } else { parts.join(" ") }
        }
        Node::Alt(_) => format!("({})", expr(n)),
        n => atom(n),
    }
}

fn atom(n: &Node) -> String {
    match n {
        Node::Empty => "\"\"".to_string(),
        Node::Lit(s) => literal(s),
        Node::Class { negated, items } => class(*negated, items),
        Node::Ref(r) => name(r),
        Node::Seq(_) | Node::Alt(_) => format!("({})", expr(n)),
        Node::Opt(x) => format!("{}?", postfix_operand(x)),
        Node::Star(x) => format!("{}*", postfix_operand(x)),
        Node::Plus(x) => format!("{}+", postfix_operand(x)),
    }
}

fn postfix_operand(n: &Node) -> String {
    match n {
        Node::Lit(_) | Node::Class { .. } | Node::Ref(_) => atom(n),
        _ => format!("({})", expr(n)),
    }
}

fn escape(c: char, in_class: bool) -> String {
    match c {
        '\n' => "\\n".into(),
        '\r' => "\\r".into(),
        '\t' => "\\t".into(),
        '\\' => "\\\\".into(),
        '"' if !in_class => "\\\"".into(),
        ']' | '[' | '^' | '-' if in_class => format!("\\{c}"),
        c if (c as u32) < 0x20 => format!("\\x{:02X}", c as u32),
        c => c.to_string(),
    }
}

fn literal(s: &str) -> String {
    format!("\"{}\"", s.chars().map(|c| escape(c, false)).collect::<String>())
}

fn class(negated: bool, items: &[ClassItem]) -> String {
    if negated && items.is_empty() {
        // Any character: an empty negated class is not valid GBNF.
        return "[^\\x00]".to_string();
    }
    let body: String = items
        .iter()
        .map(|i| match i {
            ClassItem::Char(c) => escape(*c, true),
            ClassItem::Range(a, b) => format!("{}-{}", escape(*a, true), escape(*b, true)),
        })
        .collect();
    format!("[{}{}]", if negated { "^" } else { "" }, body)
}
