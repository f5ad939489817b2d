//! Staged conflicts: the contact geometry and the choice of impact time (`plan`), the rollout's
//! two passes that stage them (`passes`), the striker's intercept and the crash latch
//! (`strike`), and why a staging is refused (`refusals`); near misses, staged the same way
//! without contact (`near`, and `across` for a close call across a path); strikes that follow an earlier impact, measured
//! rather than staged (`follow`).

pub(crate) mod across;
pub(crate) mod follow;
pub(crate) mod near;
pub(crate) mod passes;
pub(crate) mod plan;
pub(crate) mod refusals;
pub(crate) mod strike;
