//! Diffuse-reflectance textures (`docs/scene-format.md`, "Textured diffuse reflectance"):
//! decoded from sRGB once into linear reflectance, clamped to the reflectance bound per texel,
//! and kept as a mip pyramid so that a mean over a large area is a few lookups, not thousands.
//!
//! Coordinates are image coordinates: (0, 0) the top-left corner of the image, (1, 1) the
//! bottom-right, wrapped (repeat) outside. glTF's texture coordinates are these already; OBJ's
//! `vt` has v upwards and the OBJ reader flips it.

use std::io::Cursor;

use glam::{Vec2, Vec3};

/// The largest texture read, in texels per side: bigger ones are refused with a warning rather
/// than allocated (a 16384² texture and its mips take 4.3 GB as linear floats).
pub const MAX_TEXTURE_SIDE: u32 = 8192;

/// Points per axis over which [`Texture::mean_over`] averages, each at a mip level whose texels
/// are about as far apart as the points.
const MEAN_POINTS: usize = 4;

/// A texture of linear diffuse reflectance.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// What it is called in messages: its file, or the glTF image's name.
    name: String,
    /// Level 0 is the image; each next one halves both sides (rounding up) by averaging.
    levels: Vec<Level>,
    /// The reflectance bound its texels were clamped to.
    bound: f32,
}

#[derive(Clone, Debug, PartialEq)]
struct Level {
    width: usize,
    height: usize,
    texels: Vec<Vec3>,
}

impl Texture {
    /// A texture from 8-bit sRGB texels, `channels` (3 or 4; alpha is ignored) bytes each, row
    /// by row from the top. Each channel is decoded to linear and clamped to
    /// `max_reflectance`.
    pub fn from_srgb8(
        name: impl Into<String>,
        width: u32,
        height: u32,
        channels: usize,
        data: &[u8],
        max_reflectance: f32,
    ) -> Result<Texture, String> {
        let name = name.into();
        if let Some(problem) = super::validate::max_reflectance(max_reflectance) {
            return Err(problem);
        }
        check_size(width, height)?;
        if !(3..=4).contains(&channels) {
            return Err(format!(
                "{channels} channels per texel: 3 (RGB) or 4 (RGBA) are read"
            ));
        }
        let count = width as usize * height as usize;
        if data.len() != count * channels {
            return Err(format!(
                "{} bytes for {width} × {height} texels of {channels} channels: {} expected",
                data.len(),
                count * channels
            ));
        }
        let table: Vec<f32> = (0..=255u8)
            .map(|c| srgb_to_linear(f32::from(c) / 255.0).min(max_reflectance))
            .collect();
        let texels = data
            .chunks_exact(channels)
            .map(|t| {
                Vec3::new(
                    table[t[0] as usize],
                    table[t[1] as usize],
                    table[t[2] as usize],
                )
            })
            .collect();
        Ok(Texture::from_level(
            name,
            width as usize,
            height as usize,
            texels,
            max_reflectance,
        ))
    }

    /// A texture from an image file's bytes (PNG, JPEG, TGA, or an OpenEXR image, whose values
    /// are linear already), clamped to `max_reflectance`. The error says what is wrong.
    pub fn decode(
        name: impl Into<String>,
        bytes: &[u8],
        max_reflectance: f32,
    ) -> Result<Texture, String> {
        let name = name.into();
        if let Some(problem) = super::validate::max_reflectance(max_reflectance) {
            return Err(problem);
        }
        let mut reader = image::ImageReader::new(Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())?;
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(MAX_TEXTURE_SIDE);
        limits.max_image_height = Some(MAX_TEXTURE_SIDE);
        reader.limits(limits);
        let image = reader.decode().map_err(|e| e.to_string())?;
        let (width, height) = (image.width(), image.height());
        check_size(width, height)?;
        let linear = matches!(
            image,
            image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
        );
        if linear {
            let rgb = image.to_rgb32f();
            let texels = rgb
                .pixels()
                .map(|p| {
                    Vec3::from(p.0)
                        .max(Vec3::ZERO)
                        .min(Vec3::splat(max_reflectance))
                })
                .map(|t| if t.is_finite() { t } else { Vec3::ZERO })
                .collect();
            return Ok(Texture::from_level(
                name,
                width as usize,
                height as usize,
                texels,
                max_reflectance,
            ));
        }
        let rgb = image.to_rgb8();
        Texture::from_srgb8(name, width, height, 3, rgb.as_raw(), max_reflectance)
    }

