//! Stability: the highest natural frequency of a cloth (Gershgorin bound and power iteration on the
//! actual stiffness matrix), the explicit integrators' step limit `2/ω_max`, a bisection for the step
//! at which a method actually diverges, and the stability map (time step × stiffness) of every method.
//!
//! Linear stability of symplectic Euler and velocity Verlet on `ẍ = −ω² x`: both are stable exactly for
//! `h ω < 2` (e.g. Hairer, Lubich & Wanner, "Geometric Numerical Integration", 2nd ed., sect. I.5 / the
//! Störmer–Verlet stability interval). For a mass–spring cloth linearised about rest, `M ẍ = −K x`, the
//! frequencies are the square roots of the eigenvalues of `M⁻¹K`, so the limit is `h < 2/ω_max`.

use sheer_cloth::glam::DVec3;
use sheer_cloth::{ClothModel, Method, SimParams, SpringKind};

use crate::metrics::position_errors;
use crate::reference::reference;
use crate::run::{on_one_thread, simulate};
use crate::{Monitor, Scene, StudyError};

fn spring_stiffness(params: &SimParams, kind: SpringKind) -> f64 {
    let family = match kind {
        SpringKind::Stretch => params.stretch,
        SpringKind::Shear => params.shear,
        SpringKind::Bend => params.bend,
    };
    if family.enabled {
        family.stiffness
    } else {
        0.0
    }
}

/// Upper bound on the highest undamped angular frequency `ω_max` (rad/s) of the springs of `model`
/// linearised at rest: Gershgorin's theorem applied block-wise to the symmetric `M^{-1/2} K M^{-1/2}`.
/// Row `i` has diagonal block `Σ_s k_s d_s d_sᵀ / m_i` (norm ≤ `Σ_s k_s / m_i`) and off-diagonal blocks
/// `k_s d_s d_sᵀ / sqrt(m_i m_j)` (norm `k_s / sqrt(m_i m_j)`), so every eigenvalue is at most
/// `max_i Σ_s k_s (1/m_i + 1/sqrt(m_i m_j))`. Exact for one spring between two equal free masses
/// (`ω² = 2k/m`). Pinned particles do not move: their rows are dropped and springs to them keep only
/// their diagonal term.
pub fn omega_max_gershgorin(model: &ClothModel, params: &SimParams) -> f64 {
    let mut row_bound = vec![0.0f64; model.positions.len()];
    for spring in &model.springs {
        let k = spring_stiffness(params, spring.kind);
        let (a, b) = (spring.a as usize, spring.b as usize);
        let (ma, mb) = (model.masses[a], model.masses[b]);
        let off_diagonal = if model.pinned[a] || model.pinned[b] {
            0.0
        } else {
            k / (ma * mb).sqrt()
        };
        row_bound[a] += k / ma + off_diagonal;
        row_bound[b] += k / mb + off_diagonal;
    }
    row_bound
        .iter()
        .zip(&model.pinned)
        .filter(|(_, pinned)| !**pinned)
        .map(|(bound, _)| *bound)
        .fold(0.0, f64::max)
        .sqrt()
}

