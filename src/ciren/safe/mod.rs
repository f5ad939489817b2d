//! SAFE-format VLM extraction -> `Crash`. In: the JSON the SAFE pipeline's vision model wrote
//! for a CIREN case (`meta`: road type, car count; `dsl`: actors with model, W2E/E2W/S2N/N2S,
//! action and speed in mph or "N/A", lane count, a `Conflict` block). Out: the crash description.
//!
//! The input is a model's output: every field is checked, garbage is a diagnostic, and where the
//! fields disagree (a `struck_vehicle` that the `point_of_impact` text contradicts) the more
//! specific field wins with a warning (E0807). Every `Conflict` field is used: the free-text
//! `point_of_impact` decides the struck side and the striking face by the rules of
//! `point_of_impact`; `impact_type` is checked against them; `at_fault_vehicle` keeps its
//! manoeuvre and is rocc's `at_fault` whenever rocc's staging allows (a striking front, or either
//! party of a sideswipe).

use super::case::read_capped;
use super::crash::{
    Compass, Crash, LANE_WIDTH, Manoeuvre, RoadDesc, Template, VehicleDesc, approach_arm, man_word, t_junction_turn,
};
use super::record::{TURN_KMH, kind_for};
use crate::diag::Diagnostic;
use crate::source::{SourceMap, Span};
use serde_json::Value;
use std::path::Path;

/// Largest extraction read; real ones are about 1 kB.
pub const MAX_SAFE_BYTES: u64 = 1024 * 1024;

mod conflict;
mod poi;

use poi::*;
pub use poi::{Named, Part, PointOfImpact, parse_point_of_impact};

const MPH: f64 = 1.609_344;

struct Ctx {
    id: String,
    file: u32,
    text: String,
    warnings: Vec<Diagnostic>,
}

impl Ctx {
    /// The span of the first occurrence of `"key"` in the JSON text (for labels).
    fn key_span(&self, key: &str) -> Span {
        let pat = format!("\"{key}\"");
        let start = self.text.find(&pat).unwrap_or(0);
        Span::new(self.file, start, (start + pat.len()).min(self.text.len()))
    }
    fn err(&self, code: &'static str, key: &str, msg: String, help: &str) -> Vec<Diagnostic> {
        vec![
            Diagnostic::error(code, format!("SAFE {}: {msg}", self.id))
                .label(self.key_span(key), "here")
                .help(help.to_string()),
        ]
    }
    fn warn(&mut self, key: &str, msg: String) {
        let d = Diagnostic::warning("E0807", format!("SAFE {}: {msg}", self.id))
            .label(self.key_span(key), "here")
            .help("the choice is written as a comment in the generated file; check it against the case");
        self.warnings.push(d);
    }
}

fn str_of<'a>(v: &'a Value, key: &str) -> Option<&'a str> {
    v.get(key).and_then(Value::as_str).map(str::trim)
}

/// One actor as extracted.
struct Actor {
    n: u32,
    key: String,
    model: String,
    position: String,
    action: String,
    speed: String,
}

/// Read and map a SAFE extraction.
pub fn read_safe(path: &Path, sources: &mut SourceMap) -> Result<(Crash, Vec<Diagnostic>), Vec<Diagnostic>> {
    let text = read_capped(path, MAX_SAFE_BYTES)
        .map_err(|m| vec![Diagnostic::error("E0800", m).help("pass a SAFE extraction file (`<case id>.json`)")])?;
    let file = sources.add(path.display().to_string(), text.clone());
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("safe").to_string();
    let root: Value = serde_json::from_str(&text).map_err(|e| {
        let off = line_offset(&text, e.line(), e.column());
        vec![
            Diagnostic::error("E0801", format!("`{}` is not valid JSON: {e}", path.display()))
                .label(Span::new(file, off, (off + 1).min(text.len()).max(off)), "here")
                .help("a SAFE extraction is one JSON object with `case_id`, `meta` and `dsl`"),
        ]
    })?;
    let id_raw =
        root.get("case_id").and_then(|v| v.as_str().map(str::to_string).or_else(|| v.as_u64().map(|n| n.to_string())));
    let id: String = id_raw
        .unwrap_or(stem)
        .chars()
        .take(64)
        .map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' })
        .collect();
    let id = if id.is_empty() { "safe".to_string() } else { id };
    let mut cx = Ctx { id, file, text, warnings: Vec::new() };
    let crash = map(&mut cx, &root, path)?;
    Ok((crash, cx.warnings))
}

