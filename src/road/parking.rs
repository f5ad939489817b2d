//! Kerbside places of a `straight` road (`parking`, `driveway`). In: the checked road and the
//! map its template built. Out: the same map with parking lanes, driveways and their standing
//! places (`Map::kerb_places`).
//!
//! A parking lane lies between the paving and the sidewalk of its kerb: drivable surface (BEV
//! channel 1) and a parking area (channel 3); the sidewalk moves out by its width. With a
//! mid-block crosswalk the first `KERB_CLEAR_M` of the kerb is a kerb extension (walkway), so
//! the crosswalk still ends on a walkway. A driveway crosses the sidewalk and runs
//! `DRIVEWAY_APRON_M` beyond it: a parking area (channel 3) over the walkway, not drivable
//! paving, so no walkway overlaps drivable paving.

use super::arm::SIDEWALK;
use super::map::{KerbPlace, KerbRef, Map};
use super::shape::strip;
use crate::check::kerb::{DRIVEWAY_APRON_M, DRIVEWAY_WIDTH_M};
use crate::check::scenario::{Arm, Dir, Road};
use crate::geom::{Polyline, wrap_angle};
use glam::DVec2;
use std::f64::consts::{FRAC_PI_2, PI};

/// The axis of a straight road's arm, from the centre outward (as `straight::build` lays it).
fn axis(road: &Road, arm: Arm) -> Polyline {
    let sign = if arm == Arm::East { 1.0 } else { -1.0 };
    Polyline::new(vec![DVec2::ZERO, DVec2::new(sign * road.length / 2.0, 0.0)])
}

/// Left of the arm's axis (+1) for its in-lanes' kerb, right (-1) for its out-lanes'.
fn side(dir: Dir) -> f64 {
    if dir == Dir::In { 1.0 } else { -1.0 }
}

/// The paving's edge on a kerb, m from the axis (median, lanes, shoulder).
fn paving(road: &Road) -> f64 {
    road.median / 2.0 + f64::from(road.lanes) * road.lane_width + road.shoulder
}

pub(crate) fn lay(road: &Road, map: &mut Map) {
    let (h, start, half) = (paving(road), road.kerb_start(), road.length / 2.0);
    for p in &road.kerb.parking {
        let (ax, sg) = (axis(road, p.arm), side(p.dir));
        let strip_at = |from: f64, to: f64| strip(&ax, from, to, sg * h, sg * (h + p.width));
        map.drivable.push(strip_at(start, half));
        map.carparks.push(strip_at(start, half));
        if start > 0.0 {
            map.walkways.push(strip_at(0.0, start));
        }
        shift_sidewalk(map, p.arm, p.dir, ax.offset_point(0.0, sg * p.width) - ax.offset_point(0.0, 0.0));
        let travel = wrap_angle(ax.pose_at(0.0).1 + if p.dir == Dir::In { PI } else { 0.0 });
        for slot in 1..=road.parking_slots() {
            let (lo, hi) = road.slot_stretch(slot);
            map.kerb_places.push(KerbPlace {
                at: KerbRef::Slot { arm: p.arm, dir: p.dir, slot },
                centre: ax.offset_point(0.5 * (lo + hi), sg * (h + p.width / 2.0)),
                yaw: travel,
            });
        }
    }
    for (index, d) in road.kerb.driveways.iter().enumerate() {
        let (ax, sg) = (axis(road, d.arm), side(d.dir));
        let kerb = h + road.parking_at(d.arm, d.dir).map_or(0.0, |p| p.width);
        let (lo, hi) = (d.at - DRIVEWAY_WIDTH_M / 2.0, d.at + DRIVEWAY_WIDTH_M / 2.0);
        map.carparks.push(strip(&ax, lo, hi, sg * kerb, sg * (kerb + SIDEWALK + DRIVEWAY_APRON_M)));
        map.kerb_places.push(KerbPlace {
            at: KerbRef::Driveway(index),
            centre: ax.offset_point(d.at, sg * (kerb + SIDEWALK + DRIVEWAY_APRON_M / 2.0)),
            yaw: wrap_angle(ax.pose_at(0.0).1 + sg * FRAC_PI_2),
        });
    }
}

/// Move the sidewalk along a kerb (and its walkway polygon) out by `by`.
fn shift_sidewalk(map: &mut Map, arm: Arm, dir: Dir, by: DVec2) {
    let Some(sw) = map.sidewalks.iter_mut().find(|s| s.arm == arm && s.dir == dir) else { return };
    if let Some(w) = map.walkways.iter_mut().find(|w| **w == sw.polygon) {
        w.iter_mut().for_each(|q| *q += by);
    }
    sw.polygon.iter_mut().for_each(|q| *q += by);
    sw.centre = Polyline::new(sw.centre.points.iter().map(|q| *q + by).collect());
}

impl Map {
    /// Where a parking slot or a driveway's car stands.
    pub fn kerb_place(&self, at: KerbRef) -> Option<&KerbPlace> {
        self.kerb_places.iter().find(|k| k.at == at)
    }
}
