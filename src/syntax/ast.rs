//! The syntax tree of a `.scn` file. Every node carries the byte span it was parsed from; numbers
//! keep their literal text so the formatter reprints exactly what the user wrote.

use crate::source::Span;
use serde::Serialize;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Ident {
    pub name: String,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct File {
    pub items: Vec<Item>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Item {
    Use(Use),
    Kind(KindDecl),
    Scenario(Scenario),
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Use {
    /// The path between the quotes.
    pub path: String,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct KindDecl {
    pub name: Ident,
    pub class: Ident,
    pub stmts: Vec<KindStmt>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum KindStmt {
    Size(SizeStmt),
    Motion {
        motion: Ident,
        span: Span,
    },
    /// `mass VALUE` (kg).
    Mass {
        value: Value,
        span: Span,
    },
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Scenario {
    pub name: Ident,
    pub stmts: Vec<ScenarioStmt>,
    pub span: Span,
}

// Built once per file and walked once: boxing the large variants would only add noise.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum ScenarioStmt {
    Seed {
        value: u64,
        literal: String,
        span: Span,
    },
    Duration {
        value: Value,
        span: Span,
    },
    Rate {
        value: Value,
        span: Span,
    },
    Egos {
        egos: Egos,
        span: Span,
    },
    Road(Road),
    Agent(Agent),
    Row(Row),
    Conflict(Conflict),
    /// `near_miss { passer ..; passed ..; gap ..; side ..; at .. }`: the same key-value shape.
    NearMiss(Conflict),
    Traffic(ParamBlock),
    Expect(ExpectBlock),
}

impl ScenarioStmt {
    pub fn span(&self) -> Span {
        match self {
            ScenarioStmt::Seed { span, .. }
            | ScenarioStmt::Duration { span, .. }
            | ScenarioStmt::Rate { span, .. }
            | ScenarioStmt::Egos { span, .. } => *span,
            ScenarioStmt::Road(r) => r.span,
            ScenarioStmt::Agent(a) => a.span,
            ScenarioStmt::Row(r) => r.span,
            ScenarioStmt::Conflict(c) => c.span,
            ScenarioStmt::NearMiss(c) => c.span,
            ScenarioStmt::Traffic(t) => t.span,
            ScenarioStmt::Expect(e) => e.span,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Egos {
    List(Vec<Ident>),
    Vehicles,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Road {
    pub template: Ident,
    pub params: Vec<Param>,
    /// `parking ARM SIDE [WIDTH]` and `driveway NAME ARM.DIR DIST` (src/road/parking.rs).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub kerb: Vec<KerbDecl>,
    pub span: Span,
}

/// A kerbside place declared in a road block.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum KerbDecl {
    /// `parking east both 2.5 m`: the side word (`in`, `out`, `both`) is checked.
    Parking { arm: Ident, side: Ident, width: Option<Value>, span: Span },
    /// `driveway d1 east.out 20 m`: across the sidewalk of that kerb, 20 m along the arm.
    Driveway { name: Ident, side: SideRef, at: Value, span: Span },
}

/// `traffic { ... }`: a block of named parameters.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParamBlock {
    pub params: Vec<Param>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Param {
    pub name: Ident,
    pub value: ParamValue,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum ParamValue {
    Value(Value),
    Switch { on: bool, span: Span },
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Agent {
    /// `object` declarations never move; `agent` ones may.
    pub is_object: bool,
    pub name: Ident,
    pub kind: KindRef,
    pub stmts: Vec<AgentStmt>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum KindRef {
    Named(Ident),
    OneOf { kinds: Vec<Ident>, span: Span },
}

impl KindRef {
    pub fn span(&self) -> Span {
        match self {
            KindRef::Named(i) => i.span,
            KindRef::OneOf { span, .. } => *span,
        }
    }
}

#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum AgentStmt {
    At {
        place: Placement,
        span: Span,
    },
    Speed {
        value: Value,
        span: Span,
    },
    Size(SizeStmt),
    Goal(Goal),
    Track(Track),
    /// `posture WORD` (standing, kneeling, lying), validated by the checker.
    Posture {
        word: Ident,
        span: Span,
    },
    Behaviour(Behaviour),
    /// `siren on|off` (the word as written, checked by the checker).
    Siren {
        value: Ident,
        span: Span,
    },
    /// `lights|hazards|beacons on|off` (key and word as written, checked by the checker).
    Lamp {
        key: Ident,
        value: Ident,
        span: Span,
    },
    /// `door NAME ACTION at TIME` or `door NAME ACTION when ...` (words checked by the checker).
    Door(DoorStmt),
    /// `mass VALUE` (kg).
    Mass {
        value: Value,
        span: Span,
    },
    /// `flag { ... }`: a flagger's stop/go states.
    Flag(Flag),
}

/// `door front_left open at 3 s` / `door front_left open when bike within 8 m`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DoorStmt {
    pub door: Ident,
    pub action: Ident,
    /// `at TIME`; `None` with `when`.
    pub at: Option<Value>,
    pub when: Option<Trigger>,
    pub span: Span,
}

impl AgentStmt {
    pub fn span(&self) -> Span {
        match self {
            AgentStmt::At { span, .. } | AgentStmt::Speed { span, .. } | AgentStmt::Siren { span, .. } => *span,
            AgentStmt::Lamp { span, .. } => *span,
            AgentStmt::Door(d) => d.span,
            AgentStmt::Size(s) => s.span,
            AgentStmt::Goal(g) => g.span,
            AgentStmt::Track(t) => t.span,
            AgentStmt::Posture { span, .. } => *span,
            AgentStmt::Behaviour(b) => b.span,
            AgentStmt::Mass { span, .. } => *span,
            AgentStmt::Flag(f) => f.span,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum SizeKey {
    Length,
    Width,
    Height,
}

impl SizeKey {
    pub fn as_str(self) -> &'static str {
        match self {
            SizeKey::Length => "length",
            SizeKey::Width => "width",
            SizeKey::Height => "height",
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SizeStmt {
    pub key: SizeKey,
    pub value: Value,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    pub kind: KindRef,
    pub from: Placement,
    pub to: Placement,
    pub every: Value,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Placement {
    /// `ARM.in[k], 20 m before stop_line [offset 1 m right] [heading 10 deg]`
    Lane { lane: LaneRef, along: Along, offset: Option<Offset>, heading: Option<Value>, span: Span },
    /// `(12 m, -3 m) [heading 90 deg]`
    World { x: Value, y: Value, heading: Option<Value>, span: Span },
    /// `crosswalk(north), 30 %`
    Crosswalk { arm: Ident, fraction: Value, span: Span },
    /// `sidewalk(north.out), 3 m after junction`
    Sidewalk { side: SideRef, along: Along, offset: Option<Offset>, heading: Option<Value>, span: Span },
    /// `parking(east.out)[3]`
    Parking { side: SideRef, slot: u32, slot_span: Span, span: Span },
    /// `driveway(d1)`
    Driveway { name: Ident, span: Span },
}

impl Placement {
    pub fn span(&self) -> Span {
        match self {
            Placement::Lane { span, .. }
            | Placement::World { span, .. }
            | Placement::Crosswalk { span, .. }
            | Placement::Sidewalk { span, .. }
            | Placement::Parking { span, .. }
            | Placement::Driveway { span, .. } => *span,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Dir {
    In,
    Out,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SideRef {
    pub arm: Ident,
    pub dir: Dir,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LaneRef {
    pub arm: Ident,
    pub dir: Dir,
    pub index: u32,
    pub index_span: Span,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Rel {
    Before,
    After,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Along {
    pub dist: Value,
    pub rel: Rel,
    pub landmark: Ident,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Offset {
    pub dist: Value,
    pub side: Ident,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Goal {
    pub stmts: Vec<GoalStmt>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum GoalStmt {
    Speed {
        value: Value,
        span: Span,
    },
    Lateral {
        lateral: Lateral,
        span: Span,
    },
    Stop {
        stop: Stop,
        span: Span,
    },
    Turn {
        turn: Ident,
        span: Span,
    },
    Start {
        after: Value,
        span: Span,
    },
    /// `start when NAME CONDITION` (a trigger; `start after` is the time condition).
    StartWhen {
        trigger: Trigger,
        span: Span,
    },
    /// `reverse 8 m` or `reverse into east.out[1]`.
    Reverse {
        to: ReverseTo,
        span: Span,
    },
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum ReverseTo {
    Dist(Value),
    Into(LaneRef),
}

impl GoalStmt {
    pub fn span(&self) -> Span {
        match self {
            GoalStmt::Speed { span, .. }
            | GoalStmt::Lateral { span, .. }
            | GoalStmt::Stop { span, .. }
            | GoalStmt::Turn { span, .. }
            | GoalStmt::Start { span, .. }
            | GoalStmt::StartWhen { span, .. }
            | GoalStmt::Reverse { span, .. } => *span,
        }
    }
    pub fn keyword(&self) -> &'static str {
        match self {
            GoalStmt::Speed { .. } => "speed",
            GoalStmt::Lateral { .. } => "lateral",
            GoalStmt::Stop { .. } => "stop",
            GoalStmt::Turn { .. } => "turn",
            GoalStmt::Start { .. } | GoalStmt::StartWhen { .. } => "start",
            GoalStmt::Reverse { .. } => "reverse",
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Lateral {
    /// `hold_lane`, `pull_to_shoulder`, `cross`, or a misspelling the checker reports.
    Word(Ident),
    ChangeLane(Ident),
    AwayFrom(Ident),
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Stop {
    /// `stop at stop_line` (the word is kept to report misspellings).
    At(Ident),
    Behind(Ident),
    After(Value),
}

/// `when NAME WORD [under] [VALUE | LANDMARK]`, as written: the checker validates the word.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Trigger {
    pub who: Ident,
    pub cond: Ident,
    pub under: bool,
    pub value: Option<Value>,
    pub landmark: Option<Ident>,
    pub span: Span,
}

/// `flag { STATE [after T | when ... | T]; ... }`: the state words are validated by the checker.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Flag {
    pub steps: Vec<FlagStep>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FlagStep {
    /// `stop` or `go`, as written.
    pub state: Ident,
    pub when: FlagWhen,
    pub span: Span,
}

/// When a flag step begins.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum FlagWhen {
    /// The first step, shown from the start.
    Start,
    /// `after T`: at a clip time.
    After(Value),
    /// `when NAME CONDITION`.
    When(Trigger),
    /// `STATE T`: shown for `T` in a repeating cycle.
    For(Value),
}

/// `behaviour { NAME VALUE|WORD ... }`: settings are validated by the checker.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Behaviour {
    pub sets: Vec<BehaviourSet>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BehaviourSet {
    pub name: Ident,
    pub value: FieldValue,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Track {
    pub keys: Vec<Keyframe>,
    /// `track when NAME CONDITION { ... }`: keyframe times count from when it fires.
    pub when: Option<Trigger>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Keyframe {
    pub t: Value,
    pub pose: KeyPose,
    pub span: Span,
}

/// Where a keyframe puts the agent: a world pose, or a lane placement (`west.in[1], 20 m before
/// center`) resolved on the map.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum KeyPose {
    World { x: Value, y: Value, yaw: Value },
    Lane(Placement),
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Conflict {
    pub fields: Vec<ConflictField>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConflictField {
    pub key: String,
    pub key_span: Span,
    pub value: FieldValue,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum FieldValue {
    Ident(Ident),
    Value(Value),
}

/// A number or a range with an optional unit, exactly as written.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Value {
    pub lo: Number,
    /// `Some` for a range `lo..hi`.
    pub hi: Option<Number>,
    pub unit: Option<Unit>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Number {
    pub value: f64,
    pub literal: String,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Unit {
    pub text: String,
    pub span: Span,
}

// ---- expectations (`expect { ... }`, evaluated by `rocc test`) ----

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ExpectBlock {
    pub items: Vec<Expectation>,
    pub span: Span,
}

/// One line of an `expect` block; `window` is `during A..B s` or `by T s`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Expectation {
    pub what: ExpectWhat,
    pub window: Option<Window>,
    pub span: Span,
}

impl Expectation {
    /// The agents the line names.
    pub fn agents(&self) -> Vec<&Ident> {
        match &self.what {
            ExpectWhat::Contact { a, b, .. } | ExpectWhat::Gap { a, b, .. } => vec![a, b],
            ExpectWhat::NoContact { pair } => pair.iter().flat_map(|(a, b)| [a, b]).collect(),
            ExpectWhat::Stopped { agent, .. }
            | ExpectWhat::Reach { agent, .. }
            | ExpectWhat::Speed { agent, .. }
            | ExpectWhat::Enters { agent, .. } => {
                vec![agent]
            }
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum ExpectWhat {
    /// `contact A with B [on SIDE]`: SIDE is on B's box.
    Contact { a: Ident, b: Ident, side: Option<Ident> },
    /// `no_contact [A with B]`.
    NoContact { pair: Option<(Ident, Ident)> },
    /// `gap A with B at_least|at_most DIST`.
    Gap { a: Ident, b: Ident, bound: Bound, value: Value },
    /// `stopped A before LANDMARK`.
    Stopped { agent: Ident, landmark: Ident },
    /// `reach A LANDMARK by T`.
    Reach { agent: Ident, landmark: Ident },
    /// `speed A at_least|at_most SPEED`.
    Speed { agent: Ident, bound: Bound, value: Value },
    /// `enters A on red|yellow|green`: the light of A's own approach as A's front passes its stop line.
    Enters { agent: Ident, light: Ident },
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Bound {
    pub at_least: bool,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Window {
    /// `by T` (from the start to T) rather than `during A..B`.
    pub by: bool,
    pub value: Value,
    pub span: Span,
}
