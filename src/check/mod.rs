//! Check pass. In: the AST of one scenario plus every kind in scope (stdlib, `use`d files).
//! Out: `scenario::Scenario` — names resolved, units converted to SI, domain rules enforced —
//! or every diagnostic found (the checker keeps going after an error to report them all).

pub mod classes;
pub mod load;
pub mod scenario;
pub mod summary;
pub mod units;

use crate::diag::{Diagnostic, did_you_mean};
use crate::source::{SourceMap, Span};
use crate::syntax::ast;
use scenario::*;
use std::collections::BTreeMap;
use std::path::Path;
use units::Dim;

/// Caps that keep a typo from asking for a week of compute.
pub const MAX_DURATION_S: f64 = 120.0;
pub const MAX_RATE_HZ: f64 = 100.0;
pub const MAX_SPEED_MS: f64 = 90.0;
pub const MAX_LANES: u32 = 6;
pub const MAX_ROW_OBJECTS: usize = 500;

/// Load, parse and check a scenario file.
pub fn check_path(path: &Path, sources: &mut SourceMap) -> Result<Scenario, Vec<Diagnostic>> {
    let program = load::load_path(path, sources)?;
    check_program(&program)
}

/// Parse and check scenario text (imports resolve against `base`).
pub fn check_text(name: &str, text: &str, base: &Path, sources: &mut SourceMap) -> Result<Scenario, Vec<Diagnostic>> {
    let program = load::load_text(name, text, base, sources)?;
    check_program(&program)
}

pub fn check_program(p: &load::Program) -> Result<Scenario, Vec<Diagnostic>> {
    let mut c = Checker { diags: vec![], kinds: BTreeMap::new() };
    c.kinds(&p.kinds);
    let s = c.scenario(&p.scenario);
    if c.diags.iter().any(Diagnostic::is_error) {
        c.diags.sort_by_key(|d| d.span().map(|s| (s.file, s.start)));
        Err(c.diags)
    } else {
        Ok(s.expect("a scenario is built whenever no error was reported"))
    }
}

/// Every road parameter of any template, in the order the decoding grammar offers them
/// (the scenario library's order).
pub const ROAD_PARAMS: [&str; 10] = [
    "lanes",
    "lane_width",
    "radius",
    "angle",
    "speed_limit",
    "shoulder",
    "median",
    "crosswalks",
    "sidewalks",
    "length",
];

struct Checker {
    diags: Vec<Diagnostic>,
    kinds: BTreeMap<String, (Kind, Span)>,
}

/// Look a word up in a closed vocabulary, reporting E0116 with a suggestion.
fn word<T: Copy>(c: &mut Checker, ident: &ast::Ident, table: &[(&str, T)], what: &str) -> Option<T> {
    if let Some((_, v)) = table.iter().find(|(n, _)| *n == ident.name) {
        return Some(*v);
    }
    let names: Vec<&str> = table.iter().map(|(n, _)| *n).collect();
    c.diags.push(
        Diagnostic::error("E0116", format!("unknown {what} `{}`", ident.name))
            .label(ident.span, format!("not a {what}"))
            .help(did_you_mean(&ident.name, &names, what)),
    );
    None
}

impl Checker {
    fn err(&mut self, d: Diagnostic) {
        self.diags.push(d);
    }

    /// Convert a value to SI, checking its dimension. Ranges become uniform distributions.
    fn quantity(&mut self, v: &ast::Value, dim: Dim, what: &str) -> Option<Dist> {
        let (got, factor) = match &v.unit {
            Some(u) => units::unit(&u.text),
            None => (Dim::Count, 1.0),
        };
        let got = if dim == Dim::Ratio && got == Dim::Count { Dim::Ratio } else { got };
        if got != dim {
            let d = if got == Dim::Count {
                Diagnostic::error("E0102", format!("{what} needs a unit"))
                    .label(v.span, format!("expected {}", dim.name()))
                    .help(format!("write the unit: {}", dim.units()))
            } else {
                let written = crate::syntax::fmt::val(v);
                Diagnostic::error("E0101", format!("{what} needs {}, but `{written}` is {}", dim.units(), got.name()))
                    .label(
                        v.span,
                        format!(
                            "{} here, expected {}",
                            got.name().trim_start_matches("a ").trim_start_matches("an "),
                            dim.name()
                        ),
                    )
                    .help(format!("{what} needs {}{}", dim.units(), units::hint(dim, got, v)))
            };
            self.err(d);
            return None;
        }
        let lo = v.lo.value * factor;
        match &v.hi {
            None => Some(Dist::Fixed(lo)),
            Some(hi) => {
                let hi = hi.value * factor;
                if hi < lo {
                    self.err(
                        Diagnostic::error("E0104", format!("range of {what} is reversed"))
                            .label(v.span, "lower bound is larger than upper bound")
                            .help(format!(
                                "write it as {}..{}",
                                v.hi.as_ref().map_or("", |h| &h.literal),
                                v.lo.literal
                            )),
                    );
                    return None;
                }
                Some(if hi == lo { Dist::Fixed(lo) } else { Dist::Uniform(lo, hi) })
            }
        }
    }

    /// A quantity that must lie within [min, max] (SI).
    fn bounded(&mut self, v: &ast::Value, dim: Dim, what: &str, min: f64, max: f64, shown: &str) -> Option<Dist> {
        let d = self.quantity(v, dim, what)?;
        if d.lo() < min || d.hi() > max {
            let mut e = Diagnostic::error("E0103", format!("{what} is out of range"))
                .label(v.span, format!("must be within {shown}"))
                .help(format!("{what} must be within {shown}"));
            if let Some(meant) = units::slip(v, dim, min, max, shown) {
                let written = crate::syntax::fmt::val(v);
                e = e.and_help(format!(
                    "did you mean `{meant}`? `{written}` is far outside, so the unit looks like a slip"
                ));
            }
            self.err(e);
            return None;
        }
        Some(d)
    }

    fn fixed(&mut self, v: &ast::Value, dim: Dim, what: &str, min: f64, max: f64, shown: &str) -> Option<f64> {
        let d = self.bounded(v, dim, what, min, max, shown)?;
        match d {
            Dist::Fixed(x) => Some(x),
            Dist::Uniform(..) => {
                self.err(
                    Diagnostic::error("E0103", format!("{what} cannot be a range"))
                        .label(v.span, "a single value is needed here")
                        .help("ranges are allowed for sizes, speeds, distances and headings"),
                );
                None
            }
        }
    }

    fn dup(&mut self, what: &str, first: Span, second: Span) {
        self.err(
            Diagnostic::error("E0105", format!("{what} is given twice"))
                .label(second, "second one here")
                .label(first, "first one here")
                .help("keep one of them"),
        );
    }

    // ---------------------------------------------------------------- kinds

    fn kinds(&mut self, decls: &[ast::KindDecl]) {
        for k in decls {
            if let Some((_, first)) = self.kinds.get(&k.name.name) {
                let first = *first;
                self.dup(&format!("kind `{}`", k.name.name), first, k.name.span);
                continue;
            }
            // After the colon, a class; else an earlier kind, whose class, motion, box priors and
            // emergency status the new kind inherits (its own statements override them).
            let is_class = Class::ALL.iter().any(|(n, _)| *n == k.class.name);
            let parent = self.kinds.get(&k.class.name).filter(|_| !is_class).map(|(p, _)| p.clone());
            let class = match &parent {
                Some(p) => p.class,
                None => {
                    let Some(class) = word(self, &k.class, &Class::ALL, "class") else { continue };
                    class
                }
            };
            let mut motion = parent.as_ref().map_or(class.default_motion(), |p| p.motion);
            let mut size: [Option<Dist>; 3] =
                parent.as_ref().map_or([None; 3], |p| [Some(p.length), Some(p.width), Some(p.height)]);
            let emergency = EMERGENCY_KINDS.contains(&k.name.name.as_str()) || parent.is_some_and(|p| p.emergency);
            for s in &k.stmts {
                match s {
                    ast::KindStmt::Motion { motion: m, .. } => {
                        if let Some(m) = word(self, m, &MOTIONS, "motion") {
                            motion = m;
                        }
                    }
                    ast::KindStmt::Size(s) => {
                        let what = format!("kind {}", s.key.as_str());
                        size[s.key as usize] = self.bounded(&s.value, Dim::Length, &what, 0.01, 40.0, "0.01..40 m");
                    }
                }
            }
            let missing: Vec<&str> =
                ["length", "width", "height"].iter().zip(size).filter(|(_, s)| s.is_none()).map(|(n, _)| *n).collect();
            if !missing.is_empty() {
                if !self.diags.iter().any(|d| {
                    d.span().is_some_and(|s| s.file == k.span.file && s.start >= k.span.start && s.end <= k.span.end)
                }) {
                    self.err(
                        Diagnostic::error("E0106", format!("kind `{}` has no {}", k.name.name, missing.join(", ")))
                            .label(k.name.span, "incomplete kind")
                            .help("a kind gives length, width and height priors, e.g. `length 4.2..4.8 m`"),
                    );
                }
                continue;
            }
            let [length, width, height] = size.map(|s| s.expect("checked above"));
            self.kinds.insert(
                k.name.name.clone(),
                (Kind { name: k.name.name.clone(), class, motion, length, width, height, emergency }, k.name.span),
            );
        }
    }

