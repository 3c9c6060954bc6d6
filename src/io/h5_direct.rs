//! Direct chunk reading of compressed 1-D HDF5 datasets.
//!
//! libhdf5 serialises every call (hdf5-metno holds one lock) and inflates a dataset's gzip
//! chunks one after another, so reading an event_utils file is bound by single-threaded
//! zlib. Here the file addresses of the needed chunks are looked up through libhdf5
//! (`H5Dget_chunk_info_by_coord`), and the compressed bytes are read and inflated (zlib-rs)
//! on all cores. Only the filter pipelines event files use are handled (shuffle, deflate,
//! in any order, little-endian fixed-size elements); any other layout, filter, byte order or
//! unallocated chunk makes [`DirectColumn::new`] decline, and the caller reads through the
//! library instead.

use hdf5::filters::Filter;
use rayon::prelude::*;
use std::path::Path;

/// How to undo one filter of the pipeline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Shuffle,
    Deflate,
}

/// A 1-D chunked dataset that can be read chunk by chunk, bypassing libhdf5's inflation.
pub struct DirectColumn {
    dataset: hdf5::Dataset,
    file: std::fs::File,
    /// Bytes in the file: a chunk said to lie beyond is damage, not data.
    file_len: u64,
    len: usize,
    chunk_len: usize,
    element_size: usize,
    /// The filter pipeline in write order.
    pipeline: Vec<Stage>,
}

impl DirectColumn {
    /// `None` when the dataset is not a 1-D chunked little-endian dataset filtered by
    /// shuffle and/or deflate only.
    pub fn new(path: &Path, dataset: &hdf5::Dataset) -> Option<Self> {
        let shape = dataset.shape();
        let chunk = dataset.chunk()?;
        if shape.len() != 1 || chunk.len() != 1 || chunk[0] == 0 {
            return None;
        }
        let dtype = dataset.dtype().ok()?;
        let little = matches!(
            dtype.byte_order(),
            hdf5::datatype::ByteOrder::LittleEndian | hdf5::datatype::ByteOrder::None
        );
        if !little {
            return None;
        }
        let mut pipeline = Vec::new();
        for filter in dataset.filters() {
            pipeline.push(match filter {
                Filter::Shuffle => Stage::Shuffle,
                Filter::Deflate(_) => Stage::Deflate,
                _ => return None,
            });
        }
        let file = std::fs::File::open(path).ok()?;
        let file_len = file.metadata().ok()?.len();
        Some(Self {
            dataset: dataset.clone(),
            file,
            file_len,
            len: shape[0],
            chunk_len: chunk[0],
            element_size: dtype.size(),
            pipeline,
        })
    }

    /// Where chunk `index` lies in the file: (address, stored size, filter mask).
    fn locate(&self, index: usize) -> Option<(u64, u64, u32)> {
        let offset: [hdf5_sys::h5::hsize_t; 1] =
            [(index * self.chunk_len) as hdf5_sys::h5::hsize_t];
        let (mut mask, mut address, mut size) =
            (0u32, 0 as hdf5_sys::h5::haddr_t, 0 as hdf5_sys::h5::hsize_t);
        let id = self.dataset.id();
        // SAFETY: `id` is a live dataset handle (held by `self.dataset`); the out-pointers
        // point to locals; libhdf5 is called under hdf5-metno's global lock.
        let status = hdf5::sync::sync(|| unsafe {
            hdf5_sys::h5d::H5Dget_chunk_info_by_coord(
                id,
                offset.as_ptr(),
                &mut mask,
                &mut address,
                &mut size,
            )
        });
        (status >= 0
            && address != hdf5_sys::h5::HADDR_UNDEF
            && size > 0
            && address
                .checked_add(size)
                .is_some_and(|end| end <= self.file_len))
        .then_some((address, size, mask))
    }

