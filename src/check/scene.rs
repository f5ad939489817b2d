//! The scenario block: its settings, egos and background traffic, and the order of checks.

use super::scenario::*;
use super::units::Dim;
use super::{Checker, MAX_DURATION_S, MAX_RATE_HZ};
use crate::diag::{Diagnostic, did_you_mean};
use crate::source::Span;
use crate::syntax::ast;
use std::collections::BTreeMap;

impl Checker {
    pub(super) fn scenario(&mut self, s: &ast::Scenario) -> Option<Scenario> {
        let mut seed = None;
        let mut duration: Option<(f64, Span)> = None;
        let mut rate: Option<(f64, Span)> = None;
        let mut egos_stmt: Option<(&ast::Egos, Span)> = None;
        let mut road_ast: Option<&ast::Road> = None;
        let mut traffic_ast: Option<&ast::ParamBlock> = None;
        let mut agents_ast = vec![];
        let mut rows_ast = vec![];
        let mut conflicts_ast = vec![];
        let mut near_ast = vec![];
        let mut expects_ast = vec![];
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
                ast::ScenarioStmt::NearMiss(c) => near_ast.push(c),
                ast::ScenarioStmt::Expect(e) => expects_ast.extend(&e.items),
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

        self.trigger_refs(&agents, &agents_ast, road.as_ref());

        let conflicts: Vec<Option<Conflict>> =
            conflicts_ast.iter().map(|c| self.conflict(c, &order, &agents, duration_s)).collect();
        self.conflicts_in_order(&conflicts, &conflicts_ast, &order, duration_s);
        let near: Vec<Option<NearMiss>> =
            near_ast.iter().map(|c| self.near_miss(c, &order, &agents, duration_s)).collect();
        self.near_misses_apart(&near, &conflicts, &order, duration_s);
        let flaggers = self.flaggers(&agents_ast, &agents, &order, duration_s);
        let egos = self.egos(egos_stmt, &order, &agents, header);
        let expects = self.expects(&expects_ast, &order, &agents, road.as_ref(), duration_s);

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
            near_misses: near.into_iter().collect::<Option<Vec<_>>>()?,
            flaggers: flaggers?,
            traffic,
            expects: expects?,
            kinds: used_kinds,
        })
    }

    pub(super) fn resolve(&mut self, i: &ast::Ident, order: &[&str]) -> Option<usize> {
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
}