    /// Resolve a kind reference; `one_of` choices must share class and motion.
    fn kind_ref(
        &mut self,
        r: &ast::KindRef,
        used: &mut BTreeMap<String, Kind>,
    ) -> Option<(Vec<String>, Class, Motion)> {
        let idents: Vec<&ast::Ident> = match r {
            ast::KindRef::Named(i) => vec![i],
            ast::KindRef::OneOf { kinds, .. } => kinds.iter().collect(),
        };
        let mut found: Vec<Kind> = vec![];
        for i in &idents {
            match self.kinds.get(&i.name) {
                Some((k, _)) => found.push(k.clone()),
                None => {
                    let names: Vec<&str> = self.kinds.keys().map(String::as_str).collect();
                    let help = did_you_mean(&i.name, &names, "kind");
                    self.err(
                        Diagnostic::error("E0108", format!("unknown kind `{}`", i.name))
                            .label(i.span, "no kind of this name")
                            .help(format!("{help} (kinds come from stdlib/kinds.scn or a `use`d file)")),
                    );
                }
            }
        }
        if found.len() != idents.len() {
            return None;
        }
        let first = &found[0];
        if let Some(other) = found.iter().find(|k| k.class != first.class || k.motion != first.motion) {
            self.err(
                Diagnostic::error("E0119", "the kinds of `one_of` differ in class or motion")
                    .label(
                        r.span(),
                        format!(
                            "`{}` is a {} but `{}` is a {}",
                            first.name,
                            first.class.name(),
                            other.name,
                            other.class.name()
                        ),
                    )
                    .help("list kinds of one class, e.g. `one_of [sedan, suv, pickup_truck]`"),
            );
            return None;
        }
        let (class, motion) = (first.class, first.motion);
        for k in found.iter() {
            used.insert(k.name.clone(), k.clone());
        }
        Some((found.into_iter().map(|k| k.name).collect(), class, motion))
    }

    // ---------------------------------------------------------------- scenario

    fn scenario(&mut self, s: &ast::Scenario) -> Option<Scenario> {
        let mut seed = None;
        let mut duration: Option<(f64, Span)> = None;
        let mut rate: Option<(f64, Span)> = None;
        let mut egos_stmt: Option<(&ast::Egos, Span)> = None;
        let mut road_ast: Option<&ast::Road> = None;
        let mut traffic_ast: Option<&ast::ParamBlock> = None;
        let mut agents_ast = vec![];
        let mut rows_ast = vec![];
        let mut conflicts_ast = vec![];
        let mut first_span: BTreeMap<&str, Span> = BTreeMap::new();
        for st in &s.stmts {
            let key = match st {
                ast::ScenarioStmt::Seed { .. } => Some("seed"),
                ast::ScenarioStmt::Duration { .. } => Some("duration"),
                ast::ScenarioStmt::Rate { .. } => Some("rate"),
                ast::ScenarioStmt::Egos { .. } => Some("egos"),
                ast::ScenarioStmt::Road(_) => Some("road"),
                ast::ScenarioStmt::Traffic(_) => Some("traffic"),
                _ => None,
            };
            if let Some(k) = key {
                if let Some(first) = first_span.get(k) {
                    let first = *first;
                    self.dup(&format!("`{k}`"), first, st.span());
                    continue;
                }
                first_span.insert(k, st.span());
            }
            match st {
                ast::ScenarioStmt::Seed { value, literal, span } => {
                    if *value == u64::MAX && literal != &u64::MAX.to_string() {
                        self.err(
                            Diagnostic::error("E0103", "seed is too large")
                                .label(*span, "does not fit in 64 bits")
                                .help("use a seed below 18446744073709551615"),
                        );
                    }
                    seed = Some(*value);
                }
                ast::ScenarioStmt::Duration { value, span } => {
                    duration =
                        self.fixed(value, Dim::Time, "duration", 0.1, MAX_DURATION_S, "0.1..120 s").map(|d| (d, *span));
                }
                ast::ScenarioStmt::Rate { value, span } => {
                    rate =
                        self.fixed(value, Dim::Frequency, "rate", 0.5, MAX_RATE_HZ, "0.5..100 Hz").map(|r| (r, *span));
                }
                ast::ScenarioStmt::Egos { egos, span } => egos_stmt = Some((egos, *span)),
                ast::ScenarioStmt::Road(r) => road_ast = Some(r),
                ast::ScenarioStmt::Traffic(t) => traffic_ast = Some(t),
                ast::ScenarioStmt::Agent(a) => agents_ast.push(a),
                ast::ScenarioStmt::Row(r) => rows_ast.push(r),
                ast::ScenarioStmt::Conflict(c) => conflicts_ast.push(c),
            }
        }
        let header = s.name.span;
        if !first_span.contains_key("duration") {
            self.err(
                Diagnostic::error("E0106", format!("scenario `{}` has no duration", s.name.name))
                    .label(header, "add `duration 8 s`")
                    .help("every scenario states its clip length, e.g. `duration 8 s`"),
            );
        }
        if road_ast.is_none() {
            self.err(
                Diagnostic::error("E0106", format!("scenario `{}` has no road", s.name.name))
                    .label(header, "add a `road` block")
                    .help("e.g. `road straight { lanes 2; lane_width 3.5 m }`"),
            );
        }
        let road = road_ast.and_then(|r| self.road(r));
        let traffic = traffic_ast.and_then(|t| self.traffic(t));

        // Agent names first, so references can point forward.
        let mut names: BTreeMap<&str, Span> = BTreeMap::new();
        for a in &agents_ast {
            if let Some(first) = names.get(a.name.name.as_str()) {
                let first = *first;
                self.dup(&format!("agent `{}`", a.name.name), first, a.name.span);
            } else {
                names.insert(&a.name.name, a.name.span);
            }
        }
        let order: Vec<&str> = agents_ast.iter().map(|a| a.name.name.as_str()).collect();
        let mut used_kinds = BTreeMap::new();
        let duration_s = duration.map(|d| d.0);
        let agents: Vec<Option<Agent>> =
            agents_ast.iter().map(|a| self.agent(a, road.as_ref(), &order, duration_s, &mut used_kinds)).collect();
        let rows: Vec<Option<Row>> = rows_ast.iter().map(|r| self.row(r, road.as_ref(), &mut used_kinds)).collect();

        // Goals that refer to other agents, now that classes are known.
        for (a, ast_a) in agents.iter().zip(&agents_ast) {
            let Some(a) = a else { continue };
            self.goal_refs(a, ast_a, &agents);
        }

        let conflicts: Vec<Option<Conflict>> =
            conflicts_ast.iter().map(|c| self.conflict(c, &order, &agents, duration_s)).collect();
        self.one_conflict_each(&conflicts, &conflicts_ast, &order);
        let egos = self.egos(egos_stmt, &order, &agents, header);

        if self.diags.iter().any(Diagnostic::is_error) {
            return None;
        }
        Some(Scenario {
            name: s.name.name.clone(),
            seed: seed.unwrap_or(0),
            duration: duration?.0,
            rate: rate.map_or(10.0, |r| r.0),
            egos: egos?,
            road: road?,
            agents: agents.into_iter().collect::<Option<Vec<_>>>()?,
            rows: rows.into_iter().collect::<Option<Vec<_>>>()?,
            conflicts: conflicts.into_iter().collect::<Option<Vec<_>>>()?,
            traffic,
            kinds: used_kinds,
        })
    }

