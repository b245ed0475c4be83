//! The thin-slab shading model on the CPU in `f64`: the reference every other path is tested against.
//!
//! Frisvad, Christensen & Falster (2005), "Efficient light scattering through thin semi-transparent
//! objects", section 3, after Chandrasekhar (1960) ch. IX (single scattering in a plane-parallel slab with
//! isotropic phase function `p = Λ/4π`):
//!
//! * direct transmission `α = exp(−τ1/μ)` (the first terms of eqs. 2–3, the blend factor of eq. 9);
//! * single-scattered radiance emerging on the lit side, eq. (4):
//!   `L+ = Λ/(4π) · E · μ0/(μ+μ0) · (1 − exp(−τ1 (1/μ + 1/μ0)))`;
//! * single-scattered radiance emerging on the far side, eq. (5):
//!   `L− = Λ/(4π) · E · μ0/(μ−μ0) · (exp(−τ1/μ) − exp(−τ1/μ0))`;
//! * the composites of eqs. (7)–(8), i.e. the blend of eq. (9): `L = L_behind · α + L±`.
//!
//! Units: optical thickness τ1 and albedo Λ are dimensionless, μ and μ0 are cosines, irradiance E is in
//! W/m², radiance in W/(m²·sr). The radiance functions here return radiance **per unit irradiance normal to
//! the beam** (sr⁻¹); multiply by the irradiance that [`IrradianceConvention::inserted_irradiance`] gives.
//!
//! # The irradiance convention (our finding)
//!
//! Integrating the single-scattering source along the view ray for a collimated beam whose irradiance on a
//! plane *normal to the beam* is `F` reproduces eq. (4) and eq. (5) exactly with `E(0) = F`
//! (`reference::single_scattered_radiance_by_view_ray_quadrature`, `tests/model_numerics.rs`:
//! worst relative difference 2.1e-14 over 160 cases). Eq. (6),
//! the irradiance *on the surface*, already contains the factor μ0 = cos θ0 (it is `F·μ0`); inserting it into
//! eqs. (4)–(5) counts the obliquity twice. The energy balance confirms it: for an optically thin slab the
//! single-scattered flux leaving both faces must approach `Λ·F·μ0·(1 − e^{−τ1/μ0})` (everything scattered
//! escapes), and with `E(0) = F` it does (ratio → 1), whereas with `E(0) = F·μ0` the ratio tends to μ0, so the
//! paper-literal reading loses the fraction `1 − μ0` of the scattered light. [`IrradianceConvention::NormalToBeam`]
//! is therefore the default; [`IrradianceConvention::PaperLiteral`] keeps the paper's eq. (6) insertion.
//!
//! # Eq. (5) without cancellation
//!
//! With `a = τ1/μ`, `b = τ1/μ0`, one has `μ0/(μ−μ0) = a/(b−a)`, so
//! `L− = Λ/(4π)·E·a·(e^{−a} − e^{−b})/(b − a)`. Writing `M = max(μ, μ0)`, `d = |b − a| = τ1·|μ−μ0|/(μ·μ0)`
//! and `φ(d) = (1 − e^{−d})/d = −expm1(−d)/d` (φ(0) = 1):
//!
//! * `d ≤ 1`: `L− = Λ/(4π)·E·(τ1/μ)·e^{−τ1/M}·φ(d)`, with `(τ1/μ)·e^{−τ1/M} = (τ1/M + s·d)·e^{−τ1/M}`
//!   (`s = 1` if μ < μ0, else 0) so no overflow can meet an underflow;
//! * `d > 1`: `L− = Λ/(4π)·E·μ0/|μ−μ0|·e^{−τ1/M}·(−expm1(−d))` (no 0/0 possible: μ ≠ μ0 there).
//!
//! Both are products of non-negative, non-cancelling factors; at μ = μ0 the first gives the exact limit
//! `Λ/(4π)·E·(τ1/μ)·e^{−τ1/μ}`. The same two branches are used in WGSL (`shaders/thin_slab.wgsl`), where
//! `expm1` is replaced by its Taylor series for small arguments.

use std::f64::consts::PI;

use thiserror::Error;

/// Which face of the slab the eye sees ([`Face::Lit`]: eq. 4, [`Face::Far`]: eq. 5), as the lit-side
/// rule of `sheer-normals` decides it; and that rule's error.
pub use sheer_normals::{Face, NormalsError};

