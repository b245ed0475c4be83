//! Contacts: the cloth against itself and against rigid colliders, as position constraints projected
//! once a sub-step after the springs (Müller, Heidelberger, Hennix & Ratcliff 2007, §3.3 and §4.2:
//! collision constraints are inequality constraints projected like any other).
//!
//! **Self-contacts** (Bridson, Fedkiw & Anderson 2002, "Robust treatment of collisions, contact and
//! friction for cloth animation", §6: point–triangle and edge–edge proximity): every particle keeps
//! `thickness` (m) from every triangle it is not a corner of, and every edge as far from every edge it
//! shares no particle with, on the side it was on at the start of the sub-step, so that a particle or
//! an edge that crossed during the sub-step is put back, not pushed on through. The distance between
//! two triangles is reached at a corner and a face or at two edges, so the two kinds cover every way
//! two triangles can approach. Pairs closer than the thickness at rest (neighbours in the fabric) never
//! touch.
//!
//! **Broad phase**: uniform grids of cells over the cloth's box (Ericson 2005, *Real-Time Collision
//! Detection*, §7.1), one of the particles, queried with each triangle's box, and one of the edges'
//! midpoints, whose neighbouring cells are paired, listing the pairs within `thickness + skin`
//! (tested against a search of every pair). The lists are rebuilt only once some particle has moved
//! more than `skin / 2` since they were built: a pair not listed was then at least `thickness + skin`
//! apart, and the distance between a point and a triangle, or between two segments, changes by at most
//! twice the largest displacement of their four particles, so it is still at least `thickness` apart.
//!
//! **Colliders** (spheres, capsules, planes): every free particle keeps `thickness / 2` from the
//! surface, with Coulomb friction on its motion along the surface (Macklin, Müller, Chentanez & Kim
//! 2014, "Unified particle physics for real-time applications", §6.1).
//!
//! Everything here runs on one thread in a fixed order: the same state gives the same bits whatever
//! the thread count.

use glam::DVec3;
use rayon::prelude::*;

use crate::params::{Collider, Collisions};

/// How far beyond the thickness the broad phase looks, as a multiple of the thickness: a larger skin
/// rebuilds the lists less often but lists more pairs for every sub-step to check. 2 keeps the
/// default flag's reach (12 mm) below the 12.4 mm between non-adjacent elements of its flat grid, so
/// a flat flag lists nothing (docs/perf/collisions.md compares 1, 2 and 3).
const SKIN_PER_THICKNESS: f64 = 2.0;

/// The particle grid's cell side (the smallest it takes), as a multiple of the reach: larger cells
/// mean fewer cells a triangle's box overlaps, more particles in each.
const CELL_PER_REACH: f64 = 4.0;

/// The candidate contact pairs of a cloth and the scratch the projection works in.
#[derive(Clone, Debug, Default)]
pub(crate) struct Contacts {
    /// Where the particles were when the pairs were listed (empty: not listed yet).
    listed_at: Vec<DVec3>,
    /// The thickness (m) the list was made for.
    listed_thickness: f64,
    /// Particle–triangle pairs within `thickness + skin` when listed, apart at rest.
    point_triangle: Vec<(u32, u32)>,
    /// Pairs of edges (indices into `edges`, the lower first) within `thickness + skin` when listed,
    /// sharing no particle, apart at rest.
    edge_edge: Vec<(u32, u32)>,
    /// The cloth's edges, each once, its particles in ascending order (built at the first listing).
    edges: Vec<[u32; 2]>,
    /// The particles and the edges' midpoints binned by cell, rebuilt with the lists.
    grid: CellGrid,
    edge_grid: CellGrid,
    /// Scratch: the edges' midpoints and half-lengths (m), and each edge's particles, midpoint,
    /// half-length and box in `edge_grid`'s order.
    midpoints: Vec<DVec3>,
    half_lengths: Vec<f64>,
    binned_edges: Vec<BinnedEdge>,
    /// The colliders' boxes and the free particles inside one (`list_near_colliders`).
    collider_boxes: Vec<(DVec3, DVec3)>,
    pub(crate) near_colliders: Vec<u32>,
    /// Scratch of the sub-step: which particle the contacts moved, from where to where (m).
    pub(crate) moves: Vec<(usize, DVec3, DVec3)>,
    /// Positions at the start of the sub-step and now (m), joined from the solver's split state.
    pub(crate) start: Vec<DVec3>,
    pub(crate) now: Vec<DVec3>,
}

impl Contacts {
    /// Projects every contact of `collisions` once, moving the particles in `now` (m) whose inverse
    /// mass is > 0; `start` holds where they were at the start of the sub-step. `rest` is the rest
    /// shape (m), `triangles` the cloth's triangles; `parallel` lists the pairs on rayon's threads
    /// (the same list; the projection runs on this thread, in the list's order).
    pub(crate) fn project(
        &mut self,
        collisions: &Collisions,
        rest: &[DVec3],
        inverse_masses: &[f64],
        triangles: &[[u32; 3]],
        parallel: bool,
    ) {
        if collisions.self_collision {
            let skin = SKIN_PER_THICKNESS * collisions.thickness;
            if self.list_is_stale(collisions.thickness, skin) {
                self.list_pairs(collisions.thickness, skin, rest, triangles, parallel);
            }
            let Contacts {
                point_triangle,
                edge_edge,
                edges,
                start,
                now,
                ..
            } = self;
            for &(p, t) in point_triangle.iter() {
                let [a, b, c] = triangles[t as usize].map(|i| i as usize);
                keep_point_off_triangle(
                    [p as usize, a, b, c],
                    collisions.thickness,
                    inverse_masses,
                    start,
                    now,
                );
            }
            for &(e, f) in edge_edge.iter() {
                let [a, b] = edges[e as usize].map(|i| i as usize);
                let [c, d] = edges[f as usize].map(|i| i as usize);
                keep_edges_apart(
                    [a, b, c, d],
                    collisions.thickness,
                    inverse_masses,
                    start,
                    now,
                );
            }
        }
        // Colliders last: nothing ends a sub-step inside one.
        let now = std::mem::take(&mut self.now);
        self.list_near_colliders(collisions, inverse_masses, |i| now[i]);
        self.now = now;
        for &i in &self.near_colliders {
            let i = i as usize;
            self.now[i] = self.kept_off_colliders(collisions, self.start[i], self.now[i]);
        }
    }

