//! Every diagnostic code rocc can emit, with the long explanation `rocc explain CODE` prints,
//! one file per range:
//! E00xx: files and syntax. E01xx: the checker. E02xx: road and placement (E0250-E0259:
//! reversing, parking lanes and driveways). E03xx: compile
//! options. E04xx: I/O.
//! E07xx: import, edit and eval.
//! E06xx: the LLM front end (`rocc text`): the HTTP client, the model's replies, the repair loop.
//! E08xx: CIREN crash recreation (`rocc ciren`): E0800-E0849 records and SAFE extractions.
//! E0850-E0899: the CIREN VLM route (`rocc ciren extract`): case files, the conflict descriptor
//! (E0870-E0879: near misses across a path, `near.rs`).
//! E09xx: the learned (grounded) occupancy backend and `rocc train`.
//! E10xx: expectations and `rocc test`.
//!
//! A `\` line continuation also eats the next line's leading spaces, so an indented example
//! line follows a literal line break (no `\n\` before it); a test guards this.

mod check;
mod ciren;
mod compile;
mod expect;
mod impact;
mod import;
mod io;
mod kerb;
mod learn;
mod llm;
mod near;
mod place;
mod syntax;

pub struct Code {
    pub code: &'static str,
    pub title: &'static str,
    pub explanation: &'static str,
}

/// Every code, in numeric order of its range.
pub fn all() -> impl Iterator<Item = &'static Code> {
    [
        syntax::CODES,
        check::CODES,
        impact::CODES,
        place::CODES,
        kerb::CODES,
        compile::CODES,
        io::CODES,
        import::CODES,
        llm::CODES,
        ciren::CODES,
        near::CODES,
        learn::CODES,
        expect::CODES,
    ]
    .into_iter()
    .flatten()
}

pub fn lookup(code: &str) -> Option<&'static Code> {
    let code = code.trim().to_ascii_uppercase();
    all().find(|c| c.code == code)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reader of `rocc explain` has the repository at most: a file it cites is a page under
    /// `docs/`, never a reference file kept beside the repository or a section of another page.
    #[test]
    fn explanations_cite_only_files_users_have() {
        for c in all() {
            let text = c.explanation;
            assert!(!text.contains("shared/"), "{}: cites a reference folder users do not have", c.code);
            assert!(!text.contains("README"), "{}: cites the README instead of a docs page", c.code);
            for (i, _) in text.match_indices(".md") {
                let path_char = |ch: char| ch.is_ascii_alphanumeric() || "/_-".contains(ch);
                let start =
                    text[..i].char_indices().rev().take_while(|(_, ch)| path_char(*ch)).last().map_or(i, |(j, _)| j);
                let file = &text[start..i + 3];
                assert!(file.starts_with("docs/"), "{}: cites `{file}`, which users do not have", c.code);
            }
        }
    }
}
