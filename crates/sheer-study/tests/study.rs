//! Tests of the study's own machinery: the reference against an analytic answer, the error metrics
//! (pointwise and time-averaged coverage), determinism of the reference, the stability boundary against
//! linear stability analysis, the automatic choice, and a quick end-to-end run that writes every output
//! file.

use sheer_cloth::glam::DVec3;
use sheer_cloth::{GridSpec, Method, SimParams, SpringParams};
use sheer_study::chart::register_chart_font;
use sheer_study::reference::reference;
use sheer_study::silhouette::Viewport;
use sheer_study::stability::{
    find_stability_boundary, omega_max_gershgorin, omega_max_power_iteration,
};
use sheer_study::{
    Budget, ChoiceFile, CostRatio, CostTiming, CoverageWindow, ErrorMetrics, Monitor, Pinning, Row,
    Scene, StudyConfig, ablation, choose, coverage_difference, simulate, work_precision,
};

/// A free 6 × 4 cloth at rest under gravity, no air, no damping: every particle feels the same
/// acceleration and the springs stay at rest length, so `x(t) = x₀ + ½ g t²` exactly.
fn free_fall() -> Scene {
    let mut params = SimParams::springs_only(
        Method::Verlet { substeps: 1 },
        SpringParams::new(1000.0, 0.0),
    );
    params.gravity = DVec3::new(0.0, -9.81, 0.0);
    Scene {
        name: "free_fall".into(),
        grid: GridSpec {
            columns: 6,
            rows: 4,
            ..GridSpec::default()
        },
        pinning: Pinning::Free,
        params,
        frame: 1.0 / 60.0,
        coverage: None,
    }
}

#[test]
fn reference_reproduces_free_fall() {
    let scene = free_fall();
    let time = 0.5;
    let reference = reference(&scene, &[time], &Monitor::hidden()).unwrap();
    let snapshot = reference.trajectory.at(time).unwrap();
    let g = scene.params.gravity;
    let rest = scene.model().unwrap().positions;
    let analytic: Vec<DVec3> = rest.iter().map(|x| *x + 0.5 * g * time * time).collect();
    let (rms, max) = sheer_study::position_errors(&snapshot.positions, &analytic).unwrap();
    // Verlet is exact for constant acceleration; what remains is rounding: a few thousand sub-steps,
    // each adding ~1e-16 relative to positions of order 1 m, so ~1e-12 m. 1e-10 m leaves margin.
    assert!(max < 1e-10, "rms {rms:e}, max {max:e}");
    // The fall drops 1.23 m; the reference must have moved (guards against comparing rest to rest).
    assert!((snapshot.positions[0].y - rest[0].y + 0.5 * 9.81 * 0.25).abs() < 1e-10);
    // The halving check agrees: both runs are exact up to rounding.
    assert!(reference.halving[0].max_difference < 1e-10);
}

#[test]
fn error_metrics_vanish_for_identical_runs_and_not_otherwise() {
    let scene = Scene::hanging_sheet((8, 6)).unwrap();
    let monitor = Monitor::hidden();
    let times = [0.25];
    let a = simulate(
        &scene,
        Method::SymplecticEuler { substeps: 50 },
        scene.frame,
        &times,
        &monitor,
    )
    .unwrap();
    let b = simulate(
        &scene,
        Method::SymplecticEuler { substeps: 50 },
        scene.frame,
        &times,
        &monitor,
    )
    .unwrap();
    let same = ErrorMetrics::at(&a, &b, 0.25).unwrap();
    // The simulator is deterministic: identical runs give identical bits, so exactly zero.
    assert_eq!(same.rms_position_error, Some(0.0));
    assert_eq!(same.max_position_error, Some(0.0));
    assert!(!same.diverged);
    let c = simulate(
        &scene,
        Method::SymplecticEuler { substeps: 25 },
        scene.frame,
        &times,
        &monitor,
    )
    .unwrap();
    let different = ErrorMetrics::at(&c, &a, 0.25).unwrap();
    assert!(different.rms_position_error.unwrap() > 0.0);
    assert!(different.max_position_error.unwrap() >= different.rms_position_error.unwrap());
    // A run that diverges is reported as diverged, with no error values (never NaN).
    let stiff = Scene::stiff((8, 6)).unwrap();
    let blown = simulate(
        &stiff,
        Method::ExplicitEuler { substeps: 10 },
        stiff.frame,
        &times,
        &monitor,
    )
    .unwrap();
    assert!(blown.diverged_at.is_some());
    let metrics = ErrorMetrics::at(&blown, &a, 0.25).unwrap();
    assert!(metrics.diverged && metrics.rms_position_error.is_none());
}

