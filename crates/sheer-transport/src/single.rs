//! Single scattering in a homogeneous plane-parallel slab: the paper's eqs. (4)–(5) (Frisvad et al. 2005,
//! after Chandrasekhar 1960 §IX) and their Henyey–Greenstein generalisation (Blinn 1982, who replaced the
//! isotropic phase function by a normalised one; Henyey & Greenstein 1941 for the phase function).
//!
//! All radiances are per unit irradiance normal to the incident beam (`E(0) = 1` W m⁻²), so they are in
//! sr⁻¹; multiply by the beam irradiance in W m⁻² for W m⁻² sr⁻¹. With that normalisation the flux
//! crossing the lit surface is `μ0`, and `μ0` appears once in eqs. (4)–(5), as the paper writes them.
//!
//! Because the slab is homogeneous, the scattering angle of a singly scattered photon does not depend on
//! the depth where it scatters, so the phase function factors out of the depth integral: the
//! Henyey–Greenstein radiance is `Λ p_HG(cos Θ)` times the same path factor as the isotropic one, and
//! `g = 0` gives `p = 1/(4π)` bit for bit.

use crate::{Result, TransportError, validate};

/// Isotropic phase function `1/(4π)` sr⁻¹ (normalised over the sphere; the paper folds Λ into it).
pub const ISOTROPIC_PHASE: f64 = 1.0 / (4.0 * std::f64::consts::PI);

/// Depth integral of single scattering towards the lit side:
/// `∫_0^τ1 e^{−t/μ0} e^{−t/μ} dt/μ = μ0/(μ+μ0) (1 − e^{−τ1(1/μ+1/μ0)})` (dimensionless);
/// its grazing limit `μ → 0` is 1. Arguments are assumed validated.
pub(crate) fn reflected_path_factor(tau1: f64, mu0: f64, mu: f64) -> f64 {
    if mu == 0.0 {
        return 1.0;
    }
    mu0 / (mu + mu0) * -(-tau1 * (1.0 / mu + 1.0 / mu0)).exp_m1()
}

/// Depth integral of single scattering towards the unlit side:
/// `∫_0^τ1 e^{−t/μ0} e^{−(τ1−t)/μ} dt/μ = μ0/(μ−μ0) (e^{−τ1/μ} − e^{−τ1/μ0})` (dimensionless), written
/// with `expm1` so that it stays accurate at and near `μ = μ0` (limit `τ1 e^{−τ1/μ0}/μ0`); its grazing
/// limit `μ → 0` is `e^{−τ1/μ0}`. Arguments are assumed validated.
///
/// It depends on the slant optical paths `a = τ1/μ` and `b = τ1/μ0` alone, `a (e^{−a} − e^{−b})/(b − a)`,
/// and is computed from them: a path that overflows to ∞ (`μ = 0`, or a cosine as small as 10⁻³¹⁰, whose
/// reciprocal overflows) takes its limit, where `1/μ0 − 1/μ` gave ∞ − ∞ = NaN.
pub(crate) fn transmitted_path_factor(tau1: f64, mu0: f64, mu: f64) -> f64 {
    let (a, b) = (tau1 / mu, tau1 / mu0);
    if a == f64::INFINITY {
        // The grazing limit; 0 when b is infinite too.
        return (-b).exp();
    }
    if b == f64::INFINITY {
        return 0.0;
    }
    // x = b − a = τ1 (1/μ0 − 1/μ); the integral is a e^{−a} (1 − e^{−x}) / x. The ratio, in (0, 1], is
    // formed first: a·x underflows for a thin slab (τ1 = 1e-200 gave 0).
    let x = b - a;
    if x == 0.0 {
        a * (-a).exp()
    } else if x > 0.0 {
        a * (-a).exp() * (-(-x).exp_m1() / x)
    } else {
        a * (-b).exp() * (x.exp_m1() / x)
    }
}

/// Eq. (4): singly scattered radiance leaving the lit surface,
/// `L₊⁽¹⁾(0, μ) = Λ/(4π) μ0/(μ+μ0) (1 − e^{−τ1(1/μ+1/μ0)})`, per unit irradiance normal to the beam (sr⁻¹).
///
/// `tau1` > 0, `albedo` Λ ∈ [0, 1], `mu0` ∈ (0, 1] towards the light, `mu` ∈ [0, 1] towards the viewer.
pub fn single_scattered_reflected_radiance(
    tau1: f64,
    albedo: f64,
    mu0: f64,
    mu: f64,
) -> Result<f64> {
    validate::optical_thickness(tau1)?;
    validate::albedo(albedo)?;
    validate::incident_cosine(mu0)?;
    validate::emergent_cosine(mu)?;
    Ok(albedo * ISOTROPIC_PHASE * reflected_path_factor(tau1, mu0, mu))
}

/// Eq. (5): singly scattered radiance leaving the unlit surface,
/// `L₋⁽¹⁾(τ1, μ) = Λ/(4π) μ0/(μ−μ0) (e^{−τ1/μ} − e^{−τ1/μ0})`, per unit irradiance normal to the beam
/// (sr⁻¹); finite and continuous at `μ = μ0`. Arguments as in [`single_scattered_reflected_radiance`].
pub fn single_scattered_transmitted_radiance(
    tau1: f64,
    albedo: f64,
    mu0: f64,
    mu: f64,
) -> Result<f64> {
    validate::optical_thickness(tau1)?;
    validate::albedo(albedo)?;
    validate::incident_cosine(mu0)?;
    validate::emergent_cosine(mu)?;
    Ok(albedo * ISOTROPIC_PHASE * transmitted_path_factor(tau1, mu0, mu))
}

