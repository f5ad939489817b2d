//! The crash description every CIREN route fills in (coded records, SAFE extractions, and any
//! later front end): plain data in rocc's own terms (templates, arms, kinds, goals, impact and
//! point), with the source fields each choice came from kept as comment lines. `emit` turns it
//! into `.scn` text.

use crate::check::scenario::{Impact, Point};

/// A compass direction of travel in the source's frame (x east, y north).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compass {
    North,
    East,
    South,
    West,
}

impl Compass {
    pub fn name(self) -> &'static str {
        match self {
            Compass::North => "north",
            Compass::East => "east",
            Compass::South => "south",
            Compass::West => "west",
        }
    }
    /// Quarter turns counter-clockwise from east.
    fn quarter(self) -> i32 {
        match self {
            Compass::East => 0,
            Compass::North => 1,
            Compass::West => 2,
            Compass::South => 3,
        }
    }
    fn from_quarter(q: i32) -> Compass {
        match q.rem_euclid(4) {
            0 => Compass::East,
            1 => Compass::North,
            2 => Compass::West,
            _ => Compass::South,
        }
    }
    /// This direction turned counter-clockwise by `quarters` quarter turns.
    pub fn rotate(self, quarters: i32) -> Compass {
        Compass::from_quarter(self.quarter() + quarters)
    }
    pub fn opposite(self) -> Compass {
        self.rotate(2)
    }
    /// Quarter turns counter-clockwise that take `self` to `to`.
    pub fn turns_to(self, to: Compass) -> i32 {
        (to.quarter() - self.quarter()).rem_euclid(4)
    }
    pub fn parse(word: &str) -> Option<Compass> {
        match word.to_ascii_lowercase().as_str() {
            "north" | "northbound" | "n" => Some(Compass::North),
            "east" | "eastbound" | "e" => Some(Compass::East),
            "south" | "southbound" | "s" => Some(Compass::South),
            "west" | "westbound" | "w" => Some(Compass::West),
            _ => None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Template {
    Straight,
    /// A curve bending left or right for a vehicle on `west.in`.
    Curve {
        right: bool,
    },
    FourWay,
    TJunction,
    Merge,
}

impl Template {
    pub fn name(self) -> &'static str {
        match self {
            Template::Straight => "straight",
            Template::Curve { .. } => "curve",
            Template::FourWay => "four_way",
            Template::TJunction => "t_junction",
            Template::Merge => "merge",
        }
    }
    pub fn has_junction(self) -> bool {
        matches!(self, Template::FourWay | Template::TJunction)
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct RoadDesc {
    pub template: Template,
    /// Per direction (the merge: the main carriageway's lanes).
    pub lanes: u32,
    pub lane_width: f64,
    pub speed_limit_kmh: f64,
    /// A centre turn lane or a median strip, m.
    pub median: f64,
    pub shoulder: f64,
    /// Quarter turns counter-clockwise from the source's compass frame into rocc's.
    pub turns: i32,
    /// Why: one line per choice, citing the source.
    pub notes: Vec<String>,
}

/// Neither CIREN nor SAFE codes a lane width: the importers use a standard US lane, and a
/// centre turn lane becomes a median of the same width (rocc has no centre lane).
pub const LANE_WIDTH: f64 = 3.5;

impl RoadDesc {
    /// A road with standard lanes, no median and no shoulder.
    pub fn new(template: Template, lanes: u32, speed_limit_kmh: f64, turns: i32, notes: Vec<String>) -> Self {
        RoadDesc { template, lanes, lane_width: LANE_WIDTH, speed_limit_kmh, median: 0.0, shoulder: 0.0, turns, notes }
    }
}

/// What a vehicle does before the crash.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Manoeuvre {
    Straight,
    TurnLeft,
    TurnRight,
    ChangeLaneLeft,
    ChangeLaneRight,
    /// On-ramp vehicle joining the main road.
    Merge,
    /// Stays where it is, speed 0.
    Stopped,
}

/// The manoeuvre as the comments of both importers name it.
pub fn man_word(m: Manoeuvre) -> &'static str {
    match m {
        Manoeuvre::Straight => "straight on",
        Manoeuvre::TurnLeft => "turn left",
        Manoeuvre::TurnRight => "turn right",
        Manoeuvre::ChangeLaneLeft => "change lane left",
        Manoeuvre::ChangeLaneRight => "change lane right",
        Manoeuvre::Merge => "merge from the ramp",
        Manoeuvre::Stopped => "stopped",
    }
}

/// A T-junction has no north leg (its stem is rotated to `south`): a manoeuvre that would leave
/// by it becomes one the T holds, said in the vehicle's notes. From the stem, straight on turns
/// right; from the west, a left turn and from the east a right turn go straight on.
pub fn t_junction_turn(template: Template, arm: &str, man: Manoeuvre, notes: &mut Vec<String>) -> Manoeuvre {
    if template != Template::TJunction {
        return man;
    }
    match (arm, man) {
        ("south", Manoeuvre::Straight) => {
            notes.push("no straight on from a T's stem: turns right".into());
            Manoeuvre::TurnRight
        }
        ("west", Manoeuvre::TurnLeft) | ("east", Manoeuvre::TurnRight) => {
            let turn = if man == Manoeuvre::TurnLeft { "left" } else { "right" };
            notes.push(format!("a {turn} turn from the T's {arm} arm would leave by its missing leg: straight on"));
            Manoeuvre::Straight
        }
        _ => man,
    }
}

/// Where a vehicle starts, in rocc's arms: `arm.in[lane]`.
#[derive(Clone, Debug, PartialEq)]
pub struct VehicleDesc {
    /// `v1`, `v2`, ... after the record's vehicle numbers.
    pub name: String,
    pub kind: String,
    pub arm: &'static str,
    pub lane: u32,
    pub speed_kmh: f64,
    pub manoeuvre: Manoeuvre,
    /// Stopped where a vehicle sliding from an earlier impact strikes it (`ciren::slide`); its
    /// world pose once placed there: x, y (m) and heading (rad).
    pub on_slide: bool,
    pub at: Option<[f64; 3]>,
    pub notes: Vec<String>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Left,
    Right,
}

/// A fixed object struck in a single-vehicle crash: a structure beside the striker's lane.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectDesc {
    /// `obj1`, ...
    pub name: String,
    /// `tree`, `pole`, `wall`, `building`, or a barrier kind.
    pub kind: String,
    /// Which side of the striker's road it stands on.
    pub side: Side,
    /// Struck by a vehicle sliding from an earlier impact: it stands where the slide carries the
    /// striker (`ciren::slide`), not beside the road.
    pub on_slide: bool,
    /// Its world pose once placed on the slide: x, y (m) and heading (rad).
    pub at: Option<[f64; 3]>,
    pub notes: Vec<String>,
}

