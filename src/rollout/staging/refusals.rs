//! Why a staging is refused (E0205): a crash that misses, lands elsewhere than asked, or makes
//! someone brake beyond their limit or be stopped dead.

use crate::diag::Diagnostic;
use crate::geom::Obb;
use crate::rollout::Tracks;
use crate::rollout::agent::{Actor, Conf};
use crate::rollout::staging::plan;
use crate::rollout::staging::plan::Plan;
use glam::DVec2;

/// Within this of a striker (box to box, m), an agent braking beyond its limit is braking for
/// the staged crash.
pub(crate) const FORCED_NEAR_M: f64 = 1.0;

/// A staged crash that makes someone brake beyond their limit: what the controller cannot
/// foresee of a striker that leaves its goal at speed (one cutting across a lane a few metres
/// ahead of a car, one swerving into a lane that a motorcycle is setting off in), measured on
/// the tracks. The first frame at which an agent's speed falls faster than its `brake_max`
/// while its box is within `FORCED_NEAR_M` of another's, either of the two a striker (the pair
/// up to their latched frame, where the crash stops them dead).
pub(crate) fn forced_braking(actors: &[Actor], confs: &[Conf], plans: &[Option<Plan>], out: &Tracks) -> Option<Forced> {
    let dt = 1.0 / out.rate;
    let staged = |k: usize| confs.iter().zip(plans).position(|(c, p)| p.is_some() && c.af == k);
    let bx = |k: usize, f: usize| {
        let (p, s) = (out.poses[k][f], out.agents[k].size);
        Obb { center: DVec2::new(p.x, p.y), yaw: p.yaw, length: s[0], width: s[1] }.grown(0.5 * FORCED_NEAR_M)
    };
    let mut first: Option<Forced> = None;
    for (i, a) in actors.iter().enumerate() {
        let end = out.impacts.iter().filter(|r| r.at_fault == i || r.struck == i).map(|r| r.frame).min();
        let end = end.into_iter().chain(out.first_contact(i)).min();
        let end = end.unwrap_or(out.frames).min(first.map_or(out.frames, |f| (f.t / dt).round() as usize));
        for f in 1..end {
            let acc = (out.speeds[i][f] - out.speeds[i][f - 1]) / dt;
            if acc >= -a.lim.brake_max - 1e-6 {
                continue;
            }
            let near = (0..actors.len()).find_map(|k| {
                let ki = staged(i).or(staged(k)).filter(|_| k != i)?;
                [f - 1, f].iter().any(|&g| bx(i, g).overlaps(&bx(k, g))).then_some((ki, k))
            });
            if let Some((ki, k)) = near {
                first = Some(Forced { conflict: ki, agent: i, other: k, t: f as f64 * dt, acc });
                break;
            }
        }
    }
    first
}

/// Someone braking beyond their limit for a staged crash (`forced_braking`): the conflict (index
/// into `confs`), the braking agent, the other (one of the two a striker), when, and the
/// deceleration (m/s2, negative).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Forced {
    pub conflict: usize,
    pub agent: usize,
    pub other: usize,
    pub t: f64,
    pub acc: f64,
}

/// E0205 for a staging whose every plan makes someone brake beyond their limit for the crash
/// (`forced_braking`).
pub(crate) fn forced_error(
    actors: &[Actor],
    confs: &[Conf],
    Forced { conflict: ki, agent: x, other: y, t, acc }: Forced,
) -> Diagnostic {
    let k = &confs[ki];
    let (a, b) = (&actors[k.af].info.name, &actors[k.st].info.name);
    let (xn, yn) = (&actors[x].info.name, &actors[y].info.name);
    let by = if x == k.af { y } else { x };
    Diagnostic::error(
        "E0205",
        format!(
            "the conflict between `{a}` and `{b}` cannot be staged within the agents' limits: at {t:.1} s `{xn}` \
             would have to brake at {:.1} m/s2 for `{yn}` (its limit is {:.1})",
            -acc, actors[x].lim.brake_max
        ),
    )
    .label(k.c.span, "no plan tried stages it within everyone's braking")
    .help(keep_out(actors, k, by, k.af))
}

