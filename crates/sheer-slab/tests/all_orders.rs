//! The `all-orders` scattering model: the WGSL table lookup against the CPU sampler it mirrors (on the
//! GPU, lavapipe/llvmpipe in CI), the CPU model against sheer-transport's all-orders solver within the
//! table's stated interpolation error, and the typed errors of table loading and of τ1 outside the
//! table.
//!
//! Without any adapter the GPU test fails, unless `SHEER_SKIP_GPU_TESTS=1`.

use std::sync::Arc;

use glam::Vec3;
use sheer_slab::all_orders::{
    AllOrdersTable, Scattering, TableLoadError, default_table_path, diffuse_radiance,
    load_all_orders_table,
};
use sheer_slab::model::{Albedo, Cosine, Face, OpticalThickness};
use sheer_slab::render::{
    HeadlessRenderer, RenderError, ShadingError, ShadingParams, Texture2d, gpu_tests_may_be_skipped,
};
use sheer_transport::SlabSolver;

fn table() -> Arc<AllOrdersTable> {
    load_all_orders_table(default_table_path()).expect("the shipped table")
}

/// Largest difference of stored `ln f` between neighbouring nodes along each axis (τ1, Λ, μ0, μ): how
/// much an error in an interpolation weight can move the interpolated logarithm.
fn largest_steps(table: &AllOrdersTable) -> [f64; 4] {
    let spec = table.spec();
    let (nt, na, nc) = (spec.tau_count, spec.albedo_count, spec.cosine_count);
    let values = table.log_values();
    let at = |face: usize, t: usize, a: usize, k: usize, j: usize| {
        f64::from(values[(((face * nt + t) * na + a) * nc + k) * nc + j])
    };
    let mut steps = [0.0f64; 4];
    for face in 0..2 {
        for t in 0..nt {
            for a in 0..na {
                for k in 0..nc {
                    for j in 0..nc {
                        let here = at(face, t, a, k, j);
                        if t + 1 < nt {
                            steps[0] = steps[0].max((at(face, t + 1, a, k, j) - here).abs());
                        }
                        if a + 1 < na {
                            steps[1] = steps[1].max((at(face, t, a + 1, k, j) - here).abs());
                        }
                        if k + 1 < nc {
                            steps[2] = steps[2].max((at(face, t, a, k + 1, j) - here).abs());
                        }
                        if j + 1 < nc {
                            steps[3] = steps[3].max((at(face, t, a, k, j + 1) - here).abs());
                        }
                    }
                }
            }
        }
    }
    steps
}

/// A small deterministic generator (SplitMix64) for random samples.
struct SplitMix(u64);

impl SplitMix {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn wgsl_lookup_matches_the_cpu_sampler() {
    let mut renderer = match HeadlessRenderer::new(16, 16) {
        Ok(renderer) => renderer,
        Err(error @ RenderError::NoAdapter { .. }) if gpu_tests_may_be_skipped() => {
            eprintln!("skipping GPU test (SHEER_SKIP_GPU_TESTS=1): {error}");
            return;
        }
        Err(error) => panic!("GPU tests need an adapter: {error}"),
    };
    let table = table();
    let spec = table.spec();
    // Samples: every τ1 node and mid-cell, Λ and cosines at their ends, at nodes and between, plus
    // 4000 random points (cosines log-uniform down to the renderer's floor 1e-6 half the time).
    let mut samples: Vec<[f32; 4]> = Vec::new();
    let albedos = [0.0, 0.2, 0.5, 0.8, 0.9, 0.97, 0.995, 1.0];
    let cosines = [1e-6, 1e-3, 0.02, 0.0816, 0.3, 0.5, 0.77, 0.999, 1.0];
    for t in 0..(2 * spec.tau_count - 1) {
        let tau = spec.tau_at(0.5 * t as f64);
        for (i, &albedo) in albedos.iter().enumerate() {
            for (k, &mu0) in cosines.iter().enumerate() {
                let mu = cosines[(k + i + t) % cosines.len()];
                samples.push([tau as f32, albedo as f32, mu0 as f32, mu as f32]);
            }
        }
    }
    let mut random = SplitMix(7);
    for _ in 0..4000 {
        let tau = spec.tau_at(random.unit() * (spec.tau_count - 1) as f64);
        let albedo = 1.0 - random.unit().powi(2);
        let cosine = |r: &mut SplitMix| {
            if r.unit() < 0.5 {
                r.unit()
            } else {
                (1e-6f64).powf(r.unit())
            }
        };
        let (mu0, mu) = (cosine(&mut random).max(1e-6), cosine(&mut random).max(1e-6));
        samples.push([tau as f32, albedo as f32, mu0 as f32, mu as f32]);
    }
    let outputs = renderer
        .evaluate_shader_all_orders(&table, &samples)
        .unwrap();

