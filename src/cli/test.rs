//! `rocc test [DIR|FILE...]`: a scenario library as a test suite. Every file is checked, rolled
//! out, its `expect` lines judged and its snapshot compared with `snapshots/NAME.snap` beside
//! it; files run in parallel, results print in the order given. Exit status 1 when anything
//! failed. `--accept` writes snapshots, `--review` asks per change, `--pending` leaves
//! `NAME.snap.new` files for `cargo insta review`, `--junit FILE` writes a JUnit report.

use super::check::MessageFormat;
use super::{Failure, show};
use rayon::prelude::*;
use rocc::diag::Diagnostic;
use rocc::expect::compare::{self, Status};
use rocc::source::SourceMap;
use serde_json::json;
use std::io::BufRead;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct Args {
    /// Scenario files, or folders whose `*.scn` files are tested (default: the current folder).
    paths: Vec<PathBuf>,
    /// Write or update every snapshot that is missing or differs.
    #[arg(long, conflicts_with_all = ["review", "pending"])]
    accept: bool,
    /// Show each change and ask: accept, reject or skip (answers read from stdin).
    #[arg(long, conflicts_with = "pending")]
    review: bool,
    /// Leave `snapshots/NAME.snap.new` beside each snapshot that is missing or differs.
    #[arg(long)]
    pending: bool,
    /// Also write a JUnit XML report here (one test case per expectation and per snapshot).
    #[arg(long)]
    junit: Option<PathBuf>,
    /// `json`: one JSON object per line (diagnostics, one result per file, a summary).
    #[arg(long, value_enum, default_value = "human")]
    message_format: MessageFormat,
}

/// One file's outcome.
struct Outcome {
    file: PathBuf,
    sources: SourceMap,
    /// `Err`: the file did not check or roll out.
    report: Result<rocc::expect::Report, Vec<Diagnostic>>,
    snap: PathBuf,
    status: Status,
}

impl Outcome {
    fn passed(&self) -> bool {
        self.report.as_ref().is_ok_and(|r| r.failures.is_empty()) && self.status == Status::Match
    }
}

pub fn run(a: Args) -> Result<(), Failure> {
    let files = discover(&a.paths)?;
    let mut outcomes: Vec<Outcome> = files.par_iter().map(|f| test_one(f)).collect();
    for o in &mut outcomes {
        settle(o, &a)?;
    }
    let failed = outcomes.iter().filter(|o| !o.passed()).count();
    for o in &outcomes {
        print(o, a.message_format)?;
    }
    if let Some(path) = &a.junit {
        super::write_file(path, super::test_junit::xml(&outcomes_view(&outcomes)).as_bytes()).map_err(|e| {
            Diagnostic::error("E1024", format!("cannot write `{}`: {e}", path.display()))
                .help("check the folder exists")
        })?;
    }
    let n = outcomes.len();
    match a.message_format {
        MessageFormat::Json => {
            outln!("{}", json!({"type": "summary", "files": n, "passed": n - failed, "failed": failed}))?
        }
        MessageFormat::Human => outln!("{} of {n} scenario(s) passed", n - failed)?,
    }
    if failed == 0 { Ok(()) } else { Err(Failure::shown()) }
}

