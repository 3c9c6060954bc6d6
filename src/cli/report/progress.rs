//! The report's progress on stderr: one bar over the recordings' stages, with the sequence
//! and stage last finished and the time left, and the warnings of reading each recording.

use super::super::{Global, warn};
use ctcal::report::pipeline::{Event, Stage};

/// Stages per recording (reading, statistics, estimates, fit, written).
const STAGES: u64 = Stage::ALL.len() as u64 + 1;

pub(super) struct Progress<'a> {
    global: &'a Global,
    bar: indicatif::ProgressBar,
    /// Stages done per sequence.
    done: std::sync::Mutex<std::collections::BTreeMap<String, u64>>,
}

impl<'a> Progress<'a> {
    pub fn new(global: &'a Global, sequences: usize) -> Self {
        let bar = if global.quiet {
            indicatif::ProgressBar::hidden()
        } else {
            indicatif::ProgressBar::with_draw_target(
                Some(sequences as u64 * STAGES),
                indicatif::ProgressDrawTarget::stderr(),
            )
        };
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "report [{bar:30}] {percent:>3}% {elapsed_precise} (ETA {eta_precise}) {msg}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        );
        Self {
            global,
            bar,
            done: Default::default(),
        }
    }

    /// What the pipeline tells of `sequence`.
    pub fn event(&self, sequence: &str, event: Event) {
        match event {
            Event::Done(stage) => self.stage(sequence, stage.name()),
            Event::Warning(message) => warn(self.global, message),
            Event::Finished(written) => {
                self.finished(sequence, if written { "written" } else { "failed" })
            }
        }
    }

    /// `sequence` finished `stage`.
    fn stage(&self, sequence: &str, stage: &str) {
        self.bar.set_message(format!("{sequence}: {stage} done"));
        if let Ok(mut done) = self.done.lock() {
            *done.entry(sequence.to_string()).or_insert(0) += 1;
        }
        self.bar.inc(1);
    }

    /// `sequence` is done (or failed): its remaining stages count as done.
    fn finished(&self, sequence: &str, outcome: &str) {
        let done = self
            .done
            .lock()
            .map_or(0, |d| d.get(sequence).copied().unwrap_or(0));
        self.bar.set_message(format!("{sequence}: {outcome}"));
        self.bar.inc(STAGES.saturating_sub(done));
    }

    pub fn clear(&self) {
        self.bar.finish_and_clear();
    }
}
