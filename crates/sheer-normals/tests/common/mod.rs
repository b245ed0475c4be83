//! Mesh generators shared by the integration tests.
#![allow(dead_code)]

use glam::Vec3;
use std::collections::HashMap;

/// `side × side` vertices in the plane z = 0, spacing `spacing` m, two triangles per cell;
/// `flip(cell)` reverses the winding of both triangles of that cell.
pub fn flat_grid(side: usize, spacing: f32, flip: impl Fn(usize) -> bool) -> (Vec<Vec3>, Vec<u32>) {
    let positions = (0..side * side)
        .map(|k| {
            Vec3::new(
                (k % side) as f32 * spacing,
                (k / side) as f32 * spacing,
                0.0,
            )
        })
        .collect();
    (positions, grid_indices(side, flip))
}

/// Triangle list of a `side × side` grid, cell by cell; `flip(cell)` reverses a cell's winding.
pub fn grid_indices(side: usize, flip: impl Fn(usize) -> bool) -> Vec<u32> {
    let mut indices = Vec::new();
    let s = side as u32;
    for j in 0..side - 1 {
        for i in 0..side - 1 {
            let v = (j * side + i) as u32;
            if flip(j * (side - 1) + i) {
                indices.extend_from_slice(&[v, v + s, v + 1, v + 1, v + s, v + s + 1]);
            } else {
                indices.extend_from_slice(&[v, v + 1, v + s, v + 1, v + s + 1, v + s]);
            }
        }
    }
    indices
}

/// A waving `side × side` sheet over [0, 1]², height 0.1·sin(6x)·cos(4y) m.
pub fn wavy_grid(side: usize) -> (Vec<Vec3>, Vec<u32>) {
    let spacing = 1.0 / (side - 1) as f32;
    let positions = (0..side * side)
        .map(|k| {
            let (x, y) = ((k % side) as f32 * spacing, (k / side) as f32 * spacing);
            Vec3::new(x, y, 0.1 * (6.0 * x).sin() * (4.0 * y).cos())
        })
        .collect();
    (positions, grid_indices(side, |_| false))
}

/// Unit icosphere refined `levels` times (each level splits every triangle in four and pushes the
/// new vertices onto the sphere).
pub fn icosphere(levels: usize) -> (Vec<Vec3>, Vec<u32>) {
    let t = (1.0 + 5.0f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut indices: Vec<u32> = vec![
        0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7,
        1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9,
        8, 1,
    ];
    for _ in 0..levels {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let m = (positions[a as usize] + positions[b as usize]).normalize();
                positions.push(m);
                (positions.len() - 1) as u32
            })
        };
        let mut refined = Vec::with_capacity(indices.len() * 4);
        for t in indices.chunks_exact(3) {
            let ab = midpoint(t[0], t[1], &mut positions);
            let bc = midpoint(t[1], t[2], &mut positions);
            let ca = midpoint(t[2], t[0], &mut positions);
            refined.extend_from_slice(&[t[0], ab, ca, t[1], bc, ab, t[2], ca, bc, ab, bc, ca]);
        }
        indices = refined;
    }
    (positions, indices)
}

/// A small deterministic pseudo-random generator (SplitMix64), so tests need no extra crate.
pub struct SplitMix(pub u64);

impl SplitMix {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, n).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// Each triangle's indices reversed (odd `seed` bits) and/or rotated, chosen pseudo-randomly.
pub fn rewind(indices: &[u32], seed: u64) -> Vec<u32> {
    let mut random = SplitMix(seed);
    indices
        .chunks_exact(3)
        .flat_map(|t| {
            let r = random.below(6);
            let mut t = [t[0], t[1], t[2]];
            if r >= 3 {
                t.swap(1, 2);
            }
            t.rotate_left(r % 3);
            t
        })
        .collect()
}

/// Bit patterns of a normal array, for bit-for-bit comparisons.
pub fn bits(normals: &[Vec3]) -> Vec<[u32; 3]> {
    normals
        .iter()
        .map(|n| [n.x.to_bits(), n.y.to_bits(), n.z.to_bits()])
        .collect()
}