#[test]
fn symplectic_euler_boundary_matches_linear_stability_analysis() {
    let scene = Scene::undamped_sheet((8, 6), 1.0e4).unwrap();
    let model = scene.model().unwrap();
    let omega_power = omega_max_power_iteration(&model, &scene.params, 3000);
    let omega_bound = omega_max_gershgorin(&model, &scene.params);
    // Power iteration approaches ω_max from below; Gershgorin bounds it from above.
    assert!(omega_power <= omega_bound * (1.0 + 1e-12));
    let predicted = 2.0 / omega_power;
    let duration = 0.5;
    let found = find_stability_boundary(
        &scene,
        Method::SymplecticEuler { substeps: 1 },
        0.5 * predicted,
        1.5 * predicted,
        duration,
        12,
        &Monitor::hidden(),
    )
    .unwrap();
    // Rigorous side: linear analysis guarantees stability below 2/ω_bound.
    assert!(
        found >= 2.0 / omega_bound,
        "{found:e} < {:e}",
        2.0 / omega_bound
    );
    // Sharp side. Above the limit by a fraction δ, symplectic Euler's worst eigenvalue has modulus
    // ≈ 1 + sqrt(8δ); growing from rounding (1e-16) to the divergence limit (strain 10) takes
    // ln(1e17) ≈ 39 e-foldings, so over N = duration/dt ≈ 1100 steps anything with
    // δ > (39/N)²/8 ≈ 1.6e-4 diverges. The bisection resolves ln(3)/2^12 ≈ 3e-4. The sagging sheet's
    // tension (strain < 0.1 %) shifts ω by less than 0.1 %, and the power iteration underestimates
    // ω_max by less than that. So the found step lies within 1 % of the prediction.
    let ratio = found / predicted;
    assert!(
        (ratio - 1.0).abs() < 0.01,
        "found {found:e}, predicted {predicted:e}"
    );
}

fn row(method: Method, time: f64, rms: Option<f64>, cost: f64) -> Row {
    Row {
        scene: "flag".into(),
        particles: 10,
        method,
        substep: 1e-3,
        metrics: ErrorMetrics {
            time,
            rms_position_error: rms,
            max_position_error: rms,
            relative_energy_drift: rms.map(|_| 0.0),
            reference_energy_drift: 0.0,
            max_strain: rms.map(|_| 0.0),
            diverged: rms.is_none(),
        },
        cpu_ms_per_simulated_second: cost,
        reference_rms_halving: 0.0,
        coverage_difference: rms.map(|e| e * 10.0),
        reference_coverage_halving: Some(1e-4),
    }
}

#[test]
fn choice_is_the_cheapest_setting_within_budget() {
    let rows = vec![
        row(
            Method::SmallStepsXpbd { substeps: 10 },
            1.0,
            Some(8e-3),
            5.0,
        ),
        row(
            Method::SmallStepsXpbd { substeps: 20 },
            1.0,
            Some(4e-3),
            10.0,
        ),
        row(Method::Verlet { substeps: 100 }, 1.0, Some(1e-4), 50.0),
        row(Method::ExplicitEuler { substeps: 10 }, 1.0, None, 1.0),
        // Cheaper but measured at another time: not eligible.
        row(
            Method::Xpbd {
                substeps: 1,
                iterations: 5,
            },
            5.0,
            Some(1e-3),
            2.0,
        ),
    ];
    let budget = Budget::RmsPosition {
        time: 1.0,
        max_error: 5e-3,
    };
    let choice = choose(&budget, &rows).unwrap();
    assert_eq!(choice.method, Method::SmallStepsXpbd { substeps: 20 });
    assert_eq!(choice.candidates, 2);
    assert_eq!(choice.error, 4e-3);
    let strict = Budget::RmsPosition {
        time: 1.0,
        max_error: 1e-5,
    };
    assert!(choose(&strict, &rows).is_none());
    // The coverage budget reads the per-run coverage difference (here 10 × the RMS error), whatever
    // the time: the XPBD run measured at 5 s (coverage 0.01) is now the cheapest within 0.05.
    let coverage = Budget::Coverage {
        max_difference: 0.05,
    };
    let choice = choose(&coverage, &rows).unwrap();
    assert_eq!(
        choice.method,
        Method::Xpbd {
            substeps: 1,
            iterations: 5
        }
    );
    assert_eq!(choice.candidates, 3);
    // The default budget is the coverage one.
    assert!(matches!(Budget::default(), Budget::Coverage { .. }));
}