/// Why a model parameter was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum SlabParameterError {
    /// τ1 must be finite and strictly positive (a slab of zero thickness is not a slab).
    #[error("optical thickness tau1 = {0:?} is not a finite number > 0")]
    OpticalThickness(f64),
    /// Λ = σs/σt must lie in [0, 1].
    #[error("single-scattering albedo Lambda = {0:?} is outside [0, 1]")]
    Albedo(f64),
    /// μ and μ0 are cosines of directions on the hemisphere they belong to: (0, 1].
    #[error("direction cosine {name} = {value:?} is outside (0, 1]")]
    Cosine {
        /// `"mu"` or `"mu0"`.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// Irradiance must be finite and non-negative (W/m²).
    #[error("irradiance {0:?} W/m^2 is not a finite number >= 0")]
    Irradiance(f64),
    /// Flux Φ of a point light must be finite and non-negative (W).
    #[error("light flux {0:?} W is not a finite number >= 0")]
    Flux(f64),
    /// Distance from a point light must be finite and strictly positive (m).
    #[error("distance {0:?} m to the light is not a finite number > 0")]
    Distance(f64),
    /// A normal or a direction to the light or the eye has a NaN or infinite component (the lit-side
    /// rule refuses it).
    #[error(transparent)]
    Geometry(#[from] NormalsError),
    /// The `all-orders` model covers only the τ1 range of its precomputed table.
    #[error(
        "optical thickness tau1 = {value:?} lies outside the all-orders table's range [{min}, {max}]"
    )]
    OutsideTable {
        /// The rejected τ1.
        value: f64,
        /// Smallest τ1 of the table.
        min: f64,
        /// Largest τ1 of the table.
        max: f64,
    },
    /// The all-orders table's sampler refused a query for another reason (not expected for validated
    /// inputs; reported rather than panicking).
    #[error(
        "the all-orders table refused tau1 = {tau1:?}, Lambda = {albedo:?}, mu0 = {mu0:?}, mu = {mu:?}"
    )]
    TableQuery {
        /// τ1.
        tau1: f64,
        /// Λ.
        albedo: f64,
        /// μ0.
        mu0: f64,
        /// μ.
        mu: f64,
    },
    /// The diffuse (sky light) table's sampler refused a query (not expected for validated inputs;
    /// reported rather than panicking).
    #[error("the diffuse table refused tau1 = {tau1:?}, Lambda = {albedo:?}, mu = {mu:?}")]
    DiffuseTableQuery {
        /// τ1.
        tau1: f64,
        /// Λ.
        albedo: f64,
        /// μ.
        mu: f64,
    },
}

/// Optical thickness τ1 of the slab (dimensionless), validated finite and > 0.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct OpticalThickness(f64);

impl OpticalThickness {
    /// Validates τ1.
    pub fn new(value: f64) -> Result<Self, SlabParameterError> {
        if value.is_finite() && value > 0.0 {
            Ok(Self(value))
        } else {
            Err(SlabParameterError::OpticalThickness(value))
        }
    }

    /// The value of τ1.
    pub fn get(self) -> f64 {
        self.0
    }
}

/// Single-scattering albedo Λ = σs/σt (dimensionless), validated in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Albedo(f64);

impl Albedo {
    /// Validates Λ.
    pub fn new(value: f64) -> Result<Self, SlabParameterError> {
        if (0.0..=1.0).contains(&value) {
            Ok(Self(value))
        } else {
            Err(SlabParameterError::Albedo(value))
        }
    }

    /// The value of Λ.
    pub fn get(self) -> f64 {
        self.0
    }
}

/// A direction cosine μ = n·ω or μ0 = n·ω0 (dimensionless), validated in (0, 1].
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Cosine(f64);

impl Cosine {
    /// Validates a cosine; `name` ("mu" or "mu0") goes into the error.
    pub fn new(name: &'static str, value: f64) -> Result<Self, SlabParameterError> {
        if value > 0.0 && value <= 1.0 {
            Ok(Self(value))
        } else {
            Err(SlabParameterError::Cosine { name, value })
        }
    }

    /// The value of the cosine.
    pub fn get(self) -> f64 {
        self.0
    }
}

/// Which irradiance is inserted as `E(0)` in eqs. (4)–(5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum IrradianceConvention {
    /// `E(0)` = irradiance on a plane normal to the beam, `Φ/(4πr²)` for a point light. Physically right:
    /// this is what eqs. (4)–(5) are derived for (see the module docs).
    #[default]
    NormalToBeam,
    /// `E(0)` = irradiance on the surface, eq. (6) `Φμ0/(4πr²)`, as the paper literally suggests; counts the
    /// obliquity μ0 twice.
    PaperLiteral,
}

