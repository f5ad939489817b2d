//! `point_of_impact`, the SAFE extraction's free text naming the parts that met ("front of V2
//! struck right side of V1"), read by fixed rules into striker and struck parts, and the small
//! predicates on parts the mapping uses.

use crate::check::scenario::Point;

/// A part of a vehicle named in `point_of_impact`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    Point(Point),
    /// "side" without a hand, "trailer", "trailer component": a side contact of unknown hand.
    Side,
}

/// One "PART of V<n>" phrase.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Named {
    pub vehicle: u32,
    pub part: Option<Part>,
}

/// What `point_of_impact` says: who strikes with what, who is struck where.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PointOfImpact {
    pub striker: Option<Named>,
    pub struck: Option<Named>,
    /// "front of V1 and front of V2": no direction.
    pub mutual: bool,
}

pub(super) fn part_of(words: &[&str]) -> Option<Part> {
    let w: Vec<String> = words.iter().map(|x| x.replace('-', " ")).collect();
    let joined = w.join(" ");
    let has = |x: &str| joined.split_whitespace().any(|t| t == x);
    let front = has("front");
    let rear = has("rear") || has("back");
    let left = has("left");
    let right = has("right");
    Some(Part::Point(match (front, rear, left, right) {
        (true, false, true, false) => Point::FrontLeft,
        (true, false, false, true) => Point::FrontRight,
        (false, true, true, false) => Point::RearLeft,
        (false, true, false, true) => Point::RearRight,
        (true, false, false, false) => Point::Front,
        (false, true, false, false) => Point::Rear,
        (false, false, true, false) => Point::Left,
        (false, false, false, true) => Point::Right,
        (false, false, false, false) if has("side") || has("trailer") || has("door") || has("doors") => {
            return Some(Part::Side);
        }
        _ => return None,
    }))
}

pub(super) fn vehicle_no(w: &str, next: Option<&str>) -> Option<u32> {
    let w = w.trim_end_matches(['\'', 's']);
    let digits = w.strip_prefix("vehicle_").or_else(|| w.strip_prefix('v')).filter(|d| !d.is_empty());
    if let Some(n) = digits.and_then(|d| d.parse().ok()) {
        return Some(n);
    }
    if w == "vehicle" {
        return next.and_then(|n| n.parse().ok());
    }
    None
}

/// Read `point_of_impact` by rules: `PART of V<n>` phrases joined by an active verb (`struck`,
/// `striking`, `hit`, `impacted`), a passive one (`struck by`, `hit by`) or `and`.
pub fn parse_point_of_impact(text: &str) -> PointOfImpact {
    let lower = text.to_ascii_lowercase();
    let words: Vec<&str> = lower
        .split(|c: char| c.is_whitespace() || matches!(c, ',' | ';' | '.' | '(' | ')' | ':'))
        .filter(|w| !w.is_empty())
        .collect();
    // Each vehicle mention with the part words before its "of".
    let mut named: Vec<(usize, Named)> = Vec::new();
    let mut i = 0;
    while i < words.len() {
        if let Some(n) = vehicle_no(words[i], words.get(i + 1).copied()) {
            let part = if i >= 1 && words[i - 1] == "of" {
                let start = named.last().map(|x| x.0 + 1).unwrap_or(0);
                // Part words: up to three before "of", back to the previous mention or verb.
                let lo = (i - 1).saturating_sub(3).max(start);
                let ws: Vec<&str> = words[lo..i - 1]
                    .iter()
                    .copied()
                    .filter(|w| {
                        !matches!(*w, "the" | "a" | "an" | "struck" | "striking" | "by" | "and" | "hit" | "impacted")
                    })
                    .collect();
                part_of(&ws)
            } else {
                None
            };
            named.push((i, Named { vehicle: n, part }));
        }
        i += 1;
    }
    let mut out = PointOfImpact { striker: None, struck: None, mutual: false };
    let (Some(&(ia, a)), Some(&(ib, b))) = (named.first(), named.get(1)) else {
        if let Some(&(_, a)) = named.first() {
            out.struck = Some(a);
        }
        return out;
    };
    let between = &words[ia + 1..ib];
    let passive =
        between.windows(2).any(|w| matches!(w[0], "struck" | "hit" | "impacted" | "contacted") && w[1] == "by");
    let active = between
        .iter()
        .any(|w| matches!(*w, "struck" | "striking" | "strikes" | "hit" | "hits" | "impacted" | "contacted"));
    if passive {
        out.struck = Some(a);
        out.striker = Some(b);
    } else if active {
        out.striker = Some(a);
        out.struck = Some(b);
    } else if between.contains(&"and") {
        out.striker = Some(a);
        out.struck = Some(b);
        out.mutual = true;
    }
    out
}

pub(super) fn is_front(p: Point) -> bool {
    matches!(p, Point::Front | Point::FrontLeft | Point::FrontRight)
}

pub(super) fn is_rear(p: Point) -> bool {
    matches!(p, Point::Rear | Point::RearLeft | Point::RearRight)
}

/// `Some(true)` for a left side, `Some(false)` for a right side; `None` otherwise.
pub(super) fn hand(p: Point) -> Option<bool> {
    match p {
        Point::Left => Some(true),
        Point::Right => Some(false),
        _ => None,
    }
}

pub(super) fn part_point(p: Option<Part>) -> Point {
    match p {
        Some(Part::Point(x)) => x,
        _ => Point::Front,
    }
}

/// A left/right side paired with a side of unknown hand: `Some(true)` when the first is the
/// handed one, `Some(false)` when the second is.
pub(super) fn side_pair(a: Option<Part>, b: Option<Part>) -> Option<bool> {
    match (a, b) {
        (Some(Part::Point(p)), Some(Part::Side)) if hand(p).is_some() => Some(true),
        (Some(Part::Side), Some(Part::Point(p))) if hand(p).is_some() => Some(false),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn named(vehicle: u32, p: Point) -> Option<Named> {
        Some(Named { vehicle, part: Some(Part::Point(p)) })
    }

    #[test]
    fn point_of_impact_rules() {
        let p = parse_point_of_impact("front of V2 striking right side of V1");
        assert_eq!((p.striker, p.struck, p.mutual), (named(2, Point::Front), named(1, Point::Right), false));
        let p = parse_point_of_impact("right side of V1 struck by front of V2");
        assert_eq!((p.striker, p.struck), (named(2, Point::Front), named(1, Point::Right)));
        let p = parse_point_of_impact("front of V1 and front of V2");
        assert_eq!((p.striker, p.struck, p.mutual), (named(1, Point::Front), named(2, Point::Front), true));
        let p = parse_point_of_impact("left side of V1 struck by trailer component of V2");
        assert_eq!(p.struck, named(1, Point::Left));
        assert_eq!(p.striker, Some(Named { vehicle: 2, part: Some(Part::Side) }));
        let p = parse_point_of_impact("left-front of Vehicle 1 struck the rear of Vehicle 2");
        assert_eq!((p.striker, p.struck), (named(1, Point::FrontLeft), named(2, Point::Rear)));
        let p = parse_point_of_impact("somewhere in the middle");
        assert_eq!((p.striker, p.struck), (None, None));
    }
}
