//! Pairs placed too near their shared zone for either to stop short: one order fixed at set-up
//! (`Crossing::placed_yield`), or E0207 where no order keeps them apart.

use crate::diag::Diagnostic;
use crate::geom::Obb;
use crate::rollout::agent::{Actor, Drive, StopGoal};
use crate::rollout::junction::bend::SWEEP_MARGIN;
use crate::rollout::kinematics::can_stop;

/// Two vehicles placed so near where their junction paths meet, and so fast, that neither can
/// stop short of its zone (`Crossing::enter`, which the other's sweep may move back from where
/// the paths come near) within its emergency braking: the right-of-way rule then has nobody to
/// hold (both are in or at their zone), and only the overlap safety net would part them (two
/// buses 6 m before their lines at 9 m/s, turning across each other, were stopped dead from
/// 9 m/s). Whichever of them can give way, braking as hard as it may while the other goes on at
/// its placed speed or slowed to a share of it (`GO_ON_KEEP`), without their boxes (grown by
/// `SWEEP_MARGIN`) meeting, does so (`Crossing::placed_yield`); where both can, the one clear
/// at every share, else the later to the paths' meeting. Where neither can, and braking both
/// they still meet or stand each in the other's way, no order keeps them apart: E0207. A
/// vehicle whose start is delayed, or whose stop goal lies short of the stretch, can hold; a
/// merge is followed, not crossed.
pub(crate) fn order_crossings(actors: &mut [Actor], errs: &mut Vec<Diagnostic>) {
    let holds = |a: &Actor, meet: f64| {
        !matches!(a.drive, Drive::Mover)
            || a.start > 1e-9
            || a.trigger.is_some()
            || matches!(a.stop, StopGoal::Front(sf) | StopGoal::Centre(sf) if sf < meet + a.hl)
    };
    let mut set = vec![];
    for (i, a) in actors.iter().enumerate() {
        for (k, c) in a.crossings.iter().enumerate().filter(|(_, c)| c.other > i && !c.merge) {
            let b = &actors[c.other];
            if holds(a, c.meet)
                || holds(b, c.other_meet)
                || can_stop(a.v0, c.enter - 0.3 - a.s0, a.lim.brake_max)
                || can_stop(b.v0, c.other_enter - 0.3 - b.s0, b.lim.brake_max)
            {
                continue;
            }
            // When `y` gives way: the first contact with `o` going on at its placed speed, or
            // none if it does not touch `y` at that speed or at any share it may brake down to.
            let gives_way = |y: &Actor, o: &Actor, leave: f64| {
                let first = first_contact(y, o, 1.0, leave)?;
                GO_ON_KEEP[1..].iter().all(|&keep| first_contact(y, o, keep, leave).is_some()).then_some(first)
            };
            let (ta, tb) = (gives_way(a, b, c.other_leave), gives_way(b, a, c.leave));
            // Whether `a` is the later to where the paths meet at its placed speed (then the name).
            let later = |x: &Actor, meet: f64| (meet - x.s0).max(0.0) / x.v0.max(0.1);
            let a_later = || {
                later(a, c.meet).total_cmp(&later(b, c.other_meet)).then_with(|| a.info.name.cmp(&b.info.name)).is_gt()
            };
            match (ta, tb) {
                (None, Some(_)) => set.push((i, k, true)),
                (Some(_), None) => set.push((i, k, false)),
                // Either may give way: the one that stays clear whatever share of its speed the
                // other keeps, else the later to reach where the paths meet (then the name). Left
                // to the rule, one placed in the other's sweep short of the stretch counted as
                // inside, and an SUV beside a bus turning from the next lane went with it and met
                // its swinging tail.
                (None, None) => {
                    let clear = |y: &Actor, o: &Actor, leave: f64| {
                        GO_ON_KEEP.iter().all(|&keep| first_contact(y, o, keep, leave).is_none())
                    };
                    let a_yields = match (clear(a, b, c.other_leave), clear(b, a, c.leave)) {
                        (true, false) => true,
                        (false, true) => false,
                        _ => a_later(),
                    };
                    set.push((i, k, a_yields));
                }
                // Neither can give way while the other goes on: both brake, and where they then
                // stand clear of each other, the one not standing in the other's way goes first
                // (its car-following holds it short of the other where it must); left unordered,
                // two buses side by side turning away from each other both went, and each one's
                // tail swung into the other.
                (Some(ta), Some(tb)) => {
                    let both = first_contact(a, b, 0.0, f64::INFINITY);
                    match (both, standoff(a, b, (c.leave, c.other_leave))) {
                        (Some(_), _) | (None, (true, true)) => errs.push(no_order(a, b, [ta, tb], both)),
                        (None, (a_blocked, b_blocked)) => {
                            let a_yields = a_blocked || (!b_blocked && a_later());
                            set.push((i, k, a_yields));
                        }
                    }
                }
            }
        }
    }
    for (i, k, yields) in set {
        let c = &mut actors[i].crossings[k];
        c.placed_yield = Some(yields);
        let (j, enter, leave) = (c.other, c.enter, c.leave);
        let theirs =
            actors[j].crossings.iter_mut().find(|x| x.other == i && x.other_enter == enter && x.other_leave == leave);
        if let Some(x) = theirs {
            x.placed_yield = Some(!yields);
        }
    }
}

