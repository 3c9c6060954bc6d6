//! Decoding on a second thread: while the caller consumes one chunk, the next is decoded.
//! Decoding and statistics each run near 100 M events/s on one core, so on two cores a
//! pass runs at the speed of the slower of the two instead of their sum. Chunk buffers
//! are recycled between the threads; the order of chunks is kept.

use super::{EventStream, InputError, Progress};
use crate::events::EventChunk;
use std::sync::mpsc::{channel, sync_channel};

/// Calls `f` on every chunk of `stream` in order, decoding ahead on another thread when
/// `read_ahead` is set.
pub fn for_each_chunk(
    stream: &mut EventStream,
    read_ahead: bool,
    mut f: impl FnMut(&EventChunk, Progress),
) -> Result<(), InputError> {
    if !read_ahead {
        while stream.next_chunk()?.is_some() {
            f(stream.current_chunk(), stream.progress());
        }
        return Ok(());
    }
    std::thread::scope(|scope| {
        let (full_tx, full_rx) = sync_channel::<Result<(EventChunk, Progress), InputError>>(2);
        let (empty_tx, empty_rx) = channel::<EventChunk>();
        scope.spawn(move || {
            loop {
                let spare = empty_rx.try_recv().unwrap_or_default();
                let message = match stream.next_chunk_swapped(spare) {
                    Ok(Some(chunk)) => Ok((chunk, stream.progress())),
                    Ok(None) => break,
                    Err(e) => Err(e),
                };
                let failed = message.is_err();
                if full_tx.send(message).is_err() || failed {
                    break;
                }
            }
        });
        for message in full_rx {
            let (chunk, progress) = message?;
            f(&chunk, progress);
            // the decoder may have finished; a closed channel just drops the buffer
            let _ = empty_tx.send(chunk);
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{OpenOptions, Recording};

    #[test]
    fn read_ahead_delivers_the_same_chunks_in_order() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("events.txt");
        let mut text = String::new();
        for i in 0..700_000u32 {
            text.push_str(&format!(
                "{}.{:06} {} {} {}\n",
                i / 1_000_000,
                i % 1_000_000,
                i % 240,
                i % 180,
                i % 2
            ));
        }
        std::fs::write(&path, text).unwrap();
        let recording = Recording::open(&path, &OpenOptions::default()).unwrap();
        let mut collected = [EventChunk::default(), EventChunk::default()];
        for (slot, ahead) in [(0, false), (1, true)] {
            let mut stream = recording.events().unwrap();
            for_each_chunk(&mut stream, ahead, |chunk, _| {
                collected[slot].extend_from(chunk)
            })
            .unwrap();
        }
        assert_eq!(collected[0].len(), 700_000);
        assert!(collected[0] == collected[1]);
    }

    #[test]
    fn errors_come_through_the_read_ahead_thread() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("events.txt");
        std::fs::write(&path, "0.1 1 1 1\n0.2 x 1 1\n").unwrap();
        let recording = Recording::open(
            &path,
            &OpenOptions {
                format: Some(crate::Format::Ijrr),
                ..OpenOptions::default()
            },
        )
        .unwrap();
        let mut stream = recording.events().unwrap();
        let e = for_each_chunk(&mut stream, true, |_, _| {}).unwrap_err();
        assert!(e.to_string().contains("line 2"), "{e}");
    }
}
