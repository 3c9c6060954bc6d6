//! Blosc 1 buffers (the HDF5 filter 32001 that DSEC and PyTables write): a 16-byte header
//! (`version, versionlz, flags, typesize, nbytes, blocksize, cbytes`), then either the
//! bytes as they are (flag `0x2`) or a table of block offsets and the blocks, each in
//! `typesize` separately compressed streams ("splits") or one, each stream prefixed by its
//! compressed length (equal to the raw length when stored raw), and each block byte-shuffled
//! when flag `0x1` is set. Codec in the top three flag bits: 0 BloscLZ, 1 LZ4, 2 Snappy,
//! 3 zlib, 4 Zstandard. Reference: c-blosc `blosc/blosc.c` (`blosc_d`,
//! `blosc_run_decompression_with_context`).
//!
//! Decoded here for the codecs that matter (Zstandard, LZ4, zlib; byte shuffle or none)
//! rather than only through c-blosc (`blosc-src`, which still handles the rest: BloscLZ,
//! Snappy, bit shuffle): c-blosc decompresses every split with `ZSTD_decompress`, which
//! builds a new Zstandard context and runs `cpuid` each time; on a virtual machine that
//! was half the time of reading a DSEC file (4 KB splits). Here each thread keeps one
//! context.

use std::cell::RefCell;
use std::io::Read;

const HEADER: usize = 16;
const FLAG_SHUFFLE: u8 = 0x1;
const FLAG_MEMCPYED: u8 = 0x2;
const FLAG_BITSHUFFLE: u8 = 0x4;
const FLAG_DONT_SPLIT: u8 = 0x10;
/// c-blosc: splits are used only for type sizes up to this, and blocks of at least
/// `MIN_BUFFERSIZE` elements.
const MAX_SPLITS: usize = 16;
const MIN_BUFFERSIZE: usize = 128;

thread_local! {
    static ZSTD: RefCell<Option<zstd::bulk::Decompressor<'static>>> = const { RefCell::new(None) };
}

fn le32(bytes: &[u8], at: usize) -> Result<usize, String> {
    let b = bytes
        .get(at..at + 4)
        .ok_or_else(|| format!("ends at byte {} inside its block table", bytes.len()))?;
    let v = i32::from_le_bytes(b.try_into().expect("4 bytes"));
    usize::try_from(v).map_err(|_| format!("holds a negative length ({v}) at byte {at}"))
}

/// What decoding needs of a Blosc 1 header.
struct Header {
    flags: u8,
    typesize: usize,
    nbytes: usize,
    blocksize: usize,
}

impl Header {
    /// The codec, in the top three flag bits (0 BloscLZ, 1 LZ4, 2 Snappy, 3 zlib, 4
    /// Zstandard).
    fn codec(&self) -> u8 {
        self.flags >> 5
    }
}

/// Reads and checks the 16-byte header (blosc1 format: byte 0 `version`, 1 `versionlz`, 2
/// `flags`, 3 `typesize`, then little-endian i32 `nbytes` (uncompressed), `blocksize` and
/// `cbytes` (compressed, header included)): `nbytes` must be the chunk's `expected` size,
/// `cbytes` within `data`, the version 1 or 2 and the reserved flag bit `0x8` clear.
fn read_header(data: &[u8], expected: usize) -> Result<Header, String> {
    if data.len() < HEADER {
        return Err("is shorter than a Blosc header".into());
    }
    let (version, flags, typesize) = (data[0], data[2], data[3] as usize);
    let nbytes = le32(data, 4)?;
    let blocksize = le32(data, 8)?;
    let cbytes = le32(data, 12)?;
    if nbytes != expected {
        return Err(format!(
            "claims {nbytes} bytes where the chunk holds {expected}"
        ));
    }
    if cbytes > data.len() {
        return Err(format!("claims {cbytes} bytes but holds {}", data.len()));
    }
    if version == 0 || version > 2 || typesize == 0 || flags & 0x08 != 0 {
        return Err(format!(
            "has an unknown Blosc header (version {version}, flags {flags:#x})"
        ));
    }
    Ok(Header {
        flags,
        typesize,
        nbytes,
        blocksize,
    })
}

/// Decompresses a Blosc buffer into exactly `expected` bytes.
pub fn decompress(data: &[u8], expected: usize) -> Result<Vec<u8>, String> {
    let header = read_header(data, expected)?;
    if header.flags & FLAG_MEMCPYED != 0 {
        return data
            .get(HEADER..HEADER + header.nbytes)
            .map(<[u8]>::to_vec)
            .ok_or_else(|| "is cut short".to_string());
    }
    if header.flags & FLAG_BITSHUFFLE != 0 || !matches!(header.codec(), 1 | 3 | 4) {
        return with_c_blosc(data, expected);
    }
    if header.blocksize == 0 {
        return Err("has a block size of 0".into());
    }
    let mut out = vec![0u8; header.nbytes];
    decode_blocks(data, &header, &mut out)?;
    Ok(out)
}

