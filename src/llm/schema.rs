//! The scene schema (stage 1 of the pipeline): what the model returns as JSON, how it is read
//! and validated, and how rocc — not the model — writes the scenario skeleton from it.

pub use super::spec::*;
use serde_json::{Value, json};

/// The `.scn` lines of an agent's lamps and door.
fn body_lines(a: &AgentSpec) -> Vec<String> {
    let on = |b: bool| if b { "on" } else { "off" };
    let mut v: Vec<String> = [("lights", a.lights), ("hazards", a.hazards), ("beacons", a.beacons)]
        .into_iter()
        .filter_map(|(k, x)| x.map(|x| format!("{k} {}", on(x))))
        .collect();
    if let Some(d) = &a.door {
        match (&d.open_when, d.open_at_s) {
            (Some(t), _) => v.push(format!("door {} open {}", d.door, trigger(t).trim_start_matches("start "))),
            (None, at) => v.push(format!("door {} open at {} s", d.door, num(at.unwrap_or(0.0)))),
        }
    }
    v
}

/// The user's sliders: they win over whatever the model said, deterministically.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Overrides {
    pub density: Option<f64>,
    pub randomness: Option<f64>,
    pub seed: Option<u64>,
}

/// The JSON schema sent with the schema stage (as a decoding constraint where the server takes one).
pub fn json_schema(kinds: &[String]) -> Value {
    let mut v = base_schema(kinds);
    let trigger = v["properties"]["agents"]["items"]["properties"]["start_when"].clone();
    let road = &mut v["properties"]["road"]["properties"];
    for (k, p) in super::control::road_properties().as_object().into_iter().flatten() {
        road[k] = p.clone();
    }
    let agent = &mut v["properties"]["agents"]["items"]["properties"];
    agent["flag"] = super::control::flag_property(&trigger);
    // Kerbside placements, lamps and doors (a separate statement: one macro holding them all
    // overflows its recursion limit).
    agent["slot"] = json!({"type": "integer", "minimum": 1, "maximum": 40});
    agent["driveway"] = json!({"type": "string", "pattern": "^[a-z][a-z0-9_]{0,20}$"});
    for lamp in ["lights", "hazards", "beacons"] {
        agent[lamp] = json!({"type": "boolean"});
    }
    agent["door"] = door_schema();
    agent["behaviour"]["properties"]["signal"] = json!({"enum": ["obey", "ignore"]});
    v["properties"]["near_misses"] = super::control::near_misses_property();
    v
}

fn base_schema(kinds: &[String]) -> Value {
    json!({
        "type": "object",
        "required": ["name", "brief", "road", "duration_s", "agents"],
        "properties": {
            "name": {"type": "string", "pattern": "^[a-z][a-z0-9_]{0,40}$"},
            "brief": {"type": "string", "maxLength": 300},
            "duration_s": {"type": "number", "minimum": 1, "maximum": 30},
            "road": {
                "type": "object",
                "required": ["template", "lanes"],
                "properties": {
                    "template": {"enum": TEMPLATES},
                    "lanes": {"type": "integer", "minimum": 1, "maximum": 4},
                    "speed_limit_kmh": {"type": "number", "minimum": 10, "maximum": 130},
                    "crosswalks": {"type": "boolean"},
                    "sidewalks": {"type": "boolean"},
                    "parking": parking_schema(),
                    "driveways": driveways_schema()
                }
            },
            "agents": {
                "type": "array", "minItems": 1, "maxItems": MAX_AGENTS,
                "items": {
                    "type": "object",
                    "required": ["name", "kind", "on", "arm", "direction", "lane", "distance_m", "relation", "landmark", "speed_kmh", "ego"],
                    "properties": {
                        "name": {"type": "string", "pattern": "^[a-z][a-z0-9_]{0,20}$"},
                        "kind": {"enum": kinds},
                        "on": {"enum": PLACES},
                        "arm": {"enum": ARMS},
                        "direction": {"enum": ["in", "out"]},
                        "lane": {"type": "integer", "minimum": 1, "maximum": 4},
                        "distance_m": {"type": "number", "minimum": 0, "maximum": 100},
                        "relation": {"enum": ["before", "after"]},
                        "landmark": {"enum": LANDMARKS},
                        "speed_kmh": {"type": "number", "minimum": 0, "maximum": 130},
                        "ego": {"type": "boolean"},
                        "posture": {"enum": POSTURES},
                        "siren": {"type": "boolean"},
                        "behaviour": {
                            "type": "object",
                            "properties": {
                                "yield": {"enum": ["always", "never"]},
                                "stop_line": {"enum": ["obey", "ignore"]},
                                "reaction_s": {"type": "number", "minimum": 0, "maximum": 5},
                                "speeding_pct": {"type": "number", "minimum": 0, "maximum": 200}
                            }
                        },
                        "start_when": {
                            "type": "object",
                            "required": ["agent", "condition"],
                            "properties": {
                                "agent": {"type": "string", "pattern": "^[a-z][a-z0-9_]{0,20}$"},
                                "condition": {"enum": CONDITIONS},
                                "value": {"type": "number", "minimum": 0, "maximum": 200}
                            }
                        }
                    }
                }
            },
            "density": {"type": "number", "minimum": 0, "maximum": 1},
            "randomness": {"type": "number", "minimum": 0, "maximum": 1}
        }
    })
}