    fn resolve(&mut self, i: &ast::Ident, order: &[&str]) -> Option<usize> {
        if let Some(idx) = order.iter().position(|n| *n == i.name) {
            return Some(idx);
        }
        self.err(
            Diagnostic::error("E0107", format!("`{}` names no agent", i.name))
                .label(i.span, "unknown agent")
                .help(did_you_mean(&i.name, order, "agent")),
        );
        None
    }

    fn egos(
        &mut self,
        stmt: Option<(&ast::Egos, Span)>,
        order: &[&str],
        agents: &[Option<Agent>],
        header: Span,
    ) -> Option<Vec<usize>> {
        let movers = |i: &usize| agents[*i].as_ref().is_some_and(|a| a.motion != Motion::Static && !a.is_object);
        match stmt {
            None => {
                // Default: the agent called `ego`, else the first mover.
                let pick =
                    order.iter().position(|n| *n == "ego").filter(movers).or_else(|| (0..agents.len()).find(movers));
                match pick {
                    Some(i) => Some(vec![i]),
                    None if agents.iter().any(Option::is_none) => None,
                    None => {
                        self.err(
                            Diagnostic::error("E0115", "the scenario has no mover to take a viewpoint from")
                                .label(header, "no agent can be the ego")
                                .help("add a vehicle, bicycle or pedestrian `agent`; clips are rendered from its viewpoint"),
                        );
                        None
                    }
                }
            }
            Some((ast::Egos::Vehicles, span)) => {
                let v: Vec<usize> = (0..agents.len())
                    .filter(|i| agents[*i].as_ref().is_some_and(|a| a.class == Class::Vehicle && !a.is_object))
                    .collect();
                if v.is_empty() && agents.iter().all(Option::is_some) {
                    self.err(
                        Diagnostic::error("E0115", "`egos vehicles` but the scenario has no vehicle agent")
                            .label(span, "selects nothing")
                            .help("list the egos by name: `egos [walker]`"),
                    );
                    return None;
                }
                Some(v)
            }
            Some((ast::Egos::List(list), span)) => {
                if list.is_empty() {
                    self.err(
                        Diagnostic::error("E0115", "`egos []` lists no agent")
                            .label(span, "empty list")
                            .help("name at least one moving agent, e.g. `egos [ego]`"),
                    );
                    return None;
                }
                let mut out = vec![];
                for i in list {
                    let idx = self.resolve(i, order)?;
                    if out.contains(&idx) {
                        self.err(
                            Diagnostic::error("E0105", format!("`{}` is listed twice in egos", i.name))
                                .label(i.span, "second time")
                                .help("each ego yields one clip; list it once"),
                        );
                        continue;
                    }
                    if let Some(a) = &agents[idx]
                        && (a.motion == Motion::Static || a.is_object)
                    {
                        self.err(
                            Diagnostic::error(
                                "E0115",
                                format!("`{}` cannot be an ego: it is a static {}", i.name, a.class.name()),
                            )
                            .label(i.span, "not a mover")
                            .help("egos are vehicles, bicycles, pedestrians or animals declared with `agent`"),
                        );
                    }
                    out.push(idx);
                }
                Some(out)
            }
        }
    }

    // ---------------------------------------------------------------- road

    fn road(&mut self, r: &ast::Road) -> Option<Road> {
        let names: Vec<&str> = Template::ALL.iter().map(|(n, _)| *n).collect();
        let Some(&(_, template)) = Template::ALL.iter().find(|(n, _)| *n == r.template.name) else {
            self.err(
                Diagnostic::error("E0109", format!("unknown road template `{}`", r.template.name))
                    .label(r.template.span, "not a template")
                    .help(did_you_mean(&r.template.name, &names, "road template")),
            );
            return None;
        };
        let junction_arm = 60.0;
        let mut road = Road {
            template,
            lanes: 1,
            lane_width: 3.5,
            speed_limit: 50.0 / 3.6,
            shoulder: 0.0,
            median: 0.0,
            crosswalks: false,
            sidewalks: false,
            length: if template.has_junction() { junction_arm } else { 120.0 },
            radius: match template {
                Template::Roundabout => 15.0,
                _ => 100.0,
            },
            angle: 45f64.to_radians(),
        };
        let mut allowed =
            vec!["lanes", "lane_width", "speed_limit", "shoulder", "median", "crosswalks", "sidewalks", "length"];
        if template == Template::None {
            // A road-less scene has no geometry to parameterise.
            allowed.clear();
        }
        match template {
            Template::Curve => allowed.extend(["radius", "angle"]),
            Template::Roundabout => allowed.push("radius"),
            // The on-ramp has no pedestrian crossing: a switch that builds nothing is refused.
            Template::Merge => allowed.retain(|p| *p != "crosswalks"),
            _ => {}
        }
        let mut seen: BTreeMap<&str, Span> = BTreeMap::new();
        let mut ok = true;
        let mut radius_span = None;
        for p in &r.params {
            let n = p.name.name.as_str();
            if !allowed.contains(&n) {
                let all = ROAD_PARAMS;
                let msg = if all.contains(&n) {
                    format!("`{n}` does not apply to a {} road", template.name())
                } else {
                    format!("unknown road parameter `{n}`")
                };
                let help = if allowed.is_empty() {
                    format!("a {} road takes no parameters: write `road {}`", template.name(), template.name())
                } else if all.contains(&n) {
                    format!("{} roads take: {}", template.name(), allowed.join(", "))
                } else {
                    did_you_mean(n, &allowed, "road parameter")
                };
                self.err(Diagnostic::error("E0110", msg).label(p.name.span, "here").help(help));
                ok = false;
                continue;
            }
            if let Some(first) = seen.get(n) {
                let first = *first;
                self.dup(&format!("road parameter `{n}`"), first, p.span);
                ok = false;
                continue;
            }
            seen.insert(n, p.span);
            if n == "radius" {
                radius_span = Some(match &p.value {
                    ast::ParamValue::Value(v) => v.span,
                    ast::ParamValue::Switch { span, .. } => *span,
                });
            }
            let v = match (&p.value, n) {
                (ast::ParamValue::Switch { on, .. }, "crosswalks") => {
                    road.crosswalks = *on;
                    continue;
                }
                (ast::ParamValue::Switch { on, .. }, "sidewalks") => {
                    road.sidewalks = *on;
                    continue;
                }
                (ast::ParamValue::Value(v), "crosswalks" | "sidewalks") => {
                    self.err(
                        Diagnostic::error("E0101", format!("`{n}` is `on` or `off`"))
                            .label(v.span, "expected `on` or `off`")
                            .help(format!("write `{n} on`")),
                    );
                    ok = false;
                    continue;
                }
                (ast::ParamValue::Switch { span, .. }, _) => {
                    self.err(
                        Diagnostic::error("E0101", format!("`{n}` takes a value, not on/off"))
                            .label(*span, "expected a number with a unit")
                            .help("e.g. `lane_width 3.5 m`"),
                    );
                    ok = false;
                    continue;
                }
                (ast::ParamValue::Value(v), _) => v,
            };
            let got = match n {
                "lanes" => self
                    .fixed(v, Dim::Count, "lanes", 1.0, MAX_LANES as f64, "1..6 lanes per direction")
                    .and_then(|x| {
                        if x.fract() != 0.0 {
                            self.err(
                                Diagnostic::error("E0103", "lanes must be a whole number")
                                    .label(v.span, "not whole")
                                    .help("e.g. `lanes 2`"),
                            );
                            None
                        } else {
                            road.lanes = x as u32;
                            Some(())
                        }
                    }),
                "lane_width" => {
                    self.fixed(v, Dim::Length, "lane_width", 2.5, 6.0, "2.5..6 m").map(|x| road.lane_width = x)
                }
                "speed_limit" => self
                    .fixed(v, Dim::Speed, "speed_limit", 1.0, MAX_SPEED_MS, "1..324 km/h")
                    .map(|x| road.speed_limit = x),
                "shoulder" => self.fixed(v, Dim::Length, "shoulder", 0.0, 6.0, "0..6 m").map(|x| road.shoulder = x),
                "median" => self.fixed(v, Dim::Length, "median", 0.0, 20.0, "0..20 m").map(|x| road.median = x),
                "length" => self.fixed(v, Dim::Length, "length", 20.0, 1000.0, "20..1000 m").map(|x| road.length = x),
                "radius" => {
                    let (min, shown) =
                        if template == Template::Roundabout { (8.0, "8..60 m") } else { (20.0, "20..2000 m") };
                    let max = if template == Template::Roundabout { 60.0 } else { 2000.0 };
                    self.fixed(v, Dim::Length, "radius", min, max, shown).map(|x| road.radius = x)
                }
                "angle" => self
                    .fixed(v, Dim::Angle, "angle", 1f64.to_radians(), 180f64.to_radians(), "1..180 deg")
                    .map(|x| road.angle = x),
                _ => unreachable!("parameter names are filtered above"),
            };
            ok &= got.is_some();
        }
        if ok {
            ok = self.radius_fits(&road, r, radius_span);
        }
        ok.then_some(road)
    }