    // Error budget of the f32 lookup for ln f (absolute), from the weights' errors times the largest
    // step of ln f between neighbouring nodes along each axis, plus the rounding of the sum:
    // * τ1: c = ln τ1 + τ1 with WGSL's log (absolute error < 2^-21 on [0.5, 2], 3 ulps elsewhere) and
    //   c0 rounded to f32, over the axis span 16.9 times 48 cells: weight error ≤ 4e-6;
    // * Λ: w = ln(1 + s(e^β − 1))/β; below x = 1/2 the series is relatively exact to a few ulps, above
    //   it log's 2^-21 absolute error plus 1 + x's rounding over β ≥ ln 1.5 gives 1.9e-6, times 20
    //   cells: weight error ≤ 4e-5;
    // * μ0, μ: √μ to 4 ulps times 14 cells: weight error ≤ 4e-6 each;
    // * the 16-term weighted sum in f32: 16 ε·max|ln f| (|ln f| ≤ 16).
    let [tau_step, albedo_step, mu0_step, mu_step] = largest_steps(&table);
    let epsilon = f64::from(f32::EPSILON);
    let log_tolerance =
        4e-6 * tau_step + 4e-5 * albedo_step + 4e-6 * (mu0_step + mu_step) + 16.0 * epsilon * 16.0;
    // L_m = Λ² μ0 e^{ln f}: exp adds (3 + 2|x|) ulps ≤ 35 ε and the products 3 ε, relative.
    let radiance_tolerance = log_tolerance + 38.0 * epsilon;
    println!(
        "largest steps of ln f (tau, albedo, mu0, mu) {tau_step:.3} {albedo_step:.3} {mu0_step:.3} \
         {mu_step:.3}; tolerance ln f {log_tolerance:.2e}, L_m relative {radiance_tolerance:.2e}"
    );
    let (min, max) = (spec.tau_min, spec.tau_max);
    let (mut worst_log, mut worst_relative) = (0.0f64, 0.0f64);
    for (sample, output) in samples.iter().zip(&outputs) {
        let [tau, albedo, mu0, mu] = sample.map(f64::from);
        // f32 τ1 at the table's ends may fall outside by rounding; the renderer's CPU path clamps the
        // same way.
        let tau = tau.clamp(min, max);
        for (face, column) in [
            (sheer_transport::TableFace::Reflected, 0),
            (sheer_transport::TableFace::Transmitted, 1),
        ] {
            let log_value = table
                .log_reduced_multiple_radiance(face, tau, albedo, mu0, mu)
                .unwrap();
            let radiance = albedo * albedo * mu0 * log_value.exp();
            let gpu_log = f64::from(output[column + 2]);
            let gpu_radiance = f64::from(output[column]);
            assert!(
                gpu_radiance.is_finite() && gpu_log.is_finite(),
                "{sample:?}"
            );
            let log_error = (gpu_log - log_value).abs();
            assert!(
                log_error <= log_tolerance,
                "{face:?} {sample:?}: ln f GPU {gpu_log} CPU {log_value}"
            );
            worst_log = worst_log.max(log_error);
            if radiance > 0.0 {
                let relative = (gpu_radiance - radiance).abs() / radiance;
                assert!(
                    relative <= radiance_tolerance,
                    "{face:?} {sample:?}: L_m GPU {gpu_radiance} CPU {radiance}"
                );
                worst_relative = worst_relative.max(relative);
            } else {
                assert_eq!(gpu_radiance, 0.0, "{sample:?}");
            }
        }
    }
    println!(
        "{} samples: worst |ln f| error {worst_log:.2e}, worst L_m relative error {worst_relative:.2e}",
        samples.len()
    );
}

#[test]
fn cpu_all_orders_matches_the_solver_within_the_tables_stated_error() {
    // Points halfway between nodes on all four axes (the worst case of multilinear interpolation),
    // cosines ≥ 0.05: a subset of the sweep `make_table` prints (τ1 cells ≡ 0 mod 3, other cells even),
    // whose maxima the sheer-transport README states as 4.3e-3 (reflected) and 3.2e-2 (transmitted);
    // bounds rounded up as in sheer-transport's own test. Evaluated by the function the renderer's CPU
    // path calls.
    let table = table();
    let spec = table.spec();
    let scattering = Scattering::AllOrders(Arc::clone(&table));
    let (mut worst_reflected, mut worst_transmitted) = (0.0f64, 0.0f64);
    let mut compared = 0;
    for t in (3..spec.tau_count - 1).step_by(9) {
        let tau1 = spec.tau_at(t as f64 + 0.5);
        for a in (2..spec.albedo_count - 1).step_by(6) {
            let albedo = spec.albedo_at(a as f64 + 0.5, tau1);
            let solver = SlabSolver::new(tau1, albedo).unwrap();
            for k in (2..spec.cosine_count - 1).step_by(4) {
                let mu0 = spec.cosine_at(k as f64 + 0.5);
                let solution = solver.solve(mu0).unwrap();
                for j in (2..spec.cosine_count - 1).step_by(4) {
                    let mu = spec.cosine_at(j as f64 + 0.5);
                    let ours = |side| {
                        diffuse_radiance(
                            &scattering,
                            side,
                            OpticalThickness::new(tau1).unwrap(),
                            Albedo::new(albedo).unwrap(),
                            Cosine::new("mu0", mu0).unwrap(),
                            Cosine::new("mu", mu).unwrap(),
                        )
                        .unwrap()
                    };
                    let exact = solution.reflected_radiance(mu).unwrap();
                    worst_reflected =
                        worst_reflected.max(((ours(Face::Lit) - exact) / exact).abs());
                    let exact = solution.transmitted_radiance(mu).unwrap();
                    worst_transmitted =
                        worst_transmitted.max(((ours(Face::Far) - exact) / exact).abs());
                    compared += 1;
                }
            }
        }
    }
    println!(
        "{compared} points: worst relative error reflected {worst_reflected:.2e}, transmitted \
         {worst_transmitted:.2e}"
    );
    assert_eq!(compared, 5 * 3 * 3 * 3);
    assert!(worst_reflected < 5e-3, "reflected {worst_reflected}");
    assert!(
        worst_transmitted < 3.5e-2,
        "transmitted {worst_transmitted}"
    );
    // The comparison has power: single scattering alone misses by far more at these points.
    let single = diffuse_radiance(
        &Scattering::Single,
        Face::Lit,
        OpticalThickness::new(2.0).unwrap(),
        Albedo::new(0.95).unwrap(),
        Cosine::new("mu0", 0.6).unwrap(),
        Cosine::new("mu", 0.7).unwrap(),
    )
    .unwrap();
    let exact = SlabSolver::new(2.0, 0.95)
        .unwrap()
        .solve(0.6)
        .unwrap()
        .reflected_radiance(0.7)
        .unwrap();
    assert!((exact - single) / exact > 0.2, "{single} {exact}");
}

/// Writes the checksum of a changed table file as its format documents it (sheer-transport's `table`
/// module): FNV-1a, 64-bit, over every byte but the checksum's own eight at offset 40.
fn reseal(bytes: &mut [u8]) {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for (i, &b) in bytes.iter().enumerate() {
        if !(40..48).contains(&i) {
            hash = (hash ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    bytes[40..48].copy_from_slice(&hash.to_le_bytes());
}

#[test]
fn bad_table_files_are_typed_errors() {
    let dir = std::env::temp_dir().join(format!("sheer-slab-bad-table-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    assert!(matches!(
        load_all_orders_table(dir.join("absent.bin")),
        Err(TableLoadError::Unreadable { .. })
    ));
    let mut bytes = table().to_bytes();
    let last = bytes.len() - 4;
    bytes[last..].copy_from_slice(&f32::INFINITY.to_le_bytes());
    let path = dir.join("infinite.bin");
    std::fs::write(&path, &bytes).unwrap();
    let error = load_all_orders_table(&path).unwrap_err();
    assert!(
        matches!(&error, TableLoadError::Corrupt { reason, .. } if reason.contains("non-finite")),
        "{error}"
    );
    assert!(error.to_string().contains("infinite.bin"), "{error}");
    // Finite but no slab's: e^{ln f} would overflow to an infinite radiance.
    for value in [1e30f32, 10.001] {
        bytes[last..].copy_from_slice(&value.to_le_bytes());
        std::fs::write(&path, &bytes).unwrap();
        let error = load_all_orders_table(&path).unwrap_err();
        assert!(
            matches!(&error, TableLoadError::Corrupt { reason, .. } if reason.contains("above 10")),
            "{value}: {error}"
        );
    }
    // The bound itself is admitted, and so is a vanishing term (e^{ln f} = 0, not a wrong value), in a
    // file whose checksum is written anew for the changed value.
    for value in [10.0f32, -1e30] {
        bytes[last..].copy_from_slice(&value.to_le_bytes());
        reseal(&mut bytes);
        std::fs::write(&path, &bytes).unwrap();
        load_all_orders_table(&path).unwrap();
    }
    bytes[8] = 9; // version
    std::fs::write(&path, &bytes).unwrap();
    assert!(matches!(
        load_all_orders_table(&path),
        Err(TableLoadError::Corrupt { .. })
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn optical_thickness_outside_the_table_is_refused_for_all_orders_only() {
    let table = table();
    let mut params = ShadingParams::uniform(20.0, 0.9, Vec3::Z, 10.0).unwrap();
    params.scattering = Scattering::AllOrders(Arc::clone(&table));
    assert!(matches!(
        params.validate(),
        Err(ShadingError::OutsideTable { channel: 0, .. })
    ));
    // The table's end typed as f32 is admitted.
    params.optical_thickness = [0.01, 10.0, 2.0];
    params.validate().unwrap();
    // A thickness texture that takes τ1 out of range on one texel is refused, naming the channel.
    params.optical_thickness = [2.0, 2.0, 4.0];
    params.thickness_texture =
        Some(Texture2d::new(2, 1, vec![[0.5, 0.0, 0.0, 1.0], [3.0, 0.0, 0.0, 1.0]]).unwrap());
    assert!(matches!(
        params.validate(),
        Err(ShadingError::OutsideTable { channel: 2, value, .. }) if value == 12.0
    ));
    params.scattering = Scattering::Single;
    params.validate().unwrap();
}
