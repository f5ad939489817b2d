//! The impact state of a run, plain data: each body's inverse mass and inertia, who moves on
//! from an impact and how fast, and the open contact windows (`motion` moves them).

use crate::rollout::agent::{Actor, Conf, Drive};
use crate::rollout::impact::{box_inertia, prior_mass};
use glam::DVec2;

/// A body moving on from an impact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Slide {
    pub vel: DVec2,
    /// Yaw rate, rad/s.
    pub omega: f64,
    /// It moved this frame (or was just struck).
    pub moving: bool,
}

/// Two bodies that met at `frame`, allowed to overlap until `until`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Window {
    pub a: usize,
    pub b: usize,
    pub until: usize,
}

/// The impact state of a run: each body's inverse mass and inertia (0 for one that does not
/// move when struck), who moves on from an impact, and the open contact windows.
pub(crate) struct Wrecks {
    pub inv_mass: Vec<f64>,
    pub inv_inertia: Vec<f64>,
    pub slide: Vec<Option<Slide>>,
    pub windows: Vec<Window>,
    /// Some body has been struck: the passes below have something to do.
    pub any: bool,
    /// Conflicts whose striker is already moving on from an earlier impact
    /// (`staging::follow`): their contact is one the motion brings about, with their
    /// coefficients.
    pub follows: Vec<Conf>,
}

impl Wrecks {
    /// Masses from the class priors (`prior_mass`); objects, static kinds and replayed tracks
    /// do not move when struck.
    pub(crate) fn new(actors: &[Actor]) -> Wrecks {
        let mut w = Wrecks {
            inv_mass: vec![0.0; actors.len()],
            inv_inertia: vec![0.0; actors.len()],
            slide: vec![None; actors.len()],
            windows: vec![],
            any: false,
            follows: vec![],
        };
        for (i, a) in actors.iter().enumerate() {
            w.set_mass(a, i, prior_mass(a.info.class, a.info.motion, a.info.size));
        }
        w
    }

    pub(crate) fn set_mass(&mut self, a: &Actor, i: usize, m: f64) {
        if matches!(a.drive, Drive::Mover) && m.is_finite() && m > 0.0 {
            self.inv_mass[i] = 1.0 / m;
            self.inv_inertia[i] = 1.0 / box_inertia(m, 2.0 * a.hl, 2.0 * a.hw);
        }
    }

    /// Whether body `i` is moving on from an impact now.
    #[inline]
    pub(crate) fn moving(&self, i: usize) -> bool {
        self.any && self.slide[i].is_some_and(|s| s.moving)
    }
}
