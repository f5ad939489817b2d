//! Which vehicles' junction paths cross or merge, and the zone each pair shares (`Crossing`),
//! set up once; and who yields to an emergency vehicle (`Actor::yield_to`).

use crate::geom::Projector;
use crate::road::Map;
use crate::road::route::Junction;
use crate::rollout::agent::{Actor, Conf, Crossing, Drive};
use crate::rollout::junction::dry_run::sweep_entry;

/// Two junction paths whose headings at a shared stretch differ by less than about 26 degrees
/// run on together there (`Crossing::merge`).
pub(crate) const MERGE_COS: f64 = 0.9;

/// Two paths running the same way count as one merging into the other only where they come
/// this near: one lane (a ring a car enters), not two lanes side by side.
pub(crate) const JOIN_M: f64 = 1.0;

/// Whether two junction paths cross or merge: some point of one lies within `gap` of the other,
/// away from their shared start (two paths from the same lane diverge; they do not cross).
pub(crate) fn paths_cross(map: &Map, a: usize, b: usize, gap: f64) -> bool {
    let (ca, cb) = (&map.connectors[a], &map.connectors[b]);
    if ca.from == cb.from {
        return false;
    }
    let (la, lb) = (ca.path.length(), cb.path.length());
    let n = (la / 0.5).ceil().max(1.0) as usize;
    let on_b = Projector::new(&cb.path);
    let mut hint = 0;
    (0..=n).any(|k| {
        // Farther than `gap` fails the test below in any case.
        let p = ca.path.point_at(la * k as f64 / n as f64);
        on_b.project_within(p, &mut hint, gap).is_ok_and(|(s, d)| s > -0.5 && s < lb + 0.5 && d.abs() < gap)
    })
}

/// Fill every agent's `yield_to`: the emergency vehicles whose junction path crosses its own.
/// Emergency vehicles and staged conflict agents (their goal is the crash) do not yield.
pub(crate) fn assign_yields(map: &Map, actors: &mut [Actor], confs: &[Conf]) {
    let em: Vec<usize> = (0..actors.len())
        .filter(|&e| actors[e].emergency && matches!(actors[e].drive, Drive::Mover) && actors[e].junction.is_some())
        .collect();
    if em.is_empty() {
        return;
    }
    for i in 0..actors.len() {
        let a = &actors[i];
        let Some(ji) = a.junction else { continue };
        if a.emergency || !a.vehicle || !matches!(a.drive, Drive::Mover) || confs.iter().any(|k| k.af == i || k.st == i)
        {
            continue;
        }
        let ys: Vec<usize> = em
            .iter()
            .copied()
            .filter(|&e| {
                let je = actors[e].junction.map(|j| j.conn).unwrap_or(ji.conn);
                paths_cross(map, ji.conn, je, a.hw + actors[e].hw + 0.5)
            })
            .collect();
        actors[i].yield_to = ys;
    }
}

