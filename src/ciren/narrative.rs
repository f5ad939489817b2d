//! Deterministic rules over a CIREN `Summary` narrative (no model): per vehicle, the direction of
//! travel, the lane position, the road's lane count and layout, turns and swerves; for the
//! scene, the junction shape and a struck fixed object. In: the narrative text. Out: `Narrative`,
//! each finding with the sentence it came from so comments can quote it.

use super::crash::Compass;

/// A finding and the words it was read from.
#[derive(Clone, Debug, PartialEq)]
pub struct Found<T> {
    pub value: T,
    pub quote: String,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LanePos {
    Left,
    Right,
    Center,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Junction {
    FourLeg,
    T,
    /// "intersection" without a leg count.
    Unspecified,
    Ramp,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Move {
    TurnLeft,
    TurnRight,
    VeerLeft,
    VeerRight,
}

/// Lanes of one road as the narrative gives them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lanes {
    /// "five-lane": both directions together.
    pub total: u32,
    /// "two lanes eastbound": one direction, when spelled out.
    pub per_direction: Option<u32>,
    /// A centre (turn) lane between the directions.
    pub centre_lane: bool,
    pub divided: bool,
    pub one_way: bool,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct VehicleText {
    pub travel: Option<Found<Compass>>,
    pub lane: Option<Found<LanePos>>,
    pub lanes: Option<Found<Lanes>>,
    pub movement: Option<Found<Move>>,
    /// On an entrance ramp.
    pub ramp: Option<Found<()>>,
    /// The road is the one the previous vehicle's sentence described ("the same roadway").
    pub same_road: bool,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Narrative {
    /// Indexed by vehicle number - 1.
    pub vehicles: Vec<VehicleText>,
    pub junction: Option<Found<Junction>>,
    /// "off the right side of the road".
    pub departure: Option<Found<Side2>>,
    /// "struck a large tree", "a utility pole".
    pub object: Option<Found<&'static str>>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side2 {
    Left,
    Right,
}

impl Narrative {
    pub fn vehicle(&self, n: u32) -> Option<&VehicleText> {
        self.vehicles.get((n as usize).checked_sub(1)?)
    }
}

const NUMBERS: [(&str, u32); 10] = [
    ("one", 1),
    ("two", 2),
    ("three", 3),
    ("four", 4),
    ("five", 5),
    ("six", 6),
    ("seven", 7),
    ("eight", 8),
    ("nine", 9),
    ("ten", 10),
];

fn number(w: &str) -> Option<u32> {
    w.parse().ok().filter(|n| (1..=12).contains(n)).or_else(|| NUMBERS.iter().find(|x| x.0 == w).map(|x| x.1))
}

/// Sentences: split at `.` followed by white space (keeps "2.5" and initials together).
pub fn sentences(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        cur.push(c);
        if c == '.' && chars.peek().is_none_or(|n| n.is_whitespace()) {
            let s = cur.split_whitespace().collect::<Vec<_>>().join(" ");
            if !s.is_empty() {
                out.push(s);
            }
            cur.clear();
        }
    }
    let s = cur.split_whitespace().collect::<Vec<_>>().join(" ");
    if !s.is_empty() {
        out.push(s);
    }
    out
}

/// Lower-case words, punctuation other than `-` and `#` stripped.
fn words(s: &str) -> Vec<String> {
    s.to_ascii_lowercase()
        .split(|c: char| c.is_whitespace() || matches!(c, ',' | ';' | ':' | '(' | ')' | '.' | '"'))
        .filter(|w| !w.is_empty())
        .map(str::to_string)
        .collect()
}

/// Every vehicle mention in a sentence: word index and vehicle number (`V<n>`, `Vehicle <word>`).
fn mentions(ws: &[String]) -> Vec<(usize, u32)> {
    let mut out = Vec::new();
    for (i, w) in ws.iter().enumerate() {
        if let Some(rest) = w.strip_prefix('v')
            && let Ok(n) = rest.trim_end_matches(['\'', 's']).parse::<u32>()
            && (1..=20).contains(&n)
        {
            out.push((i, n));
        }
        if w == "vehicle"
            && let Some(n) = ws.get(i + 1).and_then(|x| number(x))
        {
            out.push((i, n));
        }
    }
    out
}

/// The vehicle a sentence is about: its first mention.
fn subject(ws: &[String]) -> Option<u32> {
    mentions(ws).first().map(|m| m.1)
}

fn contains_seq(ws: &[String], seq: &[&str]) -> bool {
    ws.windows(seq.len()).any(|w| w.iter().zip(seq).all(|(a, b)| a == b))
}

/// "traveling north", "traveling on ... the right westbound lane", "northbound lane".
fn travel(ws: &[String]) -> Option<(usize, Compass)> {
    for (i, w) in ws.iter().enumerate() {
        if matches!(w.as_str(), "traveling" | "travelling" | "heading" | "proceeding" | "driving")
            && let Some(d) = ws.get(i + 1).and_then(|x| Compass::parse(x))
        {
            return Some((i, d));
        }
    }
    ws.iter().enumerate().find_map(|(i, w)| Some((i.saturating_sub(3), Compass::parse(w)?)))
}

/// The words `lo..hi` of a sentence, as a quotation: "... traveling east in the left ...".
fn excerpt(ws: &[String], lo: usize, hi: usize) -> String {
    let hi = hi.min(ws.len());
    let lo = lo.min(hi);
    let mut q = ws[lo..hi].join(" ");
    if lo > 0 {
        q = format!("...{q}");
    }
    if hi < ws.len() {
        q.push_str("...");
    }
    q
}

fn lane_pos(ws: &[String]) -> Option<LanePos> {
    for (i, w) in ws.iter().enumerate() {
        let pos = match w.as_str() {
            "left" => LanePos::Left,
            "right" => LanePos::Right,
            "center" | "centre" | "middle" => LanePos::Center,
            _ => continue,
        };
        // "left northbound lane", "right lane", "center left-turn lane".
        let rest: Vec<&str> = ws.iter().skip(i + 1).take(2).map(String::as_str).collect();
        let lane_next = rest.first().is_some_and(|x| x.starts_with("lane") || x.ends_with("-lane"))
            || (rest.first().is_some_and(|x| x.ends_with("bound") || x.ends_with("-turn") || *x == "turn")
                && rest.get(1).is_some_and(|x| x.starts_with("lane") || x.ends_with("-lane")));
        if lane_next {
            return Some(pos);
        }
    }
    None
}

fn lanes(ws: &[String]) -> Option<(usize, Lanes)> {
    let (i, total) = ws.iter().enumerate().find_map(|(i, w)| {
        let n = w.strip_suffix("-lane")?;
        Some((i, number(n)?))
    })?;
    let after: Vec<&str> = ws.iter().skip(i + 1).take(4).map(String::as_str).collect();
    let divided = after.contains(&"divided");
    let one_way = after.contains(&"one-way");
    // "(two lanes westbound, center westbound left turn lane, two lanes eastbound)".
    let mut per_direction = None;
    for (j, w) in ws.iter().enumerate().skip(i) {
        if (w == "lanes" || w == "lane")
            && ws.get(j + 1).is_some_and(|x| x.ends_with("bound"))
            && let Some(n) = j.checked_sub(1).and_then(|k| number(&ws[k]))
        {
            per_direction = Some(n);
            break;
        }
    }
    let tail: Vec<String> = ws.iter().skip(i).cloned().collect();
    let centre_lane = contains_seq(&tail, &["center", "turn", "lane"])
        || tail.windows(2).any(|p| (p[0] == "center" || p[0] == "centre") && p[1].ends_with("bound"))
        || contains_seq(&tail, &["center", "left", "turn", "lane"]);
    Some((i, Lanes { total, per_direction, centre_lane, divided, one_way }))
}

/// A manoeuvre phrase and its word index.
fn movement(ws: &[String]) -> Option<(usize, Move)> {
    let pairs: [(&[&str], Move); 8] = [
        (&["turn", "left"], Move::TurnLeft),
        (&["turning", "left"], Move::TurnLeft),
        (&["left", "turn"], Move::TurnLeft),
        (&["turn", "right"], Move::TurnRight),
        (&["turning", "right"], Move::TurnRight),
        (&["right", "turn"], Move::TurnRight),
        (&["veered", "to", "the", "left"], Move::VeerLeft),
        (&["veered", "to", "the", "right"], Move::VeerRight),
    ];
    // The earliest mention wins ("began a left turn and crossed ..."); "left-turn lane" is one
    // hyphenated word, so a lane name never reads as a turn.
    let mut best: Option<(usize, Move)> = None;
    for (seq, m) in pairs {
        if let Some(p) = ws.windows(seq.len()).position(|w| w.iter().zip(seq).all(|(a, b)| a == b))
            && best.is_none_or(|b| p < b.0)
        {
            best = Some((p, m));
        }
    }
    best
}

/// Read the narrative.
pub fn read(text: &str) -> Narrative {
    let mut n = Narrative::default();
    // A sentence that names no vehicle continues the previous one's ("Vehicle one (V1 - case
    // vehicle). a 2000 Chevrolet Malibu ... was traveling north").
    let mut prev: Option<u32> = None;
    for s in sentences(text) {
        let ws = words(&s);
        let lower = s.to_ascii_lowercase();
        let find = |pred: &dyn Fn(&str) -> bool| ws.iter().position(|w| pred(w));
        if n.junction.is_none() {
            let j = if let Some(i) = find(&|w| w == "4-leg" || w == "four-leg") {
                Some((i, Junction::FourLeg))
            } else if let Some(i) = find(&|w| w == "t-intersection" || w == "3-leg" || w == "three-leg") {
                Some((i, Junction::T))
            } else if let Some(i) = find(&|w| w == "on-ramp").or_else(|| {
                ws.windows(2)
                    .position(|p| (p[0] == "entrance" && p[1] == "ramp") || (p[0] == "merge" && p[1] == "area"))
            }) {
                Some((i, Junction::Ramp))
            } else {
                find(&|w| w == "intersection").map(|i| (i, Junction::Unspecified))
            };
            n.junction = j.map(|(i, value)| Found { value, quote: excerpt(&ws, i.saturating_sub(4), i + 2) });
        }
        if n.departure.is_none() {
            for (side, word) in [(Side2::Right, "right"), (Side2::Left, "left")] {
                let at = ws
                    .windows(4)
                    .position(|p| p[0] == "off" && p[1] == "the" && p[2] == word && (p[3] == "side" || p[3] == "edge"));
                if let Some(i) = at {
                    n.departure = Some(Found { value: side, quote: excerpt(&ws, i.saturating_sub(2), i + 7) });
                }
            }
        }
        if n.object.is_none()
            && let Some(k) = find(&|w| w == "struck" || w == "impacted" || w == "hit")
        {
            let obj = if let Some(i) = find(&|w| w == "tree" || w == "trees") {
                Some((i, "tree"))
            } else if let Some(i) = find(&|w| w == "pole" || w == "post") {
                Some((i, "pole"))
            } else {
                find(&|w| w == "wall").map(|i| (i, "wall"))
            };
            n.object =
                obj.map(|(i, value)| Found { value, quote: excerpt(&ws, k.min(i).saturating_sub(3), i.max(k) + 4) });
        }
        let Some(v) = subject(&ws).or(if mentions(&ws).is_empty() { prev } else { None }) else { continue };
        prev = Some(v);
        if n.vehicles.len() < v as usize {
            n.vehicles.resize(v as usize, VehicleText::default());
        }
        let vt = &mut n.vehicles[v as usize - 1];
        if vt.travel.is_none()
            && let Some((i, d)) = travel(&ws)
        {
            vt.travel = Some(Found { value: d, quote: excerpt(&ws, i, i + 10) });
            vt.lane = lane_pos(&ws).map(|value| Found { value, quote: excerpt(&ws, i, i + 10) });
            vt.lanes = lanes(&ws).map(|(k, value)| Found { value, quote: excerpt(&ws, k.saturating_sub(1), k + 16) });
            vt.same_road = lower.contains("same roadway") || lower.contains("same road");
            if let Some(k) =
                ws.windows(2).position(|p| p[0] == "entrance" && p[1] == "ramp").or_else(|| find(&|w| w == "on-ramp"))
            {
                vt.ramp = Some(Found { value: (), quote: excerpt(&ws, k.saturating_sub(3), k + 3) });
            }
        }
        // A manoeuvre belongs to the vehicle named last before it ("As V1 was traversing the
        // intersection, the driver of V2 attempted to turn left" is V2's turn).
        if let Some((pos, m)) = movement(&ws)
            && let Some(&(_, who)) = mentions(&ws).iter().rev().find(|x| x.0 < pos)
        {
            if n.vehicles.len() < who as usize {
                n.vehicles.resize(who as usize, VehicleText::default());
            }
            let w = &mut n.vehicles[who as usize - 1];
            if w.movement.is_none() {
                w.movement = Some(Found { value: m, quote: excerpt(&ws, pos.saturating_sub(5), pos + 5) });
            }
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_directions_lanes_and_junctions() {
        let n = read(
            "Vehicle one (V1 - case vehicle), a 1999 Ford Windstar, minivan was traveling east in the left eastbound \
             lane of a five-lane, two-way bituminous urban road (two lanes eastbound, center turn lane, two lanes \
             westbound) and was approaching a T-intersection.  Vehicle two (V2), a 2005 Jeep, was traveling north in \
             the northbound lane of a two-lane, two-way concrete road.  As V1 was traversing through the \
             T-intersection, the driver of V2 attempted to turn left so as to travel westbound.",
        );
        let v1 = n.vehicle(1).expect("v1");
        assert_eq!(v1.travel.as_ref().map(|f| f.value), Some(Compass::East));
        assert_eq!(v1.lane.as_ref().map(|f| f.value), Some(LanePos::Left));
        let l = v1.lanes.as_ref().expect("lanes").value;
        assert_eq!((l.total, l.per_direction, l.centre_lane), (5, Some(2), true));
        let v2 = n.vehicle(2).expect("v2");
        assert_eq!(v2.travel.as_ref().map(|f| f.value), Some(Compass::North));
        assert_eq!(v2.lanes.as_ref().map(|f| f.value.total), Some(2));
        // "As V1 was traversing ..., the driver of V2 attempted to turn left": the sentence's
        // first vehicle is V1, but the turn is V2's.
        assert_eq!(v1.movement, None);
        assert_eq!(v2.movement.as_ref().map(|f| f.value), Some(Move::TurnLeft));
        assert_eq!(n.junction.as_ref().map(|f| f.value), Some(Junction::T));
    }

    #[test]
    fn a_lane_name_is_not_a_turn() {
        let n = read("Vehicle one (V1) was traveling east in the center left-turn lane of a five-lane road.");
        assert_eq!(n.vehicle(1).and_then(|v| v.movement.as_ref()), None);
        assert_eq!(n.vehicle(1).and_then(|v| v.lane.as_ref()).map(|f| f.value), Some(LanePos::Center));
    }
}