    /// The cross-parameter rule the per-parameter ranges cannot express: the bend or ring must
    /// be wider than the carriageway it carries.
    fn radius_fits(&mut self, road: &Road, r: &ast::Road, radius_span: Option<Span>) -> bool {
        let Some(min) = min_radius(road) else { return true };
        if road.radius >= min - 1e-9 {
            return true;
        }
        let min_shown = (min * 10.0).ceil() / 10.0;
        let m = |x: f64| (x * 100.0).round() / 100.0;
        let (msg, why) = if road.template == Template::Roundabout {
            (
                format!(
                    "a roundabout of radius {} m with {} lane(s) of {} m leaves no central island",
                    m(road.radius),
                    road.lanes,
                    m(road.lane_width)
                ),
                format!("the ring is {} m wide around its middle line", m(f64::from(road.lanes) * road.lane_width)),
            )
        } else {
            (
                format!("a curve of radius {} m is tighter than its own carriageway", m(road.radius)),
                format!("the road reaches {} m either side of its centre line", m(min - CURVE_MARGIN_M)),
            )
        };
        let label = match radius_span {
            Some(s) => (s, "radius too small for this cross-section"),
            None => (r.template.span, "the default radius is too small for this cross-section"),
        };
        self.err(
            Diagnostic::error("E0103", msg)
                .label(label.0, label.1)
                .help(format!("{why}; use `radius {min_shown} m` or more, or fewer or narrower lanes")),
        );
        false
    }

    fn traffic(&mut self, t: &ast::ParamBlock) -> Option<Traffic> {
        let mut out = Traffic { density: 0.0, randomness: 0.0 };
        let mut ok = true;
        let mut seen: BTreeMap<&str, Span> = BTreeMap::new();
        for p in &t.params {
            let n = p.name.name.as_str();
            if !["density", "randomness"].contains(&n) {
                self.err(
                    Diagnostic::error("E0110", format!("unknown traffic parameter `{n}`"))
                        .label(p.name.span, "here")
                        .help(did_you_mean(n, &["density", "randomness"], "traffic parameter")),
                );
                ok = false;
                continue;
            }
            if let Some(first) = seen.get(n) {
                let first = *first;
                self.dup(&format!("traffic parameter `{n}`"), first, p.span);
                ok = false;
                continue;
            }
            seen.insert(n, p.span);
            let ast::ParamValue::Value(v) = &p.value else {
                self.err(
                    Diagnostic::error("E0101", format!("`{n}` takes a number 0..1"))
                        .label(p.span, "not on/off")
                        .help(format!("e.g. `{n} 0.5`")),
                );
                ok = false;
                continue;
            };
            match self.fixed(v, Dim::Ratio, n, 0.0, 1.0, "0..1 (or 0..100 %)") {
                Some(x) if n == "density" => out.density = x,
                Some(x) => out.randomness = x,
                None => ok = false,
            }
        }
        ok.then_some(out)
    }

    // ---------------------------------------------------------------- placement

    fn arm(&mut self, i: &ast::Ident, road: &Road) -> Option<Arm> {
        let arms = road.template.arms();
        if let Some(a) = arms.iter().find(|a| a.name() == i.name) {
            return Some(*a);
        }
        let names: Vec<&str> = arms.iter().map(|a| a.name()).collect();
        self.err(
            Diagnostic::error("E0111", format!("a {} road has no arm `{}`", road.template.name(), i.name))
                .label(i.span, "unknown arm")
                .help(did_you_mean(&i.name, &names, "arm")),
        );
        None
    }

    fn along(&mut self, a: &ast::Along, road: &Road, dir: Dir, sidewalk: bool) -> Option<Along> {
        let landmark = word(self, &a.landmark, &LANDMARKS, "landmark");
        let dist = self.bounded(&a.dist, Dim::Length, "distance", 0.0, 2000.0, "0..2000 m");
        let landmark = landmark?;
        let bad = match landmark {
            Landmark::Center => None,
            Landmark::Junction if !road.template.has_junction() => {
                Some(format!("a {} road has no junction", road.template.name()))
            }
            Landmark::StopLine if !road.template.has_stop_lines() => {
                Some(format!("a {} road has no stop lines", road.template.name()))
            }
            Landmark::StopLine if dir == Dir::Out || sidewalk => Some("stop lines are on in-lanes only".to_string()),
            _ => None,
        };
        if let Some(msg) = bad {
            self.err(
                Diagnostic::error("E0111", msg)
                    .label(a.landmark.span, "landmark not on this road")
                    .help(if road.template.has_junction() { "use `junction` or `center`" } else { "use `center`" }),
            );
            return None;
        }
        let dist = dist?;
        Some(Along { landmark, dist: if a.rel == ast::Rel::Before { dist.map(|d| -d) } else { dist } })
    }

    fn offset(&mut self, o: &Option<ast::Offset>) -> Option<f64> {
        let Some(o) = o else { return Some(0.0) };
        let side = word(self, &o.side, &SIDES, "side");
        let d = self.fixed(&o.dist, Dim::Length, "offset", 0.0, 50.0, "0..50 m")?;
        Some(if side? == Side::Left { d } else { -d })
    }

    fn heading(&mut self, h: &Option<ast::Value>) -> Option<Option<Dist>> {
        match h {
            None => Some(None),
            Some(v) => self
                .bounded(
                    v,
                    Dim::Angle,
                    "heading",
                    -4.0 * std::f64::consts::PI,
                    4.0 * std::f64::consts::PI,
                    "-720..720 deg",
                )
                .map(Some),
        }
    }

    fn dir(d: ast::Dir) -> Dir {
        if d == ast::Dir::In { Dir::In } else { Dir::Out }
    }