    /// Lists in `near_colliders` the free particles inside some collider's box (the box outside
    /// which a particle is farther than half the thickness from it), in index order, reading
    /// particle `i`'s position (m) as `position(i)`; `collider_boxes` keeps the boxes.
    pub(crate) fn list_near_colliders(
        &mut self,
        collisions: &Collisions,
        inverse_masses: &[f64],
        position: impl Fn(usize) -> DVec3,
    ) {
        let gap = collisions.thickness / 2.0;
        self.collider_boxes.clear();
        self.collider_boxes
            .extend(collisions.colliders.iter().map(|c| c.bounds(gap)));
        self.near_colliders.clear();
        if self.collider_boxes.is_empty() {
            return;
        }
        let boxes = &self.collider_boxes;
        self.near_colliders.extend(
            (0..inverse_masses.len() as u32)
                .filter(|&i| inverse_masses[i as usize] > 0.0)
                .filter(|&i| {
                    let x = position(i as usize);
                    boxes
                        .iter()
                        .any(|(low, high)| x.cmpge(*low).all() && x.cmple(*high).all())
                }),
        );
    }

    /// Where a particle listed by [`list_near_colliders`](Self::list_near_colliders) that was at
    /// `start` and is now at `x` (m) ends up when kept off every collider in turn whose box it is in
    /// ([`kept_off_collider`], a gap of half the thickness): a particle's place depends on nothing
    /// else, so particles are kept off one at a time, and one in no box stays where it is.
    pub(crate) fn kept_off_colliders(
        &self,
        collisions: &Collisions,
        start: DVec3,
        x: DVec3,
    ) -> DVec3 {
        let gap = collisions.thickness / 2.0;
        collisions.colliders.iter().zip(&self.collider_boxes).fold(
            x,
            |x, (collider, (low, high))| {
                if x.cmpge(*low).all() && x.cmple(*high).all() {
                    kept_off_collider(collider, gap, collisions.friction, start, x)
                } else {
                    x
                }
            },
        )
    }

    /// Whether a particle has moved more than `skin / 2` since the pairs were listed (or they never
    /// were, or for another thickness).
    fn list_is_stale(&self, thickness: f64, skin: f64) -> bool {
        let limit = (skin / 2.0) * (skin / 2.0);
        self.listed_thickness != thickness
            || self.listed_at.len() != self.now.len()
            || self
                .listed_at
                .iter()
                .zip(&self.now)
                .any(|(a, b)| a.distance_squared(*b) > limit)
    }

    /// Lists the particle–triangle pairs within `thickness + skin` (m) now and at least `thickness`
    /// apart at rest, in triangle order.
    fn list_pairs(
        &mut self,
        thickness: f64,
        skin: f64,
        rest: &[DVec3],
        triangles: &[[u32; 3]],
        parallel: bool,
    ) {
        let reach = thickness + skin;
        self.grid.build(&self.now, CELL_PER_REACH * reach);
        let (grid, now) = (&self.grid, &self.now[..]);
        self.point_triangle = concat_in_order(parallel, triangles.len(), |t, pairs| {
            let triangle = &triangles[t];
            let corners = triangle.map(|i| now[i as usize]);
            let low = corners[0].min(corners[1]).min(corners[2]) - DVec3::splat(reach);
            let high = corners[0].max(corners[1]).max(corners[2]) + DVec3::splat(reach);
            // A ball around the centroid holding the triangle and its reach: a cheap first test.
            let centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
            let ball = corners
                .iter()
                .map(|c| c.distance_squared(centroid))
                .fold(0.0, f64::max)
                .sqrt()
                + reach;
            grid.for_each_in_box(low, high, |p, x| {
                if triangle.contains(&p) || x.distance_squared(centroid) > ball * ball {
                    return;
                }
                if (x - closest_point_on_triangle(x, corners).0).length() >= reach {
                    return;
                }
                let rest_corners = triangle.map(|i| rest[i as usize]);
                let at_rest = rest[p as usize];
                let rest_distance =
                    (at_rest - closest_point_on_triangle(at_rest, rest_corners).0).length();
                if rest_distance >= thickness {
                    pairs.push((p, t as u32));
                }
            });
        });
        self.list_edge_pairs(thickness, reach, rest, triangles, parallel);
        self.listed_at.clone_from(&self.now);
        self.listed_thickness = thickness;
    }
}

