//! Which planar surfaces meet along an edge, and the pieces they join into: a tessellated
//! sphere is thousands of planar surfaces, one per facet, and the lights and reflectors made of
//! them are handled as the one object they are (`light`, `specular`).

use std::collections::HashMap;

use glam::Vec3;

use super::Scene;

/// A corner's position, bit for bit (−0 and +0 alike): triangles that share a vertex of the
/// mesh share these bits exactly.
fn key(v: Vec3) -> [u32; 3] {
    (v + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// Every pair of surfaces (a < b) that share an edge of their triangles, each pair once, in
/// ascending order.
pub(crate) fn shared_edges(scene: &Scene) -> Vec<(u32, u32)> {
    let mut first: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
    let mut pairs = Vec::new();
    for t in &scene.triangles {
        let k = t.vertices.map(key);
        for (a, b) in [(k[0], k[1]), (k[1], k[2]), (k[2], k[0])] {
            let edge = if a < b { (a, b) } else { (b, a) };
            match first.get(&edge) {
                Some(&s) if s != t.surface => pairs.push((s.min(t.surface), s.max(t.surface))),
                Some(_) => {}
                None => {
                    first.insert(edge, t.surface);
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// The pieces `n` items join into through `links`: per item, the smallest item of its piece
/// (so the labels do not depend on the order of the links).
pub(crate) fn pieces(n: usize, links: impl IntoIterator<Item = (u32, u32)>) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn root(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            let up = parent[parent[i as usize] as usize];
            parent[i as usize] = up;
            i = up;
        }
        i
    }
    for (a, b) in links {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        // The smaller index becomes the root: each piece is labelled by its first item.
        if ra < rb {
            parent[rb as usize] = ra;
        } else if rb < ra {
            parent[ra as usize] = rb;
        }
    }
    (0..n as u32).map(|i| root(&mut parent, i)).collect()
}

/// Emitting surfaces joined along edges, of one material, in pieces of at least this many make
/// one light (a tessellated sphere or tube): their light is integrated and sampled over the
/// whole piece, not surface by surface. Fewer (a panel, a box of six faces) stay lights of
/// their own.
pub(crate) const LIGHT_FROM_SURFACES: usize = 8;

/// The scene's area lights: lists of emitting surfaces, each list one light, in the order of
/// their first surface (each surface alone, but for pieces of [`LIGHT_FROM_SURFACES`] or more).
pub(crate) fn emitter_groups(scene: &Scene) -> Vec<Vec<u32>> {
    let emits: Vec<bool> = (0..scene.surfaces.len() as u32)
        .map(|s| scene.material_of(s).is_emitter())
        .collect();
    let same = |a: u32, b: u32| {
        emits[a as usize]
            && emits[b as usize]
            && scene.surfaces[a as usize].material == scene.surfaces[b as usize].material
    };
    let links: Vec<(u32, u32)> = shared_edges(scene)
        .into_iter()
        .filter(|&(a, b)| same(a, b))
        .collect();
    let label = pieces(scene.surfaces.len(), links);
    let mut members: HashMap<u32, Vec<u32>> = HashMap::new();
    for (s, _) in scene.emitters() {
        members.entry(label[s as usize]).or_default().push(s);
    }
    let mut groups = Vec::new();
    for (s, _) in scene.emitters() {
        let piece = &members[&label[s as usize]];
        if piece.len() < LIGHT_FROM_SURFACES {
            groups.push(vec![s]);
        } else if piece[0] == s {
            groups.push(piece.clone());
        }
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_are_labelled_by_their_first_item_whatever_the_order_of_links() {
        let a = pieces(6, [(4, 5), (1, 3), (3, 4)]);
        let b = pieces(6, [(3, 4), (4, 5), (1, 3)]);
        assert_eq!(a, vec![0, 1, 2, 1, 1, 1]);
        assert_eq!(a, b);
    }
}
