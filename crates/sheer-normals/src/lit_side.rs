//! The per-fragment lit-side rule: which of the paper's rendering equations (7) or (8) applies at a
//! fragment, with the cosines μ0 and μ it needs — in Rust here and, as the same rule, in WGSL
//! ([`LIT_SIDE_WGSL`], the file `shaders/lit_side.wgsl`).
//!
//! Frisvad, Christensen & Falster (2005), §3–4: the surface normal n is "always turned outwards such
//! that μ0 = cos θ0 > 0", i.e. toward the light. Then, with ω the unit direction toward the eye,
//! - n · ω > 0: the eye is on the lit side, the surface is front-lit: eq. (7) with the single
//!   scattering term L+ of eq. (4), μ = n · ω;
//! - n · ω < 0: the eye is on the far side, the surface is back-lit: eq. (8) with L− of eq. (5),
//!   μ = −n · ω (the cosine with the eye's side of the slab).
//!
//! Interpolated normals and the terminator: vertex normals come from [`crate::NormalUpdater`]
//! turned toward the light at each vertex. With a fixed light direction a convex combination of
//! two such normals still has n · ω0′ > 0, so interpolation alone cannot cross the terminator; it
//! does where ω0′ varies along an edge, i.e. for a point light close to the surface. The rule
//! therefore turns the *interpolated* normal toward the light again at the fragment.
//! Consequences, tested in `tests/lit_side.rs`:
//! - μ0 ≥ 0 at every fragment, and it tends to 0 continuously from both sides of the point where the
//!   interpolated normal is perpendicular to the light — where eq. (4) and (5) both vanish
//!   (E ∝ μ0 by eq. 6), so the diffuse term is continuous there;
//! - at that point the flip changes which side the eye is on, so eq. (7)/(8) swap, but μ = |n · ω|
//!   is continuous and the direct transmission e^{−τ1/μ} is the same in both equations;
//! - a fragment whose interpolated normal is exactly zero (two opposite vertex normals, halfway)
//!   has no defined orientation: it gets μ0 = 0, μ = 0, eye on the lit side — "grazing": no
//!   single-scattered light (μ0 = 0) and no direct transmission (e^{−τ1/μ} → 0).
//!
//! Ties: n · ω0′ = 0 keeps n (μ0 = 0 either way); n · ω = 0 (eye grazing) counts as the lit side,
//! eq. (7), with μ = 0. A zero `to_light` (light at the fragment) gives μ0 = 0; a zero `to_eye`
//! (eye at the fragment) gives μ = 0.

use glam::{DVec3, Vec3, Vec3A};

use crate::error::NormalsError;
use crate::vector::unit_or_none;

/// The WGSL source of the same rule, `fn lit_side_cosines(normal, to_light, to_eye) -> LitSide`, to
/// be prepended to a shader's own source. It declares only `struct LitSide`, `fn lit_side_unit` and
/// `fn lit_side_cosines`: no entry points, no bindings.
pub const LIT_SIDE_WGSL: &str = include_str!("../../../shaders/lit_side.wgsl");

/// Which face of the slab the eye sees, and so which of the paper's equations applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Face {
    /// The eye is on the lit side (front-lit surface): eq. (7) with L+ of eq. (4).
    Lit,
    /// The eye is on the far side (back-lit surface): eq. (8) with L− of eq. (5).
    Far,
}

/// The cosines of one fragment and which equation of the paper applies, in `f32` (the shader's
/// precision, from `Vec3`) or `f64` (CPU references, from `DVec3`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LitSide<S = f32> {
    /// μ0 = cos θ0 = n · ω0′ ≥ 0 with n turned toward the light (eq. 4–6); in [0, 1] up to a few
    /// ulps of rounding.
    pub mu0: S,
    /// μ = |n · ω| ≥ 0, the cosine between the normal and the eye direction on the eye's side of
    /// the slab (already negated for the back-lit case, as eq. 8 with eq. 5 needs it).
    pub mu: S,
    /// The face the eye is on: [`Face::Lit`], eq. (7) with L+ of eq. (4); [`Face::Far`], eq. (8)
    /// with L− of eq. (5).
    pub face: Face,
}

