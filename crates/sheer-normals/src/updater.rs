//! The reusable per-frame vertex-normal updater: topology is analysed once, then every frame writes
//! unit normals turned toward the light in place, without allocating.
//!
//! Algorithm (one frame):
//! 1. validate the light and the positions (typed errors, nothing written on failure);
//! 2. face pass (parallel over triangles): one face normal per triangle into a preallocated buffer,
//!    computed from the triangle's vertices in ascending index order, so it is bit-for-bit the same
//!    for either winding, and given the canonical sign of [`canonical_sign`] (the μ0 = 0 tie-break);
//! 3. vertex pass (parallel over vertices): gather the incident face normals in a fixed order from a
//!    precomputed CSR adjacency, each one first turned toward the light *at that vertex*, then sum
//!    and normalise.
//!
//! No atomics and no scatter: every output element is a function of its own fixed-order gather, so
//! the result is identical whatever the rayon thread count or scheduling.

use glam::{DVec3, Vec3, Vec3A};
use rayon::prelude::*;

use crate::error::NormalsError;
use crate::light::{Light, MAX_COORDINATE, ValidLight};
use crate::vector::{canonical_sign, toward, unit_or_none};

/// How the incident faces of a vertex are weighted when their normals are summed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Weighting {
    /// Weight by triangle area: the face normal is the raw edge cross product (twice the area).
    /// Cheapest (no square root or trigonometry per face), about 4× faster than angle weighting;
    /// on a refined icosphere its error is about twice angle weighting's, with the same first-order
    /// convergence (README). The default.
    #[default]
    Area,
    /// Weight by the triangle's interior angle at the vertex (Thürmer & Wüthrich 1998): independent
    /// of how a planar fan around the vertex is split into triangles, at the cost of two `atan2`
    /// and one normalisation per triangle.
    Angle,
}

/// Whether the per-frame passes run on the rayon thread pool.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Execution {
    /// Everything on the calling thread.
    Serial,
    /// Faces and vertices in parallel on the current rayon pool once the mesh has at least
    /// [`PARALLEL_MIN_VERTICES`] vertices (below that, waking the pool costs more than it saves).
    /// Results are bit-for-bit those of [`Execution::Serial`].
    #[default]
    Parallel,
}

/// Options of a [`NormalUpdater`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NormalOptions {
    /// Face weighting; default [`Weighting::Area`].
    pub weighting: Weighting,
    /// Serial or rayon; default [`Execution::Parallel`].
    pub execution: Execution,
}

/// Meshes with fewer vertices than this run serially even under [`Execution::Parallel`].
pub const PARALLEL_MIN_VERTICES: usize = 8_192;

/// Smallest unit of parallel work (triangles or vertices per rayon task).
const PARALLEL_CHUNK: usize = 2_048;

/// A triangle counts as zero-area when the sine of its angle at its lowest-index vertex is at most
/// this, i.e. |e1 × e2| ≤ `DEGENERATE_SINE`·|e1|·|e2|.
///
/// Derivation: each edge component carries a rounding error of at most u = ε/2 of itself, and each
/// cross-product component is a difference of two rounded products, so an exactly collinear
/// triangle yields |e1 × e2| ≲ √3·3u·|e1||e2| ≈ 2.6ε·|e1||e2| of pure rounding noise. Twice that
/// keeps noise from posing as a normal (which angle weighting would otherwise weight by up to π).
const DEGENERATE_SINE: f64 = 6.0 * f32::EPSILON as f64;

/// Positions checked per branch-free block in validation.
const VALIDATION_CHUNK: usize = 256;

/// Largest supported vertex count: every vertex must be addressable by a `u32` index.
const MAX_VERTEX_COUNT: usize = (u32::MAX as usize).saturating_add(1);

/// Largest supported index-buffer length: corner ids `4·triangle + slot` are stored as `u32`.
const MAX_INDEX_COUNT: usize = 3 * (u32::MAX as usize / 4);

