//! The scene schema's traffic control and near misses: a road's `signals`, a flagger's `flag`
//! and the `near_misses` list, as the model states them and as rocc writes them into the file
//! (docs/llm.md, "Signals, flaggers and near misses").

use super::spec::{AgentSpec, FlagSpec, RoadSpec, Schema, ident, num, trigger};
use serde_json::{Value, json};

/// The JSON schema of a road's signal fields, an agent's `flag` and the `near_misses` list.
pub fn road_properties() -> Value {
    json!({
        "signals": {"type": "boolean"},
        "signal_green_s": {"type": "number", "minimum": 1, "maximum": 120},
        "signal_offset_s": {"type": "number", "minimum": 0, "maximum": 240}
    })
}

pub fn flag_property(trigger: &Value) -> Value {
    json!({
        "type": "object",
        "required": ["shows"],
        "properties": {
            "shows": {"enum": ["stop", "go"]},
            "switch_after_s": {"type": "number", "minimum": 0, "maximum": 120},
            "switch_when": trigger
        }
    })
}

pub fn near_misses_property() -> Value {
    let name = json!({"type": "string", "pattern": "^[a-z][a-z0-9_]{0,20}$"});
    json!({
        "type": "array", "maxItems": 2,
        "items": {
            "type": "object",
            "required": ["passer", "passed"],
            "properties": {
                "passer": name, "passed": name,
                "gap_m": {"type": "number", "minimum": 0.2, "maximum": 3},
                "ttc_s": {"type": "number", "minimum": 0.5, "maximum": 3},
                "side": {"enum": ["left", "right"]},
                "at_s": {"type": "number", "minimum": 0, "maximum": 30}
            }
        }
    })
}

/// The words and numbers of the fields here (what a JSON schema's enums say, for servers that
/// take no schema); the error is what the model is told.
pub fn validate(s: &mut Schema) -> Result<(), String> {
    for v in [s.road.signal_green_s, s.road.signal_offset_s].into_iter().flatten() {
        if !v.is_finite() || v < 0.0 {
            return Err("road.signal_green_s and signal_offset_s must be non-negative numbers".into());
        }
    }
    for a in &mut s.agents {
        let Some(f) = &mut a.flag else { continue };
        if !["stop", "go"].contains(&f.shows.as_str()) {
            return Err(format!("agent `{}`: flag.shows `{}` is not one of stop, go", a.name, f.shows));
        }
        if f.switch_after_s.is_some_and(|v| !v.is_finite() || v < 0.0) {
            return Err(format!("agent `{}`: flag.switch_after_s must be a non-negative number", a.name));
        }
        if let Some(t) = &mut f.switch_when {
            t.agent = ident(&t.agent, "agent");
        }
    }
    for n in &mut s.near_misses {
        if n.side.as_deref().is_some_and(|w| !["left", "right"].contains(&w)) {
            return Err(format!("near miss side `{}` is not one of left, right", n.side.as_deref().unwrap_or("")));
        }
        match (n.gap_m, n.ttc_s) {
            (Some(_), Some(_)) | (None, None) => {
                return Err("a near miss takes one of gap_m (a pass alongside) and ttc_s (a time to collision)".into());
            }
            (None, Some(_)) if n.side.is_some() => {
                return Err("a near miss by ttc_s takes no side".into());
            }
            _ => {}
        }
        let bad = |v: f64| !v.is_finite() || v <= 0.0;
        if n.gap_m.is_some_and(bad) || n.ttc_s.is_some_and(bad) || n.at_s.is_some_and(|v| !v.is_finite() || v < 0.0) {
            return Err("a near miss's gap_m and ttc_s must be positive and at_s non-negative".into());
        }
        (n.passer, n.passed) = (ident(&n.passer, "agent"), ident(&n.passed, "agent"));
    }
    Ok(())
}

/// The road parameters of `signals` (after the others).
pub fn road_params(r: &RoadSpec, params: &mut Vec<String>) {
    if !r.signals {
        return;
    }
    params.push("signals on".into());
    if let Some(g) = r.signal_green_s {
        params.push(format!("signal_green {} s", num(g)));
    }
    if let Some(o) = r.signal_offset_s {
        params.push(format!("signal_offset {} s", num(o)));
    }
}

/// A flagger's placement: on the verge beside its lane, facing the lane's traffic where the
/// arm runs along an axis (elsewhere without a heading, for the checker to judge).
pub fn flagger_placement(a: &AgentSpec, template: &str) -> String {
    let travel = match (a.arm.as_str(), a.direction.as_str()) {
        ("west", "in") | ("east", "out") => Some(0),
        ("south", "in") | ("north", "out") => Some(90),
        ("east", "in") | ("west", "out") => Some(180),
        ("north", "in") | ("south", "out") => Some(270),
        _ => None,
    };
    let axis = matches!(template, "straight" | "four_way" | "t_junction" | "roundabout");
    let heading = travel.filter(|_| axis).map_or(String::new(), |d| format!(" heading {} deg", (d + 180) % 360));
    format!(
        "at {}.{}[{}], {} m {} {} offset 2.5 m right{heading}",
        a.arm,
        a.direction,
        a.lane,
        num(a.distance_m),
        a.relation,
        a.landmark
    )
}

/// `flag { stop; go after 8 s }` and its kin.
pub fn flag_block(f: &FlagSpec) -> String {
    let other = if f.shows == "stop" { "go" } else { "stop" };
    let then = match (&f.switch_when, f.switch_after_s) {
        (Some(t), _) => format!("; {other} {}", trigger(t).trim_start_matches("start ")),
        (None, Some(s)) => format!("; {other} after {} s", num(s)),
        (None, None) => String::new(),
    };
    format!("flag {{ {}{then} }}", f.shows)
}

/// The `near_miss` blocks.
pub fn near_miss_blocks(s: &Schema) -> String {
    let mut out = String::new();
    for n in &s.near_misses {
        let mut parts = vec![format!("passer {}", n.passer), format!("passed {}", n.passed)];
        if let Some(g) = n.gap_m {
            parts.push(format!("gap {} m", num(g)));
        }
        if let Some(t) = n.ttc_s {
            parts.push(format!("ttc {} s", num(t)));
        }
        if let Some(side) = &n.side {
            parts.push(format!("side {side}"));
        }
        if let Some(at) = n.at_s {
            parts.push(format!("at {} s", num(at)));
        }
        out.push_str(&format!("\n    near_miss {{ {} }}\n", parts.join("; ")));
    }
    out
}
