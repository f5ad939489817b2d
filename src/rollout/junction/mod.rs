//! Junctions: each turning vehicle's sweep (`bend`, found by its `dry_run`), the zones that
//! crossing paths share (`zones`), the order fixed at set-up for pairs too close to stop
//! (`order`), and the right-of-way rule applied every frame (`right_of_way`); traffic signals (`signals`).

pub(crate) mod bend;
pub(crate) mod dry_run;
pub(crate) mod order;
pub(crate) mod right_of_way;
pub(crate) mod signals;
pub(crate) mod zones;
