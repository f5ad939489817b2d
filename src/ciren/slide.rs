//! Fixed objects struck on a slide. In: a crash some of whose objects are struck by a vehicle
//! after its earlier contact (`ObjectDesc::on_slide`: a car glancing off another into a pole).
//! Out: the staged text with each such object standing where the slide carries the striker's
//! coded face, the strike's `at` and `point` as the rolled-out boxes meet; or E0805 saying why no
//! place on the slide worked.
//!
//! The language does not stage a strike that follows an impact: the striker is no longer driven,
//! and the rollout measures where its slide takes it (E0199). So the staged contacts are staged
//! first, without those objects (`emit::stage_staged`); each slide is read off the tracks, and a
//! few places along it are tried in a fixed order, the object just ahead of the striker's coded
//! face where that face leads the motion. The first place whose contact lands on the coded face,
//! with no one else touching the object, is kept: deterministic, and never unverified.

use super::crash::{ConflictDesc, Crash, Face};
use super::emit::{Staged, Staging, conflict_times, contacts_on_sides, roll, stage_staged};
use crate::check::scenario::{Kind, Point};
use crate::diag::Diagnostic;
use crate::geom::Obb;
use crate::rollout::Tracks;
use glam::DVec2;
use std::collections::BTreeMap;

/// Emit, check and roll out `c`, keeping the first staging whose contacts land on their coded
/// sides and meet their coded force (`emit::stage_staged`), then place each party struck on a
/// slide, in time order. Deterministic; an error says what the last attempt did.
pub fn stage(c: &Crash) -> Result<Staged, Vec<Diagnostic>> {
    if !c.conflicts.iter().any(|k| c.on_slide(k)) {
        return stage_staged(c).map(|(s, _)| s);
    }
    let mut base = c.clone();
    base.conflicts.retain(|k| !c.on_slide(k));
    base.objects.retain(|o| !o.on_slide);
    base.vehicles.retain(|v| !v.on_slide);
    let (staged, adjusted) = stage_staged(&base)?;
    let st = staged.staging;
    let mut crash = c.clone();
    for v in adjusted.vehicles {
        let i = crash.vehicles.iter().position(|x| x.name == v.name).expect("the same vehicles");
        crash.vehicles[i] = v;
    }
    for i in 0..c.conflicts.len() {
        if c.on_slide(&c.conflicts[i]) {
            place(&mut crash, i, st)?;
        }
    }
    let (text, tracks) = roll(&crash, st)?.map(|(text, f)| (text, f.tracks)).map_err(|m| refuse(c, &m))?;
    let recs = contacts_on_sides(&crash, &tracks).map_err(|m| refuse(c, &m))?;
    Ok(Staged {
        text,
        staging: st,
        frame: recs[0].frame,
        time: recs[0].frame as f64 / tracks.rate,
        struck_side: recs[0].struck_side,
        shortfalls: staged.shortfalls,
    })
}

fn refuse(c: &Crash, why: &str) -> Vec<Diagnostic> {
    vec![
        Diagnostic::error(
            "E0805",
            format!("case {}: rocc could not stage its {} contacts: {why}", c.id, c.conflicts.len()),
        )
        .help("nothing is written for this case; `rocc explain E0805` lists what the staging can and cannot do"),
    ]
}

/// The crash up to conflict `i`: every staged conflict, the slide strikes before `i` (placed),
/// conflict `i` itself when `with_i`, and its object when `with_obj`.
fn upto(c: &Crash, i: usize, with_i: bool, with_obj: bool) -> Crash {
    let mut out = c.clone();
    let keep = |j: usize| !c.on_slide(&c.conflicts[j]) || j < i || (j == i && with_i);
    out.conflicts = (0..c.conflicts.len()).filter(|&j| keep(j)).map(|j| c.conflicts[j].clone()).collect();
    let obj = &c.conflicts[i].struck;
    let kept = |on_slide: bool, name: &str| {
        !on_slide || out.conflicts.iter().any(|k| k.struck == name) || (with_obj && name == obj)
    };
    let objects = c.objects.iter().filter(|o| kept(o.on_slide, &o.name)).cloned().collect();
    let vehicles = c.vehicles.iter().filter(|v| kept(v.on_slide, &v.name)).cloned().collect();
    (out.objects, out.vehicles) = (objects, vehicles);
    out
}

