//! Per-pixel maps stored as NumPy `.npy` arrays (H x W, row = y): the per-pixel contrast
//! thresholds and leak-rate factors that v2e realises, so that ctcal can simulate with a
//! camera's (or an oracle's) exact pixel population. Read with `ndarray-npy`.

use super::error::InputError;
use crate::events::Sensor;
use std::path::Path;

/// Reads an H x W float map (float32 or float64) and checks its size against `sensor`.
pub fn read_pixel_map(path: &Path, sensor: Sensor) -> Result<Vec<f32>, InputError> {
    if !path.is_file() {
        return Err(InputError::NotFound {
            path: path.to_path_buf(),
        });
    }
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