/// The face of the striking vehicle that meets the struck one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Face {
    Front,
    Left,
    Right,
    /// Only in a strike that follows an impact: a car sliding backwards into a pole.
    Back,
}

impl Face {
    pub fn name(self) -> &'static str {
        match self {
            Face::Front => "front",
            Face::Left => "left side",
            Face::Right => "right side",
            Face::Back => "back",
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct ConflictDesc {
    /// rocc's `at_fault`: the agent that leaves its goal and strikes (its `face` meets `point`).
    pub at_fault: String,
    pub struck: String,
    pub impact: Impact,
    /// The struck side, as coded.
    pub point: Point,
    /// The striker's face, as coded.
    pub face: Face,
    /// Coded clock directions of the principal force (CDC), per vehicle of the pair.
    pub clocks: Vec<ClockDesc>,
    /// Closing speed at contact implied by a coded delta-V (km/h), and the vehicle it is of.
    pub closing: Option<Closing>,
    /// The time (s) of a strike into an object on the striker's slide, as measured; `None` for a
    /// staged strike, whose time is its slot (`emit::EVENT_GAP` apart).
    pub at: Option<f64>,
    pub notes: Vec<String>,
}

/// The clock direction (1..=12) the principal force on `vehicle` comes from: 12 the front, 3
/// the right side, 6 the back, 9 the left side.
#[derive(Clone, Debug, PartialEq)]
pub struct ClockDesc {
    pub vehicle: String,
    pub hour: u32,
}

/// The closing speed a coded delta-V implies (see `impact.rs` for the model).
#[derive(Clone, Debug, PartialEq)]
pub struct Closing {
    pub kmh: f64,
}

/// Where a crash was read from. A CIREN case and the SAFE extraction of the same case share the
/// case number, so the source is part of the file and scenario names: both land in one
/// directory side by side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// A coded CIREN record (`rocc ciren import`): `<id>.scn`, scenario `ciren_<id>`.
    Record,
    /// A SAFE-format extraction (`rocc ciren import-safe`): `safe_<id>.scn`, scenario `safe_<id>`.
    Safe,
}

/// A crash ready to emit.
#[derive(Clone, Debug, PartialEq)]
pub struct Crash {
    /// Case id (the CIREN case number); with `source` it gives the file stem and scenario name.
    pub id: String,
    pub source: Source,
    /// Header comment lines (what the case is, where it came from).
    pub header: Vec<String>,
    pub road: RoadDesc,
    pub vehicles: Vec<VehicleDesc>,
    pub objects: Vec<ObjectDesc>,
    /// The staged contacts in time order (the record's event order).
    pub conflicts: Vec<ConflictDesc>,
}

impl Crash {
    pub fn scenario_name(&self) -> String {
        let prefix = match self.source {
            Source::Record => "ciren",
            Source::Safe => "safe",
        };
        format!("{prefix}_{}", self.id.replace('-', "_"))
    }
    /// The output file's stem: `100237` for a record, `safe_100237` for a SAFE extraction.
    pub fn file_stem(&self) -> String {
        match self.source {
            Source::Record => self.id.clone(),
            Source::Safe => format!("safe_{}", self.id),
        }
    }
    pub fn vehicle(&self, name: &str) -> Option<&VehicleDesc> {
        self.vehicles.iter().find(|v| v.name == name)
    }
    /// Whether conflict `k` strikes an object or a stopped vehicle placed on its striker's slide
    /// (not staged).
    pub fn on_slide(&self, k: &ConflictDesc) -> bool {
        self.objects.iter().any(|o| o.name == k.struck && o.on_slide)
            || self.vehicles.iter().any(|v| v.name == k.struck && v.on_slide)
    }
}

/// How a list of contacts in time order breaks the chains the importers stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChainBreak {
    /// The striker struck another vehicle before.
    StrikesAgain,
    /// The striker was struck before.
    StrikesAfterStruck,
    /// The pair met before.
    MetAgain,
    /// A party placed where a slide strikes it takes part in another contact.
    PlacedOnSlide,
}

