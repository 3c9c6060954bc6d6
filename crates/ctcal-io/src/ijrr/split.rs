//! Text parsing on two threads: the whole lines at the front of a block are cut at a line
//! boundary near their middle and the halves are parsed at once (`rayon::join`), the second
//! into its own chunk that is then appended. Events, errors and their line numbers are
//! those of parsing line by line: an error in the first half wins; the second half's parser
//! counts its lines from 0 and they are numbered on once the first half has counted its own
//! (an error of the second half is found again from the right line, a cold path); and the
//! order of the second half's times is checked after both, against the first half's last
//! time. What runs on one thread before the halves start is a vectorised newline count
//! (memchr's `count`), not a walk from line to line.

use super::super::error::InputError;
use super::super::order::OrderCheck;
use super::{LineParser, MIN_SPLIT_BYTES};
use crate::events::{CHUNK_EVENTS, EventChunk};

/// Parses the whole lines at the front of `available` (at most as many as `out` has room
/// for) in two halves on two threads, appending their events to `out`; returns the bytes
/// consumed, 0 when there are too few to be worth splitting (then nothing is parsed).
/// `lines` must have seen a data line (so that no `width height` line can follow).
pub(super) fn parse_halves(
    available: &[u8],
    lines: &mut LineParser,
    out: &mut EventChunk,
    second: &mut EventChunk,
) -> Result<usize, InputError> {
    debug_assert!(lines.seen_data_line && lines.check_order);
    let room = CHUNK_EVENTS.saturating_sub(out.len());
    // a line holds at most one event: `room` lines cannot overfill the chunk
    let Some(end) = end_of_lines(available, room) else {
        return Ok(0);
    };
    if end < MIN_SPLIT_BYTES {
        return Ok(0);
    }
    let region = &available[..end];
    let middle = end / 2 + memchr::memchr(b'\n', &region[end / 2..]).map_or(0, |i| i + 1);
    let (first_text, second_text) = region.split_at(middle);
    let mut second_lines = lines.continuation(0);
    second.clear();
    let (first_result, second_result) = rayon::join(
        || parse_lines(lines, first_text, out),
        || parse_lines(&mut second_lines, second_text, second),
    );
    first_result?;
    // the first half's parser has counted its lines: the second half's follow them
    let second_start = lines.line;
    if second_result.is_err() {
        // the error again, its line numbered as one thread numbers it
        parse_lines(&mut lines.continuation(second_start), second_text, second)?;
        second_result?;
    }
    lines.order.check_all(&second.t, |i| {
        format!(
            "line {}",
            line_of_event(&second_lines, second_text, second_start, i)
        )
    });
    out.extend_from(second);
    lines.line = second_start + second_lines.line;
    Ok(end)
}

/// Bytes per piece of [`end_of_lines`]' search for the `n`-th newline.
const COUNT_PIECE_BYTES: usize = 64 << 10;

/// The end (one past its newline) of the first `n` whole lines of `text`, or of all its
/// whole lines where it has fewer; `None` where it has none or `n` is 0. Newlines are
/// counted a piece at a time with memchr's vectorised `count`, and only the piece holding
/// the `n`-th is walked newline by newline.
fn end_of_lines(text: &[u8], n: usize) -> Option<usize> {
    if n == 0 {
        return None;
    }
    let mut left = n;
    let mut start = 0;
    while start < text.len() {
        let piece = &text[start..text.len().min(start + COUNT_PIECE_BYTES)];
        let newlines = memchr::memchr_iter(b'\n', piece).count();
        if newlines >= left {
            return memchr::memchr_iter(b'\n', piece)
                .nth(left - 1)
                .map(|i| start + i + 1);
        }
        left -= newlines;
        start += piece.len();
    }
    memchr::memrchr(b'\n', text).map(|i| i + 1)
}

/// Parses `text`, whole lines each ending in a newline.
fn parse_lines(
    lines: &mut LineParser,
    text: &[u8],
    out: &mut EventChunk,
) -> Result<(), InputError> {
    let mut start = 0;
    for end in memchr::memchr_iter(b'\n', text) {
        lines.parse(&text[start..end], out)?;
        start = end + 1;
    }
    Ok(())
}

