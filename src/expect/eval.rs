//! Each `expect` line judged on the tracks. A line that does not hold becomes a diagnostic on
//! the line, saying what happened instead: when, and the value measured.

use super::geometry::{Contact, box_distance, footprint, past_landmark, touching};
use crate::check::scenario::{Expect, ExpectWhat, Landmark, Point};
use crate::compile::Front;
use crate::diag::Diagnostic;

/// Below this speed (m/s) an agent counts as stopped.
pub const STOPPED_MS: f64 = 0.1;
/// Slack on landmark and speed comparisons (m, m/s): track noise, not behaviour.
const SLACK: f64 = 0.05;

/// The verdict on one line: `None` when it holds.
pub fn judge(front: &Front, x: &Expect, contacts: &[Contact]) -> Option<Diagnostic> {
    let frames = window(front, x);
    let t = |f: usize| f as f64 / front.tracks.rate;
    let name = |i: usize| front.tracks.agents[i].name.as_str();
    let fail = |code: &'static str, what: String, help: &str| {
        Some(
            Diagnostic::error(code, format!("expectation failed: {}", x.text))
                .label(x.span, what)
                .help(help.to_string()),
        )
    };
    match x.what {
        ExpectWhat::Contact { a, b, side } => {
            let hit = frames.clone().find(|&f| touching(front, a, b, f));
            match hit {
                None => {
                    let (d, f) = closest(front, a, b, frames);
                    fail(
                        "E1010",
                        format!("no contact; closest {d:.2} m apart at {}", secs(t(f))),
                        "the boxes never overlap within the window",
                    )
                }
                Some(f) => {
                    let got = super::geometry::side_hit(front, a, b, f);
                    match side {
                        Some(want) if !on_side(got, want) => fail(
                            "E1010",
                            format!(
                                "contact at {} on {}'s {}, not its {}",
                                secs(t(f)),
                                name(b),
                                got.name(),
                                want.name()
                            ),
                            "a face (`rear`) also takes its corners (`rear_left`); a corner takes only itself",
                        ),
                        _ => None,
                    }
                }
            }
        }
        ExpectWhat::NoContact { pair } => {
            let c = contacts.iter().find(|c| {
                pair.is_none_or(|(a, b)| (c.a, c.b) == (a.min(b), a.max(b)))
                    && c.first <= *frames.end()
                    && c.last >= *frames.start()
            })?;
            let f = c.first.max(*frames.start());
            fail(
                "E1011",
                format!(
                    "{}'s {} touches {}'s {} at {}",
                    name(c.a),
                    c.side_a.name(),
                    name(c.b),
                    c.side_b.name(),
                    secs(t(f))
                ),
                "the boxes overlap: a crash that was not asked for",
            )
        }
        ExpectWhat::Gap { a, b, at_least, metres } => {
            let (d, f) = closest(front, a, b, frames);
            let bad = if at_least { d < metres - 1e-9 } else { d > metres + 1e-9 };
            if !bad {
                return None;
            }
            fail(
                "E1012",
                format!("closest {d:.2} m apart, at {}", secs(t(f))),
                "the least distance between the two boxes over the window",
            )
        }
        ExpectWhat::Speed { agent, at_least, ms } => {
            let v = &front.tracks.speeds[agent];
            let pick = |f: &usize| if at_least { -v[*f] } else { v[*f] };
            let f = frames.clone().max_by(|p, q| pick(p).total_cmp(&pick(q)).then(q.cmp(p)))?;
            let bad = if at_least { v[f] < ms - SLACK } else { v[f] > ms + SLACK };
            if !bad {
                return None;
            }
            fail(
                "E1015",
                format!("{} at {}", kmh(v[f]), secs(t(f))),
                "speeds are along the heading, in the track's frames",
            )
        }
        ExpectWhat::Stopped { agent, lane, landmark } => stopped(front, x, frames, agent, lane, landmark),
        ExpectWhat::Reach { agent, lane, landmark } => {
            let past: Vec<(usize, f64)> =
                frames.filter_map(|f| past_landmark(front, agent, f, lane, landmark).map(|p| (f, p))).collect();
            if past.iter().any(|(_, p)| *p >= -SLACK) {
                return None;
            }
            let (f, p) = past.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1))?;
            fail(
                "E1014",
                format!(
                    "its front stays {:.2} m short of the {} (nearest at {})",
                    -p,
                    landmark_name(landmark),
                    secs(t(f))
                ),
                "measured along the lane the agent starts in, from the front of its box",
            )
        }
    }
}

fn stopped(
    front: &Front,
    x: &Expect,
    frames: std::ops::RangeInclusive<usize>,
    agent: usize,
    lane: crate::check::scenario::LaneId,
    landmark: Landmark,
) -> Option<Diagnostic> {
    let t = |f: usize| f as f64 / front.tracks.rate;
    let v = &front.tracks.speeds[agent];
    let what = landmark_name(landmark);
    let fail = |code: &'static str, msg: String| {
        Some(
            Diagnostic::error(code, format!("expectation failed: {}", x.text))
                .label(x.span, msg)
                .help("measured along the lane the agent starts in, from the front of its box"),
        )
    };
    for f in frames.clone() {
        let p = past_landmark(front, agent, f, lane, landmark)?;
        if p > SLACK {
            return fail("E1013", format!("its front passes the {what} by {p:.2} m at {} ({})", secs(t(f)), kmh(v[f])));
        }
    }
    if frames.clone().any(|f| v[f] < STOPPED_MS) {
        return None;
    }
    let f = frames.min_by(|p, q| v[*p].total_cmp(&v[*q]))?;
    fail("E1013", format!("it never stops: slowest {} at {}", kmh(v[f]), secs(t(f))))
}

/// The frames of the expectation's window.
pub fn window(front: &Front, x: &Expect) -> std::ops::RangeInclusive<usize> {
    let last = front.tracks.frames.saturating_sub(1);
    let r = front.tracks.rate;
    let from = ((x.from * r - 1e-9).ceil().max(0.0) as usize).min(last);
    let to = ((x.to * r + 1e-9).floor().max(0.0) as usize).min(last);
    from..=to.max(from)
}

/// The least distance between two boxes over `frames`, and its first frame.
fn closest(front: &Front, a: usize, b: usize, frames: std::ops::RangeInclusive<usize>) -> (f64, usize) {
    let first = *frames.start();
    frames
        .filter(|&f| front.present(a, f) && front.present(b, f))
        .map(|f| (box_distance(&footprint(front, a, f), &footprint(front, b, f)), f))
        .fold((f64::INFINITY, first), |best, x| if x.0 < best.0 { x } else { best })
}

/// A face asked for also takes its two corners; a corner asked for takes only itself.
fn on_side(got: Point, want: Point) -> bool {
    use Point::*;
    got == want
        || matches!(
            (want, got),
            (Front, FrontLeft | FrontRight)
                | (Rear, RearLeft | RearRight)
                | (Left, FrontLeft | RearLeft)
                | (Right, FrontRight | RearRight)
        )
}

fn landmark_name(l: Landmark) -> &'static str {
    crate::check::scenario::LANDMARKS.iter().find(|x| x.1 == l).map_or("landmark", |x| x.0)
}

fn secs(t: f64) -> String {
    format!("t = {t:.1} s")
}

fn kmh(v: f64) -> String {
    format!("{:.1} km/h", v * 3.6)
}
