//! Running the cases: `--jobs` workers each take the next case, write it, run its methods
//! one after another, and hand the records to the main thread, which appends them to the
//! results files as they come (so an interrupted study keeps what it measured).

use crate::Args;
use crate::run::{RunOptions, run_method};
use ctcal::coverage::{CaseSpec, Method, Outcome, RunRecord, write_case};
use std::collections::BTreeSet;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc;
use std::time::Duration;

/// Writes `case`, runs `methods` on it, and removes it unless `keep`.
fn run_case(
    case: &CaseSpec,
    methods: &[Method],
    options: &RunOptions,
    work: &Path,
    keep: bool,
) -> Vec<RunRecord> {
    let dir = work.join(&case.id);
    let started = std::time::Instant::now();
    let written = write_case(case, &dir);
    let write_s = started.elapsed().as_secs_f64();
    let records = methods
        .iter()
        .map(|&method| match &written {
            Ok(truth) => {
                let (outcome, seconds) = run_method(options, method, &dir, case);
                RunRecord::new(case.clone(), Some(truth.clone()), method, seconds, outcome)
            }
            Err(e) => {
                let outcome = Outcome::Failed {
                    exit_code: None,
                    timed_out: false,
                    message: format!("the case could not be written: {e}"),
                };
                RunRecord::new(case.clone(), None, method, write_s, outcome)
            }
        })
        .collect();
    if !keep {
        let _ = std::fs::remove_dir_all(&dir);
    }
    records
}

/// (case id, method) pairs already in a results file.
fn done_runs(results: &Path) -> anyhow::Result<BTreeSet<(String, Method)>> {
    if !results.exists() {
        return Ok(BTreeSet::new());
    }
    Ok(ctcal::coverage::record::read_jsonl(results)?
        .into_iter()
        .map(|r| (r.case.id, r.method))
        .collect())
}

fn open(path: &Path, append: bool) -> anyhow::Result<std::fs::File> {
    Ok(std::fs::OpenOptions::new()
        .create(true)
        .write(true)
        .append(append)
        .truncate(!append)
        .open(path)?)
}

fn binary(args: &Args) -> PathBuf {
    args.ctcal
        .clone()
        .unwrap_or_else(|| ctcal::coverage::write::project_root().join("target/release/ctcal"))
}

/// The two results files, appended to as runs come in.
struct ResultsFiles {
    full: std::fs::File,
    compact: std::fs::File,
    written: usize,
}

impl ResultsFiles {
    fn open(out: &Path, append: bool) -> anyhow::Result<Self> {
        Ok(Self {
            full: open(&out.join("results.jsonl"), append)?,
            compact: open(&out.join("results.compact.jsonl"), append)?,
            written: 0,
        })
    }

    /// Appends a case's records and reports them on stderr.
    fn append(&mut self, records: &[RunRecord]) -> anyhow::Result<()> {
        self.written += 1;
        for r in records {
            writeln!(self.full, "{}", r.to_line())?;
            writeln!(self.compact, "{}", r.compact().to_line())?;
            let status = r.failure().map_or("ok".to_string(), |m| {
                format!("FAILED {}", m.lines().next().unwrap_or(""))
            });
            let (id, method) = (&r.case.id, r.method.name());
            eprintln!(
                "[{}] {id} {method} {:.1} s {status}",
                self.written, r.seconds
            );
        }
        self.full.flush()?;
        Ok(self.compact.flush()?)
    }
}

/// What every worker shares.
struct Plan<'a> {
    args: &'a Args,
    methods: &'a [Method],
    done: BTreeSet<(String, Method)>,
    options: RunOptions,
    work: PathBuf,
    next: AtomicU64,
}

impl Plan<'_> {
    /// The methods still to run on `case`.
    fn todo(&self, case: &CaseSpec) -> Vec<Method> {
        self.methods
            .iter()
            .copied()
            .filter(|m| m.applies_to(case) && !self.done.contains(&(case.id.clone(), *m)))
            .collect()
    }

    /// Takes cases until none is left, sending each one's records.
    fn work_on(&self, send: mpsc::Sender<Vec<RunRecord>>) {
        loop {
            let i = self.next.fetch_add(1, Ordering::SeqCst);
            let seed = match &self.args.only {
                Some(seeds) => match seeds.get(i as usize) {
                    Some(&seed) => seed,
                    None => return,
                },
                None if i < self.args.cases => self.args.seed + i,
                None => return,
            };
            let case = CaseSpec::draw_from(seed, &self.args.generators.0);
            let todo = self.todo(&case);
            if todo.is_empty() {
                continue;
            }
            let records = run_case(
                &case,
                &todo,
                &self.options,
                &self.work,
                self.args.keep_cases,
            );
            if send.send(records).is_err() {
                return;
            }
        }
    }
}

/// Runs every case; returns the path of the full results file.
pub fn run_all(args: &Args, methods: &[Method]) -> anyhow::Result<PathBuf> {
    let results = args.out.join("results.jsonl");
    let plan = Plan {
        args,
        methods,
        done: if args.resume {
            done_runs(&results)?
        } else {
            BTreeSet::new()
        },
        options: RunOptions {
            binary: binary(args),
            threads: args.threads,
            timeout: Duration::from_secs(args.timeout_s),
        },
        work: args.work.clone().unwrap_or_else(|| args.out.join("cases")),
        next: AtomicU64::new(0),
    };
    let binary = &plan.options.binary;
    anyhow::ensure!(
        binary.is_file(),
        "{} is not built: cargo build --release --all-targets",
        binary.display()
    );
    std::fs::create_dir_all(&plan.work)?;
    let mut files = ResultsFiles::open(&args.out, args.resume)?;
    let (send, receive) = mpsc::channel::<Vec<RunRecord>>();
    std::thread::scope(|scope| -> anyhow::Result<()> {
        for _ in 0..args.jobs.max(1) {
            let (send, plan) = (send.clone(), &plan);
            scope.spawn(move || plan.work_on(send));
        }
        drop(send);
        receive
            .iter()
            .try_for_each(|records| files.append(&records))
    })?;
    Ok(results)
}
