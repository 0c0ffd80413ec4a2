//! Each sample's diffuse reflectance on textured surfaces: the texture's mean over the area
//! the sample represents (its shares of area cells, eq. 5), so that light inter-reflects with
//! what that area reflects on average however fine the texture; the image shows the texture
//! itself at each hit.

use glam::{Mat2, Vec2, Vec3};

use super::surface_map::SurfaceMap;
use super::{surface_of, AreaCell, Samples};
use crate::error::Result;
use crate::parallel::for_chunks;
use crate::scene::Scene;

/// Every sample's reflectance when some surface of the scene is textured (Kd on the others);
/// empty when none is. On up to `threads` threads; the result does not depend on their number.
pub(crate) fn means(
    scene: &Scene,
    samples: &Samples,
    maps: &[SurfaceMap],
    threads: usize,
) -> Result<Vec<Vec3>> {
    let textured = (0..scene.surfaces.len() as u32).any(|s| scene.is_textured(s));
    if !textured || scene.texcoords.is_empty() {
        return Ok(Vec::new());
    }
    let mut cells = vec![Vec3::ZERO; samples.cells.len()];
    for_chunks(&mut cells, 1024, threads, |first, chunk| {
        for ((out, cell), c) in chunk.iter_mut().zip(&samples.cells[first..]).zip(first..) {
            *out = cell_mean(scene, maps, cell, samples.side_of_cell(c));
        }
        Ok(())
    })?;
    let mut out = vec![Vec3::ZERO; samples.len()];
    for_chunks(&mut out, 4096, threads, |first, chunk| {
        for (out, k) in chunk.iter_mut().zip(first..) {
            let surface = surface_of(samples.side[k]);
            let (mut area, mut sum) = (0.0f32, Vec3::ZERO);
            if scene.is_textured(surface) {
                for (c, a) in samples.shares_of(k) {
                    area += a;
                    sum += a * cells[c as usize];
                }
            }
            *out = if area > 0.0 {
                sum / area
            } else if scene.is_textured(surface) {
                let map = &maps[surface as usize];
                mean_around(scene, map, surface, samples.uv[k], 0.0)
            } else {
                scene.material_of(surface).kd
            };
        }
        Ok(())
    })?;
    Ok(out)
}

/// A cell's mean reflectance (zero on untextured surfaces: nothing asks for it).
fn cell_mean(scene: &Scene, maps: &[SurfaceMap], cell: &AreaCell, side: u32) -> Vec3 {
    let surface = surface_of(side);
    if !scene.is_textured(surface) {
        return Vec3::ZERO;
    }
    let map = &maps[surface as usize];
    // The cell seen as the square of its area around its centroid, as the solver sees it.
    let side = cell.area.max(0.0).sqrt();
    mean_around(scene, map, surface, map.to_2d(cell.centroid), side)
}

/// The mean reflectance over the square of side `side` around 2D point `p` of a textured
/// surface, through the texture mapping of the triangle `p` lies in (extended affinely beyond
/// it); Kd where that triangle has no texture coordinates.
fn mean_around(scene: &Scene, map: &SurfaceMap, surface: u32, p: Vec2, side: f32) -> Vec3 {
    let material = scene.material_of(surface);
    let local = map
        .triangle_at(p)
        .unwrap_or_else(|| map.nearest_triangle(p));
    let triangle = scene.surfaces[surface as usize].triangles.start as usize + local;
    let Some(texture) = &material.texture else {
        return material.kd;
    };
    let Some(Some(uv)) = scene.texcoords.get(triangle) else {
        return material.kd.min(Vec3::splat(texture.bound()));
    };
    let [a, b, c] = map.triangles[local];
    let to_uv =
        Mat2::from_cols(uv[1] - uv[0], uv[2] - uv[0]) * Mat2::from_cols(b - a, c - a).inverse();
    let centre = uv[0] + to_uv * (p - a);
    let e1 = to_uv * Vec2::new(side, 0.0);
    let e2 = to_uv * Vec2::new(0.0, side);
    if !(centre.is_finite() && e1.is_finite() && e2.is_finite()) {
        return material.kd * texture.mean();
    }
    material.kd * texture.mean_over(centre, e1, e2)
}