/// The line number of the `index`-th event of `text` (whose first line follows line
/// `start`), found by parsing it again: only for naming the place of an order violation.
#[cold]
fn line_of_event(template: &LineParser, text: &[u8], start: usize, index: usize) -> usize {
    let mut lines = template.continuation(start);
    let mut scratch = EventChunk::default();
    let mut line_start = 0;
    for end in memchr::memchr_iter(b'\n', text) {
        // the text parsed without error the first time
        let _ = lines.parse(&text[line_start..end], &mut scratch);
        if scratch.len() > index {
            break;
        }
        line_start = end + 1;
    }
    lines.line
}

impl LineParser {
    /// A parser of the lines after `line` of a block this parser is reading, past its data
    /// line: the same file and sensor, its order checked by the caller.
    fn continuation(&self, line: usize) -> LineParser {
        LineParser {
            path: self.path.clone(),
            line,
            seen_data_line: true,
            sensor: self.sensor,
            order: OrderCheck::default(),
            check_order: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::{EventChunk, OpenOptions, Recording};

    type Read = Result<EventChunk, String>;

    /// Every event of `text` (or the error's message) read on one thread and on two.
    fn read(text: &str) -> (Read, Read) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("events.txt");
        std::fs::write(&path, text).unwrap();
        (read_on(&path, 1), read_on(&path, 2))
    }

    fn read_on(path: &std::path::Path, threads: usize) -> Read {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let recording = Recording::open(path, &OpenOptions::default()).unwrap();
            let mut stream = recording.events().map_err(|e| e.to_string())?;
            let mut all = EventChunk::default();
            while let Some(chunk) = stream.next_chunk().map_err(|e| e.to_string())? {
                all.extend_from(chunk);
            }
            Ok(all)
        })
    }

    /// 600,000 event lines (two chunks, several blocks), with `edit` applied to the lines.
    fn lines(edit: impl Fn(usize, String) -> String) -> String {
        let mut text = String::from("# comment\n");
        for i in 0..600_000usize {
            let line = format!(
                "{}.{:06} {} {} {}",
                i / 100_000,
                i % 100_000,
                i % 240,
                i % 180,
                i % 2
            );
            text.push_str(&edit(i, line));
            text.push('\n');
        }
        text
    }

    #[test]
    fn the_end_of_n_lines_is_found_across_count_pieces() {
        use super::{COUNT_PIECE_BYTES, end_of_lines};
        // lines of 1 to 9 bytes (newline included), longer than three count pieces
        let mut text = Vec::new();
        let mut ends = Vec::new();
        while text.len() < 3 * COUNT_PIECE_BYTES + 100 {
            let len = ends.len() % 9;
            text.extend(std::iter::repeat_n(b'7', len));
            text.push(b'\n');
            ends.push(text.len());
        }
        text.extend_from_slice(b"12 3 4"); // a last line without its newline
        for n in [1, 2, 17, 7281, 7282, ends.len() - 1, ends.len()] {
            assert_eq!(end_of_lines(&text, n), Some(ends[n - 1]), "{n}");
        }
        assert_eq!(end_of_lines(&text, ends.len() + 5), ends.last().copied());
        assert_eq!(end_of_lines(&text, 0), None);
        assert_eq!(end_of_lines(b"no newline", 3), None);
    }

    #[test]
    fn two_threads_read_what_one_reads() {
        let text = lines(|i, line| {
            if i % 9_999 == 0 {
                format!("{line}\n\n# note")
            } else {
                line
            }
        });
        let (one, two) = read(&text);
        let one = one.unwrap();
        assert_eq!(one.len(), 600_000);
        assert!(one == two.unwrap());
    }

    #[test]
    fn errors_name_the_same_line_on_two_threads() {
        // a bad line, a pixel outside the stated sensor and times going backwards, each
        // placed in the first half, at a half's edge and in the second half of blocks
        let mut errors = 0;
        for at in [
            1usize, 50_000, 90_000, 150_000, 262_143, 262_144, 400_001, 599_999,
        ] {
            let bad = lines(|i, line| if i == at { "0.5 1 x 1".into() } else { line });
            let backwards = lines(|i, line| {
                if i == at {
                    "0.000001 1 1 1".into()
                } else {
                    line
                }
            });
            let sized = format!(
                "240 180\n{}",
                lines(|i, line| if i == at { "0.5 240 1 1".into() } else { line })
            );
            for text in [bad, backwards, sized] {
                let (one, two) = read(&text);
                errors += one.is_err() as usize;
                assert!(one == two, "at {at}: {:?} vs {:?}", one.err(), two.err());
            }
        }
        // every case an error but the one going backwards at line 2 (1 us after 0)
        assert_eq!(errors, 8 * 3 - 1);
    }
}
