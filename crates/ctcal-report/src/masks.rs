//! The hot-pixel mask of a recording, in the form `--mask` reads: one value per pixel (H x W,
//! row = y), non-zero = keep, so the hot pixels are 0. As an 8-bit grey PNG (255 = keep)
//! and as a NumPy `.npy` array (uint8, 1 = keep).

use crate::stats::hot_pixels::HotPixel;
use ndarray_npy::WriteNpyExt;

/// The mask's values, row-major: 0 at the hot pixels, 1 elsewhere.
pub fn keep_flags(width: usize, height: usize, hot: &[HotPixel]) -> Vec<u8> {
    let mut keep = vec![1u8; width * height];
    for p in hot {
        let (x, y) = (p.x as usize, p.y as usize);
        if x < width && y < height {
            keep[y * width + x] = 0;
        }
    }
    keep
}

/// The mask as a grey PNG (255 = keep, 0 = hot).
pub fn png(width: usize, height: usize, hot: &[HotPixel]) -> Vec<u8> {
    let grey: Vec<u8> = keep_flags(width, height, hot)
        .into_iter()
        .map(|k| k * 255)
        .collect();
    let image =
        image::GrayImage::from_raw(width as u32, height as u32, grey).expect("one value per pixel");
    let mut out = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .expect("encoding a PNG in memory");
    out
}

/// The mask as a `.npy` array, uint8, shape (H, W), 1 = keep.
pub fn npy(width: usize, height: usize, hot: &[HotPixel]) -> Vec<u8> {
    let array = ndarray::Array2::from_shape_vec((height, width), keep_flags(width, height, hot))
        .expect("one value per pixel");
    let mut out = Vec::new();
    array.write_npy(&mut out).expect("writing .npy to memory");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hot(x: u16, y: u16) -> HotPixel {
        HotPixel {
            x,
            y,
            events: 100,
            rate_hz: 50.0,
            z: 9.0,
        }
    }

    #[test]
    fn hot_pixels_are_zero_and_the_rest_kept() {
        assert_eq!(
            keep_flags(3, 2, &[hot(1, 0), hot(2, 1)]),
            [1, 0, 1, 1, 1, 0]
        );
        let image = image::load_from_memory(&png(3, 2, &[hot(0, 1)]))
            .unwrap()
            .to_luma8();
        assert_eq!(image.dimensions(), (3, 2));
        assert_eq!(image.as_raw(), &[255, 255, 255, 0, 255, 255]);
        let array: ndarray::Array2<u8> =
            ndarray_npy::ReadNpyExt::read_npy(&npy(3, 2, &[hot(2, 0)])[..]).unwrap();
        assert_eq!(array.dim(), (2, 3));
        assert_eq!(array[[0, 2]], 0);
        assert_eq!(array.sum(), 5);
    }
}