    fn from_level(
        name: String,
        width: usize,
        height: usize,
        texels: Vec<Vec3>,
        bound: f32,
    ) -> Texture {
        let mut levels = vec![Level {
            width,
            height,
            texels,
        }];
        while let Some(last) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            levels.push(last.halved());
        }
        Texture {
            name,
            levels,
            bound,
        }
    }

    /// The reflectance bound its texels were clamped to (what Kd is lowered to where a face of
    /// its material has no texture coordinates).
    pub fn bound(&self) -> f32 {
        self.bound
    }

    /// What it is called in messages.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Width and height in texels.
    pub fn size(&self) -> (usize, usize) {
        (self.levels[0].width, self.levels[0].height)
    }

    /// The mean reflectance of the whole texture.
    pub fn mean(&self) -> Vec3 {
        self.levels.last().map_or(Vec3::ZERO, |l| l.texels[0])
    }

    /// The reflectance at `uv`, bilinearly filtered at full resolution.
    pub fn at(&self, uv: Vec2) -> Vec3 {
        self.levels[0].bilinear(uv)
    }

    /// The mean reflectance over the parallelogram `centre ± e1/2 ± e2/2` (texture
    /// coordinates): a grid of points over it, each looked up at the mip level whose texels
    /// are as far apart as the points, so that every texel under it counts.
    pub fn mean_over(&self, centre: Vec2, e1: Vec2, e2: Vec2) -> Vec3 {
        let (w, h) = self.size();
        let texels = Vec2::new(w as f32, h as f32);
        let spacing = (e1 * texels).length().max((e2 * texels).length()) / MEAN_POINTS as f32;
        let level = if spacing > 1.0 && spacing.is_finite() {
            (spacing.log2().ceil() as usize).min(self.levels.len() - 1)
        } else if spacing.is_finite() {
            0
        } else {
            self.levels.len() - 1
        };
        let level = &self.levels[level];
        let mut sum = Vec3::ZERO;
        for i in 0..MEAN_POINTS {
            for j in 0..MEAN_POINTS {
                let a = (i as f32 + 0.5) / MEAN_POINTS as f32 - 0.5;
                let b = (j as f32 + 0.5) / MEAN_POINTS as f32 - 0.5;
                sum += level.bilinear(centre + a * e1 + b * e2);
            }
        }
        sum / (MEAN_POINTS * MEAN_POINTS) as f32
    }
}

fn check_size(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("the image is {width} × {height}: it has no texels"));
    }
    if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
        return Err(format!(
            "the image is {width} × {height}: textures up to {MAX_TEXTURE_SIDE} texels a side \
             are read"
        ));
    }
    Ok(())
}

impl Level {
    /// Texel (x, y), wrapped.
    fn texel(&self, x: i64, y: i64) -> Vec3 {
        let x = x.rem_euclid(self.width as i64) as usize;
        let y = y.rem_euclid(self.height as i64) as usize;
        self.texels[y * self.width + x]
    }

    fn bilinear(&self, uv: Vec2) -> Vec3 {
        // Texel centres at half-integers; wrapping keeps far-away coordinates exact enough.
        let x = (uv.x - uv.x.floor()) * self.width as f32 - 0.5;
        let y = (uv.y - uv.y.floor()) * self.height as f32 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return self.texel(0, 0);
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0) * (1.0 - fx) + self.texel(x0 + 1, y0) * fx;
        let bottom = self.texel(x0, y0 + 1) * (1.0 - fx) + self.texel(x0 + 1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The next mip level: 2 × 2 texels averaged (1 × 2 or 2 × 1 at an odd edge).
    fn halved(&self) -> Level {
        let width = self.width.div_ceil(2);
        let height = self.height.div_ceil(2);
        let mut texels = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                let (mut sum, mut n) = (Vec3::ZERO, 0.0);
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (sx, sy) = (2 * x + dx, 2 * y + dy);
                    if sx < self.width && sy < self.height {
                        sum += self.texels[sy * self.width + sx];
                        n += 1.0;
                    }
                }
                texels.push(sum / n);
            }
        }
        Level {
            width,
            height,
            texels,
        }
    }
}