/// Fill every vehicle's `crossings`: the other vehicles whose first junction path crosses or
/// merges into its own, with the zone each would share. Emergency vehicles and those yielding to
/// them are settled by `yield_to`; the two agents of a staged conflict are meant to meet. Marks
/// the conflict agents, and drops the kerb wait of a walker in a staged conflict.
pub(crate) fn assign_crossings(map: &Map, actors: &mut [Actor], confs: &[Conf]) {
    for k in confs {
        for x in [k.af, k.st] {
            actors[x].in_conflict = true;
            actors[x].kerb = None;
        }
    }
    let js: Vec<usize> = (0..actors.len())
        .filter(|&i| actors[i].vehicle && matches!(actors[i].drive, Drive::Mover) && actors[i].junction.is_some())
        .collect();
    // Many agents share a connector (background traffic on one lane): each pair of connectors
    // is sampled once.
    let mut profiles = std::collections::HashMap::new();
    let mut zones_of: std::collections::HashMap<(usize, usize, u64, u64), Zones> = std::collections::HashMap::new();
    // `sweep_entry` reads the sweep, the other's box size and its route's points from `lo` to
    // `hi`: where those points are its route's shared samples, agents on one route with one
    // sweep ask the same question.
    let mut entries: std::collections::HashMap<[u64; 6], Option<f64>> = std::collections::HashMap::new();
    let mut entry_of = |a: &Actor, b: &Actor, lo: f64, hi: f64| -> Option<f64> {
        let (Some(bend), Some(grid)) = (&a.bend, b.path.shared_upto(hi)) else { return sweep_entry(a, b, lo, hi) };
        let key = [
            std::sync::Arc::as_ptr(bend) as usize as u64,
            grid as u64,
            b.hl.to_bits(),
            b.hw.to_bits(),
            lo.to_bits(),
            hi.to_bits(),
        ];
        *entries.entry(key).or_insert_with(|| sweep_entry(a, b, lo, hi))
    };
    for (n, &i) in js.iter().enumerate() {
        for &j in &js[n + 1..] {
            let (a, b) = (&actors[i], &actors[j]);
            let (Some(ji), Some(jj)) = (a.junction, b.junction) else { continue };
            let emergency = a.yield_to.contains(&j) || b.yield_to.contains(&i);
            if confs.iter().any(|k| (k.af == i && k.st == j) || (k.af == j && k.st == i)) {
                continue;
            }
            // A long box swings wide of its path in a turn (a bus's front corner sweeps into the
            // next lane): the zone widens by each box's off-tracking.
            let gap = a.hw + b.hw + 0.5 + off_tracking(a) + off_tracking(b);
            let mut zones = |x: usize, y: usize, join: f64| {
                // A pure function of these (the profile's samples within `gap` are the same
                // whatever reach it was taken to): pairs of agents on the same connectors share it.
                let key = (x, y, gap.to_bits(), join.to_bits());
                zones_of
                    .entry(key)
                    .or_insert_with(|| shared_zones(map, (x, y), profile(&mut profiles, map, x, y, gap), gap, join))
                    .clone()
            };
            let za = zones(ji.conn, jj.conn, 2.0 * a.hl);
            let zb = zones(jj.conn, ji.conn, 2.0 * b.hl);
            let entry = |j: Junction| j.exit - map.connectors[j.conn].path.length();
            let (ei, ej) = (entry(ji), entry(jj));
            let (hi, hj) = (a.hl, b.hl);
            let first = actors[i].crossings.len();
            // Each stretch of ours goes with the stretch of theirs that its middle lies beside.
            for &(ai, ao, at, closest) in &za {
                let dist = |z: &(f64, f64, f64, f64)| (z.0 - at).max(at - z.1).max(0.0);
                let Some(&(bi, bo, ..)) = zb.iter().min_by(|x, y| dist(x).total_cmp(&dist(y))) else { continue };
                let (_, ha) = map.connectors[ji.conn].path.pose_at(0.5 * (ai + ao));
                let (_, hb) = map.connectors[jj.conn].path.pose_at(at);
                // Run on together: the same way, and into one lane. Two turning the same way
                // from side by side lanes into side by side lanes run the same way but apart,
                // and a long one's swing reaches over the other's lane: car-following along
                // our path does not see one in the next lane (a bus turning right behind a
                // sedan turning right beside it met the sedan's tail), so the two take turns.
                let merge = (ha - hb).cos() > MERGE_COS && closest < JOIN_M;
                let ci = Crossing {
                    other: j,
                    enter: ei + ai - hi,
                    leave: ei + ao + hi,
                    other_enter: ej + bi - hj,
                    other_leave: ej + bo + hj,
                    meet: ei + ai - hi,
                    other_meet: ej + bi - hj,
                    placed_yield: None,
                    emergency,
                    merge,
                };
                let cj = Crossing {
                    other: i,
                    enter: ci.other_enter,
                    leave: ci.other_leave,
                    other_enter: ci.enter,
                    other_leave: ci.leave,
                    meet: ci.other_meet,
                    other_meet: ci.meet,
                    placed_yield: None,
                    emergency,
                    merge,
                };
                actors[i].crossings.push(ci);
                actors[j].crossings.push(cj);
            }
            // Where one's sweep reaches over the other's approach short of their first shared
            // stretch, that stretch begins there for the other (it holds clear of the loop).
            let n_new = actors[i].crossings.len() - first;
            if n_new > 0 {
                let kj0 = actors[j].crossings.len() - n_new;
                // Ours moved back to their sweep, then theirs to ours.
                for ours in [true, false] {
                    let pick = |c: &Crossing| if ours { c.enter } else { c.other_enter };
                    let (sweeper, mover, lo) =
                        if ours { (j, i, ei - 2.0 * hi - 20.0) } else { (i, j, ej - 2.0 * hj - 20.0) };
                    let cs = &actors[i].crossings;
                    let Some(k) = (first..first + n_new).min_by(|&x, &y| pick(&cs[x]).total_cmp(&pick(&cs[y]))) else {
                        continue;
                    };
                    let Some(s) = entry_of(&actors[sweeper], &actors[mover], lo, pick(&cs[k])) else { continue };
                    let kj = kj0 + k - first;
                    if ours {
                        actors[i].crossings[k].enter = s;
                        actors[j].crossings[kj].other_enter = s;
                    } else {
                        actors[i].crossings[k].other_enter = s;
                        actors[j].crossings[kj].enter = s;
                    }
                }
            }
        }
    }
    for &i in &js {
        actors[i].approach = actors[i].junction.map(|j| map.connectors[j.conn].from);
    }
}