fn line_offset(text: &str, line: usize, col: usize) -> usize {
    let mut off = 0;
    for (i, l) in text.split_inclusive('\n').enumerate() {
        if i + 1 == line {
            return off + col.saturating_sub(1).min(l.len());
        }
        off += l.len();
    }
    text.len()
}

fn direction(p: &str) -> Option<Compass> {
    match p.to_ascii_uppercase().replace([' ', '-', '_'], "").as_str() {
        "W2E" => Some(Compass::East),
        "E2W" => Some(Compass::West),
        "S2N" => Some(Compass::North),
        "N2S" => Some(Compass::South),
        _ => None,
    }
}

fn action(a: &str) -> Option<(Manoeuvre, Option<&'static str>)> {
    let t = a.to_ascii_lowercase();
    let has = |w: &str| t.contains(w);
    Some(if has("stop") || has("park") || has("wait") || has("stationary") {
        (Manoeuvre::Stopped, None)
    } else if has("turn left") || has("left turn") {
        (Manoeuvre::TurnLeft, None)
    } else if has("turn right") || has("right turn") {
        (Manoeuvre::TurnRight, None)
    } else if has("change lane") || has("lane change") {
        if has("right") { (Manoeuvre::ChangeLaneRight, None) } else { (Manoeuvre::ChangeLaneLeft, None) }
    } else if has("merge") {
        (Manoeuvre::Merge, None)
    } else if has("wrong way") {
        (
            Manoeuvre::Straight,
            Some("wrong-way driving starts in its own direction's lane; the staging carries it across the centre line"),
        )
    } else if has("forward") || has("straight") || has("drive") || has("continue") || has("cruise") {
        (Manoeuvre::Straight, None)
    } else {
        return None;
    })
}

