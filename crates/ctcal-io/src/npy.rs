//! Per-pixel maps stored as NumPy `.npy` arrays (H x W, row = y): the per-pixel contrast
//! thresholds and leak-rate factors that v2e realises, so that ctcal can simulate with a
//! camera's (or an oracle's) exact pixel population. Read with `ndarray-npy`.

use super::error::InputError;
use crate::events::Sensor;
use std::path::Path;

/// What a `.npy` file's header claims: its element type, order and shape, and where the
/// data start.
#[derive(Clone, Debug, PartialEq)]
pub struct NpyHeader {
    /// NumPy's type string, e.g. `<f4`, `|b1`.
    pub descr: String,
    pub fortran_order: bool,
    pub shape: Vec<u64>,
    /// Bytes of magic, version and header before the data.
    pub data_offset: u64,
}

impl NpyHeader {
    /// Bytes of one element (the digits of `descr`), if stated.
    pub fn item_bytes(&self) -> Option<u64> {
        let digits: String = self
            .descr
            .chars()
            .skip_while(|c| !c.is_ascii_digit())
            .collect();
        digits.parse().ok().filter(|&n| n > 0)
    }
}

/// Reads the header of a `.npy` file (at most 64 KB of it), without reading its data: so
/// that the shape it claims can be checked against the sensor and the file's length before
/// anything is allocated for it.
pub fn read_header(path: &Path) -> Result<NpyHeader, String> {
    use std::io::Read;
    let mut file = std::fs::File::open(path).map_err(|e| format!("cannot read: {e}"))?;
    let (len, prefix) = header_length(&mut file)?;
    if len > 1 << 16 {
        return Err(format!("the .npy header claims {len} bytes"));
    }
    let mut text = vec![0u8; len as usize];
    file.read_exact(&mut text)
        .map_err(|_| "the .npy header is cut short".to_string())?;
    parse_header(&String::from_utf8_lossy(&text), prefix + len)
}

/// Reads the magic and version at the start of a `.npy` file: the length of the header's
/// text that follows, and the bytes before that text (10 in version 1, 12 in 2 and 3).
fn header_length(file: &mut std::fs::File) -> Result<(u64, u64), String> {
    use std::io::Read;
    let mut start = [0u8; 12];
    file.read_exact(&mut start[..10])
        .map_err(|_| "shorter than a .npy header".to_string())?;
    if &start[..6] != b"\x93NUMPY" {
        return Err("not a .npy file (no \\x93NUMPY magic)".into());
    }
    match start[6] {
        1 => Ok((u16::from_le_bytes([start[8], start[9]]) as u64, 10)),
        2 | 3 => {
            file.read_exact(&mut start[10..12])
                .map_err(|_| "shorter than a .npy header".to_string())?;
            Ok((
                u32::from_le_bytes([start[8], start[9], start[10], start[11]]) as u64,
                12,
            ))
        }
        v => Err(format!(".npy format version {v} is not known")),
    }
}

/// The header whose text (a Python dict literal) is `text`, its data starting at
/// `data_offset`: the element type, the order and the shape.
fn parse_header(text: &str, data_offset: u64) -> Result<NpyHeader, String> {
    let descr = value_after(text, "descr")
        .and_then(|v| {
            let quote = v.chars().next().filter(|&c| c == '\'' || c == '"')?;
            v[1..].split(quote).next()
        })
        .ok_or("the .npy header has no 'descr'")?
        .to_string();
    let fortran_order = value_after(text, "fortran_order").is_some_and(|v| v.starts_with("True"));
    let shape = value_after(text, "shape")
        .and_then(|v| v.strip_prefix('('))
        .and_then(|v| v.split(')').next())
        .ok_or("the .npy header has no 'shape'")?;
    let shape = shape
        .split(',')
        .map(str::trim)
        .filter(|d| !d.is_empty())
        .map(|d| d.parse::<u64>())
        .collect::<Result<Vec<u64>, _>>()
        .map_err(|_| format!("the .npy header's shape ({shape}) is not a list of sizes"))?;
    Ok(NpyHeader {
        descr,
        fortran_order,
        shape,
        data_offset,
    })
}

/// The text after `'key':` in a header's dict literal (leading spaces left out), if the
/// key is there.
fn value_after<'t>(text: &'t str, key: &str) -> Option<&'t str> {
    let at = text.find(&format!("'{key}'"))? + key.len() + 2;
    Some(text[at..].trim_start().strip_prefix(':')?.trim_start())
}