/// The sRGB transfer function undone (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker(n: u32, a: u8, b: u8) -> Texture {
        let data: Vec<u8> = (0..n * n)
            .flat_map(|i| {
                let v = if (i % n + i / n) % 2 == 0 { a } else { b };
                [v, v, v]
            })
            .collect();
        Texture::from_srgb8("checker", n, n, 3, &data, WHITE).unwrap()
    }

    /// What white (255) reads as in `checker`'s textures.
    const WHITE: f32 = 0.99;

    #[test]
    fn srgb_decodes_to_the_standard_values() {
        // 0.5 in sRGB is 0.21404 linear; 1 is 1; the linear segment below 0.04045.
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.04) - 0.04 / 12.92).abs() < 1e-7);
    }

    #[test]
    fn lookups_wrap_and_interpolate_between_texel_centres() {
        let t = checker(2, 255, 0);
        // Texel (0, 0) is white, (1, 0) black: its centre (0.25, 0.25) is white, and halfway
        // between the two centres (0.5, 0.25) is half.
        assert!((t.at(Vec2::new(0.25, 0.25)).x - WHITE).abs() < 1e-6);
        assert!((t.at(Vec2::new(0.5, 0.25)).x - WHITE / 2.0).abs() < 1e-6);
        // Repeat: 3.25 is 0.25, -0.75 too.
        assert_eq!(t.at(Vec2::new(3.25, -0.75)), t.at(Vec2::new(0.25, 0.25)));
        // Bound per texel.
        let dim = Texture::from_srgb8("w", 1, 1, 4, &[255, 255, 255, 0], 0.9).unwrap();
        assert_eq!(dim.at(Vec2::ZERO), Vec3::splat(0.9));
    }

    #[test]
    fn a_mean_over_many_checks_is_the_average_of_the_two_colours() {
        // 64 × 64 checks of white (0.99: `checker`'s bound) and sRGB 128 (0.21586 linear): any
        // area covering many of them averages (0.99 + 0.21586) / 2 = 0.60293, by hand.
        let t = checker(64, 255, 128);
        let expected = (WHITE + srgb_to_linear(128.0 / 255.0)) / 2.0;
        assert!((t.mean().x - expected).abs() < 1e-5);
        for (centre, size) in [(Vec2::new(0.5, 0.5), 0.5), (Vec2::new(0.13, 0.71), 0.3)] {
            let m = t.mean_over(centre, Vec2::new(size, 0.0), Vec2::new(0.0, size));
            assert!((m.x - expected).abs() < 0.01 * expected, "{m} at {centre}");
        }
        // A small area sees its own texel.
        let one = t.mean_over(Vec2::new(0.5 / 64.0, 0.5 / 64.0), Vec2::ZERO, Vec2::ZERO);
        assert!((one.x - WHITE).abs() < 1e-6);
    }

    #[test]
    fn bad_images_are_errors_not_panics() {
        assert!(Texture::decode("x.png", b"not an image", 0.9).is_err());
        // A bound outside (0, 1) would give negative reflectances, or ones above 1.
        for bound in [-1.0, 0.0, 1.0, 2.0, f32::NAN] {
            let made = Texture::from_srgb8("x", 1, 1, 3, &[255, 128, 0], bound);
            assert!(
                made.is_err_and(|e| e.contains("max_reflectance")),
                "{bound}"
            );
            let decoded = Texture::decode("x.png", b"not even an image", bound);
            assert!(
                decoded.is_err_and(|e| e.contains("max_reflectance")),
                "{bound}"
            );
        }
        assert!(Texture::from_srgb8("x", 0, 4, 3, &[], 0.9).is_err());
        assert!(Texture::from_srgb8("x", 2, 2, 3, &[0; 11], 0.9).is_err());
        assert!(Texture::from_srgb8("x", 99_999, 1, 3, &[0; 3], 0.9)
            .unwrap_err()
            .contains("8192"));
    }
}
