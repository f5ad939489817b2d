//! Recorded boxes no body could have followed (a detector's glitch: a box jumping metres in one
//! frame) are dropped before a track is written, each with an E0135 warning, so that the rest of
//! the recording still imports; where a track jumps for good, the rest of it becomes an agent of
//! its own. What is kept passes the checker's track limits (`check::track`, E0131-E0134).

use super::Segment;
use crate::check::scenario::{Keyframe, Motion};
use crate::check::track::{Violation, first_violation, limits};
use crate::diag::Diagnostic;
use crate::place::Pose;
use crate::source::Span;

/// Every segment with its infeasible keyframes dropped or split off, in order.
pub(super) fn drop_infeasible(
    segs: Vec<Segment>,
    rate: f64,
    warnings: &mut Vec<Diagnostic>,
    whole: Span,
) -> Vec<Segment> {
    let mut names: Vec<String> = segs.iter().map(|s| s.name.clone()).collect();
    let mut out = Vec::with_capacity(segs.len());
    for seg in segs {
        let mut todo = vec![seg];
        while let Some(mut s) = todo.pop() {
            if let Some(rest) = clean(&mut s, rate, warnings, whole, &mut names) {
                todo.push(rest);
            }
            out.push(s);
        }
    }
    out
}

/// Drop `s`'s outlying keyframes till it is feasible; where dropping one does not mend the step
/// (the box jumped and stays), cut it there and return the rest under a new name.
fn clean(
    s: &mut Segment,
    rate: f64,
    warnings: &mut Vec<Diagnostic>,
    whole: Span,
    names: &mut Vec<String>,
) -> Option<Segment> {
    // Carried things (a static kind on a pickup) move like vehicles: `limits` says so.
    let motion = if s.kind == "animal" { Motion::Holonomic } else { s.class.default_motion() };
    let lim = limits(motion, s.class);
    loop {
        let v = first_violation(&keyframes(&s.keys, rate), &lim, s.size[0])?;
        let k = v.key;
        let mut without = s.keys.clone();
        without.remove(k);
        let mended = first_violation(&keyframes(&without, rate), &lim, s.size[0]).is_none_or(|w| w.key > k);
        let frame = s.keys[k].0;
        if mended {
            warnings.push(warn(s, frame, &v, "dropped; the track is interpolated across it", whole));
            s.keys = without;
            continue;
        }
        let mut n = 2;
        let name = loop {
            let candidate = format!("{}_from_{frame}{}", s.name, if n == 2 { String::new() } else { format!("_{n}") });
            if !names.contains(&candidate) {
                break candidate;
            }
            n += 1;
        };
        names.push(name.clone());
        warnings.push(warn(
            s,
            frame,
            &v,
            &format!("the track jumps there for good: its rest is agent `{name}`"),
            whole,
        ));
        let keys = s.keys.split_off(k);
        return Some(Segment { name, keys, ..s.clone() });
    }
}

/// The keyframes the checker would read for recorded (clip frame, pose) keys at `rate` Hz.
fn keyframes(keys: &[(usize, Pose)], rate: f64) -> Vec<Keyframe> {
    keys.iter()
        .map(|(f, p)| Keyframe { t: *f as f64 / rate, x: p.x, y: p.y, yaw: p.yaw, at: None, span: Span::default() })
        .collect()
}

fn warn(s: &Segment, frame: usize, v: &Violation, what: &str, whole: Span) -> Diagnostic {
    let check = match v.code {
        "E0131" => "moves too fast",
        "E0132" => "accelerates too hard",
        "E0133" => "turns too fast",
        _ => "slides sideways",
    };
    Diagnostic::warning(
        "E0135",
        format!(
            "track `{}` {check} at clip frame {frame} ({} at most {:.2}, measured {:.2}): {what}",
            s.track, v.code, v.limit, v.measured
        ),
    )
    .label(whole, "in this file")
    .help("a recorded box no body could have followed (a detector's glitch); check the recording there")
}
