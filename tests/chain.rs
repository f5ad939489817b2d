//! Several crashes per agent (a chain), measured on the rolled-out boxes, not with the stager's
//! geometry: each pair first touches within 1.5 s of its `at`, in the order the file states,
//! on the stated sides (sampled overlap of the boxes at the impact), each agent involved slows
//! down from its last contact on (it slides, no longer driven), and no other pair touches before one of them has been in an impact (after
//! it, an impulse may drive it into another: tests/impact.rs). Scenes: tests/chain/.

#[path = "support/contact.rs"]
mod contact;
#[path = "support/front.rs"]
mod front;

use contact::{measured_contact, obb, sector};
use front::front_of;
use rocc::rollout::Tracks;

fn first_touch(t: &Tracks, a: usize, b: usize) -> Option<usize> {
    (0..t.frames).find(|&f| obb(t, a, f).overlaps(&obb(t, b, f)))
}

#[test]
fn chains_land_each_contact_in_order_on_its_sides() {
    let mut files: Vec<_> =
        std::fs::read_dir("tests/chain").expect("scenes").map(|e| e.expect("entry").path()).collect();
    files.sort();
    assert!(!files.is_empty(), "the chain scenes are missing");
    for path in files {
        let p = path.display();
        let front = front_of(&std::fs::read_to_string(&path).expect("scene"));
        let (t, s) = (&front.tracks, &front.scenario);
        let dt = 1.0 / t.rate;
        let idx = |i: usize| t.agents.iter().position(|a| a.name == s.agents[i].name).expect("agent");
        let last = t.frames - 1;
        let mut firsts = vec![];
        for c in &s.conflicts {
            let (a, b) = (idx(c.at_fault), idx(c.struck));
            let f = first_touch(t, a, b).unwrap_or_else(|| panic!("{p}: {a} never touches {b}"));
            let at = c.at.unwrap_or(s.duration / 2.0);
            assert!((f as f64 * dt - at).abs() <= 1.5 + 0.5 * dt, "{p}: contact at {:.1} s, asked {at}", f as f64 * dt);
            let at_impact = t.impacts.iter().find(|r| (r.at_fault, r.struck) == (a, b)).expect("impact").frame;
            let (on_struck, on_striker) = measured_contact(t, a, b, at_impact).expect("in contact at the impact");
            let (sb, sa) = (t.agents[b].size, t.agents[a].size);
            assert_eq!(sector(on_struck, sb[0], sb[1]), c.point, "{p}: struck elsewhere");
            assert_eq!(sector(on_striker, sa[0], sa[1]), rocc::check::scenario::Point::Front, "{p}: not its front");
            firsts.push(f);
        }
        assert!(firsts.windows(2).all(|w| w[0] <= w[1]), "{p}: contacts out of order {firsts:?}");
        // Each agent involved slows down from a second after its last contact on (its window
        // over): it slides, no longer driven.
        let speed = |i: usize, f: usize| {
            let (a, b) = (t.poses[i][f], t.poses[i][f + 1]);
            (b.x - a.x).hypot(b.y - a.y) / dt
        };
        for i in 0..t.agents.len() {
            let Some(lastc) = t.contacts.iter().filter(|c| c.a == i || c.b == i).map(|c| c.frame).max() else {
                continue;
            };
            for f in (lastc + 10).min(last)..last.saturating_sub(1) {
                assert!(
                    speed(i, f + 1) <= speed(i, f) + 1e-9,
                    "{p}: agent {i} speeds up at frame {f} after its impacts"
                );
            }
        }
        assert!(s.conflicts.iter().all(|c| t.first_contact(idx(c.at_fault)).is_some()), "{p}: an impact is missing");
        // No pair outside the conflicts touches before one of the two has been in an impact.
        let struck_at = |i: usize| t.impacts.iter().filter(|r| r.at_fault == i || r.struck == i).map(|r| r.frame).min();
        for a in 0..t.agents.len() {
            for b in a + 1..t.agents.len() {
                let listed = s.conflicts.iter().any(|c| {
                    let (x, y) = (idx(c.at_fault), idx(c.struck));
                    (x, y) == (a, b) || (x, y) == (b, a)
                });
                let after = struck_at(a).into_iter().chain(struck_at(b)).min();
                let early = first_touch(t, a, b).is_some_and(|f| after.is_none_or(|h| f <= h));
                assert!(listed || !early, "{p}: {a} and {b} touch before either is struck");
            }
        }
    }
}
