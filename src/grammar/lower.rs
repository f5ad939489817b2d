//! PEG (pest) -> context-free grammar. See the module docs of `grammar` for what changes.

use pest_meta::ast::{Expr, RuleType};
use std::collections::{BTreeMap, BTreeSet};

/// One element of a character class.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ClassItem {
    Char(char),
    Range(char, char),
}

/// A context-free grammar expression.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Node {
    /// Matches nothing (the empty string).
    Empty,
    Lit(String),
    Class {
        negated: bool,
        items: Vec<ClassItem>,
    },
    Ref(String),
    Seq(Vec<Node>),
    Alt(Vec<Node>),
    Opt(Box<Node>),
    Star(Box<Node>),
    Plus(Box<Node>),
}

/// A grammar: the start rule and every rule reachable from it, in first-reached order so the
/// printed grammar reads top-down like the pest source.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Cfg {
    pub root: String,
    pub rules: Vec<(String, Node)>,
}

impl Cfg {
    /// Replace the start rule by `node` named `name` (kept rules stay reachable through refs).
    pub fn with_root(mut self, name: &str, node: Node) -> Cfg {
        self.rules.insert(0, (name.to_string(), node));
        self.root = name.to_string();
        self
    }
}

/// The whitespace rule the lowering inserts where pest skips implicitly.
pub const WS: &str = "ws";

pub fn lower(pest_source: &str, root: &str) -> Result<Cfg, String> {
    let pairs = pest_meta::parser::parse(pest_meta::parser::Rule::grammar_rules, pest_source)
        .map_err(|e| format!("pest grammar: {e}"))?;
    let rules = pest_meta::parser::consume_rules(pairs)
        .map_err(|es| es.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"))?;
    let defs: BTreeMap<String, (RuleType, Expr)> = rules.into_iter().map(|r| (r.name, (r.ty, r.expr))).collect();
    if !defs.contains_key(root) {
        return Err(format!("the grammar has no rule `{root}`"));
    }
    let mut l = Lowering { defs: &defs, done: BTreeMap::new(), order: vec![], queue: vec![], uses_ws: false };
    // The skip rules run atomically in pest (no whitespace inside a comment).
    let skip: Vec<&str> = ["WHITESPACE", "COMMENT"].into_iter().filter(|n| defs.contains_key(*n)).collect();
    l.want(root, false)?;
    while let Some((name, atomic)) = l.queue.pop() {
        let expr = &defs[&name].1;
        let node = l.expr(expr, atomic || skip.contains(&name.as_str()))?;
        l.done.insert(name.clone(), (atomic, Some(node)));
    }
    let mut out = Cfg { root: root.to_string(), rules: vec![] };
    for name in &l.order {
        let node = l.done[name].1.clone().expect("every queued rule is lowered");
        out.rules.push((name.clone(), node));
    }
    if l.uses_ws {
        let mut alts = vec![];
        for s in &skip {
            if !l.done.contains_key(*s) {
                let node = l.expr(&defs[*s].1, true)?;
                out.rules.push((s.to_string(), node));
            }
            alts.push(Node::Ref(s.to_string()));
        }
        let ws = if alts.is_empty() { Node::Empty } else { Node::Star(Box::new(Node::Alt(alts))) };
        out.rules.push((WS.to_string(), ws));
    }
    Ok(out)
}

struct Lowering<'a> {
    defs: &'a BTreeMap<String, (RuleType, Expr)>,
    /// Rule -> (lowered in atomic context, lowered node once done).
    done: BTreeMap<String, (bool, Option<Node>)>,
    order: Vec<String>,
    queue: Vec<(String, bool)>,
    uses_ws: bool,
}