/// Precomputed topology plus preallocated scratch for per-frame vertex-normal updates.
///
/// Build once per mesh topology with [`NormalUpdater::new`]; call [`NormalUpdater::update`] every
/// frame with the moving positions. `update` allocates nothing.
#[derive(Debug, Clone)]
pub struct NormalUpdater {
    vertex_count: usize,
    /// Triangles with their three indices sorted ascending (winding is discarded on purpose: the
    /// orientation comes from the light, and sorted corners make face normals winding-invariant).
    triangles: Vec<[u32; 3]>,
    /// CSR offsets: the incident corners of vertex `v` are `incident_corners[offsets[v]..offsets[v+1]]`.
    incident_offsets: Vec<u32>,
    /// Corner ids `4·triangle + slot` (slot 0–2 in the sorted triangle), ascending per vertex; a
    /// power of two so the gather splits them with a shift and a mask.
    incident_corners: Vec<u32>,
    /// Per triangle: canonical-sign face normal (area weighting: unnormalised cross product; angle
    /// weighting: unit), or zero for a zero-area triangle. Rewritten every frame.
    face_normals: Vec<Vec3A>,
    /// Per corner: interior angle, radians (angle weighting only; empty otherwise).
    corner_angles: Vec<f32>,
    options: NormalOptions,
}

impl NormalUpdater {
    /// An updater with the default options (area weighting, rayon for large meshes).
    ///
    /// `indices` is a triangle list (three indices per triangle, any winding, any mix of windings).
    /// Errors: [`NormalsError::EmptyMesh`] for no triangle,
    /// [`NormalsError::IndexCountNotMultipleOfThree`], [`NormalsError::IndexOutOfRange`],
    /// [`NormalsError::TooManyIndices`], [`NormalsError::TooManyVertices`].
    pub fn new(vertex_count: usize, indices: &[u32]) -> Result<Self, NormalsError> {
        Self::with_options(vertex_count, indices, NormalOptions::default())
    }

    /// An updater with explicit options; errors as for [`NormalUpdater::new`].
    pub fn with_options(
        vertex_count: usize,
        indices: &[u32],
        options: NormalOptions,
    ) -> Result<Self, NormalsError> {
        if !indices.len().is_multiple_of(3) {
            return Err(NormalsError::IndexCountNotMultipleOfThree {
                index_count: indices.len(),
            });
        }
        if indices.is_empty() {
            return Err(NormalsError::EmptyMesh);
        }
        if vertex_count > MAX_VERTEX_COUNT {
            return Err(NormalsError::TooManyVertices {
                vertex_count,
                max: MAX_VERTEX_COUNT,
            });
        }
        if indices.len() > MAX_INDEX_COUNT {
            return Err(NormalsError::TooManyIndices {
                index_count: indices.len(),
                max: MAX_INDEX_COUNT,
            });
        }
        if let Some(slot) = indices.iter().position(|&i| i as usize >= vertex_count) {
            return Err(NormalsError::IndexOutOfRange {
                slot,
                index: indices[slot],
                vertex_count,
            });
        }

        let triangles: Vec<[u32; 3]> = indices
            .chunks_exact(3)
            .map(|t| {
                let mut sorted = [t[0], t[1], t[2]];
                sorted.sort_unstable();
                sorted
            })
            .collect();

        // CSR by counting sort: stable, so each vertex lists its corners in ascending corner id,
        // which fixes the summation order once and for all.
        let mut incident_offsets = vec![0u32; vertex_count + 1];
        for triangle in &triangles {
            for &vertex in triangle {
                incident_offsets[vertex as usize + 1] += 1;
            }
        }
        for v in 0..vertex_count {
            incident_offsets[v + 1] += incident_offsets[v];
        }
        let mut cursor: Vec<u32> = incident_offsets[..vertex_count].to_vec();
        let mut incident_corners = vec![0u32; indices.len()];
        for (face, triangle) in triangles.iter().enumerate() {
            for (slot, &vertex) in triangle.iter().enumerate() {
                let next = &mut cursor[vertex as usize];
                // Fits: 4·face + slot < 4/3·indices.len() ≤ u32::MAX (checked above).
                incident_corners[*next as usize] = (4 * face + slot) as u32;
                *next += 1;
            }
        }

        let corner_angles = match options.weighting {
            Weighting::Area => Vec::new(),
            Weighting::Angle => vec![0.0; indices.len()],
        };
        Ok(Self {
            vertex_count,
            face_normals: vec![Vec3A::ZERO; triangles.len()],
            triangles,
            incident_offsets,
            incident_corners,
            corner_angles,
            options,
        })
    }