/// The first time at which `y`, braking at its emergency limit along its path from its placed
/// pose, is touched by `o`, which brakes as hard down to `keep` times its placed speed and goes
/// on at that along its own (`keep` 0: it brakes to a stand) while its centre is short of
/// `leave` on its route, within `ORDER_HORIZON_S`; boxes laid as `box_at` lays them.
pub(crate) fn first_contact(y: &Actor, o: &Actor, keep: f64, leave: f64) -> Option<f64> {
    let dt = 0.05;
    // Arc length after `t` braking at the emergency limit from `v0` down to `v1`, then at `v1`.
    let s_at = |a: &Actor, v1: f64, t: f64| {
        let (b, v0) = (a.lim.brake_max, a.v0);
        let tb = (v0 - v1) / b;
        a.s0 + if t < tb { v0 * t - 0.5 * b * t * t } else { (v0 * v0 - v1 * v1) / (2.0 * b) + v1 * (t - tb) }
    };
    let vo = keep * o.v0;
    // Braking both to a stand, nothing moves once both stand.
    let until = if keep > 0.0 { ORDER_HORIZON_S } else { (y.v0 / y.lim.brake_max).max(o.v0 / o.lim.brake_max) + dt };
    (1..)
        .map(|k| k as f64 * dt)
        .take_while(|&t| t <= until && s_at(o, vo, t - dt) <= leave)
        .find(|&t| box_at(y, s_at(y, 0.0, t)).overlaps(&box_at(o, s_at(o, vo, t)).grown(SWEEP_MARGIN)))
}

/// The speeds, as shares of its placed speed, down to which one that goes on may brake while
/// the other gives way (`order_crossings`).
pub(crate) const GO_ON_KEEP: [f64; 4] = [1.0, 0.75, 0.5, 0.25];

/// Where `x` and `y` are both braked to a stand as in `first_contact` without touching: whether
/// each stands in the other's way, `x` unable to go on along its path until its centre is past
/// `lx` without its box meeting `y`'s, standing (and `y` past `ly`). Both: a standoff.
pub(crate) fn standoff(x: &Actor, y: &Actor, (lx, ly): (f64, f64)) -> (bool, bool) {
    let stand = |a: &Actor| a.s0 + a.v0 * a.v0 / (2.0 * a.lim.brake_max);
    let (sx, sy) = (stand(x), stand(y));
    let blocked = |a: &Actor, from: f64, to: f64, theirs: &Obb| {
        let n = ((to - from) / 0.25).ceil().max(0.0) as usize;
        (0..=n).any(|k| box_at(a, from + k as f64 * 0.25).overlaps(theirs))
    };
    (blocked(x, sx, lx, &box_at(y, sy)), blocked(y, sy, ly, &box_at(x, sx)))
}

/// The box of vehicle `a` with its centre at route arc length `s`: through its junction where
/// its dry run steered it (`Bend::pose`); elsewhere on its path, at its placed offset.
pub(crate) fn box_at(a: &Actor, s: f64) -> Obb {
    let (center, yaw) = a.bend.as_ref().and_then(|b| b.pose(s)).unwrap_or_else(|| a.path.point(s, a.d0));
    Obb { center, yaw, length: 2.0 * a.hl, width: 2.0 * a.hw }
}

/// How long `first_contact` follows one that goes on, s.
pub(crate) const ORDER_HORIZON_S: f64 = 10.0;

pub(crate) fn no_order(a: &Actor, b: &Actor, [ta, tb]: [f64; 2], both: Option<f64>) -> Diagnostic {
    let (x, y) = (&a.info.name, &b.info.name);
    let mut d = Diagnostic::error(
        "E0207",
        format!(
            "`{x}` and `{y}` start too close to where their junction paths meet for either to give way to the other"
        ),
    );
    for (k, t) in [(a, ta), (b, tb)] {
        if let Some(span) = k.span {
            d = d.label(
                span,
                format!(
                    "`{}` cannot stop short of where the paths meet: giving way, braking as hard as it may, it is struck at {t:.1} s",
                    k.info.name
                ),
            );
        }
    }
    let both = match both {
        Some(t) => format!("with both braking as hard as they may, they meet at {t:.1} s"),
        None => "with both braking as hard as they may, each stands in the other's way".to_string(),
    };
    let fix = if [a, b].iter().any(|k| k.info.background) {
        "one of them is background traffic: lower `density`, or change the scenario's `seed`; or start the placed one further back or slower"
    } else {
        "start one of them further back or slower, so that it can hold while the other crosses, or delay it with `start after`; to stage their crash, write a `conflict`"
    };
    d.help(format!("{both}; {fix}"))
}
