//! Stage 2, the "traffic director": one `goal { ... }` per mover, in the language's goal
//! vocabulary. Replies are read here; the model's text is only ever parsed, never run.

use crate::grammar::{self, Cfg, Format, Node};

/// Does this goal block parse? (It is wrapped into a throw-away agent so the real parser judges it.)
pub fn parses(block: &str) -> Result<(), String> {
    let wrapped = format!("scenario g {{ agent a: sedan {{ {block} }} }}");
    crate::syntax::parse(0, &wrapped).map(|_| ()).map_err(|d| d.message)
}

/// Byte range of the first balanced `goal { ... }` block at or after `from`.
fn next_block(text: &str, from: usize) -> Option<(usize, usize)> {
    let mut search = from;
    while let Some(rel) = text[search..].find("goal") {
        let start = search + rel;
        let after = &text[start + 4..];
        let trimmed = after.trim_start();
        if trimmed.starts_with('{') {
            let open = start + 4 + (after.len() - trimmed.len());
            let mut depth = 0;
            for (i, c) in text[open..].char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => {
                        depth -= 1;
                        if depth == 0 {
                            return Some((start, open + i + 1));
                        }
                    }
                    _ => {}
                }
            }
            return None;
        }
        search = start + 4;
    }
    None
}

/// Flatten a block onto one line (the emitter indents it). Comments are dropped with the rest
/// of each line after `//`, since a one-line block could not end them.
fn one_line(block: &str) -> String {
    let open = block.find('{').expect("a goal block has `{`");
    let close = block.rfind('}').expect("a goal block has `}`");
    let parts: Vec<&str> = block[open + 1..close]
        .lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .flat_map(|l| l.split(';'))
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect();
    if parts.is_empty() { "goal { }".to_string() } else { format!("goal {{ {} }}", parts.join("; ")) }
}

/// Later blocks of one agent: goal phases (`goal { speed 0 m/s; start when ... }`). More than
/// this many is a model looping, not a plan.
pub const MAX_PHASES: usize = 4;

/// The goal block of a hierarchical reply, with any phases that follow it, one block a line.
pub fn parse_single(reply: &str) -> Result<String, String> {
    let (a, mut b) = next_block(reply, 0).ok_or("the reply holds no `goal { ... }` block")?;
    let mut blocks = vec![one_line(&reply[a..b])];
    while let Some((c, d)) = next_block(reply, b).filter(|_| blocks.len() < MAX_PHASES) {
        blocks.push(one_line(&reply[c..d]));
        b = d;
    }
    let block = blocks.join("\n");
    parses(&block)?;
    Ok(block)
}

/// The `NAME: goal { ... }` lines of a joint reply, as (roster index, block). Agents the model
/// left out get no goal; an unknown name or a block that does not parse is an error to correct.
pub fn parse_joint(reply: &str, names: &[String]) -> Result<Vec<(usize, String)>, String> {
    let mut out: Vec<(usize, String)> = vec![];
    let mut from = 0;
    let mut last: Option<usize> = None;
    while let Some((a, b)) = next_block(reply, from) {
        let prev = from;
        from = b;
        // A block right after another on its line is a phase of the same agent.
        if let Some(j) = last.filter(|_| prev > 0 && reply[prev..a].trim_matches([' ', '\t']).is_empty()) {
            let phase = one_line(&reply[a..b]);
            if let Some((_, blocks)) = out.iter_mut().find(|(i, _)| *i == j)
                && blocks.lines().count() < MAX_PHASES
            {
                blocks.push('\n');
                blocks.push_str(&phase);
                parses(blocks).map_err(|e| format!("the goal phases of `{}` do not parse: {e}", names[j]))?;
            }
            continue;
        }
        // The name is the identifier before the `:` that precedes `goal`.
        let head = reply[..a].trim_end();
        let Some(head) = head.strip_suffix(':') else { return Err("write each line as `NAME: goal { ... }`".into()) };
        let name: String = head
            .chars()
            .rev()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect();
        let Some(i) = names.iter().position(|n| *n == name) else {
            return Err(format!("`{name}` is not one of the road users ({})", names.join(", ")));
        };
        let block = one_line(&reply[a..b]);
        parses(&block).map_err(|e| format!("the goal of `{name}` does not parse: {e}"))?;
        if out.iter().all(|(j, _)| *j != i) {
            out.push((i, block));
            last = Some(i);
        } else {
            last = None;
        }
    }
    if out.is_empty() {
        return Err("the reply holds no `NAME: goal { ... }` line".into());
    }
    Ok(out)
}