impl IrradianceConvention {
    /// The irradiance `E(0)` (W/m²) to insert in eqs. (4)–(5) given the irradiance normal to the beam
    /// (W/m²) and μ0.
    pub fn inserted_irradiance(self, beam_normal_irradiance: f64, mu0: Cosine) -> f64 {
        match self {
            Self::NormalToBeam => beam_normal_irradiance,
            Self::PaperLiteral => beam_normal_irradiance * mu0.get(),
        }
    }
}

/// Irradiance (W/m²) on a plane normal to the beam at distance `distance` (m) from an isotropic point light
/// of flux `flux` (W): `Φ/(4πr²)`.
pub fn point_light_beam_normal_irradiance(
    flux: f64,
    distance: f64,
) -> Result<f64, SlabParameterError> {
    if !(flux.is_finite() && flux >= 0.0) {
        return Err(SlabParameterError::Flux(flux));
    }
    if !(distance.is_finite() && distance > 0.0) {
        return Err(SlabParameterError::Distance(distance));
    }
    // Divided step by step: r² of a tiny r underflows to 0 (0/0 for no flux), where Φ/(4π)/r/r does
    // not; an irradiance beyond f64 (a strong light almost touching the surface) is refused.
    let irradiance = flux / (4.0 * PI) / distance / distance;
    if irradiance.is_finite() {
        Ok(irradiance)
    } else {
        Err(SlabParameterError::Irradiance(irradiance))
    }
}

/// Irradiance (W/m²) on the surface, eq. (6): `Φμ0/(4πr²)`.
pub fn point_light_surface_irradiance(
    flux: f64,
    distance: f64,
    mu0: Cosine,
) -> Result<f64, SlabParameterError> {
    Ok(point_light_beam_normal_irradiance(flux, distance)? * mu0.get())
}

/// Direct transmission `α = exp(−τ1/μ)` (first terms of eqs. 2–3; α_source of eq. 9), dimensionless.
pub fn direct_transmission(optical_thickness: OpticalThickness, mu: Cosine) -> f64 {
    (-optical_thickness.get() / mu.get()).exp()
}

/// Eq. (4): single-scattered radiance emerging on the lit side, per unit irradiance `E(0)` (sr⁻¹).
pub fn single_scattered_reflected_radiance(
    optical_thickness: OpticalThickness,
    albedo: Albedo,
    mu0: Cosine,
    mu: Cosine,
) -> f64 {
    let (tau, mu0, mu) = (optical_thickness.get(), mu0.get(), mu.get());
    // τ1(1/μ + 1/μ0) written over a common denominator; `-expm1` keeps 1 − e^{−x} accurate for small x.
    // A sum of two positive quotients: +∞ at worst (then −expm1(−∞) = 1), never 0/0.
    let exponent = tau / mu + tau / mu0;
    albedo.get() / (4.0 * PI) * mu0 / (mu + mu0) * -(-exponent).exp_m1()
}

/// Eq. (5): single-scattered radiance emerging on the far side, per unit irradiance `E(0)` (sr⁻¹), in the
/// cancellation-free form described in the module docs (exact at μ = μ0).
pub fn single_scattered_transmitted_radiance(
    optical_thickness: OpticalThickness,
    albedo: Albedo,
    mu0: Cosine,
    mu: Cosine,
) -> f64 {
    albedo.get() / (4.0 * PI) * transmitted_shape(optical_thickness.get(), mu0.get(), mu.get())
}

/// `μ0/(μ−μ0)·(e^{−τ/μ} − e^{−τ/μ0})` without cancellation (valid for τ > 0, μ, μ0 in (0, 1]).
fn transmitted_shape(tau: f64, mu0: f64, mu: f64) -> f64 {
    let larger = mu.max(mu0);
    let smaller = mu.min(mu0);
    let tau_over_larger = tau / larger;
    let attenuation = (-tau_over_larger).exp();
    // d = τ|μ−μ0|/(μμ0) = (τ/m)(1 − m/M): the difference μ−μ0 is formed exactly (Sterbenz) when close.
    let exponent_difference = if larger == smaller {
        0.0
    } else {
        (tau / smaller) * ((larger - smaller) / larger)
    };
    if exponent_difference <= 1.0 {
        // (τ/μ)·e^{−τ/M}·φ(d); τ/μ = τ/M + d when μ is the smaller cosine.
        let tau_over_mu = if mu < mu0 {
            tau_over_larger + exponent_difference
        } else {
            tau_over_larger
        };
        let leading = if attenuation == 0.0 {
            0.0
        } else {
            tau_over_mu * attenuation
        };
        leading * one_minus_exp_neg_over(exponent_difference)
    } else {
        mu0 / (larger - smaller) * attenuation * -(-exponent_difference).exp_m1()
    }
}

