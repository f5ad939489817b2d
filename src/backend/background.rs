//! Procedural static background. In: a scenario's world-frame `road::Map` and a seed. Out: a
//! `Background`, a list of world-frame structure items (trees, poles, bushes, buildings) that
//! stays put across frames; each frame places it in the ego frame with the ego `Pose`.
//!
//! Placement walks every edge of the road surface (drivable area, road segments, lane groups,
//! junctions, crosswalks, car parks) and of the walkways. At each step the side of the edge that
//! lies outside all of them is the verge; a near row (trees, street poles, bushes) and a far row
//! (buildings, set back 3-8 m, with gaps and vacant lots) are proposed there. A proposal is kept
//! when its footprint, crowns included and inflated by a margin, touches no road or walkway
//! polygon and no item already placed, and lies within the map bounds plus 15 m. Everything is
//! drawn from one stream of `sample::Rng` keyed by (seed, "background"), in map order, so the
//! same map and seed give the same background.

use super::shape::crown_radius;
use crate::geom::{Obb, point_in_polygon};
use crate::place::Pose;
use crate::road::Map;
use crate::sample::Rng;
use crate::view::EgoFrame;
use glam::DVec2;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BgKind {
    Tree,
    Pole,
    Bush,
    Building,
}

impl BgKind {
    /// The structure kind name whose shape this item gets (see `shape::shape_kind`).
    pub fn kind_name(self) -> &'static str {
        match self {
            BgKind::Tree => "tree",
            BgKind::Pole => "pole",
            BgKind::Bush => "bush",
            BgKind::Building => "building",
        }
    }
}

/// One world-frame structure item: a box standing on the ground.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BgItem {
    pub kind: BgKind,
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
    pub l: f64,
    pub w: f64,
    pub h: f64,
}

impl BgItem {
    /// Radius of a circle around (x, y) that holds everything the item draws.
    pub fn reach(&self) -> f64 {
        let r = 0.5 * self.l.hypot(self.w);
        if self.kind == BgKind::Tree { r.max(crown_radius(self.h)) } else { r }
    }

    /// Ground footprint including a tree's crown.
    fn extent(&self) -> Obb {
        let (l, w) = if self.kind == BgKind::Tree {
            let d = 2.0 * crown_radius(self.h);
            (d.max(self.l), d.max(self.w))
        } else {
            (self.l, self.w)
        };
        Obb { center: DVec2::new(self.x, self.y), yaw: self.yaw, length: l, width: w }
    }
}

/// Tunables of the placement, with the defaults `Background::generate` uses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BgParams {
    /// Spacing along the edge between near-row items (m).
    pub near_gap: (f64, f64),
    /// Shares of trees and poles in the near row (the rest are bushes).
    pub tree_share: f64,
    pub pole_share: f64,
    /// Building setback from the edge, length along it, depth, height, gap between (m).
    pub setback: (f64, f64),
    pub building_length: (f64, f64),
    pub building_depth: (f64, f64),
    pub building_height: (f64, f64),
    pub building_gap: (f64, f64),
    /// Probability that a building slot is left vacant.
    pub vacant: f64,
    /// Clearance kept to road and walkway polygons and between items (m).
    pub margin: f64,
}

impl Default for BgParams {
    fn default() -> Self {
        BgParams {
            near_gap: (6.0, 14.0),
            tree_share: 0.6,
            pole_share: 0.2,
            setback: (3.0, 8.0),
            building_length: (10.0, 30.0),
            building_depth: (8.0, 18.0),
            building_height: (6.0, 20.0),
            building_gap: (2.0, 8.0),
            vacant: 0.25,
            margin: 0.3,
        }
    }
}

/// World-fixed background of one scenario.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Background {
    pub items: Vec<BgItem>,
}

/// A polygon with its bounding box, for fast rejection.
struct Keep<'a> {
    poly: &'a [DVec2],
    lo: DVec2,
    hi: DVec2,
}

impl Keep<'_> {
    fn contains(&self, p: DVec2) -> bool {
        p.x >= self.lo.x && p.y >= self.lo.y && p.x <= self.hi.x && p.y <= self.hi.y && point_in_polygon(p, self.poly)
    }
}