/// Decodes every block of `data` into its place in `out` (`nbytes` long). blosc1 format:
/// the header is followed by one i32 offset per block (from the start of the buffer);
/// block `j` holds bytes `j * blocksize..` of the result, `blocksize` of them except the
/// last, which holds what is left over.
fn decode_blocks(data: &[u8], header: &Header, out: &mut [u8]) -> Result<(), String> {
    let (nbytes, blocksize) = (header.nbytes, header.blocksize);
    let blocks = nbytes.div_ceil(blocksize);
    let leftover = nbytes % blocksize;
    // reused by every zlib split of the buffer
    let mut split = Vec::new();
    for j in 0..blocks {
        let last = j + 1 == blocks && leftover > 0;
        let size = if last { leftover } else { blocksize };
        let block = &mut out[j * blocksize..j * blocksize + size];
        decode_block(data, header, j, last, block, &mut split)?;
    }
    Ok(())
}

/// How many streams ("splits") a block of `size` bytes is stored in, as c-blosc's
/// `blosc_d` decides: one per byte of the type, unless the header's flag `0x10` says not
/// to split, the type is wider than [`MAX_SPLITS`] bytes, the block holds fewer than
/// [`MIN_BUFFERSIZE`] elements, or it is the leftover block (then one).
fn split_count(header: &Header, size: usize, last: bool) -> usize {
    let typesize = header.typesize;
    if header.flags & FLAG_DONT_SPLIT == 0
        && typesize <= MAX_SPLITS
        && size / typesize >= MIN_BUFFERSIZE
        && !last
    {
        typesize
    } else {
        1
    }
}

/// Decodes block `j` into `block` (its bytes of the result). blosc1 format: the block is
/// its splits one after another, each an i32 compressed length and that many bytes (a
/// length equal to the split's raw size means stored as it is); with flag `0x1` (and a
/// type wider than a byte) the decoded block is byte-shuffled. `split` is a buffer reused
/// for zlib.
fn decode_block(
    data: &[u8],
    header: &Header,
    j: usize,
    last: bool,
    block: &mut [u8],
    split: &mut Vec<u8>,
) -> Result<(), String> {
    let size = block.len();
    let splits = split_count(header, size, last);
    let per_split = size / splits;
    let shuffled = header.flags & FLAG_SHUFFLE != 0 && header.typesize > 1;
    let mut at = le32(data, HEADER + 4 * j)?;
    // unshuffled blocks decompress straight into place; shuffled ones via a buffer
    let mut buffer = if shuffled {
        vec![0u8; size]
    } else {
        Vec::new()
    };
    for s in 0..splits {
        let length = le32(data, at)?;
        at += 4;
        let source = data
            .get(at..at + length)
            .ok_or_else(|| format!("block {j} runs past the end of the buffer"))?;
        at += length;
        let target = if shuffled {
            &mut buffer[s * per_split..(s + 1) * per_split]
        } else {
            &mut block[s * per_split..(s + 1) * per_split]
        };
        if length == per_split {
            target.copy_from_slice(source);
            continue;
        }
        let got = decode_split(header.codec(), j, source, target, split)?;
        if got != per_split {
            return Err(format!(
                "block {j} decompresses to {got} bytes instead of {per_split}"
            ));
        }
    }
    if shuffled {
        unshuffle(&buffer, header.typesize, block);
    }
    Ok(())
}

/// Decompresses one compressed split of block `j`, `source`, into `target` (its raw size)
/// with `codec` (1 LZ4 block, 3 zlib, else Zstandard); the number of bytes it decompresses
/// to (zlib: up to one more than `target` holds, so that an overlong split is told).
/// `split` is a buffer reused for zlib.
fn decode_split(
    codec: u8,
    j: usize,
    source: &[u8],
    target: &mut [u8],
    split: &mut Vec<u8>,
) -> Result<usize, String> {
    let per_split = target.len();
    split.clear();
    Ok(match codec {
        1 => lz4_flex::block::decompress_into(source, target)
            .map_err(|e| format!("block {j}: LZ4 data do not decompress ({e})"))?,
        3 => {
            flate2::read::ZlibDecoder::new(source)
                .take(per_split as u64 + 1)
                .read_to_end(split)
                .map_err(|e| format!("block {j}: zlib data do not decompress ({e})"))?;
            let n = split.len().min(per_split);
            target[..n].copy_from_slice(&split[..n]);
            split.len()
        }
        _ => zstd_into(j, source, target)?,
    })
}

/// Zstandard-decompresses a split of block `j`, `source`, into `target` with this thread's
/// context (made on first use; see the module docs); the number of bytes written.
fn zstd_into(j: usize, source: &[u8], target: &mut [u8]) -> Result<usize, String> {
    ZSTD.with(|cell| {
        let mut cell = cell.borrow_mut();
        if cell.is_none() {
            *cell = Some(
                zstd::bulk::Decompressor::new()
                    .map_err(|e| format!("cannot start Zstandard ({e})"))?,
            );
        }
        cell.as_mut()
            .expect("set above")
            .decompress_to_buffer(source, target)
            .map_err(|e| format!("block {j}: Zstandard data do not decompress ({e})"))
    })
}

