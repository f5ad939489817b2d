//! A small GBNF reader and Earley recogniser, enough to prove what `rocc grammar --format gbnf`
//! prints accepts or rejects a file (the same text a llama.cpp server would be given).

use std::collections::{HashMap, HashSet};

#[derive(Clone, Debug, PartialEq)]
enum Sym {
    Nt(usize),
    Chars { negated: bool, ranges: Vec<(char, char)> },
}

pub struct Grammar {
    rules: Vec<(usize, Vec<Sym>)>,
    names: HashMap<String, usize>,
    count: usize,
    nullable: Vec<bool>,
}

struct Reader<'a> {
    s: Vec<char>,
    i: usize,
    g: &'a mut Grammar,
}

impl Grammar {
    pub fn parse(text: &str) -> Grammar {
        let mut g = Grammar { rules: vec![], names: HashMap::new(), count: 0, nullable: vec![] };
        for line in text.lines().map(str::trim).filter(|l| !l.is_empty() && !l.starts_with('#')) {
            let (name, body) = line.split_once("::=").unwrap_or_else(|| panic!("not a rule: {line}"));
            let lhs = g.nt(name.trim());
            let mut r = Reader { s: body.chars().collect(), i: 0, g: &mut g };
            let alts = r.alts();
            r.ws();
            assert_eq!(r.i, r.s.len(), "trailing text in rule {name}: {body}");
            for a in alts {
                g.rules.push((lhs, a));
            }
        }
        for (n, id) in &g.names {
            assert!(g.rules.iter().any(|(l, _)| l == id), "rule `{n}` is used but never defined");
        }
        g.nullable = vec![false; g.count];
        loop {
            let mut changed = false;
            for (l, rhs) in &g.rules {
                if !g.nullable[*l] && rhs.iter().all(|s| matches!(s, Sym::Nt(n) if g.nullable[*n])) {
                    g.nullable[*l] = true;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        g
    }

    fn nt(&mut self, name: &str) -> usize {
        if let Some(i) = self.names.get(name) {
            return *i;
        }
        self.count += 1;
        self.names.insert(name.to_string(), self.count - 1);
        self.count - 1
    }

    fn fresh(&mut self) -> usize {
        self.count += 1;
        self.count - 1
    }

    /// Earley recognition of `input` from `root`.
    pub fn accepts(&self, input: &str) -> bool {
        let root = self.names["root"];
        let text: Vec<char> = input.chars().collect();
        let n = text.len();
        let mut by_lhs: HashMap<usize, Vec<usize>> = HashMap::new();
        for (i, (l, _)) in self.rules.iter().enumerate() {
            by_lhs.entry(*l).or_default().push(i);
        }
        type Item = (usize, usize, usize);
        let mut sets: Vec<Vec<Item>> = vec![vec![]; n + 1];
        let mut seen: Vec<HashSet<Item>> = vec![HashSet::new(); n + 1];
        let add = |sets: &mut Vec<Vec<Item>>, seen: &mut Vec<HashSet<Item>>, k: usize, it: Item| {
            if seen[k].insert(it) {
                sets[k].push(it);
            }
        };
        for r in &by_lhs[&root] {
            add(&mut sets, &mut seen, 0, (*r, 0, 0));
        }
        for k in 0..=n {
            let mut j = 0;
            while j < sets[k].len() {
                let (r, dot, origin) = sets[k][j];
                j += 1;
                let (lhs, rhs) = &self.rules[r];
                match rhs.get(dot) {
                    Some(Sym::Nt(b)) => {
                        for r2 in by_lhs.get(b).into_iter().flatten() {
                            add(&mut sets, &mut seen, k, (*r2, 0, k));
                        }
                        if self.nullable[*b] {
                            add(&mut sets, &mut seen, k, (r, dot + 1, origin));
                        }
                    }
                    Some(Sym::Chars { negated, ranges }) => {
                        if k < n {
                            let c = text[k];
                            if ranges.iter().any(|(a, b)| *a <= c && c <= *b) != *negated {
                                add(&mut sets, &mut seen, k + 1, (r, dot + 1, origin));
                            }
                        }
                    }
                    None => {
                        let parents: Vec<Item> = sets[origin]
                            .iter()
                            .filter(|(pr, pd, _)| self.rules[*pr].1.get(*pd) == Some(&Sym::Nt(*lhs)))
                            .copied()
                            .collect();
                        for (pr, pd, po) in parents {
                            add(&mut sets, &mut seen, k, (pr, pd + 1, po));
                        }
                    }
                }
            }
            if k < n && sets[k + 1].is_empty() {
                return false;
            }
        }
        sets[n].iter().any(|(r, dot, o)| *o == 0 && self.rules[*r].0 == root && *dot == self.rules[*r].1.len())
    }
}

impl Reader<'_> {
    fn ws(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_whitespace() {
            self.i += 1;
        }
    }
    fn peek(&mut self) -> Option<char> {
        self.ws();
        self.s.get(self.i).copied()
    }
    fn alts(&mut self) -> Vec<Vec<Sym>> {
        let mut out = vec![self.seq()];
        while self.peek() == Some('|') {
            self.i += 1;
            out.push(self.seq());
        }
        out
    }
    fn seq(&mut self) -> Vec<Sym> {
        let mut out = vec![];
        while let Some(c) = self.peek() {
            if c == '|' || c == ')' {
                break;
            }
            let atom = self.atom();
            match self.s.get(self.i) {
                Some('?') | Some('*') | Some('+') => {
                    let op = self.s[self.i];
                    self.i += 1;
                    let n = self.g.fresh();
                    let inner = atom;
                    match op {
                        '?' => {
                            self.g.rules.push((n, vec![]));
                            self.g.rules.push((n, inner));
                        }
                        '*' => {
                            self.g.rules.push((n, vec![]));
                            self.g.rules.push((n, [vec![Sym::Nt(n)], inner].concat()));
                        }
                        _ => {
                            self.g.rules.push((n, inner.clone()));
                            self.g.rules.push((n, [vec![Sym::Nt(n)], inner].concat()));
                        }
                    }
                    out.push(Sym::Nt(n));
                }
                _ => out.extend(atom),
            }
        }
        out
    }
    fn esc(&mut self) -> char {
        let c = self.s[self.i];
        self.i += 1;
        if c != '\\' {
            return c;
        }
        let e = self.s[self.i];
        self.i += 1;
        match e {
            'n' => '\n',
            'r' => '\r',
            't' => '\t',
            'x' => {
                let h: String = self.s[self.i..self.i + 2].iter().collect();
                self.i += 2;
                char::from_u32(u32::from_str_radix(&h, 16).unwrap()).unwrap()
            }
            c => c,
        }
    }
    /// One atom as a symbol sequence (a literal is one symbol per character).
    fn atom(&mut self) -> Vec<Sym> {
        match self.peek().expect("an atom") {
            '"' => {
                self.i += 1;
                let mut out = vec![];
                while self.s[self.i] != '"' {
                    let c = self.esc();
                    out.push(Sym::Chars { negated: false, ranges: vec![(c, c)] });
                }
                self.i += 1;
                out
            }
            '[' => {
                self.i += 1;
                let negated = self.s[self.i] == '^';
                if negated {
                    self.i += 1;
                }
                let mut ranges = vec![];
                while self.s[self.i] != ']' {
                    let a = self.esc();
                    if self.s[self.i] == '-' && self.s[self.i + 1] != ']' {
                        self.i += 1;
                        let b = self.esc();
                        ranges.push((a, b));
                    } else {
                        ranges.push((a, a));
                    }
                }
                self.i += 1;
                vec![Sym::Chars { negated, ranges }]
            }
            '(' => {
                self.i += 1;
                let alts = self.alts();
                assert_eq!(self.peek(), Some(')'));
                self.i += 1;
                let n = self.g.fresh();
                for a in alts {
                    self.g.rules.push((n, a));
                }
                vec![Sym::Nt(n)]
            }
            _ => {
                let start = self.i;
                while self.i < self.s.len() && (self.s[self.i].is_ascii_alphanumeric() || self.s[self.i] == '-') {
                    self.i += 1;
                }
                assert!(self.i > start, "unexpected `{}`", self.s[self.i]);
                let name: String = self.s[start..self.i].iter().collect();
                vec![Sym::Nt(self.g.nt(&name))]
            }
        }
    }
}