fn map(cx: &mut Ctx, root: &Value, path: &Path) -> Result<Crash, Vec<Diagnostic>> {
    let meta = root.get("meta").filter(|m| m.is_object()).ok_or_else(|| {
        cx.err("E0802", "case_id", "no `meta` object".into(), "`meta` holds road_type, car_num and drive_dir")
    })?;
    let dsl = root.get("dsl").filter(|m| m.is_object()).ok_or_else(|| {
        cx.err("E0802", "meta", "no `dsl` object".into(), "`dsl` holds Actors, Road network and Conflict")
    })?;
    let road_type = str_of(meta, "road_type")
        .ok_or_else(|| cx.err("E0802", "meta", "`meta.road_type` is missing".into(), "give the road type"))?;
    let template = match road_type.to_ascii_lowercase().replace(['-', '_', ' '], "").as_str() {
        "intersection" | "4wayintersection" | "crossroads" => Template::FourWay,
        "tintersection" | "tjunction" => Template::TJunction,
        "straight" | "straightroad" => Template::Straight,
        "curve" | "curved" | "curvedroad" => Template::Curve { right: false },
        "merging" | "merge" | "onramp" => Template::Merge,
        _ => {
            return Err(cx.err(
                "E0803",
                "road_type",
                format!("unknown road_type \"{road_type}\""),
                "known: Intersection, T-intersection, Straight, Curve, Merging",
            ));
        }
    };

    // Actors: one object (or several) of "Vehicle_N": {...}.
    let mut actors: Vec<Actor> = Vec::new();
    let list = dsl.get("Actors").and_then(Value::as_array).ok_or_else(|| {
        cx.err(
            "E0802",
            "dsl",
            "`dsl.Actors` is missing or not a list".into(),
            "`Actors` is a list of {\"Vehicle_1\": {...}} objects",
        )
    })?;
    for obj in list {
        let Some(map) = obj.as_object() else {
            return Err(cx.err(
                "E0802",
                "Actors",
                "an entry of `Actors` is not an object".into(),
                "write {\"Vehicle_1\": {...}}",
            ));
        };
        for (k, v) in map {
            let n = vehicle_no(&k.to_ascii_lowercase(), None).filter(|n| (1..=9).contains(n)).ok_or_else(|| {
                cx.err(
                    "E0803",
                    k,
                    format!("actor `{k}` is not named Vehicle_<n>"),
                    "name actors Vehicle_1, Vehicle_2, ...",
                )
            })?;
            let field = |f: &str| -> Result<String, Vec<Diagnostic>> {
                match v.get(f) {
                    Some(Value::String(s)) => Ok(s.trim().to_string()),
                    Some(Value::Number(x)) => Ok(x.to_string()),
                    _ => Err(cx.err(
                        "E0802",
                        k,
                        format!("actor `{k}` has no `{f}` text"),
                        "each actor has Model, Initial_position, Actions and Speed",
                    )),
                }
            };
            if actors.iter().any(|a| a.n == n) {
                return Err(cx.err("E0803", k, format!("two actors are called Vehicle_{n}"), "name each actor once"));
            }
            actors.push(Actor {
                n,
                key: k.clone(),
                model: field("Model")?,
                position: field("Initial_position")?,
                action: field("Actions")?,
                speed: field("Speed")?,
            });
        }
    }
    actors.sort_by_key(|a| a.n);
    if actors.is_empty() {
        return Err(cx.err("E0802", "Actors", "no actors".into(), "a crash needs at least one vehicle"));
    }
    if let Some(c) = meta.get("car_num").and_then(Value::as_u64)
        && c as usize != actors.len()
    {
        let msg = format!("meta.car_num says {c} but {} actors are listed; the actors are used", actors.len());
        cx.warn("car_num", msg);
    }

    // Lanes: the count is of the whole road (both directions) on two-way roads.
    let net = dsl.get("Road network");
    let lanes_raw =
        net.and_then(|n| n.get("Number of lanes")).map(|v| v.as_str().map(str::to_string).unwrap_or(v.to_string()));
    let (lanes, centre, lanes_note) = match lanes_raw.as_deref().map(str::trim) {
        Some(s) => {
            let n: u32 = s.parse().ok().filter(|n| (1..=12).contains(n)).ok_or_else(|| {
                cx.err(
                    "E0803",
                    "Number of lanes",
                    format!("`Number of lanes` is \"{s}\", not a count 1..12"),
                    "give the lane count as a number",
                )
            })?;
            let per = (n / 2).max(1);
            let centre = n % 2 == 1 && n > 1 && template != Template::Merge;
            let note = if n == 1 {
                "Number of lanes 1: one lane per direction".to_string()
            } else if centre {
                format!(
                    "Number of lanes {n} (both directions): {per} per direction and a centre lane, kept as a 3.5 m median (not a lane split by the centre line)"
                )
            } else {
                format!("Number of lanes {n} (both directions): {per} per direction")
            };
            (per.min(6), centre, note)
        }
        None => {
            cx.warn("dsl", "no `Number of lanes`; one lane per direction is assumed".into());
            (1, false, "no lane count: one per direction assumed".into())
        }
    };

    // Speeds (mph; "N/A" = not known).
    struct Sp {
        kmh: Option<f64>,
        cite: String,
    }
    let mut speeds = Vec::new();
    for a in &actors {
        let s = a.speed.trim();
        let sp = if s.eq_ignore_ascii_case("n/a")
            || s.eq_ignore_ascii_case("na")
            || s.eq_ignore_ascii_case("unknown")
            || s.is_empty()
        {
            Sp { kmh: None, cite: format!("Speed \"{s}\"") }
        } else {
            let num = s.trim_end_matches("mph").trim();
            let v: f64 =
                num.parse().ok().filter(|v: &f64| v.is_finite() && (0.0..=150.0).contains(v)).ok_or_else(|| {
                    cx.err(
                        "E0803",
                        &a.key,
                        format!("{}: Speed \"{s}\" is not a speed in mph (0..150) or \"N/A\"", a.key),
                        "write the speed in mph, e.g. \"45\", or \"N/A\"",
                    )
                })?;
            Sp { kmh: Some(v * MPH), cite: format!("Speed \"{s}\" mph") }
        };
        speeds.push(sp);
    }
    let limit = speeds.iter().filter_map(|s| s.kmh).fold(0.0, f64::max);
    let (limit, limit_note) = if limit > 0.0 {
        let l = (limit / 5.0).ceil() * 5.0;
        (l, format!("speed_limit {} km/h: the fastest actor's speed, rounded up", super::emit::num(l)))
    } else {
        (50.0, "no actor speed given: 50 km/h".to_string())
    };

    // The conflicts: one block, or a list of impacts in time order.
    let entries: Vec<&Value> = match dsl.get("Conflict") {
        Some(Value::Array(list)) => list.iter().collect(),
        Some(one) => vec![one],
        None => Vec::new(),
    };
    if entries.is_empty() || entries.iter().any(|c| !c.is_object()) {
        return Err(cx.err(
            "E0802",
            "dsl",
            "no `Conflict` block".into(),
            "the Conflict block names at_fault_vehicle, struck_vehicle, impact_type and point_of_impact",
        ));
    }
    let mut conflicts = Vec::new();
    for (i, c) in entries.iter().enumerate() {
        conflicts.push(conflict::decode(cx, c, &actors, (i, entries.len()))?);
    }
    if let Some((i, j, how)) = super::crash::chain_break(&conflicts, |_| false) {
        return Err(cx.err(
            "E0804",
            "Conflict",
            format!("`Conflict` entry {}: {}", i + 1, how.say(&conflicts[i], &format!("entry {}", j + 1))),
            how.help(),
        ));
    }

    // Rotation into the template frame.
    let dirs: Vec<Option<Compass>> = actors.iter().map(|a| direction(&a.position)).collect();
    let mans: Vec<(Manoeuvre, Option<&'static str>)> = actors
        .iter()
        .map(|a| {
            action(&a.action).ok_or_else(|| {
                cx.err(
                    "E0803",
                    &a.key,
                    format!("{}: unknown Actions \"{}\"", a.key, a.action),
                    "known: Move forward, Turn left, Turn right, Change lane, Merge, Stop, Enter the Wrong Way",
                )
            })
        })
        .collect::<Result<_, _>>()?;
    let mut header = vec![
        format!("SAFE extraction {}, imported by `rocc ciren import-safe` from {}.", cx.id, path.display()),
        format!("meta: road_type \"{road_type}\"; the extraction is a model's output, checked field by field."),
    ];
    let q = match template {
        Template::FourWay | Template::Merge => 0,
        Template::Straight | Template::Curve { .. } => match dirs.iter().flatten().next() {
            Some(Compass::North) => -1,
            Some(Compass::South) => 1,
            _ => 0,
        },
        Template::TJunction => {
            let stem = net.and_then(|n| str_of(n, "Stem road direction")).and_then(Compass::parse);
            match stem {
                Some(s) => s.turns_to(Compass::South),
                None => {
                    let turner = actors
                        .iter()
                        .zip(&mans)
                        .zip(&dirs)
                        .find(|((_, m), _)| matches!(m.0, Manoeuvre::TurnLeft | Manoeuvre::TurnRight));
                    let d = turner.and_then(|(_, d)| *d).or(dirs[dirs.len() - 1]).unwrap_or(Compass::North);
                    cx.warn(
                        "Road network",
                        "no `Stem road direction`; the turning vehicle's leg is taken as the stem".into(),
                    );
                    d.opposite().turns_to(Compass::South)
                }
            }
        }
    };
    if q.rem_euclid(4) != 0 {
        header.push(format!(
            "Rotated into the template: the extraction's north is rocc's {}.",
            Compass::North.rotate(q).name()
        ));
    }

    let mut vehicles: Vec<VehicleDesc> = Vec::new();
    for ((a, sp), (dir, (man, man_note))) in actors.iter().zip(&speeds).zip(dirs.iter().zip(&mans)) {
        let kind = kind_for(&a.model).ok_or_else(|| {
            cx.err(
                "E0803",
                &a.key,
                format!("{}: Model \"{}\" has no rocc kind", a.key, a.model),
                "known: Sedan, SUV, Van, Pickup, Truck, Semi Truck, Bus, Motorcycle",
            )
        })?;
        let mut man = *man;
        let mut notes = vec![format!("v{}: {}: Model \"{}\" -> {kind}", a.n, a.key, a.model)];
        let (arm, lane, where_note): (&'static str, u32, String) = match (template, dir) {
            (Template::Merge, _) => {
                let p = a.position.to_ascii_lowercase();
                if p.contains("ramp") || man == Manoeuvre::Merge {
                    man = Manoeuvre::Merge;
                    ("ramp", 1, format!("Initial_position \"{}\" -> ramp.in[1]", a.position))
                } else {
                    // The main-road party of a merge crash drives the lane the ramp joins.
                    (
                        "main",
                        lanes,
                        format!("Initial_position \"{}\" -> main.in[{lanes}], the lane the ramp joins", a.position),
                    )
                }
            }
            (_, Some(d)) => {
                let rd = d.rotate(q);
                (
                    approach_arm(rd),
                    1,
                    format!("Initial_position \"{}\" travels {} -> {}.in[1]", a.position, d.name(), approach_arm(rd)),
                )
            }
            (_, None) => {
                return Err(cx.err(
                    "E0803",
                    &a.key,
                    format!("{}: Initial_position \"{}\" is not W2E, E2W, S2N or N2S", a.key, a.position),
                    "a SAFE actor starts W2E, E2W, S2N or N2S (On-ramp / Main road on a merge)",
                ));
            }
        };
        if template == Template::TJunction && arm == "north" {
            return Err(cx.err(
                "E0804",
                &a.key,
                format!("{} approaches the T-junction from its missing leg", a.key),
                "the directions do not fit the stem direction",
            ));
        }
        notes.push(where_note);
        if let Some(n) = man_note {
            notes.push((*n).to_string());
        }
        let junction = template.has_junction();
        if matches!(man, Manoeuvre::TurnLeft | Manoeuvre::TurnRight) && !junction {
            notes.push(format!("Actions \"{}\": no junction to turn at on this road: straight on", a.action));
            man = Manoeuvre::Straight;
        }
        man = t_junction_turn(template, arm, man, &mut notes);
        // A stopped car stays stopped: 0 mph, or an action that says so.
        let stopped = man == Manoeuvre::Stopped || sp.kmh == Some(0.0);
        if stopped {
            man = Manoeuvre::Stopped;
        }
        let (speed, speed_note) = if stopped {
            (0.0, format!("{}, Actions \"{}\": stopped, speed 0 for the whole clip", sp.cite, a.action))
        } else {
            match sp.kmh {
                Some(k) if matches!(man, Manoeuvre::TurnLeft | Manoeuvre::TurnRight) && k > TURN_KMH => (
                    TURN_KMH,
                    format!(
                        "{} ({} km/h); turning: {TURN_KMH} km/h through the junction",
                        sp.cite,
                        super::emit::num(k)
                    ),
                ),
                Some(k) => (k, format!("{} = {} km/h", sp.cite, super::emit::num(k))),
                None => {
                    let d = if matches!(man, Manoeuvre::TurnLeft | Manoeuvre::TurnRight) {
                        TURN_KMH.min(limit)
                    } else {
                        limit
                    };
                    cx.warn(
                        &a.key,
                        format!(
                            "{}: Speed \"{}\" with a moving action: {} km/h assumed",
                            a.key,
                            a.speed,
                            super::emit::num(d)
                        ),
                    );
                    (d, format!("{}: not known, {} km/h assumed", sp.cite, super::emit::num(d)))
                }
            }
        };
        notes.push(format!("Actions \"{}\" -> {}; speed: {speed_note}", a.action, man_word(man)));
        vehicles.push(VehicleDesc {
            on_slide: false,
            at: None,
            name: format!("v{}", a.n),
            kind: kind.into(),
            arm,
            lane,
            speed_kmh: speed,
            manoeuvre: man,
            notes,
        });
    }
    separate_lanes(&mut vehicles, lanes);

    let mut road_notes =
        vec![format!("road {}: meta.road_type \"{road_type}\"", template.name()), format!("lanes: {lanes_note}")];
    road_notes.push(limit_note);
    Ok(Crash {
        id: cx.id.clone(),
        source: super::crash::Source::Safe,
        header,
        road: RoadDesc {
            median: if centre { LANE_WIDTH } else { 0.0 },
            ..RoadDesc::new(template, lanes, limit, q, road_notes)
        },
        vehicles,
        objects: Vec::new(),
        conflicts,
    })
}

/// Two vehicles starting on the same in-lane: the left-turner keeps the lane next to the centre
/// line, the other moves one lane out (a right-turner to the outermost), when the road has one.
fn separate_lanes(vs: &mut [VehicleDesc], lanes: u32) {
    for i in 0..vs.len() {
        for j in 0..vs.len() {
            if i == j || vs[i].arm != vs[j].arm || vs[i].lane != vs[j].lane || lanes < 2 {
                continue;
            }
            let k = if vs[i].manoeuvre == Manoeuvre::TurnLeft { j } else { i };
            let target = if vs[k].manoeuvre == Manoeuvre::TurnRight { lanes } else { (vs[k].lane + 1).min(lanes) };
            if target != vs[k].lane {
                vs[k].lane = target;
                let note = format!("shares its start lane with another vehicle: moved to {}.in[{target}]", vs[k].arm);
                vs[k].notes.push(note);
            }
        }
    }
}
