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

/// The image averaged over blocks of `block` × `block` pixels (rows and columns that do not
/// fill a block are left out). Comparing averages of blocks takes a noisy reference's noise
/// down by about `block` while errors that span several pixels stay.
pub fn block_average(image: &Image, block: u32) -> Result<Image> {
    image.check()?;
    let (w, h) = (image.width / block.max(1), image.height / block.max(1));
    if block == 0 || w == 0 || h == 0 {
        return Err(Error::Option {
            option: "block",
            problem: format!(
                "{block} does not fit a {} × {} image",
                image.width, image.height
            ),
        });
    }
    let b = block as usize;
    let mut pixels = vec![glam::Vec3::ZERO; (w * h) as usize];
    for y in 0..h as usize * b {
        for x in 0..w as usize * b {
            pixels[(y / b) * w as usize + x / b] += image.pixels[y * image.width as usize + x];
        }
    }
    let n = (b * b) as f32;
    for p in &mut pixels {
        *p /= n;
    }
    Ok(Image {
        width: w,
        height: h,
        pixels,
    })
}

/// [`compare`] on averages over blocks of `block` × `block` pixels ([`block_average`]);
/// `block` 1 is [`compare`] itself.
pub fn compare_blocks(image: &Image, reference: &Image, block: u32) -> Result<ImageError> {
    same_size(image, reference)?;
    if block == 1 {
        return compare(image, reference);
    }
    compare(
        &block_average(image, block)?,
        &block_average(reference, block)?,
    )
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

/// How far above its 3 × 3 neighbourhood's median a pixel must be to count as a sparkle
/// ([`sparkles`]).
pub const SPARKLE_RATIO: f32 = 1.3;

/// Sparkles: pixels (not on the border) whose brightness (the mean of their channels) exceeds
/// `ratio` times the median of their 3 × 3 neighbourhood, themselves included. An isolated
/// bright pixel is one; an edge or a highlight a few pixels wide is not, since the median
/// then lies among the bright ones. A converged render of a scene of diffuse surfaces has
/// few; each one in an image is noise a viewer sees as a white dot.
pub fn sparkles(image: &Image, ratio: f32) -> Result<usize> {
    image.check()?;
    let (w, h) = (image.width as usize, image.height as usize);
    let lum: Vec<f32> = image.pixels.iter().map(|p| p.element_sum() / 3.0).collect();
    let mut count = 0;
    let mut window = [0.0f32; 9];
    for y in 1..h.saturating_sub(1) {
        for x in 1..w.saturating_sub(1) {
            let mut k = 0;
            for yy in y - 1..=y + 1 {
                for xx in x - 1..=x + 1 {
                    window[k] = lum[yy * w + xx];
                    k += 1;
                }
            }
            window.sort_unstable_by(f32::total_cmp);
            let v = lum[y * w + x];
            if v > ratio * window[4] && v > 0.0 {
                count += 1;
            }
        }
    }
    Ok(count)
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

    fn image_of(width: u32, height: u32, f: impl Fn(u32, u32) -> f32) -> Image {
        let pixels = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| Vec3::splat(f(x, y)))
            .collect();
        Image {
            width,
            height,
            pixels,
        }
    }

    #[test]
    fn a_lone_bright_pixel_is_a_sparkle_and_a_line_three_wide_is_not() {
        // One pixel at 1.5 on a field of 1 stands above its neighbourhood's median (1); a
        // band three pixels wide at 2 does not: its middle's 3 × 3 median is 2, and its edges'
        // is 2 as well (six of nine in the band).
        let lone = image_of(8, 8, |x, y| if (x, y) == (4, 3) { 1.5 } else { 1.0 });
        assert_eq!(sparkles(&lone, SPARKLE_RATIO).unwrap(), 1);
        let just_under = image_of(8, 8, |x, y| if (x, y) == (4, 3) { 1.29 } else { 1.0 });
        assert_eq!(sparkles(&just_under, SPARKLE_RATIO).unwrap(), 0);
        let band = image_of(8, 8, |x, _| if (3..6).contains(&x) { 2.0 } else { 1.0 });
        assert_eq!(sparkles(&band, SPARKLE_RATIO).unwrap(), 0);
        // On the border a pixel has no full neighbourhood: not counted.
        let edge = image_of(8, 8, |x, y| if (x, y) == (0, 3) { 5.0 } else { 1.0 });
        assert_eq!(sparkles(&edge, SPARKLE_RATIO).unwrap(), 0);
    }

    #[test]
    fn block_averages_by_hand() {
        // 5 × 3 image, blocks of 2: the last column and row are left out; 2 × 1 blocks.
        let pixels = (0..15).map(|i| Vec3::splat(i as f32)).collect();
        let image = Image {
            width: 5,
            height: 3,
            pixels,
        };
        let b = block_average(&image, 2).unwrap();
        assert_eq!((b.width, b.height), (2, 1));
        // (0 + 1 + 5 + 6) / 4 = 3, (2 + 3 + 7 + 8) / 4 = 5.
        assert_eq!(b.pixels, vec![Vec3::splat(3.0), Vec3::splat(5.0)]);
        assert!(block_average(&image, 4).is_err());
        assert!(block_average(&image, 0).is_err());
        // Errors of both signs within a block cancel: 0 at blocks of 2, not at 1.
        let a = Image {
            width: 2,
            height: 2,
            pixels: vec![Vec3::ONE; 4],
        };
        let mut r = a.clone();
        r.pixels[0] = Vec3::splat(2.0);
        r.pixels[1] = Vec3::ZERO;
        assert_eq!(compare_blocks(&a, &r, 2).unwrap().mae_over_mean, 0.0);
        assert_eq!(compare_blocks(&a, &r, 1).unwrap().mae_over_mean, 0.5);
    }
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
