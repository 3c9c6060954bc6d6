//! The recordings of `ctcal report`'s command line (`ctcal::report::pipeline::inputs`),
//! with its errors worded in the command's flags.

use super::super::BadInput;
use super::ReportArgs;
use ctcal::report::pipeline::Input;
use ctcal::report::pipeline::inputs::{self, InputsError};
use std::path::Path;

fn hinted(e: InputsError) -> BadInput {
    BadInput(match e {
        InputsError::Nothing => {
            "no recordings given\n  fix: ctcal report INPUT... --out DIR (or --dataset NAME=INPUT)"
                .into()
        }
        other => other.to_string(),
    })
}

/// The inputs of the command line, named uniquely (names made safe for paths).
pub(super) fn inputs(args: &ReportArgs) -> Result<Vec<Input>, BadInput> {
    let mut all = Vec::new();
    for path in &args.inputs {
        all.extend(inputs::expand(path, None).map_err(hinted)?);
    }
    for spec in &args.datasets {
        let Some((name, path)) = spec.split_once('=') else {
            return Err(BadInput(format!(
                "--dataset `{spec}` is not NAME=INPUT\n  fix: e.g. --dataset ijrr=recordings/ijrr"
            )));
        };
        all.extend(inputs::expand(Path::new(path), Some(name.trim())).map_err(hinted)?);
    }
    inputs::named(all).map_err(hinted)
}