    /// The raw little-endian bytes of elements `range` into `out` (cleared first, so that
    /// buffers are reused); `None` if a chunk cannot be read this way (the caller then reads
    /// through the library).
    pub fn read_into(&self, range: std::ops::Range<usize>, out: &mut Vec<u8>) -> Option<()> {
        out.clear();
        if range.is_empty() {
            return Some(());
        }
        if range.end > self.len {
            return None;
        }
        let first = range.start / self.chunk_len;
        let last = (range.end - 1) / self.chunk_len;
        let located: Vec<(u64, u64, u32)> = (first..=last)
            .map(|i| self.locate(i))
            .collect::<Option<_>>()?;
        let chunk_bytes = self.chunk_len * self.element_size;
        let chunks: Vec<Vec<u8>> = located
            .par_iter()
            .map(|&(address, size, mask)| self.decode_chunk(address, size, mask, chunk_bytes))
            .collect::<Option<_>>()?;
        // copy the wanted elements of each chunk
        let element = self.element_size;
        for (k, chunk) in chunks.iter().enumerate() {
            let chunk_start = (first + k) * self.chunk_len;
            let from = range.start.max(chunk_start) - chunk_start;
            let to = range.end.min(chunk_start + self.chunk_len) - chunk_start;
            out.extend_from_slice(&chunk[from * element..to * element]);
        }
        Some(())
    }

    fn decode_chunk(
        &self,
        address: u64,
        size: u64,
        mask: u32,
        chunk_bytes: usize,
    ) -> Option<Vec<u8>> {
        let mut data = vec![0u8; size as usize];
        read_at(&self.file, &mut data, address).ok()?;
        // undo the filters in reverse order; bit i of the mask means filter i was skipped
        for (position, stage) in self.pipeline.iter().enumerate().rev() {
            if mask & (1 << position) != 0 {
                continue;
            }
            data = match stage {
                Stage::Deflate => inflate(&data, chunk_bytes)?,
                Stage::Shuffle => unshuffle(&data, self.element_size),
            };
        }
        (data.len() == chunk_bytes).then_some(data)
    }
}

#[cfg(unix)]
fn read_at(file: &std::fs::File, buffer: &mut [u8], offset: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buffer, offset)
}

#[cfg(not(unix))]
fn read_at(file: &std::fs::File, buffer: &mut [u8], offset: u64) -> std::io::Result<()> {
    std::os::windows::fs::FileExt::seek_read(file, buffer, offset).and_then(|n| {
        if n == buffer.len() {
            Ok(())
        } else {
            Err(std::io::ErrorKind::UnexpectedEof.into())
        }
    })
}

/// zlib-inflates `data` into exactly `expected` bytes.
fn inflate(data: &[u8], expected: usize) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(expected);
    let mut inflater = flate2::Decompress::new(true);
    match inflater.decompress_vec(data, &mut out, flate2::FlushDecompress::Finish) {
        Ok(flate2::Status::StreamEnd) if out.len() == expected => Some(out),
        _ => None,
    }
}

/// Undoes HDF5's byte shuffle: the i-th byte of every element was stored together.
fn unshuffle(data: &[u8], element_size: usize) -> Vec<u8> {
    if element_size <= 1 {
        return data.to_vec();
    }
    let n = data.len() / element_size;
    let mut out = vec![0u8; data.len()];
    for byte in 0..element_size {
        for i in 0..n {
            out[i * element_size + byte] = data[byte * n + i];
        }
    }
    // a tail shorter than one element is stored unshuffled
    let tail = n * element_size;
    out[tail..].copy_from_slice(&data[tail..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unshuffle_regroups_bytes() {
        // two u16 elements 0x0201, 0x0403 shuffled: low bytes [01 03], high bytes [02 04]
        assert_eq!(unshuffle(&[1, 3, 2, 4], 2), vec![1, 2, 3, 4]);
        assert_eq!(unshuffle(&[7, 8, 9], 1), vec![7, 8, 9]);
    }

    #[test]
    fn direct_reads_equal_library_reads_with_every_supported_pipeline() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("columns.h5");
        let values: Vec<i16> = (0..10_000)
            .map(|i| ((i * 37) % 3001 - 1500) as i16)
            .collect();
        {
            let file = hdf5::File::create(&path).unwrap();
            file.new_dataset_builder()
                .with_data(&values)
                .chunk(1000)
                .deflate(4)
                .create("deflate")
                .unwrap();
            file.new_dataset_builder()
                .with_data(&values)
                .chunk(1000)
                .shuffle()
                .deflate(6)
                .create("both")
                .unwrap();
            file.new_dataset_builder()
                .with_data(&values)
                .chunk(1000)
                .create("plain")
                .unwrap();
            file.new_dataset_builder()
                .with_data(&values)
                .chunk(1000)
                .fletcher32()
                .create("checksummed")
                .unwrap();
        }
        let file = hdf5::File::open(&path).unwrap();
        for name in ["deflate", "both", "plain"] {
            let ds = file.dataset(name).unwrap();
            let column = DirectColumn::new(&path, &ds).unwrap_or_else(|| panic!("{name} declined"));
            for range in [0..10_000, 1234..5678, 999..1001, 9_999..10_000] {
                let mut bytes = Vec::new();
                column.read_into(range.clone(), &mut bytes).unwrap();
                let direct: Vec<i16> = bytes
                    .chunks_exact(2)
                    .map(|b| i16::from_le_bytes([b[0], b[1]]))
                    .collect();
                assert_eq!(direct, values[range].to_vec(), "{name}");
            }
        }
        assert!(DirectColumn::new(&path, &file.dataset("checksummed").unwrap()).is_none());
    }
}

/// How the elements of a column are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElementKind {
    Signed(usize),
    Unsigned(usize),
    Float(usize),
}

