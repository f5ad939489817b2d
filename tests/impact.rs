//! Motion after an impact, measured on the rolled-out boxes, not with the impact code's own
//! geometry (as `support/contact.rs` measures staged contacts): across each impact of two
//! moving bodies the momentum, from the poses just before and after and the masses the file
//! states, is conserved; each staged impact lands on its stated sides; boxes overlap only in
//! the short window around a contact; and everyone comes to rest with no two boxes overlapping.
//! Scenes: tests/impact/ (a three-vehicle chain, a five-vehicle pile-up, a car glancing off
//! another into a pole).

#[path = "support/contact.rs"]
mod contact;
#[path = "support/front.rs"]
mod front;

use contact::{measured_contact, obb, sector};
use front::front_of;
use glam::DVec2;
use rocc::check::scenario::{Impact, Point};
use rocc::compile::Front;
use rocc::rollout::Tracks;

/// The documented physics: gravity, the tyre friction a sliding body decelerates at, and the
/// window within which two bodies that met must be apart again (docs/rollout.md).
const G: f64 = 9.81;
const TYRE_MU: f64 = 0.7;
const WINDOW_S: f64 = 0.5;

fn scene(name: &str) -> Front {
    front_of(&std::fs::read_to_string(format!("tests/impact/{name}")).expect("scene"))
}

fn scenes() -> Vec<(String, Front)> {
    let mut names: Vec<String> = std::fs::read_dir("tests/impact")
        .expect("scenes")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".scn"))
        .collect();
    names.sort();
    assert!(names.len() >= 3, "the impact scenes are missing");
    names.into_iter().map(|n| (n.clone(), scene(&n))).collect()
}

/// The mass each track's agent states in the file (`None` for objects).
fn masses(f: &Front) -> Vec<Option<f64>> {
    f.tracks.agents.iter().map(|a| f.scenario.agents.iter().find(|s| s.name == a.name).and_then(|s| s.mass)).collect()
}

fn pos(t: &Tracks, a: usize, f: usize) -> DVec2 {
    DVec2::new(t.poses[a][f].x, t.poses[a][f].y)
}

fn vel(t: &Tracks, a: usize, f: usize) -> DVec2 {
    (pos(t, a, f + 1) - pos(t, a, f)) * t.rate
}

/// Contacts measured on the boxes: every frame at which two boxes overlap.
fn overlapping(t: &Tracks, f: usize) -> Vec<(usize, usize)> {
    let n = t.agents.len();
    (0..n)
        .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
        .filter(|&(a, b)| obb(t, a, f).overlaps(&obb(t, b, f)))
        .collect()
}

/// Across each impact of two moving bodies, the momentum of every moving body in the crash so
/// far (a body pressed on by another inside a contact's window takes part in the exchange) is
/// conserved but for the tyres' friction, the only outside force; impacts beside one with an
/// immovable body (a pole) are left out.
#[test]
fn momentum_is_conserved_across_each_impact() {
    for (name, f) in scenes() {
        let (t, m) = (&f.tracks, masses(&f));
        let dt = 1.0 / t.rate;
        let window = (WINDOW_S * t.rate).round() as usize + 1;
        let mut checked = 0;
        for c in &t.contacts {
            let g = c.frame;
            if m[c.a].is_none() || m[c.b].is_none() || g == 0 || g + 1 >= t.frames {
                continue;
            }
            let crash: Vec<usize> =
                (0..t.agents.len()).filter(|&x| m[x].is_some() && t.first_contact(x).is_some_and(|h| h <= g)).collect();
            let immovable_near = t.contacts.iter().any(|o| {
                (m[o.a].is_none() || m[o.b].is_none())
                    && o.frame + window >= g
                    && o.frame <= g + 1
                    && (crash.contains(&o.a) || crash.contains(&o.b))
            });
            if immovable_near {
                continue;
            }
            assert!(obb(t, c.a, g).overlaps(&obb(t, c.b, g)), "{name}: no contact at frame {g}");
            let p = |f: usize| crash.iter().map(|&x| vel(t, x, f) * m[x].expect("mass")).sum::<DVec2>();
            let (before, after) = (p(g - 1), p(g));
            let mb = m[c.b].expect("mass");
            let exchanged = (vel(t, c.b, g) - vel(t, c.b, g - 1)).length() * mb;
            let friction = crash.iter().map(|&x| m[x].expect("mass")).sum::<f64>() * TYRE_MU * G * dt;
            let tol = friction + 0.02 * before.length();
            assert!(
                (after - before).length() <= tol,
                "{name}: momentum {before:.0} -> {after:.0} across the impact of {} and {} at frame {g} (tolerance {tol:.0})",
                t.agents[c.a].name,
                t.agents[c.b].name
            );
            // One that exchanges more than the tolerance makes the check mean something.
            checked += usize::from(exchanged > tol);
        }
        assert!(checked >= 1, "{name}: no impact between two moving bodies exchanged enough to measure");
    }
}

