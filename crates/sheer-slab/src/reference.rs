//! Independent numerics for checking the closed forms of [`crate::model`]: Gauss–Legendre quadrature of the
//! single-scattering integral along the view ray through the slab, and of the emergent flux over both
//! hemispheres.
//!
//! Nothing here uses eqs. (4)–(5). The view-ray integral is set up from first principles (Chandrasekhar 1960,
//! ch. I; Frisvad et al. 2005 eqs. 2–3 with one scattering): a slab of geometric thickness `h` (m) and
//! extinction coefficient `σt = τ1/h` (m⁻¹) is crossed by a collimated beam of irradiance `F` (W/m²) on a
//! plane *normal to the beam*, entering the lit face at cosine μ0. At depth `z` the beam has travelled
//! `z/μ0`, so its normal irradiance is `F·e^{−σt z/μ0}`; scattering with phase function `Λ/4π` puts
//! `σt·(Λ/4π)·F·e^{−σt z/μ0}` W/(m³·sr) into the view direction, which is attenuated by `e^{−σt s}` over the
//! path length `s` back to the face the eye is on.

use std::f64::consts::PI;

use crate::model::{
    Albedo, Cosine, IrradianceConvention, OpticalThickness, SlabParameterError,
    single_scattered_reflected_radiance, single_scattered_transmitted_radiance,
};

/// Nodes and weights of the `n`-point Gauss–Legendre rule on [−1, 1] (Newton iteration on `P_n`).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut rule = Vec::with_capacity(n);
    for i in 0..n {
        // Tricomi's initial guess for the i-th root, then Newton to machine precision.
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut derivative = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let p_n = if n == 0 { 1.0 } else { p1 };
            let p_n_minus_1 = p0;
            derivative = n as f64 * (x * p_n - p_n_minus_1) / (x * x - 1.0);
            let step = p_n / derivative;
            x -= step;
            if step.abs() <= 1e-16 {
                break;
            }
        }
        rule.push((x, 2.0 / ((1.0 - x * x) * derivative * derivative)));
    }
    rule
}

/// Composite Gauss–Legendre: `panels` equal panels on [a, b], `rule` on each.
pub fn integrate(
    rule: &[(f64, f64)],
    a: f64,
    b: f64,
    panels: usize,
    f: impl Fn(f64) -> f64,
) -> f64 {
    let width = (b - a) / panels as f64;
    let mut sum = 0.0;
    for panel in 0..panels {
        let centre = a + (panel as f64 + 0.5) * width;
        for &(x, w) in rule {
            sum += w * 0.5 * width * f(centre + 0.5 * width * x);
        }
    }
    sum
}

/// Single-scattered radiance (W/(m²·sr)) emerging at cosine `mu` on the lit face (`lit_side = true`) or the
/// far face, for a beam of normal irradiance `beam_normal_irradiance` (W/m²) at cosine `mu0`, by quadrature
/// along the view ray through a slab of thickness 1 m. Panels are sized so that the integrand's exponent
/// changes by at most 1/2 per panel; with 20 nodes per panel the rule is exact to rounding
/// (error ≤ (1/2)^40/40! relative per panel).
///
/// Along the ray the integrand is `e^{−(a + b s)}`; where it falls 750 e-folds below its largest value
/// (below the smallest `f64` relative to it) the path is cut, so that a thick slab or a grazing cosine
/// needs at most 1 500 panels (the panel count was capped at 10⁶ instead, silently losing the exactness).
/// The inputs are checked as the model's are; a `mu` so small that the view path overflows is refused
/// (`SlabParameterError::Cosine`).
pub fn single_scattered_radiance_by_view_ray_quadrature(
    optical_thickness: f64,
    albedo: f64,
    mu0: f64,
    mu: f64,
    beam_normal_irradiance: f64,
    lit_side: bool,
) -> Result<f64, SlabParameterError> {
    OpticalThickness::new(optical_thickness)?;
    Albedo::new(albedo)?;
    Cosine::new("mu0", mu0)?;
    Cosine::new("mu", mu)?;
    if !(beam_normal_irradiance.is_finite() && beam_normal_irradiance >= 0.0) {
        return Err(SlabParameterError::Irradiance(beam_normal_irradiance));
    }
    let thickness = 1.0; // m
    let extinction = optical_thickness / thickness; // σt, 1/m
    let path_length = thickness / mu; // through the slab along the view ray, m
    if !path_length.is_finite() {
        return Err(SlabParameterError::Cosine {
            name: "mu",
            value: mu,
        });
    }
    let rule = gauss_legendre(20);
    // The exponent's rate along s: σt (1 + μ/μ0) towards the lit face, σt (1 − μ/μ0) towards the far one
    // (the beam's depth shrinks as the view path grows), either sign.
    let rate = extinction
        * if lit_side {
            1.0 + mu / mu0
        } else {
            1.0 - mu / mu0
        };
    const NEGLIGIBLE_E_FOLDS: f64 = 750.0;
    let span = NEGLIGIBLE_E_FOLDS / rate.abs();
    let (start, end) = if span >= path_length {
        (0.0, path_length)
    } else if rate > 0.0 {
        (0.0, span) // largest at s = 0
    } else {
        (path_length - span, path_length) // largest at the end of the path
    };
    let panels = ((2.0 * rate.abs() * (end - start)).ceil() as usize).max(1);
    let integrand = |s: f64| {
        let depth = if lit_side { s * mu } else { thickness - s * mu };
        let beam = beam_normal_irradiance * (-extinction * depth / mu0).exp();
        extinction * albedo / (4.0 * PI) * beam * (-extinction * s).exp()
    };
    Ok(integrate(&rule, start, end, panels, integrand))
}

