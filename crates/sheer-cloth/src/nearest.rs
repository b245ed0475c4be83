//! The nearest of a set of points to each of many others, by a k-d tree (Bentley 1975).
//!
//! The long-range attachments tie every free particle to its nearest pinned particle at rest. Scanning
//! every pin for every particle costs particles × pins: for a 1024 × 745 flag with its hoist pinned,
//! 570 million distances and most of `Simulation::new` (about 1.6 s). The tree answers each query in
//! about log₂(pins) steps. Its answer is exactly the scan's: the smallest [`DVec3::distance`], computed
//! by the same expression, with ties going to the lowest index (the scan's first minimum), so the
//! attachments and every result after them are the same bits.

use glam::DVec3;
use rayon::prelude::*;

/// Points per leaf: below this a scan is cheaper than splitting further.
const LEAF: usize = 8;

/// The index into `points` of the point nearest to each of `queries` and its distance (m), ties to the
/// lowest index; `None` for every query when `points` is empty. Deterministic whatever the thread count.
pub(crate) fn nearest_points(points: &[DVec3], queries: &[DVec3]) -> Vec<Option<(u32, f64)>> {
    if points.is_empty() {
        return vec![None; queries.len()];
    }
    // The tree's pruning bound assumes ordered coordinates; any other input takes the scan.
    if !points.iter().chain(queries).all(|p| p.is_finite()) {
        return queries.iter().map(|&q| scan(points, q)).collect();
    }
    let tree = Tree::new(points);
    queries
        .par_iter()
        .map(|&q| Some(tree.nearest(points, q)))
        .collect()
}

/// The linear scan the tree replaces: first minimum of the distance in index order.
fn scan(points: &[DVec3], query: DVec3) -> Option<(u32, f64)> {
    points
        .iter()
        .enumerate()
        .map(|(k, p)| (k as u32, query.distance(*p)))
        .min_by(|x, y| x.1.total_cmp(&y.1))
}

/// A k-d tree over point indices: each range of `order` is split at its median along the axis of its
/// widest extent; every range keeps its bounding box, which bounds the distance to all its points.
struct Tree {
    order: Vec<u32>,
    /// The ranges, each before the two it splits into (the root first).
    nodes: Vec<Node>,
}

struct Node {
    start: usize,
    end: usize,
    /// Corners of the bounding box of the range's points (m).
    low: DVec3,
    high: DVec3,
    /// Indices into `nodes` of the lower and upper halves; `None` for a leaf.
    halves: Option<(usize, usize)>,
}

impl Tree {
    fn new(points: &[DVec3]) -> Tree {
        let mut tree = Tree {
            order: (0..points.len() as u32).collect(),
            nodes: Vec::new(),
        };
        tree.build(points, 0, points.len());
        tree
    }

