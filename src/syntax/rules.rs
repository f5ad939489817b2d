//! The pest parser derived from `grammar/scn.pest`: its `Rule`s are read by the tree walk
//! (`parse`) and by the syntax-error messages (`error`).

#[derive(pest_derive::Parser)]
#[grammar = "../grammar/scn.pest"]
pub(super) struct ScnParser;