/// The `.scn` files named, folders expanded (their own files only, sorted).
fn discover(paths: &[PathBuf]) -> Result<Vec<PathBuf>, Diagnostic> {
    let here = [PathBuf::from(".")];
    let paths = if paths.is_empty() { &here[..] } else { paths };
    let mut out = vec![];
    for p in paths {
        if p.is_dir() {
            let mut v: Vec<PathBuf> = std::fs::read_dir(p)
                .map_err(|e| nothing(p, &e.to_string()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| f.is_file() && f.extension().is_some_and(|e| e == "scn"))
                .collect();
            if v.is_empty() {
                return Err(nothing(p, "the folder holds no .scn file"));
            }
            v.sort();
            out.extend(v);
        } else if p.is_file() {
            out.push(p.clone());
        } else {
            return Err(nothing(p, "no such file or folder"));
        }
    }
    Ok(out)
}

fn nothing(p: &Path, why: &str) -> Diagnostic {
    Diagnostic::error("E1023", format!("nothing to test at `{}`: {why}", p.display()))
        .help("give scenario files or folders of them: `rocc test scenarios/`")
}

fn test_one(file: &Path) -> Outcome {
    let mut sources = SourceMap::default();
    let report = rocc::expect::run(file, &mut sources);
    let snap = compare::path_for(file);
    let status = match &report {
        Ok(r) => compare::status(&snap, &r.body),
        Err(_) => Status::Match,
    };
    Outcome { file: file.to_path_buf(), sources, report, snap, status }
}

/// Apply `--accept`, `--review` or `--pending` to one outcome, in file order.
fn settle(o: &mut Outcome, a: &Args) -> Result<(), Failure> {
    let Ok(r) = &o.report else { return Ok(()) };
    if !matches!(o.status, Status::Missing | Status::Differs(_)) {
        return Ok(());
    }
    let pending = o.snap.with_extension("snap.new");
    if a.accept || (a.review && ask(o)?) {
        compare::write(&o.snap, &o.file, &r.body)?;
        let _ = std::fs::remove_file(&pending);
        o.status = Status::Match;
    } else if a.pending {
        compare::write(&pending, &o.file, &r.body)?;
    }
    Ok(())
}

/// Show one change on stderr and read the answer from stdin: `a` accepts; `r` rejects (the old
/// snapshot stays and a pending `.snap.new` is removed); `s` or end of input skips.
fn ask(o: &Outcome) -> Result<bool, Diagnostic> {
    let change = match &o.status {
        Status::Differs(d) => format!("{}:\n{d}", o.snap.display()),
        _ => format!("{}: new snapshot\n{}", o.snap.display(), o.report.as_ref().map_or("", |r| r.body.as_str())),
    };
    eprint!("{change}accept (a), reject (r) or skip (s)? ");
    let mut line = String::new();
    std::io::stdin().lock().read_line(&mut line).map_err(|e| {
        Diagnostic::error("E1024", format!("cannot read the answer: {e}")).help("answer a, r or s, one a line")
    })?;
    match line.trim() {
        "a" | "accept" => Ok(true),
        "r" | "reject" => {
            let _ = std::fs::remove_file(o.snap.with_extension("snap.new"));
            Ok(false)
        }
        _ => Ok(false),
    }
}

fn print(o: &Outcome, format: MessageFormat) -> Result<(), Failure> {
    let file = o.file.display().to_string();
    let mut diags: Vec<Diagnostic> = match &o.report {
        Err(d) => d.clone(),
        Ok(r) => r.failures.clone(),
    };
    diags.extend(compare::diagnostic(&o.snap, &o.status));
    let diff = match &o.status {
        Status::Differs(d) => Some(d.as_str()),
        _ => None,
    };
    match format {
        MessageFormat::Human => {
            let (ok, total) =
                o.report.as_ref().map_or((0, 0), |r| (r.verdicts.iter().filter(|v| v.1).count(), r.verdicts.len()));
            let verdict = if o.passed() { "ok  " } else { "FAIL" };
            outln!(
                "{verdict} {file}: {ok} of {total} expectation(s) hold, snapshot {}",
                status_word(&o.status, &o.report)
            )?;
            show(&diags, &o.sources);
            if let Some(d) = diff {
                eprint!("{d}");
            }
        }
        MessageFormat::Json => {
            for d in &diags {
                let mut v = d.to_json(&o.sources);
                v["type"] = "diagnostic".into();
                outln!("{v}")?;
            }
            let (scenario, expectations) = match &o.report {
                Ok(r) => (
                    Some(r.scenario.clone()),
                    r.verdicts.iter().map(|(l, ok)| json!({"expect": l, "ok": ok})).collect::<Vec<_>>(),
                ),
                Err(_) => (None, vec![]),
            };
            let v = json!({"type": "test", "file": file, "scenario": scenario, "ok": o.passed(),
                "expectations": expectations, "snapshot": status_word(&o.status, &o.report),
                "snapshot_file": o.snap.display().to_string(), "diff": diff});
            outln!("{v}")?;
        }
    }
    Ok(())
}

fn status_word<T, E>(s: &Status, report: &Result<T, E>) -> &'static str {
    match (report, s) {
        (Err(_), _) => "not run",
        (_, Status::Match) => "matches",
        (_, Status::Missing) => "missing",
        (_, Status::Differs(_)) => "differs",
        (_, Status::Corrupt(_)) => "unreadable",
    }
}

/// What the JUnit report needs of each outcome.
fn outcomes_view(outcomes: &[Outcome]) -> Vec<super::test_junit::Case> {
    let mut cases = vec![];
    for o in outcomes {
        let file = o.file.display().to_string();
        match &o.report {
            Err(d) => cases.push(super::test_junit::Case {
                class: file.clone(),
                name: "check and rollout".into(),
                failure: Some(d.iter().map(|d| d.render_plain(&o.sources)).collect()),
            }),
            Ok(r) => {
                let mut fails = r.failures.iter();
                for (line, ok) in &r.verdicts {
                    let failure = if *ok { None } else { fails.next().map(|d| d.render_plain(&o.sources)) };
                    cases.push(super::test_junit::Case {
                        class: file.clone(),
                        name: format!("expect {line}"),
                        failure,
                    });
                }
                let failure = compare::diagnostic(&o.snap, &o.status).map(|d| {
                    let diff = if let Status::Differs(x) = &o.status { x.as_str() } else { "" };
                    format!("{}{diff}", d.render_plain(&o.sources))
                });
                cases.push(super::test_junit::Case { class: file, name: "snapshot".into(), failure });
            }
        }
    }
    cases
}
