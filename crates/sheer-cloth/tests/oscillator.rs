//! The single spring–mass oscillator: period, energy behaviour and stability limits of every method,
//! against the linear stability analysis of each integrator.
//!
//! For `ẍ = −ω² x` the methods are linear maps whose eigenvalues are known in closed form, so every
//! tolerance below is derived from them rather than tuned.

mod common;

use common::{displacement, mean_period, oscillator, upward_zero_crossings};
use sheer_cloth::{Method, StepError};
use std::f64::consts::PI;

const MASS: f64 = 1.0; // kg
const STIFFNESS: f64 = 100.0; // N/m
const OMEGA: f64 = 10.0; // rad/s = sqrt(STIFFNESS / MASS)
const AMPLITUDE: f64 = 0.01; // m

fn run(method: Method, h: f64, steps: usize) -> (Vec<f64>, Vec<f64>) {
    let mut sim = oscillator(method, MASS, STIFFNESS, 0.0, AMPLITUDE);
    let mut times = vec![0.0];
    let mut x = vec![displacement(&sim)];
    for _ in 0..steps {
        sim.step(h).expect("stable step");
        times.push(sim.time());
        x.push(displacement(&sim));
    }
    (times, x)
}

#[test]
fn period_matches_two_pi_sqrt_m_over_k_with_each_methods_predicted_phase_error() {
    let h = 1e-3; // ωh = 0.01
    let exact = 2.0 * PI * (MASS / STIFFNESS).sqrt();
    // Symplectic Euler and Störmer/velocity Verlet: cos(ω̃h) = 1 − (ωh)²/2.
    let symplectic = 2.0 * PI * h / (1.0 - (OMEGA * h).powi(2) / 2.0).acos();
    // Backward Euler (and XPBD, identical on one linear constraint): eigenvalues 1/(1 ± iωh).
    let backward = 2.0 * PI * h / (OMEGA * h).atan();
    for (method, predicted) in [
        (Method::SymplecticEuler { substeps: 1 }, symplectic),
        (Method::Verlet { substeps: 1 }, symplectic),
        (
            Method::ImplicitEuler {
                substeps: 1,
                cg_max_iterations: 10,
                cg_tolerance: 1e-14,
            },
            backward,
        ),
        (Method::SmallStepsXpbd { substeps: 1 }, backward),
    ] {
        let (times, x) = run(method, h, 20_000); // 31.8 periods
        let period = mean_period(&upward_zero_crossings(&times, &x));
        // The sampled motion is an exact (possibly decaying) sinusoid, so only the linear interpolation
        // of the crossings errs, by O((ωh)²) of a step at worst: 1e-4·h, averaged over 31 periods.
        assert!(
            (period - predicted).abs() < 1e-4 * h,
            "{}: period {period} vs predicted {predicted}",
            method.name()
        );
        // And so the period matches 2π√(m/k) up to the method's own phase error.
        assert!(
            (period - exact).abs() <= (predicted - exact).abs() + 1e-4 * h,
            "{}: period {period} vs 2π√(m/k) = {exact}",
            method.name()
        );
    }
    // The phase errors themselves are tiny at ωh = 0.01: (ωh)²/24 and (ωh)²/3 relative.
    assert!((symplectic / exact - 1.0).abs() < 5e-6);
    assert!((backward / exact - 1.0).abs() < 4e-5);
}

#[test]
fn xpbd_on_one_linear_constraint_is_backward_euler() {
    // Macklin et al. 2016 §4: one XPBD iteration on a linear constraint is one backward Euler step.
    let h = 0.05;
    let implicit = Method::ImplicitEuler {
        substeps: 1,
        cg_max_iterations: 10,
        cg_tolerance: 1e-15,
    };
    let (_, x_implicit) = run(implicit, h, 400);
    let (_, x_xpbd) = run(Method::SmallStepsXpbd { substeps: 1 }, h, 400);
    for (a, b) in x_implicit.iter().zip(&x_xpbd) {
        assert!((a - b).abs() < 1e-12 * AMPLITUDE.max(1.0), "{a} vs {b}");
    }
}