/// Henyey–Greenstein phase function `p(cos Θ) = (1 − g²) / (4π (1 + g² − 2g cos Θ)^{3/2})` (sr⁻¹),
/// normalised to 1 over the sphere, mean cosine `g`; `g = 0` returns exactly [`ISOTROPIC_PHASE`].
pub fn henyey_greenstein_phase(asymmetry: f64, cos_scattering_angle: f64) -> Result<f64> {
    if !(asymmetry > -1.0 && asymmetry < 1.0) {
        return Err(TransportError::Asymmetry(asymmetry));
    }
    if !(-1.0..=1.0).contains(&cos_scattering_angle) {
        return Err(TransportError::Cosine {
            name: "cos_scattering_angle",
            range: "[-1, 1]",
            value: cos_scattering_angle,
        });
    }
    let g = asymmetry;
    let denominator = 1.0 + g * g - 2.0 * g * cos_scattering_angle;
    Ok((1.0 - g * g) / (4.0 * std::f64::consts::PI * denominator * denominator.sqrt()))
}

/// Cosine of the scattering angle between the incident beam's propagation direction and the emergent
/// direction. The z axis is the lit side's outward normal; the beam propagates along
/// `(sin θ0, 0, −μ0)`; the emergent direction is `(sin θ cos Δφ, sin θ sin Δφ, ±μ)` with `+` for the lit
/// side (reflection) and `−` for the unlit side (transmission). So `Δφ = 0` is forward in azimuth, and
/// `Δφ = π` with `μ = μ0` on the lit side is exact backscatter.
fn cos_scattering_angle(mu0: f64, mu: f64, azimuth_difference: f64, transmitted: bool) -> f64 {
    let sin_product = ((1.0 - mu0 * mu0) * (1.0 - mu * mu)).max(0.0).sqrt();
    let vertical = if transmitted { mu0 * mu } else { -mu0 * mu };
    // Round-off can push |cos Θ| a few ulp past 1; the exact value lies in [−1, 1].
    (sin_product * azimuth_difference.cos() + vertical).clamp(-1.0, 1.0)
}

fn validate_hg(
    tau1: f64,
    albedo: f64,
    mu0: f64,
    mu: f64,
    asymmetry: f64,
    azimuth_difference: f64,
) -> Result<()> {
    validate::optical_thickness(tau1)?;
    validate::albedo(albedo)?;
    validate::incident_cosine(mu0)?;
    validate::emergent_cosine(mu)?;
    if !(asymmetry > -1.0 && asymmetry < 1.0) {
        return Err(TransportError::Asymmetry(asymmetry));
    }
    if !azimuth_difference.is_finite() {
        return Err(TransportError::Azimuth(azimuth_difference));
    }
    Ok(())
}

/// Eq. (4) with a Henyey–Greenstein phase function of asymmetry `g` ∈ (−1, 1): singly scattered radiance
/// leaving the lit surface, `Λ p_HG(cos Θ) μ0/(μ+μ0)(1 − e^{−τ1(1/μ+1/μ0)})` per unit irradiance normal to
/// the beam (sr⁻¹). `azimuth_difference` Δφ (radians) is measured from the beam's propagation azimuth
/// (see the module docs). `g = 0` gives exactly [`single_scattered_reflected_radiance`].
pub fn single_scattered_reflected_radiance_hg(
    tau1: f64,
    albedo: f64,
    mu0: f64,
    mu: f64,
    asymmetry: f64,
    azimuth_difference: f64,
) -> Result<f64> {
    validate_hg(tau1, albedo, mu0, mu, asymmetry, azimuth_difference)?;
    let phase = henyey_greenstein_phase(
        asymmetry,
        cos_scattering_angle(mu0, mu, azimuth_difference, false),
    )?;
    Ok(albedo * phase * reflected_path_factor(tau1, mu0, mu))
}

/// Eq. (5) with a Henyey–Greenstein phase function: singly scattered radiance leaving the unlit surface,
/// `Λ p_HG(cos Θ) μ0/(μ−μ0)(e^{−τ1/μ} − e^{−τ1/μ0})` per unit irradiance normal to the beam (sr⁻¹).
/// Arguments as in [`single_scattered_reflected_radiance_hg`]; `g = 0` gives exactly
/// [`single_scattered_transmitted_radiance`].
pub fn single_scattered_transmitted_radiance_hg(
    tau1: f64,
    albedo: f64,
    mu0: f64,
    mu: f64,
    asymmetry: f64,
    azimuth_difference: f64,
) -> Result<f64> {
    validate_hg(tau1, albedo, mu0, mu, asymmetry, azimuth_difference)?;
    let phase = henyey_greenstein_phase(
        asymmetry,
        cos_scattering_angle(mu0, mu, azimuth_difference, true),
    )?;
    Ok(albedo * phase * transmitted_path_factor(tau1, mu0, mu))
}
