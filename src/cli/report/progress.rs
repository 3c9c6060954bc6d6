//! The report's progress on stderr: one bar over the recordings' stages, with the sequence
//! and stage last finished and the time left.

use super::super::Global;

/// Stages per recording (reading, statistics, estimates, fit, written).
const STAGES: u64 = 5;

pub(super) struct Progress {
    bar: indicatif::ProgressBar,
    /// Stages done per sequence.
    done: std::sync::Mutex<std::collections::BTreeMap<String, u64>>,
}

impl Progress {
    pub fn new(global: &Global, sequences: usize) -> Self {
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
            bar,
            done: Default::default(),
        }
    }

    /// `sequence` finished `stage`.
    pub fn stage(&self, sequence: &str, stage: &str) {
        self.bar.set_message(format!("{sequence}: {stage} done"));
        if let Ok(mut done) = self.done.lock() {
            *done.entry(sequence.to_string()).or_insert(0) += 1;
        }
        self.bar.inc(1);
    }

    /// `sequence` is done (or failed): its remaining stages count as done.
    pub fn finished(&self, sequence: &str, outcome: &str) {
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
