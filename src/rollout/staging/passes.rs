//! The rollout's passes: set up, pass 1 (everyone's natural motion), the staging plans chosen
//! from it, pass 2 (the strikers on their intercepts), planned again where a staging fails.

use crate::check::scenario::{Conflict, Impact, Point};
use crate::diag::Diagnostic;
use crate::geom::{Obb, wrap_angle};
use crate::place::Placed;
use crate::road::Map;
use crate::rollout::Tracks;
use crate::rollout::agent::{Actor, Conf, Near, State, initial};
use crate::rollout::frame::{HardStop, Sim, empty_tracks};
use crate::rollout::junction::dry_run::assign_bends;
use crate::rollout::junction::order::order_crossings;
use crate::rollout::junction::zones::{assign_crossings, assign_yields};
use crate::rollout::setup::{Routes, background_actor, build_actor, face_the_striker};
use crate::rollout::staging::near::near_errors;
use crate::rollout::staging::plan;
use crate::rollout::staging::plan::Plan;
use crate::rollout::staging::refusals::{forced_braking, forced_error, staging_errors, stopped_dead};
use crate::rollout::staging::{across, follow};
use crate::rollout::traffic;
use crate::rollout::turn_check::check_turns;
use crate::sample::Concrete;
use glam::DVec2;