impl ChainBreak {
    /// The reason, `earlier` naming the contact it conflicts with (`event 2`).
    pub fn say(self, k: &ConflictDesc, earlier: &str) -> String {
        match self {
            ChainBreak::StrikesAgain => format!("{} strikes again (it struck in {earlier})", k.at_fault),
            ChainBreak::StrikesAfterStruck => format!("{} strikes after it was struck in {earlier}", k.at_fault),
            ChainBreak::MetAgain => format!("{} and {} met already in {earlier}", k.at_fault, k.struck),
            ChainBreak::PlacedOnSlide => {
                format!("{} and {}: one of them stands where a slide reaches it in {earlier}", k.at_fault, k.struck)
            }
        }
    }
    /// What the importers can stage instead.
    pub fn help(self) -> &'static str {
        match self {
            ChainBreak::MetAgain => {
                "two vehicles are staged to crash once (the language's E0123): keep the pair's first contact"
            }
            ChainBreak::PlacedOnSlide => {
                "the importer places a party where a slide strikes it for that strike alone: import the other contacts"
            }
            _ => {
                "after its first crash a vehicle only slides to rest; the importers place a struck fixed object where \
                 that slide goes, but not another vehicle: they stage chains where each vehicle strikes another \
                 once, before it is struck"
            }
        }
    }
}

/// The first contact of `conflicts` (time order) that breaks the chain, the earlier one it
/// conflicts with, and how: each vehicle strikes another once, before it is struck, and a pair
/// meets once. A strike on a slide (`on_slide`) is brought about by that slide: its striker
/// may have struck before, and what it strikes there takes part in no other contact.
pub fn chain_break(
    conflicts: &[ConflictDesc],
    on_slide: impl Fn(&ConflictDesc) -> bool,
) -> Option<(usize, usize, ChainBreak)> {
    let pair = |x: &ConflictDesc| {
        let mut p = [x.at_fault.clone(), x.struck.clone()];
        p.sort();
        p
    };
    let involves = |x: &ConflictDesc, name: &str| x.at_fault == name || x.struck == name;
    for (i, k) in conflicts.iter().enumerate() {
        if let Some(j) = conflicts[..i].iter().position(|x| pair(x) == pair(k)) {
            return Some((i, j, ChainBreak::MetAgain));
        }
        let placed = |(j, x): &(usize, &ConflictDesc)| *j != i && on_slide(x) && involves(k, &x.struck);
        if let Some((j, _)) = conflicts.iter().enumerate().find(placed) {
            return Some((i.max(j), i.min(j), ChainBreak::PlacedOnSlide));
        }
        if on_slide(k) {
            continue;
        }
        let before = || conflicts[..i].iter().enumerate().filter(|(_, x)| !on_slide(x));
        if let Some((j, _)) = before().find(|(_, x)| x.at_fault == k.at_fault) {
            return Some((i, j, ChainBreak::StrikesAgain));
        }
        if let Some((j, _)) = before().find(|(_, x)| x.struck == k.at_fault) {
            return Some((i, j, ChainBreak::StrikesAfterStruck));
        }
    }
    None
}

/// The rocc impact name.
pub fn impact_name(i: Impact) -> &'static str {
    crate::check::scenario::IMPACTS.iter().find(|x| x.1 == i).map(|x| x.0).unwrap_or("angle")
}

/// The rocc in-arm a vehicle travelling `dir` (in rocc's frame) comes from on a four-way,
/// T-junction or straight road: travelling north it approaches from the south.
pub fn approach_arm(dir: Compass) -> &'static str {
    dir.opposite().name()
}
