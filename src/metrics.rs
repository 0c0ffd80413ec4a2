//! Image error measures: the paper's mean absolute error over all pixels and channels divided
//! by the reference's mean, and companions.

use crate::error::{Error, Result};
use crate::render::Image;

/// How an image differs from a reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageError {
    /// Mean |a − b| over pixels and channels / mean of b (the paper's measure).
    pub mae_over_mean: f64,
    /// √(mean (a − b)²) / mean of b.
    pub rmse_over_mean: f64,
    /// 99th percentile of the per-pixel mean absolute error (over channels) / mean of b.
    pub p99_over_mean: f64,
    /// Signed bias: (mean of a − mean of b) / mean of b, over pixels and channels; positive
    /// when `a` is too bright.
    pub bias: f64,
    /// Per-channel means of a.
    pub mean: [f64; 3],
    /// Per-channel means of b.
    pub reference_mean: [f64; 3],
}

/// Compares `image` with `reference`; errors if their sizes differ.
pub fn compare(image: &Image, reference: &Image) -> Result<ImageError> {
    same_size(image, reference)?;
    let n = image.pixels.len().max(1) as f64;
    let mut mean = [0.0f64; 3];
    let mut reference_mean = [0.0f64; 3];
    let (mut abs, mut sq) = (0.0f64, 0.0f64);
    let mut per_pixel = Vec::with_capacity(image.pixels.len());
    for (a, b) in image.pixels.iter().zip(&reference.pixels) {
        let mut pixel = 0.0;
        for c in 0..3 {
            let (x, y) = (f64::from(a[c]), f64::from(b[c]));
            mean[c] += x / n;
            reference_mean[c] += y / n;
            abs += (x - y).abs();
            sq += (x - y) * (x - y);
            pixel += (x - y).abs() / 3.0;
        }
        per_pixel.push(pixel);
    }
    let scale = reference_mean.iter().sum::<f64>() / 3.0;
    let scale = if scale > 0.0 { scale } else { 1.0 };
    per_pixel.sort_unstable_by(f64::total_cmp);
    let p99 = per_pixel
        .get(per_pixel.len() * 99 / 100)
        .copied()
        .unwrap_or(0.0);
    Ok(ImageError {
        mae_over_mean: abs / (3.0 * n) / scale,
        rmse_over_mean: (sq / (3.0 * n)).sqrt() / scale,
        p99_over_mean: p99 / scale,
        bias: (mean.iter().sum::<f64>() - reference_mean.iter().sum::<f64>()) / 3.0 / scale,
        mean,
        reference_mean,
    })
}

/// Per pixel, the signed error (a − b, averaged over channels) divided by the reference's
/// mean: the map a false-colour error image shows. Errors if the sizes differ.
pub fn signed_error_map(image: &Image, reference: &Image) -> Result<Vec<f32>> {
    same_size(image, reference)?;
    let scale = reference.mean();
    let scale = if scale > 0.0 { scale } else { 1.0 };
    Ok(image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(a, b)| (f64::from((*a - *b).element_sum()) / 3.0 / scale) as f32)
        .collect())
}

fn same_size(image: &Image, reference: &Image) -> Result<()> {
    for (name, i) in [("image", image), ("reference", reference)] {
        if i.pixels.len() as u64 != u64::from(i.width) * u64::from(i.height) {
            return Err(Error::Option {
                option: "compare",
                problem: format!(
                    "the {name} holds {} pixels, not {}x{}",
                    i.pixels.len(),
                    i.width,
                    i.height
                ),
            });
        }
    }
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(Error::Option {
            option: "compare",
            problem: format!(
                "image sizes differ: {}x{} vs {}x{}",
                image.width, image.height, reference.width, reference.height
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn image(pixels: &[[f32; 3]]) -> Image {
        Image {
            width: pixels.len() as u32,
            height: 1,
            pixels: pixels.iter().map(|&p| Vec3::from(p)).collect(),
        }
    }

    #[test]
    fn identical_images_differ_by_nothing() {
        let a = image(&[[0.1, 0.2, 0.3], [1.0, 2.0, 3.0]]);
        let e = compare(&a, &a).unwrap();
        assert_eq!(
            (e.mae_over_mean, e.rmse_over_mean, e.p99_over_mean, e.bias),
            (0.0, 0.0, 0.0, 0.0)
        );
        assert!(signed_error_map(&a, &a).unwrap().iter().all(|&v| v == 0.0));
    }

    #[test]
    fn a_hand_made_pair() {
        // Reference mean = (1+1+1+3+3+3)/6 = 2; |a−b| = 0.5 on three channels of one pixel.
        let b = image(&[[1.0, 1.0, 1.0], [3.0, 3.0, 3.0]]);
        let a = image(&[[1.5, 1.5, 1.5], [3.0, 3.0, 3.0]]);
        let e = compare(&a, &b).unwrap();
        assert!(
            (e.mae_over_mean - (1.5 / 6.0) / 2.0).abs() < 1e-12,
            "{}",
            e.mae_over_mean
        );
        assert!((e.rmse_over_mean - (0.75f64 / 6.0).sqrt() / 2.0).abs() < 1e-12);
        // Mean of a = (4.5 + 9) / 6 = 2.25: 12.5% too bright.
        assert!((e.bias - 0.125).abs() < 1e-12, "{}", e.bias);
        let map = signed_error_map(&a, &b).unwrap();
        assert_eq!(map, vec![0.25, 0.0]);
        let dark = signed_error_map(&b, &a).unwrap();
        assert!((dark[0] + 0.5 / 2.25).abs() < 1e-6, "{dark:?}");
    }

    #[test]
    fn errors_of_both_signs_cancel_in_the_bias_only() {
        // One pixel 0.5 too bright, one 0.5 too dark: bias 0, MAE (0.5 + 0.5)·3 / 6 / 2.
        let b = image(&[[1.0, 1.0, 1.0], [3.0, 3.0, 3.0]]);
        let a = image(&[[1.5, 1.5, 1.5], [2.5, 2.5, 2.5]]);
        let e = compare(&a, &b).unwrap();
        assert!(e.bias.abs() < 1e-12, "{}", e.bias);
        assert!(
            (e.mae_over_mean - 0.25).abs() < 1e-12,
            "{}",
            e.mae_over_mean
        );
        // Two black images: no error and no bias, not −100%.
        let black = image(&[[0.0; 3]]);
        assert_eq!(compare(&black, &black).unwrap().bias, 0.0);
    }

    #[test]
    fn sizes_must_match() {
        let e = compare(&image(&[[0.0; 3]]), &image(&[[0.0; 3], [0.0; 3]])).unwrap_err();
        assert!(
            e.to_string().contains("image sizes differ: 1x1 vs 2x1"),
            "{e}"
        );
        assert!(signed_error_map(&image(&[[0.0; 3]]), &image(&[[0.0; 3], [0.0; 3]])).is_err());
        let mut short = image(&[[0.0; 3], [0.0; 3]]);
        short.pixels.pop();
        let e = compare(&short, &image(&[[0.0; 3], [0.0; 3]])).unwrap_err();
        assert!(e.to_string().contains("holds 1 pixels, not 2x1"), "{e}");
    }
}
