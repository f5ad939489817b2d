//! Goals: what an agent does (turn, stop, lateral moves) and the checks that relate it to others.

use super::road::turn_exists;
use super::scenario::*;
use super::units::Dim;
use super::{Checker, MAX_DURATION_S, MAX_SPEED_MS, lane_count, word};
use crate::diag::{Diagnostic, did_you_mean};
use crate::source::Span;
use crate::syntax::ast;
use std::collections::BTreeMap;

impl Checker {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn goal(
        &mut self,
        g: &ast::Goal,
        motion: Motion,
        class: Class,
        place: Option<&Place>,
        road: Option<&Road>,
        order: &[&str],
        me: &ast::Ident,
    ) -> Option<Option<Goal>> {
        let mut out = Goal::default();
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
                ast::GoalStmt::StartWhen { trigger, .. } => match self.trigger(trigger, order) {
                    Some(t) => out.start_when = Some(t),
                    None => ok = false,
                },
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
                        Lateral::ChangeLane(side) => no_lane_beside(place, road, side),
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
                ast::GoalStmt::Reverse { to, span } => match self.reverse(to, *span, class, road) {
                    Some(r) => out.reverse = Some(r),
                    None => ok = false,
                },
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
        if ok && let Some(r) = out.reverse {
            ok = self.reverse_fits(&out, r, g, place);
        }
        ok.then_some(Some(out))
    }
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

/// Why a lane change to `side` from a lane placement has nowhere to go, if it has not.
pub(super) fn no_lane_beside(place: Option<&Place>, road: Option<&Road>, side: Side) -> Option<String> {
    let (Some(Place::Lane { lane, .. }), Some(r)) = (place, road) else { return None };
    let lanes = lane_count(r, lane.arm, lane.dir);
    // Lane 1 is nearest the centre line: moving left lowers the index.
    let target = if side == Side::Left { lane.index as i64 - 1 } else { lane.index as i64 + 1 };
    (target < 1 || target > lanes as i64).then(|| {
        format!("there is no lane to the {} of lane {} ({} lanes per direction)", side_name(side), lane.index, lanes)
    })
}
