//! One timed run: a scene integrated by one method, with snapshots at fixed simulated times.

use sheer_cloth::glam::DVec3;
use sheer_cloth::{Method, StepError};

use crate::cpu::thread_cpu_seconds;
use crate::{Monitor, Scene, StudyError};

/// The state of a run at one simulated time.
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    /// Simulated time, s.
    pub time: f64,
    /// Particle positions, m.
    pub positions: Vec<DVec3>,
    /// Total (kinetic + gravitational + elastic) energy, J.
    pub total_energy: f64,
    /// Largest spring strain `length/rest − 1` (dimensionless).
    pub max_strain: f64,
}

/// A finished (or diverged) run.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    pub method: Method,
    /// Length of each `step` call, s.
    pub step: f64,
    /// Total energy at rest, J.
    pub initial_energy: f64,
    /// One snapshot per requested time reached before any divergence, in time order.
    pub snapshots: Vec<Snapshot>,
    /// CPU seconds the stepping took on this thread (snapshots excluded).
    pub cpu_seconds: f64,
    /// Simulated seconds actually integrated.
    pub simulated_seconds: f64,
    /// Simulated time of the step that diverged, if one did.
    pub diverged_at: Option<f64>,
}

impl Trajectory {
    /// Measured cost: CPU milliseconds per simulated second.
    pub fn cpu_ms_per_simulated_second(&self) -> f64 {
        if self.simulated_seconds > 0.0 {
            1e3 * self.cpu_seconds / self.simulated_seconds
        } else {
            0.0
        }
    }

    /// The snapshot taken at `time` (within half a step), if the run got there.
    pub fn at(&self, time: f64) -> Option<&Snapshot> {
        self.snapshots
            .iter()
            .find(|s| (s.time - time).abs() <= 0.5 * self.step)
    }
}

/// Integrates `scene` with `method`, calling `step(step)` until the last of `sample_times` (s), and
/// keeps a snapshot at each sample time (rounded to a whole number of steps). A diverged step ends the
/// run (its snapshots so far are kept). Call it inside a one-thread pool for comparable costs.
pub fn simulate(
    scene: &Scene,
    method: Method,
    step: f64,
    sample_times: &[f64],
    monitor: &Monitor,
) -> Result<Trajectory, StudyError> {
    if !(step.is_finite() && step > 0.0) {
        return Err(StudyError::InvalidInput {
            name: "step",
            value: step,
            reason: "must be finite and > 0 s",
        });
    }
    let mut sample_steps = Vec::with_capacity(sample_times.len());
    for &time in sample_times {
        if !(time.is_finite() && time > 0.0) {
            return Err(StudyError::InvalidInput {
                name: "sample time",
                value: time,
                reason: "must be finite and > 0 s",
            });
        }
        sample_steps.push((time / step).round().max(1.0) as u64);
    }
    sample_steps.sort_unstable();
    let mut sim = scene.simulation(method)?;
    let mut trajectory = Trajectory {
        method,
        step,
        initial_energy: sim.total_energy(),
        snapshots: Vec::with_capacity(sample_steps.len()),
        cpu_seconds: 0.0,
        simulated_seconds: 0.0,
        diverged_at: None,
    };
    let last = sample_steps.last().copied().unwrap_or(0);
    let mut next_sample = 0;
    let mut taken = 0u64;
    let mut started = thread_cpu_seconds();
    while taken < last {
        match sim.step(step) {
            Ok(_) => taken += 1,
            Err(StepError::Diverged { .. }) => {
                trajectory.diverged_at = Some((taken + 1) as f64 * step);
                break;
            }
            Err(StepError::InvalidTimeStep(value)) => {
                return Err(StudyError::InvalidInput {
                    name: "step",
                    value,
                    reason: "rejected by the simulator",
                });
            }
        }
        if taken == sample_steps[next_sample] {
            let now = thread_cpu_seconds();
            trajectory.cpu_seconds += now - started;
            while next_sample < sample_steps.len() && sample_steps[next_sample] == taken {
                trajectory.snapshots.push(Snapshot {
                    time: taken as f64 * step,
                    positions: sim.positions().to_vec(),
                    total_energy: sim.total_energy(),
                    max_strain: sim.max_strain(None),
                });
                next_sample += 1;
            }
            started = thread_cpu_seconds();
        }
        // Checking the flag every few steps keeps Ctrl-C responsive without costing a measurable share.
        if taken.is_multiple_of(16) {
            monitor.check()?;
        }
    }
    trajectory.cpu_seconds += thread_cpu_seconds() - started;
    trajectory.simulated_seconds = taken as f64 * step;
    Ok(trajectory)
}

/// Runs `work` on a fresh one-thread rayon pool, so every cost the study reports is single-threaded.
pub fn on_one_thread<R: Send>(work: impl FnOnce() -> R + Send) -> Result<R, StudyError> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| StudyError::ThreadPool(e.to_string()))?;
    Ok(pool.install(work))
}
