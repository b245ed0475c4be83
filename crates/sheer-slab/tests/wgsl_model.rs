//! The WGSL model (`slab_shapes` in `shaders/thin_slab.wgsl`, evaluated by a compute shader on the adapter
//! the renderer picks) against the `f64` reference of `sheer_slab::model` over the whole domain the
//! renderer uses: τ1 in (0, 10], μ, μ0 in [10⁻⁶, 1] (the shader's cosine floor), including μ = μ0 exactly,
//! neighbours of the diagonal one f32 ulp apart, and grazing angles. No NaN or Inf may appear.
//!
//! Without any adapter this fails, unless `SHEER_SKIP_GPU_TESTS=1`.

use sheer_slab::model::{
    Albedo, Cosine, OpticalThickness, direct_transmission, single_scattered_reflected_radiance,
    single_scattered_transmitted_radiance,
};
use sheer_slab::render::{HeadlessRenderer, RenderError, gpu_tests_may_be_skipped};

fn samples() -> Vec<[f32; 3]> {
    let taus = [1e-6f32, 1e-3, 0.05, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0];
    let cosines = [1e-6f32, 1e-4, 0.01, 0.1, 0.3, 0.5, 0.7, 0.9, 0.999, 1.0];
    let mut samples = Vec::new();
    for &tau in &taus {
        for &mu0 in &cosines {
            for &mu in &cosines {
                samples.push([tau, mu0, mu]);
            }
            // The diagonal and its f32 neighbours (the paper's 0/0 point).
            let up = f32::from_bits(mu0.to_bits() + 1).min(1.0);
            let down = f32::from_bits(mu0.to_bits() - 1);
            for mu in [mu0, up, down, mu0 * (1.0 + 1e-4), mu0 * (1.0 - 1e-3)] {
                samples.push([tau, mu0, mu.min(1.0)]);
            }
        }
    }
    // Deterministic pseudo-random samples (64-bit LCG, Knuth's MMIX constants).
    let mut state: u64 = 0x5eed_1234_abcd_ef01;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..4096 {
        let tau = 10f64.powf(-6.0 + 7.0 * next()).min(10.0) as f32;
        let mu0 = 10f64.powf(-6.0 * next() * next()) as f32;
        let mu = if next() < 0.2 {
            mu0
        } else {
            10f64.powf(-6.0 * next() * next()) as f32
        };
        samples.push([tau, mu0.max(1e-6), mu.max(1e-6)]);
    }
    samples
}

#[test]
fn wgsl_model_matches_f64_reference_and_stays_finite() {
    let mut renderer = match HeadlessRenderer::new(8, 8) {
        Ok(renderer) => renderer,
        Err(error @ RenderError::NoAdapter { .. }) if gpu_tests_may_be_skipped() => {
            eprintln!("skipping GPU test (SHEER_SKIP_GPU_TESTS=1): {error}");
            return;
        }
        Err(error) => {
            panic!("GPU tests need an adapter (set SHEER_SKIP_GPU_TESTS=1 to skip): {error}")
        }
    };
    let samples = samples();
    let gpu = renderer.evaluate_shader_model(&samples).unwrap();
    assert_eq!(gpu.len(), samples.len());
    let four_pi = 4.0 * std::f64::consts::PI;
    let unit = Albedo::new(1.0).unwrap();
    let mut worst = [0.0f64; 3];
    for (&[tau, mu0, mu], values) in samples.iter().zip(&gpu) {
        let (t, c0, c) = (
            OpticalThickness::new(f64::from(tau)).unwrap(),
            Cosine::new("mu0", f64::from(mu0)).unwrap(),
            Cosine::new("mu", f64::from(mu)).unwrap(),
        );
        let reference = [
            single_scattered_reflected_radiance(t, unit, c0, c) * four_pi,
            single_scattered_transmitted_radiance(t, unit, c0, c) * four_pi,
            direct_transmission(t, c),
        ];
        // Tolerance from WGSL's accuracy rules (exp: 3 + 2|x| ulp, division 2.5 ulp, others correctly
        // rounded): with a = τ1/μ, b = τ1/μ0, each exponential is good to (3 + 4.5·arg) ε including its
        // argument's rounding; differences of exponentials are taken where they amplify errors at most
        // 1/(1 − e^{−1/2}) = 2.54 times; the φ series and the remaining products add < 20 ε. Altogether
        // (40 + 12(a + b)) ε relative. Absolute 1e-30: f32 flushes results below 1.2e-38, and factors up
        // to τ1/μ ≤ 1e7 can scale such a flushed intermediate.
        let (a, b) = (
            f64::from(tau) / f64::from(mu),
            f64::from(tau) / f64::from(mu0),
        );
        let relative = (40.0 + 12.0 * (a + b)) * f64::from(f32::EPSILON);
        for k in 0..3 {
            let value = f64::from(values[k]);
            assert!(
                value.is_finite() && value >= 0.0,
                "tau1={tau} mu0={mu0} mu={mu}: component {k} = {value}"
            );
            let error = (value - reference[k]).abs();
            let tolerance = relative * reference[k].abs() + 1e-30;
            assert!(
                error <= tolerance,
                "tau1={tau} mu0={mu0} mu={mu}: component {k}: WGSL {value:e} vs f64 {:e} (tolerance {tolerance:e})",
                reference[k]
            );
            if reference[k] > 1e-20 {
                worst[k] = worst[k].max(error / reference[k]);
            }
        }
    }
    println!(
        "{} samples; worst relative error (values > 1e-20): eq.4 {:e}, eq.5 {:e}, alpha {:e}",
        samples.len(),
        worst[0],
        worst[1],
        worst[2]
    );
}