/// φ(d) = (1 − e^{−d})/d for d ≥ 0, with φ(0) = 1.
fn one_minus_exp_neg_over(d: f64) -> f64 {
    if d == 0.0 { 1.0 } else { -(-d).exp_m1() / d }
}

/// What the shader computes for one sample: the source radiance and the blend factor of eq. (9).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlabShading {
    /// `L_source` (W/(m²·sr)): L+ or L− times the inserted irradiance.
    pub source_radiance: f64,
    /// `α_source = exp(−τ1/μ)`.
    pub transmittance: f64,
}

impl SlabShading {
    /// Eq. (9) (= eq. 7 or 8): the radiance seen through the slab over `behind_radiance` (W/(m²·sr)).
    pub fn composite_over(self, behind_radiance: f64) -> f64 {
        behind_radiance * self.transmittance + self.source_radiance
    }
}

/// Eq. (4) on the lit face (`Face::Lit`), eq. (5) on the far face (`Face::Far`): the single-scattered radiance on
/// the face the eye is on, per unit irradiance normal to the beam (sr⁻¹).
pub(crate) fn single_scattered_radiance(
    side: Face,
    optical_thickness: OpticalThickness,
    albedo: Albedo,
    mu0: Cosine,
    mu: Cosine,
) -> f64 {
    match side {
        Face::Lit => single_scattered_reflected_radiance(optical_thickness, albedo, mu0, mu),
        Face::Far => single_scattered_transmitted_radiance(optical_thickness, albedo, mu0, mu),
    }
}

/// The model at one point: α and `L±·E(0)` for the side the eye is on; `beam_normal_irradiance` in W/m².
pub fn slab_shading(
    optical_thickness: OpticalThickness,
    albedo: Albedo,
    mu0: Cosine,
    mu: Cosine,
    side: Face,
    beam_normal_irradiance: f64,
    convention: IrradianceConvention,
) -> Result<SlabShading, SlabParameterError> {
    shading_from_diffuse_radiance(
        optical_thickness,
        mu0,
        mu,
        beam_normal_irradiance,
        convention,
        || {
            Ok(single_scattered_radiance(
                side,
                optical_thickness,
                albedo,
                mu0,
                mu,
            ))
        },
    )
}

