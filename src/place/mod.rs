//! Place pass. In: a `Concrete` scenario and its `Map`. Out: `Placed` — every agent, object and
//! row element with a world pose and box — or E02xx diagnostics (off a valid surface, overlap).

use crate::check::scenario::{Class, Motion};
use crate::source::Span;
use serde::{Deserialize, Serialize};

/// A pose on the ground plane: world metres, yaw counter-clockwise from +x (rad).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlacedAgent {
    /// The declared name; row elements are named `ROWKIND_rowN_K`.
    pub name: String,
    pub kind: String,
    pub class: Class,
    pub motion: Motion,
    pub is_object: bool,
    /// Box length, width, height (m); the box stands on the ground (z from 0 to height).
    pub size: [f64; 3],
    pub pose: Pose,
    pub speed: f64,
    /// Index into `Concrete::agents`, `None` for row elements.
    pub source: Option<usize>,
    #[serde(skip)]
    pub span: Span,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Placed {
    pub agents: Vec<PlacedAgent>,
}
