//! Training the grounded occupancy backend (`rocc train`). In: a data directory — what
//! `rocc compile --stage occ` writes, or nuPlan-Occ / UniScene-style BEV, occupancy and boxes
//! (`data`) — and a `GroundedConfig`. Out: weights (`.bpk`) with their config, checkpoints,
//! per-epoch validation under the shared scorer (`train`).

pub mod adam;
pub mod data;
pub mod train;

pub use train::{Stage, TrainOptions, TrainReport, export_safetensors, step_summary, train};