/// `ω_max` (rad/s) of the springs of `model` linearised at rest, by power iteration on the symmetric
/// `M^{-1/2} K M^{-1/2}` with `K = Σ_s k_s d_s d_sᵀ` (the material stiffness of a spring at its rest
/// length; pinned particles fixed). Returns the Rayleigh quotient after `iterations` iterations, which
/// approaches `ω_max²` from below.
pub fn omega_max_power_iteration(model: &ClothModel, params: &SimParams, iterations: u32) -> f64 {
    let n = model.positions.len();
    let scale: Vec<f64> = model
        .masses
        .iter()
        .zip(&model.pinned)
        .map(|(&m, &pinned)| if pinned { 0.0 } else { 1.0 / m.sqrt() })
        .collect();
    let springs: Vec<(usize, usize, f64, DVec3)> = model
        .springs
        .iter()
        .filter_map(|s| {
            let k = spring_stiffness(params, s.kind);
            let (a, b) = (s.a as usize, s.b as usize);
            let d = (model.positions[b] - model.positions[a]).normalize_or_zero();
            (k > 0.0 && d != DVec3::ZERO).then_some((a, b, k, d))
        })
        .collect();
    // A deterministic start vector with components along every direction (a fixed linear
    // congruential sequence), zero on pinned particles.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut v: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new(next(), next(), next()) * scale[i].signum())
        .collect();
    let mut w = vec![DVec3::ZERO; n];
    let mut rayleigh = 0.0;
    for _ in 0..iterations {
        let norm = v.iter().map(|x| x.length_squared()).sum::<f64>().sqrt();
        if norm == 0.0 {
            return 0.0;
        }
        for x in &mut v {
            *x /= norm;
        }
        // w = M^{-1/2} K M^{-1/2} v
        w.fill(DVec3::ZERO);
        for &(a, b, k, d) in &springs {
            let relative = d.dot(v[a] * scale[a] - v[b] * scale[b]);
            let force = k * relative * d;
            w[a] += force;
            w[b] -= force;
        }
        for (x, s) in w.iter_mut().zip(&scale) {
            *x *= *s;
        }
        rayleigh = v.iter().zip(&w).map(|(a, b)| a.dot(*b)).sum::<f64>();
        std::mem::swap(&mut v, &mut w);
    }
    rayleigh.max(0.0).sqrt()
}

/// Whether `method` (called with `step(dt)`, one sub-step) survives `duration` seconds of `scene`.
fn survives(
    scene: &Scene,
    method: Method,
    dt: f64,
    duration: f64,
    monitor: &Monitor,
) -> Result<bool, StudyError> {
    let trajectory = on_one_thread(|| simulate(scene, method, dt, &[duration], monitor))??;
    Ok(trajectory.diverged_at.is_none())
}

/// The largest step (s) at which `method` (one sub-step per call) survives `duration` seconds of
/// `scene`, by bisection on `log dt` between `stable` (must survive) and `unstable` (must diverge),
/// to a relative resolution of `2^-bisections`.
pub fn find_stability_boundary(
    scene: &Scene,
    method: Method,
    mut stable: f64,
    mut unstable: f64,
    duration: f64,
    bisections: u32,
    monitor: &Monitor,
) -> Result<f64, StudyError> {
    if !survives(scene, method, stable, duration, monitor)? {
        return Err(StudyError::InvalidInput {
            name: "stable bracket",
            value: stable,
            reason: "the method already diverges at the lower end of the bracket",
        });
    }
    if survives(scene, method, unstable, duration, monitor)? {
        return Err(StudyError::InvalidInput {
            name: "unstable bracket",
            value: unstable,
            reason: "the method still survives at the upper end of the bracket",
        });
    }
    for _ in 0..bisections {
        let middle = (stable * unstable).sqrt();
        if survives(scene, method, middle, duration, monitor)? {
            stable = middle;
        } else {
            unstable = middle;
        }
    }
    Ok(stable)
}

/// Stable, inaccurate or diverged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StabilityClass {
    /// Ran to the end with an RMS position error within the bound.
    Stable,
    /// Ran to the end, but with an RMS position error above the bound.
    Inaccurate,
    /// A step diverged (non-finite, speed or strain beyond the simulator's limits).
    Diverged,
}

impl StabilityClass {
    /// Short lowercase name, as written in the stability CSV.
    pub fn name(&self) -> &'static str {
        match self {
            StabilityClass::Stable => "stable",
            StabilityClass::Inaccurate => "inaccurate",
            StabilityClass::Diverged => "diverged",
        }
    }
}

/// One cell of the stability map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StabilityCell {
    /// The integrator run in this cell.
    pub method: Method,
    /// Stretch stiffness, N/m (XPBD compliance is its inverse; PBD ignores it).
    pub stiffness: f64,
    /// Time step of each `step` call (one sub-step), s.
    pub dt: f64,
    /// Whether the run stayed stable and accurate, stable but inaccurate, or diverged.
    pub class: StabilityClass,
    /// RMS position error against the reference at the end, m (`None` if diverged).
    pub rms_position_error: Option<f64>,
}

