//! Strikes that follow an impact: a conflict whose at-fault agent has already struck, or been
//! struck, at an earlier time (tests/impact/suv-glances-off-sedan-strikes-pole.scn). From that
//! impact on the agent is not driven, so no intercept is planned for it: the motion after the
//! impact brings it to its next contact, which is resolved with the conflict's coefficients
//! (`Sim::follows`) and measured here like a staged one, on the struck agent's stated side.

use crate::check::scenario::Conflict;
use crate::diag::Diagnostic;
use crate::geom::Obb;
use crate::rollout::agent::{Actor, Conf};
use crate::rollout::staging::plan;
use crate::rollout::{ImpactRecord, Tracks};
use glam::DVec2;

/// Whether conflict `k` follows an impact: its at-fault agent (track `af`) is in another
/// contact conflict asked for strictly earlier. `tracks` maps each conflict to its pair.
pub(crate) fn follows_an_impact(
    conflicts: &[Conflict],
    tracks: &[Option<(usize, usize)>],
    k: usize,
    when: impl Fn(&Conflict) -> f64,
) -> bool {
    let Some((af, _)) = tracks[k] else { return false };
    let t = when(&conflicts[k]);
    conflicts
        .iter()
        .zip(tracks)
        .enumerate()
        .any(|(j, (c, p))| j != k && p.is_some_and(|(a, s)| a == af || s == af) && when(c) < t)
}

/// Records each follow-on conflict's contact as its impact, or E0199 where the motion does not
/// bring the pair together within `plan::WINDOW_S` of the asked time, or brings them together
/// on another side of the struck agent than the one stated.
pub(crate) fn measure(
    actors: &[Actor],
    follows: &[Conf],
    out: &mut Tracks,
    (dt, frames, duration): (f64, usize, f64),
) -> Vec<Diagnostic> {
    let mut errs = vec![];
    for k in follows {
        let t_req = plan::requested_time(&k.c, dt, frames, duration);
        let (a, b) = (&actors[k.af].info.name, &actors[k.st].info.name);
        let met = out.contacts.iter().find(|c| c.conflict == Some(k.index)).map(|c| c.frame);
        let what = match met {
            None => format!("they never touch: the motion after `{a}`'s earlier impact does not bring it to `{b}`"),
            Some(f) if (f as f64 * dt - t_req).abs() > plan::WINDOW_S + 0.5 * dt => {
                format!("they touch at {:.1} s, not within {:.1} s of {t_req:.1} s", f as f64 * dt, plan::WINDOW_S)
            }
            Some(f) => {
                let rec = record(k, f, out);
                // An object is not turned to face this striker (it is not staged), so its
                // side is measured as stated too.
                if rec.struck_side == k.c.point {
                    out.impacts.push(rec);
                    continue;
                }
                format!(
                    "at {:.1} s `{b}` is struck on its {}, not its {}",
                    f as f64 * dt,
                    rec.struck_side.name(),
                    k.c.point.name()
                )
            }
        };
        errs.push(
            Diagnostic::error("E0199", format!("the strike of `{a}` on `{b}` does not happen as asked: {what}"))
                .label(k.c.span, "a strike that follows an earlier impact")
                .help(format!(
                    "`{a}` is not driven after its earlier impact; it slides to rest: start `{b}` where that slide \
                     reaches it, change the earlier crash (speed, side, time), or move `at` to when they meet"
                )),
        );
    }
    errs
}

/// The impact record of a follow-on contact at frame `f`, measured on the boxes there.
fn record(k: &Conf, f: usize, out: &Tracks) -> ImpactRecord {
    let bx = |x: usize| {
        let (p, s) = (out.poses[x][f], out.agents[x].size);
        Obb { center: DVec2::new(p.x, p.y), yaw: p.yaw, length: s[0], width: s[1] }
    };
    let (a, b) = (bx(k.af), bx(k.st));
    let p = plan::contact_centroid(&a, &b).unwrap_or((a.center + b.center) / 2.0);
    let local = |o: &Obb| {
        let q = (p - o.center).rotate(DVec2::from_angle(-o.yaw));
        [q.x, q.y]
    };
    let sl = local(&b);
    ImpactRecord {
        conflict: k.index,
        frame: f,
        at_fault: k.af,
        struck: k.st,
        point_world: [p.x, p.y],
        at_fault_local: local(&a),
        struck_local: sl,
        struck_side: plan::side_of(DVec2::new(sl[0], sl[1]), b.length, b.width),
        depth: plan::depth(&a, &b),
    }
}