/// Undoes Blosc's byte shuffle of one block: byte `b` of element `i` was stored at
/// `b * n + i`; bytes beyond the last whole element are stored as they are.
fn unshuffle(source: &[u8], typesize: usize, out: &mut [u8]) {
    let n = source.len() / typesize;
    if n == 0 {
        out.copy_from_slice(source);
        return;
    }
    match typesize {
        // the sizes of event columns, written so that the loops vectorise
        2 => {
            let (a, b) = source.split_at(n);
            for (o, (&a, &b)) in out.chunks_exact_mut(2).zip(a.iter().zip(b)) {
                o.copy_from_slice(&[a, b]);
            }
        }
        4 => {
            let planes: Vec<&[u8]> = source[..4 * n].chunks_exact(n).collect();
            for (i, o) in out.chunks_exact_mut(4).enumerate() {
                o.copy_from_slice(&[planes[0][i], planes[1][i], planes[2][i], planes[3][i]]);
            }
        }
        _ => {
            for (b, plane) in source[..n * typesize].chunks_exact(n).enumerate() {
                for (i, &v) in plane.iter().enumerate() {
                    out[i * typesize + b] = v;
                }
            }
        }
    }
    out[n * typesize..].copy_from_slice(&source[n * typesize..]);
}

/// c-blosc for what is not decoded here, after its own validation of the buffer.
fn with_c_blosc(data: &[u8], expected: usize) -> Result<Vec<u8>, String> {
    let mut claimed: usize = 0;
    // SAFETY: `data` is a live slice of `data.len()` bytes and `claimed` a local; c-blosc
    // reads at most `data.len()` bytes to validate the header and block offsets.
    let valid = unsafe {
        blosc_src::blosc_cbuffer_validate(data.as_ptr().cast(), data.len(), &mut claimed)
    };
    if valid < 0 || claimed != expected {
        return Err("is not a valid Blosc buffer of the chunk's size".into());
    }
    let mut out = vec![0u8; expected];
    // SAFETY: `out` has room for `expected` bytes, the size the validated header gives; the
    // context version keeps no global state, so several threads may call it.
    let written = unsafe {
        blosc_src::blosc_decompress_ctx(data.as_ptr().cast(), out.as_mut_ptr().cast(), expected, 1)
    };
    if written < 0 || written as usize != expected {
        return Err(format!(
            "does not decompress (c-blosc returned {written}: damaged data, or a codec this build lacks)"
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `data` compressed by c-blosc.
    fn c_blosc(
        data: &[u8],
        typesize: usize,
        shuffle: i32,
        codec: &str,
        blocksize: usize,
    ) -> Vec<u8> {
        let mut out = vec![0u8; data.len() + 16 + 64];
        let name = std::ffi::CString::new(codec).unwrap();
        // SAFETY: buffers of the stated sizes; the context interface needs no global state
        let n = unsafe {
            blosc_src::blosc_compress_ctx(
                5,
                shuffle,
                typesize,
                data.len(),
                data.as_ptr().cast(),
                out.as_mut_ptr().cast(),
                out.len(),
                name.as_ptr(),
                blocksize,
                1,
            )
        };
        assert!(n > 0, "{codec}");
        out.truncate(n as usize);
        out
    }

    fn sample(n: usize) -> Vec<u8> {
        // event-like: slowly rising u32 times with small noise
        (0..n as u32)
            .map(|i| i * 7 + ((i * 2_654_435_761) >> 28))
            .flat_map(|v| v.to_le_bytes())
            .collect()
    }

    #[test]
    fn every_codec_shuffle_and_size_decodes_as_c_blosc_wrote_it() {
        for bytes in [16_384usize, 100_003, 37, 4 * 70_000] {
            let data = sample(bytes.div_ceil(4))[..bytes].to_vec();
            for codec in ["zstd", "lz4", "zlib", "blosclz", "lz4hc"] {
                for shuffle in [0, 1, 2] {
                    for (typesize, blocksize) in [(4, 0), (2, 4096), (1, 0), (8, 16_384)] {
                        let packed = c_blosc(&data, typesize, shuffle, codec, blocksize);
                        let unpacked = decompress(&packed, data.len()).unwrap_or_else(|e| {
                            panic!("{codec} shuffle {shuffle} typesize {typesize}: {e}")
                        });
                        assert!(
                            unpacked == data,
                            "{codec} shuffle {shuffle} typesize {typesize} blocksize {blocksize} {bytes}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn damage_is_an_error_not_a_panic() {
        let data = sample(20_000);
        let packed = c_blosc(&data, 4, 1, "zstd", 0);
        assert!(
            decompress(&packed, data.len() + 1)
                .unwrap_err()
                .contains("claims")
        );
        assert!(decompress(&packed[..packed.len() / 2], data.len()).is_err());
        for at in (16..packed.len()).step_by(97) {
            let mut bad = packed.clone();
            bad[at] ^= 0x5a;
            if let Ok(out) = decompress(&bad, data.len()) {
                assert_eq!(out.len(), data.len());
            }
        }
        assert!(decompress(&[2, 1, 0x91, 4], 16).is_err());
    }
}
