//! The scene schema's plain data: what the model returns as JSON (`Schema` and its parts) and
//! the words rocc writes from it (`ident`, `num`, `trigger`). Read and written by `schema.rs`
//! and `control.rs`.

use serde::{Deserialize, Serialize};

pub const TEMPLATES: [&str; 6] = ["straight", "curve", "four_way", "t_junction", "merge", "roundabout"];
pub const ARMS: [&str; 6] = ["north", "east", "south", "west", "main", "ramp"];
pub const LANDMARKS: [&str; 3] = ["center", "stop_line", "junction"];
/// Upper bound on the roster: a sentence names a handful of agents; background traffic is
/// `traffic { density }`, not a roster.
pub const MAX_AGENTS: usize = 8;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Schema {
    pub name: String,
    #[serde(default)]
    pub brief: String,
    pub road: RoadSpec,
    #[serde(default = "default_duration")]
    pub duration_s: f64,
    pub agents: Vec<AgentSpec>,
    #[serde(default)]
    pub density: Option<f64>,
    #[serde(default)]
    pub randomness: Option<f64>,
    #[serde(default)]
    pub seed: Option<u64>,
    /// Passes within a gap, staged without contact (`near_miss { ... }`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub near_misses: Vec<NearMissSpec>,
}

fn default_duration() -> f64 {
    8.0
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoadSpec {
    pub template: String,
    #[serde(default = "one")]
    pub lanes: u32,
    #[serde(default)]
    pub speed_limit_kmh: Option<f64>,
    #[serde(default)]
    pub crosswalks: bool,
    #[serde(default)]
    pub sidewalks: bool,
    /// Parking lanes along kerbs (`parking ARM in|out|both`), straight roads only.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub parking: Vec<ParkingSpec>,
    /// Driveways across the sidewalk (`driveway NAME ARM.DIR D m`), straight roads only.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub driveways: Vec<DrivewaySpec>,
    /// Traffic signals at the junction (`signals on`), with an optional green and offset, s.
    #[serde(default)]
    pub signals: bool,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signal_green_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signal_offset_s: Option<f64>,
}

/// A parking lane: the arm and the kerb (`in`, `out` or `both`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParkingSpec {
    pub arm: String,
    pub side: String,
}

/// A driveway: its name, the kerb it crosses and its distance along the arm from the centre.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DrivewaySpec {
    pub name: String,
    pub arm: String,
    #[serde(default = "out_word")]
    pub direction: String,
    #[serde(default = "twenty")]
    pub distance_m: f64,
}

/// Where an agent stands (`AgentSpec::on`).
pub const PLACES: [&str; 5] = ["lane", "sidewalk", "crosswalk", "parking", "driveway"];

fn out_word() -> String {
    "out".into()
}

fn one() -> u32 {
    1
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AgentSpec {
    pub name: String,
    pub kind: String,
    /// `lane` (default), `sidewalk`, `crosswalk`, `parking` (a slot of the parking lane along
    /// `arm`.`direction`) or `driveway`.
    #[serde(default = "lane_word")]
    pub on: String,
    pub arm: String,
    /// `in` (toward the centre, default) or `out`.
    #[serde(default = "in_word")]
    pub direction: String,
    #[serde(default = "one")]
    pub lane: u32,
    #[serde(default = "twenty")]
    pub distance_m: f64,
    /// `before` (default) or `after` the landmark.
    #[serde(default = "before_word")]
    pub relation: String,
    #[serde(default = "center_word")]
    pub landmark: String,
    #[serde(default)]
    pub speed_kmh: f64,
    #[serde(default)]
    pub ego: bool,
    /// `standing`, `kneeling` or `lying` (people and animals); `None` writes nothing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub posture: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub behaviour: Option<BehaviourSpec>,
    /// When the agent's goal starts (in place of `start after`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start_when: Option<TriggerSpec>,
    /// An emergency vehicle's siren (on unless `false`); `None` writes nothing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub siren: Option<bool>,
    /// Headlights, hazard lights and an emergency vehicle's beacons, on or off; `None` writes
    /// nothing (docs/language.md, "Lamps and doors").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lights: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hazards: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beacons: Option<bool>,
    /// A side door that opens at a time or on a trigger (dooring).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub door: Option<DoorSpec>,
    /// The parking slot of `on: parking` (1 = nearest the centre; `lane` otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slot: Option<u32>,
    /// The driveway of `on: driveway` (the road's first otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub driveway: Option<String>,
    /// A person directing traffic: what it shows and when it switches.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flag: Option<FlagSpec>,
}

/// `door NAME open at T s` or `door NAME open when ...` (the trigger's `within` or `ttc_under`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DoorSpec {
    /// `front_left`, `front_right`, `rear_left` or `rear_right`.
    pub door: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub open_at_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub open_when: Option<TriggerSpec>,
}