    /// Number of vertices the mesh was built with (the required length of positions and normals).
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Number of triangles, degenerate ones included.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The options in force.
    pub fn options(&self) -> NormalOptions {
        self.options
    }

    /// Switches between serial and rayon execution (results are identical either way).
    pub fn set_execution(&mut self, execution: Execution) {
        self.options.execution = execution;
    }

    /// Writes into `normals[v]` the unit normal of vertex `v`, turned so that n · ω0′ ≥ 0 with ω0′
    /// the direction from `positions[v]` toward `light`.
    ///
    /// Each incident face normal is turned toward the light *at `v`* before it is summed: summing
    /// first would let inconsistently wound faces of a sheet cancel, and orienting at the vertex
    /// (not at the face) makes every summand, hence the sum, satisfy the rule at `v` even for a
    /// point light close to the surface.
    ///
    /// Defined special cases:
    /// - μ0 = 0: a face exactly perpendicular to the light at a vertex, or within the rounding
    ///   error of the dot product of it (|n · ω0′| ≤ 4ε·Σ|n_i||ω_i|), keeps its canonical sign
    ///   (first non-zero component positive), so an edge-on flat sheet gets one consistent normal
    ///   instead of faces flipped at random by rounding. The same tolerance applies to the final
    ///   vertex normal: n · ω0′ ≥ −4ε·Σ|n_i||ω_i|, and ≥ 0 whenever the sign is resolvable;
    /// - zero-area triangles contribute nothing;
    /// - a vertex with no non-degenerate incident triangle (isolated, or on collapsed geometry) gets
    ///   the unit vector toward the light, or +Z if a point light sits exactly on it.
    ///
    /// Errors (checked before anything is written): [`NormalsError::LengthMismatch`],
    /// [`NormalsError::NonFinitePosition`], [`NormalsError::PositionOutOfRange`] and the light
    /// errors of [`Light`]. Allocation-free; in parallel mode called from outside a rayon pool,
    /// rayon's own injector queue allocates one block per 63 calls (see `tests/allocation.rs`).
    pub fn update(
        &mut self,
        positions: &[Vec3],
        light: &Light,
        normals: &mut [Vec3],
    ) -> Result<(), NormalsError> {
        check_length("positions", self.vertex_count, positions.len())?;
        check_length("normals", self.vertex_count, normals.len())?;
        let light = light.validate()?;
        let parallel = self.options.execution == Execution::Parallel
            && self.vertex_count >= PARALLEL_MIN_VERTICES;
        if parallel {
            // Enter the pool once per frame, not once per pass: every entry from a thread outside
            // the pool goes through rayon's injector queue, which allocates a block per 63 entries.
            // Inside `scope` the passes run on a worker and split through its local deque.
            rayon::scope(|_| self.run_passes(positions, light, normals, true))
        } else {
            self.run_passes(positions, light, normals, false)
        }
    }

    /// Validation of the positions, then the face and vertex passes (see the module docs).
    fn run_passes(
        &mut self,
        positions: &[Vec3],
        light: ValidLight,
        normals: &mut [Vec3],
        parallel: bool,
    ) -> Result<(), NormalsError> {
        validate_positions(positions, parallel)?;
        let Self {
            triangles,
            incident_offsets,
            incident_corners,
            face_normals,
            corner_angles,
            options,
            ..
        } = self;
        let incident_offsets: &[u32] = incident_offsets;
        let incident_corners: &[u32] = incident_corners;
        match options.weighting {
            Weighting::Area => {
                face_pass_area(positions, triangles, face_normals, parallel);
                let face_normals: &[Vec3A] = face_normals;
                vertex_pass(positions, light, normals, parallel, |v, to_light| {
                    let corners = incident_range(incident_offsets, incident_corners, v);
                    corners.iter().fold(Vec3A::ZERO, |sum, &corner| {
                        sum + toward(face_normals[(corner >> 2) as usize], to_light)
                    })
                });
            }
            Weighting::Angle => {
                face_pass_angle(positions, triangles, face_normals, corner_angles, parallel);
                let face_normals: &[Vec3A] = face_normals;
                let corner_angles: &[f32] = corner_angles;
                vertex_pass(positions, light, normals, parallel, |v, to_light| {
                    let corners = incident_range(incident_offsets, incident_corners, v);
                    corners.iter().fold(Vec3A::ZERO, |sum, &corner| {
                        let face = (corner >> 2) as usize;
                        let angle = corner_angles[3 * face + (corner & 3) as usize];
                        sum + toward(face_normals[face], to_light) * angle
                    })
                });
            }
        }
        Ok(())
    }
}