/// An agent's `door` in the JSON schema.
fn door_schema() -> Value {
    json!({
        "type": "object",
        "required": ["door"],
        "properties": {
            "door": {"enum": ["front_left", "front_right", "rear_left", "rear_right"]},
            "open_at_s": {"type": "number", "minimum": 0, "maximum": 60},
            "open_when": {
                "type": "object",
                "required": ["agent", "condition"],
                "properties": {
                    "agent": {"type": "string", "pattern": "^[a-z][a-z0-9_]{0,20}$"},
                    "condition": {"enum": ["within", "ttc_under"]},
                    "value": {"type": "number", "minimum": 0, "maximum": 200}
                }
            }
        }
    })
}

/// `road.parking` in the JSON schema.
fn parking_schema() -> Value {
    json!({
        "type": "array", "maxItems": 4,
        "items": {
            "type": "object", "required": ["arm", "side"],
            "properties": {"arm": {"enum": ARMS}, "side": {"enum": ["in", "out", "both"]}}
        }
    })
}

/// `road.driveways` in the JSON schema.
fn driveways_schema() -> Value {
    json!({
        "type": "array", "maxItems": 4,
        "items": {
            "type": "object", "required": ["name", "arm", "direction", "distance_m"],
            "properties": {
                "name": {"type": "string", "pattern": "^[a-z][a-z0-9_]{0,20}$"},
                "arm": {"enum": ARMS},
                "direction": {"enum": ["in", "out"]},
                "distance_m": {"type": "number", "minimum": 2, "maximum": 100}
            }
        }
    })
}

/// Read the model's reply: the first JSON object in it (code fences and chatter around it are
/// tolerated), then the checks serde cannot express. The error is what the model is told.
pub fn parse(reply: &str) -> Result<Schema, String> {
    let start = reply.find('{').ok_or("the reply holds no JSON object")?;
    let end = reply.rfind('}').filter(|e| *e > start).ok_or("the JSON object is not closed")?;
    let mut s: Schema = serde_json::from_str(&reply[start..=end]).map_err(|e| format!("invalid schema JSON: {e}"))?;
    s.name = ident(&s.name, "generated");
    if !TEMPLATES.contains(&s.road.template.as_str()) {
        return Err(format!("road.template `{}` is not one of {}", s.road.template, TEMPLATES.join(", ")));
    }
    if s.agents.is_empty() {
        return Err("`agents` is empty: list every road user the sentence mentions".into());
    }
    if s.agents.len() > MAX_AGENTS {
        return Err(format!(
            "{} agents is more than {MAX_AGENTS}; use `density` for background traffic",
            s.agents.len()
        ));
    }
    if !(s.duration_s.is_finite() && s.duration_s > 0.0) {
        return Err("duration_s must be a positive number of seconds".into());
    }
    // Agent names become identifiers and must be unique; the model's spelling is kept when legal.
    let mut seen: Vec<String> = vec![];
    for a in &mut s.agents {
        let base = ident(&a.name, "agent");
        let mut name = base.clone();
        let mut k = 2;
        while seen.contains(&name) {
            name = format!("{base}_{k}");
            k += 1;
        }
        seen.push(name.clone());
        a.name = name;
        a.kind = ident(&a.kind, "sedan");
        for (field, v) in [("distance_m", a.distance_m), ("speed_kmh", a.speed_kmh)] {
            if !v.is_finite() || v < 0.0 {
                return Err(format!("agent `{}`: {field} must be a non-negative number", a.name));
            }
        }
        rare_fields(a)?;
    }
    kerb_fields(&mut s)?;
    super::control::validate(&mut s)?;
    Ok(s)
}

