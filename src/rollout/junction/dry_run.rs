//! Dry runs: each turning vehicle driven alone through its first junction, as the controller
//! steers it, to find where its box reaches beyond its lane band (`Bend`).

use crate::geom::Obb;
use crate::road::Map;
use crate::road::route::Junction;
use crate::rollout::agent::Actor;
use crate::rollout::junction::bend::Bend;
use crate::rollout::kinematics::{look_ahead, pursuit, steer};
use crate::rollout::path::{Foot, Path};
use glam::DVec2;

/// The least reach beyond the band a junction sweep's slice is kept for (`Bend::slices`), m:
/// the vehicle band's margin in `Sim::drive`.
pub(crate) const SLICE_MIN: f64 = 0.25;

/// Fill every vehicle's `bend` through its first junction by a dry run: the vehicle alone,
/// steered as `Sim::drive` steers (pure pursuit of its path, curvature bounded by its turning
/// radius and yaw rate) at its path's curve speed, from 10 m before the junction until it has
/// rejoined its path; each corner beyond the band is booked at its own place along the route.
/// Runs sharing a connector, start, box, turning radius, limits and route length (the curve
/// speeds it steers by brake toward the route's end) are done once.
pub(crate) fn assign_bends(map: &Map, actors: &mut [Actor], dt: f64) {
    // The first vehicle with each key runs; later ones take its bend.
    let mut runs: Vec<DryRun> = vec![];
    let mut run_of: Vec<Option<usize>> = vec![None; actors.len()];
    let mut keys: std::collections::HashMap<[u64; 10], usize> = std::collections::HashMap::new();
    for (i, a) in actors.iter().enumerate().filter(|(_, a)| a.vehicle) {
        let Some(j) = a.junction else { continue };
        let entry = j.exit - map.connectors[j.conn].path.length();
        let start = (entry - 10.0).max(a.s0.min(entry));
        let key = [
            j.conn as u64,
            start.to_bits(),
            j.exit.to_bits(),
            a.hl.to_bits(),
            a.hw.to_bits(),
            a.r_min.to_bits(),
            a.lim.yaw_rate.to_bits(),
            a.lim.lat_acc.to_bits(),
            a.lim.brake.to_bits(),
            a.path.length().to_bits(),
        ];
        run_of[i] = Some(*keys.entry(key).or_insert_with(|| {
            runs.push(DryRun::new(map, i, a, j, start));
            runs.len() - 1
        }));
    }
    // Each run is a long chain of dependent steps: the runs take a step each in turn, so that
    // their chains overlap. A run's steps read only its own state, so each is the run it
    // would be alone.
    let mut steps = 0;
    while steps < 2000 && runs.iter().any(|r| r.live) {
        for r in runs.iter_mut().filter(|r| r.live) {
            r.step(&actors[r.actor], dt);
        }
        steps += 1;
    }
    let bends: Vec<std::sync::Arc<Bend>> = runs.into_iter().map(|r| std::sync::Arc::new(r.finish(actors))).collect();
    for (a, r) in actors.iter_mut().zip(run_of) {
        if let Some(r) = r {
            a.bend = Some(bends[r].clone());
        }
    }
}

/// One dry run of `assign_bends`: its vehicle (track index), junction, the bend it fills, and
/// its state between steps.
pub(crate) struct DryRun {
    pub(crate) actor: usize,
    pub(crate) j: Junction,
    pub(crate) b: Bend,
    pub(crate) pos: DVec2,
    pub(crate) yaw: f64,
    pub(crate) s: f64,
    /// The unit heading of `yaw`, taken once per step: the corners' and the next step's.
    pub(crate) fwd: DVec2,
    pub(crate) live: bool,
}

impl DryRun {
    pub(crate) fn new(map: &Map, actor: usize, a: &Actor, j: Junction, start: f64) -> DryRun {
        let (kl, kr) = junction_bend(map, &a.path, j);
        let from = start - 2.0 * a.hl - 5.0;
        let mut b = Bend {
            from,
            reach: vec![],
            widest: sweep(a, kl.max(kr)),
            slices: vec![],
            bounds: (DVec2::INFINITY, DVec2::NEG_INFINITY),
            spans: vec![],
            poses: vec![],
            run_bounds: (DVec2::INFINITY, DVec2::NEG_INFINITY),
        };
        let (pos, yaw) = a.path.point(start, 0.0);
        b.poses.push((start, pos, yaw));
        DryRun { actor, j, b, pos, yaw, s: start, fwd: DVec2::from_angle(yaw), live: true }
    }

