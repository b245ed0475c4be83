//! Henyey–Greenstein single scattering (Blinn 1982's generalisation of eqs. (4)–(5)): exact reduction to
//! the isotropic formulas at g = 0, phase-function normalisation, and agreement with brute-force
//! quadrature along the beam using explicit 3-D directions.

use sheer_transport::quadrature::{composite_gauss_legendre, gauss_legendre};
use sheer_transport::{
    TransportError, henyey_greenstein_phase, single_scattered_reflected_radiance,
    single_scattered_reflected_radiance_hg, single_scattered_transmitted_radiance,
    single_scattered_transmitted_radiance_hg,
};
use std::f64::consts::PI;

#[test]
fn zero_asymmetry_is_exactly_isotropic() {
    for tau1 in [0.01, 0.7, 5.0] {
        for mu0 in [0.05, 0.5, 1.0] {
            for mu in [0.0, 0.2, 0.5, 1.0] {
                for azimuth in [0.0, 1.0, PI] {
                    assert_eq!(
                        single_scattered_reflected_radiance_hg(tau1, 0.8, mu0, mu, 0.0, azimuth)
                            .unwrap(),
                        single_scattered_reflected_radiance(tau1, 0.8, mu0, mu).unwrap()
                    );
                    assert_eq!(
                        single_scattered_transmitted_radiance_hg(tau1, 0.8, mu0, mu, 0.0, azimuth)
                            .unwrap(),
                        single_scattered_transmitted_radiance(tau1, 0.8, mu0, mu).unwrap()
                    );
                }
            }
        }
    }
}

#[test]
fn phase_function_is_normalised_with_mean_cosine_g() {
    // 2π ∫_{-1}^{1} p(x) dx = 1 and 2π ∫ x p(x) dx = g. The forward peak of width ~(1 − g) is resolved
    // (towards x = −1 for g < 0) by panels graded towards both ends (64-point Gauss each); the error is
    // below 1e-12.
    let mut breaks = vec![-1.0];
    for k in (1..=8).rev() {
        breaks.push(-1.0 + 10f64.powi(-k));
    }
    breaks.push(0.0);
    for k in 1..=8 {
        breaks.push(1.0 - 10f64.powi(-k));
    }
    breaks.push(1.0);
    let (nodes, weights) = composite_gauss_legendre(&breaks, 64);
    for g in [-0.9, -0.3, 0.0, 0.5, 0.9] {
        let mut norm = 0.0;
        let mut mean = 0.0;
        for (&x, &w) in nodes.iter().zip(&weights) {
            let p = henyey_greenstein_phase(g, x).unwrap();
            norm += 2.0 * PI * w * p;
            mean += 2.0 * PI * w * x * p;
        }
        assert!((norm - 1.0).abs() < 1e-12, "g {g}: norm {norm}");
        assert!((mean - g).abs() < 1e-12, "g {g}: mean {mean}");
    }
}

/// Brute force: explicit unit vectors for beam and viewer, HG phase from their dot product, and the
/// depth integral of the attenuated singly scattered beam by 200-point Gauss.
fn brute_force(
    tau1: f64,
    albedo: f64,
    mu0: f64,
    mu: f64,
    g: f64,
    azimuth: f64,
    reflected: bool,
) -> f64 {
    let sin0 = (1.0 - mu0 * mu0).sqrt();
    let sin = (1.0 - mu * mu).sqrt();
    let beam = [sin0, 0.0, -mu0];
    let viewer = [
        sin * azimuth.cos(),
        sin * azimuth.sin(),
        if reflected { mu } else { -mu },
    ];
    let cos_angle: f64 = beam.iter().zip(&viewer).map(|(a, b)| a * b).sum();
    let g2 = g * g;
    let phase = (1.0 - g2) / (4.0 * PI * (1.0 + g2 - 2.0 * g * cos_angle).powf(1.5));
    let (depths, weights) = gauss_legendre(200, 0.0, tau1);
    depths
        .iter()
        .zip(&weights)
        .map(|(&t, &w)| {
            let escape = if reflected { t } else { tau1 - t };
            w * albedo * phase * (-t / mu0).exp() * (-escape / mu).exp() / mu
        })
        .sum()
}

#[test]
fn closed_form_matches_brute_force_quadrature() {
    // The depth integrand is a single exponential; 200-point Gauss on [0, τ1 ≤ 3] with decay rate
    // ≤ 1/0.1 + 1/0.15 integrates it to ~1e-15 relative, so 1e-12 allows for rounding in the sum.
    for g in [-0.7, 0.3, 0.85] {
        for tau1 in [0.05, 0.5, 3.0] {
            for (mu0, mu) in [(0.15, 0.9), (0.6, 0.6), (1.0, 0.1), (0.4, 0.75)] {
                for azimuth in [0.0, 0.8, 2.0, PI] {
                    let ours =
                        single_scattered_reflected_radiance_hg(tau1, 0.9, mu0, mu, g, azimuth)
                            .unwrap();
                    let brute = brute_force(tau1, 0.9, mu0, mu, g, azimuth, true);
                    assert!(
                        ((ours - brute) / brute).abs() < 1e-12,
                        "refl {ours} vs {brute}"
                    );
                    let ours =
                        single_scattered_transmitted_radiance_hg(tau1, 0.9, mu0, mu, g, azimuth)
                            .unwrap();
                    let brute = brute_force(tau1, 0.9, mu0, mu, g, azimuth, false);
                    assert!(
                        ((ours - brute) / brute).abs() < 1e-12,
                        "trans {ours} vs {brute}"
                    );
                }
            }
        }
    }
}

#[test]
fn forward_scattering_favours_the_straight_through_direction() {
    // With g > 0 the unlit side is brightest looking straight along the beam (Δφ = 0, μ = μ0) and the
    // lit side is darker than isotropic in the backscatter direction (Δφ = π, μ = μ0).
    let forward = single_scattered_transmitted_radiance_hg(0.5, 1.0, 0.7, 0.7, 0.8, 0.0).unwrap();
    let sideways = single_scattered_transmitted_radiance_hg(0.5, 1.0, 0.7, 0.7, 0.8, PI).unwrap();
    assert!(forward > 10.0 * sideways);
    let back = single_scattered_reflected_radiance_hg(0.5, 1.0, 0.7, 0.7, 0.8, PI).unwrap();
    assert!(back < single_scattered_reflected_radiance(0.5, 1.0, 0.7, 0.7).unwrap());
    // Mirror symmetry in azimuth.
    let plus = single_scattered_reflected_radiance_hg(0.5, 1.0, 0.3, 0.8, 0.5, 1.1).unwrap();
    let minus = single_scattered_reflected_radiance_hg(0.5, 1.0, 0.3, 0.8, 0.5, -1.1).unwrap();
    assert_eq!(plus, minus);
}

#[test]
fn asymmetry_outside_open_interval_is_an_error() {
    for g in [-1.0, 1.0, f64::NAN] {
        assert!(matches!(
            single_scattered_reflected_radiance_hg(1.0, 1.0, 0.5, 0.5, g, 0.0),
            Err(TransportError::Asymmetry(_))
        ));
    }
    assert!(matches!(
        single_scattered_transmitted_radiance_hg(1.0, 1.0, 0.5, 0.5, 0.2, f64::INFINITY),
        Err(TransportError::Azimuth(_))
    ));
}