    fn placement(&mut self, p: &ast::Placement, road: Option<&Road>, class: Option<Class>) -> Option<Place> {
        match p {
            ast::Placement::World { x, y, heading, .. } => {
                let x = self.bounded(x, Dim::Length, "x", -1000.0, 1000.0, "-1000..1000 m");
                let y = self.bounded(y, Dim::Length, "y", -1000.0, 1000.0, "-1000..1000 m");
                let heading = self.heading(heading);
                Some(Place::World { x: x?, y: y?, heading: heading? })
            }
            ast::Placement::Lane { lane, along, offset, heading, .. } => {
                let road = road?;
                let arm = self.arm(&lane.arm, road);
                let dir = Self::dir(lane.dir);
                let along = self.along(along, road, dir, false);
                let offset = self.offset(offset);
                let heading = self.heading(heading);
                let arm = arm?;
                let lanes = lane_count(road, arm, dir);
                if lanes == 0 {
                    self.err(
                        Diagnostic::error(
                            "E0112",
                            format!(
                                "the {} arm has no {} lanes",
                                arm.name(),
                                if dir == Dir::In { "in" } else { "out" }
                            ),
                        )
                        .label(lane.span, "no such lanes")
                        .help("the ramp of a merge has one in-lane: `ramp.in[1]`"),
                    );
                    return None;
                }
                if lane.index == 0 || lane.index > lanes {
                    self.err(
                        Diagnostic::error(
                            "E0112",
                            format!(
                                "lane {} does not exist on a road with {} lane{} per direction",
                                lane.index,
                                lanes,
                                if lanes == 1 { "" } else { "s" }
                            ),
                        )
                        .label(lane.index_span, format!("lanes are numbered 1..={lanes}"))
                        .help(format!(
                            "use {}.{}[1] (nearest the centre line) .. [{lanes}], or raise `lanes`",
                            arm.name(),
                            if dir == Dir::In { "in" } else { "out" }
                        )),
                    );
                    return None;
                }
                Some(Place::Lane {
                    lane: LaneId { arm, dir, index: lane.index },
                    along: along?,
                    offset: offset?,
                    heading: heading?,
                })
            }
            ast::Placement::Crosswalk { arm, fraction, span } => {
                let road = road?;
                let a = self.arm(arm, road);
                let f = self.bounded(fraction, Dim::Ratio, "crosswalk position", 0.0, 1.0, "0..100 %");
                if !road.crosswalks {
                    self.err(
                        Diagnostic::error("E0203", "this road has no crosswalks")
                            .label(*span, "crosswalk placement")
                            .help("add `crosswalks on` to the road block"),
                    );
                    return None;
                }
                Some(Place::Crosswalk { arm: a?, fraction: f? })
            }
            ast::Placement::Sidewalk { side, along, offset, heading, span } => {
                let road = road?;
                let arm = self.arm(&side.arm, road);
                let dir = Self::dir(side.dir);
                let along = self.along(along, road, dir, true);
                let offset = self.offset(offset);
                let heading = self.heading(heading);
                if !road.sidewalks {
                    self.err(
                        Diagnostic::error("E0203", "this road has no sidewalks")
                            .label(*span, "sidewalk placement")
                            .help("add `sidewalks on` to the road block"),
                    );
                    return None;
                }
                if let Some(c @ Class::Vehicle) = class {
                    self.err(
                        Diagnostic::error("E0201", format!("a {} cannot be placed on a sidewalk", c.name()))
                            .label(*span, "sidewalk")
                            .help("place vehicles on a lane, e.g. `at east.out[1], 10 m after center`, or on the shoulder with `offset`"),
                    );
                    return None;
                }
                Some(Place::Sidewalk { arm: arm?, dir, along: along?, offset: offset?, heading: heading? })
            }
        }
    }

    // ---------------------------------------------------------------- agents

    fn agent(
        &mut self,
        a: &ast::Agent,
        road: Option<&Road>,
        order: &[&str],
        duration: Option<f64>,
        used: &mut BTreeMap<String, Kind>,
    ) -> Option<Agent> {
        let kind = self.kind_ref(&a.kind, used);
        let class = kind.as_ref().map(|k| k.1);
        let motion = kind.as_ref().map(|k| k.2);
        let is_static = a.is_object || motion == Some(Motion::Static);
        let mut place: Option<(&ast::Placement, Span)> = None;
        let mut speed: Option<(&ast::Value, Span)> = None;
        let mut sizes: [Option<(&ast::Value, Span)>; 3] = [None; 3];
        let mut goal: Option<&ast::Goal> = None;
        let mut track: Option<&ast::Track> = None;
        for st in &a.stmts {
            let (slot_first, what): (Option<Span>, &str) = match st {
                ast::AgentStmt::At { place: p, span } => (place.replace((p, *span)).map(|x| x.1), "placement `at`"),
                ast::AgentStmt::Speed { value, span } => (speed.replace((value, *span)).map(|x| x.1), "`speed`"),
                ast::AgentStmt::Size(s) => {
                    (sizes[s.key as usize].replace((&s.value, s.span)).map(|x| x.1), s.key.as_str())
                }
                ast::AgentStmt::Goal(g) => (goal.replace(g).map(|x| x.span), "`goal`"),
                ast::AgentStmt::Track(t) => (track.replace(t).map(|x| x.span), "`track`"),
            };
            if let Some(first) = slot_first {
                self.dup(what, first, st.span());
            }
        }
        let what = if a.is_object { "object" } else { "agent" };
        if is_static {
            let label = if a.is_object {
                "an object never moves".to_string()
            } else {
                format!("a {} never moves", class.map_or("static kind", |c| c.name()))
            };
            if let Some(g) = goal {
                self.err(
                    Diagnostic::error("E0113", format!("`{}` cannot have a goal: {label}", a.name.name))
                        .label(g.span, "goal on a static thing")
                        .help("remove the goal, or declare a moving kind with `agent`"),
                );
            }
            if let Some((v, span)) = speed
                && (v.lo.value != 0.0 || v.hi.is_some())
            {
                self.err(
                    Diagnostic::error("E0113", format!("`{}` cannot have a speed: {label}", a.name.name))
                        .label(span, "speed on a static thing")
                        .help("remove the speed"),
                );
            }
        }
        let track_keys = track.and_then(|t| self.track(t, duration));
        let place = match (place, track) {
            (Some((p, _)), Some(t)) => {
                self.err(
                    Diagnostic::error("E0117", format!("`{}` has both a placement and a track", a.name.name))
                        .label(t.span, "the track gives the pose")
                        .label(p.span(), "placement")
                        .help("remove `at ...`: the first keyframe places the agent"),
                );
                None
            }
            (None, Some(_)) => Some(Place::Track),
            (Some((p, _)), None) => self.placement(p, road, class),
            (None, None) => {
                self.err(
                    Diagnostic::error("E0106", format!("{what} `{}` has no placement", a.name.name))
                        .label(a.name.span, "where does it start?")
                        .help("add `at LANE, DIST before|after LANDMARK`, e.g. `at west.in[1], 20 m before center`"),
                );
                None
            }
        };
        if let (Some(_), Some(g)) = (track, goal) {
            self.err(
                Diagnostic::error("E0117", format!("`{}` replays a track and cannot also have a goal", a.name.name))
                    .label(g.span, "goal")
                    .help("a replayed agent follows its keyframes; remove the goal"),
            );
        }
        let speed_d = match speed {
            None => Some(Dist::Fixed(0.0)),
            Some((v, _)) => self.bounded(v, Dim::Speed, "speed", 0.0, MAX_SPEED_MS, "0..324 km/h"),
        };
        let mut size = [None; 3];
        for (i, s) in sizes.iter().enumerate() {
            if let Some((v, _)) = s {
                let what = ["length", "width", "height"][i];
                size[i] = Some(self.bounded(v, Dim::Length, what, 0.05, 40.0, "0.05..40 m"));
            }
        }
        let goal_c = match (goal, motion) {
            (Some(g), Some(m)) if !is_static => self.goal(g, m, class?, place.as_ref(), road, order, &a.name),
            _ => Some(None),
        };
        let span = a.span;
        let place_span = place.as_ref().and(a.stmts.iter().find_map(|s| match s {
            ast::AgentStmt::At { place, .. } => Some(place.span()),
            ast::AgentStmt::Track(t) => Some(t.span),
            _ => None,
        }));
        let (kinds, class, motion) = kind?;
        Some(Agent {
            name: a.name.name.clone(),
            kinds,
            class,
            motion: if a.is_object { Motion::Static } else { motion },
            is_object: a.is_object,
            length: size[0].flatten(),
            width: size[1].flatten(),
            height: size[2].flatten(),
            place: place?,
            speed: speed_d?,
            goal: goal_c?,
            track: track_keys.clone(),
            span,
            place_span: place_span.unwrap_or(span),
        })
        // A size or track that was given but invalid has been reported: no agent then.
        .filter(|_| size.iter().all(|s| s.is_none_or(|x| x.is_some())))
        .filter(|_| track.is_none() || track_keys.is_some())
    }

