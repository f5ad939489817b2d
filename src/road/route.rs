//! The route an agent drives: its lane found from its pose, continued lane by lane through the
//! junction connectors of its `turn`. One function for the rollout (`sim.rs`, which drives it)
//! and for the place pass's E0206 check (`place::leader`, which asks whether a `stop behind`
//! leader is ahead on it), so that the two cannot disagree about where an agent goes.

use crate::check::scenario::{LaneId, Side, Turn};
use crate::geom::wrap_angle;
use crate::road::Map;
use glam::DVec2;

/// Length of the straight run appended after a route's last lane, m: agents that reach the end
/// of the map keep going instead of piling up at the edge.
pub const RUN_OUT: f64 = 300.0;
/// Where a route passes its first junction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Junction {
    /// Arc length where a yielding front bumper halts (the stop line, else the junction entry).
    pub stop: f64,
    /// Arc length where the route leaves the junction.
    pub exit: f64,
    /// Index into `Map::connectors`.
    pub conn: usize,
}

/// The lane a vehicle at `p` heading `yaw` is driving in: nearest centre line among lanes whose
/// direction agrees, within the lane (and its shoulder).
pub fn find_lane(map: &Map, p: DVec2, yaw: f64) -> Option<(usize, f64, f64)> {
    let mut best: Option<(usize, f64, f64)> = None;
    for (i, l) in map.lanes.iter().enumerate() {
        if l.centre.points.len() < 2 {
            continue;
        }
        let (s, d) = l.centre.project(p);
        if s < -0.5 || s > l.centre.length() + 0.5 {
            continue;
        }
        let (_, h) = l.centre.pose_at(s);
        if wrap_angle(yaw - h).abs() > 1.0 {
            continue;
        }
        let reach = l.width / 2.0 + if d < 0.0 { l.shoulder_right } else { 0.0 } + 0.5;
        if d.abs() > reach {
            continue;
        }
        if best.is_none_or(|b| d.abs() < b.2.abs()) {
            best = Some((i, s, d));
        }
    }
    best
}

/// The lane a `change_lane` goal moves to from lane `l`, where the route then starts: lane 1 is
/// nearest the centre line, so `left` is index - 1 and `right` index + 1 on the same arm and
/// direction. `None` when there is no lane on that side.
pub fn side_lane(map: &Map, l: usize, side: Side) -> Option<usize> {
    let id = map.lanes[l].id;
    let index = match side {
        Side::Left => id.index.checked_sub(1)?,
        Side::Right => id.index + 1,
    };
    map.lanes.iter().position(|x| x.id == LaneId { index, ..id })
}

/// Points of the route starting with lane `l`: its centre, then at each lane end the connector
/// of the requested turn (consumed at the first junction) or else straight on, then the next
/// lane. `false` when a requested turn finds no connector before the route runs out. Also where
/// the route passes its first junction.
pub fn chain(map: &Map, l: usize, turn: Option<Turn>) -> (Vec<DVec2>, bool, Option<Junction>) {
    let mut pts: Vec<DVec2> = map.lanes[l].centre.points.clone();
    let mut cur = l;
    let mut pending = turn;
    let mut ok = true;
    let mut junction = None;
    let mut total = map.lanes[l].centre.length();
    for _ in 0..6 {
        if total > 800.0 {
            break;
        }
        let mut from_here = map.connectors.iter().enumerate().filter(|(_, c)| c.from == cur && c.to < map.lanes.len());
        let pick = match pending {
            Some(t) => match from_here.clone().find(|(_, c)| c.turn == t) {
                Some(cn) => Some(cn),
                None if map.lanes[cur].next.is_some() => None,
                None => {
                    ok = false;
                    break;
                }
            },
            None => from_here
                .clone()
                .find(|(_, c)| c.turn == Turn::Straight)
                .or_else(|| if map.lanes[cur].next.is_some() { None } else { from_here.next() }),
        };
        let nxt = match pick {
            Some((ci, cn)) => {
                if junction.is_none() {
                    // The stop line counts only on the lane the route starts in.
                    let stop = if cur == l { map.lanes[l].stop_line_s } else { None };
                    let (entry, len) = (total, cn.path.length());
                    junction = Some(Junction { stop: stop.unwrap_or(entry), exit: entry + len, conn: ci });
                }
                pts.extend_from_slice(&cn.path.points);
                total += cn.path.length();
                pending = None;
                cn.to
            }
            None => match map.lanes[cur].next {
                Some(n) if n < map.lanes.len() => n,
                _ => break,
            },
        };
        pts.extend_from_slice(&map.lanes[nxt].centre.points);
        total += map.lanes[nxt].centre.length();
        cur = nxt;
    }
    if pending.is_some() {
        ok = false;
    }
    let n = pts.len();
    if n >= 2 {
        let dir = (pts[n - 1] - pts[n - 2]).normalize_or_zero();
        pts.push(pts[n - 1] + dir * RUN_OUT);
    }
    (pts, ok, junction)
}