/// Checks what a `.npy` file claims before it is read: a 2-D (H, W) array of `sensor`'s size
/// whose data fill the rest of the file exactly. `what` names the array in messages.
pub fn check_header(path: &Path, sensor: Sensor, what: &str) -> Result<NpyHeader, InputError> {
    let header = read_header(path).map_err(|problem| {
        InputError::invalid(
            path,
            problem,
            format!("save the {what} with numpy.save(path, array) as an (H, W) array"),
        )
    })?;
    let (h, w) = (sensor.height as u64, sensor.width as u64);
    if header.shape.len() != 2 || header.shape != [h, w] {
        let shape = header
            .shape
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(", ");
        return Err(InputError::invalid(
            path,
            format!(
                "the .npy header says the {what} has shape ({shape}), but the {sensor} sensor needs ({h}, {w}) (H, W)"
            ),
            format!("give a {what} of {sensor}, one value per pixel, shaped (H, W) = ({h}, {w})"),
        ));
    }
    let len = std::fs::metadata(path)
        .map_err(|e| InputError::io(path, e))?
        .len();
    let item = header.item_bytes().unwrap_or(1);
    let needed = h * w * item;
    if len.saturating_sub(header.data_offset) != needed {
        return Err(InputError::invalid(
            path,
            format!(
                "the .npy header says ({h}, {w}) values of type {} ({needed} bytes), but the file holds {} bytes after its {}-byte header",
                header.descr,
                len.saturating_sub(header.data_offset),
                header.data_offset
            ),
            super::error::FIX_TRUNCATED,
        ));
    }
    Ok(header)
}

/// Reads an H x W float map (float32 or float64) and checks its size against `sensor`.
pub fn read_pixel_map(path: &Path, sensor: Sensor) -> Result<Vec<f32>, InputError> {
    if !path.is_file() {
        return Err(InputError::NotFound {
            path: path.to_path_buf(),
        });
    }
    check_header(path, sensor, "map")?;
    let array: ndarray::Array2<f32> = match ndarray_npy::read_npy::<_, ndarray::Array2<f32>>(path) {
        Ok(a) => a,
        Err(_) => ndarray_npy::read_npy::<_, ndarray::Array2<f64>>(path)
            .map(|a| a.mapv(|v| v as f32))
            .map_err(|e| {
                InputError::invalid(
                    path,
                    format!("not a 2-D float32/float64 .npy array: {e}"),
                    "save the map with numpy.save(path, array.astype(numpy.float32)) as an (H, W) array",
                )
            })?,
    };
    let (h, w) = array.dim();
    if (w, h) != (sensor.width as usize, sensor.height as usize) {
        return Err(InputError::invalid(
            path,
            format!("the map is {w}x{h} (W x H) but the sensor is {sensor}"),
            "give a map with one value per pixel, shaped (H, W)",
        ));
    }
    if let Some(i) = array.iter().position(|v| !v.is_finite()) {
        return Err(InputError::invalid(
            path,
            format!("value at row {}, column {} is not finite", i / w, i % w),
            "replace NaN/inf entries with real values",
        ));
    }
    Ok(array.iter().copied().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headers_are_read_and_checked_before_the_data() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.npy");
        let array = ndarray::Array2::<f32>::zeros((3, 4));
        ndarray_npy::write_npy(&path, &array).unwrap();
        let header = read_header(&path).unwrap();
        assert_eq!(header.shape, vec![3, 4]);
        assert_eq!(header.item_bytes(), Some(4));
        assert!(!header.fortran_order);
        assert!(check_header(&path, Sensor::new(4, 3), "mask").is_ok());
        let e = check_header(&path, Sensor::new(3, 4), "mask")
            .unwrap_err()
            .to_string();
        assert!(e.contains("shape (3, 4)") && e.contains("(4, 3)"), "{e}");
        // a header claiming 100000 x 100000 in a file of a few bytes
        let mut bytes = std::fs::read(&path).unwrap();
        let at = bytes.windows(6).position(|w| w == b"(3, 4)").unwrap();
        bytes.splice(at..at + 6, b"(100000, 100000)".iter().copied());
        std::fs::write(&path, &bytes).unwrap();
        let e = check_header(&path, Sensor::new(4, 3), "mask")
            .unwrap_err()
            .to_string();
        assert!(e.contains("(100000, 100000)"), "{e}");
    }
}