    fn track(&mut self, t: &ast::Track, duration: Option<f64>) -> Option<Vec<Keyframe>> {
        let _ = duration;
        if t.keys.is_empty() {
            self.err(
                Diagnostic::error("E0117", "a track needs at least one keyframe")
                    .label(t.span, "empty track")
                    .help("write keyframes as `0 s: (12.0 m, -3.5 m) yaw 90 deg`"),
            );
            return None;
        }
        let mut out = vec![];
        let mut prev: Option<(f64, Span)> = None;
        for k in &t.keys {
            let tt = self.fixed(&k.t, Dim::Time, "keyframe time", 0.0, MAX_DURATION_S, "0..120 s");
            let x = self.fixed(&k.x, Dim::Length, "x", -1000.0, 1000.0, "-1000..1000 m");
            let y = self.fixed(&k.y, Dim::Length, "y", -1000.0, 1000.0, "-1000..1000 m");
            let yaw = self.fixed(
                &k.yaw,
                Dim::Angle,
                "yaw",
                -4.0 * std::f64::consts::PI,
                4.0 * std::f64::consts::PI,
                "-720..720 deg",
            );
            let (Some(tt), Some(x), Some(y), Some(yaw)) = (tt, x, y, yaw) else { return None };
            if let Some((pt, pspan)) = prev
                && tt <= pt
            {
                self.err(
                    Diagnostic::error("E0117", "keyframe times must strictly increase")
                        .label(k.t.span, format!("{tt} s is not after {pt} s"))
                        .label(pspan, "previous keyframe")
                        .help("sort the keyframes by time and drop duplicates"),
                );
                return None;
            }
            prev = Some((tt, k.t.span));
            out.push(Keyframe { t: tt, x, y, yaw });
        }
        Some(out)
    }

    #[allow(clippy::too_many_arguments)]
    fn goal(
        &mut self,
        g: &ast::Goal,
        motion: Motion,
        class: Class,
        place: Option<&Place>,
        road: Option<&Road>,
        order: &[&str],
        me: &ast::Ident,
    ) -> Option<Option<Goal>> {
        let mut out = Goal {
            speed: None,
            lateral: Lateral::HoldLane,
            stop: None,
            turn: None,
            start_after: 0.0,
            stop_span: Span::default(),
        };
        let mut ok = true;
        let mut seen: BTreeMap<&str, Span> = BTreeMap::new();
        let walker = motion == Motion::Holonomic;
        let who = if walker { format!("a {} walks", class.name()) } else { format!("a {} drives", class.name()) };
        let lane_in = match place {
            Some(Place::Lane { lane, .. }) => Some(lane.dir == Dir::In),
            _ => None,
        };
        for st in &g.stmts {
            let k = st.keyword();
            if let Some(first) = seen.get(k) {
                let first = *first;
                self.dup(&format!("goal `{k}`"), first, st.span());
                ok = false;
                continue;
            }
            seen.insert(k, st.span());
            match st {
                ast::GoalStmt::Speed { value, .. } => {
                    out.speed = self.bounded(value, Dim::Speed, "goal speed", 0.0, MAX_SPEED_MS, "0..324 km/h");
                    ok &= out.speed.is_some();
                }
                ast::GoalStmt::Start { after, .. } => {
                    match self.fixed(after, Dim::Time, "start delay", 0.0, MAX_DURATION_S, "0..120 s") {
                        Some(t) => out.start_after = t,
                        None => ok = false,
                    }
                }
                ast::GoalStmt::Lateral { lateral, span } => {
                    let l = match lateral {
                        ast::Lateral::Word(w) => word(
                            self,
                            w,
                            &[
                                ("hold_lane", Lateral::HoldLane),
                                ("pull_to_shoulder", Lateral::PullToShoulder),
                                ("cross", Lateral::Cross),
                            ],
                            "lateral goal",
                        ),
                        ast::Lateral::ChangeLane(side) => word(self, side, &SIDES, "side").map(Lateral::ChangeLane),
                        ast::Lateral::AwayFrom(n) => {
                            let idx = self.resolve(n, order);
                            if n.name == me.name {
                                self.err(
                                    Diagnostic::error("E0113", format!("`{}` cannot ease away from itself", me.name))
                                        .label(n.span, "names the agent itself")
                                        .help("name the approaching agent, e.g. `lateral away_from amb`"),
                                );
                                None
                            } else {
                                idx.map(Lateral::AwayFrom)
                            }
                        }
                    };
                    let Some(l) = l else {
                        ok = false;
                        continue;
                    };
                    let bad = match l {
                        Lateral::ChangeLane(_) | Lateral::PullToShoulder | Lateral::AwayFrom(_) if walker => {
                            Some(format!("{who}; it cannot {}", lateral_name(l)))
                        }
                        Lateral::Cross if !walker => Some(format!("{who}; only pedestrians and animals `cross`")),
                        Lateral::ChangeLane(_) | Lateral::PullToShoulder | Lateral::AwayFrom(_)
                            if lane_in.is_none() =>
                        {
                            Some(format!("{} needs a lane placement", lateral_name(l)))
                        }
                        Lateral::ChangeLane(side) => match (place, road) {
                            (Some(Place::Lane { lane, .. }), Some(r)) => {
                                let lanes = lane_count(r, lane.arm, lane.dir);
                                // Lane 1 is nearest the centre line: moving left lowers the index.
                                let target =
                                    if side == Side::Left { lane.index as i64 - 1 } else { lane.index as i64 + 1 };
                                (target < 1 || target > lanes as i64).then(|| {
                                    format!(
                                        "there is no lane to the {} of lane {} ({} lanes per direction)",
                                        side_name(side),
                                        lane.index,
                                        lanes
                                    )
                                })
                            }
                            _ => None,
                        },
                        _ => None,
                    };
                    if let Some(msg) = bad {
                        self.err(Diagnostic::error("E0113", msg).label(*span, "not possible here").help(match l {
                            Lateral::Cross => {
                                "vehicles keep to lanes: use `lateral hold_lane` or `change_lane`".to_string()
                            }
                            _ if walker => "walkers use `lateral cross` or keep their course".to_string(),
                            _ => "change the placement or the goal".to_string(),
                        }));
                        ok = false;
                        continue;
                    }
                    out.lateral = l;
                }
                ast::GoalStmt::Stop { stop, span } => {
                    let s = match stop {
                        ast::Stop::At(w) => {
                            if w.name != "stop_line" {
                                let help = did_you_mean(&w.name, &["stop_line"], "landmark");
                                self.err(
                                    Diagnostic::error(
                                        "E0116",
                                        format!("`stop at` takes `stop_line`, not `{}`", w.name),
                                    )
                                    .label(w.span, "unknown stop target")
                                    .help(format!("{help} (to stop after a distance write `stop after 20 m`)")),
                                );
                                None
                            } else if walker {
                                self.err(
                                    Diagnostic::error("E0113", format!("{who}; stop lines are for vehicles"))
                                        .label(*span, "not possible here")
                                        .help("use `stop after DIST` or `stop behind NAME`"),
                                );
                                None
                            } else if !road.is_some_and(|r| r.template.has_stop_lines()) {
                                self.err(
                                    Diagnostic::error("E0113", format!("a {} road has no stop lines", road.map_or("", |r| r.template.name())))
                                        .label(*span, "no stop line to stop at")
                                        .help("stop lines exist on four_way, t_junction and roundabout roads; use `stop after DIST`"),
                                );
                                None
                            } else if lane_in != Some(true) {
                                self.err(
                                    Diagnostic::error("E0113", "the stop line is not ahead of this agent")
                                        .label(*span, "stop lines are on in-lanes")
                                        .help("place the agent on an in-lane before the stop line, e.g. `at south.in[1], 20 m before stop_line`"),
                                );
                                None
                            } else {
                                if let Some(Place::Lane { along, .. }) = place
                                    && along.landmark == Landmark::StopLine
                                    && along.dist.lo() > 0.0
                                {
                                    self.err(
                                        Diagnostic::error("E0113", "the agent starts past the stop line")
                                            .label(*span, "the stop line is behind it")
                                            .help("place it `before stop_line`, or use `stop after DIST`"),
                                    );
                                    ok = false;
                                    continue;
                                }
                                Some(Stop::AtStopLine)
                            }
                        }
                        ast::Stop::Behind(n) => {
                            let idx = self.resolve(n, order);
                            if n.name == me.name {
                                self.err(
                                    Diagnostic::error("E0113", format!("`{}` cannot stop behind itself", me.name))
                                        .label(n.span, "names the agent itself")
                                        .help("name the agent ahead"),
                                );
                                None
                            } else {
                                idx.map(Stop::Behind)
                            }
                        }
                        ast::Stop::After(v) => {
                            self.fixed(v, Dim::Length, "stop distance", 0.0, 2000.0, "0..2000 m").map(Stop::After)
                        }
                    };
                    match s {
                        Some(s) => {
                            out.stop = Some(s);
                            out.stop_span = *span;
                        }
                        None => ok = false,
                    }
                }
                ast::GoalStmt::Turn { turn, span } => {
                    let Some(t) = word(self, turn, &TURNS, "turn") else {
                        ok = false;
                        continue;
                    };
                    let bad = if walker {
                        Some(format!("{who}; turns are for vehicles"))
                    } else if let Some(r) = road.filter(|r| !r.template.has_stop_lines()) {
                        Some(format!("a {} road has no junction to turn at", r.template.name()))
                    } else if lane_in != Some(true) {
                        Some("turns are chosen on an in-lane approaching the junction".to_string())
                    } else if let (Some(Place::Lane { lane, .. }), Some(r)) = (place, road) {
                        turn_exists(r.template, lane.arm, t)
                    } else {
                        None
                    };
                    if let Some(msg) = bad {
                        self.err(
                            Diagnostic::error("E0113", msg)
                                .label(*span, "not possible here")
                                .help("turns need an in-lane of a four_way, t_junction or roundabout"),
                        );
                        ok = false;
                        continue;
                    }
                    out.turn = Some(t);
                }
            }
        }
        ok.then_some(Some(out))
    }