/// What `list(i, pairs)` pushes for every `i` in `0..count`, concatenated in the order of `i`: on
/// rayon's threads when `parallel`, else on this one, the same list either way.
fn concat_in_order(
    parallel: bool,
    count: usize,
    list: impl Fn(usize, &mut Vec<(u32, u32)>) + Sync,
) -> Vec<(u32, u32)> {
    if parallel {
        (0..count)
            .into_par_iter()
            .with_min_len(1024)
            .fold_with(Vec::new(), |mut pairs, i| {
                list(i, &mut pairs);
                pairs
            })
            .collect::<Vec<Vec<(u32, u32)>>>()
            .concat()
    } else {
        let mut pairs = Vec::new();
        for i in 0..count {
            list(i, &mut pairs);
        }
        pairs
    }
}

impl Collider {
    /// The box (m) outside which a particle is farther than `gap` (m) from this collider (unbounded
    /// for a plane).
    fn bounds(&self, gap: f64) -> (DVec3, DVec3) {
        match *self {
            Collider::Sphere { center, radius } => {
                let r = DVec3::splat(radius + gap);
                (center - r, center + r)
            }
            Collider::Capsule { start, end, radius } => {
                let r = DVec3::splat(radius + gap);
                (start.min(end) - r, start.max(end) + r)
            }
            Collider::Plane { .. } => (DVec3::NEG_INFINITY, DVec3::INFINITY),
        }
    }
}

impl Contacts {
    /// Lists the pairs of edges within `reach` (m) now, sharing no particle and at least `thickness`
    /// apart at rest. Edges are binned by midpoint in cells of `reach` plus the longest edge: two
    /// edges within `reach` have midpoints at most that far apart, in the same or neighbouring cells.
    fn list_edge_pairs(
        &mut self,
        thickness: f64,
        reach: f64,
        rest: &[DVec3],
        triangles: &[[u32; 3]],
        parallel: bool,
    ) {
        if self.edges.is_empty() {
            self.edges = triangles
                .iter()
                .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
                .map(|[a, b]| [a.min(b), a.max(b)])
                .collect();
            self.edges.sort_unstable();
            self.edges.dedup();
        }
        let Contacts {
            edges,
            edge_edge,
            edge_grid,
            midpoints,
            half_lengths,
            binned_edges,
            now,
            ..
        } = self;
        midpoints.clear();
        midpoints.extend(
            edges
                .iter()
                .map(|&[a, b]| (now[a as usize] + now[b as usize]) / 2.0),
        );
        half_lengths.clear();
        half_lengths.extend(
            edges
                .iter()
                .map(|&[a, b]| now[a as usize].distance(now[b as usize]) / 2.0),
        );
        let longest = 2.0 * half_lengths.iter().copied().fold(0.0, f64::max);
        edge_grid.build(midpoints, reach + longest);
        binned_edges.clear();
        binned_edges.extend(edge_grid.entries.iter().map(|&e| {
            let [a, b] = edges[e as usize];
            let (x, y) = (now[a as usize], now[b as usize]);
            BinnedEdge {
                edge: e,
                particles: [a, b],
                midpoint: midpoints[e as usize],
                half_length: half_lengths[e as usize],
                low: x.min(y),
                high: x.max(y),
            }
        }));
        let (grid, binned, now) = (&*edge_grid, &binned_edges[..], &now[..]);
        *edge_edge = concat_in_order(parallel, grid.cells(), |c, pairs| {
            let own = grid.run(c as u32);
            if own.is_empty() {
                return;
            }
            grid.for_each_forward_neighbour(grid.cell_coordinates_of(c as u32), |d| {
                let other = grid.run(d);
                for slot in own.clone() {
                    let this = &binned[slot];
                    let [a, b] = this.particles;
                    // Each pair once: in its own cell, only the edges after this one.
                    let first = if d == c as u32 { slot + 1 } else { other.start };
                    for that in &binned[first..other.end] {
                        let within = reach + this.half_length + that.half_length;
                        if this.midpoint.distance_squared(that.midpoint) > within * within {
                            continue;
                        }
                        let [c, d] = that.particles;
                        if c == a || c == b || d == a || d == b {
                            continue;
                        }
                        // Boxes farther apart than the reach along some axis: a cheap first test.
                        let apart = (this.low - that.high).max(that.low - this.high);
                        if apart.max_element() >= reach {
                            continue;
                        }
                        let [x, y, z, w] = [a, b, c, d].map(|i| now[i as usize]);
                        if closest_points_of_segments(x, y, z, w).2 >= reach {
                            continue;
                        }
                        let [x, y, z, w] = [a, b, c, d].map(|i| rest[i as usize]);
                        if closest_points_of_segments(x, y, z, w).2 >= thickness {
                            pairs.push((this.edge.min(that.edge), this.edge.max(that.edge)));
                        }
                    }
                }
            });
        });
        // Listed in the order the cells were visited: sorted, the order depends on the pairs alone.
        edge_edge.sort_unstable();
    }
}

