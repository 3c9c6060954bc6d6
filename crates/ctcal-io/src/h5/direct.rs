//! Direct chunk reading of compressed 1-D HDF5 datasets.
//!
//! libhdf5 serialises every call (hdf5-metno holds one lock) and inflates a dataset's gzip
//! chunks one after another, so reading an event_utils file is bound by single-threaded
//! zlib. Here the stored bytes of the needed chunks are read through libhdf5
//! (`H5Dget_chunk_storage_size` and `H5Dread_chunk`, each a B-tree lookup; the
//! `H5Dget_chunk_info*` calls walk the whole index and make a pass quadratic in the number
//! of chunks), and decompressed on all cores. Only the filter pipelines event files use are handled (shuffle, deflate,
//! in any order, and Blosc, HDF5 filter 32001 as DSEC writes it ([`super::blosc`]; its
//! filter is also registered with libhdf5 through `blosc-src`); little-endian
//! fixed-size elements); any other layout, filter, byte order or unallocated chunk makes
//! [`DirectColumn::new`] decline, and the caller reads through the library instead. A chunk
//! that does not decode is reported as damage.

use hdf5::filters::Filter;

unsafe extern "C" {
    /// libhdf5 >= 1.10.2 (not bound by hdf5-sys): the stored size of the chunk at `offset`.
    fn H5Dget_chunk_storage_size(
        dset_id: hdf5_sys::h5i::hid_t,
        offset: *const hdf5_sys::h5::hsize_t,
        chunk_bytes: *mut hdf5_sys::h5::hsize_t,
    ) -> hdf5_sys::h5::herr_t;
}
use rayon::prelude::*;
use std::path::Path;

/// How to undo one filter of the pipeline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Shuffle,
    Deflate,
    Blosc,
}

/// Why a direct read did not give the bytes.
#[derive(Debug)]
pub enum DirectError {
    /// Not readable this way (the caller reads through libhdf5).
    Unsupported,
    /// Chunk `chunk` does not decode.
    Damaged { chunk: usize, problem: String },
}

