//! CIREN crash cases to scenarios. In: NHTSA CIREN case folders (crash report, sketch).
//! Out: checked `.scn` text that stages the recorded collision.
//!
//! `extract`: the VLM route (`rocc ciren extract`): sketch and summary to a vision model, the
//! scene checked and repaired like `rocc text`, the conflict from a separate greedy call merged
//! by span (`descriptor`).

pub mod descriptor;
pub mod extract;
