//! Lark (llguidance, vLLM's `guidance` backend, Python `lark` with the Earley parser).
//! Printed at character level with the explicit `ws` rule, so no `%ignore` and no lexer
//! conflicts between keywords and identifiers.

use std::collections::{BTreeMap, BTreeSet};

use super::lower::{Cfg, ClassItem, Node};

/// Lark rule names are lowercase; a leading `_` would inline the rule, so none is produced.
fn base_name(n: &str) -> String {
    let n = n.to_ascii_lowercase();
    n.trim_start_matches('_').to_string()
}

/// Pest rule name -> Lark rule name. Lark rejects a rule defined twice, and lowercasing,
/// dropping `_` and the added `start` can all make two names meet (the goal statement's
/// `start` rule did), so a clashing name gets a numbered suffix.
struct Names(BTreeMap<String, String>);

impl Names {
    fn new(cfg: &Cfg) -> Names {
        let mut taken: BTreeSet<String> = BTreeSet::from(["start".to_string()]);
        let mut map = BTreeMap::new();
        for (n, _) in &cfg.rules {
            if map.contains_key(n) {
                continue;
            }
            let base = base_name(n);
            let mut candidate = base.clone();
            let mut k = 1;
            while taken.contains(&candidate) {
                candidate = format!("{base}_{k}");
                k += 1;
            }
            taken.insert(candidate.clone());
            map.insert(n.clone(), candidate);
        }
        Names(map)
    }

    fn get(&self, n: &str) -> String {
        self.0.get(n).cloned().unwrap_or_else(|| base_name(n))
    }
}

pub fn print(cfg: &Cfg) -> String {
    let names = Names::new(cfg);
    let mut out = String::from(
        "// The rocc .scn language, exported from grammar/scn.pest by `rocc grammar --format lark`.\n\
         // Lookaheads are dropped, so this accepts a superset of what `rocc check` parses.\n",
    );
    out.push_str(&format!("start: {}\n", names.get(&cfg.root)));
    for (n, node) in &cfg.rules {
        out.push_str(&format!("{}: {}\n", names.get(n), expr(&names, node)));
    }
    out
}

fn expr(names: &Names, n: &Node) -> String {
    match n {
        Node::Alt(alts) => alts.iter().map(|a| seq(names, a)).collect::<Vec<_>>().join(" | "),
        n => seq(names, n),
    }
}

fn seq(names: &Names, n: &Node) -> String {
    match n {
        Node::Seq(parts) => {
            let parts: Vec<String> = parts.iter().filter(|p| **p != Node::Empty).map(|p| atom(names, p)).collect();
            if parts.is_empty() { "\"\"".to_string() } else { parts.join(" ") }
        }
        Node::Alt(_) => format!("({})", expr(names, n)),
        n => atom(names, n),
    }
}

fn atom(names: &Names, n: &Node) -> String {
    match n {
        Node::Empty => "\"\"".to_string(),
        Node::Lit(s) => serde_json::to_string(s).expect("a string serialises"),
        Node::Class { negated, items } => class(*negated, items),
        Node::Ref(r) => names.get(r),
        Node::Seq(_) | Node::Alt(_) => format!("({})", expr(names, n)),
        Node::Opt(x) => format!("{}?", operand(names, x)),
        Node::Star(x) => format!("{}*", operand(names, x)),
        Node::Plus(x) => format!("{}+", operand(names, x)),
    }
}

fn operand(names: &Names, n: &Node) -> String {
    match n {
        Node::Lit(_) | Node::Class { .. } | Node::Ref(_) => atom(names, n),
        _ => format!("({})", expr(names, n)),
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
