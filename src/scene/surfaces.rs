//! Grouping triangles into planar surfaces: connected through shared edges, coplanar with the
//! surface's first triangle within a tolerance, one material, one facing. Later stages rely on
//! "same surface, same side" to share areas and interpolate without light leaking across
//! corners or through thin walls.

use std::collections::HashMap;

use glam::{DVec3, Vec2, Vec3};

use super::{Material, Mesh, Surface, Triangle};

/// Normals within this angle (radians) of the surface's seed triangle count as coplanar.
const ANGLE_TOLERANCE: f64 = 1e-3;
/// Vertices within this fraction of the scene diagonal of the seed plane count as on it.
const DISTANCE_TOLERANCE: f64 = 1e-5;
/// A triangle whose |cross product| is below this fraction of its longest edge squared has no
/// usable area or normal in f32 arithmetic: it is dropped.
const DEGENERATE: f64 = 1e-7;

/// A triangle that survived the degeneracy check, before grouping.
#[derive(Clone, Copy, Debug)]
pub(super) struct Face {
    pub vertices: [Vec3; 3],
    pub material: u32,
    /// Texture coordinates, when its material has a texture and the mesh gives them.
    pub texcoords: Option<[Vec2; 3]>,
    normal: DVec3,
    area: f64,
}

/// The mesh's triangles with a usable area, and how many were dropped.
pub(super) fn drop_degenerate(mesh: &Mesh) -> (Vec<Face>, usize) {
    let mut kept = Vec::with_capacity(mesh.triangles.len());
    for (i, (t, &material)) in mesh
        .triangles
        .iter()
        .zip(&mesh.triangle_materials)
        .enumerate()
    {
        let vertices = t.map(|i| mesh.positions[i as usize]);
        let [a, b, c] = vertices.map(|v| v.as_dvec3());
        let cross = (b - a).cross(c - a);
        let longest = (b - a)
            .length_squared()
            .max((c - b).length_squared())
            .max((a - c).length_squared());
        let length = cross.length();
        if length > DEGENERATE * longest && length.is_finite() {
            let textured = mesh
                .materials
                .get(material as usize)
                .is_some_and(|m| m.texture.is_some());
            kept.push(Face {
                vertices,
                material,
                texcoords: mesh
                    .texcoords
                    .get(i)
                    .copied()
                    .flatten()
                    .filter(|_| textured),
                normal: cross / length,
                area: 0.5 * length,
            });
        }
    }
    let dropped = mesh.triangles.len() - kept.len();
    (kept, dropped)
}

/// Triangles ordered by surface, the surfaces, and the triangles' texture coordinates (empty
/// when no triangle has any).
pub(super) type Grouped = (Vec<Triangle>, Vec<Surface>, Vec<Option<[Vec2; 3]>>);

/// Groups faces into surfaces.
pub(super) fn group(
    faces: &[Face],
    materials: &[Material],
    two_sided: bool,
    diagonal: f32,
) -> Grouped {
    let neighbours = Adjacency::new(faces);
    let cos_tolerance = ANGLE_TOLERANCE.cos();
    let distance_tolerance = DISTANCE_TOLERANCE * f64::from(diagonal);

    // Region growing from each unassigned triangle, in file order: deterministic.
    const NONE: u32 = u32::MAX;
    let mut surface_of = vec![NONE; faces.len()];
    let mut members: Vec<Vec<u32>> = Vec::new();
    let mut stack = Vec::new();
    for seed in 0..faces.len() {
        if surface_of[seed] != NONE {
            continue;
        }
        let s = members.len() as u32;
        let seed_face = &faces[seed];
        let n0 = seed_face.normal;
        let d0 = n0.dot(seed_face.vertices[0].as_dvec3());
        let mut group = Vec::new();
        surface_of[seed] = s;
        stack.push(seed as u32);
        while let Some(t) = stack.pop() {
            group.push(t);
            for &u in neighbours.of(t) {
                let f = &faces[u as usize];
                let fits = surface_of[u as usize] == NONE
                    && f.material == seed_face.material
                    && f.normal.dot(n0) >= cos_tolerance
                    && f.vertices
                        .iter()
                        .all(|v| (n0.dot(v.as_dvec3()) - d0).abs() <= distance_tolerance);
                if fits {
                    surface_of[u as usize] = s;
                    stack.push(u);
                }
            }
        }
        group.sort_unstable();
        members.push(group);
    }

    let mut triangles = Vec::with_capacity(faces.len());
    let mut texcoords = Vec::new();
    let textured = faces.iter().any(|f| f.texcoords.is_some());
    let mut surfaces = Vec::with_capacity(members.len());
    for (s, group) in members.iter().enumerate() {
        let start = triangles.len() as u32;
        let mut weighted_normal = DVec3::ZERO;
        let mut weighted_offset = 0.0;
        let mut area = 0.0;
        for &t in group {
            let f = &faces[t as usize];
            let centroid = (f.vertices[0] + f.vertices[1] + f.vertices[2]).as_dvec3() / 3.0;
            weighted_normal += f.area * f.normal;
            weighted_offset += f.area * f.normal.dot(centroid);
            area += f.area;
            triangles.push(Triangle {
                vertices: f.vertices,
                normal: f.normal.as_vec3(),
                area: f.area as f32,
                surface: s as u32,
            });
            if textured {
                texcoords.push(f.texcoords);
            }
        }
        let first = &faces[group[0] as usize];
        surfaces.push(Surface {
            material: first.material,
            normal: weighted_normal.normalize_or(first.normal).as_vec3(),
            offset: (weighted_offset / area) as f32,
            triangles: start..triangles.len() as u32,
            area,
            two_sided: {
                let m = &materials[first.material as usize];
                (two_sided || m.two_sided) && !m.is_emitter()
            },
        });
    }
    (triangles, surfaces, texcoords)
}

