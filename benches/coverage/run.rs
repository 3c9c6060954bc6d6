//! Running one method on one case: the `ctcal` binary as a subprocess with `--json -`,
//! bounded threads and a time limit; stdout and stderr go to files beside the case (so a
//! large JSON never blocks a pipe), and the outcome is the parsed JSON or the error.
//!
//! The binary's command line is built here, on the runner's side: the library
//! (`ctcal::coverage`) says which method runs on which case, never how the binary spells it.
//! `tests/cli/coverage.rs` uses this file too.

use ctcal::coverage::{CaseSpec, Method, Outcome, RecordingSpec};
use std::ffi::OsString;
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

/// The command line after `ctcal` (without the output options). The methods that read
/// frames are told the frames' exposure, as a user who knows the camera's setting would
/// (the IJRR text a case is written in has no field for it).
pub fn command_line(method: Method, input: &Path, case: &CaseSpec) -> Vec<OsString> {
    let mut args: Vec<OsString> = match method {
        Method::Fit | Method::FitEvents => vec!["fit".into()],
        Method::EpppsEvents => vec!["estimate".into(), "eppps".into()],
        estimate => vec!["estimate".into(), estimate.name().into()],
    };
    args.push(input.as_os_str().to_owned());
    match method {
        Method::EpppsEvents => args.push("--ignore-frames".into()),
        Method::FitEvents => args.push("--no-frames".into()),
        _ => {}
    }
    let exposure_s = match &case.recording {
        RecordingSpec::Scene { scene } => scene.aps.as_ref().map(|a| a.exposure_s),
        RecordingSpec::Screen { .. } => None,
    };
    if let Some(e) = exposure_s
        && matches!(method, Method::Fit | Method::Aps)
    {
        args.extend(["--exposure-s".into(), e.to_string().into()]);
    }
    args
}

/// The options of every run: the JSON on stdout, no progress or warnings, `threads` worker
/// threads.
fn output_options(threads: usize) -> Vec<String> {
    ["--json", "-", "--quiet", "--threads"]
        .map(String::from)
        .into_iter()
        .chain([threads.to_string()])
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
        .args(command_line(method, input, case))
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