#[test]
fn quick_sweep_against_a_converged_reference() {
    let config = StudyConfig::quick();
    let monitor = Monitor::hidden();
    let scene = Scene::hanging_sheet(config.sweep_grid).unwrap();
    let reference = reference(&scene, &config.sample_times, &monitor).unwrap();
    // Converged: halving the reference's step moves it far less than the 5 mm budget the study
    // judges against (an order of magnitude at least; measured ~1e-6 m).
    for check in &reference.halving {
        assert!(check.rms_difference < 5e-4, "{check:?}");
    }
    let rows = work_precision(&scene, &reference, &config.sweep(&scene), &monitor).unwrap();
    assert_eq!(
        rows.len(),
        config.sweep(&scene).methods.len() * config.sample_times.len()
    );
    // First-order symplectic Euler converges: 4× the sub-steps gives a smaller error.
    let error = |substeps: u32| {
        rows.iter()
            .find(|r| r.method == Method::SymplecticEuler { substeps } && r.metrics.time == 0.25)
            .and_then(|r| r.metrics.rms_position_error)
            .unwrap()
    };
    assert!(error(200) < error(50));
    assert!(rows.iter().all(|r| r.cpu_ms_per_simulated_second >= 0.0));
}

#[test]
fn quick_study_writes_every_output() {
    if register_chart_font().is_err() {
        // The charts need a TrueType font (fonts-dejavu-core); without one the study reports a typed
        // error, which this checks instead of the files.
        let out = std::env::temp_dir().join("sheer-study-no-font");
        let result = sheer_study::outputs::write_all(
            &StudyConfig::quick(),
            &Budget::default(),
            &out,
            &Monitor::hidden(),
        );
        assert!(matches!(result, Err(sheer_study::StudyError::Font { .. })));
        return;
    }
    let out = std::env::temp_dir().join(format!("sheer-study-quick-{}", std::process::id()));
    // A budget every quick setting that does not diverge meets, so a choice file is written.
    sheer_study::outputs::write_all(
        &StudyConfig::quick(),
        &Budget::Coverage {
            max_difference: 10.0,
        },
        &out,
        &Monitor::hidden(),
    )
    .unwrap();
    for file in [
        "work-precision.csv",
        "work-precision.png",
        "work-precision.md",
        "stability-map.csv",
        "stability-map.png",
        "stability-map.md",
        "ablation.csv",
        "ablation.md",
        "choice.toml",
    ] {
        let path = out.join(file);
        let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
        assert!(size > 100, "{} missing or empty", path.display());
    }
    // The seed study (not part of `all`): one row per seed and setting, a summary row per setting.
    sheer_study::outputs::write_seeds(&StudyConfig::quick(), 2, &out, &Monitor::hidden()).unwrap();
    let seeds = std::fs::read_to_string(out.join("seeds.csv")).unwrap();
    assert_eq!(seeds.lines().count(), 1 + 2 * 11);
    assert!(seeds.lines().skip(1).all(|l| !l.contains(",,")), "{seeds}");
    let seeds_md = std::fs::read_to_string(out.join("seeds.md")).unwrap();
    assert!(seeds_md.contains("| full model | small_steps_xpbd ×40 | 2 |"));
    assert!(seeds_md.contains("held ≤ 2 ms (every 4 sub-steps), the default flag"));
    assert!(matches!(
        sheer_study::outputs::write_seeds(&StudyConfig::quick(), 0, &out, &Monitor::hidden()),
        Err(sheer_study::StudyError::InvalidInput { .. })
    ));
    let csv = std::fs::read_to_string(out.join("work-precision.csv")).unwrap();
    assert!(csv.starts_with("scene,particles,method,"));
    for scene in ["flag", "hanging_sheet", "stiff", "default_flag"] {
        assert!(
            csv.lines().any(|l| l.starts_with(&format!("{scene},"))),
            "{scene}"
        );
    }
    // The flags' rows carry a coverage difference; the sheets' do not.
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let column = header
        .iter()
        .position(|c| *c == "coverage_difference")
        .unwrap();
    let covered = |scene: &str| {
        csv.lines()
            .filter(|l| l.starts_with(&format!("{scene},")))
            .any(|l| !l.split(',').nth(column).unwrap().is_empty())
    };
    assert!(covered("flag") && covered("default_flag"));
    assert!(!covered("hanging_sheet") && !covered("stiff"));
    // The choice file parses, says it is a quick run, and records the flag it was measured on: the
    // default flag's parameters with the chosen method.
    let text = std::fs::read_to_string(out.join("choice.toml")).unwrap();
    let file: ChoiceFile = toml::from_str(&text).unwrap();
    assert!(file.quick);
    assert_eq!(file.budget.kind, "coverage");
    let method = file.scene.simulation.method;
    assert_eq!(method.name(), file.choice.method);
    assert_eq!(method.substeps(), file.choice.substeps);
    assert_eq!(
        file.scene.simulation,
        Scene::default_flag().unwrap().params_with(method)
    );
    assert!(
        file.choice.error <= 10.0 && file.choice.coverage_difference == Some(file.choice.error)
    );
    let md = std::fs::read_to_string(out.join("work-precision.md")).unwrap();
    assert!(md.contains("## Budget, choice and why"), "{md}");
    // Every variant of the ablation but the full model has a cost ratio from its timed rounds, its
    // median between the least and the greatest; the full model's rows have none.
    let ablation = std::fs::read_to_string(out.join("ablation.csv")).unwrap();
    let header: Vec<&str> = ablation.lines().next().unwrap().split(',').collect();
    let at = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let (median, low, high) = (
        at("cost_vs_full"),
        at("cost_vs_full_low"),
        at("cost_vs_full_high"),
    );
    let mut variants = 0;
    for line in ablation.lines().skip(1) {
        // The setting (the second column) is quoted and may hold commas: split after it.
        let after_setting = line.rsplit('"').next().unwrap();
        let fields: Vec<&str> = after_setting.split(',').skip(1).collect();
        let value = |i: usize| fields[i - 2].parse::<f64>().ok();
        if line.starts_with("full,") {
            assert!(value(median).is_none() && value(low).is_none(), "{line}");
            continue;
        }
        variants += 1;
        let (m, l, h) = (
            value(median).unwrap(),
            value(low).unwrap(),
            value(high).unwrap(),
        );
        assert!(0.0 < l && l <= m && m <= h && h.is_finite(), "{line}");
    }
    assert!(variants >= 10, "{ablation}");
    std::fs::remove_dir_all(&out).ok();
}

