//! Two-sided emitters (`two_sided` on an emitting material, glTF's `doubleSided`, Blender's
//! mesh lights): each triangle becomes two one-sided sheets back to back, a hair apart, each
//! emitting (and reflecting) towards its own side.
//!
//! Decision: split the geometry rather than teach every consumer of light a second emitting
//! side. Direct light, the solver, the path tracer, mirror images of lights, the patch
//! baseline and the scene's power all handle one-sided emitters already, and a sheet facing
//! each way is exactly what a two-sided emitter is. The sheets are moved apart along the normal
//! by [`SEPARATION`] so that a ray from either side meets the sheet facing it first; coincident
//! sheets would leave the ray caster to pick one at random, and the back of the other is black.

use super::Mesh;

/// How far apart the two sheets are, as a fraction of the scene's diagonal: a tenth of the
/// lift of visibility queries (`visibility::LIFT`), so a query ending on one sheet never
/// reaches the other, and still hundreds of f32 steps at the scene's scale.
pub(crate) const SEPARATION: f32 = 1e-5;

/// Splits every triangle of a two-sided emitting material into two sheets; returns how many
/// triangles were split. Other triangles, and the order of all, are left as they were (the
/// second sheets come after).
pub(super) fn split(mesh: &mut Mesh, diagonal: f32) -> usize {
    let two_sided: Vec<bool> = mesh
        .materials
        .iter()
        .map(|m| m.two_sided && m.is_emitter())
        .collect();
    let half = 0.5 * SEPARATION * diagonal;
    let textured = !mesh.texcoords.is_empty();
    let mut split = 0;
    for t in 0..mesh.triangles.len() {
        let material = mesh.triangle_materials[t] as usize;
        if !two_sided.get(material).copied().unwrap_or(false) {
            continue;
        }
        let corners = mesh.triangles[t].map(|i| mesh.positions[i as usize]);
        let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        let Some(n) = normal.try_normalize() else {
            continue; // degenerate: dropped later anyway
        };
        let first = mesh.positions.len() as u32;
        mesh.positions.extend(corners.map(|p| p + half * n));
        mesh.positions.extend(corners.map(|p| p - half * n));
        mesh.triangles[t] = [first, first + 1, first + 2];
        // The back sheet, wound the other way: it faces −n.
        mesh.triangles.push([first + 3, first + 5, first + 4]);
        mesh.triangle_materials.push(material as u32);
        if textured {
            let uv = mesh.texcoords[t].map(|[a, b, c]| [a, c, b]);
            mesh.texcoords.push(uv);
        }
        split += 1;
    }
    split
}

/// Whether any material is a two-sided emitter.
pub(super) fn any(mesh: &Mesh) -> bool {
    mesh.materials.iter().any(|m| m.two_sided && m.is_emitter())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Material;
    use glam::Vec3;

    #[test]
    fn a_two_sided_emitter_becomes_two_sheets_facing_away_from_each_other() {
        let mut lamp = Material::diffuse("lamp", Vec3::ZERO, Vec3::ONE);
        lamp.two_sided = true;
        let wall = Material::diffuse("wall", Vec3::splat(0.5), Vec3::ZERO);
        let mut mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            triangles: vec![[0, 1, 2], [0, 1, 3]],
            triangle_materials: vec![0, 1],
            materials: vec![lamp, wall],
            texcoords: Vec::new(),
        };
        assert_eq!(split(&mut mesh, 10.0), 1);
        assert_eq!(mesh.triangles.len(), 3);
        assert_eq!(mesh.triangles[1], [0, 1, 3], "the wall is untouched");
        let normal = |t: [u32; 3]| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            ((b - a).cross(c - a).normalize(), a.z)
        };
        // The front sheet faces +z, 5e-5 above z = 0; the back one faces −z, 5e-5 below.
        let (n0, z0) = normal(mesh.triangles[0]);
        let (n1, z1) = normal(mesh.triangles[2]);
        assert!((n0 - Vec3::Z).length() < 1e-6 && (n1 + Vec3::Z).length() < 1e-6);
        assert!(
            (z0 - 5e-5).abs() < 1e-9 && (z1 + 5e-5).abs() < 1e-9,
            "{z0} {z1}"
        );
        assert_eq!(mesh.triangle_materials, vec![0, 1, 0]);
    }
}