pub(crate) fn run(c: &Concrete, map: &Map, placed: &Placed) -> Result<Tracks, Vec<Diagnostic>> {
    // Concrete agent index -> track index.
    let mut track_of = vec![None; c.agents.len()];
    for (i, p) in placed.agents.iter().enumerate() {
        if let Some(src) = p.source
            && src < track_of.len()
            && track_of[src].is_none()
        {
            track_of[src] = Some(i);
        }
    }
    let mut errs = vec![];
    // One resampling per distinct route (start lane, turn), shared by every agent on it.
    let mut routes = Routes::new();
    let mut actors: Vec<Actor> =
        placed.agents.iter().map(|p| build_actor(c, map, p, &track_of, &mut routes, &mut errs)).collect();
    if !errs.is_empty() {
        return Err(errs);
    }
    if let Some(t) = c.traffic {
        let boxes: Vec<(Obb, f64)> = actors.iter().map(|a| (a.obb(&initial(a)), initial(a).v)).collect();
        for s in traffic::spawn(map, &boxes, t, c.seed) {
            actors.push(background_actor(map, s, c.duration, &mut routes));
        }
    }
    crate::rollout::drive::slow::measure_rooms(map, &mut actors);
    let frames = c.frame_count();
    let dt = if c.rate > 0.0 { 1.0 / c.rate } else { 0.1 };
    let (mut confs, mut follows) = (vec![], vec![]);
    let pairs: Vec<Option<(usize, usize)>> = c
        .conflicts
        .iter()
        .map(|k| match (track_of.get(k.at_fault), track_of.get(k.struck)) {
            (Some(Some(af)), Some(Some(st))) if af != st => Some((*af, *st)),
            _ => None,
        })
        .collect();
    let when = |k: &Conflict| plan::requested_time(k, dt, frames, c.duration);
    for (index, k) in c.conflicts.iter().enumerate() {
        let Some((af, st)) = pairs[index] else { continue };
        let conf = Conf { index, af, st, c: k.clone(), near: None };
        // A striker already moving on from an earlier impact is not driven to this one.
        if follow::follows_an_impact(&c.conflicts, &pairs, index, when) {
            follows.push(conf);
        } else if !confs.iter().any(|x: &Conf| x.af == af) {
            confs.push(conf);
        }
    }
    confs.extend(near_confs(c, &actors, &track_of));
    for k in confs.iter().filter(|k| k.near.is_none()) {
        face_the_striker(&mut actors, k);
    }
    assign_bends(map, &mut actors, dt);
    assign_yields(map, &mut actors, &confs);
    assign_crossings(map, &mut actors, &confs);
    crate::rollout::junction::signals::assign_signals(map, &mut actors);
    crate::rollout::flagger::assign_flaggers(&c.flaggers, map, &mut actors, &track_of, &mut errs);
    order_crossings(&mut actors, &mut errs);
    if !errs.is_empty() {
        return Err(errs);
    }
    let masses = stated_masses(c, placed, actors.len());
    let mut out = empty_tracks(&actors, c.rate, frames);
    if confs.is_empty() {
        Sim::new(&actors, &confs, &[], None, dt).masses(&masses).follows(&follows).run(&mut out);
    } else {
        let mut pass1 = empty_tracks(&actors, c.rate, frames);
        let mut states = Vec::with_capacity(frames);
        Sim::new(&actors, &confs, &[], None, dt)
            .masses(&masses)
            .follows(&follows)
            .keep_states(&mut states)
            .run(&mut pass1);
        // A staging that misses or lands elsewhere than asked, or that has the overlap safety
        // net stop someone dead, is planned again away from the impact times tried (the plan
        // nearest the request may be the one a bystander spoils), up to `RESTAGE` times. The
        // first attempt that lands every crash as asked with everyone inside their limits is
        // kept; if none does, the first attempt (the plans nearest the request) stands: its
        // tracks, or its errors.
        let mut avoid: Vec<Vec<f64>> = vec![Vec::new(); confs.len()];
        // The first attempt's tracks (only where they are the answer should nothing do
        // better: its crashes landed) and its errors.
        let (mut first_tracks, mut first_failed, mut first_hard, mut first_forced) = (None, Vec::new(), None, None);
        let mut plans: Vec<Option<Plan>> =
            confs.iter().map(|k| choose(k, &actors, &pass1, (dt, c.duration), &[])).collect();
        for attempt in 0..=RESTAGE {
            // Pass 2 is pass 1 until a planned striker departs or a planned pair first
            // overlaps: those frames are copied, not simulated again.
            let start = pass2_start(&actors, &confs, &plans, &states, dt);
            out = empty_tracks(&actors, c.rate, frames);
            let report = Sim::new(&actors, &confs, &plans, Some(&pass1), dt)
                .masses(&masses)
                .follows(&follows)
                .resume(&pass1, &states, start)
                .run(&mut out);
            let mut failed =
                staging_errors(&actors, &confs, &plans, &out, &report.blocked_by, (dt, frames, c.duration));
            failed.extend(near_errors(&actors, &confs, &plans, &out, (dt, c.duration)));
            let forced = forced_braking(&actors, &confs, &plans, &out);
            if failed.is_empty() && report.first_hard.is_none() && forced.is_none() {
                break;
            }
            // Plan again the conflicts that failed; where none did, every one.
            let redo: Vec<usize> =
                if failed.is_empty() { (0..confs.len()).collect() } else { failed.iter().map(|f| f.0).collect() };
            if attempt == 0 {
                first_tracks = failed.is_empty().then(|| out.clone());
                first_failed = failed;
                first_hard = report.first_hard;
                first_forced = forced;
            }
            let mut replanned = false;
            if attempt < RESTAGE {
                for ki in redo {
                    let Some(tried) = plans[ki].as_ref().map(|p| p.t_impact) else { continue };
                    avoid[ki].push(tried);
                    if let Some(p) = choose(&confs[ki], &actors, &pass1, (dt, c.duration), &avoid[ki]) {
                        plans[ki] = Some(p);
                        replanned = true;
                    }
                }
            }
            if !replanned {
                // Landed, but only with the safety net stopping one of a staged pair dead: the
                // crash is not driven within the limits (a motorcycle striker's intercept ran
                // through a car standing at its line, and it was stopped from 19.8 m/s).
                let pair_stopped = first_hard.and_then(|HardStop { agent: k, other, t }| {
                    confs.iter().position(|c| c.af == k || c.st == k).map(|ki| (ki, k, other, t))
                });
                match (first_tracks, pair_stopped, first_forced) {
                    (Some(_), Some((ki, k, other, t)), _) => errs.push(stopped_dead(&actors, &confs[ki], k, other, t)),
                    (Some(_), None, Some(f)) => errs.push(forced_error(&actors, &confs, f)),
                    (Some(tracks), None, None) => out = tracks,
                    (None, ..) => {}
                }
                errs.extend(first_failed.into_iter().map(|(_, d)| d));
                break;
            }
        }
    }
    if errs.is_empty() {
        errs.extend(follow::measure(&actors, &follows, &mut out, (dt, frames, c.duration)));
    }
    check_turns(map, &actors, &confs, &out, &mut errs);
    if !errs.is_empty() {
        return Err(errs);
    }
    Ok(out)
}

