//! pest parse tree -> AST. The pest grammar guarantees the shape of each pair, so the tree walk
//! uses `expect` only on what the grammar makes impossible.

use super::ast::*;
use super::error::syntax_error;
use super::rules::{Rule, ScnParser};
use crate::diag::Diagnostic;
use crate::source::{FileId, Span};
use pest::Parser;
use pest::iterators::Pair;

type P<'a> = Pair<'a, Rule>;

/// Parse one file. A syntax error yields exactly one diagnostic.
pub fn parse(file: FileId, text: &str) -> Result<File, Diagnostic> {
    let mut pairs = ScnParser::parse(Rule::file, text).map_err(|e| syntax_error(file, text, e))?;
    let root = pairs.next().expect("grammar: file is the root rule");
    let b = Builder { file };
    let span = b.span(&root);
    let items = root.into_inner().filter(|p| p.as_rule() != Rule::EOI).map(|p| b.item(p)).collect();
    Ok(File { items, span })
}

struct Builder {
    file: FileId,
}

fn inner(p: P<'_>) -> Vec<P<'_>> {
    p.into_inner().collect()
}

impl Builder {
    fn span(&self, p: &P<'_>) -> Span {
        let s = p.as_span();
        Span::new(self.file, s.start(), s.end())
    }

    /// A `conflict` or `near_miss` block: its keyword, then `KEY VALUE` fields.
    fn key_fields(&self, p: P<'_>, span: Span) -> Conflict {
        let fields = inner(p)
            .into_iter()
            .skip(1)
            .map(|f| {
                let span = self.span(&f);
                let mut it = inner(f).into_iter();
                let k = it.next().expect("grammar: block field key");
                let v = it.next().expect("grammar: block field value");
                let value = match v.as_rule() {
                    Rule::ident => FieldValue::Ident(self.ident(v)),
                    _ => FieldValue::Value(self.value(v)),
                };
                ConflictField { key: k.as_str().to_string(), key_span: self.span(&k), value, span }
            })
            .collect();
        Conflict { fields, span }
    }

    fn ident(&self, p: P<'_>) -> Ident {
        debug_assert_eq!(p.as_rule(), Rule::ident);
        Ident { name: p.as_str().to_string(), span: self.span(&p) }
    }

    fn item(&self, p: P<'_>) -> Item {
        let span = self.span(&p);
        match p.as_rule() {
            Rule::use_decl => {
                let s = inner(p).into_iter().find(|q| q.as_rule() == Rule::string).expect("grammar: use has a string");
                let raw = s.as_str();
                Item::Use(Use { path: raw[1..raw.len() - 1].to_string(), span })
            }
            Rule::kind_decl => {
                let mut it = inner(p).into_iter().filter(|q| q.as_rule() != Rule::kw_kind);
                let name = self.ident(it.next().expect("grammar: kind name"));
                let class = self.ident(it.next().expect("grammar: kind class"));
                let stmts = it
                    .map(|q| match q.as_rule() {
                        Rule::size_stmt => KindStmt::Size(self.size(q)),
                        Rule::mass_stmt => KindStmt::Mass { span: self.span(&q), value: self.value(last(q)) },
                        Rule::motion_stmt => {
                            let span = self.span(&q);
                            let m = inner(q).pop().expect("grammar: motion word");
                            KindStmt::Motion { motion: self.ident(m), span }
                        }
                        r => unreachable!("grammar: kind statement {r:?}"),
                    })
                    .collect();
                Item::Kind(KindDecl { name, class, stmts, span })
            }
            Rule::scenario => {
                let mut it = inner(p).into_iter().skip(1);
                let name = self.ident(it.next().expect("grammar: scenario name"));
                let stmts = it.map(|q| self.scenario_stmt(q)).collect();
                Item::Scenario(Scenario { name, stmts, span })
            }
            r => unreachable!("grammar: item {r:?}"),
        }
    }

    fn scenario_stmt(&self, p: P<'_>) -> ScenarioStmt {
        let span = self.span(&p);
        match p.as_rule() {
            Rule::seed_stmt => {
                let n = inner(p).pop().expect("grammar: seed value");
                let literal = n.as_str().to_string();
                // An integer too large for u64 saturates; the checker reports it.
                let value = literal.parse().unwrap_or(u64::MAX);
                ScenarioStmt::Seed { value, literal, span }
            }
            Rule::duration_stmt => ScenarioStmt::Duration { value: self.value(last(p)), span },
            Rule::rate_stmt => ScenarioStmt::Rate { value: self.value(last(p)), span },
            Rule::egos_stmt => {
                let q = last(p);
                let egos = match q.as_rule() {
                    Rule::ego_list => Egos::List(inner(q).into_iter().map(|i| self.ident(i)).collect()),
                    _ => Egos::Vehicles,
                };
                ScenarioStmt::Egos { egos, span }
            }
            Rule::road => {
                let mut it = inner(p).into_iter().skip(1);
                let template = self.ident(it.next().expect("grammar: road template"));
                let (mut params, mut kerb) = (vec![], vec![]);
                for q in it {
                    match q.as_rule() {
                        Rule::parking_decl | Rule::driveway_decl => kerb.push(self.kerb_decl(q)),
                        _ => params.push(self.param(q)),
                    }
                }
                ScenarioStmt::Road(Road { template, params, kerb, span })
            }
            Rule::traffic => {
                let params = inner(p).into_iter().skip(1).map(|q| self.param(q)).collect();
                ScenarioStmt::Traffic(ParamBlock { params, span })
            }
            Rule::agent | Rule::object => {
                let is_object = p.as_rule() == Rule::object;
                let mut it = inner(p).into_iter().skip(1);
                let name = self.ident(it.next().expect("grammar: agent name"));
                let kind = self.kind_ref(it.next().expect("grammar: agent kind"));
                let stmts = it.map(|q| self.agent_stmt(q)).collect();
                ScenarioStmt::Agent(Agent { is_object, name, kind, stmts, span })
            }
            Rule::row => {
                let parts: Vec<_> = inner(p)
                    .into_iter()
                    .filter(|q| !matches!(q.as_rule(), Rule::kw_row | Rule::kw_from | Rule::kw_to | Rule::kw_every))
                    .collect();
                let [kind, from, to, every]: [P<'_>; 4] = parts.try_into().expect("grammar: row has four parts");
                ScenarioStmt::Row(Row {
                    kind: self.kind_ref(kind),
                    from: self.placement(from),
                    to: self.placement(to),
                    every: self.value(every),
                    span,
                })
            }
            Rule::conflict => ScenarioStmt::Conflict(self.key_fields(p, span)),
            Rule::near_miss => ScenarioStmt::NearMiss(self.key_fields(p, span)),
            Rule::expect_block => {
                let items = inner(p).into_iter().skip(1).map(|q| self.expectation(q)).collect();
                ScenarioStmt::Expect(ExpectBlock { items, span })
            }
            r => unreachable!("grammar: scenario statement {r:?}"),
        }
    }

    /// One expectation: keywords dropped, the names, bound, value and window in written order.
    fn expectation(&self, p: P<'_>) -> Expectation {
        // pest's span of a rule that ends in an optional part takes the white space (and
        // comments) skipped before it: end at the last part instead.
        let end = p.clone().into_inner().last().map_or(p.as_span().end(), |q| q.as_span().end());
        let span = Span::new(self.file, p.as_span().start(), end);
        let rule = p.as_rule();
        let mut window = None;
        let mut names = vec![];
        let (mut bound, mut value, mut side) = (None, None, None);
        for q in inner(p) {
            match q.as_rule() {
                Rule::ident => names.push(self.ident(q)),
                Rule::exp_pair => {
                    names.extend(inner(q).into_iter().filter(|x| x.as_rule() == Rule::ident).map(|x| self.ident(x)))
                }
                Rule::exp_bound => {
                    bound = Some(Bound { at_least: q.as_str().starts_with("at_least"), span: self.span(&q) })
                }
                Rule::value => value = Some(self.value(q)),
                Rule::exp_on => side = Some(self.ident(last(q))),
                Rule::exp_window => {
                    let wspan = self.span(&q);
                    let mut it = inner(q).into_iter();
                    let by = it.next().expect("grammar: window word").as_str().starts_with("by");
                    window =
                        Some(Window { by, value: self.value(it.next().expect("grammar: window value")), span: wspan });
                }
                _ => {}
            }
        }
        let name = |i: usize| names.get(i).cloned().expect("grammar: expectation names");
        let what = match rule {
            Rule::exp_contact => ExpectWhat::Contact { a: name(0), b: name(1), side },
            Rule::exp_no_contact => ExpectWhat::NoContact { pair: names.first().cloned().zip(names.get(1).cloned()) },
            Rule::exp_gap => ExpectWhat::Gap {
                a: name(0),
                b: name(1),
                bound: bound.expect("grammar: gap bound"),
                value: value.expect("grammar: gap value"),
            },
            Rule::exp_stopped => ExpectWhat::Stopped { agent: name(0), landmark: name(1) },
            Rule::exp_reach => ExpectWhat::Reach { agent: name(0), landmark: name(1) },
            Rule::exp_speed => ExpectWhat::Speed {
                agent: name(0),
                bound: bound.expect("grammar: speed bound"),
                value: value.expect("grammar: speed value"),
            },
            Rule::exp_enters => ExpectWhat::Enters { agent: name(0), light: name(1) },
            r => unreachable!("grammar: expectation {r:?}"),
        };
        Expectation { what, window, span }
    }

    fn param(&self, p: P<'_>) -> Param {
        let span = self.span(&p);
        let mut it = inner(p).into_iter();
        let name = self.ident(it.next().expect("grammar: param name"));
        let v = it.next().expect("grammar: param value");
        let value = match v.as_rule() {
            Rule::switch => ParamValue::Switch { on: v.as_str().starts_with("on"), span: self.span(&v) },
            _ => ParamValue::Value(self.value(v)),
        };
        Param { name, value, span }
    }

    fn kerb_decl(&self, p: P<'_>) -> KerbDecl {
        let span = self.span(&p);
        let rule = p.as_rule();
        let parts: Vec<_> = inner(p).into_iter().skip(1).collect();
        if rule == Rule::parking_decl {
            let width = parts.get(2).map(|v| self.value(v.clone()));
            return KerbDecl::Parking {
                arm: self.ident(parts[0].clone()),
                side: self.ident(parts[1].clone()),
                width,
                span,
            };
        }
        KerbDecl::Driveway {
            name: self.ident(parts[0].clone()),
            side: self.side_ref(parts[1].clone()),
            at: self.value(parts[2].clone()),
            span,
        }
    }

    fn side_ref(&self, s: P<'_>) -> SideRef {
        let span = self.span(&s);
        let mut it = inner(s).into_iter();
        let arm = self.ident(it.next().expect("grammar: side arm"));
        let dir = dir(it.next().expect("grammar: side dir").as_str());
        SideRef { arm, dir, span }
    }

    fn kind_ref(&self, p: P<'_>) -> KindRef {
        let q = last(p);
        match q.as_rule() {
            Rule::ident => KindRef::Named(self.ident(q)),
            _ => {
                let span = self.span(&q);
                let kinds = inner(q).into_iter().skip(1).map(|i| self.ident(i)).collect();
                KindRef::OneOf { kinds, span }
            }
        }
    }

    fn agent_stmt(&self, p: P<'_>) -> AgentStmt {
        let span = self.span(&p);
        match p.as_rule() {
            Rule::at_stmt => AgentStmt::At { place: self.placement(last(p)), span },
            Rule::speed_stmt => AgentStmt::Speed { value: self.value(last(p)), span },
            Rule::siren_stmt => AgentStmt::Siren { value: self.ident(last(p)), span },
            Rule::lamp_stmt => {
                let parts = inner(p);
                let key = Ident { name: parts[0].as_str().to_string(), span: self.span(&parts[0]) };
                AgentStmt::Lamp { key, value: self.ident(parts[1].clone()), span }
            }
            Rule::door_stmt => AgentStmt::Door(self.door(p)),
            Rule::mass_stmt => AgentStmt::Mass { value: self.value(last(p)), span },
            Rule::size_stmt => AgentStmt::Size(self.size(p)),
            Rule::goal => {
                let stmts = inner(p).into_iter().skip(1).map(|q| self.goal_stmt(q)).collect();
                AgentStmt::Goal(Goal { stmts, span })
            }
            Rule::track => {
                let parts = inner(p);
                let when = parts.iter().find(|q| q.as_rule() == Rule::trigger).map(|q| self.trigger(q.clone()));
                let keys = parts
                    .into_iter()
                    .filter(|q| q.as_rule() == Rule::keyframe)
                    .map(|k| {
                        let span = self.span(&k);
                        let parts = inner(k);
                        let t = self.value(parts[0].clone());
                        if let Some(lane) = parts.iter().find(|q| q.as_rule() == Rule::key_lane) {
                            return Keyframe { t, pose: KeyPose::Lane(self.placement(lane.clone())), span };
                        }
                        let v: Vec<_> = parts.into_iter().skip(1).filter(|q| q.as_rule() == Rule::value).collect();
                        let [x, y, yaw]: [P<'_>; 3] = v.try_into().expect("grammar: a world keyframe has x, y and yaw");
                        let (x, y, yaw) = (self.value(x), self.value(y), self.value(yaw));
                        Keyframe { t, pose: KeyPose::World { x, y, yaw }, span }
                    })
                    .collect();
                AgentStmt::Track(Track { keys, when, span })
            }
            Rule::posture_stmt => AgentStmt::Posture { word: self.ident(last(p)), span },
            Rule::behaviour => {
                let sets = inner(p).into_iter().skip(1).map(|q| self.behaviour_set(q)).collect();
                AgentStmt::Behaviour(Behaviour { sets, span })
            }
            Rule::flag => {
                let steps = inner(p).into_iter().skip(1).map(|q| self.flag_step(q)).collect();
                AgentStmt::Flag(Flag { steps, span })
            }
            r => unreachable!("grammar: agent statement {r:?}"),
        }
    }

    fn size(&self, p: P<'_>) -> SizeStmt {
        let span = self.span(&p);
        let mut it = inner(p).into_iter();
        let key = match it.next().expect("grammar: size key").as_str() {
            "length" => SizeKey::Length,
            "width" => SizeKey::Width,
            _ => SizeKey::Height,
        };
        SizeStmt { key, value: self.value(it.next().expect("grammar: size value")), span }
    }

    fn goal_stmt(&self, p: P<'_>) -> GoalStmt {
        let span = self.span(&p);
        match p.as_rule() {
            Rule::speed_stmt => GoalStmt::Speed { value: self.value(last(p)), span },
            Rule::lateral => {
                let q = last(p);
                let lateral = match q.as_rule() {
                    Rule::lat_away => Lateral::AwayFrom(self.ident(last(q))),
                    Rule::lat_change => Lateral::ChangeLane(self.ident(last(q))),
                    _ => Lateral::Word(self.ident(q)),
                };
                GoalStmt::Lateral { lateral, span }
            }
            Rule::stop => {
                let q = last(p);
                let stop = match q.as_rule() {
                    Rule::stop_line => Stop::At(self.ident(last(q))),
                    Rule::stop_behind => Stop::Behind(self.ident(last(q))),
                    _ => Stop::After(self.value(last(q))),
                };
                GoalStmt::Stop { stop, span }
            }
            Rule::turn => GoalStmt::Turn { turn: self.ident(last(p)), span },
            Rule::reverse => {
                let q = last(p);
                let to = match q.as_rule() {
                    Rule::lane_ref => ReverseTo::Into(self.lane_ref(q)),
                    _ => ReverseTo::Dist(self.value(q)),
                };
                GoalStmt::Reverse { to, span }
            }
            Rule::start => match last(p.clone()) {
                q if q.as_rule() == Rule::trigger => GoalStmt::StartWhen { trigger: self.trigger(q), span },
                q => GoalStmt::Start { after: self.value(q), span },
            },
            r => unreachable!("grammar: goal statement {r:?}"),
        }
    }

    /// `door NAME ACTION (at TIME | when ...)`.
    fn door(&self, p: P<'_>) -> DoorStmt {
        let span = self.span(&p);
        let parts = inner(p);
        let at = parts.iter().find(|x| x.as_rule() == Rule::value).map(|v| self.value(v.clone()));
        let when = parts.iter().find(|x| x.as_rule() == Rule::trigger).map(|t| self.trigger(t.clone()));
        DoorStmt { door: self.ident(parts[1].clone()), action: self.ident(parts[2].clone()), at, when, span }
    }

    fn trigger(&self, p: P<'_>) -> Trigger {
        let span = self.span(&p);
        let parts = inner(p);
        let idents: Vec<_> = parts.iter().filter(|x| x.as_rule() == Rule::ident).cloned().collect();
        let value = parts.iter().find(|x| x.as_rule() == Rule::value).map(|v| self.value(v.clone()));
        let under = parts.iter().any(|x| x.as_rule() == Rule::kw_under);
        let mut it = idents.into_iter();
        let who = self.ident(it.next().expect("grammar: trigger names an agent"));
        let cond = self.ident(it.next().expect("grammar: trigger has a condition"));
        let landmark = it.next().map(|l| self.ident(l));
        Trigger { who, cond, under, value, landmark, span }
    }

    fn flag_step(&self, p: P<'_>) -> FlagStep {
        let span = self.span(&p);
        let parts = inner(p);
        let state = self.ident(parts[0].clone());
        let when = match parts.get(1) {
            None => FlagWhen::Start,
            Some(q) if q.as_rule() == Rule::trigger => FlagWhen::When(self.trigger(q.clone())),
            Some(q) if q.as_rule() == Rule::kw_after => {
                FlagWhen::After(self.value(parts.last().expect("grammar: `after` takes a time").clone()))
            }
            Some(q) => FlagWhen::For(self.value(q.clone())),
        };
        FlagStep { state, when, span }
    }

    fn behaviour_set(&self, p: P<'_>) -> BehaviourSet {
        let span = self.span(&p);
        let mut it = inner(p).into_iter();
        let name = self.ident(it.next().expect("grammar: behaviour setting name"));
        let v = it.next().expect("grammar: behaviour setting value");
        let value = if v.as_rule() == Rule::value {
            FieldValue::Value(self.value(v))
        } else {
            FieldValue::Ident(self.ident(v))
        };
        BehaviourSet { name, value, span }
    }

    fn placement(&self, p: P<'_>) -> Placement {
        let q = last(p);
        let span = self.span(&q);
        let parts = inner(q.clone());
        let heading = parts.iter().find(|x| x.as_rule() == Rule::heading).map(|h| self.value(last(h.clone())));
        let offset = parts.iter().find(|x| x.as_rule() == Rule::offset).map(|o| {
            let span = self.span(o);
            let v: Vec<_> = inner(o.clone()).into_iter().skip(1).collect();
            let [dist, side]: [P<'_>; 2] = v.try_into().expect("grammar: offset has a distance and a side");
            Offset { dist: self.value(dist), side: self.ident(side), span }
        });
        let along = parts.iter().find(|x| x.as_rule() == Rule::along).map(|a| self.along(a.clone()));
        match q.as_rule() {
            Rule::world_place => {
                let v: Vec<_> = parts.iter().filter(|x| x.as_rule() == Rule::value).cloned().collect();
                let [x, y]: [P<'_>; 2] = v.try_into().expect("grammar: world placement has x and y");
                Placement::World { x: self.value(x), y: self.value(y), heading, span }
            }
            Rule::crosswalk_place => {
                let arm = parts.iter().find(|x| x.as_rule() == Rule::ident).expect("grammar: crosswalk arm");
                let v = parts.iter().find(|x| x.as_rule() == Rule::value).expect("grammar: crosswalk fraction");
                Placement::Crosswalk { arm: self.ident(arm.clone()), fraction: self.value(v.clone()), span }
            }
            Rule::sidewalk_place => {
                let s = parts.iter().find(|x| x.as_rule() == Rule::side_ref).expect("grammar: sidewalk side");
                let sspan = self.span(s);
                let mut it = inner(s.clone()).into_iter();
                let arm = self.ident(it.next().expect("grammar: side arm"));
                let dir = dir(it.next().expect("grammar: side dir").as_str());
                Placement::Sidewalk {
                    side: SideRef { arm, dir, span: sspan },
                    along: along.expect("grammar: sidewalk placement has a distance"),
                    offset,
                    heading,
                    span,
                }
            }
            Rule::parking_place => {
                let s = parts.iter().find(|x| x.as_rule() == Rule::side_ref).expect("grammar: parking side");
                let k = parts.iter().find(|x| x.as_rule() == Rule::integer).expect("grammar: parking slot");
                Placement::Parking {
                    side: self.side_ref(s.clone()),
                    slot: k.as_str().parse().unwrap_or(u32::MAX),
                    slot_span: self.span(k),
                    span,
                }
            }
            Rule::driveway_place => {
                let n = parts.iter().find(|x| x.as_rule() == Rule::ident).expect("grammar: driveway name");
                Placement::Driveway { name: self.ident(n.clone()), span }
            }
            _ => {
                let l = parts.iter().find(|x| x.as_rule() == Rule::lane_ref).expect("grammar: lane ref");
                Placement::Lane {
                    lane: self.lane_ref(l.clone()),
                    along: along.expect("grammar: lane placement has a distance"),
                    offset,
                    heading,
                    span,
                }
            }
        }
    }

    fn lane_ref(&self, l: P<'_>) -> LaneRef {
        let span = self.span(&l);
        let mut it = inner(l).into_iter();
        let arm = self.ident(it.next().expect("grammar: lane arm"));
        let d = dir(it.next().expect("grammar: lane dir").as_str());
        let idx = it.next().expect("grammar: lane index");
        LaneRef { arm, dir: d, index: idx.as_str().parse().unwrap_or(u32::MAX), index_span: self.span(&idx), span }
    }

    fn along(&self, p: P<'_>) -> Along {
        let span = self.span(&p);
        let v: Vec<_> = inner(p);
        let [dist, rel, landmark]: [P<'_>; 3] = v.try_into().expect("grammar: along has three parts");
        Along {
            dist: self.value(dist),
            rel: if rel.as_str() == "before" { Rel::Before } else { Rel::After },
            landmark: self.ident(landmark),
            span,
        }
    }

    fn value(&self, p: P<'_>) -> Value {
        debug_assert_eq!(p.as_rule(), Rule::value);
        let span = self.span(&p);
        let q = last(p);
        let is_range = q.as_rule() == Rule::range;
        let mut nums = Vec::new();
        let mut unit = None;
        for x in inner(q) {
            match x.as_rule() {
                Rule::number => nums.push(Number {
                    value: x.as_str().parse().expect("grammar: numbers are decimal literals"),
                    literal: x.as_str().to_string(),
                }),
                Rule::unit => unit = Some(Unit { text: x.as_str().to_string(), span: self.span(&x) }),
                r => unreachable!("grammar: value part {r:?}"),
            }
        }
        let mut nums = nums.into_iter();
        let lo = nums.next().expect("grammar: value has a number");
        let hi = if is_range { nums.next() } else { None };
        Value { lo, hi, unit, span }
    }
}

fn last(p: P<'_>) -> P<'_> {
    p.into_inner().last().expect("grammar: rule has children")
}

fn dir(s: &str) -> Dir {
    if s.starts_with("in") { Dir::In } else { Dir::Out }
}
