//! Lark (llguidance, vLLM's `guidance` backend, Python `lark` with the Earley parser).
//! Printed at character level with the explicit `ws` rule, so no `%ignore` and no lexer
//! conflicts between keywords and identifiers.

use super::lower::{Cfg, ClassItem, Node};

/// Lark rule names are lowercase; a leading `_` would inline the rule, so none is produced.
fn name(n: &str) -> String {
    let n = n.to_ascii_lowercase();
    n.trim_start_matches('_').to_string()
}

pub fn print(cfg: &Cfg) -> String {
    let mut out = String::from(
        "// The rocc .scn language, exported from grammar/scn.pest by `rocc grammar --format lark`.\n\
         // Lookaheads are dropped, so this accepts a superset of what `rocc check` parses.\n",
    );
    out.push_str(&format!("start: {}\n", name(&cfg.root)));
    for (n, node) in &cfg.rules {
        out.push_str(&format!("{}: {}\n", name(n), expr(node)));
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
        Node::Lit(s) => serde_json::to_string(s).expect("a string serialises"),
        Node::Class { negated, items } => class(*negated, items),
        Node::Ref(r) => name(r),
        Node::Seq(_) | Node::Alt(_) => format!("({})", expr(n)),
        Node::Opt(x) => format!("{}?", operand(x)),
        Node::Star(x) => format!("{}*", operand(x)),
        Node::Plus(x) => format!("{}+", operand(x)),
    }
}

fn operand(n: &Node) -> String {
    match n {
        Node::Lit(_) | Node::Class { .. } | Node::Ref(_) => atom(n),
        _ => format!("({})", expr(n)),
    }
}

fn class_char(c: char) -> String {
    match c {
        '\n' => "\\n".into(),
        '\r' => "\\r".into(),
        '\t' => "\\t".into(),
        '\\' | ']' | '[' | '^' | '-' | '/' => format!("\\{c}"),
        c => c.to_string(),
    }
}

fn class(negated: bool, items: &[ClassItem]) -> String {
    if negated && items.is_empty() {
        return "/(.|\\n)/".to_string();
    }
    let body: String = items
        .iter()
        .map(|i| match i {
            ClassItem::Char(c) => class_char(*c),
            ClassItem::Range(a, b) => format!("{}-{}", class_char(*a), class_char(*b)),
        })
        .collect();
    format!("/[{}{}]/", if negated { "^" } else { "" }, body)
}
