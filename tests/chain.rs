//! Several crashes per agent (a chain), measured on the rolled-out boxes, not with the stager's
//! geometry: each pair first touches within 1.5 s of its `at`, in the order the file states,
//! on the stated sides (sampled overlap of the final, latched boxes), each agent stands still
//! from its first contact, and no other pair touches. Scenes: tests/chain/.

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
            let (on_struck, on_striker) = measured_contact(t, a, b, last).expect("still in contact");
            let (sb, sa) = (t.agents[b].size, t.agents[a].size);
            assert_eq!(sector(on_struck, sb[0], sb[1]), c.point, "{p}: struck elsewhere");
            assert_eq!(sector(on_striker, sa[0], sa[1]), rocc::check::scenario::Point::Front, "{p}: not its front");
            firsts.push(f);
        }
        assert!(firsts.windows(2).all(|w| w[0] <= w[1]), "{p}: contacts out of order {firsts:?}");
        // Each agent stands still from its first contact.
        for i in 0..t.agents.len() {
            let first = s
                .conflicts
                .iter()
                .zip(&firsts)
                .filter(|(c, _)| idx(c.at_fault) == i || idx(c.struck) == i)
                .map(|(_, &f)| f)
                .min();
            if let Some(f) = first {
                let (p0, p1) = (t.poses[i][f + 1], t.poses[i][last]);
                assert!((p0.x - p1.x).hypot(p0.y - p1.y) < 1e-9, "{p}: agent {i} moves after its contact");
            }
        }
        // No pair outside the conflicts touches.
        for a in 0..t.agents.len() {
            for b in a + 1..t.agents.len() {
                let listed = s.conflicts.iter().any(|c| {
                    let (x, y) = (idx(c.at_fault), idx(c.struck));
                    (x, y) == (a, b) || (x, y) == (b, a)
                });
                assert!(listed || first_touch(t, a, b).is_none(), "{p}: {a} and {b} touch");
            }
        }
    }
}
