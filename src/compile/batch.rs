//! Batch plumbing: which files a command line names, which of them this shard owns, and
//! progress reporting that suits a terminal or a log file.

use super::{ClipInput, ClipReport, Front, Options, Stage, clip_dir, compile_clip, front};
use crate::backend::Background;
use crate::diag::Diagnostic;
use crate::source::SourceMap;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// A file that failed, with the sources its diagnostics point into.
pub struct Failure {
    pub input: PathBuf,
    pub diags: Vec<Diagnostic>,
    pub sources: SourceMap,
}

#[derive(Default)]
pub struct BatchReport {
    /// In input order, then ego order.
    pub clips: Vec<ClipReport>,
    /// In input order.
    pub failures: Vec<Failure>,
}

/// A scenario decided and ready to render.
struct Prepared {
    input: PathBuf,
    bytes: Vec<u8>,
    sources: SourceMap,
    front: Front,
    background: Background,
    egos: Vec<usize>,
    frames: Vec<usize>,
}

/// Files decided and rendered together: enough to keep every core busy, few enough that memory
/// does not grow with the corpus.
const CHUNK_PER_THREAD: usize = 4;

/// Compile `inputs` into `out`. A cheap survey checks every file first (errors, duplicate
/// scenario names, the frame total for the progress bar); then the files are decided (sample ->
/// rollout) and rendered chunk by chunk, clips and frames in parallel, so peak memory depends on
/// the chunk, not on the corpus. Failures never stop the others.
pub fn run(inputs: &[PathBuf], out: &Path, opts: &Options, quiet: bool) -> BatchReport {
    run_shard(inputs, None, out, opts, quiet)
}

/// `run` for shard `k` of `n` of `inputs` (all of them, before sharding): duplicate scenario
/// names are found over every input, so two files that land in different shards still clash
/// (E0303 goes to the later one in input order, as without sharding). Errors in files of
/// other shards are theirs to report.
pub fn run_shard(
    inputs: &[PathBuf],
    shard: Option<(usize, usize)>,
    out: &Path,
    opts: &Options,
    quiet: bool,
) -> BatchReport {
    let mut report = BatchReport::default();
    let mine = |i: usize| shard.is_none_or(|(k, n)| i % n == k - 1);
    let surveyed: Vec<Result<(String, usize), Failure>> = inputs.par_iter().map(|p| survey(p, opts)).collect();
    let mut owner: BTreeMap<String, &PathBuf> = BTreeMap::new();
    let mut todo = Vec::new();
    let mut total = 0;
    for (i, (input, r)) in inputs.iter().zip(surveyed).enumerate() {
        if !mine(i) {
            if let Ok((name, _)) = r {
                owner.entry(name).or_insert(input);
            }
            continue;
        }
        match r {
            Ok((name, frames)) => match owner.get(&name) {
                Some(first) => report.failures.push(Failure {
                    diags: vec![
                        Diagnostic::error(
                            "E0303",
                            format!("`{}` and `{}` both declare scenario `{name}`", first.display(), input.display()),
                        )
                        .help("rename one of them: outputs go to OUT/<scenario>/<ego>/"),
                    ],
                    input: input.clone(),
                    sources: SourceMap::default(),
                }),
                None => {
                    owner.insert(name, input);
                    todo.push(input.clone());
                    total += frames;
                }
            },
            Err(f) => report.failures.push(f),
        }
    }

    let progress = Progress::new(total as u64, quiet);
    let chunk = (rayon::current_num_threads() * CHUNK_PER_THREAD).max(1);
    for files in todo.chunks(chunk) {
        let prepared: Vec<Result<Prepared, Failure>> = files.par_iter().map(|p| prepare(p, opts)).collect();
        let mut ok = Vec::new();
        for r in prepared {
            match r {
                Ok(p) => ok.push(p),
                Err(f) => report.failures.push(f),
            }
        }
        let jobs: Vec<(usize, usize)> =
            ok.iter().enumerate().flat_map(|(i, p)| p.egos.iter().map(move |&e| (i, e))).collect();
        let results: Vec<Result<ClipReport, Failure>> =
            jobs.par_iter().map(|&(i, ego)| render(&ok[i], ego, out, opts, &progress)).collect();
        for r in results {
            match r {
                // Only the summary: a corpus of 10^5 clips would otherwise hold every file name.
                Ok(c) => report.clips.push(c.summary()),
                Err(f) => report.failures.push(f),
            }
        }
    }
    progress.finish();
    // Failures in input order, whichever phase found them.
    report.failures.sort_by_key(|f| inputs.iter().position(|p| *p == f.input));
    if let Some(f) = refresh_index(out) {
        report.failures.push(f);
    }
    report
}

