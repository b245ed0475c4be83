//! Work–precision: every method swept over its knobs, error against the reference on one axis and
//! measured CPU cost on the other (the chart numerical-ODE benchmark suites publish, e.g. the
//! SciML benchmarks' work–precision diagrams).

use sheer_cloth::Method;

use crate::ablation::CostTiming;
use crate::coverage::{CoverageWindow, coverage_difference};
use crate::metrics::ErrorMetrics;
use crate::reference::Reference;
use crate::run::{on_one_thread, simulate};
use crate::{Monitor, Scene, StudyError};

/// The knob settings of every method to run, each called with `step(scene.frame)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// The methods, each with its own sub-step and iteration counts.
    pub methods: Vec<Method>,
}

/// One run at one sample time.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Name of the scene run.
    pub scene: String,
    /// Particles in the scene's cloth.
    pub particles: usize,
    /// The integrator run, with its sub-step and iteration counts.
    pub method: Method,
    /// Sub-step length, s.
    pub substep: f64,
    /// The run's errors against the reference at this sample time.
    pub metrics: ErrorMetrics,
    /// CPU milliseconds per simulated second (single thread), measured over the whole run.
    pub cpu_ms_per_simulated_second: f64,
    /// The reference's own halving difference (RMS, m) at this time: errors below it are not resolved.
    pub reference_rms_halving: f64,
    /// Time-averaged coverage difference of the whole run against the reference's (dimensionless,
    /// [`crate::coverage`]); the same on each of the run's rows. `None` when the scene measures no
    /// coverage or the run diverged.
    pub coverage_difference: Option<f64>,
    /// The reference's own coverage halving difference.
    pub reference_coverage_halving: Option<f64>,
}

impl Row {
    /// `substeps` and `iterations` of the method (iterations = CG cap for implicit Euler).
    pub fn knobs(&self) -> (u32, u32) {
        (self.method.substeps(), self.method.iterations())
    }
}

/// Sizes, times and sweeps of a study; [`StudyConfig::full`] for the published results,
/// [`StudyConfig::quick`] for tests and smoke runs.
#[derive(Clone, Debug, PartialEq)]
pub struct StudyConfig {
    /// Whether this is the quick smoke-test configuration (small grids, short windows).
    pub quick: bool,
    /// Flag and sheet grid of the work–precision sweeps.
    pub sweep_grid: (usize, usize),
    /// Grid of the stiff scene.
    pub stiff_grid: (usize, usize),
    /// Simulated times at which errors are measured, s.
    pub sample_times: Vec<f64>,
    /// Grid of the automatic choice and the ablation (the app's default flag).
    pub choice_grid: (usize, usize),
    /// Sample times of the choice sweep and the ablation, s (the budget's time must be one).
    pub choice_times: Vec<f64>,
    /// Grid of the converged reference compared with the choice grid's: the resolution difference in
    /// coverage that sizes the default budget.
    pub choice_coarse_grid: (usize, usize),
    /// Window and camera of the time-averaged coverage of the flags.
    pub coverage_window: CoverageWindow,
    /// Resolutions of the ablation.
    pub ablation_grids: Vec<(usize, usize)>,
    /// How the ablation times its variants against the full model.
    pub ablation_timing: CostTiming,
    /// Grid of the stability map.
    pub stability_grid: (usize, usize),
    /// Stretch stiffnesses of the stability map, N/m.
    pub stability_stiffnesses: Vec<f64>,
    /// Time steps of the stability map, s.
    pub stability_steps: Vec<f64>,
    /// Simulated time of each stability-map run, s.
    pub stability_duration: f64,
}

impl StudyConfig {
    /// The published study: 32 × 23 sweeps at 0.25 s, 1 s and 5 s, the default 64 × 46 flag for the
    /// choice and the ablation (0.25 s and 1 s).
    pub fn full() -> StudyConfig {
        StudyConfig {
            quick: false,
            sweep_grid: (32, 23),
            stiff_grid: (16, 11),
            // 0.25 s lies inside the waving flag's predictability horizon (its reference changes by
            // 0.1 mm when its step is halved, against 3 cm at 1 s: the flutter is chaotic).
            sample_times: vec![0.25, 1.0, 5.0],
            choice_grid: (64, 46),
            // Pointwise errors up to 1 s at 64 × 46 (the 32 × 23 sweep shows how they grow to 5 s);
            // the runs go on to the end of the coverage window.
            choice_times: vec![0.25, 1.0],
            choice_coarse_grid: (32, 23),
            coverage_window: CoverageWindow::flag(),
            ablation_grids: vec![(16, 11), (32, 23), (64, 46), (128, 93), (256, 186)],
            // Five rounds of a simulated second: the flag is waving by then; a part's rounds spread by
            // up to about a fifth around its median (gusts: 0.874–1.097, docs/ablation.md).
            ablation_timing: CostTiming {
                rounds: 5,
                window: 1.0,
            },
            stability_grid: (16, 11),
            stability_stiffnesses: vec![1e2, 3e2, 1e3, 3e3, 1e4, 3e4, 1e5],
            stability_steps: crate::stability::log_spaced(1e-5, 1.0 / 60.0, 12)
                .expect("positive constants"),
            stability_duration: 1.0,
        }
    }

