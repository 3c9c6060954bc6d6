//! The two message types ctcal reads from bags, in ROS1 serialisation (little-endian,
//! strings and arrays prefixed by a `u32` length):
//!
//! - `dvs_msgs/EventArray` (rpg_dvs_ros): `std_msgs/Header header, uint32 height,
//!   uint32 width, dvs_msgs/Event[] events`, each event `uint16 x, uint16 y, time ts,
//!   bool polarity` (13 bytes);
//! - `sensor_msgs/Image`: `Header header, uint32 height, uint32 width, string encoding,
//!   uint8 is_bigendian, uint32 step, uint8[] data`; `mono8` as it is, `mono16` by its high
//!   byte, colour (`rgb8`, `bgr8`, `rgba8`, `bgra8`) to grey with the ITU-R BT.601 weights
//!   (0.299 R + 0.587 G + 0.114 B, as OpenCV's `cvtColor`).
//!
//! `std_msgs/Header` is `uint32 seq, time stamp, string frame_id`; a ROS `time` is `uint32
//! sec, uint32 nsec`, converted to microseconds rounding to the nearest.
//!
//! Types are matched by name, not by their md5sum: writers other than ROS (rosbags,
//! rosbag2 converters) compute it differently.

use crate::events::{EventChunk, TimeUs};

pub const EVENT_ARRAY: &str = "dvs_msgs/EventArray";
pub const IMAGE: &str = "sensor_msgs/Image";

/// Bytes of one serialised `dvs_msgs/Event`.
const EVENT_BYTES: usize = 13;

/// A reader over a message's bytes; every read checks the length.
struct Cursor<'a> {
    bytes: &'a [u8],
    position: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self
            .position
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(format!(
                "the message ends inside {what} (byte {} of {})",
                self.position,
                self.bytes.len()
            ));
        };
        let slice = &self.bytes[self.position..end];
        self.position = end;
        Ok(slice)
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4, what)?.try_into().expect("4 bytes"),
        ))
    }

    fn time(&mut self, what: &str) -> Result<TimeUs, String> {
        let sec = self.u32(what)?;
        let nsec = self.u32(what)?;
        Ok(ros_time_us(sec, nsec))
    }

    /// A length-prefixed byte string.
    fn string(&mut self, what: &str) -> Result<&'a [u8], String> {
        let n = self.u32(what)? as usize;
        self.take(n, what)
    }

    /// `std_msgs/Header`: the stamp.
    fn header(&mut self) -> Result<TimeUs, String> {
        self.u32("the header's seq")?;
        let stamp = self.time("the header's stamp")?;
        self.string("the header's frame_id")?;
        Ok(stamp)
    }
}

/// A ROS time in microseconds, rounded to the nearest.
#[inline]
pub fn ros_time_us(sec: u32, nsec: u32) -> TimeUs {
    sec as TimeUs * 1_000_000 + (nsec as TimeUs + 500) / 1000
}

/// The sensor size an `EventArray` states, and its events appended to `out` (raw: the
/// caller checks coordinates against the sensor).
pub fn event_array(bytes: &[u8], out: &mut EventChunk) -> Result<(u32, u32), String> {
    let mut c = Cursor { bytes, position: 0 };
    c.header()?;
    let height = c.u32("height")?;
    let width = c.u32("width")?;
    let count = c.u32("the event count")? as usize;
    let events = c.take(
        count.saturating_mul(EVENT_BYTES),
        &format!("its {count} events"),
    )?;
    out.t.reserve(count);
    out.x.reserve(count);
    out.y.reserve(count);
    out.on.reserve(count);
    for e in events.chunks_exact(EVENT_BYTES) {
        let x = u16::from_le_bytes([e[0], e[1]]);
        let y = u16::from_le_bytes([e[2], e[3]]);
        let sec = u32::from_le_bytes([e[4], e[5], e[6], e[7]]);
        let nsec = u32::from_le_bytes([e[8], e[9], e[10], e[11]]);
        out.push(ros_time_us(sec, nsec), x, y, e[12] != 0);
    }
    Ok((width, height))
}

/// A decoded grey image.
pub struct GreyImage {
    pub t: TimeUs,
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<u8>,
}

/// The stamp of an `Image` message (without decoding its pixels).
pub fn image_stamp(bytes: &[u8]) -> Result<TimeUs, String> {
    Cursor { bytes, position: 0 }.header()
}

/// Decodes an `Image` message to 8-bit grey; images larger than `max_side` a side are
/// refused.
pub fn image(bytes: &[u8], max_side: u32) -> Result<GreyImage, String> {
    let mut c = Cursor { bytes, position: 0 };
    let t = c.header()?;
    let height = c.u32("height")?;
    let width = c.u32("width")?;
    let encoding = String::from_utf8_lossy(c.string("the encoding")?).to_string();
    let big_endian = c.take(1, "is_bigendian")?[0] != 0;
    let step = c.u32("step")? as usize;
    let data = c.string("the pixel data")?;
    if width == 0 || height == 0 || width > max_side || height > max_side {
        return Err(format!(
            "the image is {width}x{height}; ctcal reads images of 1..={max_side} pixels a side"
        ));
    }
    let layout = ImageLayout {
        width: width as usize,
        height: height as usize,
        channels: channels(&encoding)?,
        step,
        big_endian,
    };
    let pixels = layout.grey(data, &encoding)?;
    Ok(GreyImage {
        t,
        width,
        height,
        pixels,
    })
}