    /// Checks on goals that name other agents, once every agent's class is known.
    fn goal_refs(&mut self, a: &Agent, ast_a: &ast::Agent, agents: &[Option<Agent>]) {
        let Some(g) = &a.goal else { return };
        if let Lateral::AwayFrom(i) = g.lateral
            && let Some(other) = &agents[i]
            && other.motion == Motion::Static
        {
            let span = find_goal_span(ast_a, "lateral");
            self.err(
                Diagnostic::error("E0113", format!("`{}` never moves, so nothing approaches", other.name))
                    .label(span, "away_from a static thing")
                    .help("`away_from` names an approaching mover; to pass an object use `change_lane`"),
            );
        }
    }

    fn row(&mut self, r: &ast::Row, road: Option<&Road>, used: &mut BTreeMap<String, Kind>) -> Option<Row> {
        let kind = self.kind_ref(&r.kind, used);
        let class = kind.as_ref().map(|k| k.1);
        let from = self.placement(&r.from, road, class);
        let to = self.placement(&r.to, road, class);
        let every = self.fixed(&r.every, Dim::Length, "row spacing", 0.1, 1000.0, "0.1..1000 m");
        let (kind, from, to, every) = (kind?, from?, to?, every?);
        let same = match (&from, &to) {
            // Lanes of one arm and direction run side by side: a row across them is a taper.
            (Place::Lane { lane: a, .. }, Place::Lane { lane: b, .. }) => a.arm == b.arm && a.dir == b.dir,
            (Place::Sidewalk { arm: a, dir: d, .. }, Place::Sidewalk { arm: b, dir: e, .. }) => a == b && d == e,
            (Place::World { .. }, Place::World { .. }) => true,
            _ => false,
        };
        if !same {
            self.err(
                Diagnostic::error(
                    "E0118",
                    "a row runs along the lanes of one arm and direction, one sidewalk, or between two world points",
                )
                .label(r.to.span(), "different arm, direction or placement form than `from`")
                .label(r.from.span(), "row starts here")
                .help("put both ends on lanes of one arm and direction (a taper may change lane), e.g. `from west.in[2], 20 m before center to west.in[1], 30 m after center`"),
            );
            return None;
        }
        let extent = match (&from, &to) {
            (Place::Lane { along: a, .. }, Place::Lane { along: b, .. })
            | (Place::Sidewalk { along: a, .. }, Place::Sidewalk { along: b, .. }) => {
                // Different landmarks are a few metres apart at most; the road pass measures exactly.
                (b.dist.hi() - a.dist.lo()).abs() + 100.0 * f64::from(u8::from(a.landmark != b.landmark))
            }
            (Place::World { x: x0, y: y0, .. }, Place::World { x: x1, y: y1, .. }) => {
                (x1.hi() - x0.lo()).hypot(y1.hi() - y0.lo())
            }
            _ => 0.0,
        };
        if extent / every > MAX_ROW_OBJECTS as f64 {
            self.err(
                Diagnostic::error("E0118", format!("this row would place about {} objects", (extent / every) as u64))
                    .label(r.every.span, "spacing too small for the length")
                    .help(format!("a row holds at most {MAX_ROW_OBJECTS} objects; increase `every`")),
            );
            return None;
        }
        Some(Row { kinds: kind.0, class: kind.1, from, to, every, span: r.span })
    }

    /// A crash latches its pair from the impact on, so an agent takes part in one conflict only:
    /// a second block naming it (as at_fault or struck) is rejected, pointing at both.
    fn one_conflict_each(&mut self, conflicts: &[Option<Conflict>], asts: &[&ast::Conflict], order: &[&str]) {
        // Agent index -> the block of its first conflict.
        let mut first: BTreeMap<usize, Span> = BTreeMap::new();
        for (c, ca) in conflicts.iter().zip(asts) {
            let Some(c) = c else { continue };
            for (who, key) in [(c.at_fault, "at_fault"), (c.struck, "struck")] {
                let field = ca.fields.iter().find(|f| f.key == key).map_or(ca.span, |f| f.span);
                match first.get(&who) {
                    None => {
                        first.insert(who, ca.span);
                    }
                    Some(&block) => {
                        let name = order[who];
                        self.err(
                            Diagnostic::error("E0121", format!("`{name}` is in two conflicts"))
                                .label(field, format!("`{name}` named again here, as {key}"))
                                .label(block, format!("first conflict of `{name}`"))
                                .help(format!(
                                    "a crash holds its pair from the impact on; keep one conflict for `{name}`, or stage the second crash with another agent"
                                )),
                        );
                    }
                }
            }
        }
    }

