//! Writing `COVERAGE.md`: how the study was run, then the tables of
//! `ctcal::coverage::summary`.

use crate::Args;
use ctcal::coverage::record::read_jsonl;
use ctcal::coverage::summary::Summary;
use std::path::Path;

fn header(run: Option<(&Args, f64)>, results: &Path) -> String {
    let mut out = String::from("# Coverage of ctcal's 95 % intervals\n\n");
    out.push_str("Random recordings with known parameters (`ctcal::coverage::CaseSpec::draw`: scene family, brightness, speed, APS rate and exposure, thresholds, mismatch and every effect at random strengths; on-screen cases through a random display), each run through `ctcal estimate aps|eppps|screen` and `ctcal fit` with `--json -`; see `benches/coverage/README.md`.\n\n");
    match run {
        Some((args, wall_s)) => out.push_str(&format!(
            "Run: `coverage {} --methods {} --jobs {} --threads {} --timeout-s {} --generators {}`, wall time {:.0} s ({:.1} min) on this machine.\n\n",
            match &args.only {
                Some(seeds) => format!(
                    "--only {}",
                    seeds.iter().map(u64::to_string).collect::<Vec<_>>().join(",")
                ),
                None => format!("--cases {} --seed {}", args.cases, args.seed),
            },
            args.methods, args.jobs, args.threads, args.timeout_s,
            args.generators.0.iter().map(|g| g.name()).collect::<Vec<_>>().join(","),
            wall_s, wall_s / 60.0
        )),
        None => out.push_str(&format!(
            "Tabulated from `{}`.\n\n",
            results.file_name().unwrap_or_default().to_string_lossy()
        )),
    }
    out
}

/// Reads `results` and writes `out/COVERAGE.md`.
pub fn write_coverage(results: &Path, out: &Path, run: Option<(&Args, f64)>) -> anyhow::Result<()> {
    let records = read_jsonl(results)?;
    let summary = Summary::tabulate(&records);
    let text = header(run, results) + &summary.to_markdown();
    let path = out.join("COVERAGE.md");
    std::fs::write(&path, text)?;
    eprintln!(
        "wrote {} ({} runs of {} cases)",
        path.display(),
        summary.runs,
        summary.cases
    );
    Ok(())
}