/// How an agent departs from careful behaviour (the `.scn` `behaviour { ... }` block).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BehaviourSpec {
    /// `always` or `never`.
    #[serde(default, rename = "yield", skip_serializing_if = "Option::is_none")]
    pub yield_: Option<String>,
    /// `obey` or `ignore`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stop_line: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reaction_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speeding_pct: Option<f64>,
    /// `obey` or `ignore` (traffic signals and flaggers).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signal: Option<String>,
}

/// `start when AGENT CONDITION [VALUE]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TriggerSpec {
    pub agent: String,
    /// One of `CONDITIONS`.
    pub condition: String,
    /// Metres for `within`, seconds for `ttc_under` and `headway_under`; unused otherwise.
    #[serde(default)]
    pub value: f64,
}

pub const POSTURES: [&str; 3] = ["standing", "kneeling", "lying"];
/// Trigger conditions as the schema spells them (one word each, for an enum).
pub const CONDITIONS: [&str; 6] =
    ["within", "ttc_under", "headway_under", "reaches_stop_line", "reaches_kerb", "starts"];

fn lane_word() -> String {
    "lane".into()
}
fn in_word() -> String {
    "in".into()
}
fn before_word() -> String {
    "before".into()
}
fn center_word() -> String {
    "center".into()
}
fn twenty() -> f64 {
    20.0
}

/// A flagger's stop/go: what it shows first, and when (a time, or a trigger) it switches.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlagSpec {
    /// `stop` or `go`.
    pub shows: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub switch_after_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub switch_when: Option<TriggerSpec>,
}

/// `near_miss { passer A; passed B; gap G m; side S; at T s }`, or by time to collision
/// `near_miss { passer A; passed B; ttc T s; at T s }`: one of `gap_m` and `ttc_s`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NearMissSpec {
    pub passer: String,
    pub passed: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gap_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ttc_s: Option<f64>,
    /// `left` or `right`; the side the passer starts on when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub side: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at_s: Option<f64>,
}

/// `start when ...` of a trigger.
pub fn trigger(t: &TriggerSpec) -> String {
    let v = num(t.value);
    let cond = match t.condition.as_str() {
        "within" => format!("within {v} m"),
        "ttc_under" => format!("ttc under {v} s"),
        "headway_under" => format!("headway under {v} s"),
        "reaches_stop_line" => "reaches stop_line".into(),
        "reaches_kerb" => "reaches kerb".into(),
        _ => "starts".into(),
    };
    format!("start when {} {cond}", t.agent)
}

/// A legal identifier from a model's word: lowercase, `[a-z0-9_]`, starting with a letter.
pub fn ident(word: &str, fallback: &str) -> String {
    let mut s: String = word
        .trim()
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '_' })
        .collect::<String>()
        .trim_matches('_')
        .to_string();
    s.truncate(40);
    match s.chars().next() {
        None => fallback.to_string(),
        Some(c) if !c.is_ascii_alphabetic() => format!("a_{s}"),
        Some(_) => s,
    }
}

/// A number as the DSL writes it: at most two decimals, no trailing zeros.
pub fn num(x: f64) -> String {
    let r = (x * 100.0).round() / 100.0;
    if r == 0.0 { "0".into() } else { format!("{r}") }
}
