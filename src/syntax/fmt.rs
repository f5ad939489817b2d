//! The canonical layout of a `.scn` file. The AST is lowered to a small document tree (lines and
//! blocks), printed with 4-space indentation; a block written on one line stays on one line when
//! it fits in 100 columns and holds no comment, otherwise it is expanded. Comments are
//! not in the AST: they are re-attached by position, own-line or trailing as they were written.
//! Single blank lines between statements are kept.

use super::ast::*;
use crate::source::Span;

const WIDTH: usize = 100;

enum Doc {
    Line { span: Span, text: String },
    Block { header: String, span: Span, items: Vec<Doc>, fit: bool },
}

struct Comment {
    start: usize,
    end: usize,
    trailing: bool,
}

/// Format a parsed file whose source is `src`.
pub fn format_file(file: &File, src: &str) -> String {
    let docs: Vec<Doc> = file.items.iter().map(item).collect();
    let mut p =
        Printer { src, out: String::new(), indent: 0, comments: comments(src), next: 0, last_end: 0, opened: true };
    for d in &docs {
        p.print(d);
    }
    p.flush_before(src.len());
    let mut out = p.out;
    while out.ends_with("\n\n") {
        out.pop();
    }
    if !out.ends_with('\n') {
        out.push('\n');
    }
    out
}

fn item(it: &Item) -> Doc {
    match it {
        Item::Use(u) => Doc::Line { span: u.span, text: format!("use \"{}\"", u.path) },
        Item::Kind(k) => Doc::Block {
            header: format!("kind {}: {}", k.name.name, k.class.name),
            span: k.span,
            items: k
                .stmts
                .iter()
                .map(|s| match s {
                    KindStmt::Size(s) => size(s),
                    KindStmt::Motion { motion, span } => {
                        Doc::Line { span: *span, text: format!("motion {}", motion.name) }
                    }
                    KindStmt::Mass { value, span } => Doc::Line { span: *span, text: format!("mass {}", val(value)) },
                })
                .collect(),
            fit: true,
        },
        Item::Scenario(s) => Doc::Block {
            header: format!("scenario {}", s.name.name),
            span: s.span,
            items: s.stmts.iter().map(scenario_stmt).collect(),
            fit: false,
        },
    }
}

fn scenario_stmt(s: &ScenarioStmt) -> Doc {
    let line = |text: String| Doc::Line { span: s.span(), text };
    match s {
        ScenarioStmt::Seed { literal, .. } => line(format!("seed {literal}")),
        ScenarioStmt::Duration { value, .. } => line(format!("duration {}", val(value))),
        ScenarioStmt::Rate { value, .. } => line(format!("rate {}", val(value))),
        ScenarioStmt::Egos { egos, .. } => line(match egos {
            Egos::Vehicles => "egos vehicles".to_string(),
            Egos::List(l) => format!("egos [{}]", l.iter().map(|i| i.name.as_str()).collect::<Vec<_>>().join(", ")),
        }),
        ScenarioStmt::Road(r) if r.params.is_empty() && r.kerb.is_empty() => line(format!("road {}", r.template.name)),
        ScenarioStmt::Road(r) => {
            Doc::Block { header: format!("road {}", r.template.name), span: r.span, items: road_items(r), fit: true }
        }
        ScenarioStmt::Traffic(t) => Doc::Block {
            header: "traffic".into(),
            span: t.span,
            items: t.params.iter().map(param).collect(),
            fit: true,
        },
        ScenarioStmt::Agent(a) => Doc::Block {
            header: format!("{} {}: {}", if a.is_object { "object" } else { "agent" }, a.name.name, kind_ref(&a.kind)),
            span: a.span,
            items: a.stmts.iter().map(agent_stmt).collect(),
            fit: true,
        },
        ScenarioStmt::Row(r) => line(format!(
            "row {} from {} to {} every {}",
            kind_ref(&r.kind),
            placement(&r.from),
            placement(&r.to),
            val(&r.every)
        )),
        ScenarioStmt::Conflict(c) => key_fields("conflict", c),
        ScenarioStmt::NearMiss(c) => key_fields("near_miss", c),
        ScenarioStmt::Expect(e) => Doc::Block {
            header: "expect".into(),
            span: e.span,
            items: e.items.iter().map(|x| Doc::Line { span: x.span, text: expectation(x) }).collect(),
            fit: false,
        },
    }
}

