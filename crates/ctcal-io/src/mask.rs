//! Pixel masks (a file of the pixels to keep): a PNG image or a NumPy `.npy` array (H x W, row = y) of the
//! sensor's size; a non-zero value keeps the pixel.

use super::error::InputError;
use crate::events::Sensor;
use std::path::Path;

/// Reads a mask for `sensor`: one flag per pixel, row-major, `true` = keep.
pub fn read_mask(path: &Path, sensor: Sensor) -> Result<Vec<bool>, InputError> {
    crate::files::check_regular(path).map_err(|e| InputError::not_a_file(path, e))?;
    let len = std::fs::metadata(path)
        .map_err(|e| InputError::io(path, e))?
        .len();
    // no mask of this sensor needs more than 8 bytes a pixel plus a header
    if len > 8 * sensor.pixels() as u64 + (1 << 16) {
        return Err(InputError::invalid(
            path,
            format!("the mask file holds {len} bytes, more than a {sensor} mask needs"),
            "give a PNG or .npy mask of the sensor's size (H x W)",
        ));
    }
    let is_npy = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"));
    // what the file claims (shape, dimensions) is checked against the sensor and the file's
    // length before anything is allocated for it
    let (width, height, keep) = if is_npy {
        super::npy::check_header(path, sensor, "mask")?;
        read_npy(path)?
    } else {
        read_image(path, sensor)?
    };
    if (width, height) != (sensor.width as usize, sensor.height as usize) {
        return Err(InputError::invalid(
            path,
            format!("the mask is {width}x{height} (W x H) but the sensor is {sensor}"),
            format!("give a mask of {sensor}, one value per pixel (non-zero = keep)"),
        ));
    }
    Ok(keep)
}

fn read_image(path: &Path, sensor: Sensor) -> Result<(usize, usize, Vec<bool>), InputError> {
    let unreadable = |e: &dyn std::fmt::Display| {
        InputError::invalid(
            path,
            format!("not a readable image ({e})"),
            "give a PNG (non-zero = keep) or a .npy array",
        )
    };
    let open = || {
        image::ImageReader::open(path)
            .and_then(|r| r.with_guessed_format())
            .map_err(|e| unreadable(&e))
    };
    // the dimensions from the header first: a small file may decode to gigabytes
    let (w, h) = open()?.into_dimensions().map_err(|e| unreadable(&e))?;
    if (w as usize, h as usize) != (sensor.width as usize, sensor.height as usize) {
        return Err(InputError::invalid(
            path,
            format!("the mask image is {w}x{h} (W x H) but the sensor is {sensor}"),
            format!("give a mask of {sensor}, one value per pixel (non-zero = keep)"),
        ));
    }
    let mut reader = open()?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(w);
    limits.max_image_height = Some(h);
    // 16-bit RGBA at most, and the decoder's working buffers
    limits.max_alloc = Some(8 * w as u64 * h as u64 + (16 << 20));
    reader.limits(limits);
    let image = reader.decode().map_err(|e| unreadable(&e))?;
    let rgba = image.to_rgba8();
    let (w, h) = rgba.dimensions();
    let keep = rgba
        .pixels()
        .map(|p| p.0[..3].iter().any(|&c| c != 0))
        .collect();
    Ok((w as usize, h as usize, keep))
}

fn read_npy(path: &Path) -> Result<(usize, usize, Vec<bool>), InputError> {
    use ndarray::Array2;
    use ndarray_npy::read_npy;
    let flags = |a: Array2<f64>| -> (usize, usize, Vec<bool>) {
        let (h, w) = a.dim();
        (w, h, a.iter().map(|&v| v != 0.0 && !v.is_nan()).collect())
    };
    if let Ok(a) = read_npy::<_, Array2<bool>>(path) {
        let (h, w) = a.dim();
        return Ok((w, h, a.iter().copied().collect()));
    }
    if let Ok(a) = read_npy::<_, Array2<u8>>(path) {
        return Ok(flags(a.mapv(|v| v as f64)));
    }
    if let Ok(a) = read_npy::<_, Array2<i64>>(path) {
        return Ok(flags(a.mapv(|v| v as f64)));
    }
    if let Ok(a) = read_npy::<_, Array2<f32>>(path) {
        return Ok(flags(a.mapv(|v| v as f64)));
    }
    read_npy::<_, Array2<f64>>(path).map(flags).map_err(|e| {
        InputError::invalid(
            path,
            format!("not a 2-D bool, uint8, int64, float32 or float64 .npy array ({e})"),
            "save the mask with numpy.save(path, mask) as an (H, W) array, non-zero = keep",
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray_npy::WriteNpyExt;

    #[test]
    fn png_and_npy_masks_keep_non_zero_pixels() {
        let dir = tempfile::tempdir().unwrap();
        let sensor = Sensor::new(3, 2);
        let png = dir.path().join("m.png");
        image::GrayImage::from_fn(3, 2, |x, y| image::Luma([if x == y { 255 } else { 0 }]))
            .save(&png)
            .unwrap();
        assert_eq!(
            read_mask(&png, sensor).unwrap(),
            vec![true, false, false, false, true, false]
        );
        let npy = dir.path().join("m.npy");
        let array = ndarray::arr2(&[[0.0f32, 1.0, 0.5], [0.0, 0.0, -2.0]]);
        array
            .write_npy(std::fs::File::create(&npy).unwrap())
            .unwrap();
        assert_eq!(
            read_mask(&npy, sensor).unwrap(),
            vec![false, true, true, false, false, true]
        );
        let e = read_mask(&npy, Sensor::new(2, 3)).unwrap_err().to_string();
        assert!(e.contains("(2, 3)") && e.contains("2x3"), "{e}");
        let e = read_mask(&png, Sensor::new(2, 3)).unwrap_err().to_string();
        assert!(e.contains("3x2") && e.contains("2x3"), "{e}");
    }
}