/// Unit vertex normals turned toward `light`, for a one-off computation (allocates an updater and
/// the output; use [`NormalUpdater`] per frame). `positions.len()` is the vertex count.
pub fn vertex_normals_toward_light(
    positions: &[Vec3],
    indices: &[u32],
    light: &Light,
) -> Result<Vec<Vec3>, NormalsError> {
    let mut updater = NormalUpdater::new(positions.len(), indices)?;
    let mut normals = vec![Vec3::ZERO; positions.len()];
    updater.update(positions, light, &mut normals)?;
    Ok(normals)
}

fn check_length(what: &'static str, expected: usize, actual: usize) -> Result<(), NormalsError> {
    if expected == actual {
        Ok(())
    } else {
        Err(NormalsError::LengthMismatch {
            what,
            expected,
            actual,
        })
    }
}

/// The first vertex (lowest index, whatever the thread count) that is non-finite or beyond
/// ±[`MAX_COORDINATE`] becomes the error.
fn validate_positions(positions: &[Vec3], parallel: bool) -> Result<(), NormalsError> {
    // Component-wise and branch-free so the scan vectorises; NaN fails every comparison.
    let in_range = |p: &Vec3| {
        (p.x.abs() <= MAX_COORDINATE)
            & (p.y.abs() <= MAX_COORDINATE)
            & (p.z.abs() <= MAX_COORDINATE)
    };
    let chunk_in_range = |chunk: &[Vec3]| chunk.iter().fold(true, |all, p| all & in_range(p));
    let all_in_range = if parallel {
        positions
            .par_chunks(VALIDATION_CHUNK)
            .with_min_len(PARALLEL_CHUNK / VALIDATION_CHUNK)
            .all(chunk_in_range)
    } else {
        positions.chunks(VALIDATION_CHUNK).all(chunk_in_range)
    };
    if all_in_range {
        return Ok(());
    }
    // Rare path: report the lowest offending vertex, whatever the thread count.
    let vertex = positions.iter().position(|p| !in_range(p)).unwrap_or(0);
    if positions[vertex].is_finite() {
        Err(NormalsError::PositionOutOfRange {
            vertex,
            limit: MAX_COORDINATE,
        })
    } else {
        Err(NormalsError::NonFinitePosition { vertex })
    }
}

#[inline]
fn incident_range<'a>(offsets: &[u32], corners: &'a [u32], vertex: usize) -> &'a [u32] {
    &corners[offsets[vertex] as usize..offsets[vertex + 1] as usize]
}

/// True when |e1 × e2| is indistinguishable from rounding noise (see [`DEGENERATE_SINE`]).
#[inline(always)]
fn is_zero_area(cross: Vec3A, e1: Vec3A, e2: Vec3A) -> bool {
    let e1_squared = e1.length_squared();
    let e2_squared = e2.length_squared();
    // Fast path for edges between 2⁻²⁰ and 2²⁰ m (10⁻⁶ to 10⁶ m): then the bound
    // (6ε)²·|e1|²·|e2|² ≥ 5·10⁻¹³·2⁻⁸⁰ stays a normal f32 and |e1|²|e2|² ≤ 2⁸⁰ cannot overflow.
    let edge_range = EDGE_SQUARED_MIN..=EDGE_SQUARED_MAX;
    if edge_range.contains(&e1_squared) && edge_range.contains(&e2_squared) {
        let sine_squared = (DEGENERATE_SINE * DEGENERATE_SINE) as f32;
        return cross.length_squared() <= sine_squared * e1_squared * e2_squared;
    }
    // Elsewhere in f64, where squares of any f32 magnitude neither overflow nor underflow.
    let cross_squared = cross.as_dvec3().length_squared();
    let bound = DEGENERATE_SINE
        * DEGENERATE_SINE
        * e1.as_dvec3().length_squared()
        * e2.as_dvec3().length_squared();
    cross_squared <= bound
}