/// Place the object of slide strike `i` (its pose, the strike's time and struck side).
fn place(crash: &mut Crash, i: usize, st: Staging) -> Result<(), Vec<Diagnostic>> {
    let k = crash.conflicts[i].clone();
    let what = format!("{} where {}'s slide takes its {}", k.struck, k.at_fault, k.face.name());
    let before = upto(crash, i, false, false);
    let (_, front) = roll(&before, st)?.map_err(|m| refuse(crash, &format!("{what}: {m}")))?;
    let target = Target::of(crash, &k, &front.scenario.kinds);
    let t = front.tracks;
    let a = agent(&t, &k.at_fault).expect("the striker is an agent");
    // Its last contact before this strike: every conflict before `i` keeps its index here.
    let f0 = t.impacts.iter().filter(|r| r.conflict < i && (r.at_fault == a || r.struck == a)).map(|r| r.frame).max();
    let Some(f0) = f0 else {
        return Err(refuse(crash, &format!("{what}: {} has no contact before it", k.at_fault)));
    };
    let asked = conflict_times(&before, st);
    let mine = (0..i).filter(|&j| before.conflicts[j].at_fault == k.at_fault);
    let after = mine.map(|j| asked[j] + 0.1).fold(0.0, f64::max);
    let mut last = format!("its {} leads the slide at 1 m/s or more nowhere clear of the others", k.face.name());
    for pose in places(&t, a, f0, k.face, &target) {
        target.set(crash, Some(pose));
        let probe = upto(crash, i, false, true);
        let t = match roll(&probe, st)? {
            Ok((_, f)) => f.tracks,
            Err(m) => {
                last = m;
                continue;
            }
        };
        // Objects come first in the text: the indices shift once one is added.
        let (a, o) = (agent(&t, &k.at_fault).expect("an agent"), agent(&t, &k.struck).expect("an agent"));
        // The striker first, and no one else: it may touch again as it rebounds off a rigid object.
        let mut touching = t.contacts.iter().filter(|x| x.a == o || x.b == o);
        let Some(hit) = touching.next() else {
            last = "the slide passes it by".into();
            continue;
        };
        let by = |x: &crate::rollout::impact::Contact| if x.a == o { x.b } else { x.a };
        if let Some(x) = std::iter::once(hit).chain(touching).find(|x| by(x) != a) {
            last = format!("{} touches it too", t.agents[by(x)].name);
            continue;
        }
        let (ab, ob) = (obb(&t, a, hit.frame), obb(&t, o, hit.frame));
        let p = crate::rollout::contact_centroid(&ab, &ob).unwrap_or((ab.center + ob.center) / 2.0);
        let local = (p - ob.center).rotate(DVec2::from_angle(-ob.yaw));
        let side = crate::rollout::side_of(local, ob.length, ob.width);
        // A vehicle's struck side is coded; an object's is the one the slide reaches.
        if target.vehicle && side != k.point {
            last = format!("{} is struck on its {}, not its {}", k.struck, side.name(), k.point.name());
            continue;
        }
        // Written after the striker's earlier strikes, so no earlier than they are asked for
        // (E0196, E0121): the staged ones land within their window of it, sometimes before.
        let measured = (hit.frame as f64 / t.rate * 10.0).round() / 10.0;
        let mut trial = crash.clone();
        trial.conflicts[i].at = Some(measured.max(after));
        trial.conflicts[i].point = side;
        let check = upto(&trial, i, true, true);
        let r = roll(&check, st)?;
        match r {
            Ok((_, f)) => match contacts_on_sides(&check, &f.tracks) {
                Ok(_) => {
                    *crash = trial;
                    return Ok(());
                }
                Err(m) => last = m,
            },
            Err(m) => last = m,
        }
    }
    Err(refuse(crash, &format!("no place for {what}: {last}")))
}

/// What a slide strikes: an object, or a stopped vehicle on its coded side.
struct Target {
    name: String,
    vehicle: bool,
    /// Its box (length, width), the largest of its kind's sizes.
    size: (f64, f64),
    /// Half its depth along the slide, and the outward normal (its own frame) of the side that
    /// meets the striker.
    depth: f64,
    facing: DVec2,
}