/// Linear-analysis prediction for one stiffness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StabilityPrediction {
    /// Stretch stiffness, N/m.
    pub stiffness: f64,
    /// `2/ω_max` with `ω_max` by power iteration, s.
    pub dt_power_iteration: f64,
    /// `2/ω_max` with the Gershgorin bound (a guaranteed lower bound on the limit), s.
    pub dt_gershgorin: f64,
}

/// What [`stability_map`] measures.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilitySetup {
    /// The undamped sheet's grid, (columns, rows) particles.
    pub grid: (usize, usize),
    /// Stretch stiffnesses, N/m.
    pub stiffnesses: Vec<f64>,
    /// Steps, s.
    pub steps: Vec<f64>,
    /// Simulated time of each run, s.
    pub duration: f64,
    /// RMS position error above which a run counts as inaccurate, m.
    pub error_bound: f64,
    /// The integrators to map, each with its own sub-step and iteration counts.
    pub methods: Vec<Method>,
}

impl StabilitySetup {
    /// Checks the setup: finite positive stiffnesses, steps no longer than the run, a finite positive
    /// duration and error bound. (A NaN or negative step had become one step of the whole run, through
    /// the rounding to a whole number of steps.) The grid is checked where its scene is built.
    pub fn validate(&self) -> Result<(), StudyError> {
        let invalid = |name, value, reason| StudyError::InvalidInput {
            name,
            value,
            reason,
        };
        if !(self.duration.is_finite() && self.duration > 0.0) {
            return Err(invalid(
                "stability duration",
                self.duration,
                "must be finite and > 0 (s)",
            ));
        }
        if !(self.error_bound.is_finite() && self.error_bound > 0.0) {
            return Err(invalid(
                "stability error bound",
                self.error_bound,
                "must be finite and > 0 (m)",
            ));
        }
        if let Some(&k) = self
            .stiffnesses
            .iter()
            .find(|k| !(k.is_finite() && **k > 0.0))
        {
            return Err(invalid(
                "stability stiffness",
                k,
                "must be finite and > 0 (N/m)",
            ));
        }
        if let Some(&step) = self
            .steps
            .iter()
            .find(|&&h| !(h.is_finite() && h > 0.0 && h <= self.duration))
        {
            return Err(invalid(
                "stability step",
                step,
                "must be finite, > 0 and at most the run's duration (s)",
            ));
        }
        Ok(())
    }
}

/// The map and the predictions.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityMap {
    /// What was measured.
    pub setup: StabilitySetup,
    /// One cell per method, stiffness and step.
    pub cells: Vec<StabilityCell>,
    /// The linear analysis' step limit, one per stiffness.
    pub predictions: Vec<StabilityPrediction>,
}

/// Every method with one sub-step per `step(dt)`; PBD and XPBD with 10 iterations, implicit Euler with
/// CG to 10⁻⁶.
pub fn map_methods() -> Vec<Method> {
    vec![
        Method::ExplicitEuler { substeps: 1 },
        Method::SymplecticEuler { substeps: 1 },
        Method::Verlet { substeps: 1 },
        Method::ImplicitEuler {
            substeps: 1,
            cg_max_iterations: 200,
            cg_tolerance: 1e-6,
        },
        Method::Pbd {
            substeps: 1,
            iterations: 10,
            stiffness: 1.0,
        },
        Method::Xpbd {
            substeps: 1,
            iterations: 10,
        },
        Method::SmallStepsXpbd { substeps: 1 },
    ]
}

/// `count` steps spaced evenly in `log dt` from `smallest` to `largest`, s: both finite and > 0 (a
/// logarithmic spacing has no room for 0; it gave NaN steps).
pub fn log_spaced(smallest: f64, largest: f64, count: usize) -> Result<Vec<f64>, StudyError> {
    for (name, value) in [("smallest step", smallest), ("largest step", largest)] {
        if !(value.is_finite() && value > 0.0) {
            return Err(StudyError::InvalidInput {
                name,
                value,
                reason: "must be finite and > 0 for a logarithmic spacing (s)",
            });
        }
    }
    if count < 2 {
        return Ok(vec![smallest]);
    }
    Ok((0..count)
        .map(|i| smallest * (largest / smallest).powf(i as f64 / (count - 1) as f64))
        .collect())
}