/// A `conflict` or `near_miss` block, one `KEY VALUE` line per field.
fn key_fields(header: &str, c: &Conflict) -> Doc {
    Doc::Block {
        header: header.into(),
        span: c.span,
        items: c
            .fields
            .iter()
            .map(|f| Doc::Line {
                span: f.span,
                text: format!(
                    "{} {}",
                    f.key,
                    match &f.value {
                        FieldValue::Ident(i) => i.name.clone(),
                        FieldValue::Value(v) => val(v),
                    }
                ),
            })
            .collect(),
        fit: true,
    }
}

/// One expectation in canonical form (also the name `rocc test` reports it by).
pub fn expectation(x: &Expectation) -> String {
    let bound = |b: &Bound| if b.at_least { "at_least" } else { "at_most" };
    let mut s = match &x.what {
        ExpectWhat::Contact { a, b, side } => {
            let on = side.as_ref().map_or(String::new(), |s| format!(" on {}", s.name));
            format!("contact {} with {}{on}", a.name, b.name)
        }
        ExpectWhat::NoContact { pair: None } => "no_contact".to_string(),
        ExpectWhat::NoContact { pair: Some((a, b)) } => format!("no_contact {} with {}", a.name, b.name),
        ExpectWhat::Gap { a, b, bound: k, value } => {
            format!("gap {} with {} {} {}", a.name, b.name, bound(k), val(value))
        }
        ExpectWhat::Stopped { agent, landmark } => format!("stopped {} before {}", agent.name, landmark.name),
        ExpectWhat::Reach { agent, landmark } => format!("reach {} {}", agent.name, landmark.name),
        ExpectWhat::Speed { agent, bound: k, value } => format!("speed {} {} {}", agent.name, bound(k), val(value)),
        ExpectWhat::Enters { agent, light } => format!("enters {} on {}", agent.name, light.name),
    };
    if let Some(w) = &x.window {
        s.push_str(&format!(" {} {}", if w.by { "by" } else { "during" }, val(&w.value)));
    }
    s
}

fn agent_stmt(s: &AgentStmt) -> Doc {
    match s {
        AgentStmt::At { place, span } => Doc::Line { span: *span, text: format!("at {}", placement(place)) },
        AgentStmt::Speed { value, span } => Doc::Line { span: *span, text: format!("speed {}", val(value)) },
        AgentStmt::Siren { value, span } => Doc::Line { span: *span, text: format!("siren {}", value.name) },
        AgentStmt::Lamp { key, value, span } => Doc::Line { span: *span, text: format!("{} {}", key.name, value.name) },
        AgentStmt::Door(d) => {
            let tail = match (&d.at, &d.when) {
                (Some(v), _) => format!("at {}", val(v)),
                (None, Some(w)) => trigger(w),
                (None, None) => String::new(),
            };
            Doc::Line { span: d.span, text: format!("door {} {} {tail}", d.door.name, d.action.name) }
        }
        AgentStmt::Mass { value, span } => Doc::Line { span: *span, text: format!("mass {}", val(value)) },
        AgentStmt::Size(s) => size(s),
        AgentStmt::Goal(g) => Doc::Block {
            header: "goal".into(),
            span: g.span,
            items: g.stmts.iter().map(|s| Doc::Line { span: s.span(), text: goal_stmt(s) }).collect(),
            fit: true,
        },
        AgentStmt::Behaviour(b) => Doc::Block {
            header: "behaviour".into(),
            span: b.span,
            items: b
                .sets
                .iter()
                .map(|x| Doc::Line {
                    span: x.span,
                    text: match &x.value {
                        FieldValue::Ident(i) => format!("{} {}", x.name.name, i.name),
                        FieldValue::Value(v) => format!("{} {}", x.name.name, val(v)),
                    },
                })
                .collect(),
            fit: true,
        },
        AgentStmt::Track(t) => Doc::Block {
            header: t.when.as_ref().map_or("track".into(), |w| format!("track {}", trigger(w))),
            span: t.span,
            items: t
                .keys
                .iter()
                .map(|k| Doc::Line {
                    span: k.span,
                    text: match &k.pose {
                        KeyPose::World { x, y, yaw } => {
                            format!("{}: ({}, {}) yaw {}", val(&k.t), val(x), val(y), val(yaw))
                        }
                        KeyPose::Lane(p) => format!("{}: {}", val(&k.t), placement(p)),
                    },
                })
                .collect(),
            fit: false,
        },
        AgentStmt::Posture { word, span } => Doc::Line { span: *span, text: format!("posture {}", word.name) },
        AgentStmt::Flag(f) => Doc::Block {
            header: "flag".into(),
            span: f.span,
            items: f.steps.iter().map(|x| Doc::Line { span: x.span, text: flag_step(x) }).collect(),
            fit: true,
        },
    }
}

