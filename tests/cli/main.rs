//! ctcal's integration tests: one binary (as ripgrep does), driving the `ctcal` command and
//! the library over the shared real recordings and simulator-oracle cases.

mod biases;
mod common;
mod convert;
mod coverage;
mod datasets;
mod errors;
mod estimate;
mod fit;
mod fit_events_only;
mod from_results;
mod limits;
mod peers;
mod readers;
mod report;
mod report_handover;
mod safety;
mod samples;
mod selection;
mod simulate;
mod stats;