/// The words of `posture`, `behaviour` and `start_when` (what a JSON schema's enums say, for
/// servers that take no schema). Names and meanings are the checker's to judge.
fn rare_fields(a: &mut AgentSpec) -> Result<(), String> {
    let one_of = |field: &str, v: &Option<String>, words: &[&str]| match v {
        Some(w) if !words.contains(&w.as_str()) => {
            Err(format!("agent `{}`: {field} `{w}` is not one of {}", a.name, words.join(", ")))
        }
        _ => Ok(()),
    };
    one_of("posture", &a.posture, &POSTURES)?;
    if let Some(b) = &a.behaviour {
        one_of("behaviour.yield", &b.yield_, &["always", "never"])?;
        one_of("behaviour.stop_line", &b.stop_line, &["obey", "ignore"])?;
        one_of("behaviour.signal", &b.signal, &["obey", "ignore"])?;
        for (field, v) in [("reaction_s", b.reaction_s), ("speeding_pct", b.speeding_pct)] {
            if v.is_some_and(|v| !v.is_finite() || v < 0.0) {
                return Err(format!("agent `{}`: behaviour.{field} must be a non-negative number", a.name));
            }
        }
    }
    if let Some(t) = &mut a.start_when {
        one_of("start_when.condition", &Some(t.condition.clone()), &CONDITIONS)?;
        if !t.value.is_finite() || t.value < 0.0 {
            return Err(format!("agent `{}`: start_when.value must be a non-negative number", a.name));
        }
        t.agent = ident(&t.agent, "agent");
    }
    Ok(())
}

/// The words of parking lanes, driveways and kerbside placements; names become identifiers.
fn kerb_fields(s: &mut Schema) -> Result<(), String> {
    for p in &s.road.parking {
        if !["in", "out", "both"].contains(&p.side.as_str()) {
            return Err(format!("road.parking side `{}` is not one of in, out, both", p.side));
        }
    }
    for d in &mut s.road.driveways {
        d.name = ident(&d.name, "driveway");
    }
    for a in &mut s.agents {
        if !PLACES.contains(&a.on.as_str()) {
            return Err(format!("agent `{}`: on `{}` is not one of {}", a.name, a.on, PLACES.join(", ")));
        }
        if let Some(d) = &mut a.driveway {
            *d = ident(d, "driveway");
        }
    }
    Ok(())
}

/// The `behaviour { ... }` block, if it says anything.
pub fn behaviour(b: &BehaviourSpec) -> Option<String> {
    let mut parts = vec![];
    if let Some(w) = &b.yield_ {
        parts.push(format!("yield {w}"));
    }
    if let Some(w) = &b.stop_line {
        parts.push(format!("stop_line {w}"));
    }
    if let Some(v) = b.reaction_s {
        parts.push(format!("reaction {} s", num(v)));
    }
    if let Some(v) = b.speeding_pct {
        parts.push(format!("speeding {} %", num(v)));
    }
    if let Some(w) = &b.signal {
        parts.push(format!("signal {w}"));
    }
    (!parts.is_empty()).then(|| format!("behaviour {{ {} }}", parts.join("; ")))
}

/// The goal blocks of a mover with the schema's trigger put into its first block, unless the
/// goal stage gave that block a `start` of its own; a trigger without goals starts a block.
fn goal_lines(goal: Option<&str>, start_when: Option<&TriggerSpec>) -> Vec<String> {
    let mut lines: Vec<String> = goal.map(|g| g.lines().map(|l| l.trim().to_string()).collect()).unwrap_or_default();
    let Some(t) = start_when else { return lines };
    match lines.first_mut() {
        None => lines.push(format!("goal {{ {} }}", trigger(t))),
        Some(first) if !first.contains(" start ") && !first.contains("{ start ") => {
            let body = first.trim_end().trim_end_matches('}').trim_end().trim_end_matches(';');
            *first = if body.trim_end().ends_with('{') {
                format!("goal {{ {} }}", trigger(t))
            } else {
                format!("{body}; {} }}", trigger(t))
            };
        }
        Some(_) => {}
    }
    lines
}

