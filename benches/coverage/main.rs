//! The coverage study: do ctcal's 95 % intervals contain the truth 95 % of the time?
//!
//! Draws `--cases` random recordings with known parameters (`ctcal::coverage::CaseSpec::draw`,
//! seeds `--seed` onwards), writes each as an IJRR folder under the work folder, runs the
//! `ctcal` binary on it with every applicable method of `--methods` (`--jobs` cases at a
//! time, each command with `--threads` and a time limit), appends one JSON line per (case,
//! method) to `OUT/results.jsonl` (and a compact copy without the methods' full JSON to
//! `OUT/results.compact.jsonl`), and writes the tables to `OUT/COVERAGE.md`.
//!
//! ```text
//! cargo build --release --all-targets
//! target/release/examples/coverage --cases 200 --seed 1 --out /work/coverage-run --jobs 1 --threads 2
//! target/release/examples/coverage --from-results /work/coverage-run/results.jsonl --out DIR
//! ```

mod jobs;
mod report;
mod run;

use clap::Parser;
use ctcal::coverage::{Generator, Method};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(about = "Measures the empirical coverage of ctcal's 95 % intervals")]
pub struct Args {
    /// How many cases to draw.
    #[arg(long, default_value_t = 20)]
    pub cases: u64,
    /// Seed of the first case (case i has seed SEED + i).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Only the cases of these seeds, comma-separated (instead of `--cases` from `--seed`):
    /// to run a study's draws again.
    #[arg(long, value_delimiter = ',')]
    pub only: Option<Vec<u64>>,
    /// Output folder (results.jsonl, results.compact.jsonl, COVERAGE.md).
    #[arg(long)]
    pub out: PathBuf,
    /// Threads of each ctcal command and of writing the cases.
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Methods to run, comma-separated (each on the cases it applies to).
    #[arg(long, default_value = "aps,eppps,screen,fit")]
    pub methods: String,
    /// Cases run at the same time.
    #[arg(long, default_value_t = 1)]
    pub jobs: usize,
    /// Time limit of each command, seconds.
    #[arg(long, default_value_t = 600)]
    pub timeout_s: u64,
    /// Where the case folders are written (default OUT/cases).
    #[arg(long)]
    pub work: Option<PathBuf>,
    /// Keep each case folder after its runs (default: removed; its JSON reproduces it).
    #[arg(long)]
    pub keep_cases: bool,
    /// Keep the runs already in OUT/results.jsonl and run only the missing ones.
    #[arg(long)]
    pub resume: bool,
    /// Only tabulate these results (a results.jsonl, full or compact) into OUT/COVERAGE.md.
    #[arg(long, value_name = "FILE")]
    pub from_results: Option<PathBuf>,
    /// The ctcal binary (default target/release/ctcal).
    #[arg(long)]
    pub ctcal: Option<PathBuf>,
    /// Simulators that make the cases, comma-separated, one chosen at random per case:
    /// ctcal, esim, voltmeter, iebcs (`ctcal::sim::peers`).
    #[arg(long, default_value = "ctcal", value_parser = parse_generators)]
    pub generators: Generators,
}

/// The `--generators` list.
#[derive(Clone, Debug)]
pub struct Generators(pub Vec<Generator>);

fn parse_generators(list: &str) -> Result<Generators, String> {
    list.split(',')
        .map(|name| {
            Generator::named(name.trim()).ok_or_else(|| {
                format!("unknown generator `{name}` (ctcal, esim, voltmeter, iebcs)")
            })
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Generators)
}

fn parse_methods(list: &str) -> anyhow::Result<Vec<Method>> {
    list.split(',')
        .map(|name| {
            Method::parse(name.trim()).ok_or_else(|| {
                anyhow::anyhow!(
                    "--methods: unknown method `{name}` (aps, eppps, eppps_events, screen, fit)"
                )
            })
        })
        .collect()
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    std::fs::create_dir_all(&args.out)?;
    if let Some(results) = &args.from_results {
        return report::write_coverage(results, &args.out, None);
    }
    let methods = parse_methods(&args.methods)?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.max(1))
        .build_global()?;
    let started = std::time::Instant::now();
    let results = jobs::run_all(&args, &methods)?;
    let wall_s = started.elapsed().as_secs_f64();
    report::write_coverage(&results, &args.out, Some((&args, wall_s)))
}