    /// A small, fast version of everything (tests, smoke runs): 8 × 6 grids, 0.25 s and 0.5 s, coverage
    /// over 0.25–0.5 s at 128 × 128 pixels.
    pub fn quick() -> StudyConfig {
        StudyConfig {
            quick: true,
            sweep_grid: (8, 6),
            stiff_grid: (8, 6),
            sample_times: vec![0.25, 0.5],
            choice_grid: (12, 9),
            choice_times: vec![0.25],
            choice_coarse_grid: (8, 6),
            coverage_window: CoverageWindow {
                start: 0.25,
                end: 0.5,
                viewport: crate::silhouette::Viewport::around_flag(128),
            },
            ablation_grids: vec![(8, 6), (12, 9), (16, 11)],
            ablation_timing: CostTiming {
                rounds: 1,
                window: 0.25,
            },
            stability_grid: (8, 6),
            stability_stiffnesses: vec![1e2, 1e4],
            stability_steps: crate::stability::log_spaced(1e-4, 1.0 / 60.0, 4)
                .expect("positive constants"),
            stability_duration: 0.25,
        }
    }

    /// The knob sweep of every method for `scene`. Mass–spring explicit methods need sub-steps
    /// near their stability limit, so their sweep starts where the scene's `2/ω_max` allows.
    pub fn sweep(&self, _scene: &Scene) -> Sweep {
        let counts = |full: &[u32], quick: &[u32]| -> Vec<u32> {
            if self.quick {
                quick.to_vec()
            } else {
                full.to_vec()
            }
        };
        let mut methods = Vec::new();
        for substeps in counts(&[100, 400, 1600], &[200, 800]) {
            methods.push(Method::ExplicitEuler { substeps });
        }
        for substeps in counts(&[25, 50, 100, 200, 400], &[50, 200]) {
            methods.push(Method::SymplecticEuler { substeps });
            methods.push(Method::Verlet { substeps });
        }
        for substeps in counts(&[1, 2, 4, 8, 16], &[1, 4]) {
            methods.push(Method::ImplicitEuler {
                substeps,
                cg_max_iterations: 200,
                cg_tolerance: 1e-6,
            });
        }
        let position_based: &[(u32, u32)] = if self.quick {
            &[(1, 10), (4, 10)]
        } else {
            &[(1, 10), (1, 40), (2, 20), (4, 10), (8, 10), (16, 5)]
        };
        for &(substeps, iterations) in position_based {
            methods.push(Method::Pbd {
                substeps,
                iterations,
                stiffness: 1.0,
            });
            methods.push(Method::Xpbd {
                substeps,
                iterations,
            });
        }
        for substeps in counts(&[5, 10, 20, 40, 80, 160], &[10, 40]) {
            methods.push(Method::SmallStepsXpbd { substeps });
        }
        Sweep { methods }
    }
}

/// Runs every method of `sweep` on `scene` and compares it with `reference` at every sample time of
/// the reference. One row per (method, time).
pub fn work_precision(
    scene: &Scene,
    reference: &Reference,
    sweep: &Sweep,
    monitor: &Monitor,
) -> Result<Vec<Row>, StudyError> {
    let times = reference.trajectory.snapshot_times();
    monitor.add_work(sweep.methods.len() as u64);
    let mut rows = Vec::new();
    for &method in &sweep.methods {
        let trajectory = on_one_thread(|| simulate(scene, method, scene.frame, &times, monitor))??;
        let cost = trajectory.cpu_ms_per_simulated_second();
        let coverage = trajectory
            .coverage
            .as_ref()
            .zip(reference.trajectory.coverage.as_ref())
            .and_then(|(run, expected)| coverage_difference(run, expected));
        for &time in &times {
            let Some(metrics) = ErrorMetrics::at(&trajectory, &reference.trajectory, time) else {
                continue;
            };
            rows.push(Row {
                scene: scene.name.clone(),
                particles: scene.particle_count(),
                method,
                substep: scene.frame / method.substeps() as f64,
                metrics,
                cpu_ms_per_simulated_second: cost,
                reference_rms_halving: reference.halving_at(time).map_or(0.0, |h| h.rms_difference),
                coverage_difference: coverage,
                reference_coverage_halving: reference.coverage_halving,
            });
        }
        monitor.finish_run(&format!(
            "{} {} ×{} it {}",
            scene.name,
            method.name(),
            method.substeps(),
            method.iterations()
        ));
    }
    Ok(rows)
}
