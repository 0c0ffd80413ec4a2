//! A linear radiance image, written as OpenEXR (32-bit float RGB) and as a tone-mapped sRGB PNG
//! for people to look at.

use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};

/// Outgoing radiance per pixel (W·sr⁻¹·m⁻², linear RGB), row-major from the top-left corner.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, row by row.
    pub pixels: Vec<Vec3>,
}

impl Image {
    /// Mean over all pixels and channels.
    pub fn mean(&self) -> f64 {
        let sum: f64 = self.pixels.iter().map(|p| f64::from(p.element_sum())).sum();
        sum / (3 * self.pixels.len().max(1)) as f64
    }

    /// Whether the pixels fill width × height exactly (a host may have built it by hand).
    pub fn check(&self) -> Result<()> {
        let size = u64::from(self.width) * u64::from(self.height);
        if size == 0 || size != self.pixels.len() as u64 {
            return Err(Error::argument(
                "image",
                format!(
                    "{} pixels for a {} × {} image",
                    self.pixels.len(),
                    self.width,
                    self.height
                ),
            ));
        }
        Ok(())
    }

    /// Writes linear OpenEXR.
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        self.check()?;
        let data: Vec<f32> = self.pixels.iter().flat_map(|p| p.to_array()).collect();
        let buffer = ::image::Rgb32FImage::from_raw(self.width, self.height, data)
            .ok_or_else(|| Error::argument("image", "too large to write"))?;
        buffer
            .save_with_format(path, ::image::ImageFormat::OpenExr)
            .map_err(|e| write_error(path, e))
    }

    /// Reads a linear OpenEXR image (RGB; alpha is dropped).
    pub fn read_exr(path: &Path) -> Result<Image> {
        let decoded = ::image::ImageReader::open(path)
            .map_err(|source| Error::Read {
                path: path.into(),
                cause: source,
            })?
            .with_guessed_format()
            .map_err(|source| Error::Read {
                path: path.into(),
                cause: source,
            })?
            .decode()
            .map_err(|e| Error::scene(path, None, format!("cannot decode the image: {e}")))?
            .into_rgb32f();
        let (width, height) = decoded.dimensions();
        let pixels = decoded.pixels().map(|p| Vec3::from(p.0)).collect();
        Ok(Image {
            width,
            height,
            pixels,
        })
    }

    /// An exposure for `write_png`: maps the log-average luminance of the lit pixels to 0.18
    /// (Reinhard's key value), so a visible light does not darken the rest.
    pub fn auto_exposure(&self) -> f32 {
        let lum: Vec<f64> = self
            .pixels
            .iter()
            .map(|p| f64::from(p.dot(Vec3::new(0.2126, 0.7152, 0.0722))))
            .filter(|&l| l > 0.0 && l.is_finite())
            .collect();
        if lum.is_empty() {
            return 1.0;
        }
        let log_average = (lum.iter().map(|l| l.ln()).sum::<f64>() / lum.len() as f64).exp();
        (0.18 / log_average) as f32
    }

    /// Writes an 8-bit sRGB PNG after multiplying by `exposure` and clipping.
    pub fn write_png(&self, path: &Path, exposure: f32) -> Result<()> {
        self.check()?;
        let data: Vec<u8> = self
            .pixels
            .iter()
            .flat_map(|p| (*p * exposure).to_array())
            .map(|v| (srgb(v.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8)
            .collect();
        let buffer = ::image::RgbImage::from_raw(self.width, self.height, data)
            .ok_or_else(|| Error::argument("image", "too large to write"))?;
        buffer
            .save_with_format(path, ::image::ImageFormat::Png)
            .map_err(|e| write_error(path, e))
    }
}

/// The sRGB transfer function of a linear value in [0, 1].
pub(crate) fn srgb(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

fn write_error(path: &Path, e: ::image::ImageError) -> Error {
    match e {
        ::image::ImageError::IoError(source) => Error::Write {
            path: path.into(),
            cause: source,
        },
        other => Error::Write {
            path: path.into(),
            cause: std::io::Error::other(other.to_string()),
        },
    }
}
