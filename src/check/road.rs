//! The road block: template, parameters and the rules joining them; arm names.

use super::scenario::*;
use super::units::Dim;
use super::{Checker, MAX_LANES, MAX_SPEED_MS, ROAD_PARAMS};
use crate::diag::{Diagnostic, did_you_mean};
use crate::source::Span;
use crate::syntax::ast;
use std::collections::BTreeMap;

impl Checker {
    pub(super) fn road(&mut self, r: &ast::Road) -> Option<Road> {
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
            signals: None,
            kerb: Kerbside::default(),
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
        let mut signal_params = Vec::new();
        for p in &r.params {
            let n = p.name.name.as_str();
            if super::signals::PARAMS.contains(&n) {
                signal_params.push(p);
                continue;
            }
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
        match self.signals(template, &signal_params) {
            Ok(s) => road.signals = s,
            Err(()) => ok = false,
        }
        if ok && !r.kerb.is_empty() {
            match self.kerbside(r, &road) {
                Some(k) => road.kerb = k,
                None => ok = false,
            }
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

    pub(super) fn arm(&mut self, i: &ast::Ident, road: &Road) -> Option<Arm> {
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
}

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

/// Lanes on one side of one arm.
pub fn lane_count(road: &Road, arm: Arm, dir: Dir) -> u32 {
    match (road.template, arm, dir) {
        (Template::Merge, Arm::Ramp, Dir::In) => 1,
        (Template::Merge, Arm::Ramp, Dir::Out) => 0,
        _ => road.lanes,
    }
}

/// Why a turn does not exist from an arm (the T has no north arm), or `None`.
pub(super) fn turn_exists(t: Template, from: Arm, turn: Turn) -> Option<String> {
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