fn flag_step(x: &FlagStep) -> String {
    match &x.when {
        FlagWhen::Start => x.state.name.clone(),
        FlagWhen::After(v) => format!("{} after {}", x.state.name, val(v)),
        FlagWhen::For(v) => format!("{} {}", x.state.name, val(v)),
        FlagWhen::When(w) => format!("{} {}", x.state.name, trigger(w)),
    }
}

fn goal_stmt(s: &GoalStmt) -> String {
    match s {
        GoalStmt::Speed { value, .. } => format!("speed {}", val(value)),
        GoalStmt::Lateral { lateral, .. } => match lateral {
            Lateral::Word(w) => format!("lateral {}", w.name),
            Lateral::ChangeLane(side) => format!("lateral change_lane {}", side.name),
            Lateral::AwayFrom(n) => format!("lateral away_from {}", n.name),
        },
        GoalStmt::Stop { stop, .. } => match stop {
            Stop::At(w) => format!("stop at {}", w.name),
            Stop::Behind(n) => format!("stop behind {}", n.name),
            Stop::After(v) => format!("stop after {}", val(v)),
        },
        GoalStmt::Turn { turn, .. } => format!("turn {}", turn.name),
        GoalStmt::Start { after, .. } => format!("start after {}", val(after)),
        GoalStmt::StartWhen { trigger: w, .. } => format!("start {}", trigger(w)),
        GoalStmt::Reverse { to: ReverseTo::Dist(v), .. } => format!("reverse {}", val(v)),
        GoalStmt::Reverse { to: ReverseTo::Into(l), .. } => {
            format!("reverse into {}.{}[{}]", l.arm.name, if l.dir == Dir::In { "in" } else { "out" }, l.index)
        }
    }
}

/// `when NAME CONDITION [under] [VALUE | LANDMARK]`.
fn trigger(w: &Trigger) -> String {
    let tail = match (&w.value, &w.landmark) {
        (Some(v), _) => format!(" {}{}", if w.under { "under " } else { "" }, val(v)),
        (None, Some(l)) => format!(" {}", l.name),
        (None, None) => String::new(),
    };
    format!("when {} {}{tail}", w.who.name, w.cond.name)
}

fn size(s: &SizeStmt) -> Doc {
    Doc::Line { span: s.span, text: format!("{} {}", s.key.as_str(), val(&s.value)) }
}