/// A flat sheet in the x–y plane that stays where it is: springs at rest length, no gravity, no air.
fn still_sheet(window: CoverageWindow) -> Scene {
    let params = SimParams::springs_only(
        Method::Verlet { substeps: 1 },
        SpringParams::new(1000.0, 0.0),
    );
    Scene {
        name: "still_sheet".into(),
        grid: GridSpec::default(),
        pinning: Pinning::Free,
        params,
        frame: 1.0 / 60.0,
        coverage: Some(window),
    }
}

/// Pixel centres `min + (i + ½) · pixel` of `count` pixels that lie in `[low, high]`.
fn centres_inside(min: f64, pixel: f64, count: usize, low: f64, high: f64) -> Vec<usize> {
    (0..count)
        .filter(|&i| {
            let centre = min + (i as f64 + 0.5) * pixel;
            centre >= low && centre <= high
        })
        .collect()
}

#[test]
fn coverage_of_a_still_sheet_is_its_rectangle_in_every_frame() {
    let window = CoverageWindow {
        start: 0.1,
        end: 0.3,
        viewport: Viewport::around_flag(256),
    };
    let scene = still_sheet(window);
    let run = simulate(
        &scene,
        Method::Verlet { substeps: 1 },
        scene.frame,
        &[0.2],
        &Monitor::hidden(),
    )
    .unwrap();
    let coverage = run.coverage.as_ref().unwrap();
    // Frames 6 … 18 of 1/60 s: 13 frames, each with the sheet on the same pixels.
    assert_eq!(coverage.frames, 13);
    // By hand: the 1.1 m × 0.8 m sheet spans x ∈ [0, 1.1], y ∈ [0, 0.8]; covered are exactly the
    // pixel centres inside (edges never fall on a centre: they sit 0.3 and 0.1 pixels off one).
    let v = window.viewport;
    let pixel = v.size / v.resolution as f64;
    let columns = centres_inside(v.min_x, pixel, v.resolution, 0.0, 1.1);
    let rows = centres_inside(v.min_y, pixel, v.resolution, 0.0, 0.8);
    assert_eq!((columns.len(), rows.len()), (141, 102));
    for (index, &fraction) in coverage.fractions.iter().enumerate() {
        let (row, column) = (index / v.resolution, index % v.resolution);
        let inside = rows.contains(&row) && columns.contains(&column);
        assert_eq!(
            fraction,
            if inside { 1.0 } else { 0.0 },
            "pixel {row},{column}"
        );
    }
    // Identical runs: zero difference.
    assert_eq!(coverage_difference(coverage, coverage), Some(0.0));
}

