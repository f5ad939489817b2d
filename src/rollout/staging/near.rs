//! Staged near misses (their pose alongside the passed box is `plan::alongside`, planned and
//! driven like a striker's contact pose): the passer's release back to its own route at the
//! pass, the gap between two boxes, their time to collision, and why a staging is refused
//! (E0195, E0189; across a path E0870, E0871).

use crate::diag::Diagnostic;
use crate::geom::Obb;
use crate::rollout::Tracks;
use crate::rollout::agent::{Actor, Conf, Near};
use crate::rollout::frame::Sim;
use crate::rollout::staging::plan;
use crate::rollout::staging::plan::Plan;
use glam::DVec2;

/// How far the measured least gap may be from the stated one, m.
pub const GAP_TOL_M: f64 = 0.15;
/// How far from the stated time the pass may come, s.
pub const TIME_TOL_S: f64 = 0.5;
/// How far the measured least time to collision may be from the stated one, s.
pub const TTC_TOL_S: f64 = 0.15;
/// Horizon of the time to collision, s.
const TTC_HORIZON_S: f64 = 6.0;

/// Constant-velocity time to collision of two boxes moving at `va` and `vb` without turning:
/// the first time their outlines meet, 0 where they overlap, infinite where they do not meet
/// within `TTC_HORIZON_S`. Two convex outlines first meet where a corner of one, moving at the
/// relative velocity, crosses an edge of the other.
pub fn box_ttc(a: &Obb, va: DVec2, b: &Obb, vb: DVec2) -> f64 {
    if a.overlaps(b) {
        return 0.0;
    }
    let r = va - vb;
    let (ca, cb) = (a.corners(), b.corners());
    let mut first = f64::INFINITY;
    for (ps, es, r) in [(&ca, &cb, r), (&cb, &ca, -r)] {
        for &p in ps {
            for i in 0..4 {
                let (u, e) = (es[i], es[(i + 1) % 4] - es[i]);
                let den = r.perp_dot(e);
                if den.abs() < 1e-12 {
                    continue;
                }
                let d = u - p;
                let (t, along) = (d.perp_dot(e) / den, d.perp_dot(r) / den);
                if t >= 0.0 && (0.0..=1.0).contains(&along) {
                    first = first.min(t);
                }
            }
        }
    }
    if first <= TTC_HORIZON_S { first } else { f64::INFINITY }
}

/// Distance between two boxes, 0 where they overlap: the least of each one's corners to the
/// other's edges (two convex polygons apart are nearest at a corner of one of them).
pub fn box_gap(a: &Obb, b: &Obb) -> f64 {
    if a.overlaps(b) {
        return 0.0;
    }
    let to_edges = |p: DVec2, o: &Obb| {
        let c = o.corners();
        (0..4)
            .map(|i| {
                let (u, w) = (c[i], c[(i + 1) % 4]);
                let t = ((p - u).dot(w - u) / (w - u).length_squared()).clamp(0.0, 1.0);
                p.distance(u + (w - u) * t)
            })
            .fold(f64::INFINITY, f64::min)
    };
    let ab = a.corners().iter().map(|&p| to_edges(p, b)).fold(f64::INFINITY, f64::min);
    let ba = b.corners().iter().map(|&p| to_edges(p, a)).fold(f64::INFINITY, f64::min);
    ab.min(ba)
}

/// Agent `i`'s box at frame `f` of the tracks.
fn box_at(out: &Tracks, i: usize, f: usize) -> Obb {
    let (p, s) = (out.poses[i][f], out.agents[i].size);
    Obb { center: DVec2::new(p.x, p.y), yaw: p.yaw, length: s[0], width: s[1] }
}

/// Of a measure per frame, the first least (frame, value) over the clip and the least within
/// `TIME_TOL_S` of `t_req`.
fn least_and_near(per_frame: &[f64], dt: f64, t_req: f64) -> ((usize, f64), f64) {
    let least =
        per_frame.iter().copied().enumerate().fold((0, f64::INFINITY), |m, (f, g)| if g < m.1 { (f, g) } else { m });
    let near = (0..per_frame.len())
        .filter(|&f| (f as f64 * dt - t_req).abs() <= TIME_TOL_S + 1e-9)
        .map(|f| per_frame[f])
        .fold(f64::INFINITY, f64::min);
    (least, near)
}

impl Sim<'_, '_> {
    /// At the pass the passer leaves its approach and drives its own route again, from where it
    /// is: its place along the route and its offset are taken from its pose (its approach left
    /// them where it departed), and its lateral goal brings it back to its lane.
    pub(crate) fn release(&mut self, k: usize) {
        let i = self.confs[k].af;
        self.latched[k] = true;
        let (path, st) = (&self.actors[i].path, self.next[i]);
        let mut s = st.s;
        for _ in 0..3 {
            let (q, h) = path.at(s);
            s += (st.pos - q).dot(DVec2::from_angle(h));
        }
        let foot = path.frenet(st.pos, s);
        self.next[i].s = foot.s;
        self.next[i].off = foot.d;
    }
}

