//! Link lists as words, to send a group's links to the rank that holds it: per part, its job,
//! its group, its leaf and cluster links' counts, then three words a link (receiver, shooter,
//! factor's bits). Read back exactly as written.

use super::links::{ClusterLink, LeafLink, Links};
use super::tree::Ref;
use crate::error::{Error, Result};

/// Appends one part (`job`'s links into `group`) to `out`.
pub(super) fn put(out: &mut Vec<u32>, job: u32, group: usize, links: &Links) {
    out.reserve(4 + 3 * (links.leaf.len() + links.cluster.len()));
    out.extend([
        job,
        group as u32,
        links.leaf.len() as u32,
        links.cluster.len() as u32,
    ]);
    for l in &links.leaf {
        out.extend([l.r, l.s, l.f.to_bits()]);
    }
    for l in &links.cluster {
        out.extend([l.r.raw(), l.s.raw(), l.factor.to_bits()]);
    }
}

/// Reads every part in `words` into `parts` (by group, with its job).
pub(super) fn take(words: &[u32], parts: &mut [Vec<(u32, Links)>]) -> Result<()> {
    let broken = || Error::Worker {
        problem: "a rank sent links that do not read back (a transport error)".into(),
    };
    let mut at = 0;
    while at < words.len() {
        let head = words.get(at..at + 4).ok_or_else(broken)?;
        let (job, group) = (head[0], head[1] as usize);
        let (leaves, clusters) = (head[2] as usize, head[3] as usize);
        at += 4;
        let body = words
            .get(at..at + 3 * (leaves + clusters))
            .ok_or_else(broken)?;
        at += body.len();
        let (leaf, cluster) = body.split_at(3 * leaves);
        let links = Links {
            leaf: leaf
                .chunks_exact(3)
                .map(|w| LeafLink {
                    r: w[0],
                    s: w[1],
                    f: f32::from_bits(w[2]),
                })
                .collect(),
            cluster: cluster
                .chunks_exact(3)
                .map(|w| ClusterLink {
                    r: Ref::from_raw(w[0]),
                    s: Ref::from_raw(w[1]),
                    factor: f32::from_bits(w[2]),
                })
                .collect(),
            queries: 0,
        };
        parts.get_mut(group).ok_or_else(broken)?.push((job, links));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_read_back_as_written() {
        let a = Links {
            leaf: vec![
                LeafLink {
                    r: 1,
                    s: 2,
                    f: 0.25,
                },
                LeafLink {
                    r: 7,
                    s: 3,
                    f: -1e-30,
                },
            ],
            cluster: vec![ClusterLink {
                r: Ref::sample(5),
                s: Ref::node(9),
                factor: 0.75,
            }],
            queries: 12,
        };
        let b = Links::default();
        let mut words = Vec::new();
        put(&mut words, 4, 1, &a);
        put(&mut words, 8, 0, &b);
        // 4 words of head per part, 3 per link.
        assert_eq!(words.len(), 4 + 9 + 4);
        let mut parts = vec![Vec::new(); 2];
        take(&words, &mut parts).unwrap();
        assert_eq!(parts[1].len(), 1);
        assert_eq!(parts[1][0].0, 4);
        assert_eq!(parts[1][0].1.leaf, a.leaf);
        assert_eq!(parts[1][0].1.cluster, a.cluster);
        assert_eq!(parts[0][0].0, 8);
        // A cut message, or a group that does not exist, is an error.
        assert!(take(&words[..10], &mut vec![Vec::new(); 2]).is_err());
        assert!(take(&words, &mut vec![Vec::new(); 1]).is_err());
    }
}