    /// Adds the node of `order[start..end]` and those below it; returns its index.
    fn build(&mut self, points: &[DVec3], start: usize, end: usize) -> usize {
        let range = &mut self.order[start..end];
        let (low, high) =
            range
                .iter()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(low, high), &i| {
                    let p = points[i as usize];
                    (low.min(p), high.max(p))
                });
        let index = self.nodes.len();
        self.nodes.push(Node {
            start,
            end,
            low,
            high,
            halves: None,
        });
        if end - start > LEAF {
            let extent = high - low;
            let axis = if extent.x >= extent.y && extent.x >= extent.z {
                0
            } else if extent.y >= extent.z {
                1
            } else {
                2
            };
            let middle = range.len() / 2;
            range.select_nth_unstable_by(middle, |&i, &j| {
                points[i as usize][axis].total_cmp(&points[j as usize][axis])
            });
            let lower = self.build(points, start, start + middle);
            let upper = self.build(points, start + middle, end);
            self.nodes[index].halves = Some((lower, upper));
        }
        index
    }

    /// Nearest point to `query` (all coordinates finite).
    fn nearest(&self, points: &[DVec3], query: DVec3) -> (u32, f64) {
        let mut best = (u32::MAX, f64::INFINITY);
        self.search(points, query, 0, self.bound(query, 0), &mut best);
        best
    }

    /// The distance (m) from `query` to `node`'s box: every point of the node is at least this far away.
    fn bound(&self, query: DVec3, node: usize) -> f64 {
        let node = &self.nodes[node];
        query.distance(query.clamp(node.low, node.high))
    }

    /// Searches `node`, `bound` away from `query` ([`Tree::bound`]).
    fn search(
        &self,
        points: &[DVec3],
        query: DVec3,
        node: usize,
        bound: f64,
        best: &mut (u32, f64),
    ) {
        // The margin covers the rounding of the computed distances (a few ulps) and their underflow, so
        // that no point that could equal or beat the best is skipped: the answer stays the scan's.
        if bound > best.1 * (1.0 + 1e-9) + 1e-150 {
            return;
        }
        let node = &self.nodes[node];
        match node.halves {
            None => {
                for &k in &self.order[node.start..node.end] {
                    let distance = query.distance(points[k as usize]);
                    if distance < best.1 || (distance == best.1 && k < best.0) {
                        *best = (k, distance);
                    }
                }
            }
            Some((lower, upper)) => {
                // The nearer box first, so that the farther one is more often skipped.
                let (lower_bound, upper_bound) =
                    (self.bound(query, lower), self.bound(query, upper));
                let [first, second] = if lower_bound <= upper_bound {
                    [(lower, lower_bound), (upper, upper_bound)]
                } else {
                    [(upper, upper_bound), (lower, lower_bound)]
                };
                self.search(points, query, first.0, first.1, best);
                self.search(points, query, second.0, second.1, best);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random_unit(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The tree's answer is the scan's, bit for bit, on random clouds, on lattices full of exact ties
    /// and duplicate points, on points along a line (a flag's hoist) and on coincident queries.
    #[test]
    fn the_tree_finds_the_scans_nearest_point_and_ties_to_the_lowest_index() {
        let mut state = 7;
        let mut cases: Vec<(Vec<DVec3>, Vec<DVec3>)> = Vec::new();
        for count in [1, 2, 7, 8, 9, 17, 100, 1000] {
            let points: Vec<DVec3> = (0..count)
                .map(|_| {
                    DVec3::new(
                        random_unit(&mut state),
                        random_unit(&mut state),
                        0.1 * random_unit(&mut state),
                    )
                })
                .collect();
            let mut queries: Vec<DVec3> = (0..500)
                .map(|_| {
                    DVec3::new(
                        2.0 * random_unit(&mut state) - 0.5,
                        2.0 * random_unit(&mut state) - 0.5,
                        random_unit(&mut state) - 0.5,
                    )
                })
                .collect();
            queries.extend(points.iter().take(20));
            cases.push((points, queries));
        }
        // A lattice with every point twice: equidistant candidates everywhere.
        let lattice: Vec<DVec3> = (0..2)
            .flat_map(|_| {
                (0..12)
                    .flat_map(|i| (0..9).map(move |j| DVec3::new(i as f64, j as f64, 0.0) * 0.25))
            })
            .collect();
        let lattice_queries: Vec<DVec3> = (0..48)
            .flat_map(|i| (0..36).map(move |j| DVec3::new(i as f64, j as f64, 0.5) * 0.0625))
            .collect();
        cases.push((lattice, lattice_queries));
        // A hoist: pins along a vertical line, queries over the flag.
        let hoist: Vec<DVec3> = (0..46)
            .map(|r| DVec3::new(0.0, -0.0178 * r as f64, 0.0))
            .collect();
        let flag: Vec<DVec3> = (0..46)
            .flat_map(|r| {
                (0..64).map(move |c| DVec3::new(0.0172 * c as f64, -0.0178 * r as f64, 0.0))
            })
            .collect();
        cases.push((hoist, flag));
        for (points, queries) in &cases {
            let got = nearest_points(points, queries);
            for (q, got) in queries.iter().zip(got) {
                let want = scan(points, *q);
                assert_eq!(
                    got.map(|(k, d)| (k, d.to_bits())),
                    want.map(|(k, d)| (k, d.to_bits())),
                    "query {q} among {} points",
                    points.len()
                );
            }
        }
        assert_eq!(nearest_points(&[], &[DVec3::ZERO]), vec![None]);
        let with_nan = [DVec3::ZERO, DVec3::new(f64::NAN, 0.0, 0.0)];
        assert_eq!(
            nearest_points(&with_nan, &[DVec3::X]),
            vec![scan(&with_nan, DVec3::X)]
        );
    }
}
