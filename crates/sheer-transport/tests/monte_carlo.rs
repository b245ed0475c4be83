//! Monte Carlo photon transport against the deterministic all-orders solver: binned emergent fluxes
//! must agree within 4 standard errors, and the simulation must not depend on the rayon thread count.
//! The two-slab simulation: limits it must reproduce exactly or statistically, its error estimates,
//! determinism and typed errors (its comparison with the renderer's approximation is in
//! `tests/two_slabs.rs`).

use sheer_transport::quadrature::gauss_legendre;
use sheer_transport::{
    SlabLayer, SlabSolver, TransportError, simulate_photons, simulate_two_slabs,
    single_scattered_reflected_radiance, single_scattered_transmitted_radiance,
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

const FRONT: SlabLayer = SlabLayer {
    tau1: 1.0,
    albedo: 0.9,
};
const BACK: SlabLayer = SlabLayer {
    tau1: 2.0,
    albedo: 0.99,
};

#[test]
fn two_slabs_black_back_slab_scatters_nothing() {
    let black = SlabLayer {
        albedo: 0.0,
        ..BACK
    };
    let tally = simulate_two_slabs(FRONT, black, 0.7, 200_000, 8, 3).unwrap();
    for face in [&tally.lit, &tally.far, &tally.lit_direct, &tally.far_direct] {
        assert!(face.counts.iter().all(|&c| c == 0), "{face:?}");
        assert_eq!(face.total_flux(), (0.0, 0.0));
    }
}

#[test]
fn two_slabs_black_front_slab_passes_only_the_direct_beam() {
    // Whatever interacts in a front slab of Λ = 0 is absorbed: every photon the back slab scatters
    // came in the unscattered beam, so the tallies equal their direct parts count for count, and no
    // photon leaves the back slab's near face twice.
    let black = SlabLayer {
        albedo: 0.0,
        ..FRONT
    };
    let tally = simulate_two_slabs(black, BACK, 0.7, 200_000, 8, 3).unwrap();
    assert_eq!(tally.far, tally.far_direct);
    assert_eq!(tally.lit, tally.lit_direct);
    assert_eq!(tally.lit.counts, tally.lit.squares);
    assert!(tally.lit.counts.iter().sum::<u64>() > 1000);
}

#[test]
fn two_slabs_with_a_vanishing_front_slab_is_the_back_slab_alone() {
    // τ1 = 1e-6 in front: about 1e-6 of the photons interact there, far below the statistics, so the back
    // slab's tallies are those of the back slab alone (simulate_photons) within 4 standard errors of
    // the difference of two independent runs, in every bin of both faces (2 × 10 comparisons: an
    // unbiased run fails with probability ≈ 20 × 6.3e-5 ≈ 0.1 %; fixed seeds).
    let thin = SlabLayer {
        tau1: 1e-6,
        albedo: 0.9,
    };
    let (mu0, photons, bins) = (0.6, 1_000_000, 10);
    let pair = simulate_two_slabs(thin, BACK, mu0, photons, bins, 11).unwrap();
    let alone = simulate_photons(BACK.tau1, BACK.albedo, mu0, photons, bins, 12).unwrap();
    for bin in 0..bins {
        for (face, two, count) in [
            ("lit", &pair.lit, alone.reflected[bin]),
            ("far", &pair.far, alone.transmitted[bin]),
        ] {
            let (a, sa) = two.band_flux(bin).unwrap();
            let (b, sb) = alone.flux_with_error(count).unwrap();
            assert!(
                (a - b).abs() < 4.0 * sa.hypot(sb),
                "{face} bin {bin}: two slabs {a} ± {sa}, one slab {b} ± {sb}"
            );
        }
    }
}

#[test]
fn two_slab_errors_follow_the_counts() {
    // A photon leaves the far face at most once: its counts are binomial, and the standard error is
    // √(p(1−p)/N) μ0. Between two bright slabs some photons leave the back slab's near face twice or
    // more (squares exceed counts), and the error accounts for it.
    let (mu0, photons) = (0.5, 300_000);
    let tally = simulate_two_slabs(FRONT, BACK, mu0, photons, 6, 5).unwrap();
    assert_eq!(tally.far.counts, tally.far.squares);
    for bin in 0..6 {
        let p = tally.far.counts[bin] as f64 / photons as f64;
        let (flux, error) = tally.far.band_flux(bin).unwrap();
        assert!((flux - mu0 * p).abs() < 1e-15);
        assert!((error - mu0 * (p * (1.0 - p) / photons as f64).sqrt()).abs() < 1e-15);
    }
    assert!(tally.far.band_flux(6).is_none());
    let lit = &tally.lit;
    assert!(lit.squares.iter().zip(&lit.counts).any(|(s, c)| s > c));
    assert!(lit.total_squares > lit.counts.iter().sum::<u64>());
    let (flux, error) = lit.total_flux();
    let n = photons as f64;
    let mean = lit.counts.iter().sum::<u64>() as f64 / n;
    let binomial = mu0 * (mean * (1.0 - mean) / n).sqrt();
    assert!((flux - mu0 * mean).abs() < 1e-15 && error > binomial);
}

#[test]
fn two_slabs_are_independent_of_thread_count() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| simulate_two_slabs(FRONT, BACK, 0.5, 300_000, 8, 7).unwrap())
    };
    assert_eq!(run(1), run(3));
}

#[test]
fn two_slabs_reject_bad_input() {
    let bad_tau = [0.0, -1.0, f64::NAN, f64::INFINITY];
    for tau1 in bad_tau {
        let layer = SlabLayer { tau1, ..FRONT };
        for (front, back) in [(layer, BACK), (FRONT, layer)] {
            assert!(matches!(
                simulate_two_slabs(front, back, 0.5, 10, 4, 1),
                Err(TransportError::OpticalThickness(_))
            ));
        }
    }
    for albedo in [-0.1, 1.5, f64::NAN] {
        let layer = SlabLayer { albedo, ..FRONT };
        for (front, back) in [(layer, BACK), (FRONT, layer)] {
            assert!(matches!(
                simulate_two_slabs(front, back, 0.5, 10, 4, 1),
                Err(TransportError::Albedo(_))
            ));
        }
    }
    for mu0 in [0.0, -0.5, 1.5, f64::NAN] {
        assert!(matches!(
            simulate_two_slabs(FRONT, BACK, mu0, 10, 4, 1),
            Err(TransportError::Cosine { name: "mu0", .. })
        ));
    }
    assert!(matches!(
        simulate_two_slabs(FRONT, BACK, 0.5, 0, 4, 1),
        Err(TransportError::PhotonCount)
    ));
    for bins in [0, sheer_transport::monte_carlo::MAX_BINS + 1] {
        assert!(matches!(
            simulate_two_slabs(FRONT, BACK, 0.5, 10, bins, 1),
            Err(TransportError::Bins(b)) if b == bins
        ));
    }
}