impl Target {
    fn of(c: &Crash, k: &ConflictDesc, kinds: &BTreeMap<String, Kind>) -> Target {
        let vehicle = c.vehicles.iter().find(|v| v.name == k.struck);
        let kind = vehicle.map_or_else(
            || c.objects.iter().find(|o| o.name == k.struck).map(|o| o.kind.clone()).unwrap_or_default(),
            |v| v.kind.clone(),
        );
        // The largest box of its kind: the object is placed before it is sampled.
        let size = kinds.get(&kind).map_or((1.0, 1.0), |d| (d.length.hi(), d.width.hi()));
        // An object faces the striker with its front (a tree, a pole) or its long side (a wall,
        // a barrier, a building); a vehicle with its coded side.
        let facing = match (vehicle.is_some(), k.point) {
            (false, _) if size.0 > 2.0 * size.1 => DVec2::Y,
            (false, _) => DVec2::X,
            (true, Point::Rear | Point::RearLeft | Point::RearRight) => -DVec2::X,
            (true, Point::Left) => DVec2::Y,
            (true, Point::Right) => -DVec2::Y,
            (true, _) => DVec2::X,
        };
        let depth = if facing.x != 0.0 { size.0 / 2.0 } else { size.1 / 2.0 };
        Target { name: k.struck.clone(), vehicle: vehicle.is_some(), size, depth, facing }
    }
    fn set(&self, c: &mut Crash, at: Option<[f64; 3]>) {
        if let Some(v) = c.vehicles.iter_mut().find(|v| v.name == self.name) {
            v.at = at;
        } else if let Some(o) = c.objects.iter_mut().find(|o| o.name == self.name) {
            o.at = at;
        }
    }
}

fn agent(t: &Tracks, name: &str) -> Option<usize> {
    t.agents.iter().position(|x| x.name == name)
}

fn obb(t: &Tracks, i: usize, f: usize) -> Obb {
    let (p, s) = (t.poses[i][f], t.agents[i].size);
    Obb { center: DVec2::new(p.x, p.y), yaw: p.yaw, length: s[0], width: s[1] }
}

/// Places (x, y, heading) tried for an object of `kind` on agent `a`'s slide from frame `f0`:
/// 0.1 m into the middle of its `face` (deep enough to be a strike, not a graze) at frames where
/// it still slides at 1 m/s or more with that face leading the motion (within 78 deg), no
/// sooner than 0.2 s after the impact and no later than 2 s before the clip ends (the strike
/// lies inside the staged clip). The middle of those frames first, then a quarter either way,
/// then the ends. The object faces the striker: a tree or pole with its front, a wall or
/// barrier with its long side.
fn places(t: &Tracks, a: usize, f0: usize, face: Face, target: &Target) -> Vec<[f64; 3]> {
    let (hl, hw) = (t.agents[a].size[0] / 2.0, t.agents[a].size[1] / 2.0);
    let (at, normal) = match face {
        Face::Front => (DVec2::new(hl, 0.0), DVec2::X),
        Face::Back => (DVec2::new(-hl, 0.0), -DVec2::X),
        Face::Left => (DVec2::new(0.0, hw), DVec2::Y),
        Face::Right => (DVec2::new(0.0, -hw), -DVec2::Y),
    };
    let start = f0 + (0.2 * t.rate).round() as usize;
    let end = t.frames.saturating_sub(1 + (2.0 * t.rate).round() as usize);
    let mut ok = Vec::new();
    for f in start..end {
        let (p, q) = (t.poses[a][f], t.poses[a][f + 1]);
        let vel = DVec2::new(q.x - p.x, q.y - p.y) * t.rate;
        let speed = vel.length();
        if speed < 1.0 {
            continue;
        }
        let u = vel / speed;
        let rot = DVec2::from_angle(p.yaw);
        if rot.rotate(normal).dot(u) < 0.2 {
            continue;
        }
        let c = DVec2::new(p.x, p.y) + rot.rotate(at) + u * (target.depth - 0.1);
        let (length, width) = target.size;
        let heading = (-u).to_angle() - target.facing.to_angle();
        // Clear of everyone else over the whole clip by 0.1 m: the other party of the impact
        // often slides beside the striker.
        let me = Obb { center: c, yaw: heading, length: length + 0.2, width: width + 0.2 };
        let clear = (0..t.agents.len()).filter(|&j| j != a).all(|j| (0..t.frames).all(|g| !obb(t, j, g).overlaps(&me)));
        if clear {
            ok.push([c.x, c.y, heading]);
        }
    }
    let mut out: Vec<[f64; 3]> = Vec::new();
    for q in [0.5, 0.25, 0.75, 0.1, 0.9, 0.0, 0.4, 0.6] {
        let Some(n) = ok.len().checked_sub(1) else { break };
        let p = ok[(q * n as f64).round() as usize];
        if !out.contains(&p) {
            out.push(p);
        }
    }
    out
}
