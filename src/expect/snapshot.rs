//! The snapshot of one scenario: what `rocc test` compares, in insta's file format (a `---`
//! header of `key: value` lines, then the body) so that `cargo insta` can review pending
//! `.snap.new` files inside a cargo workspace. The body holds the checked summary, each
//! expectation's verdict, every track at 1 Hz rounded to centimetres, the contacts, and digests
//! of the first ego's BEV and occupancy at the first, middle and last frame.

use super::geometry::Contact;
use crate::backend::{Background, OccInput, Occupancy, OccupancyBackend, Procedural};
use crate::check::summary::Summary;
use crate::compile::{Front, clip_seed, frame_boxes};
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
    out.push_str("\ndigests (first ego; BEV, procedural occupancy)\n");
    if let Some(&ego) = front.concrete.egos.first() {
        for (f, bev, occ) in digests(front, ego) {
            let _ = writeln!(out, "  frame {f}: bev {bev:016x} occ {occ:016x}");
        }
    }
    out
}

/// Digests of the BEV (masks, auxiliary channels, structure) and of the procedural occupancy
/// labels at the first, middle and last frame (`Words`).
fn digests(front: &Front, ego: usize) -> Vec<(usize, u64, u64)> {
    let n = front.tracks.frames;
    let mut frames = vec![0, n / 2, n.saturating_sub(1)];
    frames.dedup();
    let background = Background::generate(&front.map, front.concrete.seed);
    let seed = clip_seed(front, ego);
    let (mut raster, mut bev, mut occ) = (Rasterizer::new(), Bev::zeros(), Occupancy::empty());
    frames
        .into_iter()
        .map(|f| {
            let boxes = frame_boxes(front, ego, f);
            let pose = front.tracks.poses[ego][f];
            raster.rasterize_into(&front.map, pose, &boxes, &mut bev);
            let mut h = Words::new();
            h.i8s(bev.masks.as_slice().unwrap_or(&[]));
            h.i32s(bev.aux.as_slice().unwrap_or(&[]));
            h.i8s(bev.structure.as_slice().unwrap_or(&[]));
            let input = OccInput { boxes: &boxes, bev: &bev, background: &background, ego: pose, seed, frame: f };
            Procedural::default().occupancy_into(&input, &mut occ);
            let mut o = Words::new();
            o.u8s(occ.labels.as_slice().unwrap_or(&[]));
            (f, h.0, o.0)
        })
        .collect()
}

/// FNV-1a's offset and prime applied to little-endian 64-bit words rather than bytes: the
/// snapshot hashes about 38 MB of rasters per scene, and byte-wise FNV-1a (`fsio::Fnv1a`) over
/// them was most of `rocc test`'s time; word-wise it is an eighth of the multiplications. A
/// digest to see a change, not a cryptographic one.
struct Words(u64);

impl Words {
    fn new() -> Self {
        Words(0xcbf2_9ce4_8422_2325)
    }

    fn mix(&mut self, w: u64) {
        self.0 = (self.0 ^ w).wrapping_mul(0x0100_0000_01b3);
    }

    fn u8s(&mut self, v: &[u8]) {
        let mut it = v.chunks_exact(8);
        for c in &mut it {
            self.mix(u64::from_le_bytes(std::array::from_fn(|k| c[k])));
        }
        let rest = it.remainder();
        self.mix(rest.iter().rev().fold(rest.len() as u64, |w, &b| (w << 8) | u64::from(b)));
    }

    fn i8s(&mut self, v: &[i8]) {
        let mut it = v.chunks_exact(8);
        for c in &mut it {
            self.mix(u64::from_le_bytes(std::array::from_fn(|k| c[k] as u8)));
        }
        let rest = it.remainder();
        self.mix(rest.iter().rev().fold(rest.len() as u64, |w, &b| (w << 8) | u64::from(b as u8)));
    }

    fn i32s(&mut self, v: &[i32]) {
        let mut it = v.chunks_exact(2);
        for c in &mut it {
            self.mix(u64::from(c[0] as u32) | (u64::from(c[1] as u32) << 32));
        }
        for &x in it.remainder() {
            self.mix(u64::from(x as u32) | (1 << 40));
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn word_digests_see_every_byte_and_the_length() {
        let digest = |v: &[i8]| {
            let mut h = Words::new();
            h.i8s(v);
            h.0
        };
        let base = [0i8; 19];
        let mut seen = vec![digest(&base), digest(&base[..18]), digest(&base[..16])];
        for k in 0..base.len() {
            let mut v = base;
            v[k] = 1;
            seen.push(digest(&v));
        }
        let n = seen.len();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), n, "two inputs share a digest");
        let (mut a, mut b) = (Words::new(), Words::new());
        a.i32s(&[1, 2, 3]);
        b.i32s(&[1, 2, 4]);
        assert_ne!(a.0, b.0);
    }
}