/// Emergent single-scattered and directly transmitted flux per unit slab area for a beam of unit normal
/// irradiance, from the closed forms of [`crate::model`] integrated over both hemispheres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluxBalance {
    /// Flux incident on unit slab area, `μ0` (W/m² for unit normal irradiance).
    pub incident: f64,
    /// Directly transmitted flux `μ0·e^{−τ1/μ0}`.
    pub direct: f64,
    /// `2π∫ L+(μ) μ dμ` times the inserted irradiance.
    pub reflected: f64,
    /// `2π∫ L−(μ) μ dμ` times the inserted irradiance.
    pub transmitted: f64,
    /// |coarse − fine| of the two quadrature levels (the fine result is reported): a bound on the fine
    /// level's error since composite Gauss–Legendre converges faster than geometrically.
    pub quadrature_error_estimate: f64,
    /// Number of integrand evaluations summed at the fine level (for a rounding bound `n·ε·incident`).
    pub evaluations: usize,
}

/// Integrates eqs. (4)–(5) over the hemispheres by Gauss–Legendre in `u = ln μ` on
/// `[ln 10⁻¹², 0]` (the boundary layer at μ ≈ τ1 becomes a smooth O(1) feature in `u`). The truncated tail
/// is below `2π·(1/4π)·(10⁻¹²)²/2 < 10⁻²⁴` since `L± ≤ Λ/4π` per unit irradiance (eq. 4: `μ0/(μ+μ0)·(1−e^{…}) ≤ 1`;
/// eq. 5 is `Λ/4π·∫₀^τ1 e^{−t/μ0} e^{−(τ1−t)/μ} dt/μ ≤ Λ/4π`), far below any tolerance used.
pub fn flux_balance(
    optical_thickness: OpticalThickness,
    albedo: Albedo,
    mu0: Cosine,
    convention: IrradianceConvention,
) -> FluxBalance {
    let irradiance = convention.inserted_irradiance(1.0, mu0);
    let lower = (1e-12f64).ln();
    let rule = gauss_legendre(16);
    let hemisphere = |panels: usize, reflect: bool| {
        2.0 * PI
            * integrate(&rule, lower, 0.0, panels, |u| {
                let mu = u.exp();
                let Ok(mu) = Cosine::new("mu", mu.min(1.0)) else {
                    return 0.0;
                };
                let radiance = if reflect {
                    single_scattered_reflected_radiance(optical_thickness, albedo, mu0, mu)
                } else {
                    single_scattered_transmitted_radiance(optical_thickness, albedo, mu0, mu)
                };
                // dμ = μ du, and the flux weight is another μ.
                radiance * mu.get() * mu.get()
            })
            * irradiance
    };
    let coarse_panels = 64;
    let coarse = hemisphere(coarse_panels, true) + hemisphere(coarse_panels, false);
    let reflected = hemisphere(2 * coarse_panels, true);
    let transmitted = hemisphere(2 * coarse_panels, false);
    let m0 = mu0.get();
    FluxBalance {
        incident: m0,
        direct: m0 * (-optical_thickness.get() / m0).exp(),
        reflected,
        transmitted,
        quadrature_error_estimate: (coarse - reflected - transmitted).abs(),
        evaluations: 2 * 2 * coarse_panels * rule.len(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        // An n-point rule is exact for degree 2n−1; rounding of ~n terms bounds the error by ~n·ε.
        let rule = gauss_legendre(16);
        let integral = integrate(&rule, 0.0, 1.0, 1, |x| x.powi(31));
        assert!((integral - 1.0 / 32.0).abs() < 1e-14);
        let weights: f64 = rule.iter().map(|&(_, w)| w).sum();
        assert!((weights - 2.0).abs() < 1e-14);
    }
}