/// Rebuild the output root's `index.jsonl` (nothing to do where no clip was ever written).
fn refresh_index(out: &Path) -> Option<Failure> {
    if !out.is_dir() {
        return None;
    }
    let e = super::index::refresh(out).err()?;
    let path = out.join(super::index::INDEX_FILE);
    Some(Failure {
        diags: vec![
            Diagnostic::error("E0410", format!("cannot write `{}`: {e}", path.display()))
                .help("the clips are written; fix the cause and re-run the same command to rebuild the index"),
        ],
        input: path,
        sources: SourceMap::default(),
    })
}

fn render(p: &Prepared, ego: usize, out: &Path, opts: &Options, progress: &Progress) -> Result<ClipReport, Failure> {
    let input = p.input.display().to_string();
    let ci = ClipInput {
        input: &input,
        input_bytes: &p.bytes,
        sources: &p.sources,
        front: &p.front,
        background: &p.background,
        ego,
        frames: &p.frames,
    };
    let dir = clip_dir(out, &p.front, ego);
    if !opts.force
        && let Some(m) = super::edited_clip(&dir)
    {
        for _ in &p.frames {
            progress.inc(1);
        }
        progress.line(&format!("edited    {} (left alone)", dir.display()));
        let n = m.edits.len();
        return Err(Failure {
            input: p.input.clone(),
            diags: vec![
                Diagnostic::error(
                    "E0403",
                    format!(
                        "`{}` holds a clip changed by `rocc edit` ({n} edit{}: {}); recompiling would discard {}",
                        dir.display(),
                        if n == 1 { "" } else { "s" },
                        m.edits.join("; "),
                        if n == 1 { "it" } else { "them" }
                    ),
                )
                .help("pass `--force` to recompile it (the edits are lost), or compile into another `-o` directory"),
            ],
            sources: SourceMap::default(),
        });
    }
    let r = compile_clip(&ci, opts, &dir, &|| progress.inc(1));
    match &r {
        Ok(c) if c.resumed => progress.line(&format!("complete  {} (kept)", dir.display())),
        Ok(c) => progress.line(&format!("compiled  {} ({} frames)", dir.display(), c.frames)),
        Err(_) => {}
    }
    r.map_err(|e| {
        let backend = e.get_ref().and_then(|inner| inner.downcast_ref::<crate::backend::BackendFailure>());
        let diag = match backend {
            Some(f) => f.0.clone(),
            None => Diagnostic::error("E0401", format!("cannot write `{}`: {e}", dir.display()))
                .help("check the output directory's permissions and free space; a re-run resumes"),
        };
        Failure { input: p.input.clone(), diags: vec![diag], sources: SourceMap::default() }
    })
}

/// Check a file and count the frames it will produce; keep nothing else.
fn survey(path: &Path, opts: &Options) -> Result<(String, usize), Failure> {
    let mut sources = SourceMap::default();
    let s = crate::check::check_path(path, &mut sources).map_err(|diags| Failure {
        input: path.to_path_buf(),
        diags,
        sources,
    })?;
    let egos = if opts.egos.is_empty() { s.egos.len() } else { opts.egos.len() };
    let frames = super::parse_frames(opts.frames.as_deref(), s.frame_count()).map(|f| f.len()).unwrap_or(0);
    Ok((s.name, egos * frames))
}

