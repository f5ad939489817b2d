//! Sample pass. In: a checked `Scenario` and its seed. Out: a `Concrete` scenario where every
//! range and `one_of` is decided. Each agent draws from its own stream, keyed by the seed and its
//! name, so adding an agent never changes what another one samples.

mod rng;

pub use rng::Rng;

use crate::check::scenario::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Concrete {
    pub name: String,
    pub seed: u64,
    pub duration: f64,
    pub rate: f64,
    pub egos: Vec<usize>,
    pub road: Road,
    pub agents: Vec<ConcreteAgent>,
    pub rows: Vec<ConcreteRow>,
    pub conflicts: Vec<Conflict>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub near_misses: Vec<NearMiss>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub flaggers: Vec<Flagger>,
    pub traffic: Option<Traffic>,
    /// The kinds the scenario names, with their size priors: rows draw each element's kind and
    /// box from them when the place pass lays the row out.
    #[serde(default)]
    pub kinds: BTreeMap<String, Kind>,
}

impl Concrete {
    pub fn frame_count(&self) -> usize {
        (self.duration * self.rate).round() as usize
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConcreteAgent {
    pub name: String,
    pub kind: String,
    pub class: Class,
    pub motion: Motion,
    pub is_object: bool,
    /// Box length, width, height (m).
    pub size: [f64; 3],
    pub place: Place<f64>,
    pub speed: f64,
    pub goal: Option<Goal<f64>>,
    pub track: Option<Vec<Keyframe>>,
    #[serde(default, skip_serializing_if = "Behaviour::is_careful")]
    pub behaviour: Behaviour,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub phases: Vec<Phase<f64>>,
    /// `siren on|off` as stated (`Agent::siren`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub siren: Option<bool>,
    /// Lamps and doors as stated (`Agent::body`).
    #[serde(default, skip_serializing_if = "crate::check::scenario::Body::is_default")]
    pub body: crate::check::scenario::Body,
    /// The angle (degrees) per frame of each door `body` moves, as the rollout's last run
    /// swung it (`rollout::body`): empty before the rollout.
    #[serde(skip)]
    pub door_swing: Vec<(crate::check::scenario::Door, Vec<f64>)>,
    /// Mass in kg as the agent or its kind states it (`rollout::impact`); class priors otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    #[serde(skip)]
    pub span: crate::source::Span,
    #[serde(skip)]
    pub place_span: crate::source::Span,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConcreteRow {
    /// Kind of each object is drawn when the row is laid out; sizes too.
    pub kinds: Vec<String>,
    pub class: Class,
    pub from: Place<f64>,
    pub to: Place<f64>,
    pub every: f64,
    /// Seed of the row's own stream.
    pub stream: u64,
    #[serde(skip)]
    pub span: crate::source::Span,
}

/// Decide every random choice of `s` with `seed`.
pub fn sample(s: &Scenario, seed: u64) -> Concrete {
    let agents = s
        .agents
        .iter()
        .map(|a| {
            let mut r = Rng::stream(seed, &a.name);
            let kind = a.kinds[r.index(a.kinds.len())].clone();
            let k = &s.kinds[&kind];
            let size = a.posture.apply([
                r.draw(a.length.unwrap_or(k.length)),
                r.draw(a.width.unwrap_or(k.width)),
                r.draw(a.height.unwrap_or(k.height)),
            ]);
            let speed = r.draw(a.speed);
            ConcreteAgent {
                name: a.name.clone(),
                kind,
                class: a.class,
                motion: a.motion,
                is_object: a.is_object,
                size,
                place: place(&a.place, &mut r),
                speed,
                goal: a.goal.as_ref().map(|g| Goal {
                    speed: g.speed.map(|d| r.draw(d)),
                    lateral: g.lateral,
                    stop: g.stop,
                    turn: g.turn,
                    start_after: g.start_after,
                    start_when: g.start_when,
                    reverse: g.reverse,
                    stop_span: g.stop_span,
                }),
                track: a.track.clone(),
                behaviour: a.behaviour,
                phases: a
                    .phases
                    .iter()
                    .map(|p| Phase {
                        speed: p.speed.map(|v| r.draw(v)),
                        start_after: p.start_after,
                        start_when: p.start_when,
                        stop_after: p.stop_after,
                        pull_over: p.pull_over,
                        change: p.change,
                    })
                    .collect(),
                siren: a.siren,
                body: a.body.clone(),
                door_swing: vec![],
                mass: a.mass.or(k.mass),
                span: a.span,
                place_span: a.place_span,
            }
        })
        .collect();
    let rows = s
        .rows
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let mut r = Rng::stream(seed, &format!("row#{i}"));
            ConcreteRow {
                kinds: row.kinds.clone(),
                class: row.class,
                from: place(&row.from, &mut r),
                to: place(&row.to, &mut r),
                every: row.every,
                stream: r.next_u64(),
                span: row.span,
            }
        })
        .collect();
    Concrete {
        name: s.name.clone(),
        seed,
        duration: s.duration,
        rate: s.rate,
        egos: s.egos.clone(),
        road: s.road.clone(),
        agents,
        rows,
        conflicts: s.conflicts.clone(),
        near_misses: s.near_misses.clone(),
        flaggers: s.flaggers.clone(),
        traffic: s.traffic,
        kinds: s.kinds.clone(),
    }
}

fn place(p: &Place, r: &mut Rng) -> Place<f64> {
    let along = |a: &Along, r: &mut Rng| Along { landmark: a.landmark, dist: r.draw(a.dist) };
    match p {
        Place::Lane { lane, along: a, offset, heading } => {
            Place::Lane { lane: *lane, along: along(a, r), offset: *offset, heading: heading.map(|h| r.draw(h)) }
        }
        Place::World { x, y, heading } => {
            Place::World { x: r.draw(*x), y: r.draw(*y), heading: heading.map(|h| r.draw(h)) }
        }
        Place::Crosswalk { arm, fraction } => Place::Crosswalk { arm: *arm, fraction: r.draw(*fraction) },
        Place::Sidewalk { arm, dir, along: a, offset, heading } => Place::Sidewalk {
            arm: *arm,
            dir: *dir,
            along: along(a, r),
            offset: *offset,
            heading: heading.map(|h| r.draw(h)),
        },
        Place::Track => Place::Track,
        Place::Parking { arm, dir, slot } => Place::Parking { arm: *arm, dir: *dir, slot: *slot },
        Place::Driveway { index } => Place::Driveway { index: *index },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_values_pass_through_and_ranges_stay_inside() {
        let mut r = Rng::new(7);
        assert_eq!(r.draw(Dist::Fixed(3.5)), 3.5);
        for _ in 0..1000 {
            let x = r.draw(Dist::Uniform(4.4, 4.9));
            assert!((4.4..=4.9).contains(&x), "{x}");
        }
    }

    #[test]
    fn streams_depend_on_seed_and_name_only() {
        let a1 = Rng::stream(1, "ego").next_u64();
        assert_eq!(a1, Rng::stream(1, "ego").next_u64());
        assert_ne!(a1, Rng::stream(2, "ego").next_u64());
        assert_ne!(a1, Rng::stream(1, "amb").next_u64());
    }
}