#[test]
fn staged_impacts_land_on_their_stated_sides() {
    for (name, f) in scenes() {
        let (t, s) = (&f.tracks, &f.concrete);
        for r in &t.impacts {
            let c = &s.conflicts[r.conflict];
            let (in_struck, in_af) = measured_contact(t, r.at_fault, r.struck, r.frame).expect("contact at the impact");
            let (sb, sa) = (t.agents[r.struck].size, t.agents[r.at_fault].size);
            assert_eq!(sector(in_struck, sb[0], sb[1]), c.point, "{name}: struck elsewhere");
            let face = sector(in_af, sa[0], sa[1]);
            let fronts = [Point::Front, Point::FrontLeft, Point::FrontRight];
            assert!(c.impact == Impact::Sideswipe || fronts.contains(&face), "{name}: struck with its {face:?}");
        }
        assert!(!t.impacts.is_empty(), "{name}: nothing staged");
    }
}

/// Two boxes overlap only from shortly before an impact of theirs (the staged approach's crush)
/// to the end of its window, and never once everyone has come to rest.
#[test]
fn boxes_overlap_only_around_their_contacts_and_everyone_comes_to_rest() {
    for (name, f) in scenes() {
        let t = &f.tracks;
        let window = (WINDOW_S * t.rate).round() as usize + 1;
        for g in 0..t.frames {
            for (a, b) in overlapping(t, g) {
                let near = t.contacts.iter().any(|c| {
                    ((c.a, c.b) == (a, b) || (c.a, c.b) == (b, a)) && g + window >= c.frame && g <= c.frame + window
                });
                assert!(
                    near,
                    "{name}: {} and {} overlap at frame {g}, away from any impact of theirs",
                    t.agents[a].name, t.agents[b].name
                );
            }
        }
        let last = t.frames - 1;
        assert!(overlapping(t, last).is_empty(), "{name}: boxes still overlap at the end");
        for i in 0..t.agents.len() {
            if t.contacts.iter().any(|c| c.a == i || c.b == i) {
                assert!(
                    pos(t, i, last).distance(pos(t, i, last - 1)) < 1e-9,
                    "{name}: {} still moves",
                    t.agents[i].name
                );
                assert!(
                    (t.poses[i][last].yaw - t.poses[i][last - 1].yaw).abs() < 1e-9,
                    "{name}: {} still spins",
                    t.agents[i].name
                );
            }
        }
    }
}

/// The named pairs touch in these scenes though only the first was staged.
#[test]
fn impulses_drive_bodies_into_others() {
    let touched = |f: &Front, a: &str, b: &str| {
        let t = &f.tracks;
        let (a, b) = (t.agents.iter().position(|x| x.name == a), t.agents.iter().position(|x| x.name == b));
        let (a, b) = (a.expect("agent"), b.expect("agent"));
        (0..t.frames).any(|g| obb(t, a, g).overlaps(&obb(t, b, g)))
    };
    let chain = scene("truck-pushes-van-into-car.scn");
    assert!(touched(&chain, "van", "car"), "the van was not pushed into the car");
    let pile = scene("bus-into-queue-pile-up.scn");
    for (a, b) in [("c4", "c3"), ("c3", "c2"), ("c2", "c1")] {
        assert!(touched(&pile, a, b), "{a} was not driven into {b}");
    }
    let pole = scene("suv-glances-off-sedan-into-pole.scn");
    assert!(touched(&pole, "sedan", "pole"), "the sedan did not reach the pole");
    // The pole stands.
    let t = &pole.tracks;
    let p = t.agents.iter().position(|x| x.name == "pole").expect("pole");
    assert!(t.poses[p].iter().all(|q| *q == t.poses[p][0]));
}