    fn conflict(
        &mut self,
        c: &ast::Conflict,
        order: &[&str],
        agents: &[Option<Agent>],
        duration: Option<f64>,
    ) -> Option<Conflict> {
        let mut fields: BTreeMap<&str, &ast::ConflictField> = BTreeMap::new();
        let mut ok = true;
        for f in &c.fields {
            if let Some(first) = fields.get(f.key.as_str()) {
                let first = first.span;
                self.dup(&format!("conflict field `{}`", f.key), first, f.span);
                ok = false;
                continue;
            }
            fields.insert(&f.key, f);
        }
        let ident = |c: &mut Checker, key: &str| -> Option<&ast::Ident> {
            let f = fields.get(key)?;
            match &f.value {
                ast::FieldValue::Ident(i) => Some(i),
                ast::FieldValue::Value(v) => {
                    c.err(
                        Diagnostic::error("E0114", format!("`{key}` takes a name, not a number"))
                            .label(v.span, "expected a name")
                            .help(format!(
                                "e.g. `{key} {}`",
                                match key {
                                    "impact" => "rear_end",
                                    "point" => "rear",
                                    _ => "ego",
                                }
                            )),
                    );
                    None
                }
            }
        };
        let missing: Vec<&str> =
            ["at_fault", "struck", "impact", "point"].into_iter().filter(|k| !fields.contains_key(k)).collect();
        if !missing.is_empty() {
            self.err(
                Diagnostic::error("E0106", format!("conflict has no {}", missing.join(", ")))
                    .label(c.span, "incomplete conflict")
                    .help(
                        "a conflict needs `at_fault A; struck B; impact TYPE; point SIDE` (and optionally `at TIME`)",
                    ),
            );
            return None;
        }
        let at_fault = ident(self, "at_fault").and_then(|i| self.resolve(i, order).map(|x| (x, i.span)));
        let struck = ident(self, "struck").and_then(|i| self.resolve(i, order).map(|x| (x, i.span)));
        let impact_i = ident(self, "impact");
        let point_i = ident(self, "point");
        let impact = impact_i.and_then(|i| word(self, i, &IMPACTS, "impact type"));
        let point = point_i.and_then(|i| word(self, i, &POINTS, "impact point"));
        if let (Some(imp), Some(pt), Some(ii), Some(pi)) = (impact, point, impact_i, point_i) {
            let fits = points_for(imp);
            if !fits.contains(&pt) {
                let names: Vec<&str> = POINTS.iter().filter(|(_, p)| fits.contains(p)).map(|(n, _)| *n).collect();
                let why = match imp {
                    Impact::RearEnd => "a rear-end strikes the struck agent's rear",
                    Impact::HeadOn => "a head-on meets the struck agent's front",
                    _ => "an angle or sideswipe strikes the struck agent's side or a corner",
                };
                self.err(
                    Diagnostic::error("E0120", format!("`impact {}` cannot have `point {}`: {why}", ii.name, pi.name))
                        .label(pi.span, format!("not a side a {} strikes", ii.name.replace('_', "-")))
                        .label(ii.span, "impact type")
                        .help(format!(
                            "with `impact {}` use `point {}`; `point {}` fits `impact {}`",
                            ii.name,
                            names.join("`, `"),
                            pi.name,
                            IMPACTS
                                .iter()
                                .filter(|(_, i)| !matches!(i, Impact::Pedestrian | Impact::Object))
                                .filter(|(_, i)| points_for(*i).contains(&pt))
                                .map(|(n, _)| *n)
                                .collect::<Vec<_>>()
                                .join("` or `impact ")
                        )),
                );
                ok = false;
            }
        }
        let at = match fields.get("at").map(|f| &f.value) {
            None => Some(None),
            Some(ast::FieldValue::Value(v)) => {
                let max = duration.unwrap_or(MAX_DURATION_S);
                self.fixed(v, Dim::Time, "impact time", 0.0, max, &format!("0..{max} s (the clip)")).map(Some)
            }
            Some(ast::FieldValue::Ident(i)) => {
                self.err(
                    Diagnostic::error("E0101", "`at` takes a time")
                        .label(i.span, "expected a time")
                        .help("e.g. `at 4 s`"),
                );
                None
            }
        };
        let (at_fault, struck, impact, point, at) = (at_fault?, struck?, impact?, point?, at?);
        if at_fault.0 == struck.0 {
            self.err(
                Diagnostic::error("E0114", "a conflict needs two different agents")
                    .label(struck.1, format!("`{}` is also the at-fault agent", order[struck.0]))
                    .label(at_fault.1, "at-fault agent")
                    .help("name the agent that is struck, e.g. `struck v2`"),
            );
            return None;
        }
        if let (Some(f), Some(s)) = (&agents[at_fault.0], &agents[struck.0]) {
            let bad = if f.motion == Motion::Static {
                Some((at_fault.1, format!("`{}` is static and cannot be at fault", f.name)))
            } else if impact == Impact::Pedestrian && s.class != Class::Pedestrian {
                Some((struck.1, format!("`impact pedestrian` but `{}` is a {}", s.name, s.class.name())))
            } else if impact == Impact::Object && s.motion != Motion::Static {
                Some((struck.1, format!("`impact object` but `{}` moves", s.name)))
            } else if impact != Impact::Object && impact != Impact::Pedestrian && s.motion == Motion::Static {
                Some((struck.1, format!("`{}` is a static {}: use `impact object`", s.name, s.class.name())))
            } else {
                None
            };
            if let Some((span, msg)) = bad {
                self.err(
                    Diagnostic::error("E0114", msg)
                        .label(span, "here")
                        .help("see `rocc explain E0114` for the impact types"),
                );
                ok = false;
            }
        }
        ok.then_some(Conflict { at_fault: at_fault.0, struck: struck.0, impact, point, at, span: c.span })
    }
}

/// The points (sides of the struck agent) an impact type can hit: a rear-end strikes the rear
/// face or a rear corner, a head-on the front face or a front corner, an angle (front into side)
/// or a sideswipe (side along side) a side or a corner. A pedestrian or an object may be hit
/// anywhere. `rocc explain E0120` prints this table; keep the two in step.
pub fn points_for(impact: Impact) -> &'static [Point] {
    use Point::*;
    match impact {
        Impact::RearEnd => &[Rear, RearLeft, RearRight],
        Impact::HeadOn => &[Front, FrontLeft, FrontRight],
        Impact::Angle | Impact::Sideswipe => &[Left, Right, FrontLeft, FrontRight, RearLeft, RearRight],
        Impact::Pedestrian | Impact::Object => &[Front, Rear, Left, Right, FrontLeft, FrontRight, RearLeft, RearRight],
    }
}

fn find_goal_span(a: &ast::Agent, key: &str) -> Span {
    a.stmts
        .iter()
        .find_map(|s| match s {
            ast::AgentStmt::Goal(g) => g.stmts.iter().find(|x| x.keyword() == key).map(|x| x.span()),
            _ => None,
        })
        .unwrap_or(a.span)
}

fn lateral_name(l: Lateral) -> &'static str {
    match l {
        Lateral::HoldLane => "hold its lane",
        Lateral::ChangeLane(_) => "change lane",
        Lateral::PullToShoulder => "pull to the shoulder",
        Lateral::AwayFrom(_) => "ease aside (`away_from`)",
        Lateral::Cross => "cross",
    }
}

fn side_name(s: Side) -> &'static str {
    if s == Side::Left { "left" } else { "right" }
}

/// Lanes on one side of one arm.
/// Width of a sidewalk beside the road (m); the road pass builds them this wide.
pub const SIDEWALK_WIDTH_M: f64 = 3.0;
/// Clearance between a curve's inner road edge and the bend's centre (m).
pub const CURVE_MARGIN_M: f64 = 5.0;
/// Smallest central island a roundabout's inner ring edge must leave (m).
pub const ISLAND_MIN_M: f64 = 3.0;

/// The smallest `radius` a curve or roundabout with this cross-section accepts (`None` for the
/// other templates): a curve's centre line must clear the road's half width (median, lanes,
/// shoulder and sidewalk) by `CURVE_MARGIN_M`, and a roundabout's ring middle must sit half the
/// ring's width plus `ISLAND_MIN_M` from the centre.
pub fn min_radius(road: &Road) -> Option<f64> {
    let lanes = f64::from(road.lanes) * road.lane_width;
    match road.template {
        Template::Curve => {
            let walk = if road.sidewalks { SIDEWALK_WIDTH_M } else { 0.0 };
            Some(road.median / 2.0 + lanes + road.shoulder + walk + CURVE_MARGIN_M)
        }
        Template::Roundabout => Some(lanes / 2.0 + ISLAND_MIN_M),
        _ => None,
    }
}

pub fn lane_count(road: &Road, arm: Arm, dir: Dir) -> u32 {
    match (road.template, arm, dir) {
        (Template::Merge, Arm::Ramp, Dir::In) => 1,
        (Template::Merge, Arm::Ramp, Dir::Out) => 0,
        _ => road.lanes,
    }
}

/// Why a turn does not exist from an arm (the T has no north arm), or `None`.
fn turn_exists(t: Template, from: Arm, turn: Turn) -> Option<String> {
    if t != Template::TJunction || turn == Turn::UTurn {
        return None;
    }
    let missing = match (from, turn) {
        (Arm::West, Turn::Left) | (Arm::East, Turn::Right) => Some("north"),
        (Arm::South, Turn::Straight) => Some("north"),
        _ => None,
    }?;
    Some(format!(
        "a t_junction has no {missing} arm: from {} there is no `{}`",
        from.name(),
        TURNS.iter().find(|(_, x)| *x == turn).map_or("", |(n, _)| *n)
    ))
}