/// A 1-D chunked dataset that can be read chunk by chunk, bypassing libhdf5's inflation.
pub struct DirectColumn {
    dataset: hdf5::Dataset,
    /// Bytes in the file: a chunk said to be larger is damage, not data.
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
                Filter::Blosc(..) => Stage::Blosc,
                _ => return None,
            });
        }
        let file_len = std::fs::metadata(path).ok()?.len();
        Some(Self {
            dataset: dataset.clone(),
            file_len,
            len: shape[0],
            chunk_len: chunk[0],
            element_size: dtype.size(),
            pipeline,
        })
    }

    /// The stored (filtered) bytes of chunk `index` and its filter mask; `None` when the
    /// chunk is not allocated or its size is impossible for the file.
    fn fetch(&self, index: usize) -> Option<(Vec<u8>, u32)> {
        let offset: [hdf5_sys::h5::hsize_t; 1] =
            [(index * self.chunk_len) as hdf5_sys::h5::hsize_t];
        let id = self.dataset.id();
        let mut size: hdf5_sys::h5::hsize_t = 0;
        // SAFETY: `id` is a live dataset handle (held by `self.dataset`); the pointers point
        // to locals; libhdf5 is called under hdf5-metno's global lock.
        let status = hdf5::sync::sync(|| unsafe {
            H5Dget_chunk_storage_size(id, offset.as_ptr(), &mut size)
        });
        if status < 0 || size == 0 || size > self.file_len {
            return None;
        }
        let mut data = vec![0u8; size as usize];
        let mut mask = 0u32;
        // SAFETY: as above; `data` has room for the chunk's stored size, which is what
        // H5Dread_chunk writes.
        let status = hdf5::sync::sync(|| unsafe {
            hdf5_sys::h5d::H5Dread_chunk(
                id,
                hdf5_sys::h5p::H5P_DEFAULT,
                offset.as_ptr(),
                &mut mask,
                data.as_mut_ptr().cast(),
            )
        });
        (status >= 0).then_some((data, mask))
    }

    /// The elements of `range` into `out` (replacing its contents), each chunk decompressed
    /// and converted by `decode` (raw little-endian bytes into values) on its own core.
    pub fn read_decoded<T: Copy + Default + Send>(
        &self,
        range: std::ops::Range<usize>,
        out: &mut Vec<T>,
        decode: impl Fn(&[u8], &mut [T]) + Sync,
    ) -> Result<(), DirectError> {
        out.clear();
        if range.is_empty() {
            return Ok(());
        }
        if range.end > self.len {
            return Err(DirectError::Unsupported);
        }
        let first = range.start / self.chunk_len;
        let last = (range.end - 1) / self.chunk_len;
        // reading is serial (libhdf5 holds one lock), decompressing and converting parallel
        let stored: Vec<(Vec<u8>, u32)> = (first..=last)
            .map(|i| self.fetch(i))
            .collect::<Option<_>>()
            .ok_or(DirectError::Unsupported)?;
        out.resize(range.len(), T::default());
        // each chunk's share of `out`
        let mut pieces = Vec::with_capacity(stored.len());
        let mut rest = out.as_mut_slice();
        for k in 0..stored.len() {
            let chunk_start = (first + k) * self.chunk_len;
            let from = range.start.max(chunk_start);
            let to = range.end.min(chunk_start + self.chunk_len);
            let (piece, tail) = rest.split_at_mut(to - from);
            pieces.push((piece, from - chunk_start));
            rest = tail;
        }
        let chunk_bytes = self.chunk_len * self.element_size;
        let element = self.element_size;
        stored.into_par_iter().zip(pieces).enumerate().try_for_each(
            |(k, ((data, mask), (piece, from)))| {
                let chunk = self
                    .decode_chunk(data, mask, chunk_bytes)
                    .map_err(|problem| DirectError::Damaged {
                        chunk: first + k,
                        problem,
                    })?;
                decode(
                    &chunk[from * element..(from + piece.len()) * element],
                    piece,
                );
                Ok(())
            },
        )
    }

    /// Elements per chunk.
    pub fn chunk_len(&self) -> usize {
        self.chunk_len
    }

    fn decode_chunk(
        &self,
        mut data: Vec<u8>,
        mask: u32,
        chunk_bytes: usize,
    ) -> Result<Vec<u8>, String> {
        // undo the filters in reverse order; bit i of the mask means filter i was skipped
        for (position, stage) in self.pipeline.iter().enumerate().rev() {
            if mask & (1 << position) != 0 {
                continue;
            }
            data = match stage {
                Stage::Deflate => inflate(&data, chunk_bytes).ok_or("does not inflate")?,
                Stage::Shuffle => unshuffle(&data, self.element_size),
                Stage::Blosc => crate::blosc::decompress(&data, chunk_bytes)?,
            };
        }
        if data.len() == chunk_bytes {
            Ok(data)
        } else {
            Err(format!(
                "decodes to {} bytes instead of {chunk_bytes}",
                data.len()
            ))
        }
    }
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
                let mut direct: Vec<i16> = Vec::new();
                column
                    .read_decoded(range.clone(), &mut direct, |bytes, out| {
                        for (o, b) in out.iter_mut().zip(bytes.chunks_exact(2)) {
                            *o = i16::from_le_bytes([b[0], b[1]]);
                        }
                    })
                    .unwrap();
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

    /// Writes the element values of raw little-endian `bytes` into `out` (one value per
    /// element), converted by `integer` (integer, boolean and enum elements) or `float`
    /// (float elements).
    pub fn decode_into<T>(
        self,
        bytes: &[u8],
        out: &mut [T],
        integer: impl Fn(i64) -> T,
        float: impl Fn(f64) -> T,
    ) {
        fn fill<T, const N: usize>(bytes: &[u8], out: &mut [T], f: impl Fn([u8; N]) -> T) {
            for (o, b) in out.iter_mut().zip(bytes.chunks_exact(N)) {
                *o = f(b.try_into().expect("chunks_exact gives N bytes"));
            }
        }
        match self {
            ElementKind::Signed(1) => fill(bytes, out, |b: [u8; 1]| integer(b[0] as i8 as i64)),
            ElementKind::Unsigned(1) => fill(bytes, out, |b: [u8; 1]| integer(b[0] as i64)),
            ElementKind::Signed(2) => fill(bytes, out, |b| integer(i16::from_le_bytes(b) as i64)),
            ElementKind::Unsigned(2) => fill(bytes, out, |b| integer(u16::from_le_bytes(b) as i64)),
            ElementKind::Signed(4) => fill(bytes, out, |b| integer(i32::from_le_bytes(b) as i64)),
            ElementKind::Unsigned(4) => fill(bytes, out, |b| integer(u32::from_le_bytes(b) as i64)),
            ElementKind::Signed(_) => fill(bytes, out, |b| integer(i64::from_le_bytes(b))),
            ElementKind::Unsigned(_) => fill(bytes, out, |b| integer(u64::from_le_bytes(b) as i64)),
            ElementKind::Float(8) => fill(bytes, out, |b| float(f64::from_le_bytes(b))),
            ElementKind::Float(_) => fill(bytes, out, |b| float(f32::from_le_bytes(b) as f64)),
        }
    }
}