/// Which triangles share an edge with which, after welding vertices at equal positions
/// (exporters often repeat a vertex per face or per object).
///
/// Decision: on an edge of k > 2 triangles (duplicated faces, fans, non-manifold CAD edges)
/// each triangle is linked to its neighbours in the order of its normal's angle about the
/// edge (within one material), not to all k − 1 others: the memory and time stay linear in
/// the triangles whatever the mesh. Region growing loses nothing by it: the triangles that fit
/// a surface (normals within a small cap of its seed's) lie in one run of that order, the
/// run wrapping round at ±π, so it reaches all of them through their neighbours.
struct Adjacency {
    offsets: Vec<u32>,
    neighbours: Vec<u32>,
}

impl Adjacency {
    fn new(faces: &[Face]) -> Self {
        let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
        let mut welded: Vec<Vec3> = Vec::new();
        let mut weld = |v: Vec3| {
            // `+ 0.0` turns -0.0 into 0.0 so both weld together.
            let key = [
                (v.x + 0.0).to_bits(),
                (v.y + 0.0).to_bits(),
                (v.z + 0.0).to_bits(),
            ];
            let next = ids.len() as u32;
            *ids.entry(key).or_insert_with(|| {
                welded.push(v);
                next
            })
        };
        let mut edges: Vec<(u64, u32)> = Vec::with_capacity(3 * faces.len());
        for (t, f) in faces.iter().enumerate() {
            let v = f.vertices.map(&mut weld);
            for k in 0..3 {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                if a != b {
                    edges.push(((u64::from(a.min(b)) << 32) | u64::from(a.max(b)), t as u32));
                }
            }
        }
        edges.sort_unstable();
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(2 * edges.len());
        let mut link = |a: u32, b: u32| {
            if a != b {
                pairs.push((a, b));
                pairs.push((b, a));
            }
        };
        let mut around: Vec<(u32, f64, u32)> = Vec::new();
        for run in edges.chunk_by(|x, y| x.0 == y.0) {
            if run.len() == 2 {
                link(run[0].1, run[1].1);
                continue;
            }
            if run.len() < 2 {
                continue;
            }
            let key = run[0].0;
            let (a, b) = (welded[(key >> 32) as usize], welded[key as u32 as usize]);
            let axis = (b - a).as_dvec3().normalize_or(DVec3::X);
            let (u, v) = axis.any_orthonormal_pair();
            around.clear();
            around.extend(run.iter().map(|&(_, t)| {
                let f = &faces[t as usize];
                (f.material, f.normal.dot(v).atan2(f.normal.dot(u)), t)
            }));
            around.sort_unstable_by(|x, y| {
                (x.0.cmp(&y.0))
                    .then(x.1.total_cmp(&y.1))
                    .then(x.2.cmp(&y.2))
            });
            for group in around.chunk_by(|x, y| x.0 == y.0) {
                for w in group.windows(2) {
                    link(w[0].2, w[1].2);
                }
                if group.len() > 2 {
                    link(group[group.len() - 1].2, group[0].2);
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut offsets = vec![0u32; faces.len() + 1];
        for &(a, _) in &pairs {
            offsets[a as usize + 1] += 1;
        }
        for i in 0..faces.len() {
            offsets[i + 1] += offsets[i];
        }
        Adjacency {
            offsets,
            neighbours: pairs.into_iter().map(|(_, b)| b).collect(),
        }
    }

    fn of(&self, t: u32) -> &[u32] {
        &self.neighbours[self.offsets[t as usize] as usize..self.offsets[t as usize + 1] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey() -> Vec<Material> {
        vec![Material::diffuse("grey", Vec3::splat(0.5), Vec3::ZERO)]
    }

    fn mesh(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Mesh {
        Mesh {
            positions: positions.iter().map(|&p| Vec3::from(p)).collect(),
            triangles: triangles.to_vec(),
            triangle_materials: vec![0; triangles.len()],
            materials: grey(),
            texcoords: Vec::new(),
        }
    }

    #[test]
    fn a_quad_is_one_surface_and_a_folded_quad_is_two() {
        let flat = mesh(
            &[[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
            &[[0, 1, 2], [0, 2, 3]],
        );
        let (faces, dropped) = drop_degenerate(&flat);
        assert_eq!(dropped, 0);
        let (tris, surfaces, _) = group(&faces, &grey(), false, 1.5);
        assert_eq!((tris.len(), surfaces.len()), (2, 1));
        assert!((surfaces[0].area - 1.0).abs() < 1e-12);
        assert!((surfaces[0].normal - Vec3::Z).length() < 1e-6);

        let folded = mesh(
            &[[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.1]],
            &[[0, 1, 2], [0, 2, 3]],
        );
        let (faces, _) = drop_degenerate(&folded);
        assert_eq!(group(&faces, &grey(), false, 1.5).1.len(), 2);
    }

    #[test]
    fn opposite_facings_and_separate_pieces_stay_apart() {
        // Same plane, second triangle wound the other way.
        let flipped = mesh(
            &[[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
            &[[0, 1, 2], [0, 3, 2]],
        );
        let (faces, _) = drop_degenerate(&flipped);
        assert_eq!(group(&faces, &grey(), false, 1.5).1.len(), 2);
        // Coplanar but not touching.
        let apart = mesh(
            &[
                [0., 0., 0.],
                [1., 0., 0.],
                [0., 1., 0.],
                [5., 0., 0.],
                [6., 0., 0.],
                [5., 1., 0.],
            ],
            &[[0, 1, 2], [3, 4, 5]],
        );
        let (faces, _) = drop_degenerate(&apart);
        assert_eq!(group(&faces, &grey(), false, 8.0).1.len(), 2);
    }

    #[test]
    fn a_floor_under_a_wall_on_its_edge_stays_one_surface() {
        // The floor's two halves meet at the edge x = 0 (both facing +z); a wall (twice, as CAD
        // exports repeat faces) stands on the same edge, and a slanted fin too: four
        // triangles and a duplicate on one edge. Floor: one surface; wall: one; fin: one.
        let m = mesh(
            &[
                [0., 0., 0.],
                [0., 1., 0.],
                [1., 0.5, 0.],
                [-1., 0.5, 0.],
                [0., 0.5, 1.],
                [0.5, 0.5, 0.5],
            ],
            &[[0, 2, 1], [0, 1, 3], [0, 1, 4], [0, 1, 4], [0, 1, 5]],
        );
        let (faces, _) = drop_degenerate(&m);
        let (tris, surfaces, _) = group(&faces, &grey(), false, 3.0);
        assert_eq!(surfaces.len(), 3, "{surfaces:?}");
        let floor = surfaces.iter().find(|s| s.normal.z > 0.99).unwrap();
        assert!((floor.area - 1.0).abs() < 1e-9, "{}", floor.area);
        assert_eq!(tris.len(), 5);
    }

    #[test]
    fn zero_area_triangles_are_dropped() {
        let m = mesh(
            &[[0., 0., 0.], [1., 0., 0.], [2., 0., 0.], [0., 1., 0.]],
            &[[0, 1, 2], [0, 1, 3], [3, 3, 3]],
        );
        let (faces, dropped) = drop_degenerate(&m);
        assert_eq!((faces.len(), dropped), (1, 2));
    }
}