/// Near misses that did not come off as stated, measured on the tracks: the least gap between
/// the pair over the clip below the stated gap by more than `GAP_TOL_M` (or contact), or no frame
/// within `TIME_TOL_S` of the stated time at which they pass within the gap and tolerance.
pub(crate) fn near_errors(
    actors: &[Actor],
    confs: &[Conf],
    plans: &[Option<Plan>],
    out: &Tracks,
    (dt, duration): (f64, f64),
) -> Vec<(usize, Diagnostic)> {
    let bx = |i: usize, f: usize| box_at(out, i, f);
    let mut errs = vec![];
    for (ki, k) in confs.iter().enumerate() {
        let gap = match k.near {
            Some(Near::Gap(gap)) => gap,
            Some(Near::Ttc(ttc) | Near::Across(ttc)) => {
                errs.extend(ttc_error(actors, k, plans[ki].is_some(), out, (dt, duration), ttc).map(|e| (ki, e)));
                continue;
            }
            None => continue,
        };
        let t_req = plan::requested_time(&k.c, dt, out.frames, duration);
        let gaps: Vec<f64> = (0..out.frames).map(|f| box_gap(&bx(k.af, f), &bx(k.st, f))).collect();
        let ((f_min, least), near_time) = least_and_near(&gaps, dt, t_req);
        let (a, b) = (&actors[k.af].info.name, &actors[k.st].info.name);
        let what = if plans[ki].is_none() {
            format!("`{a}` has no way to come alongside `{b}` near {t_req:.1} s")
        } else if least <= 0.0 {
            format!("they touch at {:.1} s", f_min as f64 * dt)
        } else if least < gap - GAP_TOL_M {
            format!("they come within {least:.2} m at {:.1} s", f_min as f64 * dt)
        } else if near_time > gap + GAP_TOL_M {
            format!("within {TIME_TOL_S} s of {t_req:.1} s they come no closer than {near_time:.2} m")
        } else {
            continue;
        };
        errs.push((
            ki,
            Diagnostic::error("E0195", format!("`{a}` passing `{b}` within {gap} m cannot be staged: {what}"))
                .label(k.c.span, format!("asks for a {gap} m pass at {t_req:.1} s"))
                .help(format!(
                    "`{a}` must be able to come level with `{b}` at that time within its limits, with room on that \
                     side: start them closer, give them speeds that bring them level, pick the other `side`, or move `at`"
                )),
        ));
    }
    errs
}

/// A `ttc` near miss that did not come off as stated: contact, a time to collision over the clip
/// below the stated one by more than `TTC_TOL_S`, or none within `TIME_TOL_S` of the stated time
/// down to the stated one and tolerance.
fn ttc_error(
    actors: &[Actor],
    k: &Conf,
    planned: bool,
    out: &Tracks,
    (dt, duration): (f64, f64),
    ttc: f64,
) -> Option<Diagnostic> {
    let bx = |i: usize, f: usize| box_at(out, i, f);
    let vel = |i: usize, f: usize| DVec2::from_angle(out.poses[i][f].yaw) * out.speeds[i][f];
    let t_req = plan::requested_time(&k.c, dt, out.frames, duration);
    let ttcs: Vec<f64> =
        (0..out.frames).map(|f| box_ttc(&bx(k.af, f), vel(k.af, f), &bx(k.st, f), vel(k.st, f))).collect();
    let ((f_min, least), near_time) = least_and_near(&ttcs, dt, t_req);
    let touch = (0..out.frames).find(|&f| bx(k.af, f).overlaps(&bx(k.st, f)));
    let (a, b) = (&actors[k.af].info.name, &actors[k.st].info.name);
    let across = matches!(k.near, Some(Near::Across(_)));
    if !planned && across && !actors[k.af].vehicle {
        return Some(
            Diagnostic::error("E0871", format!("`{a}` is not a vehicle and cannot close across `{b}`'s path by `ttc`"))
                .label(k.c.span, "the passer of a `ttc` near miss across a path")
                .help(format!(
                    "the passer of a close call across a path is the vehicle that closes and brakes: swap `passer` and \
                     `passed`, or pass `{b}` alongside with `gap`"
                )),
        );
    }
    let what = if !planned && across {
        format!(
            "`{a}` has no way along its route to close across `{b}`'s path to {ttc} s near {t_req:.1} s and stop short"
        )
    } else if !planned {
        format!("`{a}` has no way to close on `{b}` from behind near {t_req:.1} s")
    } else if let Some(f) = touch {
        format!("they touch at {:.1} s", f as f64 * dt)
    } else if least < ttc - TTC_TOL_S {
        format!("their time to collision falls to {least:.2} s at {:.1} s", f_min as f64 * dt)
    } else if near_time > ttc + TTC_TOL_S {
        format!("within {TIME_TOL_S} s of {t_req:.1} s their time to collision is no less than {near_time:.2} s")
    } else {
        return None;
    };
    if across {
        return Some(
            Diagnostic::error("E0870", format!("`{a}` closing across `{b}`'s path to {ttc} s to collision cannot be staged: {what}"))
                .label(k.c.span, format!("asks for a time to collision of {ttc} s at {t_req:.1} s"))
                .help(format!(
                    "`{a}` must be able to reach the place on its route where it would meet `{b}` in {ttc} s at that \
                     time within its limits, and brake hard from there to stop short of `{b}`'s path: give it a speed \
                     it can stop from within {ttc} s, start the two where their routes cross near that time, or move `at`"
                )),
        );
    }
    Some(
        Diagnostic::error("E0189", format!("`{a}` closing on `{b}` to {ttc} s to collision cannot be staged: {what}"))
            .label(k.c.span, format!("asks for a time to collision of {ttc} s at {t_req:.1} s"))
            .help(format!(
                "`{a}` must be able to come up behind `{b}` in its line, faster than it, at that time within its \
                 limits, and brake short of it: start it behind `{b}` in the same lane and faster, or move `at`"
            )),
    )
}
