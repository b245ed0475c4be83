//! Monte Carlo photon transport against the deterministic all-orders solver: binned emergent fluxes
//! must agree within 4 standard errors, and the simulation must not depend on the rayon thread count.

use sheer_transport::quadrature::gauss_legendre;
use sheer_transport::{
    SlabSolver, TransportError, simulate_photons, single_scattered_reflected_radiance,
    single_scattered_transmitted_radiance,
};

/// Single-scattering-only flux `2π ∫ L₁ μ dμ` over a band (eqs. (4)–(5)), by 32-point Gauss.
fn single_scattering_band_flux(
    tau1: f64,
    albedo: f64,
    mu0: f64,
    band: (f64, f64),
    reflected: bool,
) -> f64 {
    let (nodes, weights) = gauss_legendre(32, band.0, band.1);
    let integral: f64 = nodes
        .iter()
        .zip(&weights)
        .map(|(&mu, &w)| {
            let radiance = if reflected {
                single_scattered_reflected_radiance(tau1, albedo, mu0, mu).unwrap()
            } else {
                single_scattered_transmitted_radiance(tau1, albedo, mu0, mu).unwrap()
            };
            w * mu * radiance
        })
        .sum();
    2.0 * std::f64::consts::PI * integral
}

#[test]
fn monte_carlo_binned_fluxes_agree_with_solver() {
    // Per bin, the Monte Carlo estimate is binomial with standard error σ = μ0 √(p(1−p)/N). The solver's
    // binned flux is accurate to ~1e-6 relative (tests/solver.rs), negligible against σ ≳ 1e-4 here.
    // 4σ per comparison: with 2 × 10 bins × 3 cases the chance that an unbiased run fails anywhere is
    // ~60 × 6.3e-5 ≈ 0.4 %, and the seed is fixed, so the outcome is reproducible.
    let cases = [(1.0, 0.9, 0.6), (0.2, 1.0, 0.3), (4.0, 0.99, 1.0)];
    let photons = 1_000_000;
    for (case, &(tau1, albedo, mu0)) in cases.iter().enumerate() {
        let tally = simulate_photons(tau1, albedo, mu0, photons, 10, 0x5eed + case as u64).unwrap();
        let solution = SlabSolver::new(tau1, albedo).unwrap().solve(mu0).unwrap();
        let mut single_scattering_rejected = false;
        for bin in 0..tally.bins() {
            let (low, high) = tally.bin_band(bin);
            for (reflected, count) in [
                (true, tally.reflected[bin]),
                (false, tally.transmitted[bin]),
            ] {
                let (estimate, error) = tally.flux_with_error(count).unwrap();
                let exact = solution.flux_between(low, high, reflected).unwrap();
                assert!(
                    (estimate - exact).abs() < 4.0 * error,
                    "tau1 {tau1} albedo {albedo} mu0 {mu0} band [{low}, {high}] reflected \
                     {reflected}: MC {estimate} ± {error}, solver {exact}"
                );
                let single = single_scattering_band_flux(tau1, albedo, mu0, (low, high), reflected);
                single_scattering_rejected |= (estimate - single).abs() > 4.0 * error;
            }
        }
        // Power: the same comparison must reject the single-scattering model, or it could not fail.
        assert!(
            single_scattering_rejected,
            "case {case} cannot tell orders apart"
        );
        let (direct, error) = tally.flux_with_error(tally.direct).unwrap();
        assert!((direct - solution.direct_transmitted_flux()).abs() < 4.0 * error);
        let (absorbed, error) = tally.flux_with_error(tally.absorbed).unwrap();
        assert!((absorbed - solution.absorbed_flux()).abs() < 4.0 * error.max(1e-12));
    }
}

#[test]
fn monte_carlo_is_independent_of_thread_count() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| simulate_photons(1.0, 0.8, 0.5, 300_000, 8, 7).unwrap())
    };
    assert_eq!(run(1), run(3));
}

#[test]
fn monte_carlo_rejects_bad_input() {
    assert!(matches!(
        simulate_photons(1.0, 0.8, 0.5, 0, 8, 1),
        Err(TransportError::PhotonCount)
    ));
    assert!(matches!(
        simulate_photons(-1.0, 0.8, 0.5, 10, 8, 1),
        Err(TransportError::OpticalThickness(_))
    ));
    // No bins, or so many that the tallies cannot be allocated ("capacity overflow" before).
    for bins in [0, sheer_transport::monte_carlo::MAX_BINS + 1, usize::MAX] {
        assert!(matches!(
            simulate_photons(1.0, 0.8, 0.5, 10, bins, 1),
            Err(TransportError::Bins(b)) if b == bins
        ));
    }
    // A count beyond the photons launched has no flux (its variance came out negative: NaN).
    let tally = simulate_photons(1.0, 0.8, 0.5, 10, 8, 1).unwrap();
    assert!(matches!(
        tally.flux_with_error(11),
        Err(TransportError::Count {
            count: 11,
            photons: 10
        })
    ));
    assert!(tally.flux_with_error(10).is_ok());
}
