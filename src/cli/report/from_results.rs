//! `ctcal report --from-results DIR...`: one report of reports made elsewhere (on other
//! machines, or of parts of a dataset): their sequences and files taken as they are, the
//! summary made again by the same merge as a report of recordings.

use super::super::{BadInput, Global};
use super::ReportArgs;
use ctcal::report::pipeline::gather::{GatherError, gather};
use std::path::Path;

pub(super) fn run(args: &ReportArgs, global: &Global) -> anyhow::Result<()> {
    let gathered = gather(&args.from_results).map_err(|e| match e {
        GatherError::Read { path, source } => {
            anyhow::Error::from(ctcal::InputError::io(&path, source))
        }
        other => BadInput(other.to_string()).into(),
    })?;
    let policy = global.outputs(args.from_results.iter().map(|p| p.as_path()));
    policy.check_folder(&args.out)?;
    let staged = policy.folder(&args.out)?;
    for f in &gathered.files {
        staged.write(&f.path, &f.bytes)?;
    }
    let report = ctcal::report::pipeline::merge(
        gathered.outcomes,
        gathered.presets,
        gathered.seed,
        std::iter::once("ctcal".to_string())
            .chain(std::env::args().skip(1))
            .collect(),
    );
    if report.sequences.is_empty() {
        return Err(BadInput(format!(
            "{}: no sequence was reported in them\n  fix: give reports with at least one sequence",
            args.from_results
                .iter()
                .map(|p| Path::new(p).display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ))
        .into());
    }
    // failures carried over from the reports gathered: their kind is not known here
    super::finish(args, global, &report, staged, false)
}