/// Apply the sliders. The seed, if neither the user nor the model gave one, is a hash of the
/// sentence, so the same sentence always gives the same file.
pub fn apply(s: &mut Schema, o: &Overrides, sentence: &str) {
    if let Some(d) = o.density {
        s.density = Some(d);
    }
    if let Some(r) = o.randomness {
        s.randomness = Some(r);
    }
    s.seed = o.seed.or(s.seed).or(Some(crate::fsio::fnv1a(sentence.as_bytes()) % 1_000_000));
}

/// The `at ...` placement of one agent.
pub fn placement(a: &AgentSpec) -> String {
    let d = num(a.distance_m);
    match a.on.as_str() {
        "parking" => format!("at parking({}.{})[{}]", a.arm, a.direction, a.slot.unwrap_or(a.lane)),
        "driveway" => format!("at driveway({})", a.driveway.as_deref().unwrap_or("d1")),
        "sidewalk" => format!("at sidewalk({}.{}), {d} m {} {}", a.arm, a.direction, a.relation, a.landmark),
        "crosswalk" => format!("at crosswalk({}), 50 %", a.arm),
        _ => format!("at {}.{}[{}], {d} m {} {}", a.arm, a.direction, a.lane, a.relation, a.landmark),
    }
}

/// Which agents are egos: those the model marked, else the first mover.
pub fn egos(s: &Schema, is_static: &dyn Fn(&str) -> bool) -> Vec<String> {
    // A flagger stands where it is placed: never an ego.
    let mover = |a: &&AgentSpec| !is_static(&a.kind) && a.flag.is_none();
    let marked: Vec<String> = s.agents.iter().filter(|a| a.ego && mover(a)).map(|a| a.name.clone()).collect();
    if !marked.is_empty() {
        return marked;
    }
    s.agents.iter().find(mover).map(|a| vec![a.name.clone()]).unwrap_or_default()
}

/// The scenario text: rocc writes it from the schema and the goal blocks the model chose.
/// `goals[i]` is the `goal { ... }` block of `s.agents[i]`, if any.
pub fn emit(s: &Schema, goals: &[Option<String>], is_static: &dyn Fn(&str) -> bool) -> String {
    let mut out = String::new();
    if !s.brief.trim().is_empty() {
        for line in s.brief.lines() {
            out.push_str(&format!("// {}\n", line.trim()));
        }
    }
    out.push_str(&format!("scenario {} {{\n", s.name));
    out.push_str(&format!("    seed {}\n", s.seed.unwrap_or(0)));
    out.push_str(&format!("    duration {} s\n    rate 10 Hz\n", num(s.duration_s.clamp(1.0, 120.0))));
    let egos = egos(s, is_static);
    if !egos.is_empty() {
        out.push_str(&format!("    egos [{}]\n", egos.join(", ")));
    }
    let r = &s.road;
    let sidewalks = r.sidewalks || s.agents.iter().any(|a| a.on == "sidewalk");
    // A merge has no crossing and the checker refuses the switch there; an agent placed on a
    // crosswalk still asks for it, so that mistake reaches the repair loop as a diagnostic.
    let crosswalks = (r.crosswalks && r.template != "merge") || s.agents.iter().any(|a| a.on == "crosswalk");
    let mut params = vec![format!("lanes {}", r.lanes)];
    if let Some(v) = r.speed_limit_kmh {
        params.push(format!("speed_limit {} km/h", num(v)));
    }
    if crosswalks {
        params.push("crosswalks on".into());
    }
    if sidewalks || !r.driveways.is_empty() {
        params.push("sidewalks on".into());
    }
    params.extend(r.parking.iter().map(|p| format!("parking {} {}", p.arm, p.side)));
    params.extend(
        r.driveways.iter().map(|d| format!("driveway {} {}.{} {} m", d.name, d.arm, d.direction, num(d.distance_m))),
    );
    super::control::road_params(r, &mut params);
    out.push_str(&format!("\n    road {} {{ {} }}\n", r.template, params.join("; ")));
    for (i, a) in s.agents.iter().enumerate() {
        let stat = is_static(&a.kind);
        out.push_str(&format!("\n    {} {}: {} {{\n", if stat { "object" } else { "agent" }, a.name, a.kind));
        if let Some(f) = &a.flag {
            // A flagger stands beside its lane facing the traffic; it has no speed or goal.
            out.push_str(&format!("        {}\n", super::control::flagger_placement(a, &r.template)));
            out.push_str(&format!("        {}\n    }}\n", super::control::flag_block(f)));
            continue;
        }
        out.push_str(&format!("        {}\n", placement(a)));
        if let Some(p) = &a.posture {
            out.push_str(&format!("        posture {p}\n"));
        }
        if !stat {
            out.push_str(&format!("        speed {} km/h\n", num(a.speed_kmh)));
            let goal = goals.get(i).and_then(|g| g.as_deref());
            for line in goal_lines(goal, a.start_when.as_ref()) {
                out.push_str(&format!("        {line}\n"));
            }
            if let Some(b) = a.behaviour.as_ref().and_then(behaviour) {
                out.push_str(&format!("        {b}\n"));
            }
            if let Some(on) = a.siren {
                out.push_str(&format!("        siren {}\n", if on { "on" } else { "off" }));
            }
        }
        for line in body_lines(a) {
            out.push_str(&format!("        {line}\n"));
        }
        out.push_str("    }\n");
    }
    out.push_str(&super::control::near_miss_blocks(s));
    if s.density.is_some() || s.randomness.is_some() {
        let mut t = vec![];
        if let Some(d) = s.density {
            t.push(format!("density {}", num(d)));
        }
        if let Some(r) = s.randomness {
            t.push(format!("randomness {}", num(r)));
        }
        out.push_str(&format!("\n    traffic {{ {} }}\n", t.join("; ")));
    }
    out.push_str("}\n");
    out
}

