//! Rendering patches smoothly per surface side: at a camera-ray hit, radiosity is interpolated
//! bilinearly between the centres of the four nearest cells of the surface's grid, over those
//! cells that hold a patch on the side seen (the weights renormalised), as radiosity methods
//! have always shown their meshes (Gouraud shading of patch values).

use glam::{DVec3, Vec3};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::mesh::{lattice, Mesh, NONE};
use crate::error::Result;
use crate::parallel::for_chunks;
use crate::render::Image;
use crate::scene::Scene;
use crate::visibility::{Hit, Ray, Visibility};

/// The radiance (radiosity / π) a hit on `triangle` at `p` shows from direction `dir`.
fn shade(scene: &Scene, mesh: &Mesh, radiosity: &[DVec3], hit: Hit, p: Vec3, dir: Vec3) -> DVec3 {
    let triangle = &scene.triangles[hit.triangle as usize];
    let side = usize::from(dir.dot(triangle.normal) >= 0.0);
    let grid = &mesh.grids[triangle.surface as usize];
    if grid.patch.is_empty() {
        return DVec3::ZERO;
    }
    let g = lattice(grid, mesh.size, p);
    let (x0, y0) = (g.x.floor(), g.y.floor());
    let (fx, fy) = (f64::from(g.x - x0), f64::from(g.y - y0));
    let (mut sum, mut weight) = (DVec3::ZERO, 0.0);
    let mut nearest = (f64::MAX, NONE);
    for (dx, dy, w) in [
        (0, 0, (1.0 - fx) * (1.0 - fy)),
        (1, 0, fx * (1.0 - fy)),
        (0, 1, (1.0 - fx) * fy),
        (1, 1, fx * fy),
    ] {
        let (cx, cy) = (x0 as i64 + dx, y0 as i64 + dy);
        if cx < 0 || cy < 0 || cx >= grid.cells[0] as i64 || cy >= grid.cells[1] as i64 {
            continue;
        }
        let patch = grid.patch[cy as usize * grid.cells[0] + cx as usize][side];
        if patch == NONE {
            continue;
        }
        sum += radiosity[patch as usize] * w;
        weight += w;
        let d = (f64::from(g.x) - cx as f64).powi(2) + (f64::from(g.y) - cy as f64).powi(2);
        if d < nearest.0 {
            nearest = (d, patch);
        }
    }
    let b = if weight > 1e-9 {
        sum / weight
    } else if nearest.1 != NONE {
        radiosity[nearest.1 as usize]
    } else {
        DVec3::ZERO
    };
    b / std::f64::consts::PI
}

/// Renders the camera view with `supersample²` jittered rays per pixel (seeded per pixel).
pub(crate) fn render(
    scene: &Scene,
    mesh: &Mesh,
    radiosity: &[DVec3],
    vis: &dyn Visibility,
    supersample: u32,
    seed: u64,
    threads: usize,
) -> Result<Image> {
    let camera = &scene.camera;
    let (w, h) = (camera.width as usize, camera.height as usize);
    let n = supersample.max(1) as usize;
    let mut pixels = vec![Vec3::ZERO; w * h];
    // About 64k rays per chunk, whatever the supersampling.
    let chunk = (65_536 / (n * n)).max(1);
    for_chunks(&mut pixels, chunk, threads, |first, out| {
        let mut rays = Vec::with_capacity(out.len() * n * n);
        for p in first..first + out.len() {
            let mut rng =
                Pcg64Mcg::seed_from_u64(seed ^ (p as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
            for k in 0..n * n {
                let (jx, jy): (f32, f32) = (rng.random(), rng.random());
                let x = (p % w) as f32 + ((k % n) as f32 + jx) / n as f32;
                let y = (p / w) as f32 + ((k / n) as f32 + jy) / n as f32;
                rays.push(Ray {
                    origin: camera.position,
                    dir: camera.direction(x, y),
                    t_min: 0.0,
                    t_max: f32::INFINITY,
                });
            }
        }
        let mut hits = vec![None; rays.len()];
        vis.intersect(&rays, &mut hits)?;
        for (k, pixel) in out.iter_mut().enumerate() {
            let mut sum = DVec3::ZERO;
            for s in k * n * n..(k + 1) * n * n {
                if let Some(hit) = hits[s] {
                    let ray = rays[s];
                    let p = ray.origin + ray.dir * hit.t;
                    sum += shade(scene, mesh, radiosity, hit, p, ray.dir);
                }
            }
            *pixel = (sum / (n * n) as f64).as_vec3();
        }
        Ok(())
    })?;
    Ok(Image {
        width: camera.width,
        height: camera.height,
        pixels,
    })
}