impl ElementKind {
    /// The kind of `dtype`, for integer, boolean, enum and 4/8-byte float types.
    pub fn of(dtype: &hdf5::Datatype) -> Option<Self> {
        use hdf5::types::TypeDescriptor as T;
        Some(match dtype.to_descriptor().ok()? {
            T::Integer(size) => ElementKind::Signed(size as usize),
            T::Unsigned(size) => ElementKind::Unsigned(size as usize),
            T::Boolean => ElementKind::Unsigned(1),
            T::Enum(e) if e.signed => ElementKind::Signed(e.size as usize),
            T::Enum(e) => ElementKind::Unsigned(e.size as usize),
            T::Float(size) if matches!(size as usize, 4 | 8) => ElementKind::Float(size as usize),
            _ => return None,
        })
    }

    /// Appends the element values of raw little-endian `bytes` to `out`, converted by
    /// `integer` (integer, boolean and enum elements) or `float` (float elements).
    pub fn decode<T>(
        self,
        bytes: &[u8],
        out: &mut Vec<T>,
        integer: impl Fn(i64) -> T,
        float: impl Fn(f64) -> T,
    ) {
        fn le<const N: usize>(b: &[u8]) -> [u8; N] {
            b.try_into().expect("chunks_exact gives N bytes")
        }
        let ints = |width: usize, f: fn(&[u8]) -> i64| bytes.chunks_exact(width).map(f);
        match self {
            ElementKind::Signed(1) => out.extend(bytes.iter().map(|&b| integer(b as i8 as i64))),
            ElementKind::Unsigned(1) => out.extend(bytes.iter().map(|&b| integer(b as i64))),
            ElementKind::Signed(2) => {
                out.extend(ints(2, |b| i16::from_le_bytes(le(b)) as i64).map(integer))
            }
            ElementKind::Unsigned(2) => {
                out.extend(ints(2, |b| u16::from_le_bytes(le(b)) as i64).map(integer))
            }
            ElementKind::Signed(4) => {
                out.extend(ints(4, |b| i32::from_le_bytes(le(b)) as i64).map(integer))
            }
            ElementKind::Unsigned(4) => {
                out.extend(ints(4, |b| u32::from_le_bytes(le(b)) as i64).map(integer))
            }
            ElementKind::Signed(_) => {
                out.extend(ints(8, |b| i64::from_le_bytes(le(b))).map(integer))
            }
            ElementKind::Unsigned(_) => {
                out.extend(ints(8, |b| u64::from_le_bytes(le(b)) as i64).map(integer))
            }
            ElementKind::Float(8) => out.extend(
                bytes
                    .chunks_exact(8)
                    .map(|b| float(f64::from_le_bytes(le(b)))),
            ),
            ElementKind::Float(_) => out.extend(
                bytes
                    .chunks_exact(4)
                    .map(|b| float(f32::from_le_bytes(le(b)) as f64)),
            ),
        }
    }
}