impl Background {
    /// No background at all (tests, or a user who wants agents only).
    pub fn none() -> Self {
        Self::default()
    }

    pub fn generate(map: &Map, seed: u64) -> Self {
        Self::generate_with(map, seed, &BgParams::default())
    }

    pub fn generate_with(map: &Map, seed: u64, p: &BgParams) -> Self {
        let mut rng = Rng::stream(seed, "background");
        let keep: Vec<Keep> = [
            &map.walkways,
            &map.drivable,
            &map.road_segments,
            &map.lane_groups,
            &map.lane_group_connectors,
            &map.intersections,
            &map.crosswalk_polygons,
            &map.carparks,
        ]
        .into_iter()
        .flatten()
        .filter(|poly| poly.len() >= 3)
        .map(|poly| {
            let lo = poly.iter().fold(DVec2::splat(f64::INFINITY), |a, b| a.min(*b));
            let hi = poly.iter().fold(DVec2::splat(f64::NEG_INFINITY), |a, b| a.max(*b));
            Keep { poly, lo, hi }
        })
        .collect();
        let inside_any = |q: DVec2| keep.iter().any(|k| k.contains(q));
        let (blo, bhi) = (map.bounds.0 - DVec2::splat(15.0), map.bounds.1 + DVec2::splat(15.0));
        let bounded = blo.x < bhi.x && blo.y < bhi.y;

        let mut items: Vec<BgItem> = Vec::new();
        let clear_of_road = |o: &Obb| {
            let o = o.grown(p.margin);
            let c = o.corners();
            // Samples along the inflated outline every <= 1 m, and the centre.
            for e in 0..4 {
                let (a, b) = (c[e], c[(e + 1) % 4]);
                let n = ((b - a).length().ceil() as usize).max(1);
                for s in 0..n {
                    if inside_any(a + (b - a) * (s as f64 / n as f64)) {
                        return false;
                    }
                }
            }
            if inside_any(o.center) {
                return false;
            }
            // A polygon vertex inside the box (a thin walkway crossing between samples).
            let (f, l) = (DVec2::from_angle(o.yaw), DVec2::from_angle(o.yaw).perp());
            !keep.iter().any(|k| {
                k.poly.iter().any(|v| {
                    let d = *v - o.center;
                    d.dot(f).abs() <= o.length / 2.0 && d.dot(l).abs() <= o.width / 2.0
                })
            })
        };
        let try_place = |it: BgItem, items: &mut Vec<BgItem>| {
            if bounded && (it.x < blo.x || it.y < blo.y || it.x > bhi.x || it.y > bhi.y) {
                return false;
            }
            let ext = it.extent();
            let ext_m = Obb { length: ext.length + p.margin, width: ext.width + p.margin, ..ext };
            let r = it.reach() + p.margin;
            let hit = items.iter().any(|o| {
                let d = (o.x - it.x).hypot(o.y - it.y);
                d < r + o.reach() + p.margin && o.extent().overlaps(&ext_m)
            });
            if hit || !clear_of_road(&ext) {
                return false;
            }
            items.push(it);
            true
        };

        for k in &keep {
            let n = k.poly.len();
            for e in 0..n {
                let (a, b) = (k.poly[e], k.poly[(e + 1) % n]);
                let len = (b - a).length();
                if len < 1.0 {
                    continue;
                }
                let t = (b - a) / len;
                let yaw = t.y.atan2(t.x);
                // Near row.
                let mut s = rng.range(0.0, p.near_gap.1);
                while s < len {
                    let q = a + t * s;
                    if let Some(nrm) = verge(q, t, &inside_any) {
                        let u = rng.unit();
                        let it = if u < p.tree_share {
                            let h = rng.range(5.0, 10.0);
                            let trunk = rng.range(0.3, 0.6);
                            let off = crown_radius(h) + rng.range(0.3, 1.2);
                            let c = q + nrm * off;
                            BgItem { kind: BgKind::Tree, x: c.x, y: c.y, yaw, l: trunk, w: trunk, h }
                        } else if u < p.tree_share + p.pole_share {
                            let d = rng.range(0.25, 0.35);
                            let c = q + nrm * rng.range(0.5, 1.0);
                            BgItem { kind: BgKind::Pole, x: c.x, y: c.y, yaw, l: d, w: d, h: rng.range(6.0, 9.0) }
                        } else {
                            let (l, w) = (rng.range(1.0, 3.0), rng.range(0.8, 1.5));
                            let c = q + nrm * (w / 2.0 + rng.range(0.3, 1.0));
                            BgItem { kind: BgKind::Bush, x: c.x, y: c.y, yaw, l, w, h: rng.range(0.6, 1.5) }
                        };
                        try_place(it, &mut items);
                    }
                    s += rng.range(p.near_gap.0, p.near_gap.1);
                }
                // Far row.
                let mut s = rng.range(0.0, p.building_gap.1);
                while s < len {
                    let l = rng.range(p.building_length.0, p.building_length.1);
                    let q = a + t * (s + l / 2.0).min(len);
                    if rng.unit() >= p.vacant
                        && let Some(nrm) = verge(q, t, &inside_any)
                    {
                        let depth = rng.range(p.building_depth.0, p.building_depth.1);
                        let c = q + nrm * (rng.range(p.setback.0, p.setback.1) + depth / 2.0);
                        let h = rng.range(p.building_height.0, p.building_height.1);
                        try_place(BgItem { kind: BgKind::Building, x: c.x, y: c.y, yaw, l, w: depth, h }, &mut items);
                    }
                    s += l + rng.range(p.building_gap.0, p.building_gap.1);
                }
            }
        }
        Background { items }
    }