fn prepare(path: &Path, opts: &Options) -> Result<Prepared, Failure> {
    let mut sources = SourceMap::default();
    let fail = |diags: Vec<Diagnostic>, sources: SourceMap| Failure { input: path.to_path_buf(), diags, sources };
    let scenario = match crate::check::check_path(path, &mut sources) {
        Ok(s) => s,
        Err(d) => return Err(fail(d, sources)),
    };
    let bytes = std::fs::read(path).unwrap_or_default();
    let front = match front(scenario, opts.seed) {
        Ok(f) => f,
        Err(d) => return Err(fail(d, sources)),
    };
    let egos = front.egos(&opts.egos).map_err(|d| fail(vec![d], SourceMap::default()))?;
    let frames = front.frames(opts.frames.as_deref()).map_err(|d| fail(vec![d], SourceMap::default()))?;
    let background = if opts.stage >= Stage::Occ {
        Background::generate(&front.map, front.concrete.seed)
    } else {
        Background::none()
    };
    Ok(Prepared { input: path.to_path_buf(), bytes, sources, front, background, egos, frames })
}

/// Expand files and directories (recursively, `*.scn`) into a sorted, de-duplicated list.
/// Directory walks skip files that hold no `scenario` (kind files imported with `use`).
pub fn collect_inputs(paths: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            walk(p, &mut out).map_err(|e| format!("cannot read directory `{}`: {e}", p.display()))?;
        } else if p.exists() {
            out.push(p.clone());
        } else {
            return Err(format!("`{}` does not exist", p.display()));
        }
    }
    out.sort();
    out.dedup();
    Ok(out)
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)?.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            walk(&p, out)?;
        } else if p.extension().is_some_and(|e| e == "scn") && holds_scenario(&p) {
            out.push(p);
        }
    }
    Ok(())
}

/// A cheap syntactic test: does the file define a scenario (rather than only kinds)?
fn holds_scenario(p: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(p) else { return true };
    match crate::syntax::parse(0, &text) {
        Ok(f) => f.items.iter().any(|i| matches!(i, crate::syntax::ast::Item::Scenario(_))),
        // A file that does not parse is compiled so that its error is reported.
        Err(_) => true,
    }
}

/// `--shard K/N` (1-based K): parse and validate.
pub fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (k, n) = s.split_once('/').ok_or_else(|| format!("`{s}`: expected K/N, e.g. 3/16"))?;
    let k: usize = k.trim().parse().map_err(|_| format!("`{s}`: K is not a number"))?;
    let n: usize = n.trim().parse().map_err(|_| format!("`{s}`: N is not a number"))?;
    if n == 0 || k == 0 || k > n {
        return Err(format!("`{s}`: need 1 <= K <= N"));
    }
    Ok((k, n))
}

/// The inputs shard K of N owns: every N-th file of the sorted list, starting at K-1. The list
/// is sorted, so every job of an array computes the same partition without talking to the others.
pub fn shard(inputs: Vec<PathBuf>, shard: Option<(usize, usize)>) -> Vec<PathBuf> {
    match shard {
        None => inputs,
        Some((k, n)) => inputs.into_iter().enumerate().filter(|(i, _)| i % n == k - 1).map(|(_, p)| p).collect(),
    }
}

/// A progress bar on a terminal; plain lines otherwise (CI logs, job arrays).
pub struct Progress {
    bar: Option<ProgressBar>,
    quiet: bool,
}

impl Progress {
    pub fn new(total: u64, quiet: bool) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let b = ProgressBar::new(total);
            if let Ok(style) =
                ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} frames  {msg}")
            {
                b.set_style(style);
            }
            b
        });
        Progress { bar, quiet }
    }

    pub fn inc(&self, n: u64) {
        if let Some(b) = &self.bar {
            b.inc(n);
        }
    }

    /// A line for the log (above the bar on a terminal).
    pub fn line(&self, msg: &str) {
        match &self.bar {
            Some(b) => b.println(msg),
            None if !self.quiet => eprintln!("{msg}"),
            None => {}
        }
    }

    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_inputs() {
        let inputs: Vec<PathBuf> = (0..10).map(|i| PathBuf::from(format!("{i:02}.scn"))).collect();
        let mut all = vec![];
        for k in 1..=3 {
            all.extend(shard(inputs.clone(), Some((k, 3))));
        }
        all.sort();
        assert_eq!(all, inputs);
        assert_eq!(shard(inputs.clone(), Some((2, 3))).len(), 3);
        assert!(parse_shard("0/3").is_err() && parse_shard("4/3").is_err() && parse_shard("x").is_err());
        assert_eq!(parse_shard("2/3"), Ok((2, 3)));
    }
}