/// How far `a`'s box reaches out of its path's lane band anywhere through its junction
/// (`Bend::widest`).
pub(crate) fn off_tracking(a: &Actor) -> f64 {
    a.bend.as_ref().map_or(0.0, |b| b.widest)
}

/// Connector `a` sampled every half metre against connector `b`'s path: arc length along `a`,
/// distance to `b` (infinite where the nearest point is beyond `b`'s ends, or where the two leave
/// the same lane: paths from one lane diverge, they do not cross), arc length along `b`. Taken
/// for `shared_zones`' test `distance < gap`: a distance beyond the profile's reach (at least
/// the gap asked for) reads infinite, its arc length NaN, as do paths from one lane.
pub(crate) type Profile = Vec<(f64, f64, f64)>;

/// The reach of a profile at least: wider than two cars' gap on bends (~3 m), so one profile
/// per pair of connectors serves most pairs of agents on them; a wider gap (a long vehicle's
/// off-tracking) recomputes it. Farther samples cost a bounding-box test, nearer ones a scan.
pub(crate) const PROFILE_REACH: f64 = 4.0;

pub(crate) fn profile<'p>(
    cache: &'p mut std::collections::HashMap<(usize, usize), (f64, Profile)>,
    map: &Map,
    a: usize,
    b: usize,
    gap: f64,
) -> &'p Profile {
    let entry = cache.entry((a, b)).or_insert((f64::NEG_INFINITY, vec![]));
    // Only the samples within the reach are projected; farther ones fail the test anyway.
    let covers = entry.0 >= gap;
    if !covers {
        let reach = gap.max(PROFILE_REACH);
        let (ca, cb) = (&map.connectors[a], &map.connectors[b]);
        let (la, lb) = (ca.path.length(), cb.path.length());
        let n = (la / 0.5).ceil().max(1.0) as usize;
        let on_b = Projector::new(&cb.path);
        let mut hint = 0;
        let (strict, mut seg) = (ca.path.strictly_increasing(), None);
        // A sample `x` along `a` from one at `floor` from `b` lies at least `floor - x` from it:
        // the samples up to where that reaches within `reach` (a margin short) are not taken.
        let mut far_until = f64::NEG_INFINITY;
        let samples = (0..=n)
            .map(|k| {
                let sa = la * k as f64 / n as f64;
                // Paths from one lane diverge: they do not cross.
                if ca.from == cb.from || sa < far_until {
                    return (sa, f64::INFINITY, f64::NAN);
                }
                let (s, d) = match on_b.project_within(ca.path.point_at_walk(sa, &mut seg, strict), &mut hint, reach) {
                    Ok(x) => x,
                    Err(floor) => {
                        far_until = sa + (floor - reach - 0.01);
                        return (sa, f64::INFINITY, f64::NAN);
                    }
                };
                let near = s > -0.5 && s < lb + 0.5;
                (sa, if near { d.abs() } else { f64::INFINITY }, s)
            })
            .collect();
        *entry = (reach, samples);
    }
    &entry.1
}

/// `shared_zones`' answer: per stretch, its first and last arc length, where its middle
/// projects onto the other connector, and how near the other path comes within it.
pub(crate) type Zones = Vec<(f64, f64, f64, f64)>;

/// The stretches of connector `a` (arc lengths along it) whose samples in `profile` lie within
/// `gap` of the other path, those less than `join` apart taken as one; with each, where its
/// middle projects onto `b`. Two paths can meet twice (a roundabout exit beside
/// another's entry, then the ring).
pub(crate) fn shared_zones(map: &Map, (a, b): (usize, usize), profile: &Profile, gap: f64, join: f64) -> Zones {
    let mut zones: Zones = vec![];
    for &(sa, d, _) in profile {
        if d < gap {
            match zones.last_mut() {
                Some(z) if sa - z.1 <= join => {
                    z.1 = sa;
                    z.3 = z.3.min(d);
                }
                _ => zones.push((sa, sa, 0.0, d)),
            }
        }
    }
    for z in &mut zones {
        // `pose_at`'s point, without the heading's arctangent.
        let p = map.connectors[a].path.point_at(0.5 * (z.0 + z.1));
        z.2 = map.connectors[b].path.project(p).0;
    }
    zones
}
