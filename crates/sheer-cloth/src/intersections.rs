//! Counting where a cloth passes through itself: the pairs of triangles, sharing no particle, where an
//! edge of one pierces the other. Written apart from the solver's contacts (`collision.rs`, which
//! works with distances and sides) so that it can check them: here a segment–triangle intersection
//! test (Möller & Trumbore 1997) over the pairs whose bounding boxes overlap.

use std::collections::HashMap;

use glam::DVec3;

/// How many pairs of triangles that share no particle intersect: an edge of one crosses the interior
/// or boundary of the other. `positions` in metres; every index of `triangles` must be in range.
pub fn intersecting_triangle_pairs(positions: &[DVec3], triangles: &[[u32; 3]]) -> usize {
    if triangles.is_empty() {
        return 0;
    }
    let corners = |t: usize| triangles[t].map(|i| positions[i as usize]);
    let boxes: Vec<(DVec3, DVec3)> = (0..triangles.len())
        .map(|t| {
            let [a, b, c] = corners(t);
            (a.min(b).min(c), a.max(b).max(c))
        })
        .collect();
    // Cells as large as the mean box's longest side: a box overlaps a few cells.
    let cell = boxes
        .iter()
        .map(|(low, high)| (*high - *low).max_element())
        .sum::<f64>()
        / boxes.len() as f64;
    let cell = if cell > 0.0 && cell.is_finite() {
        cell
    } else {
        1.0
    };
    let to_cell = |x: DVec3| (x / cell).floor().to_array().map(|c| c as i64);
    let mut cells: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    for (t, (low, high)) in boxes.iter().enumerate() {
        let (from, to) = (to_cell(*low), to_cell(*high));
        for i in from[0]..=to[0] {
            for j in from[1]..=to[1] {
                for k in from[2]..=to[2] {
                    cells.entry([i, j, k]).or_default().push(t as u32);
                }
            }
        }
    }
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    for members in cells.values() {
        for (n, &s) in members.iter().enumerate() {
            for &t in &members[n + 1..] {
                let (s, t) = (s.min(t), s.max(t));
                let (bs, bt) = (boxes[s as usize], boxes[t as usize]);
                let overlap = bs.0.cmple(bt.1).all() && bt.0.cmple(bs.1).all();
                let shared = triangles[s as usize]
                    .iter()
                    .any(|i| triangles[t as usize].contains(i));
                if overlap && !shared {
                    pairs.push((s, t));
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    pairs
        .iter()
        .filter(|&&(s, t)| {
            let (a, b) = (corners(s as usize), corners(t as usize));
            edges_pierce(a, b) || edges_pierce(b, a)
        })
        .count()
}

/// Whether an edge of triangle `edges_of` crosses triangle `face`.
fn edges_pierce(edges_of: [DVec3; 3], face: [DVec3; 3]) -> bool {
    (0..3).any(|k| segment_meets_triangle(edges_of[k], edges_of[(k + 1) % 3], face))
}

/// Whether the segment `p`–`q` meets triangle `[a, b, c]` (Möller & Trumbore 1997, "Fast, minimum
/// storage ray–triangle intersection", with the ray parameter limited to the segment).
fn segment_meets_triangle(p: DVec3, q: DVec3, [a, b, c]: [DVec3; 3]) -> bool {
    let direction = q - p;
    let (e1, e2) = (b - a, c - a);
    let h = direction.cross(e2);
    let determinant = e1.dot(h);
    // A segment in the triangle's plane does not pierce it (the neighbours' edges see such contact).
    let scale = e1.length() * e2.length() * direction.length();
    if determinant.abs() <= 1e-12 * scale {
        return false;
    }
    let f = 1.0 / determinant;
    let s = p - a;
    let u = f * s.dot(h);
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let r = s.cross(e1);
    let v = f * direction.dot(r);
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = f * e2.dot(r);
    (0.0..=1.0).contains(&t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_crossed_triangles_count_once_and_apart_none() {
        let mut positions = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.2, 0.2, -0.5),
            DVec3::new(0.2, 0.2, 0.5),
            DVec3::new(0.9, 0.9, 0.0),
        ];
        let triangles = [[0, 1, 2], [3, 4, 5]];
        assert_eq!(intersecting_triangle_pairs(&positions, &triangles), 1);
        for x in &mut positions[3..] {
            x.z += 2.0;
        }
        assert_eq!(intersecting_triangle_pairs(&positions, &triangles), 0);
        // Neighbours sharing a particle never count.
        assert_eq!(
            intersecting_triangle_pairs(&positions, &[[0, 1, 2], [2, 4, 5]]),
            0
        );
    }
}