#[test]
fn coverage_of_a_falling_sheet_matches_the_analytic_fall() {
    // The free-falling sheet of `reference_reproduces_free_fall`, seen over 0.1 … 0.3 s: Verlet (at 20
    // sub-steps, inside the springs' stability limit 2/ω_max, so rounding noise does not grow) moves it
    // exactly by ½ g t² (to ~1e-12 m), so pixel (row, column) is covered in frame k exactly when its
    // centre lies in the sheet translated by ½ g t_k².
    let window = CoverageWindow {
        start: 0.1,
        end: 0.3,
        viewport: Viewport::around_flag(256),
    };
    let scene = Scene {
        coverage: Some(window),
        ..free_fall()
    };
    let run = simulate(
        &scene,
        Method::Verlet { substeps: 20 },
        scene.frame,
        &[0.3],
        &Monitor::hidden(),
    )
    .unwrap();
    let coverage = run.coverage.as_ref().unwrap();
    let v = window.viewport;
    let pixel = v.size / v.resolution as f64;
    let columns = centres_inside(v.min_x, pixel, v.resolution, 0.0, 1.1);
    let mut expected = vec![0.0; v.resolution * v.resolution];
    let frames: Vec<f64> = (6..=18).map(|k| k as f64 / 60.0).collect();
    for &t in &frames {
        let drop = 0.5 * 9.81 * t * t;
        for row in centres_inside(v.min_y, pixel, v.resolution, -drop, 0.8 - drop) {
            for &column in &columns {
                expected[row * v.resolution + column] += 1.0 / frames.len() as f64;
            }
        }
    }
    assert_eq!(coverage.frames as usize, frames.len());
    let worst = coverage
        .fractions
        .iter()
        .zip(&expected)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    // Sums of 1/13 in another order: equal to rounding.
    assert!(worst < 1e-12, "{worst}");
    // Fractions strictly between 0 and 1 exist: rows the sheet's edges swept across.
    assert!(coverage.fractions.iter().any(|&f| f > 0.0 && f < 1.0));
}

#[test]
fn coverage_difference_vanishes_for_identical_runs_only() {
    let config = StudyConfig::quick();
    let scene = Scene::flag(config.sweep_grid)
        .unwrap()
        .with_coverage(Some(config.coverage_window));
    let monitor = Monitor::hidden();
    let run = |method| {
        simulate(&scene, method, scene.frame, &[0.25], &monitor)
            .unwrap()
            .coverage
            .unwrap()
    };
    let a = run(Method::SmallStepsXpbd { substeps: 10 });
    let b = run(Method::SmallStepsXpbd { substeps: 10 });
    assert_eq!(a, b);
    assert_eq!(coverage_difference(&a, &b), Some(0.0));
    let c = run(Method::SmallStepsXpbd { substeps: 40 });
    let d = coverage_difference(&c, &a).unwrap();
    assert!(d > 0.0 && d.is_finite(), "{d}");
}