/// The help of a staging refused for agent `by` in the way of `mover`.
pub(crate) fn keep_out(actors: &[Actor], k: &Conf, by: usize, mover: usize) -> String {
    let (a, b) = (&actors[k.af].info.name, &actors[k.st].info.name);
    format!(
        "keep `{}` out of the way `{}` takes ({}), start `{a}` where its way to `{b}` is clear, or move `at`",
        actors[by].info.name,
        actors[mover].info.name,
        if actors[by].info.background {
            "it is background traffic: lower `density`, or change the scenario's `seed`"
        } else {
            "start it elsewhere, or give it another goal"
        }
    )
}

/// E0205 for a staging whose first plan has the overlap safety net stop agent `stopped` of the
/// pair `k` dead at `t` (beyond its braking), short of running into `other`, and that no
/// re-planned one betters.
pub(crate) fn stopped_dead(actors: &[Actor], k: &Conf, stopped: usize, other: usize, t: f64) -> Diagnostic {
    let (a, b) = (&actors[k.af].info.name, &actors[k.st].info.name);
    let (x, y) = (&actors[stopped].info.name, &actors[other].info.name);
    Diagnostic::error(
        "E0205",
        format!(
            "the conflict between `{a}` and `{b}` cannot be staged within the agents' limits: at {t:.1} s `{x}` \
             would run into `{y}` and is stopped dead"
        ),
    )
    .label(k.c.span, "no plan tried stages it within everyone's braking")
    .help(keep_out(actors, k, other, stopped))
}

