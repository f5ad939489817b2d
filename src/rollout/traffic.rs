//! Background traffic: seeded vehicles on the free length of every lane. In: the map, the boxes
//! already placed, `traffic { density; randomness }` and the seed. Out: spawn slots (lane, arc
//! length, size, speeds); the frame loop drives them like any agent with an ordinary goal.

use crate::check::scenario::Traffic;
use crate::geom::Obb;
use crate::road::Map;
use crate::sample::Rng;

/// One background vehicle per this much lane length at density 1, m.
const SPACING: f64 = 25.0;

/// Background kinds with mid-range stdlib sizes (length, width, height): `sedan` alone at
/// randomness 0; the others enter as randomness grows.
const KINDS: [(&str, [f64; 3]); 5] = [
    ("sedan", [4.65, 1.8, 1.45]),
    ("hatchback", [4.1, 1.75, 1.5]),
    ("suv", [4.7, 1.9, 1.72]),
    ("van", [5.2, 2.0, 2.1]),
    ("pickup_truck", [5.6, 2.0, 1.87]),
];

pub(super) struct Spawn {
    pub name: String,
    pub kind: &'static str,
    pub size: [f64; 3],
    pub lane: usize,
    pub s: f64,
    pub speed: f64,
    pub target: f64,
}

/// Deceleration a starting gap is sized for (m/s^2): comfortable, well inside every limit.
const BRAKE: f64 = 3.0;

pub(super) fn spawn(map: &Map, placed: &[(Obb, f64)], t: Traffic, seed: u64) -> Vec<Spawn> {
    let mut rng = Rng::stream(seed, "traffic");
    let density = t.density.clamp(0.0, 1.0);
    let rnd = t.randomness.clamp(0.0, 1.0);
    let mut out: Vec<Spawn> = vec![];
    let mut boxes: Vec<Obb> = placed.iter().map(|(b, _)| *b).collect();
    for (li, lane) in map.lanes.iter().enumerate() {
        let len = lane.centre.length();
        // Spawn on the approach, short of the stop line: cars start in lanes, not junctions.
        let (lo, hi) = (6.0, lane.stop_line_s.map(|s| s - 3.0).unwrap_or(len - 6.0));
        if hi <= lo {
            continue;
        }
        let slots = ((hi - lo) / SPACING).floor() as usize;
        let first = out.len();
        for k in 0..slots {
            // Every draw happens for every slot, so a change in one slot's outcome never shifts
            // the random numbers of the next.
            let keep = rng.unit();
            let jitter = rng.range(-1.0, 1.0);
            let kind_draw = rng.unit();
            let speed_draw = rng.unit();
            if keep >= density {
                continue;
            }
            let s = (lo + (k as f64 + 0.5) * SPACING + jitter * rnd * 8.0).clamp(lo, hi);
            let ki = if kind_draw < rnd { ((kind_draw / rnd.max(1e-9)) * KINDS.len() as f64) as usize } else { 0 };
            let (kind, size) = KINDS[ki.min(KINDS.len() - 1)];
            let (p, yaw) = lane.centre.pose_at(s);
            // Keep clear of everything by a couple of metres so nobody starts bumper to bumper.
            let probe = Obb { center: p, yaw, length: size[0] + 4.0, width: size[1] + 0.4 };
            if boxes.iter().any(|b| b.overlaps(&probe)) {
                continue;
            }
            // Nor right in front of a placed agent: it must be able to stop behind the new car.
            let cut_in = placed.iter().any(|(b, v)| {
                let (sb, db) = lane.centre.project(b.center);
                let gap = s - size[0] / 2.0 - (sb + b.length / 2.0);
                sb < s && db.abs() < (lane.width + b.width) / 2.0 && gap < v * v / (2.0 * BRAKE) + 4.0
            });
            if cut_in {
                continue;
            }
            boxes.push(Obb { center: p, yaw, length: size[0], width: size[1] });
            let target = lane.speed_limit * (1.0 - 0.3 * rnd * speed_draw);
            out.push(Spawn { name: String::new(), kind, size, lane: li, s, speed: target, target });
        }
        // Start no faster than lets each car stop behind whatever is ahead of it in its lane.
        for sp in out[first..].iter_mut() {
            let front = sp.s + sp.size[0] / 2.0;
            let mut gap = f64::INFINITY;
            for b in &boxes {
                let (s, d) = lane.centre.project(b.center);
                if s > sp.s + 0.1 && d.abs() < lane.width / 2.0 + b.width / 2.0 {
                    gap = gap.min(s - b.length / 2.0 - front);
                }
            }
            let v_safe = (2.0 * BRAKE * (gap - 4.0).max(0.0)).sqrt();
            sp.speed = sp.speed.min(v_safe);
        }
    }
    for (i, s) in out.iter_mut().enumerate() {
        s.name = format!("traffic_{i}");
    }
    out
}