/// The bits of every position of every snapshot of a reference's trajectory.
fn position_bits(reference: &sheer_study::Reference) -> Vec<u64> {
    reference
        .trajectory
        .snapshots
        .iter()
        .flat_map(|s| s.positions.iter().flat_map(|p| p.to_array()))
        .map(f64::to_bits)
        .collect()
}

#[test]
fn the_reference_is_bit_reproducible() {
    // Two study runs of the same scene must produce the same reference bit for bit (the simulator is
    // deterministic and the reference's step follows from the scene alone); a different result for the
    // same setting therefore means a different scene (a changed default fabric once made two runs
    // disagree by 0.6 mm against 1.0 mm for the same setting).
    let config = StudyConfig::quick();
    let scene = Scene::default_flag()
        .unwrap()
        .with_resolution(config.choice_grid.0, config.choice_grid.1)
        .unwrap()
        .with_coverage(Some(config.coverage_window));
    let monitor = Monitor::hidden();
    let first = reference(&scene, &config.choice_times, &monitor).unwrap();
    let second = reference(&scene, &config.choice_times, &monitor).unwrap();
    assert_eq!(first.method, second.method);
    assert_eq!(position_bits(&first), position_bits(&second));
    assert_eq!(first.trajectory.coverage, second.trajectory.coverage);
    assert_eq!(first.halving, second.halving);
    assert!(first.coverage_halving.unwrap() >= 0.0);
}

#[test]
fn the_reference_renews_the_wind_however_the_scene_holds_it() {
    // Holding the wind's forces (for a time, or for the whole frame) is an approximation a run makes,
    // not part of the model: the reference of a scene that holds them is the reference of the model.
    let config = StudyConfig::quick();
    let scene = Scene::default_flag()
        .unwrap()
        .with_resolution(config.choice_grid.0, config.choice_grid.1)
        .unwrap();
    let times = [0.1];
    let monitor = Monitor::hidden();
    let bits = |scene: &Scene| position_bits(&reference(scene, &times, &monitor).unwrap());
    let mut renewed = scene.clone();
    renewed.params.wind.renewal_interval = 0.0;
    let expected = bits(&renewed);
    let mut held = scene.clone();
    held.params.wind.renewal_interval = 0.004;
    let mut per_frame = scene.clone();
    per_frame.params.wind.renewal_interval = 0.0;
    per_frame.params.wind.per_substep = false;
    for (name, variant) in [("own", &scene), ("4 ms", &held), ("per frame", &per_frame)] {
        assert!(bits(variant) == expected, "{name}: a different reference");
    }
}

#[test]
fn a_cost_ratio_is_the_median_and_range_of_its_rounds() {
    let ratio = CostRatio::of(&[1.2, 0.9, 1.0]).unwrap();
    assert_eq!((ratio.median, ratio.low, ratio.high), (1.0, 0.9, 1.2));
    let even = CostRatio::of(&[1.3, 0.9, 1.1, 1.0]).unwrap();
    assert_eq!((even.median, even.low, even.high), (1.05, 0.9, 1.3));
    assert_eq!(CostRatio::of(&[]), None);
}

#[test]
fn the_ablation_refuses_a_timing_that_times_nothing() {
    let scene = Scene::flag((6, 5)).unwrap();
    let monitor = Monitor::hidden();
    let reference = reference(&scene, &[0.05], &monitor).unwrap();
    for timing in [
        CostTiming {
            rounds: 0,
            window: 0.1,
        },
        CostTiming {
            rounds: 1,
            window: f64::NAN,
        },
        CostTiming {
            rounds: 1,
            window: 0.0,
        },
    ] {
        let result = ablation(&scene, Method::default(), &reference, &[], timing, &monitor);
        assert!(
            matches!(result, Err(sheer_study::StudyError::InvalidInput { .. })),
            "{timing:?}"
        );
    }
}

/// A sample time more than 2³² steps away is refused at once: its step count saturated at `u64::MAX`
/// and the run would never have ended.
#[test]
fn a_run_too_long_for_its_step_is_refused() {
    let scene = Scene::flag((6, 5)).unwrap();
    let result = simulate(&scene, Method::default(), 1e-9, &[1e10], &Monitor::hidden());
    assert!(
        matches!(
            result,
            Err(sheer_study::StudyError::InvalidInput {
                name: "sample time",
                ..
            })
        ),
        "{:?}",
        result.err()
    );
}