/// A road block's parameters and kerbside places, in source order.
fn road_items(r: &Road) -> Vec<Doc> {
    let dir = |d: Dir| if d == Dir::In { "in" } else { "out" };
    let kerb = r.kerb.iter().map(|k| match k {
        KerbDecl::Parking { arm, side, width, span } => {
            let w = width.as_ref().map(|w| format!(" {}", val(w))).unwrap_or_default();
            (span.start, Doc::Line { span: *span, text: format!("parking {} {}{w}", arm.name, side.name) })
        }
        KerbDecl::Driveway { name, side, at, span } => (
            span.start,
            Doc::Line {
                span: *span,
                text: format!("driveway {} {}.{} {}", name.name, side.arm.name, dir(side.dir), val(at)),
            },
        ),
    });
    let mut items: Vec<(u32, Doc)> = r.params.iter().map(|p| (p.span.start, param(p))).chain(kerb).collect();
    items.sort_by_key(|(start, _)| *start);
    items.into_iter().map(|(_, d)| d).collect()
}

fn param(p: &Param) -> Doc {
    let v = match &p.value {
        ParamValue::Value(v) => val(v),
        ParamValue::Switch { on, .. } => (if *on { "on" } else { "off" }).to_string(),
    };
    Doc::Line { span: p.span, text: format!("{} {v}", p.name.name) }
}

fn kind_ref(k: &KindRef) -> String {
    match k {
        KindRef::Named(i) => i.name.clone(),
        KindRef::OneOf { kinds, .. } => {
            format!("one_of [{}]", kinds.iter().map(|i| i.name.as_str()).collect::<Vec<_>>().join(", "))
        }
    }
}

/// The canonical text of a placement (also used by importers that write `.scn`).
pub fn placement(p: &Placement) -> String {
    let tail = |offset: &Option<Offset>, heading: &Option<Value>| {
        let mut s = String::new();
        if let Some(o) = offset {
            s += &format!(" offset {} {}", val(&o.dist), o.side.name);
        }
        if let Some(h) = heading {
            s += &format!(" heading {}", val(h));
        }
        s
    };
    let along = |a: &Along| {
        format!("{} {} {}", val(&a.dist), if a.rel == Rel::Before { "before" } else { "after" }, a.landmark.name)
    };
    let dir = |d: Dir| if d == Dir::In { "in" } else { "out" };
    match p {
        Placement::Lane { lane, along: a, offset, heading, .. } => {
            format!("{}.{}[{}], {}{}", lane.arm.name, dir(lane.dir), lane.index, along(a), tail(offset, heading))
        }
        Placement::World { x, y, heading, .. } => format!("({}, {}){}", val(x), val(y), tail(&None, heading)),
        Placement::Crosswalk { arm, fraction, .. } => format!("crosswalk({}), {}", arm.name, val(fraction)),
        Placement::Sidewalk { side, along: a, offset, heading, .. } => {
            format!("sidewalk({}.{}), {}{}", side.arm.name, dir(side.dir), along(a), tail(offset, heading))
        }
        Placement::Parking { side, slot, .. } => format!("parking({}.{})[{slot}]", side.arm.name, dir(side.dir)),
        Placement::Driveway { name, .. } => format!("driveway({})", name.name),
    }
}

/// The canonical text of a value: the literals as written, one space before the unit.
pub fn val(v: &Value) -> String {
    let mut s = v.lo.literal.clone();
    if let Some(hi) = &v.hi {
        s += "..";
        s += &hi.literal;
    }
    if let Some(u) = &v.unit {
        s += " ";
        s += &u.text;
    }
    s
}

fn comments(src: &str) -> Vec<Comment> {
    let b = src.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    let mut line_has_code = false;
    while i < b.len() {
        match b[i] {
            b'\n' => line_has_code = false,
            b'"' => {
                line_has_code = true;
                i += 1;
                while i < b.len() && b[i] != b'"' && b[i] != b'\n' {
                    i += 1;
                }
                if i < b.len() && b[i] == b'\n' {
                    line_has_code = false;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'/') => {
                let start = i;
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
                out.push(Comment { start, end: i, trailing: line_has_code });
                continue;
            }
            c if !c.is_ascii_whitespace() => line_has_code = true,
            _ => {}
        }
        i += 1;
    }
    out
}

struct Printer<'a> {
    src: &'a str,
    out: String,
    indent: usize,
    comments: Vec<Comment>,
    next: usize,
    /// End of the last thing printed, in the source: blank lines after it are kept.
    last_end: usize,
    /// True right after a `{` line: no blank line there.
    opened: bool,
}

