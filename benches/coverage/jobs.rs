//! Running the cases: `--jobs` workers each take the next case, write it, run its methods
//! one after another, and hand the records to the main thread, which appends them to the
//! results files as they come (so an interrupted study keeps what it measured).

use crate::Args;
use ctcal::coverage::run::{RunOptions, run_method};
use ctcal::coverage::{CaseSpec, Method, Outcome, RunRecord, write_case};
use std::collections::BTreeSet;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc;
use std::time::Duration;

/// The (case, method) runs of one case, skipping those in `done`.
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
                let (outcome, seconds) = run_method(options, method, &dir);
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

/// Runs every case; returns the path of the full results file.
pub fn run_all(args: &Args, methods: &[Method]) -> anyhow::Result<PathBuf> {
    let results = args.out.join("results.jsonl");
    let compact = args.out.join("results.compact.jsonl");
    let done = if args.resume {
        done_runs(&results)?
    } else {
        BTreeSet::new()
    };
    let (mut full_file, mut compact_file) =
        (open(&results, args.resume)?, open(&compact, args.resume)?);
    let work = args.work.clone().unwrap_or_else(|| args.out.join("cases"));
    std::fs::create_dir_all(&work)?;
    let options = RunOptions {
        binary: binary(args),
        threads: args.threads,
        timeout: Duration::from_secs(args.timeout_s),
    };
    anyhow::ensure!(
        options.binary.is_file(),
        "{} is not built: cargo build --release --all-targets",
        options.binary.display()
    );
    let next = AtomicU64::new(0);
    let (send, receive) = mpsc::channel::<Vec<RunRecord>>();
    std::thread::scope(|scope| -> anyhow::Result<()> {
        for _ in 0..args.jobs.max(1) {
            let send = send.clone();
            let (next, done, work, options) = (&next, &done, &work, &options);
            scope.spawn(move || {
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    if i >= args.cases {
                        break;
                    }
                    let case = CaseSpec::draw(args.seed + i);
                    let todo: Vec<Method> = methods
                        .iter()
                        .copied()
                        .filter(|m| m.applies_to(&case) && !done.contains(&(case.id.clone(), *m)))
                        .collect();
                    if !todo.is_empty() {
                        let records = run_case(&case, &todo, options, work, args.keep_cases);
                        if send.send(records).is_err() {
                            break;
                        }
                    }
                }
            });
        }
        drop(send);
        for (count, records) in receive.iter().enumerate() {
            for r in &records {
                writeln!(full_file, "{}", r.to_line())?;
                writeln!(compact_file, "{}", r.compact().to_line())?;
                let status = r.failure().map_or("ok".to_string(), |m| {
                    format!("FAILED {}", m.lines().next().unwrap_or(""))
                });
                eprintln!(
                    "[{}] {} {} {:.1} s {status}",
                    count + 1,
                    r.case.id,
                    r.method.name(),
                    r.seconds
                );
            }
            full_file.flush()?;
            compact_file.flush()?;
        }
        Ok(())
    })?;
    Ok(results)
}
