//! The flags that set the options the library's messages name: the library words a fix in
//! its own terms ("give the sensor size WxH", `ctcal::hint`); the command names the flag
//! ("pass --sensor WxH").

use ctcal::hint::{Analysis, Hint, Text};

/// The flag that sets `hint`'s option, with its value.
pub fn flag(hint: &Hint) -> String {
    match hint {
        Hint::Sensor(None) => "--sensor WxH".into(),
        Hint::Sensor(Some(sensor)) => format!("--sensor {sensor}"),
        Hint::Force => "--force".into(),
        // only `stats` and `convert` sort; the other commands read a sorted copy
        Hint::Sort => "--sort; only `ctcal stats` and `ctcal convert` take it: for the other commands write a sorted copy first with `ctcal convert INPUT --out SORTED --sort`".into(),
        Hint::Format(None) => "--format".into(),
        Hint::Format(Some(format)) => format!("--format {format}"),
        Hint::TimeWindow => "--start/--end".into(),
        Hint::Topic => "--topic NAME".into(),
        Hint::ImageTopic => "--image-topic NAME".into(),
        Hint::Side(side) => format!("--side {side}"),
        Hint::WriteAs(format) => format!("--to {format}"),
        Hint::RefreshHz => "--refresh-hz HZ".into(),
        Hint::Stimulus => "--stimulus DIR".into(),
        Hint::Roi(roi) => format!("--roi {roi}"),
        Hint::Budget => "a larger --max-events N and --max-pixels N (0: no limit)".into(),
        Hint::Analysis(Analysis::Eppps) => "`ctcal estimate eppps` (no frames needed)".into(),
        Hint::Analysis(Analysis::Fit) => "`ctcal fit`".into(),
        Hint::Analysis(Analysis::Stats) => "`ctcal stats`".into(),
    }
}

/// `text` with its options named by their flags.
pub fn render(text: &Text) -> String {
    text.render(&flag)
}

/// An error and its causes as anyhow's `{:#}` shows them (joined by ": "), each library
/// message with its options named by their flags.
pub fn message(error: &anyhow::Error) -> String {
    error
        .chain()
        .map(cause_message)
        .collect::<Vec<_>>()
        .join(": ")
}

fn cause_message(cause: &(dyn std::error::Error + 'static)) -> String {
    match library_message(cause) {
        Some(text) => render(&text),
        None => cause.to_string(),
    }
}

/// The message of a library error whose fix may name options.
fn library_message(cause: &(dyn std::error::Error + 'static)) -> Option<Text> {
    if let Some(e) = cause.downcast_ref::<ctcal::InputError>() {
        return Some(e.message());
    }
    if let Some(e) = cause.downcast_ref::<ctcal::estimate::EstimateError>() {
        return Some(e.message());
    }
    if let Some(e) = cause.downcast_ref::<ctcal::sim::SimError>() {
        return Some(e.message());
    }
    None
}