impl Printer<'_> {
    fn blank_line_before(&mut self, pos: usize) {
        if self.opened || self.out.is_empty() {
            return;
        }
        let gap = &self.src[self.last_end.min(pos)..pos];
        let blank = gap.split('\n').skip(1).collect::<Vec<_>>();
        // A blank line is a line in the gap (not the first, not the last) holding only spaces.
        if blank.len() >= 2 && blank[..blank.len() - 1].iter().any(|l| l.trim().is_empty()) {
            self.out.push('\n');
        }
    }

    fn line(&mut self, text: &str) {
        for _ in 0..self.indent {
            self.out.push_str("    ");
        }
        self.out.push_str(text);
        self.out.push('\n');
        self.opened = false;
    }

    fn flush_before(&mut self, pos: usize) {
        while self.next < self.comments.len() && self.comments[self.next].start < pos {
            let c = &self.comments[self.next];
            let (start, end, trailing) = (c.start, c.end, c.trailing);
            let text = self.src[start..end].trim_end().to_string();
            if trailing && self.out.ends_with('\n') && !self.out.is_empty() {
                self.out.pop();
                self.out.push_str("  ");
                self.out.push_str(&text);
                self.out.push('\n');
            } else {
                self.blank_line_before(start);
                self.line(&text);
            }
            self.last_end = end;
            self.next += 1;
        }
    }

    fn has_comment_in(&self, span: Span) -> bool {
        self.comments[self.next..].iter().any(|c| c.start >= span.start as usize && c.start < span.end as usize)
    }

    fn print(&mut self, d: &Doc) {
        match d {
            Doc::Line { span, text } => {
                self.flush_before(span.start as usize);
                self.blank_line_before(span.start as usize);
                self.line(text);
                // A statement ending in an optional part that is absent (`rate 1`, no unit) has
                // the whitespace after it in its span (pest skips it before trying the part): the
                // gap to the next one, and any blank line in it, starts where its text ends.
                let end = span.end as usize;
                self.last_end = span.start as usize + self.src[span.start as usize..end].trim_end().len();
                self.flush_before(span.end as usize);
            }
            Doc::Block { header, span, items, .. } => {
                self.flush_before(span.start as usize);
                self.blank_line_before(span.start as usize);
                // Like prettier's objects: a block the author wrote on one line stays on one line
                // if it fits; one written across lines stays expanded.
                let one_line = !self.src[span.range()].contains('\n');
                let inline = inline(d);
                let fits = inline.as_ref().is_some_and(|s| s.len() + 4 * self.indent <= WIDTH);
                if one_line && fits && !self.has_comment_in(*span) {
                    self.line(&inline.expect("checked above"));
                    self.last_end = span.end as usize;
                    return;
                }
                self.line(&format!("{header} {{"));
                self.opened = true;
                self.indent += 1;
                for it in items {
                    self.print(it);
                }
                // Comments before the closing brace stay inside the block.
                self.flush_before((span.end as usize).saturating_sub(1));
                self.indent -= 1;
                self.line("}");
                self.last_end = span.end as usize;
            }
        }
    }
}

/// One-line form of a block that allows it (`fit`), recursively.
fn inline(d: &Doc) -> Option<String> {
    match d {
        Doc::Line { text, .. } => Some(text.clone()),
        Doc::Block { fit: false, .. } => None,
        Doc::Block { header, items, .. } if items.is_empty() => Some(format!("{header} {{}}")),
        Doc::Block { header, items, .. } => {
            let parts: Option<Vec<String>> = items.iter().map(inline).collect();
            Some(format!("{header} {{ {} }}", parts?.join("; ")))
        }
    }
}
