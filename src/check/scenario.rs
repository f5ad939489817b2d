//! The checked scenario: names resolved, units converted to SI (m, s, m/s, rad, Hz), values that
//! the seed decides still as distributions. This is the input of the sample pass. Spans are kept
//! only where a later pass reports errors (placement), and are not serialised.

use crate::source::Span;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A value the seed decides: fixed, or uniform in [lo, hi].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Dist {
    Fixed(f64),
    Uniform(f64, f64),
}

impl Dist {
    pub fn lo(self) -> f64 {
        match self {
            Dist::Fixed(v) | Dist::Uniform(v, _) => v,
        }
    }
    pub fn hi(self) -> f64 {
        match self {
            Dist::Fixed(v) | Dist::Uniform(_, v) => v,
        }
    }
    pub fn map(self, f: impl Fn(f64) -> f64) -> Dist {
        match self {
            Dist::Fixed(v) => Dist::Fixed(f(v)),
            Dist::Uniform(a, b) => {
                let (x, y) = (f(a), f(b));
                Dist::Uniform(x.min(y), x.max(y))
            }
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scenario {
    pub name: String,
    pub seed: u64,
    /// Clip length, seconds.
    pub duration: f64,
    /// Frame rate, Hz.
    pub rate: f64,
    /// Agents (indices into `agents`) that each get an ego-centric clip.
    pub egos: Vec<usize>,
    pub road: Road,
    /// Movers and static objects, in declaration order.
    pub agents: Vec<Agent>,
    pub rows: Vec<Row>,
    pub conflicts: Vec<Conflict>,
    /// `near_miss` blocks: passes within a gap, staged without contact.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub near_misses: Vec<NearMiss>,
    /// People directing traffic (`flag { ... }`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub flaggers: Vec<Flagger>,
    pub traffic: Option<Traffic>,
    /// `expect` lines, evaluated on the tracks by `rocc test` (`crate::expect`).
    #[serde(default)]
    pub expects: Vec<Expect>,
    /// Every kind the scenario names (after `one_of`), with its priors.
    pub kinds: BTreeMap<String, Kind>,
}

impl Scenario {
    pub fn frame_count(&self) -> usize {
        (self.duration * self.rate).round() as usize
    }
    pub fn agent(&self, name: &str) -> Option<usize> {
        self.agents.iter().position(|a| a.name == name)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Template {
    Straight,
    Curve,
    FourWay,
    TJunction,
    Merge,
    Roundabout,
    /// No map: the scene of replayed tracks imported from a recorded clip (`rocc import boxes`),
    /// whose map layers, if any, come from a recorded BEV (`--static-bev`).
    None,
}

impl Template {
    pub const ALL: [(&'static str, Template); 7] = [
        ("straight", Template::Straight),
        ("curve", Template::Curve),
        ("four_way", Template::FourWay),
        ("t_junction", Template::TJunction),
        ("merge", Template::Merge),
        ("roundabout", Template::Roundabout),
        ("none", Template::None),
    ];
    pub fn name(self) -> &'static str {
        Template::ALL.iter().find(|(_, t)| *t == self).map(|(n, _)| *n).expect("every template is listed")
    }
    pub fn arms(self) -> &'static [Arm] {
        match self {
            Template::Straight | Template::Curve => &[Arm::West, Arm::East],
            Template::FourWay | Template::Roundabout => &[Arm::North, Arm::East, Arm::South, Arm::West],
            Template::TJunction => &[Arm::West, Arm::East, Arm::South],
            Template::Merge => &[Arm::Main, Arm::Ramp],
            Template::None => &[],
        }
    }
    /// Templates with a junction area (and `junction` landmarks).
    pub fn has_junction(self) -> bool {
        !matches!(self, Template::Straight | Template::Curve | Template::None)
    }
    /// Templates with stop (or yield) lines on their in-lanes, where turns are chosen.
    pub fn has_stop_lines(self) -> bool {
        matches!(self, Template::FourWay | Template::TJunction | Template::Roundabout)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Arm {
    North,
    East,
    South,
    West,
    Main,
    Ramp,
}

impl Arm {
    pub const ALL: [(&'static str, Arm); 6] = [
        ("north", Arm::North),
        ("east", Arm::East),
        ("south", Arm::South),
        ("west", Arm::West),
        ("main", Arm::Main),
        ("ramp", Arm::Ramp),
    ];
    pub fn name(self) -> &'static str {
        Arm::ALL.iter().find(|(_, a)| *a == self).map(|(n, _)| *n).expect("every arm is listed")
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Dir {
    In,
    Out,
}

/// Road template and its parameters, with the template's defaults filled in (SI units).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Road {
    pub template: Template,
    /// Lanes per direction.
    pub lanes: u32,
    pub lane_width: f64,
    pub speed_limit: f64,
    pub shoulder: f64,
    pub median: f64,
    pub crosswalks: bool,
    pub sidewalks: bool,
    /// Length of a straight road, or of each junction arm / curve tangent.
    pub length: f64,
    /// Curve or roundabout radius.
    pub radius: f64,
    /// Curve deflection angle (rad).
    pub angle: f64,
    /// Traffic signals at the junction (`signals on`); `None`: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signals: Option<Signals>,
    /// Parking lanes and driveways along the kerbs (`parking`, `driveway`); none by default.
    #[serde(default, skip_serializing_if = "Kerbside::is_empty")]
    pub kerb: Kerbside,
}

/// A junction's signal cycle (`road four_way { signals on; signal_green 20 s }`), s: two phases,
/// the north-south approaches then the east-west ones, each green, then yellow, then all red.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Signals {
    pub green: f64,
    pub yellow: f64,
    pub all_red: f64,
    /// Time into the cycle at the clip's start.
    pub offset: f64,
    /// Per-approach greens (`signal_north 0..20 s`), indexed north, east, south, west: each
    /// green's start and end, s into a cycle of `period`; all `None` for the two-phase cycle.
    #[serde(default, skip_serializing_if = "no_windows")]
    pub windows: [Option<[f64; 2]>; 4],
    /// The length of a cycle of per-approach greens, s (0 for the two-phase cycle).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub period: f64,
}

impl Signals {
    /// The two-phase cycle: no approach states its own green.
    pub fn two_phase(&self) -> bool {
        no_windows(&self.windows)
    }
}

fn no_windows(w: &[Option<[f64; 2]>; 4]) -> bool {
    w.iter().all(Option::is_none)
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

impl Default for Signals {
    fn default() -> Self {
        Signals { green: 20.0, yellow: 3.0, all_red: 1.0, offset: 0.0, windows: [None; 4], period: 0.0 }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Class {
    Vehicle,
    Bicycle,
    Pedestrian,
    TrafficCone,
    Barrier,
    CzoneSign,
    GenericObject,
    /// Trees, poles, walls, buildings: rocc's extra `structure` BEV channel.
    Structure,
}

impl Class {
    pub const ALL: [(&'static str, Class); 8] = [
        ("vehicle", Class::Vehicle),
        ("bicycle", Class::Bicycle),
        ("pedestrian", Class::Pedestrian),
        ("traffic_cone", Class::TrafficCone),
        ("barrier", Class::Barrier),
        ("czone_sign", Class::CzoneSign),
        ("generic_object", Class::GenericObject),
        ("structure", Class::Structure),
    ];
    pub fn name(self) -> &'static str {
        Class::ALL.iter().find(|(_, c)| *c == self).map(|(n, _)| *n).expect("every class is listed")
    }
    /// How a kind of this class moves unless its definition says otherwise.
    pub fn default_motion(self) -> Motion {
        match self {
            Class::Vehicle | Class::Bicycle => Motion::Vehicle,
            Class::Pedestrian => Motion::Holonomic,
            _ => Motion::Static,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Motion {
    /// Kinematic bicycle model along lanes.
    Vehicle,
    /// Walks in any direction (pedestrians, animals).
    Holonomic,
    /// Never moves.
    Static,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Kind {
    pub name: String,
    pub class: Class,
    pub motion: Motion,
    pub length: Dist,
    pub width: Dist,
    pub height: Dist,
    /// Drives with lights and siren: one of `EMERGENCY_KINDS` or derived from one
    /// (`kind my_amb: ambulance { ... }`). Derived by the checker, so not serialised.
    #[serde(skip)]
    pub emergency: bool,
    /// `mass`, kg, stated on the kind or the kind it derives from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
}

/// The stdlib kinds that drive with lights and siren (cross traffic gives them the junction);
/// kinds derived from them inherit it.
pub const EMERGENCY_KINDS: [&str; 3] = ["ambulance", "fire_truck", "police_car"];

pub use super::posture::Posture;

pub use super::body::{Body, DOORS, Door, DoorMove};

pub use super::expect::{Expect, ExpectWhat};

pub use super::kerb::{Driveway, Kerbside, ParkingLane, Reverse};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Agent {
    pub name: String,
    /// One kind, or the `one_of` choices (all of the same class and motion).
    pub kinds: Vec<String>,
    pub class: Class,
    pub motion: Motion,
    /// Declared with `object`: never moves.
    pub is_object: bool,
    /// Per-agent box overrides of the kind's priors.
    pub length: Option<Dist>,
    pub width: Option<Dist>,
    pub height: Option<Dist>,
    pub place: Place,
    /// Initial speed, m/s.
    pub speed: Dist,
    pub goal: Option<Goal>,
    /// Replayed keyframes (from the box-stream importer); `place` is `Place::Track` then. A
    /// track that starts on a trigger (`track when ...`) carries it as `goal`'s `start_when`,
    /// its only part; its keyframe times count from when it fires.
    pub track: Option<Vec<Keyframe>>,
    /// A person's or an animal's posture, which sets its box (`sample` applies it).
    #[serde(default, skip_serializing_if = "Posture::is_standing")]
    pub posture: Posture,
    /// Attention and compliance (`behaviour { ... }`); careful by default.
    #[serde(default, skip_serializing_if = "Behaviour::is_careful")]
    pub behaviour: Behaviour,
    /// Later goal blocks, in order: each takes over from the one before once it starts.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub phases: Vec<Phase>,
    /// `siren on|off` as stated (emergency vehicles only); unstated, an emergency vehicle's is on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub siren: Option<bool>,
    /// Lamps and doors as stated (`body.rs`).
    #[serde(default, skip_serializing_if = "Body::is_default")]
    pub body: Body,
    /// Mass, kg, as the agent or its kind states it (`mass 1500 kg`); class priors otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    #[serde(skip)]
    pub span: Span,
    #[serde(skip)]
    pub place_span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct LaneId {
    pub arm: Arm,
    pub dir: Dir,
    /// 1 = nearest the centre line.
    pub index: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Landmark {
    Center,
    Junction,
    StopLine,
}

/// A distance along a lane or sidewalk from a landmark; positive = `after` (further along the
/// direction of travel), negative = `before`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Along<V = Dist> {
    pub landmark: Landmark,
    pub dist: V,
}

/// Where an agent starts. `V` is `Dist` in the checked scenario and `f64` once sampled.
/// Headings given here are absolute (world yaw, rad); without one, vehicles face along the lane.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Place<V = Dist> {
    /// Lateral offset in metres, positive to the left of the direction of travel.
    Lane {
        lane: LaneId,
        along: Along<V>,
        offset: f64,
        heading: Option<V>,
    },
    World {
        x: V,
        y: V,
        heading: Option<V>,
    },
    /// Fraction across the crosswalk, 0..1, from the right-hand kerb of the in-lanes.
    Crosswalk {
        arm: Arm,
        fraction: V,
    },
    Sidewalk {
        arm: Arm,
        dir: Dir,
        along: Along<V>,
        offset: f64,
        heading: Option<V>,
    },
    /// Pose comes from the first keyframe of the agent's track.
    Track,
    /// Slot `slot` (1 = nearest the road's centre) of the parking lane along that kerb.
    Parking {
        arm: Arm,
        dir: Dir,
        slot: u32,
    },
    /// In driveway `index` of `Road::kerb`, nosed in (facing away from the road).
    Driveway {
        index: usize,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    Left,
    Right,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Goal<V = Dist> {
    /// Target speed, m/s (`None`: keep the initial speed).
    pub speed: Option<V>,
    pub lateral: Lateral,
    pub stop: Option<Stop>,
    pub turn: Option<Turn>,
    /// Delay before the goal starts, s.
    pub start_after: f64,
    /// A condition that starts the goal (`start when ...`); it holds its initial speed till then.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start_when: Option<Trigger>,
    /// `reverse 8 m` or `reverse into LANE`: the vehicle drives backwards, rear first.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reverse: Option<Reverse>,
    /// The `stop ...` statement, for the place pass's E0206 (`stop behind` a leader that is not
    /// ahead); default when there is none.
    #[serde(skip)]
    pub stop_span: Span,
}

/// The empty goal: hold the lane at the initial speed, from the start.
impl<V> Default for Goal<V> {
    fn default() -> Self {
        Goal {
            speed: None,
            lateral: Lateral::HoldLane,
            stop: None,
            turn: None,
            start_after: 0.0,
            start_when: None,
            reverse: None,
            stop_span: Span::default(),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Lateral {
    HoldLane,
    ChangeLane(Side),
    PullToShoulder,
    /// Ease aside as the agent (index) approaches.
    AwayFrom(usize),
    Cross,
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Stop {
    AtStopLine,
    /// Queue behind the agent (index) with a gap.
    Behind(usize),
    /// Stop after travelling this many metres.
    After(f64),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Turn {
    Left,
    Right,
    Straight,
    UTurn,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Keyframe {
    pub t: f64,
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
    /// A keyframe in lane coordinates (x, y and yaw are 0 until the place pass resolves it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<Place<f64>>,
    /// The keyframe in the source, for the place pass's E0131-E0134 and E0210.
    #[serde(skip)]
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    pub kinds: Vec<String>,
    pub class: Class,
    pub from: Place,
    pub to: Place,
    /// Spacing, m.
    pub every: f64,
    #[serde(skip)]
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Impact {
    RearEnd,
    HeadOn,
    Angle,
    Sideswipe,
    Pedestrian,
    Object,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Point {
    Front,
    Rear,
    Left,
    Right,
    FrontLeft,
    FrontRight,
    RearLeft,
    RearRight,
}

/// A flagger (`flag { ... }` in a standing person's block): its stop/go states in order, which
/// act as a signal for the approach it faces (docs/language.md, "Flaggers").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Flagger {
    /// Index into `Scenario::agents`.
    pub agent: usize,
    pub steps: Vec<FlagStep>,
    /// Every step has a length and the steps repeat (`flag { stop 20 s; go 15 s }`).
    pub cycle: bool,
}

/// One state of a flagger's program.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlagStep {
    /// `go` (traffic passes) or `stop`.
    pub go: bool,
    /// s: the clip time the step begins at, once the step before it has begun (`after`; 0 for
    /// the first), or in a cycle how long it lasts.
    pub at: f64,
    /// `when NAME CONDITION`: the step begins once this holds (its agent a scenario index).
    pub trigger: Option<Trigger>,
}

/// A near miss: `passer` comes alongside `passed`, on `passed`'s `side`, its box `gap` metres
/// from `passed`'s at `at`, or closes on it from behind to a time to collision `ttc` at `at`,
/// without touching it (docs/language.md, "Near misses"). Exactly one of `gap` and `ttc` is set.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NearMiss {
    pub passer: usize,
    pub passed: usize,
    /// Least box-to-box distance, m.
    pub gap: Option<f64>,
    /// Least constant-velocity time to collision between the boxes, s.
    pub ttc: Option<f64>,
    /// `Point::Left` or `Point::Right` of the passed agent; `None`: the side the passer starts on.
    pub side: Option<Point>,
    /// Time of the closest pass, s.
    pub at: Option<f64>,
    #[serde(skip)]
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Conflict {
    pub at_fault: usize,
    pub struck: usize,
    pub impact: Impact,
    /// Side of the struck agent that is hit.
    pub point: Point,
    /// Target time of impact, s.
    pub at: Option<f64>,
    /// What follows the contact (`after`, `restitution`, `friction`).
    #[serde(default, skip_serializing_if = "AfterImpact::is_default")]
    pub after: AfterImpact,
    #[serde(skip)]
    pub span: Span,
}

/// What follows a conflict's contact: the bodies move on from it (the default), or the pair
/// holds where it met (`after latch`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AfterImpact {
    /// `after latch`: the pair holds at its deepest overlap for the rest of the clip.
    pub latch: bool,
    /// `restitution`, 0..1; `rollout::impact::RESTITUTION` when unstated.
    pub restitution: Option<f64>,
    /// `friction` between the two bodies, 0..1.5; `rollout::impact::BODY_FRICTION` when unstated.
    pub friction: Option<f64>,
}

impl AfterImpact {
    pub fn is_default(&self) -> bool {
        *self == AfterImpact::default()
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Traffic {
    /// Fraction of free lane length filled with background vehicles, 0..1.
    pub density: f64,
    /// Spread of their speeds and gaps, 0..1.
    pub randomness: f64,
}

/// Closed vocabularies: (word in `.scn`, value).
pub const IMPACTS: [(&str, Impact); 6] = [
    ("rear_end", Impact::RearEnd),
    ("head_on", Impact::HeadOn),
    ("angle", Impact::Angle),
    ("sideswipe", Impact::Sideswipe),
    ("pedestrian", Impact::Pedestrian),
    ("object", Impact::Object),
];
pub const POINTS: [(&str, Point); 8] = [
    ("front", Point::Front),
    ("rear", Point::Rear),
    ("left", Point::Left),
    ("right", Point::Right),
    ("front_left", Point::FrontLeft),
    ("front_right", Point::FrontRight),
    ("rear_left", Point::RearLeft),
    ("rear_right", Point::RearRight),
];
impl Point {
    /// The `.scn` name (`front_left`).
    pub fn name(self) -> &'static str {
        POINTS.iter().find(|x| x.1 == self).map_or("front", |x| x.0)
    }
}

pub const TURNS: [(&str, Turn); 4] =
    [("left", Turn::Left), ("right", Turn::Right), ("straight", Turn::Straight), ("u_turn", Turn::UTurn)];
pub const SIDES: [(&str, Side); 2] = [("left", Side::Left), ("right", Side::Right)];
pub const LANDMARKS: [(&str, Landmark); 3] =
    [("center", Landmark::Center), ("junction", Landmark::Junction), ("stop_line", Landmark::StopLine)];
/// What a signal head shows (`crate::road::signals`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Light {
    Green,
    Yellow,
    Red,
}

impl Light {
    pub fn name(self) -> &'static str {
        match self {
            Light::Green => "green",
            Light::Yellow => "yellow",
            Light::Red => "red",
        }
    }
}

pub const LIGHTS: [(&str, Light); 3] = [("red", Light::Red), ("yellow", Light::Yellow), ("green", Light::Green)];

pub const MOTIONS: [(&str, Motion); 3] =
    [("vehicle", Motion::Vehicle), ("holonomic", Motion::Holonomic), ("static", Motion::Static)];

/// A condition that starts an agent's goal (`start when NAME ...`), after ASAM OpenSCENARIO's
/// entity conditions; `who` is an agent index. `start after` is the simulation-time condition.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Trigger {
    /// `within D`: box centres at most `D` m apart (DistanceCondition, centre to centre).
    Within { who: usize, m: f64 },
    /// `ttc under T`: time to collision, gap between bounding circles over closing speed, under
    /// `T` s (TimeToCollisionCondition).
    Ttc { who: usize, s: f64 },
    /// `headway under T`: the time `who` needs at its speed to reach this agent ahead of it,
    /// under `T` s (TimeHeadwayCondition).
    Headway { who: usize, s: f64 },
    /// `reaches MARK`: `who`'s front has reached its stop line, or a walker's its kerb
    /// (ReachPositionCondition).
    Reaches { who: usize, mark: Mark },
    /// `starts`: `who`'s own goal has started (StoryboardElementStateCondition).
    Starts { who: usize },
}

impl Trigger {
    /// The agent the condition watches.
    pub fn who(self) -> usize {
        match self {
            Trigger::Within { who, .. }
            | Trigger::Ttc { who, .. }
            | Trigger::Headway { who, .. }
            | Trigger::Reaches { who, .. }
            | Trigger::Starts { who } => who,
        }
    }
}

/// A place on another agent's way that `reaches` watches.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Mark {
    StopLine,
    Kerb,
}

pub const MARKS: [(&str, Mark); 2] = [("stop_line", Mark::StopLine), ("kerb", Mark::Kerb)];

/// How attentive and law-abiding an agent is (`behaviour { ... }`). The default is careful:
/// it gives way, holds at its stop line, reacts at once and keeps to the speed limit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Behaviour {
    /// `yield always|never`: gives way under the right-of-way rule and to emergency vehicles,
    /// and a walker waits at the kerb for a gap; `never` goes regardless (a walker darts out).
    pub yields: bool,
    /// `stop_line obey|ignore`: holds at its stop line when it gives way; `ignore` rolls past
    /// it and holds only short of the shared zone itself.
    pub stop_line: bool,
    /// `reaction T`: how long a need to brake goes unanswered, s.
    pub reaction: f64,
    /// `speeding P %`: share over the lane's speed limit it drives at.
    pub speeding: f64,
    /// `signal obey|ignore`: stops for a red (and a yellow it can stop for) or, a walker, waits
    /// for the walk signal; `ignore` goes through regardless.
    #[serde(default = "obeys")]
    pub signal: bool,
}

fn obeys() -> bool {
    true
}

impl Default for Behaviour {
    fn default() -> Self {
        Behaviour { yields: true, stop_line: true, reaction: 0.0, speeding: 0.0, signal: true }
    }
}

impl Behaviour {
    pub fn is_careful(&self) -> bool {
        *self == Behaviour::default()
    }
}

/// A later goal block (a goal phase): a new goal speed from when its start holds, after the
/// goal before it has started.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Phase<V = Dist> {
    /// The goal speed from its start; `None` keeps the one before.
    pub speed: Option<V>,
    pub start_after: f64,
    pub start_when: Option<Trigger>,
    /// `stop after DIST`: stops that far on from where the phase starts, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stop_after: Option<f64>,
    /// `lateral pull_to_shoulder` (vehicles): pulls over from its start.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub pull_over: bool,
    /// `lateral change_lane SIDE` (vehicles): moves to the next lane of its road from its start.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub change: Option<Side>,
}
