//! Each `expect` line judged on the tracks. A line that does not hold becomes a diagnostic on
//! the line, saying what happened instead: when, and the value measured.

use super::geometry::{Contact, box_distance, footprint, past_landmark, side_hit, touching};
use crate::check::scenario::{Expect, ExpectWhat, LANDMARKS, Landmark, LaneId, Light, Point};
use crate::compile::Front;
use crate::diag::Diagnostic;
use crate::road::signals;
use std::ops::RangeInclusive;

/// Below this speed (m/s) an agent counts as stopped.
pub const STOPPED_MS: f64 = 0.1;
/// Slack on landmark and speed comparisons (m, m/s): track noise, not behaviour.
const SLACK: f64 = 0.05;

/// What a failed line says: its code, what happened (on the line) and a hint.
type Miss = (&'static str, String, &'static str);

/// The verdict on one line: `None` when it holds.
pub fn judge(front: &Front, x: &Expect, contacts: &[Contact]) -> Option<Diagnostic> {
    let j = Judge { front, frames: window(front, x) };
    let miss = match x.what {
        ExpectWhat::Contact { a, b, side } => j.contact(a, b, side),
        ExpectWhat::NoContact { pair } => j.no_contact(pair, contacts),
        ExpectWhat::Gap { a, b, at_least, metres } => j.gap(a, b, at_least, metres),
        ExpectWhat::Speed { agent, at_least, ms } => j.speed(agent, at_least, ms),
        ExpectWhat::Stopped { agent, lane, landmark } | ExpectWhat::Reach { agent, lane, landmark }
            if past_landmark(front, agent, 0, lane, landmark).is_none() =>
        {
            let what = format!("the map has no {} on this agent's lane", landmark_name(landmark));
            Some(("E1002", what, "`center` is on every lane; stop lines are on in-lanes of junction roads"))
        }
        ExpectWhat::Stopped { agent, lane, landmark } => j.stopped(agent, lane, landmark),
        ExpectWhat::Reach { agent, lane, landmark } => j.reach(agent, lane, landmark),
        ExpectWhat::Enters { agent, lane, light } => j.enters(agent, lane, light),
    }?;
    let (code, what, help) = miss;
    Some(Diagnostic::error(code, format!("expectation failed: {}", x.text)).label(x.span, what).help(help))
}

/// The frames of the expectation's window.
pub fn window(front: &Front, x: &Expect) -> RangeInclusive<usize> {
    let last = front.tracks.frames.saturating_sub(1);
    let r = front.tracks.rate;
    let from = ((x.from * r - 1e-9).ceil().max(0.0) as usize).min(last);
    let to = ((x.to * r + 1e-9).floor().max(0.0) as usize).min(last);
    from..=to.max(from)
}

struct Judge<'a> {
    front: &'a Front,
    frames: RangeInclusive<usize>,
}

