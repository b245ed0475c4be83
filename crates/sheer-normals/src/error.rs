//! Typed errors of the crate: every bad input is reported here, never as a panic or a NaN.

use thiserror::Error;

/// Everything that can be wrong with a mesh, a light or a per-frame input.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum NormalsError {
    /// The index buffer holds no triangle, so there is no surface to compute normals of.
    #[error("empty mesh: the index buffer holds no triangle")]
    EmptyMesh,
    /// The index buffer length is not a whole number of triangles.
    #[error("index count {index_count} is not a multiple of 3")]
    IndexCountNotMultipleOfThree {
        /// Length of the offending index buffer.
        index_count: usize,
    },
    /// An index refers past the end of the vertex array.
    #[error(
        "index {index} at index-buffer slot {slot} is out of range for {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// Position of the offending entry in the index buffer.
        slot: usize,
        /// The offending vertex index.
        index: u32,
        /// Number of vertices the mesh was declared with.
        vertex_count: usize,
    },
    /// The index buffer is longer than the `u32` adjacency can address.
    #[error("index count {index_count} exceeds the supported maximum of {max}")]
    TooManyIndices {
        /// Length of the offending index buffer.
        index_count: usize,
        /// Largest supported index count.
        max: usize,
    },
    /// More vertices than `u32` indices can address.
    #[error("vertex count {vertex_count} exceeds the supported maximum of {max}")]
    TooManyVertices {
        /// The requested vertex count.
        vertex_count: usize,
        /// Largest supported vertex count (2³²).
        max: usize,
    },
    /// A slice handed to a per-frame call has the wrong length.
    #[error("{what} has {actual} elements, expected {expected}")]
    LengthMismatch {
        /// Which slice (`"positions"` or `"normals"`).
        what: &'static str,
        /// Length the mesh requires (its vertex count).
        expected: usize,
        /// Length that was passed.
        actual: usize,
    },
    /// A vertex position has a NaN or infinite coordinate.
    #[error("position of vertex {vertex} is not finite")]
    NonFinitePosition {
        /// The offending vertex.
        vertex: usize,
    },
    /// A vertex position is finite but so large that cross products of edges would overflow `f32`.
    #[error("position of vertex {vertex} has a coordinate beyond ±{limit} m")]
    PositionOutOfRange {
        /// The offending vertex.
        vertex: usize,
        /// The supported bound on |coordinate|, metres ([`crate::MAX_COORDINATE`]).
        limit: f32,
    },
    /// The light's position or direction has a NaN or infinite component.
    #[error("light is not finite")]
    NonFiniteLight,
    /// A point light's position is beyond the supported coordinate range.
    #[error("point light has a coordinate beyond ±{limit} m")]
    LightOutOfRange {
        /// The supported bound on |coordinate|, metres ([`crate::MAX_COORDINATE`]).
        limit: f32,
    },
    /// A directional light's direction is the zero vector, so it points nowhere.
    #[error("directional light has a zero direction")]
    ZeroLightDirection,
    /// A vector handed to [`crate::lit_side_cosines`] has a NaN or infinite component.
    #[error("{what} is not finite")]
    NonFiniteVector {
        /// Which argument (`"normal"`, `"to_light"` or `"to_eye"`).
        what: &'static str,
    },
}
