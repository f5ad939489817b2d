//! Reading a scenario file with its `use` imports and the implicit stdlib prelude.

use crate::diag::Diagnostic;
use crate::source::{FileId, SourceMap, Span};
use crate::syntax::{self, ast};
use std::path::{Component, Path, PathBuf};

/// The stdlib prelude, compiled into the binary so rocc runs from any directory.
pub const STDLIB_KINDS: &str = include_str!("../../stdlib/kinds.scn");
pub const STDLIB_NAME: &str = "<stdlib>/kinds.scn";

/// Largest source file rocc reads.
pub const MAX_SOURCE_BYTES: u64 = 4 << 20;

/// What the checker works on: the one scenario and every kind declaration in scope.
pub struct Program {
    pub scenario: ast::Scenario,
    pub kinds: Vec<ast::KindDecl>,
}

/// Read a file as UTF-8 text within the size limit.
pub fn read_source(path: &Path) -> Result<String, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    if meta.is_dir() {
        return Err(format!("`{}` is a directory, not a .scn file", path.display()));
    }
    if meta.len() > MAX_SOURCE_BYTES {
        return Err(format!("`{}` is {} bytes; rocc reads source files up to 4 MiB", path.display(), meta.len()));
    }
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    String::from_utf8(bytes).map_err(|e| {
        format!("`{}` is not UTF-8 text (invalid byte at offset {})", path.display(), e.utf8_error().valid_up_to())
    })
}

/// Load a scenario file from disk.
pub fn load_path(path: &Path, sources: &mut SourceMap) -> Result<Program, Vec<Diagnostic>> {
    let text =
        read_source(path).map_err(|m| vec![Diagnostic::error("E0002", m).help("pass a readable UTF-8 `.scn` file")])?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    load_text(&path.display().to_string(), &text, &base, sources)
}

/// Load scenario text; `use` paths resolve against `base` and may not leave it.
pub fn load_text(name: &str, text: &str, base: &Path, sources: &mut SourceMap) -> Result<Program, Vec<Diagnostic>> {
    let std_id = sources.add(STDLIB_NAME, STDLIB_KINDS);
    let stdlib = stdlib_ast(std_id).map_err(|d| vec![d])?;
    let root_id = sources.add(name, text);
    let root = syntax::parse(root_id, text).map_err(|d| vec![d])?;
    let root_dir = absolute(base);

    // Imported files are named relative to the root file's name as given, so diagnostics (and
    // snapshots of them) never show a machine's absolute paths.
    let display_dir = Path::new(name).parent().map(Path::to_path_buf).unwrap_or_default();
    let mut loader =
        Loader { sources, root_dir: root_dir.clone(), display_dir, kinds: vec![], diags: vec![], seen: vec![] };
    loader.take_kinds(&stdlib);
    let root_path = root_dir.join(Path::new(name).file_name().unwrap_or_default());
    loader.imports(&root, &root_dir, &mut vec![root_path]);
    loader.take_kinds(&root);

    let mut scenarios = root.items.iter().filter_map(|i| match i {
        ast::Item::Scenario(s) => Some(s),
        _ => None,
    });
    let scenario = scenarios.next().cloned();
    if let Some(extra) = scenarios.next() {
        loader.diags.push(
            Diagnostic::error("E0005", "a file may hold only one scenario")
                .label(extra.name.span, "second scenario")
                .help("put each scenario in its own file"),
        );
    }
    let Some(scenario) = scenario else {
        loader.diags.push(
            Diagnostic::error("E0005", "this file defines no scenario")
                .label(Span::new(root_id, 0, text.len().min(1)), "expected `scenario NAME { ... }`")
                .help("a scenario file holds one `scenario` block; kind files are imported with `use`"),
        );
        return Err(loader.diags);
    };
    if !loader.diags.is_empty() {
        return Err(loader.diags);
    }
    Ok(Program { scenario, kinds: loader.kinds })
}

/// The prelude is parsed once per process (a batch compile checks thousands of files); the
/// cached tree carries file id 0, the id it gets in a fresh `SourceMap`.
fn stdlib_ast(id: FileId) -> Result<ast::File, Diagnostic> {
    static CACHE: std::sync::OnceLock<Result<ast::File, Diagnostic>> = std::sync::OnceLock::new();
    if id != 0 {
        return syntax::parse(id, STDLIB_KINDS);
    }
    CACHE.get_or_init(|| syntax::parse(0, STDLIB_KINDS)).clone()
}

struct Loader<'a> {
    sources: &'a mut SourceMap,
    root_dir: PathBuf,
    /// `root_dir` as the user named it.
    display_dir: PathBuf,
    kinds: Vec<ast::KindDecl>,
    diags: Vec<Diagnostic>,
    /// Files already imported (a diamond imports a file once).
    seen: Vec<PathBuf>,
}