/// The agent in words, as the goal stage's "traffic director" sees it.
pub fn describe(s: &Schema, a: &AgentSpec) -> String {
    let toward = match (a.arm.as_str(), a.direction.as_str()) {
        ("west", "in") | ("east", "out") => "heading east",
        ("east", "in") | ("west", "out") => "heading west",
        ("north", "in") | ("south", "out") => "heading south",
        ("south", "in") | ("north", "out") => "heading north",
        (_, "in") => "heading toward the centre",
        _ => "heading away from the centre",
    };
    let junction = match s.road.template.as_str() {
        "straight" | "curve" => "the road centre",
        "merge" => "the merge",
        _ => "the junction",
    };
    let place = match a.on.as_str() {
        "sidewalk" => format!("on the {} sidewalk of the {} arm", a.direction, a.arm),
        "crosswalk" => format!("on the crosswalk of the {} arm", a.arm),
        "parking" => format!(
            "parked in slot {} of the parking lane along the {} {} kerb (it may `reverse into` a lane)",
            a.slot.unwrap_or(a.lane),
            a.arm,
            a.direction
        ),
        "driveway" => {
            format!("in driveway {}, nosed in (it may `reverse into` a lane)", a.driveway.as_deref().unwrap_or("d1"))
        }
        _ => {
            let motion = if a.direction == "in" { "toward" } else { "away from" };
            format!("in lane {} of the {} arm, {toward}, {motion} {junction}", a.lane, a.arm)
        }
    };
    let mut words = format!(
        "{}: a {} {place}, {} m {} the {}, at {} km/h",
        a.name,
        a.kind.replace('_', " "),
        num(a.distance_m),
        a.relation,
        a.landmark.replace('_', " "),
        num(a.speed_kmh)
    );
    if let Some(p) = &a.posture {
        words.push_str(&format!(", {p}"));
    }
    if let Some(b) = a.behaviour.as_ref().and_then(behaviour) {
        words.push_str(&format!(", {b}"));
    }
    if let Some(t) = &a.start_when {
        words.push_str(&format!(", its goal will {}", trigger(t)));
    }
    if let Some(on) = a.siren {
        words.push_str(if on { ", siren on" } else { ", siren off" });
    }
    if let Some(f) = &a.flag {
        words.push_str(&format!(", directing traffic (stands; no goal): {}", super::control::flag_block(f)));
    }
    for line in body_lines(a) {
        words.push_str(&format!(", {line}"));
    }
    words
}
