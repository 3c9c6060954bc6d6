//! Running one method on one case: the `ctcal` binary as a subprocess with `--json -`,
//! bounded threads and a time limit; stdout and stderr go to files beside the case (so a
//! large JSON never blocks a pipe), and the outcome is the parsed JSON or the error.

use super::case::CaseSpec;
use super::method::Method;
use super::record::Outcome;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How each command is run.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// The `ctcal` binary.
    pub binary: PathBuf,
    /// `--threads` of each command.
    pub threads: usize,
    /// A command still running after this is killed and recorded as timed out.
    pub timeout: Duration,
}

/// The last `max` characters of `text`, trimmed.
fn tail(text: &str, max: usize) -> String {
    let text = text.trim();
    let start = text.char_indices().rev().nth(max).map_or(0, |(i, _)| i);
    text[start..].to_string()
}

/// Waits for `child` up to `timeout`; `None` means it was killed.
fn wait(
    child: &mut std::process::Child,
    timeout: Duration,
) -> std::io::Result<Option<std::process::ExitStatus>> {
    let started = Instant::now();
    loop {
        if let Some(status) = child.try_wait()? {
            return Ok(Some(status));
        }
        if started.elapsed() > timeout {
            child.kill()?;
            child.wait()?;
            return Ok(None);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn failed(exit_code: Option<i32>, timed_out: bool, message: impl Into<String>) -> Outcome {
    Outcome::Failed {
        exit_code,
        timed_out,
        message: message.into(),
    }
}

/// Runs `method` on the case folder `input`; returns the outcome and the wall time.
pub fn run_method(
    options: &RunOptions,
    method: Method,
    input: &Path,
    case: &CaseSpec,
) -> (Outcome, f64) {
    let started = Instant::now();
    let outcome = run(options, method, input, case).unwrap_or_else(|e| {
        failed(
            None,
            false,
            format!("could not run {}: {e}", options.binary.display()),
        )
    });
    (outcome, started.elapsed().as_secs_f64())
}

/// The options of every run: the JSON on stdout, no progress or warnings, `threads` worker
/// threads (the binary's options, by name).
fn output_options(threads: usize) -> Vec<String> {
    let threads = threads.to_string();
    [
        ("json", Some("-")),
        ("quiet", None),
        ("threads", Some(threads.as_str())),
    ]
    .into_iter()
    .flat_map(|(name, value)| std::iter::once(format!("--{name}")).chain(value.map(String::from)))
    .collect()
}

fn run(
    options: &RunOptions,
    method: Method,
    input: &Path,
    case: &CaseSpec,
) -> std::io::Result<Outcome> {
    let capture = |stream: &str| input.with_extension(format!("{}.{stream}", method.name()));
    let (stdout_path, stderr_path) = (capture("stdout"), capture("stderr"));
    let mut child = Command::new(&options.binary)
        .args(method.args(input, case))
        .args(output_options(options.threads))
        .env("HDF5_USE_FILE_LOCKING", "FALSE")
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&stdout_path)?)
        .stderr(std::fs::File::create(&stderr_path)?)
        .spawn()?;
    let status = wait(&mut child, options.timeout)?;
    let stdout = std::fs::read(&stdout_path)?;
    let stderr = String::from_utf8_lossy(&std::fs::read(&stderr_path)?).into_owned();
    let _ = std::fs::remove_file(&stdout_path);
    let _ = std::fs::remove_file(&stderr_path);
    Ok(match status {
        None => failed(
            None,
            true,
            format!("timed out after {} s", options.timeout.as_secs()),
        ),
        Some(s) if !s.success() => failed(s.code(), false, tail(&stderr, 2000)),
        Some(_) => match serde_json::from_slice(&stdout) {
            Ok(output) => Outcome::Ok {
                output: Some(output),
            },
            Err(e) => failed(Some(0), false, format!("stdout is not JSON: {e}")),
        },
    })
}