impl Judge<'_> {
    fn t(&self, f: usize) -> String {
        format!("t = {:.1} s", f as f64 / self.front.tracks.rate)
    }

    fn name(&self, i: usize) -> &str {
        &self.front.tracks.agents[i].name
    }

    fn contact(&self, a: usize, b: usize, side: Option<Point>) -> Option<Miss> {
        let Some(f) = self.frames.clone().find(|&f| touching(self.front, a, b, f)) else {
            let (d, f) = self.closest(a, b);
            let what = format!("no contact; closest {d:.2} m apart at {}", self.t(f));
            return Some(("E1010", what, "the boxes never overlap within the window"));
        };
        let got = side_hit(self.front, a, b, f);
        let want = side.filter(|w| !on_side(got, *w))?;
        let what = format!("contact at {} on {}'s {}, not its {}", self.t(f), self.name(b), got.name(), want.name());
        Some(("E1010", what, "a face (`rear`) also takes its corners (`rear_left`); a corner takes only itself"))
    }

    fn no_contact(&self, pair: Option<(usize, usize)>, contacts: &[Contact]) -> Option<Miss> {
        let (from, to) = (*self.frames.start(), *self.frames.end());
        let c = contacts.iter().find(|c| {
            pair.is_none_or(|(a, b)| (c.a, c.b) == (a.min(b), a.max(b))) && c.first <= to && c.last >= from
        })?;
        let what = format!(
            "{}'s {} touches {}'s {} at {}",
            self.name(c.a),
            c.side_a.name(),
            self.name(c.b),
            c.side_b.name(),
            self.t(c.first.max(from))
        );
        Some(("E1011", what, "the boxes overlap: a crash that was not asked for"))
    }

    fn gap(&self, a: usize, b: usize, at_least: bool, metres: f64) -> Option<Miss> {
        let (d, f) = self.closest(a, b);
        let holds = if at_least { d >= metres - 1e-9 } else { d <= metres + 1e-9 };
        let what = format!("closest {d:.2} m apart, at {}", self.t(f));
        (!holds).then_some(("E1012", what, "the least distance between the two boxes over the window"))
    }

    fn speed(&self, agent: usize, at_least: bool, ms: f64) -> Option<Miss> {
        let v = &self.front.tracks.speeds[agent];
        // The frame furthest toward the bound's wrong side; the first of equals.
        let worse = |f: usize| if at_least { -v[f] } else { v[f] };
        let f = self.frames.clone().reduce(|best, f| if worse(f) > worse(best) { f } else { best })?;
        let holds = if at_least { v[f] >= ms - SLACK } else { v[f] <= ms + SLACK };
        let what = format!("{} at {}", kmh(v[f]), self.t(f));
        (!holds).then_some(("E1015", what, "speeds are along the heading, in the track's frames"))
    }

    fn stopped(&self, agent: usize, lane: LaneId, landmark: Landmark) -> Option<Miss> {
        const HELP: &str = "measured along the lane the agent starts in, from the front of its box";
        let v = &self.front.tracks.speeds[agent];
        for f in self.frames.clone() {
            let p = past_landmark(self.front, agent, f, lane, landmark).unwrap_or(0.0);
            if p > SLACK {
                let what = format!(
                    "its front passes the {} by {p:.2} m at {} ({})",
                    landmark_name(landmark),
                    self.t(f),
                    kmh(v[f])
                );
                return Some(("E1013", what, HELP));
            }
        }
        if self.frames.clone().any(|f| v[f] < STOPPED_MS) {
            return None;
        }
        let f = self.frames.clone().reduce(|best, f| if v[f] < v[best] { f } else { best })?;
        Some(("E1013", format!("it never stops: slowest {} at {}", kmh(v[f]), self.t(f)), HELP))
    }

    fn reach(&self, agent: usize, lane: LaneId, landmark: Landmark) -> Option<Miss> {
        let past = |f: usize| past_landmark(self.front, agent, f, lane, landmark).unwrap_or(f64::NEG_INFINITY);
        let f = self.frames.clone().reduce(|best, f| if past(f) > past(best) { f } else { best })?;
        if past(f) >= -SLACK {
            return None;
        }
        let what = format!(
            "its front stays {:.2} m short of the {} (nearest at {})",
            -past(f),
            landmark_name(landmark),
            self.t(f)
        );
        Some(("E1014", what, "measured along the lane the agent starts in, from the front of its box"))
    }

    /// The first frame of the clip at which the front is past its stop line (measured as for
    /// `reach`, with `stopped`'s slack, so a car held at its line does not enter) and the light
    /// its lane's head shows then; a miss when that frame lies outside the window or the light
    /// differs.
    fn enters(&self, agent: usize, lane: LaneId, light: Light) -> Option<Miss> {
        const HELP: &str = "the light of the agent's own approach as its front reaches its stop line";
        let front = self.front;
        let Some((plan, head)) =
            front.map.signals.as_ref().and_then(|p| Some((p, p.heads.iter().find(|h| h.id == lane)?)))
        else {
            return Some(("E1002", "the map has no signal on this agent's lane".to_string(), HELP));
        };
        let past = |f: usize| past_landmark(front, agent, f, lane, Landmark::StopLine).unwrap_or(f64::NEG_INFINITY);
        let Some(f) = (0..front.tracks.frames).find(|&f| past(f) > SLACK) else {
            let f = self.frames.clone().reduce(|best, f| if past(f) > past(best) { f } else { best })?;
            let what = format!(
                "it never enters: its front stays {:.2} m short of the stop line (nearest at {})",
                -past(f),
                self.t(f)
            );
            return Some(("E1004", what, HELP));
        };
        let seen = signals::arm_light(&plan.cycle, head.id.arm, f as f64 / front.tracks.rate);
        let outside = if self.frames.contains(&f) { "" } else { ", outside the window" };
        let what = format!("it enters at {} on {}{outside}", self.t(f), seen.name());
        (seen != light || !outside.is_empty()).then_some(("E1004", what, HELP))
    }

    /// The least distance between two boxes over the window, and its first frame.
    fn closest(&self, a: usize, b: usize) -> (f64, usize) {
        let f = self.front;
        self.frames
            .clone()
            .filter(|&i| f.present(a, i) && f.present(b, i))
            .map(|i| (box_distance(&footprint(f, a, i), &footprint(f, b, i)), i))
            .fold((f64::INFINITY, *self.frames.start()), |best, x| if x.0 < best.0 { x } else { best })
    }
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
    LANDMARKS.iter().find(|x| x.1 == l).map_or("landmark", |x| x.0)
}

fn kmh(v: f64) -> String {
    format!("{:.1} km/h", v * 3.6)
}