/// Keeps edges `a`–`b` and `c`–`d` at least `thickness` (m) apart on the side they started the
/// sub-step on: `C = n·(x_ab(s) − x_cd(t)) − thickness ≥ 0` at the closest points `s`, `t` of the
/// segments now, `n` the unit direction between those points at the start (Bridson et al. 2002, §6:
/// edge–edge proximity), projected with the inverse masses (Müller et al. 2007, stiffness 1).
fn keep_edges_apart(
    [a, b, c, d]: [usize; 4],
    thickness: f64,
    inverse_masses: &[f64],
    start: &[DVec3],
    now: &mut [DVec3],
) {
    let (s, t, distance) = closest_points_of_segments(now[a], now[b], now[c], now[d]);
    let gap = now[a].lerp(now[b], s) - now[c].lerp(now[d], t);
    let start_gap = start[a].lerp(start[b], s) - start[c].lerp(start[d], t);
    let Some(direction) = start_gap.try_normalize().or_else(|| gap.try_normalize()) else {
        return; // touching at the start and now: no direction to part them in
    };
    let crossed = direction.dot(gap) < 0.0 && s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0;
    if !(distance < thickness || crossed) {
        return;
    }
    let constraint = direction.dot(gap) - thickness;
    if constraint >= 0.0 {
        return;
    }
    let weights = [1.0 - s, s, -(1.0 - t), -t];
    let particles = [a, b, c, d];
    let divisor: f64 = particles
        .iter()
        .zip(weights)
        .map(|(&i, g)| inverse_masses[i] * g * g)
        .sum();
    if divisor <= 0.0 {
        return;
    }
    let push = -constraint / divisor * direction;
    for (&i, g) in particles.iter().zip(weights) {
        now[i] += inverse_masses[i] * g * push;
    }
}