/// Runs every method at every (step, stiffness) of `setup` on [`Scene::undamped_sheet`] and classes
/// each run against a Verlet reference of the same stiffness.
pub fn stability_map(
    setup: &StabilitySetup,
    monitor: &Monitor,
) -> Result<StabilityMap, StudyError> {
    setup.validate()?;
    monitor.add_work((setup.methods.len() * setup.steps.len() * setup.stiffnesses.len()) as u64);
    let mut cells = Vec::new();
    let mut predictions = Vec::new();
    for &stiffness in &setup.stiffnesses {
        let scene = Scene::undamped_sheet(setup.grid, stiffness)?;
        let model = scene.model()?;
        predictions.push(StabilityPrediction {
            stiffness,
            dt_power_iteration: 2.0 / omega_max_power_iteration(&model, &scene.params, 3000),
            dt_gershgorin: 2.0 / omega_max_gershgorin(&model, &scene.params),
        });
        let reference = reference(&scene, &[setup.duration], monitor)?;
        let expected = reference
            .trajectory
            .snapshots
            .last()
            .map(|s| s.positions.clone())
            .unwrap_or_default();
        for &method in &setup.methods {
            for &nominal in &setup.steps {
                // A whole number of steps per run, so every run ends exactly at `duration`.
                let dt = setup.duration / (setup.duration / nominal).round().max(1.0);
                let trajectory =
                    on_one_thread(|| simulate(&scene, method, dt, &[setup.duration], monitor))??;
                let rms = trajectory
                    .snapshots
                    .last()
                    .and_then(|s| position_errors(&s.positions, &expected))
                    .map(|(rms, _)| rms);
                let class = match (trajectory.diverged_at, rms) {
                    (None, Some(rms)) if rms <= setup.error_bound => StabilityClass::Stable,
                    (None, Some(_)) => StabilityClass::Inaccurate,
                    _ => StabilityClass::Diverged,
                };
                monitor.finish_run(&format!(
                    "stability {} k={stiffness:.0} dt={dt:.2e}",
                    method.name()
                ));
                cells.push(StabilityCell {
                    method,
                    stiffness,
                    dt,
                    class,
                    rms_position_error: if class == StabilityClass::Diverged {
                        None
                    } else {
                        rms
                    },
                });
            }
        }
    }
    Ok(StabilityMap {
        setup: setup.clone(),
        cells,
        predictions,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A NaN, negative or too long step, a stiffness or duration that is not a positive number, and a
    /// logarithmic spacing from 0 are refused (a bad step silently became one step of the whole run;
    /// the spacing gave NaN steps).
    #[test]
    fn bad_stability_setups_are_typed_errors() {
        let good = StabilitySetup {
            grid: (4, 3),
            stiffnesses: vec![100.0],
            steps: log_spaced(1e-4, 1e-2, 3).unwrap(),
            duration: 0.1,
            error_bound: 0.01,
            methods: map_methods(),
        };
        assert_eq!(good.steps, vec![1e-4, 1e-4 * 10f64.powf(1.0), 1e-2]);
        assert!(good.validate().is_ok());
        let refused = |f: &dyn Fn(&mut StabilitySetup)| {
            let mut setup = good.clone();
            f(&mut setup);
            match stability_map(&setup, &Monitor::hidden()) {
                Err(StudyError::InvalidInput { name, .. }) => name,
                other => panic!("expected an invalid input, got {:?}", other.err()),
            }
        };
        for step in [f64::NAN, -1e-3, 0.0, 0.5] {
            assert_eq!(refused(&|s| s.steps[1] = step), "stability step");
        }
        assert_eq!(
            refused(&|s| s.stiffnesses = vec![f64::INFINITY]),
            "stability stiffness"
        );
        assert_eq!(refused(&|s| s.duration = 0.0), "stability duration");
        assert_eq!(
            refused(&|s| s.error_bound = f64::NAN),
            "stability error bound"
        );
        assert!(matches!(
            log_spaced(0.0, 1.0, 4),
            Err(StudyError::InvalidInput {
                name: "smallest step",
                ..
            })
        ));
    }
}