/// E0205 for each planned conflict whose crash does not happen near its time, or lands
/// elsewhere than asked, with its index into `confs`. (Without a plan the at-fault agent is not
/// ours to steer, e.g. a replayed track: nothing to check.)
pub(crate) fn staging_errors(
    actors: &[Actor],
    confs: &[Conf],
    plans: &[Option<Plan>],
    out: &Tracks,
    blocked_by: &[Option<(usize, f64)>],
    (dt, frames, duration): (f64, usize, f64),
) -> Vec<(usize, Diagnostic)> {
    let mut errs = vec![];
    for (ki, (k, _)) in confs.iter().zip(plans).enumerate().filter(|(_, (k, p))| p.is_some() && k.near.is_none()) {
        let t_req = plan::requested_time(&k.c, dt, frames, duration);
        let rec = out.impacts.iter().find(|r| r.conflict == k.index);
        let hit = rec.map(|r| r.frame as f64 * dt);
        // Nor one that lands elsewhere than asked: a `rear_end` on `rear` that the struck
        // car, blocked by its striker standing in its lane, drives into front first is not
        // the crash the file describes, and its labels would say it is.
        let off = rec.and_then(|r| {
            let size = out.agents[r.at_fault].size;
            if r.depth < plan::MIN_DEPTH {
                return Some(format!("they only graze, {:.3} m deep", r.depth));
            }
            plan::wrong_struck_side(k.c.impact, k.c.point, r.struck_side)
                .map(|why| format!("`{}` is struck on its {why}", actors[k.st].info.name))
                .or_else(|| plan::off_striking_face(k.c.impact, r.at_fault_local, size))
        });
        let in_time = |t: f64| (t - t_req).abs() <= plan::WINDOW_S + 0.5 * dt;
        let (a, b) = (&actors[k.af].info.name, &actors[k.st].info.name);
        // What went wrong, its label, how the help joins a bystander's name to its advice, and
        // the help when no bystander held the striker back.
        let (what, label, met, unhindered) = match (hit.filter(|&t| in_time(t)), off) {
            (Some(_), None) => continue,
            (Some(t), Some(why)) => (
                format!("cannot be staged as asked: at {t:.1} s {why}"),
                "the crash lands elsewhere",
                ", and the two met otherwise:",
                format!(
                    "start `{a}` where its striking face can come at that side of `{b}` (behind it in its lane for \
                     `rear_end`, toward it for `head_on`), or ask for the side it can reach"
                ),
            ),
            (None, _) => (
                match hit {
                    Some(t) => format!("cannot be staged at {t_req:.1} s: they first touch at {t:.1} s"),
                    None => format!("cannot be staged at {t_req:.1} s: they never touch"),
                },
                "no contact near this time",
                ":",
                format!(
                    "`{a}` must be able to reach `{b}` within {:.1} s of `at` at its limits: \
                     start them closer, give them speeds that bring them together, or move `at`",
                    plan::WINDOW_S
                ),
            ),
        };
        let help = match blocked_by[k.af] {
            Some((j, t)) => {
                let by = &actors[j].info.name;
                format!(
                    "`{a}` slowed from {t:.1} s for `{by}` in its way (a striker never runs into a bystander){met} \
                     start `{a}` where its way to `{b}` is clear, keep `{by}` out of it, or move `at`"
                )
            }
            None => unhindered,
        };
        errs.push((
            ki,
            Diagnostic::error("E0205", format!("the conflict between `{a}` and `{b}` {what}"))
                .label(k.c.span, label)
                .help(help),
        ));
    }
    errs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::place::Pose;
    use crate::rollout::ImpactRecord;
    use crate::rollout::frame::empty_tracks;
    use crate::rollout::setup::test_actors::{lcg, random_boxes};
    use crate::rollout::staging::plan::Plan;

    /// A striker `a0` (staged against `a2`) passing `a1`; `a1` slows by `drop` m/s in one frame
    /// with its box `gap` m from the striker's. `forced_braking` names `a1` exactly when the drop
    /// is beyond its 8 m/s2 and the boxes are within 1 m; the striker's own stop dead at its
    /// latched frame is the crash, not braking.
    #[test]
    fn forced_braking_is_braking_beyond_the_limit_next_to_a_striker() {
        use crate::check::scenario::{Conflict, Impact, Point};
        let case = |drop: f64, gap: f64| {
            let actors = random_boxes(3, 0.0, &mut lcg(7));
            let (frames, dt) = (10, 0.1);
            let mut out = empty_tracks(&actors, 1.0 / dt, frames);
            for f in 0..frames {
                let (l0, l1) = (actors[0].info.size[0], actors[1].info.size[0]);
                out.poses[0].push(Pose { x: 0.0, y: 0.0, yaw: 0.0 });
                out.poses[1].push(Pose { x: 0.5 * (l0 + l1) + gap, y: 0.0, yaw: 0.0 });
                out.poses[2].push(Pose { x: -20.0, y: 0.0, yaw: 0.0 });
                out.speeds[0].push(if f < 8 { 5.0 } else { 0.0 });
                out.speeds[1].push(if f < 5 { 5.0 } else { 5.0 - drop });
                out.speeds[2].push(0.0);
            }
            out.impacts.push(ImpactRecord {
                conflict: 0,
                frame: 8,
                at_fault: 0,
                struck: 2,
                point_world: [0.0; 2],
                at_fault_local: [0.0; 2],
                struck_local: [0.0; 2],
                struck_side: Point::Rear,
                depth: 0.25,
            });
            let c = Conflict {
                at_fault: 0,
                struck: 2,
                impact: Impact::RearEnd,
                point: Point::Rear,
                at: None,
                after: Default::default(),
                span: Default::default(),
            };
            let confs = [Conf { index: 0, af: 0, st: 2, c, near: None }];
            let plan = Plan {
                struck: 2,
                rel_pos: DVec2::ZERO,
                rel_yaw: 0.0,
                t_depart: 0.0,
                t_impact: 0.8,
                frame: 8,
                delta: 0.25,
            };
            forced_braking(&actors, &confs, &[Some(plan)], &out).map(|f| (f, forced_error(&actors, &confs, f)))
        };
        let Some((Forced { conflict: k, agent: who, other: by, t, acc }, d)) = case(1.5, 0.5) else {
            panic!("15 m/s2 beside the striker passed")
        };
        assert_eq!((k, who, by), (0, 1, 0));
        assert!((t - 0.5).abs() < 1e-9 && (acc + 15.0).abs() < 1e-6, "{t} {acc}");
        assert_eq!(d.code, "E0205");
        assert!(
            d.message.contains("at 0.5 s `a1` would have to brake at 15.0 m/s2 for `a0` (its limit is 8.0)"),
            "{}",
            d.message
        );
        assert!(
            d.help.as_deref().is_some_and(|h| h.starts_with("keep `a1` out of the way `a0` takes")),
            "{:?}",
            d.help
        );
        assert!(case(1.5, 1.2).is_none(), "1.2 m from the striker is not its doing");
        assert!(case(0.75, 0.5).is_none(), "7.5 m/s2 is within the limit");
    }
}