/// The closest points of segments `p1`–`q1` and `p2`–`q2` as parameters `s`, `t` in [0, 1] along
/// each, and their distance (m) (Ericson 2005, *Real-Time Collision Detection*, §5.1.9).
pub(crate) fn closest_points_of_segments(
    p1: DVec3,
    q1: DVec3,
    p2: DVec3,
    q2: DVec3,
) -> (f64, f64, f64) {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    let (s, t) = if a <= f64::EPSILON && e <= f64::EPSILON {
        (0.0, 0.0)
    } else if a <= f64::EPSILON {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= f64::EPSILON {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denominator = a * e - b * b;
            let mut s = if denominator > 0.0 {
                ((b * f - c * e) / denominator).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    let distance = (p1 + s * d1).distance(p2 + t * d2);
    (s, t, distance)
}

/// Keeps particle `p` at least `thickness` (m) from triangle `(a, b, c)` on the side it started the
/// sub-step on: the constraint `C = s n·(x_p − Σ βᵢ x_i) − thickness ≥ 0`, with `n` the triangle's unit
/// normal now, `s` the side at the start and `β` the barycentric coordinates of the closest point,
/// projected with the particles' inverse masses (Müller et al. 2007, eq. (2)–(4) with stiffness 1).
/// Beside the triangle (closest to an edge or corner) it keeps the distance along the offset instead.
fn keep_point_off_triangle(
    [p, a, b, c]: [usize; 4],
    thickness: f64,
    inverse_masses: &[f64],
    start: &[DVec3],
    now: &mut [DVec3],
) {
    let corners = [now[a], now[b], now[c]];
    let (closest, weights) = closest_point_on_triangle(now[p], corners);
    let offset = now[p] - closest;
    let distance = offset.length();
    let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
    let start_normal = (start[b] - start[a]).cross(start[c] - start[a]);
    let Some(normal) = normal.try_normalize() else {
        return; // a triangle crushed to a line has no sides
    };
    let start_height = start_normal.dot(start[p] - start[a]);
    let side = if start_height != 0.0 {
        start_height.signum()
    } else {
        normal.dot(offset).signum()
    };
    // Over the face: along the normal, on the start side. Beside it: straight away from its edge.
    let inside = weights.iter().all(|&w| w > 0.0);
    let direction = if inside {
        side * normal
    } else if distance < thickness && distance > 0.0 {
        offset / distance
    } else {
        return;
    };
    let constraint = direction.dot(offset) - thickness;
    if constraint >= 0.0 {
        return;
    }
    let w = [
        inverse_masses[p],
        inverse_masses[a],
        inverse_masses[b],
        inverse_masses[c],
    ];
    let divisor =
        w[0] + w[1] * weights[0].powi(2) + w[2] * weights[1].powi(2) + w[3] * weights[2].powi(2);
    if divisor <= 0.0 {
        return;
    }
    let push = -constraint / divisor * direction;
    now[p] += w[0] * push;
    for (k, &i) in [a, b, c].iter().enumerate() {
        now[i] -= w[k + 1] * weights[k] * push;
    }
}

/// Where a particle that was at `start` and is now at `x` (m) ends up when kept `gap` (m) outside
/// `collider`: pushed out along the surface normal, then its motion along the surface over the
/// sub-step cancelled while it is at most `friction` times the push (static friction), else shortened
/// by that much (kinetic), after Macklin et al. 2014, eq. (24).
fn kept_off_collider(
    collider: &Collider,
    gap: f64,
    friction: f64,
    start: DVec3,
    x: DVec3,
) -> DVec3 {
    let (surface_point, normal) = match *collider {
        Collider::Sphere { center, radius } => match (x - center).try_normalize() {
            Some(n) => (center + radius * n, n),
            None => return x, // at the exact centre no direction is outward
        },
        Collider::Capsule {
            start: a,
            end: b,
            radius,
        } => {
            let axis = b - a;
            let along = if axis.length_squared() > 0.0 {
                ((x - a).dot(axis) / axis.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let on_axis = a + along * axis;
            match (x - on_axis).try_normalize() {
                Some(n) => (on_axis + radius * n, n),
                None => return x,
            }
        }
        Collider::Plane { point, normal } => (point, normal.normalize()),
    };
    let depth = gap - normal.dot(x - surface_point);
    if depth <= 0.0 {
        return x;
    }
    let pushed = x + depth * normal;
    let motion = pushed - start;
    let sliding = motion - normal.dot(motion) * normal;
    let slide = sliding.length();
    let stop = friction * depth;
    if slide <= stop {
        pushed - sliding
    } else {
        pushed - sliding * (stop / slide)
    }
}

/// The point of triangle `corners` closest to `x` (m), with its barycentric coordinates (Ericson 2005,
/// *Real-Time Collision Detection*, §5.1.5).
pub(crate) fn closest_point_on_triangle(x: DVec3, [a, b, c]: [DVec3; 3]) -> (DVec3, [f64; 3]) {
    let (ab, ac, ap) = (b - a, c - a, x - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = x - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + v * ab, [1.0 - v, v, 0.0]);
    }
    let cp = x - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + w * ac, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + w * (c - b), [0.0, 1.0 - w, w]);
    }
    let denominator = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denominator, vc * denominator);
    (a + v * ab + w * ac, [1.0 - v - w, v, w])
}

/// An edge as the edge listing reads it, stored in the order of its midpoint's cell.
#[derive(Clone, Copy, Debug)]
struct BinnedEdge {
    /// Its index in the cloth's edges, and its particles.
    edge: u32,
    particles: [u32; 2],
    /// Its midpoint, half its length and its box (m).
    midpoint: DVec3,
    half_length: f64,
    low: DVec3,
    high: DVec3,
}

/// Points binned by cubic cell over their bounding box (a uniform grid, Ericson 2005, *Real-Time
/// Collision Detection*, §7.1), sorted by cell so that each cell's points are one run, in index order,
/// with a copy of the points in that order for the queries to read in sequence.
#[derive(Clone, Debug, Default)]
struct CellGrid {
    /// The cell side (m), and the lowest cell's corner in cells (whole numbers, on the lattice
    /// `floor(x / cell)`).
    cell: f64,
    origin: DVec3,
    /// Cells along x, y and z; cell `(i, j, k)` is number `(i · dims[1] + j) · dims[2] + k`.
    dims: [usize; 3],
    /// `starts[c]..starts[c + 1]` are the entries of cell `c` in `entries` and `points`; one cell past
    /// the grid's holds the points that are not finite, which no query visits.
    starts: Vec<u32>,
    /// The points' indices and positions (m), sorted by cell.
    entries: Vec<u32>,
    points: Vec<DVec3>,
    /// Scratch: each point's cell.
    cells: Vec<u32>,
}

impl CellGrid {
    /// Bins `points` in cells of side `cell` (m) over their box, in at most `4 n + 64` cells so that
    /// memory stays linear in the points: where more would be needed, over the box of the middle 98 %
    /// of the points on each axis, the points beyond it in its outermost cells (a few particles flung
    /// far), and where that is still too many, in larger cells (a cloth spread wide). Every box query
    /// finds every point of the box whatever the grid; a larger one visits more points beside it.
    fn build(&mut self, points: &[DVec3], cell: f64) {
        let finite = points.iter().filter(|x| x.is_finite());
        let low = finite.clone().fold(DVec3::INFINITY, |a, &x| a.min(x));
        let high = finite.fold(DVec3::NEG_INFINITY, |a, &x| a.max(x));
        let (mut low, mut high) = if low.cmple(high).all() {
            (low, high)
        } else {
            (DVec3::ZERO, DVec3::ZERO)
        };
        let most = 4.0 * points.len() as f64 + 64.0;
        let mut side = if cell > 0.0 { cell } else { f64::INFINITY };
        let mut trimmed = false;
        let (origin, dims) = loop {
            let origin = (low / side).floor();
            let dims = (high / side).floor() - origin + DVec3::ONE;
            let count = dims.x * dims.y * dims.z;
            if count <= most {
                break (origin, dims.to_array().map(|d| d as usize));
            }
            // Too many: first the middle of the points, then larger cells.
            if trimmed {
                side *= (count / most).cbrt().max(1.5);
            } else {
                (low, high) = middle_box(points, 0.01);
                trimmed = true;
            }
        };
        self.cell = side;
        self.origin = origin;
        self.dims = dims;
        let count = self.cells();
        let mut cells = std::mem::take(&mut self.cells);
        cells.clear();
        cells.extend(points.iter().map(|&x| {
            if x.is_finite() {
                self.cell_number(self.cell_coordinates(x))
            } else {
                count as u32
            }
        }));
        self.cells = cells;
        self.starts.clear();
        self.starts.resize(count + 2, 0);
        for &c in &self.cells {
            self.starts[c as usize + 1] += 1;
        }
        for c in 0..=count {
            self.starts[c + 1] += self.starts[c];
        }
        self.entries.clear();
        self.entries.resize(points.len(), 0);
        self.points.clear();
        self.points.resize(points.len(), DVec3::ZERO);
        // Placed in index order: each cell's run is in index order.
        let mut next = self.starts.clone();
        for (i, &c) in self.cells.iter().enumerate() {
            let slot = next[c as usize] as usize;
            self.entries[slot] = i as u32;
            self.points[slot] = points[i];
            next[c as usize] += 1;
        }
    }

    /// The number of cells of the grid.
    fn cells(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// The cell holding `x` (m), clamped to the grid (a box reaching beyond it starts or ends in its
    /// outermost cells).
    fn cell_coordinates(&self, x: DVec3) -> [usize; 3] {
        let c = ((x / self.cell).floor() - self.origin).max(DVec3::ZERO);
        let top = DVec3::from_array(self.dims.map(|d| (d - 1) as f64));
        c.min(top).to_array().map(|c| c as usize)
    }

    fn cell_number(&self, [i, j, k]: [usize; 3]) -> u32 {
        ((i * self.dims[1] + j) * self.dims[2] + k) as u32
    }

    /// The coordinates of cell number `c` (the inverse of [`cell_number`](Self::cell_number)).
    fn cell_coordinates_of(&self, c: u32) -> [usize; 3] {
        let (c, [_, rows, columns]) = (c as usize, self.dims);
        [c / (rows * columns), (c / columns) % rows, c % columns]
    }

    /// The entries of cell number `c`, as indices into `entries` and `points`.
    fn run(&self, c: u32) -> std::ops::Range<usize> {
        self.starts[c as usize] as usize..self.starts[c as usize + 1] as usize
    }

    /// Calls `visit(index, position)` for every point whose cell overlaps the box `low..high` (m), the
    /// cells in lexicographic order, each cell's points in index order; none for a box that is not
    /// finite (a cloth diverging, which its step reports) or empty.
    fn for_each_in_box(&self, low: DVec3, high: DVec3, mut visit: impl FnMut(u32, DVec3)) {
        if !(low.is_finite() && high.is_finite() && low.cmple(high).all()) {
            return;
        }
        // Clamped like the points: a box beyond the grid reaches the outermost cells, where the
        // points beyond it are.
        let (from, to) = (self.cell_coordinates(low), self.cell_coordinates(high));
        for i in from[0]..=to[0] {
            for j in from[1]..=to[1] {
                let row = self.cell_number([i, j, from[2]])..=self.cell_number([i, j, to[2]]);
                let (first, last) = (self.run(*row.start()).start, self.run(*row.end()).end);
                for slot in first..last {
                    visit(self.entries[slot], self.points[slot]);
                }
            }
        }
    }

    /// Calls `visit(d)` for cell `c` itself and each of its 13 neighbours that come after it (in
    /// lexicographic order of the offset) inside the grid: over all cells `c`, every pair of
    /// neighbouring cells is visited once.
    fn for_each_forward_neighbour(&self, c: [usize; 3], mut visit: impl FnMut(u32)) {
        for di in 0..=1usize {
            for dj in -1..=1isize {
                for dk in -1..=1isize {
                    if (di, dj, dk) <= (0, 0, -1) {
                        continue;
                    }
                    let (i, j, k) = (
                        c[0] + di,
                        c[1].wrapping_add_signed(dj),
                        c[2].wrapping_add_signed(dk),
                    );
                    if i < self.dims[0] && j < self.dims[1] && k < self.dims[2] {
                        visit(self.cell_number([i, j, k]));
                    }
                }
            }
        }
    }
}

/// The box (m) of the points' coordinates between the `tail` and `1 − tail` quantiles on each axis,
/// of the finite points (the origin when there are none).
fn middle_box(points: &[DVec3], tail: f64) -> (DVec3, DVec3) {
    let mut low = DVec3::ZERO;
    let mut high = DVec3::ZERO;
    let mut coordinates: Vec<f64> = Vec::new();
    for axis in 0..3 {
        coordinates.clear();
        coordinates.extend(points.iter().filter(|x| x.is_finite()).map(|x| x[axis]));
        if coordinates.is_empty() {
            break;
        }
        let last = coordinates.len() - 1;
        let (from, to) = (
            (tail * last as f64) as usize,
            last - (tail * last as f64) as usize,
        );
        low[axis] = *coordinates.select_nth_unstable_by(from, f64::total_cmp).1;
        high[axis] = *coordinates.select_nth_unstable_by(to, f64::total_cmp).1;
    }
    (low, high)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_closest_point_agrees_with_a_fine_search_of_the_triangle() {
        let corners = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.2, 0.1),
            DVec3::new(0.3, 0.9, -0.2),
        ];
        for x in [
            DVec3::new(0.3, 0.3, 0.5),
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.8, 0.8, 0.1),
            DVec3::new(0.0, 2.0, 1.0),
            DVec3::new(0.5, -0.5, 0.0),
        ] {
            let (closest, weights) = closest_point_on_triangle(x, corners);
            let from_weights =
                weights[0] * corners[0] + weights[1] * corners[1] + weights[2] * corners[2];
            assert!((closest - from_weights).length() < 1e-12);
            // Sample the triangle on a 400-step barycentric lattice: none is closer.
            let n = 400;
            let mut best = f64::INFINITY;
            for i in 0..=n {
                for j in 0..=n - i {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let y =
                        corners[0] + u * (corners[1] - corners[0]) + v * (corners[2] - corners[0]);
                    best = best.min((x - y).length());
                }
            }
            let found = (x - closest).length();
            // The lattice is at most one cell diagonal (√2 · 1.1 / 400 m) from any point of the triangle.
            assert!(
                found <= best + 1e-12 && best - found <= 2.0 * 1.1 / n as f64,
                "{x}"
            );
        }
    }

    #[test]
    fn a_particle_that_crossed_a_triangle_goes_back_to_its_side() {
        let start = vec![
            DVec3::new(0.3, 0.3, 0.01),
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let mut now = start.clone();
        now[0].z = -0.002; // crossed during the sub-step
        keep_point_off_triangle([0, 1, 2, 3], 0.004, &[1.0, 0.0, 0.0, 0.0], &start, &mut now);
        assert!((now[0].z - 0.004).abs() < 1e-15, "{}", now[0]);
        // Free corners share the correction in proportion to their weights: momentum is kept.
        let mut now = start.clone();
        now[0].z = -0.002;
        keep_point_off_triangle([0, 1, 2, 3], 0.004, &[1.0; 4], &start, &mut now);
        let moved: DVec3 = now.iter().zip(&start).map(|(x, s)| *x - *s).sum();
        assert!((moved.z - (-0.012)).abs() < 1e-15, "{moved}");
        let height = now[0].z - (now[1].z + now[2].z + now[3].z) / 3.0;
        assert!(height > 0.0);
    }

    #[test]
    fn the_closest_points_of_two_segments_agree_with_a_fine_search() {
        let cases = [
            [
                DVec3::ZERO,
                DVec3::X,
                DVec3::new(0.5, 1.0, -1.0),
                DVec3::new(0.5, 1.0, 1.0),
            ],
            [
                DVec3::ZERO,
                DVec3::X,
                DVec3::new(2.0, 1.0, 0.0),
                DVec3::new(3.0, 2.0, 0.5),
            ],
            [
                DVec3::ZERO,
                DVec3::X,
                DVec3::new(0.2, 0.1, 0.0),
                DVec3::new(0.8, 0.1, 0.0),
            ],
            [
                DVec3::ZERO,
                DVec3::Y,
                DVec3::new(-0.5, 0.3, 0.2),
                DVec3::new(0.5, 0.9, -0.1),
            ],
        ];
        for [p1, q1, p2, q2] in cases {
            let (_, _, found) = closest_points_of_segments(p1, q1, p2, q2);
            let n = 1000;
            let mut best = f64::INFINITY;
            for i in 0..=n {
                let x = p1.lerp(q1, i as f64 / n as f64);
                for j in 0..=n {
                    best = best.min(x.distance(p2.lerp(q2, j as f64 / n as f64)));
                }
            }
            // The lattice points lie within half a step of the true closest points on each segment.
            let step = (q1 - p1).length().max((q2 - p2).length()) / n as f64;
            assert!(
                found <= best + 1e-12 && best - found <= step,
                "{found} {best}"
            );
        }
    }

    #[test]
    fn edges_that_passed_through_each_other_go_back() {
        // Edge 0–1 along x at z = 0.01, edge 2–3 along y at z = 0; during the sub-step the first moved
        // to z = −0.002, through the second.
        let start = vec![
            DVec3::new(-1.0, 0.0, 0.01),
            DVec3::new(1.0, 0.0, 0.01),
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let mut now = start.clone();
        now[0].z = -0.002;
        now[1].z = -0.002;
        keep_edges_apart([0, 1, 2, 3], 0.004, &[1.0, 1.0, 0.0, 0.0], &start, &mut now);
        assert!(
            (now[0].z - 0.004).abs() < 1e-15 && (now[1].z - 0.004).abs() < 1e-15,
            "{now:?}"
        );
    }

    #[test]
    fn a_collider_pushes_a_particle_out_and_friction_holds_it() {
        let ball = Collider::Sphere {
            center: DVec3::ZERO,
            radius: 1.0,
        };
        // Straight in: out to the gap, no sliding.
        let x = kept_off_collider(
            &ball,
            0.01,
            0.5,
            DVec3::new(0.0, 1.2, 0.0),
            DVec3::new(0.0, 0.9, 0.0),
        );
        assert!((x - DVec3::new(0.0, 1.01, 0.0)).length() < 1e-15);
        // A slide shorter than friction × depth stops; a long one is shortened by that much.
        let x = kept_off_collider(
            &ball,
            0.0,
            0.5,
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.01, 0.9, 0.0),
        );
        // Cancelled along the tangent at the pushed point: off the curved surface by second order.
        assert!((x - DVec3::new(0.0, 1.0, 0.0)).length() < 1e-4, "{x}");
        let plane = Collider::Plane {
            point: DVec3::ZERO,
            normal: DVec3::new(0.0, 2.0, 0.0),
        };
        let x = kept_off_collider(
            &plane,
            0.0,
            0.5,
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, -0.1, 0.0),
        );
        assert!((x - DVec3::new(0.95, 0.0, 0.0)).length() < 1e-15, "{x}");
        // Frictionless: the slide is kept.
        let x = kept_off_collider(&plane, 0.0, 0.0, DVec3::ZERO, DVec3::new(1.0, -0.1, 0.0));
        assert_eq!(x, DVec3::new(1.0, 0.0, 0.0));
    }

    /// The broad phase lists exactly the pairs a search of every pair finds, on a sheet folded onto
    /// itself with its layers within reach and a band pushed together, with `parallel` off and on.
    #[test]
    fn the_lists_hold_every_close_pair_a_search_of_all_pairs_finds() {
        let (columns, rows, spacing) = (24usize, 14usize, 0.01);
        let index = |i: usize, j: usize| (j * columns + i) as u32;
        let rest: Vec<DVec3> = (0..rows)
            .flat_map(|j| (0..columns).map(move |i| DVec3::new(i as f64, j as f64, 0.0) * spacing))
            .collect();
        let mut triangles = Vec::new();
        for j in 0..rows - 1 {
            for i in 0..columns - 1 {
                let [a, b, c, d] = [
                    index(i, j),
                    index(i + 1, j),
                    index(i, j + 1),
                    index(i + 1, j + 1),
                ];
                triangles.extend([[a, b, d], [a, d, c]]);
            }
        }
        // Folded at x = 12 cm, the upper layer 3 to 9 mm above the lower, with a ripple; the rows
        // past 10 pushed together to 60 % of their spacing.
        let now: Vec<DVec3> = rest
            .iter()
            .enumerate()
            .map(|(k, x)| {
                let wobble = 0.003 * ((k as f64) * 0.7).sin();
                let y = if x.y > 0.1 {
                    0.1 + 0.6 * (x.y - 0.1)
                } else {
                    x.y
                };
                if x.x > 0.12 {
                    DVec3::new(0.24 - x.x, y, 0.006 + wobble)
                } else {
                    DVec3::new(x.x, y, 0.3 * wobble)
                }
            })
            .collect();
        let (thickness, skin) = (0.004, 0.008);
        let reach = thickness + skin;
        let mut point_triangle = Vec::new();
        for (t, triangle) in triangles.iter().enumerate() {
            for p in 0..now.len() as u32 {
                let corners = triangle.map(|i| now[i as usize]);
                let rest_corners = triangle.map(|i| rest[i as usize]);
                let x = now[p as usize];
                let at_rest = rest[p as usize];
                if !triangle.contains(&p)
                    && (x - closest_point_on_triangle(x, corners).0).length() < reach
                    && (at_rest - closest_point_on_triangle(at_rest, rest_corners).0).length()
                        >= thickness
                {
                    point_triangle.push((p, t as u32));
                }
            }
        }
        let mut contacts = Contacts {
            now: now.clone(),
            ..Contacts::default()
        };
        contacts.list_pairs(thickness, skin, &rest, &triangles, false);
        let mut edge_edge = Vec::new();
        for (e, &[a, b]) in contacts.edges.iter().enumerate() {
            for (f, &[c, d]) in contacts.edges.iter().enumerate().skip(e + 1) {
                let at = |x: &[DVec3]| {
                    closest_points_of_segments(
                        x[a as usize],
                        x[b as usize],
                        x[c as usize],
                        x[d as usize],
                    )
                    .2
                };
                if ![c, d].contains(&a)
                    && ![c, d].contains(&b)
                    && at(&now) < reach
                    && at(&rest) >= thickness
                {
                    edge_edge.push((e as u32, f as u32));
                }
            }
        }
        assert!(
            point_triangle.len() > 500 && edge_edge.len() > 500,
            "the fold lists pairs"
        );
        for parallel in [false, true] {
            let mut contacts = Contacts {
                now: now.clone(),
                ..Contacts::default()
            };
            contacts.list_pairs(thickness, skin, &rest, &triangles, parallel);
            let mut listed = contacts.point_triangle.clone();
            // Listed triangle by triangle; sorted here by triangle to compare with the search.
            listed.sort_unstable_by_key(|&(p, t)| (t, p));
            assert_eq!(listed, point_triangle, "parallel {parallel}");
            assert_eq!(contacts.edge_edge, edge_edge, "parallel {parallel}");
        }
    }

    #[test]
    fn the_grid_finds_every_point_in_a_box_once_in_cell_order() {
        let mut positions: Vec<DVec3> = (0..500)
            .map(|i| {
                let f = i as f64;
                DVec3::new((f * 0.37).sin(), (f * 0.71).cos(), (f * 0.13).sin() * 0.5)
            })
            .collect();
        positions[7] = DVec3::new(f64::NAN, 0.0, 0.0); // binned apart, never found
        let mut far = positions.clone();
        far[3] = DVec3::new(100.0, -50.0, 80.0); // flung far: binned in the outermost cell
        let mut grid = CellGrid::default();
        // 1 µm cells would be 10¹⁸ of them: the grid takes larger ones and answers the same.
        for (positions, cell) in [(&positions, 0.2), (&positions, 1e-6), (&far, 0.2)] {
            grid.build(positions, cell);
            assert!(grid.cells() <= 4 * 500 + 64, "{cell}: {}", grid.cells());
            // The far point does not thin the grid: it keeps its cells.
            assert!(cell < 1e-3 || grid.cell == cell, "{}", grid.cell);
            assert!(
                (0..grid.cells() as u32)
                    .all(|c| grid.cell_number(grid.cell_coordinates_of(c)) == c)
            );
            let mut nothing = true;
            grid.for_each_in_box(DVec3::splat(f64::NEG_INFINITY), DVec3::ZERO, |_, _| {
                nothing = false
            });
            assert!(nothing, "a box that is not finite holds no point");
            for (low, high) in [
                (DVec3::new(-0.3, -0.2, -0.1), DVec3::new(0.4, 0.5, 0.2)),
                (DVec3::splat(-5.0), DVec3::splat(5.0)),
                (DVec3::splat(3.0), DVec3::splat(5.0)),
                (
                    DVec3::new(99.0, -51.0, 79.0),
                    DVec3::new(101.0, -49.0, 81.0),
                ),
            ] {
                let mut found = Vec::new();
                grid.for_each_in_box(low, high, |p, x| {
                    assert_eq!(
                        x.to_array().map(f64::to_bits),
                        positions[p as usize].to_array().map(f64::to_bits)
                    );
                    found.push(p)
                });
                let mut sorted = found.clone();
                sorted.sort_unstable();
                sorted.dedup();
                assert_eq!(sorted.len(), found.len(), "each point once");
                assert!(
                    !found.contains(&7),
                    "the point that is not finite is in no box"
                );
                let inside = (0..500u32).filter(|&i| {
                    let x = positions[i as usize];
                    x.cmpge(low).all() && x.cmple(high).all()
                });
                assert!(inside.into_iter().all(|i| sorted.binary_search(&i).is_ok()));
                // Cells in lexicographic order, each cell's points in index order.
                let keys: Vec<([usize; 3], u32)> = found
                    .iter()
                    .map(|&p| (grid.cell_coordinates(positions[p as usize]), p))
                    .collect();
                assert!(keys.windows(2).all(|w| w[0] < w[1]));
            }
        }
    }
}
