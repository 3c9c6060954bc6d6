//! The DSEC HDF5 layout (Gehrig et al., RA-L 2021): `events/x`, `events/y` (uint16),
//! `events/t` (uint32 microseconds after the scalar `t_offset`), `events/p` (uint8), each
//! Blosc/zstd-compressed (level 1, byte shuffle) in 4096-event chunks, and `ms_to_idx` (the
//! index of the first event of each millisecond), as DSEC's own scripts write it. Written
//! from events in memory (for tests and the decoding benchmark), with a ctcal marker
//! attribute.

use super::OutputPolicy;
use crate::error::InputError;
use crate::events::{EventChunk, TimeUs};
use crate::hint::{Hint, Text};
use std::path::Path;

/// Events per chunk of each column.
const CHUNK: usize = 4096;

/// Writes time-sorted `events` in the DSEC layout (`t_offset` = the first event's time).
pub fn write_dsec(
    target: &Path,
    events: &EventChunk,
    policy: &OutputPolicy,
) -> Result<(), InputError> {
    let staged = policy.file(target)?;
    let (t_offset, span) = dsec_time_span(target, events)?;
    let t: Vec<u32> = events.t.iter().map(|&t| (t - t_offset) as u32).collect();
    let ms_to_idx: Vec<u64> = (0..=span / 1000)
        .map(|ms| t.partition_point(|&v| (v as i64) < ms * 1000) as u64)
        .collect();
    create_dsec_file(&staged.partial, target, events, &t, t_offset, &ms_to_idx)?;
    staged.commit()
}

/// The first event's time and the events' span (us), refused unless sorted and within 32 bits.
fn dsec_time_span(target: &Path, events: &EventChunk) -> Result<(TimeUs, TimeUs), InputError> {
    if events.is_empty() || !events.is_time_sorted() {
        return Err(InputError::invalid(
            target,
            "DSEC files hold time-sorted events, at least one",
            Text::from("sort the events first").aside(Hint::Sort),
        ));
    }
    let t_offset = events.t[0];
    let span = events.t[events.len() - 1] - t_offset;
    if span > u32::MAX as i64 {
        return Err(InputError::invalid(
            target,
            format!("the events span {span} us, more than DSEC's 32-bit times hold"),
            "write HDF5 (event_utils) instead",
        ));
    }
    Ok((t_offset, span))
}

/// Creates the HDF5 file at `partial`: the event columns, `t_offset`, `ms_to_idx` and the marker.
fn create_dsec_file(
    partial: &Path,
    target: &Path,
    events: &EventChunk,
    t: &[u32],
    t_offset: TimeUs,
    ms_to_idx: &[u64],
) -> Result<(), InputError> {
    let err = |e: hdf5::Error| InputError::write(target, std::io::Error::other(e.to_string()));
    let p: Vec<u8> = events.on.iter().map(|&on| on as u8).collect();
    let file = hdf5::File::create(partial).map_err(err)?;
    file.create_group("events").map_err(err)?;
    macro_rules! column {
        ($name:expr, $data:expr) => {
            file.new_dataset_builder()
                .chunk(CHUNK.min(events.len()))
                .blosc_zstd(1, true)
                .with_data($data)
                .create($name)
                .map_err(err)?;
        };
    }
    column!("events/x", &events.x);
    column!("events/y", &events.y);
    column!("events/t", t);
    column!("events/p", &p);
    file.new_dataset_builder()
        .with_data(&ndarray::arr0(t_offset))
        .create("t_offset")
        .map_err(err)?;
    file.new_dataset_builder()
        .with_data(ms_to_idx)
        .create("ms_to_idx")
        .map_err(err)?;
    file.new_attr::<hdf5::types::VarLenUnicode>()
        .create("ctcal_version")
        .and_then(|a| {
            a.write_scalar(
                &env!("CARGO_PKG_VERSION")
                    .parse::<hdf5::types::VarLenUnicode>()
                    .expect("ascii"),
            )
        })
        .map_err(err)?;
    Ok(())
}
