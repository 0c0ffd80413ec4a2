//! Solved samples as a PLY point cloud (position, normal, colour, radius) for MeshLab or
//! Blender.

use std::io::Write;
use std::path::Path;

use crate::error::{Error, Result};
use crate::solver::Solution;

/// Writes the samples as ASCII PLY; colours are B/π scaled by `exposure`, sRGB-encoded.
pub fn write_samples(solution: &Solution, path: &Path, exposure: f32) -> Result<()> {
    let fail = |source| Error::Write {
        path: path.into(),
        cause: source,
    };
    let file = std::fs::File::create(path).map_err(fail)?;
    let mut out = std::io::BufWriter::new(file);
    let field = solution.field();
    let s = &field.samples;
    write!(
        out,
        "ply\nformat ascii 1.0\ncomment meshlight samples: colour = radiance B/pi x {exposure}\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         property float radius\nproperty float area\nend_header\n",
        s.len()
    )
    .map_err(fail)?;
    for k in 0..s.len() {
        let (p, n) = (s.position[k], s.normal[k]);
        let radiance = (field.radiosity[k] / std::f64::consts::PI).as_vec3() * exposure;
        let c = radiance
            .to_array()
            .map(|v| (crate::render::image::srgb(v.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8);
        writeln!(
            out,
            "{} {} {} {} {} {} {} {} {} {} {}",
            p.x, p.y, p.z, n.x, n.y, n.z, c[0], c[1], c[2], s.radius[k], s.area[k]
        )
        .map_err(fail)?;
    }
    out.flush().map_err(fail)
}
