//! E0204 for a turn a vehicle drives but the road does not offer: its wheels leave the drivable
//! surface in its junction.

use crate::diag::Diagnostic;
use crate::geom::Obb;
use crate::road::Map;
use crate::rollout::Tracks;
use crate::rollout::agent::{Actor, Conf};
use crate::rollout::path::Foot;
use crate::rollout::setup::turn_name;
use glam::DVec2;

/// How far a turning vehicle's wheels may stray off the drivable surface in its junction, m:
/// one BEV pixel (0.25 m), the resolution at which the surface is drawn.
pub(crate) const TURN_OFF_ROAD_M: f64 = 0.25;

/// How far over its path's curve speed a vehicle may take a turn before E0204 blames the speed
/// (car-following settles onto the speed from just above it).
pub(crate) const TURN_SPEED_SLACK: f64 = 0.5;

/// E0204 for a turn the vehicle drives but cannot make on this road: the junction path is within
/// `TURN_SLACK` of its turning radius, yet its wheels leave the drivable surface by more than
/// `TURN_OFF_ROAD_M` while in the junction. The wheels span the box's width and its wheelbase
/// (`WHEELBASE_SHARE` of its length): the overhangs beyond the axles sweep over the kerb in a
/// tight turn, as real ones do, but tyres on the pavement are a turn the road does not offer.
/// Conflict agents are exempt: their crash may take them anywhere.
pub(crate) fn check_turns(map: &Map, actors: &[Actor], confs: &[Conf], out: &Tracks, errs: &mut Vec<Diagnostic>) {
    // A map drawn without a surface (a hand-built one) has nothing to check against.
    if map.drivable.is_empty() {
        return;
    }
    let boxes: Vec<(DVec2, DVec2)> = map
        .drivable
        .iter()
        .map(|poly| poly.iter().fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p))))
        .collect();
    let off_road = |q: DVec2| -> f64 {
        let near = || map.drivable.iter().zip(&boxes).filter(|(_, (lo, hi))| q.cmpge(*lo).all() && q.cmple(*hi).all());
        if near().any(|(poly, _)| crate::geom::point_in_polygon(q, poly)) {
            return 0.0;
        }
        map.drivable
            .iter()
            .flat_map(|poly| (0..poly.len()).map(move |k| (poly[k], poly[(k + 1) % poly.len()])))
            .map(|(a, b)| {
                let d = b - a;
                let t =
                    if d.length_squared() > 0.0 { ((q - a).dot(d) / d.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
                q.distance(a + d * t)
            })
            .fold(f64::INFINITY, f64::min)
    };
    for (i, a) in actors.iter().enumerate() {
        let (Some(turn), Some(span), Some(j)) = (a.turn_goal, a.span, a.junction) else { continue };
        if confs.iter().any(|k| k.af == i || k.st == i) {
            continue;
        }
        let Some(conn) = map.connectors.get(j.conn) else { continue };
        let (lo, hi) =
            conn.path.points.iter().fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let (lo, hi) = (lo - DVec2::splat(a.radius + 1.0), hi + DVec2::splat(a.radius + 1.0));
        let mut worst = (0.0, 0);
        // The most it went over the speed its path allows there (the turn's curve speed), and
        // where: it brakes for a turn at its comfortable braking only, so one placed too fast
        // and too close takes the turn wide.
        let mut over = (0.0, 0.0, 0.0);
        let mut guess = a.s0;
        for (f, p) in out.poses[i].iter().enumerate() {
            let c = DVec2::new(p.x, p.y);
            if !(c.cmpge(lo).all() && c.cmple(hi).all()) {
                continue;
            }
            let Foot { s, .. } = a.path.frenet(c, guess);
            guess = s;
            let (v, cap) = (out.speeds[i][f], a.path.cap(s));
            if v - cap > over.0 {
                over = (v - cap, v, cap);
            }
            let obb =
                Obb { center: c, yaw: p.yaw, length: crate::rollout::WHEELBASE_SHARE * 2.0 * a.hl, width: 2.0 * a.hw };
            for q in obb.corners() {
                let d = off_road(q);
                if d > worst.0 {
                    worst = (d, f);
                }
            }
        }
        if worst.0 > TURN_OFF_ROAD_M {
            let t = worst.1 as f64 / out.rate.max(1e-9);
            let mut message = format!(
                "`{}` ({}, turning radius {:.1} m) cannot turn {} here: its box leaves the road by {:.1} m at {t:.1} s",
                a.info.name,
                a.info.kind,
                a.r_min,
                turn_name(turn),
                worst.0
            );
            let mut help = String::from(
                "a wider road (lanes, lane_width, median, a roundabout's radius) or a smaller kind; long vehicles \
                 need room to swing through a turn (see docs/rollout.md)",
            );
            if over.0 > TURN_SPEED_SLACK {
                message += &format!(", driving it at {:.1} m/s where it allows {:.1} m/s", over.1, over.2);
                help = format!(
                    "a lower `speed`, or a start farther from the junction: it brakes for a turn at its comfortable \
                     braking ({:.1} m/s2) only; else {help}",
                    a.lim.brake
                );
            }
            errs.push(Diagnostic::error("E0204", message).label(span, "this goal").help(help));
        }
    }
}
