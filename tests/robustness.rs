//! No input makes the front end panic: random text and mutated scenario files go through the
//! parser, the checker and the formatter; every diagnostic must point inside its file.

use proptest::prelude::*;
use rocc::source::SourceMap;
use std::path::PathBuf;

fn corpus() -> Vec<String> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut v = vec![];
    for dir in ["scenarios", "tests/fixtures/examples", "tests/invalid"] {
        let rd = std::fs::read_dir(root.join(dir)).unwrap_or_else(|e| panic!("{dir}: {e}"));
        let mut paths: Vec<_> =
            rd.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.extension().is_some_and(|e| e == "scn")).collect();
        paths.sort();
        v.extend(paths.iter().filter_map(|p| std::fs::read_to_string(p).ok()));
    }
    assert!(v.len() > 20, "corpus missing");
    v
}

const TOKENS: &[&str] = &[
    "scenario",
    "agent",
    "object",
    "row",
    "road",
    "goal",
    "conflict",
    "traffic",
    "track",
    "use",
    "kind",
    "{",
    "}",
    ";",
    ",",
    ":",
    "(",
    ")",
    "[",
    "]",
    ".",
    "..",
    "in",
    "out",
    "at",
    "speed",
    "m",
    "km/h",
    "s",
    "deg",
    "%",
    "Hz",
    "before",
    "after",
    "center",
    "stop_line",
    "junction",
    "west",
    "east",
    "north",
    "sedan",
    "one_of",
    "0",
    "-1",
    "3.5",
    "99999999999999999999999",
    "1e9",
    "\"x.scn\"",
    "//c\n",
    "\n",
    " ",
    "é",
    "\u{0}",
    "lanes",
    "duration",
];

/// Parse, check and format; assert every diagnostic's spans lie on char boundaries inside
/// the file they name.
fn run(text: &str) {
    let base = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut sources = SourceMap::default();
    if let Err(diags) = rocc::check::check_text("fuzz.scn", text, &base, &mut sources) {
        assert!(!diags.is_empty());
        for d in &diags {
            for l in &d.labels {
                let f = sources.text(l.span.file);
                assert!(l.span.start <= l.span.end && (l.span.end as usize) <= f.len(), "{d:?}");
                assert!(f.is_char_boundary(l.span.start as usize) && f.is_char_boundary(l.span.end as usize), "{d:?}");
            }
            // Rendering must not panic either.
            let _ = d.render_plain(&sources);
            let _ = d.to_json(&sources);
        }
    }
    if let Ok(out) = rocc::syntax::format_source(text) {
        let again = rocc::syntax::format_source(&out).expect("formatted text parses");
        assert_eq!(out, again, "formatting is idempotent");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn random_token_soup_never_panics(toks in prop::collection::vec(prop::sample::select(TOKENS), 0..120)) {
        run(&toks.join(" "));
    }

    #[test]
    fn random_bytes_never_panic(s in "\\PC{0,300}") {
        run(&s);
    }

    #[test]
    fn mutated_scenarios_never_panic(
        file in 0usize..1000,
        cut in 0usize..10_000,
        len in 0usize..40,
        insert in prop::sample::select(TOKENS),
    ) {
        let corpus = corpus();
        let text = &corpus[file % corpus.len()];
        let mut at = cut % (text.len() + 1);
        while !text.is_char_boundary(at) { at -= 1; }
        let mut end = (at + len).min(text.len());
        while !text.is_char_boundary(end) { end -= 1; }
        let mutated = format!("{}{}{}", &text[..at], insert, &text[end.max(at)..]);
        run(&mutated);
    }
}

/// The repository is self-contained: no source or test reads a path outside it (test data lives
/// in `tests/fixtures/`), so a plain clone passes `cargo test`.
#[test]
fn nothing_reads_a_path_outside_the_repository() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let needles = [concat!("..", "/shared"), concat!("/work", "/")];
    let mut stack = vec![root.join("src"), root.join("tests")];
    let mut bad = vec![];
    let mut seen = 0;
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).expect("readable source tree").flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                seen += 1;
                let text = std::fs::read_to_string(&p).expect("utf-8 source");
                for (i, line) in text.lines().enumerate() {
                    if needles.iter().any(|n| line.contains(n)) {
                        bad.push(format!("{}:{}: {}", p.display(), i + 1, line.trim()));
                    }
                }
            }
        }
    }
    assert!(seen > 50, "source tree not found");
    assert!(bad.is_empty(), "paths outside the repository:\n{}", bad.join("\n"));
}
