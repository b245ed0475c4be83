//! The reference solution of a scene: the same model integrated by velocity Verlet (second order,
//! symplectic; Swope et al. 1982) at a step far below its stability limit, checked by halving.
//!
//! The reference step is `safety × 2/ω_max` with `ω_max` the Gershgorin bound on the highest
//! undamped frequency (see [`crate::stability::omega_max_gershgorin`]), rounded to a whole number of
//! sub-steps per frame. The halving check integrates again at half that step; their difference at
//! each sample time bounds the reference's own error (for a second-order method the finer run's error
//! is about a third of it), and the study reports it beside the errors it measures; likewise the
//! difference of their time-averaged coverages ([`crate::coverage`]) when the scene measures one. The
//! reference renews the wind's forces at every force evaluation whatever the scene's
//! `wind.renewal_interval` and `wind.per_substep`: it stands for the model, which a held wind
//! approximates.

use sheer_cloth::Method;

use crate::coverage::coverage_difference;
use crate::metrics::position_errors;
use crate::run::{Trajectory, on_one_thread, simulate};
use crate::stability::omega_max_gershgorin;
use crate::{Monitor, Scene, StudyError};

/// Fraction of the explicit stability limit `2/ω_max` used as the reference's coarse sub-step.
pub const REFERENCE_SAFETY: f64 = 0.25;

/// The difference between the reference at step `h` and at `h/2`, at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalvingCheck {
    /// Simulated time of the comparison, s.
    pub time: f64,
    /// RMS position difference, m.
    pub rms_difference: f64,
    /// Largest position difference, m.
    pub max_difference: f64,
}

/// A converged solution of a scene: the finer of the two halving runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    /// Name of the scene it solves.
    pub scene: String,
    /// The method and sub-step count of the finer run.
    pub method: Method,
    /// Sub-step length of the finer run, s.
    pub substep: f64,
    /// The finer run's samples.
    pub trajectory: Trajectory,
    /// Its difference from the coarser run at each sample time: how converged it is.
    pub halving: Vec<HalvingCheck>,
    /// Coverage difference (dimensionless) of the coarser run against the finer one, when the scene
    /// measures coverage: errors in coverage below it are not resolved.
    pub coverage_halving: Option<f64>,
}

impl Reference {
    /// The halving difference at `time`, if sampled.
    pub fn halving_at(&self, time: f64) -> Option<&HalvingCheck> {
        self.halving
            .iter()
            .find(|h| (h.time - time).abs() <= 0.5 * self.trajectory.step)
    }
}

/// Sub-steps per frame for Verlet at `safety × 2/ω_max`.
pub fn reference_substeps(scene: &Scene, safety: f64) -> Result<u32, StudyError> {
    let omega_max = omega_max_gershgorin(&scene.model()?, &scene.params);
    let substep = safety * 2.0 / omega_max;
    let substeps = (scene.frame / substep).ceil();
    if !(substeps.is_finite() && substeps >= 1.0 && substeps < u32::MAX as f64) {
        return Err(StudyError::InvalidInput {
            name: "reference sub-steps",
            value: substeps,
            reason: "the scene's stiffest spring needs an impossible step",
        });
    }
    Ok(substeps as u32)
}

/// The reference of `scene` sampled at `sample_times` (s), with its halving check.
pub fn reference(
    scene: &Scene,
    sample_times: &[f64],
    monitor: &Monitor,
) -> Result<Reference, StudyError> {
    // The converged solution of the model renews the wind at every force evaluation: holding it, for a
    // time (`Wind::renewal_interval`) or for the whole frame (`Wind::per_substep = false`), is an
    // approximation a run makes, not part of the model.
    let mut scene = scene.clone();
    scene.params.wind.renew_at_every_evaluation();
    let scene = &scene;
    let substeps = reference_substeps(scene, REFERENCE_SAFETY)?;
    monitor.add_work(2);
    let run = |substeps: u32| -> Result<Trajectory, StudyError> {
        let trajectory = on_one_thread(|| {
            simulate(
                scene,
                Method::Verlet { substeps },
                scene.frame,
                sample_times,
                monitor,
            )
        })??;
        if let Some(time) = trajectory.diverged_at {
            return Err(StudyError::ReferenceDiverged {
                scene: scene.name.clone(),
                time,
            });
        }
        monitor.finish_run(&format!("{} reference, verlet ×{substeps}", scene.name));
        Ok(trajectory)
    };
    let coarse = run(substeps)?;
    let fine = run(2 * substeps)?;
    let halving = fine
        .snapshots
        .iter()
        .filter_map(|f| {
            let c = coarse.at(f.time)?;
            let (rms, max) = position_errors(&c.positions, &f.positions)?;
            Some(HalvingCheck {
                time: f.time,
                rms_difference: rms,
                max_difference: max,
            })
        })
        .collect();
    let coverage_halving = coarse
        .coverage
        .as_ref()
        .zip(fine.coverage.as_ref())
        .and_then(|(c, f)| coverage_difference(c, f));
    Ok(Reference {
        scene: scene.name.clone(),
        method: Method::Verlet {
            substeps: 2 * substeps,
        },
        substep: scene.frame / (2 * substeps) as f64,
        trajectory: fine,
        halving,
        coverage_halving,
    })
}