/// 2⁻⁴⁰: smallest squared edge length, m², of the f32 fast path of [`is_zero_area`].
const EDGE_SQUARED_MIN: f32 = 9.094_947e-13;
/// 2⁴⁰: largest squared edge length, m², of the f32 fast path of [`is_zero_area`].
const EDGE_SQUARED_MAX: f32 = 1.099_511_6e12;

/// Area-weighted face normal: (p_b − p_a) × (p_c − p_a) with a ≤ b ≤ c the sorted indices, in
/// canonical sign; zero for a zero-area triangle. Its length is twice the triangle's area, m².
#[inline(always)]
fn area_face_normal(positions: &[Vec3], [a, b, c]: [u32; 3]) -> Vec3A {
    let p_a = Vec3A::from(positions[a as usize]);
    let edge_ab = Vec3A::from(positions[b as usize]) - p_a;
    let edge_ac = Vec3A::from(positions[c as usize]) - p_a;
    let cross = edge_ab.cross(edge_ac);
    if is_zero_area(cross, edge_ab, edge_ac) {
        Vec3A::ZERO
    } else {
        canonical_sign(cross)
    }
}

/// Interior angle between edge vectors `u` and `v`, radians: atan2(|u × v|, u · v), accurate at
/// every angle (unlike acos of a normalised dot).
///
/// In f32 when both edges are in the fast-path range of [`is_zero_area`] (|e|² ∈ [2⁻⁴⁰, 2⁴⁰] m²,
/// so |u × v|² ≤ 2⁸⁰ cannot overflow, and a non-degenerate triangle's |u × v|² ≥ (6ε)²·2⁻⁸⁰ stays a
/// normal f32); in f64 otherwise, where magnitudes up to 2³³ cannot overflow.
#[inline]
fn corner_angle(u: Vec3A, v: Vec3A) -> f32 {
    let edge_range = EDGE_SQUARED_MIN..=EDGE_SQUARED_MAX;
    if edge_range.contains(&u.length_squared()) && edge_range.contains(&v.length_squared()) {
        return u.cross(v).length().atan2(u.dot(v));
    }
    let (u, v): (DVec3, DVec3) = (u.as_dvec3(), v.as_dvec3());
    u.cross(v).length().atan2(u.dot(v)) as f32
}

/// Angle weighting: unit face normal in canonical sign plus the three interior angles (sorted slot
/// order); zero normal and angles for a zero-area triangle.
#[inline(always)]
fn angle_face(positions: &[Vec3], [a, b, c]: [u32; 3]) -> (Vec3A, [f32; 3]) {
    let p_a = Vec3A::from(positions[a as usize]);
    let p_b = Vec3A::from(positions[b as usize]);
    let p_c = Vec3A::from(positions[c as usize]);
    let edge_ab = p_b - p_a;
    let edge_ac = p_c - p_a;
    let edge_bc = p_c - p_b;
    let cross = edge_ab.cross(edge_ac);
    if is_zero_area(cross, edge_ab, edge_ac) {
        return (Vec3A::ZERO, [0.0; 3]);
    }
    // Not zero-area, hence non-zero and finite: unit_or_none succeeds.
    let unit = unit_or_none(cross).unwrap_or(Vec3A::ZERO);
    // The third angle from the angle sum π: one atan2 fewer (they dominate this pass), at an
    // absolute error of a few ε·π ≈ 10⁻⁶ rad, negligible against a vertex's total angle; `max`
    // only stops that rounding from making a vanishing angle a hair negative.
    let angle_a = corner_angle(edge_ab, edge_ac);
    let angle_b = corner_angle(-edge_ab, edge_bc);
    let angle_c = (std::f32::consts::PI - angle_a - angle_b).max(0.0);
    let angles = [angle_a, angle_b, angle_c];
    (canonical_sign(unit), angles)
}

fn face_pass_area(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    face_normals: &mut [Vec3A],
    parallel: bool,
) {
    if parallel {
        face_normals
            .par_iter_mut()
            .zip(triangles.par_iter())
            .with_min_len(PARALLEL_CHUNK)
            .for_each(|(normal, &triangle)| *normal = area_face_normal(positions, triangle));
    } else {
        for (normal, &triangle) in face_normals.iter_mut().zip(triangles) {
            *normal = area_face_normal(positions, triangle);
        }
    }
}

