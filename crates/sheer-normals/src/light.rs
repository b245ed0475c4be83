//! The light that decides which side of the surface is "lit": a point light or a directional light.

use glam::{Vec3, Vec3A};

use crate::error::NormalsError;
use crate::vector::unit_or_none;

/// Largest supported |coordinate| of a vertex or point-light position, metres (2³² ≈ 4.3·10⁹ m).
///
/// Why a bound: edge vectors are then at most 2³³ per component, their cross product at most
/// 2⁶⁷, and its dot product with a light vector at most 3·2¹⁰⁰, all far below `f32::MAX` ≈ 2¹²⁸.
/// Larger finite coordinates could overflow to infinity and poison a normal with NaN, so they are
/// rejected with a typed error instead.
pub const MAX_COORDINATE: f32 = 4_294_967_296.0;

/// The light source whose side of the surface every normal is turned toward.
///
/// In the notation of Frisvad, Christensen & Falster (2005), the direction from a surface point
/// toward this light is ω0′ and μ0 = ω0′ · n (eq. 4–6); the normals this crate produces satisfy
/// μ0 ≥ 0 ("always turned outwards such that μ0 = cos θ0 > 0", §4 of the paper).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    /// An isotropic point light at `position` (world space, metres). ω0′ at a surface point `x` is
    /// the direction of `position − x`.
    Point {
        /// World-space position of the light, metres.
        position: Vec3,
    },
    /// A light at infinity. `direction_to_light` points FROM the scene TOWARD the light (it is ω0′
    /// itself, the opposite of the direction the light travels), e.g. `Vec3::Z` for a sun overhead.
    /// Any non-zero length is accepted; only the direction is used.
    Directional {
        /// Direction from the surface toward the light; need not be unit length, must not be zero.
        direction_to_light: Vec3,
    },
}

/// A light after validation, in the form the per-vertex loop uses.
#[derive(Debug, Clone, Copy)]
pub(crate) enum ValidLight {
    /// Point light at this position.
    Point(Vec3A),
    /// Unit direction toward a light at infinity.
    Directional(Vec3A),
}

impl ValidLight {
    /// The (unnormalised) vector from `position` toward the light: only its direction is used, and
    /// leaving it unnormalised keeps the per-vertex orientation test free of a square root.
    #[inline]
    pub(crate) fn to_light_from(self, position: Vec3A) -> Vec3A {
        match self {
            ValidLight::Point(light) => light - position,
            ValidLight::Directional(direction) => direction,
        }
    }
}

impl Light {
    /// The unit direction ω0′ from `position` toward the light, or `None` where it is undefined
    /// (a point light exactly at `position`). Errors: [`NormalsError::NonFiniteLight`],
    /// [`NormalsError::LightOutOfRange`], [`NormalsError::ZeroLightDirection`].
    pub fn direction_from(&self, position: Vec3) -> Result<Option<Vec3>, NormalsError> {
        Ok(unit_or_none(self.validate()?.to_light_from(position.into())).map(Vec3::from))
    }

    /// Checks the light: finite, a point light within ±[`MAX_COORDINATE`], a directional light with
    /// a non-zero direction (which is normalised here).
    pub(crate) fn validate(&self) -> Result<ValidLight, NormalsError> {
        match *self {
            Light::Point { position } => {
                if !position.is_finite() {
                    return Err(NormalsError::NonFiniteLight);
                }
                if position.abs().max_element() > MAX_COORDINATE {
                    return Err(NormalsError::LightOutOfRange {
                        limit: MAX_COORDINATE,
                    });
                }
                Ok(ValidLight::Point(position.into()))
            }
            Light::Directional { direction_to_light } => {
                if !direction_to_light.is_finite() {
                    return Err(NormalsError::NonFiniteLight);
                }
                unit_or_none(direction_to_light.into())
                    .map(ValidLight::Directional)
                    .ok_or(NormalsError::ZeroLightDirection)
            }
        }
    }
}
