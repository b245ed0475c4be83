//! Typed errors: bad models, bad parameters, bad time steps and diverged steps.

use thiserror::Error;

/// A cloth model that cannot be simulated.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    /// A grid with fewer than two particles along a side: it has no triangles.
    #[error("a grid needs at least 2×2 particles, got {columns}×{rows}")]
    GridTooSmall {
        /// Particles per row, as requested.
        columns: usize,
        /// Particles per column, as requested.
        rows: usize,
    },
    /// A grid with more particles than a `u32` index can number.
    #[error(
        "a grid of {columns}×{rows} particles is too large: particles are indexed by u32 (at most {} of them)",
        u32::MAX
    )]
    GridTooLarge {
        /// Particles per row, as requested.
        columns: usize,
        /// Particles per column, as requested.
        rows: usize,
    },
    /// A grid's width or height (m) that is not finite and > 0, or an origin coordinate that is not finite.
    #[error("{name} must be finite and > 0, got {value:?}")]
    InvalidDimension {
        /// The offending field of [`GridSpec`](crate::GridSpec): `"width"`, `"height"` or `"origin.x"` …
        name: &'static str,
        /// The value given, m.
        value: f64,
    },
    /// An areal density (kg/m²) that is zero, negative or not finite.
    #[error("areal density must be finite and > 0 kg/m², got {0:?}")]
    InvalidDensity(f64),
    /// A mesh given with no triangles at all.
    #[error("the mesh has no triangles")]
    EmptyMesh,
    /// A triangle index list whose length (the payload) is not a multiple of three.
    #[error("the index list has {0} entries, not a multiple of 3")]
    IndexCountNotMultipleOf3(usize),
    /// A triangle that names a vertex past the end of the vertex list.
    #[error(
        "triangle {triangle} refers to vertex {index}, but there are only {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// Index of the offending triangle in the index list (its entries `3·triangle..3·triangle + 3`).
        triangle: usize,
        /// The out-of-range vertex index it holds.
        index: u32,
        /// How many vertices the mesh has.
        vertex_count: usize,
    },
    /// A triangle that repeats a vertex or is (almost) flat at rest: area ≤ 10⁻⁹ × its longest side squared.
    #[error("triangle {triangle} is degenerate at rest (area {area:e} m²)")]
    DegenerateTriangle {
        /// Index of the triangle.
        triangle: usize,
        /// Its rest area, m².
        area: f64,
    },
    /// A position, velocity or pin target with a NaN or infinite coordinate (the payload: the particle's index).
    #[error("vertex {0} has a non-finite position")]
    NonFinitePosition(usize),
    /// A particle (the payload: its index) that no triangle uses, so it gets no share of any mass.
    #[error("particle {0} belongs to no triangle and so has no mass")]
    MasslessParticle(usize),
    /// A pin that names a particle past the end of the cloth, or a pin target for an unpinned particle.
    #[error("pin index {index} is out of range (the cloth has {particle_count} particles)")]
    PinOutOfRange {
        /// The particle index the pin names.
        index: usize,
        /// How many particles the cloth has.
        particle_count: usize,
    },
    /// A spring that names a particle past the end of the cloth.
    #[error(
        "spring {spring} joins particle {index}, but there are only {particle_count} particles"
    )]
    SpringOutOfRange {
        /// Index of the offending spring.
        spring: usize,
        /// The out-of-range particle index it names.
        index: u32,
        /// How many particles the cloth has.
        particle_count: usize,
    },
    /// A spring (the payload: its index) with both ends on one particle, or with zero rest length.
    #[error("spring {0} joins a particle to itself or has zero rest length")]
    DegenerateSpring(usize),
    /// A particle mass (kg) that is zero, negative or not finite.
    #[error("particle {index} has an invalid mass {mass:?} kg (must be finite and > 0)")]
    InvalidMass {
        /// Index of the particle.
        index: usize,
        /// The mass given, kg.
        mass: f64,
    },
    /// A grid-only operation (e.g. pinning the hoist) asked of a cloth built from a general mesh.
    #[error("this operation needs a grid cloth, but the cloth was built from a mesh")]
    NotAGrid,
    /// A per-particle array whose length differs from the cloth's particle count.
    #[error("{field} has {len} entries, but the cloth has {particle_count} particles")]
    LengthMismatch {
        /// Which array, e.g. `"velocities"`.
        field: &'static str,
        /// Its length.
        len: usize,
        /// How many particles the cloth has.
        particle_count: usize,
    },
    /// A rigid transform for the pins with a NaN or infinite entry.
    #[error("the pins' transform is not finite")]
    NonFinitePinTransform,
    /// A grid shape whose `columns × rows` is not the cloth's particle count.
    #[error("a {columns}×{rows} grid does not fit a cloth of {particle_count} particles")]
    GridShapeMismatch {
        /// Particles per row.
        columns: usize,
        /// Particles per column.
        rows: usize,
        /// How many particles the cloth has.
        particle_count: usize,
    },
}

/// A parameter outside its valid range; `name` is the field path as written in a scene file.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("parameter `{name}` = {}: {reason}", shortest(*value))]
pub struct ParamError {
    /// The parameter's path in a scene file, e.g. `"wind.air_density"`.
    pub name: &'static str,
    /// The value given, in the parameter's own unit (SI).
    pub value: f64,
    /// What the value must be instead, e.g. `"must be finite and > 0"`.
    pub reason: &'static str,
}

impl ParamError {
    pub(crate) fn new(name: &'static str, value: f64, reason: &'static str) -> Self {
        ParamError {
            name,
            value,
            reason,
        }
    }
}

/// Why a step was judged diverged.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DivergenceReason {
    /// A particle's position or velocity became NaN or infinite.
    #[error("particle {particle} has a non-finite position or velocity")]
    NonFinite {
        /// Index of the lowest-numbered such particle.
        particle: usize,
    },
    /// A particle moved faster than [`DivergenceLimits`](crate::DivergenceLimits) allow.
    #[error("particle {particle} moves at {speed:.3e} m/s, above the limit {limit} m/s")]
    Speed {
        /// Index of the particle.
        particle: usize,
        /// Its speed, m/s.
        speed: f64,
        /// The largest speed allowed, m/s.
        limit: f64,
    },
    /// A spring stretched beyond what [`DivergenceLimits`](crate::DivergenceLimits) allow.
    #[error("spring {spring} has strain {strain:.3e}, above the limit {limit}")]
    Strain {
        /// Index of the spring.
        spring: usize,
        /// Its strain `length / rest length − 1` (dimensionless).
        strain: f64,
        /// The largest strain allowed (dimensionless).
        limit: f64,
    },
}

/// A step that did not happen. The simulation keeps its last good state.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum StepError {
    /// A time step (s, the payload) that is zero, negative or not finite.
    #[error("time step must be finite and > 0 s, got {0}")]
    InvalidTimeStep(f64),
    /// The step produced a state that failed the divergence checks; the state before it was kept.
    #[error("step {step} diverged: {reason}; the last good state was kept")]
    Diverged {
        /// How many steps had succeeded before this one (since the simulation began or was reset).
        step: u64,
        /// Which check failed, and where.
        reason: DivergenceReason,
    },
}

/// `value` as a person reads it: `7` and `0.25` as written, `1e308` and `1e-300` with an exponent (plain
/// `Display` writes those with hundreds of digits).
fn shortest(value: f64) -> String {
    if value == 0.0 || (1e-4..1e16).contains(&value.abs()) || !value.is_finite() {
        format!("{value}")
    } else {
        format!("{value:e}")
    }
}