fn face_pass_angle(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    face_normals: &mut [Vec3A],
    corner_angles: &mut [f32],
    parallel: bool,
) {
    let write = |((normal, angles), &triangle): ((&mut Vec3A, &mut [f32]), &[u32; 3])| {
        let (face_normal, face_angles) = angle_face(positions, triangle);
        *normal = face_normal;
        angles.copy_from_slice(&face_angles);
    };
    if parallel {
        face_normals
            .par_iter_mut()
            .zip(corner_angles.par_chunks_mut(3))
            .zip(triangles.par_iter())
            .with_min_len(PARALLEL_CHUNK)
            .for_each(write);
    } else {
        face_normals
            .iter_mut()
            .zip(corner_angles.chunks_mut(3))
            .zip(triangles)
            .for_each(write);
    }
}

/// Per vertex: `oriented_sum(v, to_light)` is the sum of the incident face normals, each already
/// turned toward the light at `v`; it is normalised here with the documented fallbacks.
fn vertex_pass<F>(
    positions: &[Vec3],
    light: ValidLight,
    normals: &mut [Vec3],
    parallel: bool,
    oriented_sum: F,
) where
    F: Fn(usize, Vec3A) -> Vec3A + Sync,
{
    let vertex_normal = |vertex: usize| vertex_normal(positions, light, &oriented_sum, vertex);
    if parallel {
        normals
            .par_iter_mut()
            .enumerate()
            .with_min_len(PARALLEL_CHUNK)
            .for_each(|(vertex, normal)| *normal = vertex_normal(vertex));
    } else {
        for (vertex, normal) in normals.iter_mut().enumerate() {
            *normal = vertex_normal(vertex);
        }
    }
}

/// The finished unit normal of one vertex (see [`vertex_pass`]); forced inline so that the
/// serial and parallel loops each get the whole per-vertex body to schedule.
#[inline(always)]
fn vertex_normal<F>(positions: &[Vec3], light: ValidLight, oriented_sum: &F, vertex: usize) -> Vec3
where
    F: Fn(usize, Vec3A) -> Vec3A,
{
    let to_light = light.to_light_from(positions[vertex].into());
    Vec3::from(finish_vertex_normal(
        oriented_sum(vertex, to_light),
        to_light,
    ))
}

/// Normalises the oriented sum. Every summand had n · ω0′ ≥ 0 (up to the documented tie
/// tolerance), so the sum does too; the final `toward` makes it hold for the rounded result as
/// well. A zero sum (no non-degenerate incident face; oriented summands cannot cancel) falls back
/// to the direction toward the light, and to +Z when that is undefined too (a point light exactly
/// on the vertex).
#[inline(always)]
fn finish_vertex_normal(sum: Vec3A, to_light: Vec3A) -> Vec3A {
    match unit_or_none(sum) {
        Some(normal) => toward(normal, to_light),
        None => unit_or_none(to_light).unwrap_or(Vec3A::Z),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_path_bounds_are_the_stated_powers_of_two() {
        assert_eq!(EDGE_SQUARED_MIN, 2f32.powi(-40));
        assert_eq!(EDGE_SQUARED_MAX, 2f32.powi(40));
    }

    #[test]
    fn zero_area_test_agrees_between_its_f32_and_f64_paths() {
        // A right triangle and a sliver well above the threshold, and a collinear one, at a scale
        // inside the fast path (1 m) and outside it (10⁸ m, 10⁻⁸ m): same verdict, since the
        // criterion is scale-invariant.
        for scale in [1.0f32, 1e8, 1e-8] {
            let e1 = Vec3A::new(1.0, 0.0, 0.0) * scale;
            for (e2, degenerate) in [
                (Vec3A::new(0.0, 1.0, 0.0), false),
                (Vec3A::new(1.0, 1e-4, 0.0), false),
                (Vec3A::new(2.0, 0.0, 0.0), true),
            ] {
                let e2 = e2 * scale;
                assert_eq!(
                    is_zero_area(e1.cross(e2), e1, e2),
                    degenerate,
                    "scale {scale}"
                );
            }
        }
    }
}