/// The goal block for decoding: each part of the vocabulary at most once, in a fixed order,
/// built from the pest rules of the parts. A subset of what the parser accepts (it allows any
/// order), which keeps a small model from repeating one statement until `--max-tokens`.
fn goal_block() -> Cfg {
    let cfg = grammar::rule("goal").expect("scn.pest has a `goal` rule");
    let ws = || Node::Ref("ws".into());
    let part = |rule: &str| {
        Node::Opt(Box::new(Node::Seq(vec![
            Node::Ref(rule.into()),
            ws(),
            Node::Opt(Box::new(Node::Lit(";".into()))),
            ws(),
        ])))
    };
    let mut seq = vec![Node::Lit("goal".into()), ws(), Node::Lit("{".into()), ws()];
    seq.extend(["speed_stmt", "lateral", "stop", "turn", "reverse", "start"].map(part));
    seq.push(Node::Lit("}".into()));
    grammar::for_decoding(cfg.with_root("goal_block", Node::Seq(seq)))
}

/// A later phase for decoding: what a phase may change, each at most once (`speed`, `lateral
/// pull_to_shoulder` or `change_lane`, `stop after DIST`), then its required `start`. Turns,
/// crossings and other stops are left out, as the checker refuses them in a phase (E0155).
fn phase_block() -> Node {
    let ws = || Node::Ref("ws".into());
    let part = |head: Vec<Node>| {
        let mut seq = head;
        seq.extend([ws(), Node::Opt(Box::new(Node::Lit(";".into()))), ws()]);
        Node::Seq(seq)
    };
    let opt = |n: Node| Node::Opt(Box::new(n));
    Node::Seq(vec![
        Node::Lit("goal".into()),
        ws(),
        Node::Lit("{".into()),
        ws(),
        opt(part(vec![Node::Ref("speed_stmt".into())])),
        opt(part(vec![Node::Alt(
            ["pull_to_shoulder", "change_lane left", "change_lane right"]
                .map(|w| Node::Lit(format!("lateral {w}")))
                .to_vec(),
        )])),
        opt(part(vec![Node::Lit("stop after ".into()), Node::Ref("value".into())])),
        part(vec![Node::Ref("start".into())]),
        Node::Lit("}".into()),
    ])
}

/// The goal block and at most one later phase after it on the same line.
fn goal_phases() -> Cfg {
    let phase = Node::Opt(Box::new(Node::Seq(vec![Node::Lit(" ".into()), Node::Ref("phase_block".into())])));
    goal_block()
        .with_root("phase_block", phase_block())
        .with_root("goal_phases", Node::Seq(vec![Node::Ref("goal_block".into()), phase]))
}

/// GBNF for one goal block, or a block and a phase (hierarchical mode).
pub fn single_grammar() -> String {
    grammar::print(&goal_phases(), Format::Gbnf)
}

/// GBNF for the joint reply: exactly one `NAME: goal { ... }` line per mover (a phase may follow
/// on the line), in roster order, so a small model cannot invent agents or loop on lines.
pub fn joint_grammar(names: &[String]) -> String {
    let lines = names
        .iter()
        .map(|n| Node::Seq(vec![Node::Lit(format!("{n}: ")), Node::Ref("goal_phases".into()), Node::Lit("\n".into())]))
        .collect();
    grammar::print(&goal_phases().with_root("plan", Node::Seq(lines)), Format::Gbnf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_replies_are_read_by_name() {
        let names = vec!["amb".to_string(), "lead".to_string()];
        let r = "Sure!\namb: goal { speed 50 km/h; turn straight }\nlead: goal {\n speed 10 km/h\n lateral away_from amb\n}\n";
        let got = parse_joint(r, &names).unwrap();
        assert_eq!(got[0], (0, "goal { speed 50 km/h; turn straight }".to_string()));
        assert_eq!(got[1], (1, "goal { speed 10 km/h; lateral away_from amb }".to_string()));
        assert!(parse_joint("bob: goal { speed 3 km/h }", &names).unwrap_err().contains("not one of"));
        assert!(parse_joint("no goals here", &names).is_err());
        assert!(parse_single("goal { speed fast }").is_err());
    }
}