/// The near misses as staged approaches: each passer comes alongside its passed agent like a
/// striker to its contact pose (`plan::alongside`), on the stated side or the one it starts on,
/// or closes to the stated time to collision: on its rear where it starts behind it in its
/// line (`plan::behind`), across its path otherwise (`across`).
fn near_confs(c: &Concrete, actors: &[Actor], track_of: &[Option<usize>]) -> Vec<Conf> {
    let mut confs = vec![];
    for (index, n) in c.near_misses.iter().enumerate() {
        let (Some(Some(af)), Some(Some(st))) = (track_of.get(n.passer), track_of.get(n.passed)) else { continue };
        let (a, b) = (initial(&actors[*af]), initial(&actors[*st]));
        let point = n.side.unwrap_or_else(|| plan::start_side(a.pos, b.pos, b.yaw));
        let behind = in_line_behind(&actors[*af], a, &actors[*st], b);
        let (impact, point) = match n.ttc {
            Some(_) if behind => (Impact::RearEnd, Point::Rear),
            Some(_) => (Impact::Angle, point),
            None => (Impact::Sideswipe, point),
        };
        let k = Conflict {
            at_fault: n.passer,
            struck: n.passed,
            impact,
            point,
            at: n.at,
            after: Default::default(),
            span: n.span,
        };
        let ttc = n.ttc.map(|t| if behind { Near::Ttc(t) } else { Near::Across(t) });
        let Some(near) = ttc.or(n.gap.map(Near::Gap)) else { continue };
        confs.push(Conf { index, af: *af, st: *st, c: k, near: Some(near) });
    }
    confs
}

/// Whether the passer starts behind the passed agent, in its line and heading its way (within
/// 30 degrees), as a `ttc` near miss from behind asks; elsewhere it closes across its path.
fn in_line_behind(pa: &Actor, a: State, pb: &Actor, b: State) -> bool {
    let rel = (a.pos - b.pos).rotate(DVec2::from_angle(-b.yaw));
    rel.x < 0.0 && rel.y.abs() < pa.hw + pb.hw && wrap_angle(a.yaw - b.yaw).abs() < 30f64.to_radians()
}

/// The plan of staging `k` from pass 1: a near miss across a path has its own (`across`).
fn choose(k: &Conf, actors: &[Actor], p1: &Tracks, (dt, duration): (f64, f64), avoid: &[f64]) -> Option<Plan> {
    match k.near {
        Some(Near::Across(_)) => across::choose(k, actors, p1, (dt, duration), avoid),
        _ => plan::choose(k, actors, p1, dt, duration, avoid),
    }
}

/// The mass each track's agent states, if any (background traffic states none).
fn stated_masses(c: &Concrete, placed: &Placed, tracks: usize) -> Vec<Option<f64>> {
    let mut m = vec![None; tracks];
    for (i, p) in placed.agents.iter().enumerate().take(tracks) {
        m[i] = p.source.and_then(|s| c.agents.get(s)).and_then(|a| a.mass);
    }
    m
}

/// How many times a staging that fails is planned again (`plan::choose` away from the impact
/// times already tried) before E0205.
pub(crate) const RESTAGE: usize = 3;

/// The first frame at which pass 2 can differ from pass 1: the first whose step starts at or
/// after a planned striker's departure (`Sim::step`), or an earlier one at which a planned pair
/// overlaps (`Sim::latch` looks at those). Before it both passes run the same steps on the same
/// states, so pass 2 resumes from pass 1's state there.
pub(crate) fn pass2_start(
    actors: &[Actor],
    confs: &[Conf],
    plans: &[Option<Plan>],
    states: &[Vec<State>],
    dt: f64,
) -> usize {
    let frames = states.len();
    let mut start = frames.max(1);
    for (k, plan) in confs.iter().zip(plans).filter_map(|(k, p)| p.as_ref().map(|p| (k, p))) {
        // The same test as `Sim::step`, frame by frame, so the float comparison is the same one.
        if let Some(f) = (1..frames).find(|&f| (f - 1) as f64 * dt >= plan.t_depart - 1e-9) {
            start = start.min(f);
        }
        if let Some(f) = (1..start).find(|&f| {
            let s = &states[f];
            actors[k.af].obb(&s[k.af]).overlaps(&actors[k.st].obb(&s[k.st]))
        }) {
            start = start.min(f);
        }
    }
    start
}