/// Eq. (9)'s two terms from a diffuse radiance per unit irradiance (computed by `diffuse_per_unit`, after
/// the irradiance is checked): `L·E(0)` with the convention's inserted irradiance, and α = exp(−τ1/μ).
/// Shared by both scattering models, so they differ only in that radiance.
pub(crate) fn shading_from_diffuse_radiance(
    optical_thickness: OpticalThickness,
    mu0: Cosine,
    mu: Cosine,
    beam_normal_irradiance: f64,
    convention: IrradianceConvention,
    diffuse_per_unit: impl FnOnce() -> Result<f64, SlabParameterError>,
) -> Result<SlabShading, SlabParameterError> {
    if !(beam_normal_irradiance.is_finite() && beam_normal_irradiance >= 0.0) {
        return Err(SlabParameterError::Irradiance(beam_normal_irradiance));
    }
    let irradiance = convention.inserted_irradiance(beam_normal_irradiance, mu0);
    Ok(SlabShading {
        source_radiance: diffuse_per_unit()? * irradiance,
        transmittance: direct_transmission(optical_thickness, mu),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tau(v: f64) -> OpticalThickness {
        OpticalThickness::new(v).unwrap()
    }
    fn cos(v: f64) -> Cosine {
        Cosine::new("mu", v).unwrap()
    }

    #[test]
    fn validation_rejects_out_of_domain() {
        assert!(OpticalThickness::new(0.0).is_err());
        assert!(OpticalThickness::new(f64::NAN).is_err());
        assert!(OpticalThickness::new(f64::INFINITY).is_err());
        assert!(Albedo::new(1.0 + 1e-12).is_err());
        assert!(Albedo::new(-1e-300).is_err());
        assert!(Cosine::new("mu", 0.0).is_err());
        assert!(Cosine::new("mu0", 1.0 + 1e-15).is_err());
        assert!(point_light_beam_normal_irradiance(1.0, 0.0).is_err());
        assert!(point_light_beam_normal_irradiance(-1.0, 1.0).is_err());
        // r² underflows at 1e-200 m: no light gave 0/0, a watt +∞; a flux near the largest f64 at
        // 10 cm overflows. Now 0, and typed errors for the two beyond f64.
        assert_eq!(point_light_beam_normal_irradiance(0.0, 1e-200), Ok(0.0));
        for (flux, distance) in [(1.0, 1e-200), (f64::MAX, 0.1)] {
            assert!(matches!(
                point_light_beam_normal_irradiance(flux, distance),
                Err(SlabParameterError::Irradiance(value)) if value == f64::INFINITY
            ));
        }
        let at_a_metre = point_light_beam_normal_irradiance(4.0 * PI, 1.0).unwrap();
        assert!((at_a_metre - 1.0).abs() <= f64::EPSILON);
    }

    #[test]
    fn transmitted_equals_naive_formula_away_from_the_diagonal() {
        // Away from μ = μ0 the paper's form has no cancellation beyond a few ulps: |a−b| ≥ 0.1·max(a,b)
        // limits the relative error of the difference to ~20 ulps, hence 1e-13.
        for &(t, m0, m) in &[
            (0.5f64, 0.9f64, 0.3f64),
            (2.0, 0.2, 0.8),
            (10.0, 0.7, 0.05),
            (0.01, 1.0, 0.5),
        ] {
            let naive = m0 / (m - m0) * ((-t / m).exp() - (-t / m0).exp()) / (4.0 * PI);
            let ours = single_scattered_transmitted_radiance(
                tau(t),
                Albedo::new(1.0).unwrap(),
                cos(m0),
                cos(m),
            );
            assert!(
                (ours - naive).abs() <= 1e-13 * naive.abs(),
                "{t} {m0} {m}: {ours} vs {naive}"
            );
        }
    }

    #[test]
    fn transmitted_at_equal_cosines_is_the_limit() {
        // lim_{μ→μ0} μ0/(μ−μ0)(e^{−τ/μ} − e^{−τ/μ0}) = (τ/μ0)e^{−τ/μ0} (derivative of e^{−τ/μ}).
        for &(t, m) in &[(0.1f64, 0.5f64), (2.0, 1.0), (10.0, 0.01), (1e-6, 1e-3)] {
            let expected = t / m * (-t / m).exp() / (4.0 * PI);
            let ours = single_scattered_transmitted_radiance(
                tau(t),
                Albedo::new(1.0).unwrap(),
                cos(m),
                cos(m),
            );
            // A handful of roundings in either product (division, exp, three multiplications): 8 ulps.
            assert!(
                (ours - expected).abs() <= 8.0 * f64::EPSILON * expected,
                "{ours} {expected}"
            );
        }
    }

    #[test]
    fn extreme_inputs_stay_finite() {
        let one = Albedo::new(1.0).unwrap();
        let tiny = f64::from_bits(1); // smallest subnormal
        for &t in &[1e-300, 1e-8, 1.0, 10.0, 1e300] {
            for &m0 in &[tiny, 1e-300, 1e-8, 0.5, 1.0] {
                for &m in &[tiny, 1e-300, 1e-8, 0.5, 1.0] {
                    let r = single_scattered_reflected_radiance(tau(t), one, cos(m0), cos(m));
                    let s = single_scattered_transmitted_radiance(tau(t), one, cos(m0), cos(m));
                    let a = direct_transmission(tau(t), cos(m));
                    for v in [r, s, a] {
                        assert!(
                            v.is_finite() && v >= 0.0,
                            "{t:e} {m0:e} {m:e}: {r:e} {s:e} {a:e}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn paper_literal_inserts_surface_irradiance() {
        let m0 = cos(0.25);
        let e = point_light_beam_normal_irradiance(100.0, 2.0).unwrap();
        assert_eq!(
            IrradianceConvention::NormalToBeam.inserted_irradiance(e, m0),
            e
        );
        let eq6 = point_light_surface_irradiance(100.0, 2.0, m0).unwrap();
        assert_eq!(
            IrradianceConvention::PaperLiteral.inserted_irradiance(e, m0),
            eq6
        );
        // Φ/(4πr²) = 100/(16π) exactly up to one rounding of each operation.
        assert!((e - 100.0 / (16.0 * PI)).abs() <= 2.0 * f64::EPSILON * e);
    }
}
