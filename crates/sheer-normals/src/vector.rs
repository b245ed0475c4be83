//! Small scale-robust vector helpers shared by the vertex-normal update and the per-fragment rule.

use glam::Vec3A;

/// Squared lengths in [2⁻¹⁰⁰, 2¹⁰⁰] normalise directly: far from f32's range limits (2^±126).
const SAFE_LENGTH_SQUARED_MIN: f32 = 7.888_609e-31;
/// See [`SAFE_LENGTH_SQUARED_MIN`].
const SAFE_LENGTH_SQUARED_MAX: f32 = 1.267_650_6e30;

/// The unit vector along `v`, or `None` when `v` is zero or not finite.
///
/// Dividing by the largest absolute component first keeps every component in [-1, 1] with one equal
/// to ±1, so the squared length lies in [1, 3]: it can neither underflow (tiny sums of tiny triangles)
/// nor overflow (large areas), which `Vec3A::normalize` would turn into NaN or zero.
#[inline]
pub(crate) fn unit_or_none(v: Vec3A) -> Option<Vec3A> {
    // Fast path (every vertex of a metre-scale mesh): one square root and one division, exact for
    // axis-aligned input since sqrt(c²) = |c|. The bounds keep the squared length clear of
    // underflow and overflow; NaN fails `contains` and takes the checked path below.
    let length_squared = v.length_squared();
    if (SAFE_LENGTH_SQUARED_MIN..=SAFE_LENGTH_SQUARED_MAX).contains(&length_squared) {
        return Some(v / length_squared.sqrt());
    }
    // Checked explicitly: `max_element` uses `f32::max`, which skips NaN.
    if !v.is_finite() {
        return None;
    }
    let largest = v.abs().max_element();
    if largest <= 0.0 {
        return None;
    }
    // Divisions, not reciprocal multiplications: exact for axis-aligned input (a flat sheet gets
    // exactly ±Z), and on `Vec3A` each is one SIMD division.
    let scaled = v / largest;
    Some(scaled / scaled.length())
}

/// `v` or `-v`, whichever lies in the canonical half-space: first non-zero component (x, then y,
/// then z) positive.
///
/// This is the deterministic tie-break for a face normal exactly perpendicular to the direction to
/// the light (μ0 = 0): the choice depends only on the geometry, never on winding or vertex numbering,
/// and parallel faces of a flat sheet seen edge-on all get the same sign, so they add up instead of
/// cancelling.
#[inline]
pub(crate) fn canonical_sign(v: Vec3A) -> Vec3A {
    let negative = v.x < 0.0 || (v.x == 0.0 && (v.y < 0.0 || (v.y == 0.0 && v.z < 0.0)));
    if negative { -v } else { v }
}

/// Relative size of n · ω0′ below which its sign is rounding noise: |n · ω0′| ≤
/// `PERPENDICULAR_TOLERANCE` · Σ|n_i||ω_i| counts as μ0 = 0.
///
/// Derivation: the computed dot product of two f32 3-vectors errs by at most γ₃·Σ|n_i||ω_i| with
/// γ₃ ≈ 3u = 1.5ε, and the rounding of ω0′ = light − position (u per component) adds u·Σ|n_i||ω_i|:
/// 2ε in all; doubled for margin.
pub(crate) const PERPENDICULAR_TOLERANCE: f32 = 4.0 * f32::EPSILON;

/// `v` flipped if needed so that `v · to_light ≥ 0`. When the sign of `v · to_light` is within
/// rounding of zero (see [`PERPENDICULAR_TOLERANCE`]), `v` is kept: callers pass canonical-sign
/// vectors ([`canonical_sign`]), so coplanar faces seen edge-on by the light all keep one sign
/// instead of being flipped at random by rounding and cancelling in the vertex sum.
#[inline]
pub(crate) fn toward(v: Vec3A, to_light: Vec3A) -> Vec3A {
    let dot = v.dot(to_light);
    if dot < 0.0 && -dot > PERPENDICULAR_TOLERANCE * v.abs().dot(to_light.abs()) {
        -v
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_or_none_survives_extreme_magnitudes() {
        // 1e-30 squared underflows to 0 in f32 and 1e30 squared overflows: both must still give
        // the exact axis, since dividing by the largest component makes the vector exactly (1, 0, 0).
        assert_eq!(unit_or_none(Vec3A::new(1e-30, 0.0, 0.0)), Some(Vec3A::X));
        assert_eq!(unit_or_none(Vec3A::new(0.0, -1e30, 0.0)), Some(-Vec3A::Y));
        assert_eq!(unit_or_none(Vec3A::ZERO), None);
        assert_eq!(unit_or_none(Vec3A::new(f32::NAN, 0.0, 1.0)), None);
        assert_eq!(unit_or_none(Vec3A::new(f32::INFINITY, 0.0, 1.0)), None);
        let subnormal = unit_or_none(Vec3A::new(1e-45, 1e-45, 0.0)).unwrap();
        // Both components are the same subnormal, so the result is (1, 1, 0)/√2 up to the rounding of
        // one length and one division: a few ulps of 1.
        assert!((subnormal.length() - 1.0).abs() <= 4.0 * f32::EPSILON);
    }

    #[test]
    fn safe_range_constants_are_the_stated_powers_of_two() {
        assert_eq!(SAFE_LENGTH_SQUARED_MIN, 2f32.powi(-100));
        assert_eq!(SAFE_LENGTH_SQUARED_MAX, 2f32.powi(100));
    }

    #[test]
    fn canonical_sign_is_sign_invariant() {
        for v in [
            Vec3A::new(1.0, -2.0, 3.0),
            Vec3A::new(0.0, -2.0, 3.0),
            Vec3A::new(0.0, 0.0, -3.0),
            Vec3A::new(-0.5, 0.0, 0.0),
        ] {
            assert_eq!(canonical_sign(v), canonical_sign(-v));
        }
        assert_eq!(
            canonical_sign(Vec3A::new(0.0, 0.0, -3.0)),
            Vec3A::new(0.0, 0.0, 3.0)
        );
    }
}
