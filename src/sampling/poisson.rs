//! Initial samples (`docs/method.md` §3 and §9, eq. 3): random points on each reflecting surface side with a
//! minimum spacing ε, by dart throwing against a grid of cells ε/√2 wide (each holds at most
//! one sample), so a check costs a few cells, never O(n²).
//!
//! Every side gets at least one sample (the first dart always lands), so every side has a
//! sample to carry its area. Sides are sampled independently from a seed derived from
//! (seed, side): the result does not depend on thread count or on the order of sides.

use glam::Vec2;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::{Side, SurfaceMap};

/// Darts thrown per ε² of area: enough to come close to the jamming density (≈ 0.7 / ε²).
pub const DARTS_PER_EPSILON2: f64 = 30.0;

/// A deterministic, well-mixed seed for one side (splitmix64 of seed and side).
pub fn side_seed(seed: u64, side: Side, salt: u64) -> u64 {
    let mut z = seed ^ (u64::from(side) << 20) ^ salt.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Expected number of darts for a side (used to predict sample counts before allocating).
pub fn darts(area: f64, epsilon: f32) -> u64 {
    ((DARTS_PER_EPSILON2 * area / f64::from(epsilon).powi(2)).ceil() as u64).max(1)
}

/// Poisson-disk points with spacing `epsilon` on one surface side, in its 2D frame.
pub fn sample_side(map: &SurfaceMap, side: Side, epsilon: f32, seed: u64) -> Vec<Vec2> {
    let mut rng = Pcg64Mcg::seed_from_u64(side_seed(seed, side, 1));
    let cell = epsilon / std::f32::consts::SQRT_2;
    let size = (map.max - map.min).max(Vec2::splat(0.0));
    let nx = ((size.x / cell).floor() as usize + 1).max(1);
    let ny = ((size.y / cell).floor() as usize + 1).max(1);
    // Grids far bigger than the sample count happen for long thin surfaces: fall back to a
    // hash of occupied cells.
    let dense = nx.saturating_mul(ny) <= 64 * (darts(map.area(), epsilon) as usize + 64);
    let mut grid = CellGrid::new(dense, nx, ny);
    let mut points: Vec<Vec2> = Vec::new();
    let eps2 = epsilon * epsilon;
    for _ in 0..darts(map.area(), epsilon) {
        let p = map.point_at(
            rng.random::<f64>(),
            rng.random::<f32>(),
            rng.random::<f32>(),
        );
        let q = (p - map.min) / cell;
        let (cx, cy) = (q.x.max(0.0) as usize, q.y.max(0.0) as usize);
        let (cx, cy) = (cx.min(nx - 1), cy.min(ny - 1));
        if grid.get(cx, cy).is_some() {
            continue;
        }
        // A sample within ε lies at most two cells away.
        let mut free = true;
        'scan: for y in cy.saturating_sub(2)..=(cy + 2).min(ny - 1) {
            for x in cx.saturating_sub(2)..=(cx + 2).min(nx - 1) {
                if let Some(i) = grid.get(x, y) {
                    if points[i as usize].distance_squared(p) < eps2 {
                        free = false;
                        break 'scan;
                    }
                }
            }
        }
        if free {
            grid.set(cx, cy, points.len() as u32);
            points.push(p);
        }
    }
    points
}

/// Occupancy of the ε/√2 cells: a dense array, or a hash map for sparse huge grids.
enum CellGrid {
    Dense { nx: usize, cells: Vec<u32> },
    Sparse(std::collections::HashMap<(usize, usize), u32>),
}

impl CellGrid {
    fn new(dense: bool, nx: usize, ny: usize) -> Self {
        if dense {
            CellGrid::Dense {
                nx,
                cells: vec![u32::MAX; nx * ny],
            }
        } else {
            CellGrid::Sparse(Default::default())
        }
    }

    fn get(&self, x: usize, y: usize) -> Option<u32> {
        match self {
            CellGrid::Dense { nx, cells } => Some(cells[y * nx + x]).filter(|&i| i != u32::MAX),
            CellGrid::Sparse(map) => map.get(&(x, y)).copied(),
        }
    }

    fn set(&mut self, x: usize, y: usize, i: u32) {
        match self {
            CellGrid::Dense { nx, cells } => cells[y * *nx + x] = i,
            CellGrid::Sparse(map) => {
                map.insert((x, y), i);
            }
        }
    }
}
