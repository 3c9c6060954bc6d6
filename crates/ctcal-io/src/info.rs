//! What a recording is (the `ctcal info` JSON): format, sensor, events, time span, frames,
//! file size and biases, from one pass over its events.

use super::{Biases, Format, InputError, Recording};
use serde::Serialize;

/// What a recording is.
#[derive(Clone, Debug, Serialize)]
pub struct Info {
    pub format: Format,
    /// HDF5: which layout.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layout: Option<&'static str>,
    /// ROS bags: every topic with its message type and count.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub topics: Vec<super::bag::Topic>,
    pub width: u16,
    pub height: u16,
    pub sensor_source: String,
    pub events: u64,
    pub on_events: u64,
    pub t_first_us: i64,
    pub t_last_us: i64,
    /// Places where a timestamp is earlier than the one before.
    pub timestamps_backwards: u64,
    pub frames: usize,
    pub file_bytes: u64,
    /// Sensor biases saved in or beside the recording.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub biases: Option<Biases>,
}

/// The info of `recording` from a pass over `stream` (its events, opened by the caller,
/// timestamps out of order allowed and counted); `progress` hears of `(done, total)` as the
/// pass goes; also the warning of how the sensor size was resolved, if any.
pub fn info(
    recording: &Recording,
    mut stream: super::EventStream,
    progress: &dyn Fn(u64, u64),
) -> Result<(Info, Option<crate::hint::Text>), InputError> {
    stream.allow_unsorted = true;
    let (mut first, mut last, mut on) = (i64::MAX, i64::MIN, 0u64);
    while let Some(chunk) = stream.next_chunk()? {
        first = first.min(*chunk.t.iter().min().expect("non-empty"));
        last = last.max(*chunk.t.iter().max().expect("non-empty"));
        on += chunk.on.iter().filter(|&&p| p).count() as u64;
        let p = stream.progress();
        progress(p.done, p.total);
    }
    let resolved = recording.resolve_sensor(stream.max_coordinates());
    let info = Info {
        format: recording.format,
        layout: recording.layout(),
        topics: recording.topics().to_vec(),
        width: resolved.sensor.width,
        height: resolved.sensor.height,
        sensor_source: resolved.source.clone(),
        events: stream.events_read(),
        on_events: on,
        t_first_us: first,
        t_last_us: last,
        timestamps_backwards: stream.unsorted_count(),
        frames: recording.frame_times()?.len(),
        file_bytes: std::fs::metadata(recording.event_file())
            .map(|m| m.len())
            .unwrap_or(0),
        biases: recording.biases(),
    };
    Ok((info, resolved.warning))
}