/// A 3-vector the lit-side rule takes: glam's `Vec3` (f32) or `DVec3` (f64). Sealed: its operations
/// take a token only this crate can make, so they are not part of the API.
pub trait LitSideVector: sealed::Sealed + Copy + std::ops::Neg<Output = Self> {
    /// `f32` or `f64`.
    type Scalar: Copy + PartialOrd + Default;
    #[doc(hidden)]
    fn unit(self, _: Token) -> Option<Self>;
    #[doc(hidden)]
    fn finite(self, _: Token) -> bool;
    #[doc(hidden)]
    fn dot_with(self, other: Self, _: Token) -> Self::Scalar;
    #[doc(hidden)]
    fn magnitude(s: Self::Scalar, _: Token) -> Self::Scalar;
    #[doc(hidden)]
    fn zero(_: Token) -> Self;
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for glam::Vec3 {}
    impl Sealed for glam::DVec3 {}

    /// Proof that the caller is this crate.
    #[derive(Clone, Copy, Debug)]
    pub struct Token(pub(crate) ());
}
use sealed::Token;

impl LitSideVector for Vec3 {
    type Scalar = f32;
    /// Scale-robust: tiny and huge vectors neither underflow nor overflow (`unit_or_none`).
    fn unit(self, _: Token) -> Option<Self> {
        unit_or_none(self.into()).map(Vec3::from)
    }
    fn finite(self, _: Token) -> bool {
        self.is_finite()
    }
    fn dot_with(self, other: Self, _: Token) -> f32 {
        Vec3A::from(self).dot(other.into())
    }
    fn magnitude(s: f32, _: Token) -> f32 {
        s.abs()
    }
    fn zero(_: Token) -> Self {
        Vec3::ZERO
    }
}

impl LitSideVector for DVec3 {
    type Scalar = f64;
    /// `normalize_or_zero`: a vector shorter than about 1e-154 or longer than about 1e154 (m) counts as
    /// zero, far outside any scene.
    fn unit(self, _: Token) -> Option<Self> {
        Some(self.normalize_or_zero()).filter(|unit| *unit != DVec3::ZERO)
    }
    fn finite(self, _: Token) -> bool {
        self.is_finite()
    }
    fn dot_with(self, other: Self, _: Token) -> f64 {
        self.dot(other)
    }
    fn magnitude(s: f64, _: Token) -> f64 {
        s.abs()
    }
    fn zero(_: Token) -> Self {
        DVec3::ZERO
    }
}

/// The lit-side rule at one fragment. `normal` is the interpolated vertex normal (any length, any
/// sign), `to_light` the vector from the fragment toward the light (ω0′ up to length) and `to_eye`
/// the vector from the fragment toward the eye (ω up to length); none needs to be unit length.
/// `Vec3` gives the shader's `f32` cosines, `DVec3` the `f64` ones of a CPU reference.
///
/// Errors: [`NormalsError::NonFiniteVector`] if any component is NaN or infinite. Zero vectors are
/// defined cases (see the module documentation).
pub fn lit_side_cosines<V: LitSideVector>(
    normal: V,
    to_light: V,
    to_eye: V,
) -> Result<LitSide<V::Scalar>, NormalsError> {
    for (what, v) in [
        ("normal", normal),
        ("to_light", to_light),
        ("to_eye", to_eye),
    ] {
        if !v.finite(Token(())) {
            return Err(NormalsError::NonFiniteVector { what });
        }
    }
    let token = Token(());
    let zero = V::Scalar::default();
    let light = to_light.unit(token).unwrap_or(V::zero(token));
    let eye = to_eye.unit(token).unwrap_or(V::zero(token));
    let Some(normal) = normal.unit(token) else {
        return Ok(LitSide {
            mu0: zero,
            mu: zero,
            face: Face::Lit,
        });
    };
    // Re-orient at the fragment: interpolation may have carried the normal past the terminator.
    let normal = if normal.dot_with(light, token) < zero {
        -normal
    } else {
        normal
    };
    // After the flip the dot is ≥ 0 or −0; the magnitude only turns −0 into +0.
    let mu0 = V::magnitude(normal.dot_with(light, token), token);
    let signed_mu = normal.dot_with(eye, token);
    Ok(LitSide {
        mu0,
        mu: V::magnitude(signed_mu, token),
        face: if signed_mu >= zero {
            Face::Lit
        } else {
            Face::Far
        },
    })
}