/// Bytes per pixel of an image encoding ctcal reads.
fn channels(encoding: &str) -> Result<usize, String> {
    match encoding {
        "mono8" | "8UC1" => Ok(1),
        "mono16" | "16UC1" => Ok(2),
        "rgb8" | "bgr8" => Ok(3),
        "rgba8" | "bgra8" => Ok(4),
        other => Err(format!(
            "the image encoding is `{other}`; ctcal reads mono8, mono16, rgb8, bgr8, rgba8 and bgra8"
        )),
    }
}

/// How an image's pixels lie in its data: its size, bytes per pixel, bytes per row
/// (`step`, padding included) and the byte order of 16-bit values.
struct ImageLayout {
    width: usize,
    height: usize,
    channels: usize,
    step: usize,
    big_endian: bool,
}

impl ImageLayout {
    /// The 8-bit grey pixels of `data` in `encoding`, row by row without the rows'
    /// padding; refused where `data` is too short for the image.
    fn grey(&self, data: &[u8], encoding: &str) -> Result<Vec<u8>, String> {
        let (w, h, channels, step) = (self.width, self.height, self.channels, self.step);
        if step < w * channels || data.len() < step * (h - 1) + w * channels {
            return Err(format!(
                "the image data ({} bytes, step {step}) is too short for {w}x{h} {encoding}",
                data.len()
            ));
        }
        let mut pixels = Vec::with_capacity(w * h);
        for row in 0..h {
            self.grey_row(
                &data[row * step..row * step + w * channels],
                encoding,
                &mut pixels,
            );
        }
        Ok(pixels)
    }

    /// Appends one row's grey pixels: mono8 as it is, mono16 by its high byte, colour with
    /// the ITU-R BT.601 weights.
    fn grey_row(&self, line: &[u8], encoding: &str, pixels: &mut Vec<u8>) {
        match encoding {
            "mono8" | "8UC1" => pixels.extend_from_slice(line),
            "mono16" | "16UC1" => pixels.extend(
                line.chunks_exact(2)
                    .map(|p| if self.big_endian { p[0] } else { p[1] }),
            ),
            _ => {
                let (r, b) = if encoding.starts_with("rgb") {
                    (0, 2)
                } else {
                    (2, 0)
                };
                pixels.extend(line.chunks_exact(self.channels).map(|p| {
                    (0.299 * p[r] as f32 + 0.587 * p[1] as f32 + 0.114 * p[b] as f32).round() as u8
                }));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(stamp: (u32, u32)) -> Vec<u8> {
        let mut b = 7u32.to_le_bytes().to_vec();
        b.extend_from_slice(&stamp.0.to_le_bytes());
        b.extend_from_slice(&stamp.1.to_le_bytes());
        b.extend_from_slice(&3u32.to_le_bytes());
        b.extend_from_slice(b"cam");
        b
    }

    #[test]
    fn event_arrays_decode_with_rounded_microseconds() {
        let mut b = header((1, 0));
        b.extend_from_slice(&180u32.to_le_bytes());
        b.extend_from_slice(&240u32.to_le_bytes());
        b.extend_from_slice(&2u32.to_le_bytes());
        for (x, y, sec, nsec, p) in [
            (5u16, 6u16, 1u32, 3_811_499u32, 1u8),
            (239, 179, 2, 999_999_600, 0),
        ] {
            b.extend_from_slice(&x.to_le_bytes());
            b.extend_from_slice(&y.to_le_bytes());
            b.extend_from_slice(&sec.to_le_bytes());
            b.extend_from_slice(&nsec.to_le_bytes());
            b.push(p);
        }
        let mut out = EventChunk::default();
        assert_eq!(event_array(&b, &mut out).unwrap(), (240, 180));
        assert_eq!(out.t, vec![1_003_811, 3_000_000]);
        assert_eq!(
            (out.x[1], out.y[1], out.on[0], out.on[1]),
            (239, 179, true, false)
        );
        // a count larger than the message holds
        let e = event_array(&b[..b.len() - 1], &mut EventChunk::default()).unwrap_err();
        assert!(e.contains("its 2 events"), "{e}");
    }

    #[test]
    fn colour_images_become_grey_and_rows_skip_their_padding() {
        let mut b = header((0, 500_000));
        b.extend_from_slice(&1u32.to_le_bytes()); // height
        b.extend_from_slice(&2u32.to_le_bytes()); // width
        b.extend_from_slice(&4u32.to_le_bytes());
        b.extend_from_slice(b"bgr8");
        b.push(0);
        b.extend_from_slice(&8u32.to_le_bytes()); // step with 2 bytes of padding
        b.extend_from_slice(&8u32.to_le_bytes());
        b.extend_from_slice(&[255, 0, 0, 0, 0, 255, 9, 9]); // blue, red
        let image = image(&b, 4096).unwrap();
        assert_eq!((image.t, image.width, image.height), (500, 2, 1));
        assert_eq!(image.pixels, vec![29, 76]);
        assert_eq!(image_stamp(&b).unwrap(), 500);
    }
}