/// `after latch` holds the pair where it met: nothing moves on from the impact, and no impact
/// is resolved.
#[test]
fn after_latch_holds_the_pair() {
    let text = std::fs::read_to_string("tests/impact/truck-pushes-van-into-car.scn").expect("scene");
    let text = text.replace("point rear; at 2.5 s }", "point rear; at 2.5 s; after latch }");
    let f = front_of(&text);
    let t = &f.tracks;
    let r = t.impacts.first().expect("impact");
    assert!(t.contacts.is_empty(), "a latched pair resolved an impact");
    for x in [r.at_fault, r.struck] {
        assert!(
            t.poses[x][r.frame..].iter().all(|p| *p == t.poses[x][r.frame]),
            "{} moved after the latch",
            t.agents[x].name
        );
    }
}

/// A stated mass is the one the impact uses: the same strike moves a heavier van less, and a
/// kind's mass passes to its agents and to kinds derived from it.
#[test]
fn stated_masses_weigh_in_the_impact() {
    let text = std::fs::read_to_string("tests/impact/truck-pushes-van-into-car.scn").expect("scene");
    let pushed = |text: &str| {
        let f = front_of(text);
        let t = &f.tracks;
        let r = t.impacts.first().expect("impact");
        (vel(t, r.struck, r.frame) - vel(t, r.struck, r.frame - 1)).length()
    };
    let light = pushed(&text.replace("mass 2600 kg", "mass 1500 kg"));
    let heavy = pushed(&text.replace("mass 2600 kg", "mass 6000 kg"));
    assert!(light > heavy + 1.0, "a 1500 kg van gained {light:.2} m/s, a 6000 kg one {heavy:.2}");
    let kinds = "kind armoured_van: van { mass 6000 kg }\nkind long_armoured_van: armoured_van { length 6.0 m }\n";
    let derived = text.replace("        mass 2600 kg\n", "").replace("agent van: van", "agent van: long_armoured_van");
    let f = front_of(&format!("{kinds}{derived}"));
    let van = f.concrete.agents.iter().find(|a| a.name == "van").expect("van");
    assert_eq!(van.mass, Some(6000.0));
}

/// A car glancing off another into a pole or a post, every contact written as a conflict
/// (tests/strikes/: a struck sedan strikes a pole; an SUV strikes the sedan, then a post): each
/// lands on its stated side of the struck box as the boxes measure it, within 1.5 s of its
/// time, between the agents the file names, and an agent's strikes in the order written.
#[test]
fn later_strikes_land_on_their_sides_in_order() {
    let mut names: Vec<_> =
        std::fs::read_dir("tests/strikes").expect("scenes").map(|e| e.expect("entry").path()).collect();
    names.sort();
    assert_eq!(names.len(), 2, "the scenes of several strikes are missing");
    for path in names {
        let f = front_of(&std::fs::read_to_string(&path).expect("scene"));
        let (t, s) = (&f.tracks, &f.concrete);
        let mut last: Vec<Option<usize>> = vec![None; t.agents.len()];
        for (k, c) in s.conflicts.iter().enumerate() {
            let r = t.impacts.iter().find(|r| r.conflict == k).unwrap_or_else(|| panic!("{path:?} {k}: no impact"));
            let name = |i: usize| s.agents[i].name.as_str();
            assert_eq!(t.agents[r.at_fault].name, name(c.at_fault), "{path:?} {k}");
            assert_eq!(t.agents[r.struck].name, name(c.struck), "{path:?} {k}");
            let (in_struck, _) = measured_contact(t, r.at_fault, r.struck, r.frame).expect("contact at the impact");
            let sb = t.agents[r.struck].size;
            assert_eq!(sector(in_struck, sb[0], sb[1]), c.point, "{path:?} {k}: struck elsewhere");
            let at = c.at.expect("at");
            assert!((r.frame as f64 / t.rate - at).abs() <= 1.5 + 0.5 / t.rate, "{path:?} {k} at frame {}", r.frame);
            if let Some(before) = last[r.at_fault] {
                assert!(before < r.frame, "{path:?} {k}: struck at frame {} before its earlier strike", r.frame);
            }
            last[r.at_fault] = Some(r.frame);
        }
        // The poles stand.
        for (i, a) in t.agents.iter().enumerate().filter(|(_, a)| a.kind == "pole") {
            assert!(t.poses[i].iter().all(|q| *q == t.poses[i][0]), "{} moved", a.name);
        }
    }
}