    /// The items that can reach the 100 m x 100 m grid around `ego`, in the ego frame as
    /// (item, x, y, yaw).
    pub fn in_view(&self, ego: Pose) -> impl Iterator<Item = (&BgItem, f64, f64, f64)> + '_ {
        let f = EgoFrame::new(ego);
        let half = super::layout::UPPER[0];
        self.items.iter().filter_map(move |it| {
            let q = f.point(DVec2::new(it.x, it.y));
            let r = it.reach() + 1.0;
            (q.x.abs() <= half + r && q.y.abs() <= half + r).then(|| (it, q.x, q.y, f.heading(it.yaw)))
        })
    }
}

/// Outward unit normal at edge point `q` (tangent `t`) when exactly one side is off the road.
fn verge(q: DVec2, t: DVec2, inside_any: &impl Fn(DVec2) -> bool) -> Option<DVec2> {
    let n = t.perp();
    let (l, r) = (inside_any(q + n * 0.5), inside_any(q - n * 0.5));
    match (l, r) {
        (true, false) => Some(-n),
        (false, true) => Some(n),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<DVec2> {
        vec![DVec2::new(x0, y0), DVec2::new(x1, y0), DVec2::new(x1, y1), DVec2::new(x0, y1)]
    }

    pub(crate) fn straight_map() -> Map {
        let mut m = Map::default();
        m.drivable = vec![rect(-100.0, -7.0, 100.0, 7.0)];
        m.road_segments = m.drivable.clone();
        m.walkways = vec![rect(-100.0, 7.0, 100.0, 10.0), rect(-100.0, -10.0, 100.0, -7.0)];
        m.bounds = (DVec2::new(-100.0, -10.0), DVec2::new(100.0, 10.0));
        m
    }

    #[test]
    fn background_is_seeded_off_the_road_and_apart() {
        let m = straight_map();
        let a = Background::generate(&m, 7);
        assert_eq!(a, Background::generate(&m, 7));
        assert_ne!(a, Background::generate(&m, 8));
        assert!(a.items.iter().any(|i| i.kind == BgKind::Building));
        assert!(a.items.iter().any(|i| i.kind == BgKind::Tree));
        for it in &a.items {
            let e = it.extent();
            for c in e.corners() {
                assert!(c.y.abs() > 10.0 || c.x.abs() > 100.0, "{it:?} reaches the road or walkway");
            }
        }
        for (n, x) in a.items.iter().enumerate() {
            for y in &a.items[n + 1..] {
                assert!(!x.extent().overlaps(&y.extent()), "{x:?} overlaps {y:?}");
            }
        }
    }
}