impl Lowering<'_> {
    /// Ask for rule `name` in the given context; one CFG rule per pest rule, so a rule used both
    /// inside and outside atomic rules would need two copies (the grammar has none: an error).
    fn want(&mut self, name: &str, atomic: bool) -> Result<(), String> {
        let (ty, _) = &self.defs[name];
        let effective = match ty {
            RuleType::Atomic | RuleType::CompoundAtomic => true,
            RuleType::NonAtomic => false,
            RuleType::Normal | RuleType::Silent => atomic,
        };
        match self.done.get(name) {
            Some((a, _)) if *a != effective => {
                Err(format!("rule `{name}` is used both inside and outside atomic rules; split it in scn.pest"))
            }
            Some(_) => Ok(()),
            None => {
                self.done.insert(name.to_string(), (effective, None));
                self.order.push(name.to_string());
                self.queue.push((name.to_string(), effective));
                Ok(())
            }
        }
    }

    fn ws(&mut self) -> Node {
        self.uses_ws = true;
        Node::Ref(WS.to_string())
    }

    fn expr(&mut self, e: &Expr, atomic: bool) -> Result<Node, String> {
        Ok(match e {
            Expr::Str(s) => Node::Lit(s.clone()),
            Expr::Range(a, b) => Node::Class { negated: false, items: vec![ClassItem::Range(ch(a)?, ch(b)?)] },
            Expr::Ident(name) => self.ident(name, atomic)?,
            Expr::Seq(..) => {
                let mut parts = vec![];
                flatten_seq(e, &mut parts);
                self.seq(&parts, atomic)?
            }
            Expr::Choice(..) => {
                let mut alts = vec![];
                flatten_choice(e, &mut alts);
                Node::Alt(alts.into_iter().map(|a| self.expr(a, atomic)).collect::<Result<_, _>>()?)
            }
            Expr::Opt(x) => Node::Opt(Box::new(self.expr(x, atomic)?)),
            // pest skips whitespace between repetitions in non-atomic rules.
            Expr::Rep(x) => {
                let x = self.expr(x, atomic)?;
                if atomic { Node::Star(Box::new(x)) } else { Node::Opt(Box::new(self.rep_once(x))) }
            }
            Expr::RepOnce(x) => {
                let x = self.expr(x, atomic)?;
                if atomic { Node::Plus(Box::new(x)) } else { self.rep_once(x) }
            }
            Expr::NegPred(_) | Expr::PosPred(_) => {
                return Err(format!("lookahead `{e:?}` outside a sequence has no CFG form"));
            }
            other => return Err(format!("pest construct not supported by the export: {other:?}")),
        })
    }

    fn rep_once(&mut self, x: Node) -> Node {
        let ws = self.ws();
        Node::Seq(vec![x.clone(), Node::Star(Box::new(Node::Seq(vec![ws, x])))])
    }

    fn ident(&mut self, name: &str, atomic: bool) -> Result<Node, String> {
        let range = |a, b| ClassItem::Range(a, b);
        Ok(match name {
            "SOI" | "EOI" => Node::Empty,
            "ASCII_DIGIT" => Node::Class { negated: false, items: vec![range('0', '9')] },
            "ASCII_ALPHA" => Node::Class { negated: false, items: vec![range('a', 'z'), range('A', 'Z')] },
            "ASCII_ALPHANUMERIC" => {
                Node::Class { negated: false, items: vec![range('a', 'z'), range('A', 'Z'), range('0', '9')] }
            }
            "ANY" => Node::Class { negated: true, items: vec![] },
            _ if self.defs.contains_key(name) => {
                self.want(name, atomic)?;
                Node::Ref(name.to_string())
            }
            _ => return Err(format!("unknown rule or builtin `{name}`")),
        })
    }

    /// A sequence: whitespace between the parts of non-atomic ones, and the lookahead idioms.
    fn seq(&mut self, parts: &[&Expr], atomic: bool) -> Result<Node, String> {
        let mut out: Vec<Node> = vec![];
        let mut i = 0;
        while i < parts.len() {
            let node = match parts[i] {
                // `!X ~ ANY`: any one character except those X can start with.
                Expr::NegPred(x) if matches!(parts.get(i + 1), Some(Expr::Ident(a)) if a == "ANY") => {
                    i += 1;
                    Node::Class { negated: true, items: single_chars(x)? }
                }
                // Word boundaries and other lookaheads: dropped (the CFG over-approximates).
                Expr::NegPred(_) | Expr::PosPred(_) => {
                    i += 1;
                    continue;
                }
                p => self.expr(p, atomic)?,
            };
            if !atomic && !out.is_empty() {
                let ws = self.ws();
                out.push(ws);
            }
            out.push(node);
            i += 1;
        }
        Ok(match out.len() {
            0 => Node::Empty,
            1 => out.pop().expect("one element"),
            _ => Node::Seq(out),
        })
    }
}

fn flatten_seq<'e>(e: &'e Expr, out: &mut Vec<&'e Expr>) {
    match e {
        Expr::Seq(a, b) => {
            flatten_seq(a, out);
            flatten_seq(b, out);
        }
        e => out.push(e),
    }
}

fn flatten_choice<'e>(e: &'e Expr, out: &mut Vec<&'e Expr>) {
    match e {
        Expr::Choice(a, b) => {
            flatten_choice(a, out);
            flatten_choice(b, out);
        }
        e => out.push(e),
    }
}

fn ch(s: &str) -> Result<char, String> {
    let t = s.trim_matches('\'');
    let mut it = t.chars();
    match (it.next(), it.next()) {
        (Some(c), None) => Ok(c),
        _ => Err(format!("character range bound `{s}` is not one character")),
    }
}

/// The characters of `"a" | "b" | ...` (the X of `!X ~ ANY`).
fn single_chars(x: &Expr) -> Result<Vec<ClassItem>, String> {
    let mut alts = vec![];
    flatten_choice(x, &mut alts);
    let mut set = BTreeSet::new();
    for a in alts {
        match a {
            Expr::Str(s) if s.chars().count() == 1 => {
                set.insert(s.chars().next().expect("one char"));
            }
            other => return Err(format!("`!X ~ ANY` needs single characters in X, found {other:?}")),
        }
    }
    Ok(set.into_iter().map(ClassItem::Char).collect())
}
