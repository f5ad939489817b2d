//! A run's snapshot against the one on disk: where the file lives, what differs (a line diff),
//! and writing it atomically on `--accept`.

use super::snapshot::{self, Bad};
use crate::diag::Diagnostic;
use std::path::{Path, PathBuf};

/// How a run's snapshot stands against the file beside the library.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Status {
    Match,
    Missing,
    /// The line diff, `-` old and `+` new, with two lines of context.
    Differs(String),
    /// The file is there but is not a `rocc test` snapshot (E1022); never overwritten.
    Corrupt(String),
}

/// `DIR/snapshots/STEM.snap` for `DIR/STEM.scn`.
pub fn path_for(scn: &Path) -> PathBuf {
    let stem = scn.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    scn.parent().unwrap_or(Path::new("")).join("snapshots").join(format!("{stem}.snap"))
}

/// Compare `body` with the snapshot at `path`.
pub fn status(path: &Path, body: &str) -> Status {
    let text = match std::fs::read(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Status::Missing,
        Err(e) => return Status::Corrupt(format!("cannot read it: {e}")),
        Ok(b) => match String::from_utf8(b) {
            Ok(t) => t,
            Err(_) => return Status::Corrupt("it is not UTF-8 text".into()),
        },
    };
    match snapshot::parse(&text) {
        Err(Bad::NoHeader) => Status::Corrupt("it has no `---` header (insta's snapshot format)".into()),
        Err(Bad::Foreign(e)) => Status::Corrupt(format!("its header says `expression: {e}`, not `rocc test`")),
        Ok(old) if old.trim_end() == body.trim_end() => Status::Match,
        Ok(old) => Status::Differs(diff(old, body)),
    }
}

/// The diagnostic for a status other than `Match`.
pub fn diagnostic(path: &Path, s: &Status) -> Option<Diagnostic> {
    let p = path.display();
    Some(match s {
        Status::Match => return None,
        Status::Missing => Diagnostic::error("E1021", format!("no snapshot `{p}`"))
            .help("run `rocc test --accept` to write it, then review and commit it"),
        Status::Differs(_) => Diagnostic::error("E1020", format!("the run differs from snapshot `{p}`"))
            .help("if the change is intended, `rocc test --review` or `--accept` updates the snapshot"),
        Status::Corrupt(why) => Diagnostic::error("E1022", format!("`{p}` is not a `rocc test` snapshot: {why}"))
            .help("move or delete the file; `rocc test --accept` then writes a fresh one"),
    })
}

/// Write the snapshot file (temporary name, then rename: never a half file).
pub fn write(path: &Path, scn: &Path, body: &str) -> Result<(), Diagnostic> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let source = scn.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    std::fs::create_dir_all(dir)
        .and_then(|()| {
            crate::fsio::write_atomic(path, |w| std::io::Write::write_all(w, snapshot::file(&source, body).as_bytes()))
        })
        .map(|_| ())
        .map_err(|e| {
            Diagnostic::error("E1024", format!("cannot write `{}`: {e}", path.display()))
                .help("check the folder exists and is writable")
        })
}

/// A line diff of two texts (longest common subsequence), `-`/`+` lines with two lines of
/// context around each change and `@@` between distant hunks.
pub fn diff(old: &str, new: &str) -> String {
    let (a, b): (Vec<&str>, Vec<&str>) = (old.lines().collect(), new.lines().collect());
    let (n, m) = (a.len(), b.len());
    // lcs[i][j]: the longest common subsequence of a[i..] and b[j..].
    let mut lcs = vec![vec![0u32; m + 1]; n + 1];
    for i in (0..n).rev() {
        for j in (0..m).rev() {
            lcs[i][j] = if a[i] == b[j] { lcs[i + 1][j + 1] + 1 } else { lcs[i + 1][j].max(lcs[i][j + 1]) };
        }
    }
    let mut ops: Vec<(char, &str)> = vec![];
    let (mut i, mut j) = (0, 0);
    while i < n || j < m {
        if i < n && j < m && a[i] == b[j] {
            ops.push((' ', a[i]));
            (i, j) = (i + 1, j + 1);
        } else if i < n && (j == m || lcs[i + 1][j] >= lcs[i][j + 1]) {
            ops.push(('-', a[i]));
            i += 1;
        } else {
            ops.push(('+', b[j]));
            j += 1;
        }
    }
    let near = |k: usize| ops[k.saturating_sub(2)..(k + 3).min(ops.len())].iter().any(|o| o.0 != ' ');
    let mut out = String::new();
    let mut gap = false;
    for (k, (op, line)) in ops.iter().enumerate() {
        if near(k) {
            if gap && !out.is_empty() {
                out.push_str("@@\n");
            }
            gap = false;
            out.push_str(&format!("{op} {line}\n"));
        } else {
            gap = true;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diff_marks_changed_lines_with_context_and_separates_hunks() {
        let old = "a\nb\nc\nd\ne\nf\ng\nh\ni\nj\n";
        let new = "a\nB\nc\nd\ne\nf\ng\nh\ni\nJ\n";
        assert_eq!(diff(old, new), "  a\n- b\n+ B\n  c\n  d\n@@\n  h\n  i\n- j\n+ J\n");
        assert_eq!(diff(old, old), "");
    }

    #[test]
    fn snapshots_round_trip_and_foreign_ones_are_told_apart() {
        let body = "scenario s\n\nexpect\n  (none)\n";
        let f = super::snapshot::file("s.scn", body);
        assert_eq!(super::snapshot::parse(&f), Ok(body));
        assert_eq!(super::snapshot::parse("hello\n"), Err(Bad::NoHeader));
        assert_eq!(
            super::snapshot::parse("---\nsource: tests/a.rs\nexpression: out\n---\nx\n"),
            Err(Bad::Foreign("out".into()))
        );
    }
}