    /// One step of the run (`live` turns false at its end).
    #[inline]
    pub(crate) fn step(&mut self, a: &Actor, dt: f64) {
        let (j, from) = (self.j, self.b.from);
        let v = a.path.cap(self.s).clamp(1.0, 15.0);
        let k = pursuit(self.pos, self.fwd, a.path.point_fast_on(self.s + look_ahead(a, v)));
        let dist = v * dt;
        (self.pos, self.yaw) = steer(a, self.pos, self.yaw, k, dist, dt, 1.0);
        let (pos, yaw, fwd) = (self.pos, self.yaw, self.fwd);
        let [Foot { s, d: off, .. }] = a.path.frenet_many([pos], [self.s + dist]);
        self.s = s;
        let dir = DVec2::from_angle(yaw);
        let corners = Obb { center: pos, yaw, length: 2.0 * a.hl, width: 2.0 * a.hw }.corners_along(dir);
        let found = a.path.frenet_many(corners, corners.map(|q| s + (q - pos).dot(fwd)));
        let b = &mut self.b;
        // Arc lengths are kept increasing for `Bend::pose`'s search.
        if b.poses.last().is_none_or(|q| s > q.0) {
            b.poses.push((s, pos, yaw));
        }
        for Foot { s: sq, d: dq, beyond, .. } in found {
            if beyond > 0.0 || dq.abs() <= a.hw {
                continue;
            }
            let m = (sq - from).max(0.0) as usize;
            if b.reach.len() <= m {
                b.reach.resize(m + 1, (0.0, 0.0));
            }
            let (r, l) = &mut b.reach[m];
            if dq > 0.0 {
                *l = l.max(dq - a.hw);
            } else {
                *r = r.max(-dq - a.hw);
            }
            b.widest = b.widest.max(dq.abs() - a.hw);
        }
        self.fwd = dir;
        if (s > j.exit + a.hl && off.abs() < 0.05) || s >= a.path.length() - 1.0 {
            self.live = false;
        }
    }

    /// The bend, with its slices and spans.
    pub(crate) fn finish(self, actors: &[Actor]) -> Bend {
        let (a, mut b) = (&actors[self.actor], self.b);
        // Reaches within the band's margin are the band's business.
        for (m, &(r, l)) in b.reach.iter().enumerate() {
            if r > SLICE_MIN || l > SLICE_MIN {
                let (p, h) = a.path.point(b.from + m as f64 + 0.5, 0.5 * (l - r));
                let slice = Obb { center: p, yaw: h, length: 1.0, width: 2.0 * a.hw + r + l };
                for q in slice.corners() {
                    b.bounds = (b.bounds.0.min(q), b.bounds.1.max(q));
                }
                b.slices.push((b.from + m as f64, slice));
            }
        }
        let half = a.hl.hypot(a.hw);
        for &(_, p, _) in &b.poses {
            b.run_bounds = (b.run_bounds.0.min(p - half), b.run_bounds.1.max(p + half));
        }
        b.index();
        b
    }
}

/// The first centre position on `b`'s route from `lo` up to `hi` at which its box, half a metre
/// wider all round, meets `a`'s junction sweep beyond its path's band (`Bend::slices`): a U-turn
/// driven wide loops out over the cross street's approach, short of where the two connectors
/// come near each other.
pub(crate) fn sweep_entry(a: &Actor, b: &Actor, lo: f64, hi: f64) -> Option<f64> {
    let bend = a.bend.as_ref()?;
    let mut s = lo;
    while s < hi {
        let (p, h) = b.path.point(s, 0.0);
        let mine = Obb { center: p, yaw: h, length: 2.0 * b.hl + 1.0, width: 2.0 * b.hw + 1.0 };
        if bend.meets(&mine, f64::NEG_INFINITY, f64::INFINITY).is_some() {
            return Some(s);
        }
        s += 0.5;
    }
    None
}

/// How far `a`'s box reaches beyond the band its path's centre sweeps, on the outside of a bend
/// of curvature `k` (not signed): the corners' swing, and a bend tighter than the vehicle can
/// steer is driven wider, on its own turning radius.
pub(crate) fn sweep(a: &Actor, k: f64) -> f64 {
    let wide = if k > 1e-9 { (a.r_min - 1.0 / k).max(0.0) } else { 0.0 };
    swing(a.hl, k) + wide
}

/// The tightest curvature of `path` through its junction `j`, sampled every half metre.
pub(crate) fn junction_curvature(map: &Map, path: &Path, j: Junction) -> f64 {
    let (left, right) = junction_bend(map, path, j);
    left.max(right)
}

/// `junction_curvature` each way: the tightest left bend and the tightest right bend (both
/// positive, 0 where there is none).
pub(crate) fn junction_bend(map: &Map, path: &Path, j: Junction) -> (f64, f64) {
    let entry = j.exit - map.connectors[j.conn].path.length();
    let n = ((j.exit - entry) / 0.5).ceil().max(1.0) as usize;
    (0..=n)
        .map(|i| path.curvature(entry + (j.exit - entry) * i as f64 / n as f64))
        .fold((0.0, 0.0), |(l, r), k| (f64::max(l, k), f64::max(r, -k)))
}

/// How far the corners of a box of half length `hl`, tangent to an arc of curvature `k`, reach
/// beyond the band its centre sweeps (at most `hl`).
pub(crate) fn swing(hl: f64, k: f64) -> f64 {
    (0.5 * hl * hl * k).min(hl)
}