fn energy(sim: &sheer_cloth::Simulation) -> f64 {
    sim.total_energy()
}

#[test]
fn symplectic_methods_keep_energy_bounded_over_ten_thousand_periods() {
    let h = 0.01; // ωh = 0.1
    let c = (OMEGA * h).powi(2) / 4.0;
    let steps = (10_000.0 * 2.0 * PI / OMEGA / h).ceil() as usize;
    // Each method conserves a quadratic form exactly (checked numerically independently):
    // symplectic Euler Q = v² + ω²x² − hω²xv, so E/E₀ stays within 1 ± ωh/(2 − ωh);
    // velocity Verlet Q = v² + ω²x²(1 − (ωh)²/4), so E/E₀ stays within [1 − (ωh)²/4, 1].
    let symplectic_form =
        |x: f64, v: f64| v * v + OMEGA * OMEGA * x * x - h * OMEGA * OMEGA * x * v;
    let verlet_form = |x: f64, v: f64| v * v + OMEGA * OMEGA * x * x * (1.0 - c);
    type Invariant<'a> = &'a dyn Fn(f64, f64) -> f64;
    let cases: [(Method, f64, Invariant<'_>); 2] = [
        (
            Method::SymplecticEuler { substeps: 1 },
            OMEGA * h / (2.0 - OMEGA * h),
            &symplectic_form,
        ),
        (Method::Verlet { substeps: 1 }, c, &verlet_form),
    ];
    for (method, bound, invariant) in cases {
        let mut sim = oscillator(method, MASS, STIFFNESS, 0.0, AMPLITUDE);
        let e0 = energy(&sim);
        let q0 = invariant(displacement(&sim), 0.0);
        let mut worst = 0.0f64;
        for _ in 0..steps {
            sim.step(h).expect("stable");
            worst = worst.max((energy(&sim) / e0 - 1.0).abs());
        }
        assert!(
            worst <= bound * (1.0 + 1e-6),
            "{}: energy error {worst} above the bound {bound}",
            method.name()
        );
        // No drift: after 10⁴ periods the invariant holds to accumulated rounding (√steps · 1e-16).
        let q = invariant(displacement(&sim), sim.velocities()[1].x);
        assert!(
            (q / q0 - 1.0).abs() < 1e-10,
            "{}: invariant drifted by {}",
            method.name(),
            q / q0 - 1.0
        );
    }
}

#[test]
fn explicit_euler_gains_energy_at_every_time_step_as_predicted() {
    // Without damping |z|² = 1 + (ωh)² exactly, so E_n = E₀ (1 + (ωh)²)^n for every h.
    for h in [1e-5, 1e-4, 1e-3, 1e-2, 0.05] {
        let mut sim = oscillator(
            Method::ExplicitEuler { substeps: 1 },
            MASS,
            STIFFNESS,
            0.0,
            AMPLITUDE,
        );
        let e0 = energy(&sim);
        // As many steps as keep the growth below 10⁴ (the spring stays linear, no divergence).
        let steps = (4.0 * 10f64.ln() / (1.0 + (OMEGA * h).powi(2)).ln()).min(200.0) as i32;
        for _ in 0..steps {
            sim.step(h)
                .expect("growth stays below the divergence limits");
        }
        let predicted = (1.0 + (OMEGA * h).powi(2)).powi(steps);
        let measured = energy(&sim) / e0;
        assert!(measured > 1.0, "h = {h}: explicit Euler lost energy");
        assert!(
            (measured / predicted - 1.0).abs() < 1e-9,
            "h = {h}: energy ratio {measured} vs predicted {predicted}"
        );
    }
}

#[test]
fn damped_explicit_euler_is_stable_only_below_two_zeta_over_omega() {
    // With damping ratio ζ the eigenvalues 1 + hλ satisfy |z|² = 1 − 2hζω + (ωh)², so the method
    // is stable exactly for h ≤ 2ζ/ω.
    let zeta = 0.1;
    let damping = 2.0 * zeta * OMEGA * MASS; // N·s/m
    let limit = 2.0 * zeta / OMEGA; // 0.02 s
    let amplitude = 1e-6; // small enough to stay linear while growing 1000-fold
    let steps = 5000;
    let final_amplitude = |h: f64| {
        let mut sim = oscillator(
            Method::ExplicitEuler { substeps: 1 },
            MASS,
            STIFFNESS,
            damping,
            amplitude,
        );
        for _ in 0..steps {
            sim.step(h).expect("within the divergence limits");
        }
        // Amplitude in the energy norm, m.
        (displacement(&sim).powi(2) + (sim.velocities()[1].x / OMEGA).powi(2)).sqrt()
    };
    for factor in [0.95, 1.05] {
        let h = factor * limit;
        let modulus = (1.0 - 2.0 * h * zeta * OMEGA + (OMEGA * h).powi(2)).sqrt();
        let predicted = modulus.powi(steps);
        let ratio = final_amplitude(h) / amplitude;
        // The energy norm differs from the eigenbasis norm by the eigenvector condition number,
        // 1/sqrt(1 − ζ²) ≈ 1.005 here, so a factor of 2 is a generous envelope.
        assert!(
            ratio < 2.0 * predicted && ratio > 0.5 * predicted,
            "h = {factor}·2ζ/ω: amplitude ratio {ratio} vs predicted {predicted}"
        );
        if factor < 1.0 {
            assert!(ratio < 0.02, "did not decay below the limit: {ratio}");
        } else {
            assert!(ratio > 50.0, "did not grow above the limit: {ratio}");
        }
    }
}

#[test]
fn symplectic_euler_and_verlet_diverge_exactly_above_two_over_omega() {
    let limit = 2.0 / OMEGA;
    for method in [
        Method::SymplecticEuler { substeps: 1 },
        Method::Verlet { substeps: 1 },
    ] {
        // Just below: bounded by the conserved quadratic form, |x| ≤ A/sqrt(1 − hω/2) (symplectic
        // Euler) — the same recurrence for positions as Störmer–Verlet.
        let h = 0.99 * limit;
        let mut sim = oscillator(method, MASS, STIFFNESS, 0.0, AMPLITUDE);
        let bound = AMPLITUDE / (1.0 - h * OMEGA / 2.0).sqrt();
        for _ in 0..100_000 {
            sim.step(h).expect("stable just below 2/ω");
            assert!(displacement(&sim).abs() <= bound * (1.0 + 1e-9));
        }
        // Just above: |z| > 1 and the run is caught as diverged, with the last good state kept.
        let h = 1.01 * limit;
        let mut sim = oscillator(method, MASS, STIFFNESS, 0.0, AMPLITUDE);
        let mut diverged = false;
        for _ in 0..1000 {
            let before = sim.positions().to_vec();
            match sim.step(h) {
                Ok(_) => {}
                Err(StepError::Diverged { .. }) => {
                    assert_eq!(before, sim.positions(), "state changed by a diverged step");
                    assert!(sim.positions().iter().all(|p| p.is_finite()));
                    diverged = true;
                    break;
                }
                Err(other) => panic!("unexpected {other}"),
            }
        }
        assert!(diverged, "{} did not diverge above 2/ω", method.name());
    }
}

#[test]
fn implicit_euler_and_xpbd_stay_bounded_at_a_hundred_times_the_explicit_limit() {
    let h = 100.0 * 2.0 / OMEGA;
    for method in [
        Method::ImplicitEuler {
            substeps: 1,
            cg_max_iterations: 10,
            cg_tolerance: 1e-12,
        },
        Method::Xpbd {
            substeps: 1,
            iterations: 1,
        },
        Method::SmallStepsXpbd { substeps: 1 },
    ] {
        let mut sim = oscillator(method, MASS, STIFFNESS, 0.0, AMPLITUDE);
        for _ in 0..1000 {
            sim.step(h).expect("unconditionally stable");
            // Backward Euler's |z| = 1/sqrt(1 + (ωh)²) < 1: the amplitude can only shrink.
            assert!(displacement(&sim).abs() <= AMPLITUDE * (1.0 + 1e-12));
        }
    }
}