impl Loader<'_> {
    /// A path under `root_dir` as the user would write it.
    fn shown(&self, p: &Path) -> PathBuf {
        match p.strip_prefix(&self.root_dir) {
            Ok(rel) if rel.as_os_str().is_empty() => self.display_dir.clone(),
            Ok(rel) => self.display_dir.join(rel),
            Err(_) => p.to_path_buf(),
        }
    }

    fn take_kinds(&mut self, f: &ast::File) {
        for it in &f.items {
            if let ast::Item::Kind(k) = it {
                self.kinds.push(k.clone());
            }
        }
    }

    /// Follow the `use` items of `f` (a file in `dir`); `stack` is the chain of importers.
    fn imports(&mut self, f: &ast::File, dir: &Path, stack: &mut Vec<PathBuf>) {
        for it in &f.items {
            let ast::Item::Use(u) = it else { continue };
            let rel = Path::new(&u.path);
            if rel.is_absolute() || u.path.starts_with('/') || u.path.starts_with('\\') {
                self.diags.push(
                    Diagnostic::error("E0004", format!("import path `{}` is absolute", u.path))
                        .label(u.span, "absolute path")
                        .help("write the path relative to this file, inside the scenario's directory"),
                );
                continue;
            }
            let target = normalize(&dir.join(rel));
            if !target.starts_with(&self.root_dir) {
                self.diags.push(
                    Diagnostic::error("E0004", format!("import path `{}` leaves the scenario's directory", u.path))
                        .label(u.span, "escapes via `..`")
                        .help(format!("keep imported files under `{}`", self.shown(&self.root_dir).display())),
                );
                continue;
            }
            // The textual check above cannot see symlinks: `kinds/etc` may point at `/etc`.
            // Where the target exists, its real location must also stay under the root.
            if let Ok(real) = std::fs::canonicalize(&target)
                && !real.starts_with(&self.root_dir)
            {
                self.diags.push(
                    Diagnostic::error(
                        "E0004",
                        format!("import path `{}` leaves the scenario's directory through a symbolic link", u.path),
                    )
                    .label(u.span, "resolves outside the scenario's directory")
                    .help(format!(
                        "keep imported files (and the links leading to them) under `{}`",
                        self.shown(&self.root_dir).display()
                    )),
                );
                continue;
            }
            if let Some(i) = stack.iter().position(|p| *p == target) {
                let chain: Vec<String> = stack[i..].iter().chain([&target]).map(|p| display_name(p)).collect();
                self.diags.push(
                    Diagnostic::error("E0003", format!("import cycle: {}", chain.join(" -> ")))
                        .label(u.span, "this import closes the cycle")
                        .help("move the shared kinds into a file that both import"),
                );
                continue;
            }
            if self.seen.contains(&target) {
                continue;
            }
            self.seen.push(target.clone());
            let text = match read_source(&target) {
                Ok(t) => t,
                Err(m) => {
                    let m = m.replace(&target.display().to_string(), &self.shown(&target).display().to_string());
                    self.diags.push(
                        Diagnostic::error("E0002", m)
                            .label(u.span, "imported here")
                            .help("check the path; it is relative to this file"),
                    );
                    continue;
                }
            };
            let id: FileId = self.sources.add(self.shown(&target).display().to_string(), text);
            let text = self.sources.text(id).to_string();
            match syntax::parse(id, &text) {
                Err(d) => self.diags.push(d),
                Ok(file) => {
                    for item in &file.items {
                        if let ast::Item::Scenario(s) = item {
                            self.diags.push(
                                Diagnostic::error("E0005", "an imported file may only define kinds")
                                    .label(s.name.span, "scenario in an imported file")
                                    .label(u.span, "imported here")
                                    .help("import kind files with `use`; compile scenarios on their own"),
                            );
                        }
                    }
                    stack.push(target.clone());
                    let sub = target.parent().map(Path::to_path_buf).unwrap_or_default();
                    self.imports(&file, &sub, stack);
                    stack.pop();
                    self.take_kinds(&file);
                }
            }
        }
    }
}

fn display_name(p: &Path) -> String {
    p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| p.display().to_string())
}

fn absolute(p: &Path) -> PathBuf {
    let p = if p.as_os_str().is_empty() { Path::new(".") } else { p };
    std::fs::canonicalize(p).unwrap_or_else(|_| normalize(&std::env::current_dir().unwrap_or_default().join(p)))
}

/// Lexical normalisation: resolves `.` and `..` without touching the file system, so a path
/// that climbs out of the root is caught even when the target does not exist.
fn normalize(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other.as_os_str()),
        }
    }
    out
}
