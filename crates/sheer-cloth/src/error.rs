//! Typed errors: bad models, bad parameters, bad time steps and diverged steps.

use thiserror::Error;

/// A cloth model that cannot be simulated.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    #[error("a grid needs at least 2×2 particles, got {columns}×{rows}")]
    GridTooSmall { columns: usize, rows: usize },
    #[error(
        "a grid of {columns}×{rows} particles is too large: particles are indexed by u32 (at most {} of them)",
        u32::MAX
    )]
    GridTooLarge { columns: usize, rows: usize },
    #[error("{name} must be finite and > 0, got {value:?}")]
    InvalidDimension { name: &'static str, value: f64 },
    #[error("areal density must be finite and > 0 kg/m², got {0:?}")]
    InvalidDensity(f64),
    #[error("the mesh has no triangles")]
    EmptyMesh,
    #[error("the index list has {0} entries, not a multiple of 3")]
    IndexCountNotMultipleOf3(usize),
    #[error(
        "triangle {triangle} refers to vertex {index}, but there are only {vertex_count} vertices"
    )]
    IndexOutOfRange {
        triangle: usize,
        index: u32,
        vertex_count: usize,
    },
    #[error("triangle {triangle} is degenerate at rest (area {area:e} m²)")]
    DegenerateTriangle { triangle: usize, area: f64 },
    #[error("vertex {0} has a non-finite position")]
    NonFinitePosition(usize),
    #[error("particle {0} belongs to no triangle and so has no mass")]
    MasslessParticle(usize),
    #[error("pin index {index} is out of range (the cloth has {particle_count} particles)")]
    PinOutOfRange { index: usize, particle_count: usize },
    #[error(
        "spring {spring} joins particle {index}, but there are only {particle_count} particles"
    )]
    SpringOutOfRange {
        spring: usize,
        index: u32,
        particle_count: usize,
    },
    #[error("spring {0} joins a particle to itself or has zero rest length")]
    DegenerateSpring(usize),
    #[error("particle {index} has an invalid mass {mass:?} kg (must be finite and > 0)")]
    InvalidMass { index: usize, mass: f64 },
    #[error("this operation needs a grid cloth, but the cloth was built from a mesh")]
    NotAGrid,
    #[error("{field} has {len} entries, but the cloth has {particle_count} particles")]
    LengthMismatch {
        field: &'static str,
        len: usize,
        particle_count: usize,
    },
    #[error("the pins' transform is not finite")]
    NonFinitePinTransform,
    #[error("a {columns}×{rows} grid does not fit a cloth of {particle_count} particles")]
    GridShapeMismatch {
        columns: usize,
        rows: usize,
        particle_count: usize,
    },
}

/// A parameter outside its valid range; `name` is the field path as written in a scene file.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("parameter `{name}` = {}: {reason}", shortest(*value))]
pub struct ParamError {
    pub name: &'static str,
    pub value: f64,
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
    #[error("particle {particle} has a non-finite position or velocity")]
    NonFinite { particle: usize },
    #[error("particle {particle} moves at {speed:.3e} m/s, above the limit {limit} m/s")]
    Speed {
        particle: usize,
        speed: f64,
        limit: f64,
    },
    #[error("spring {spring} has strain {strain:.3e}, above the limit {limit}")]
    Strain {
        spring: usize,
        strain: f64,
        limit: f64,
    },
}

/// A step that did not happen. The simulation keeps its last good state.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum StepError {
    #[error("time step must be finite and > 0 s, got {0}")]
    InvalidTimeStep(f64),
    #[error("step {step} diverged: {reason}; the last good state was kept")]
    Diverged { step: u64, reason: DivergenceReason },
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
