//! The snapshot of one scenario: what `rocc test` compares, in insta's file format (a `---`
//! header of `key: value` lines, then the body) so that `cargo insta` can review pending
//! `.snap.new` files inside a cargo workspace. The body holds the checked summary, each
//! expectation's verdict, every track at 1 Hz rounded to centimetres, the contacts, and digests
//! of the first ego's BEV at the first, middle and last frame.

use super::geometry::Contact;
use crate::check::summary::Summary;
use crate::compile::{Front, frame_boxes};
use crate::fsio::Fnv1a;
use crate::raster::{Bev, Rasterizer};
use std::fmt::Write;

/// The `expression` header line that marks a file as a `rocc test` snapshot.
pub const EXPRESSION: &str = "rocc test";

/// The snapshot body (without header); `verdicts` are `(line, holds)` in the file's order.
pub fn body(front: &Front, verdicts: &[(String, bool)], contacts: &[Contact]) -> String {
    let mut out = String::new();
    let s = Summary::of(&front.scenario);
    let _ = writeln!(
        out,
        "scenario {} on {} road, seed {}, {} agents ({} moving), egos [{}], {} frames at {} Hz",
        s.scenario,
        s.road,
        front.concrete.seed,
        s.agents,
        s.movers,
        s.egos.join(", "),
        s.frames,
        front.tracks.rate
    );
    out.push_str("\nexpect\n");
    if verdicts.is_empty() {
        out.push_str("  (none)\n");
    }
    for (line, ok) in verdicts {
        let _ = writeln!(out, "  {} {line}", if *ok { "ok  " } else { "FAIL" });
    }
    out.push_str("\ntracks: t s: x m, y m, yaw deg, speed m/s (world frame, every second)\n");
    let t = &front.tracks;
    let step = (t.rate.round() as usize).max(1);
    for (i, a) in t.agents.iter().enumerate() {
        let bg = if a.background { ", background" } else { "" };
        let _ = writeln!(out, "  {} ({}{bg}, {} x {} m)", a.name, a.kind, cm(a.size[0]), cm(a.size[1]));
        for f in (0..t.frames).step_by(step).filter(|&f| front.present(i, f)) {
            let (p, v) = (t.poses[i][f], t.speeds[i][f]);
            let yaw = format!("{:.1}", p.yaw.to_degrees());
            let _ = writeln!(out, "    {:>3}: {}, {}, {}, {}", f / step, cm(p.x), cm(p.y), zero(yaw), cm(v));
        }
    }
    out.push_str("\ncontacts\n");
    if contacts.is_empty() {
        out.push_str("  (none)\n");
    }
    for c in contacts {
        let _ = writeln!(
            out,
            "  frames {}..{}: {} ({}) with {} ({})",
            c.first,
            c.last,
            t.agents[c.a].name,
            c.side_a.name(),
            t.agents[c.b].name,
            c.side_b.name()
        );
    }
    out.push_str("\nbev digests (first ego)\n");
    if let Some(&ego) = front.concrete.egos.first() {
        for (f, d) in bev_digests(front, ego) {
            let _ = writeln!(out, "  frame {f}: {d:016x}");
        }
    }
    out
}

/// FNV-1a of the BEV bytes (masks, auxiliary channels, structure) at the first, middle and last
/// frame, hashed as the digest pin in `tests/examples.rs` hashes them.
fn bev_digests(front: &Front, ego: usize) -> Vec<(usize, u64)> {
    let n = front.tracks.frames;
    let mut frames = vec![0, n / 2, n.saturating_sub(1)];
    frames.dedup();
    let (mut raster, mut bev) = (Rasterizer::new(), Bev::zeros());
    frames
        .into_iter()
        .map(|f| {
            let boxes = frame_boxes(front, ego, f);
            raster.rasterize_into(&front.map, front.tracks.poses[ego][f], &boxes, &mut bev);
            let mut h = Fnv1a::new();
            h.write(&bev.masks.iter().map(|&x| x as u8).collect::<Vec<u8>>());
            for x in bev.aux.iter() {
                h.write(&x.to_le_bytes());
            }
            h.write(&bev.structure.iter().map(|&x| x as u8).collect::<Vec<u8>>());
            (f, h.finish())
        })
        .collect()
}

/// Metres (or m/s) to two decimals, without a negative zero.
fn cm(x: f64) -> String {
    zero(format!("{x:.2}"))
}

fn zero(s: String) -> String {
    if s.trim_start_matches('-').chars().all(|c| c == '0' || c == '.') {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// The whole file: insta's header, then the body.
pub fn file(source: &str, body: &str) -> String {
    format!("---\nsource: {source}\nexpression: {EXPRESSION}\n---\n{body}")
}

/// Why a `.snap` file is not one of ours.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Bad {
    /// No `---` header with an end.
    NoHeader,
    /// A header whose `expression` is not `rocc test` (an insta snapshot of something else).
    Foreign(String),
}

/// The body of a snapshot file, checked to be a `rocc test` snapshot. Header keys other than
/// `expression` (those `cargo insta` adds) are ignored.
pub fn parse(text: &str) -> Result<&str, Bad> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let rest = text.strip_prefix("---\n").ok_or(Bad::NoHeader)?;
    let end = rest.find("\n---\n").ok_or(Bad::NoHeader)?;
    let header = &rest[..end];
    let expression = header.lines().find_map(|l| l.strip_prefix("expression:")).map(str::trim).unwrap_or("");
    if expression != EXPRESSION {
        return Err(Bad::Foreign(expression.to_string()));
    }
    Ok(&rest[end + 5..])
}
