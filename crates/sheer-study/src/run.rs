//! One timed run: a scene integrated by one method, with snapshots at fixed simulated times and, when
//! the scene asks for it, the time-averaged coverage over its window.

use sheer_cloth::glam::DVec3;
use sheer_cloth::{Method, StepError};

use crate::coverage::{CoverageAccumulator, MeanCoverage};
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
    /// The integrator the run used.
    pub method: Method,
    /// Length of each `step` call, s.
    pub step: f64,
    /// Total energy at rest, J.
    pub initial_energy: f64,
    /// One snapshot per requested time reached before any divergence, in time order.
    pub snapshots: Vec<Snapshot>,
    /// Time-averaged coverage over the scene's window (`None`: the scene has none, or the run diverged
    /// before the window's end).
    pub coverage: Option<MeanCoverage>,
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

    /// Simulated times of the snapshots, s, in order.
    pub fn snapshot_times(&self) -> Vec<f64> {
        self.snapshots.iter().map(|s| s.time).collect()
    }

    /// The snapshot taken at `time` (within half a step), if the run got there.
    pub fn at(&self, time: f64) -> Option<&Snapshot> {
        self.snapshots
            .iter()
            .find(|s| (s.time - time).abs() <= 0.5 * self.step)
    }
}

/// Integrates `scene` with `method`, calling `step(step)` until the last of `sample_times` (s) or the
/// end of the scene's coverage window, whichever is later, and keeps a snapshot at each sample time
/// (rounded to a whole number of steps) and the coverage of every step that ends inside the window. A
/// diverged step ends the run (its snapshots so far are kept; its coverage is dropped). Snapshots and
/// coverage are not counted in the run's CPU time. Call it inside a one-thread pool for comparable
/// costs.
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
    let to_steps = |time: f64| (time / step).round().max(1.0) as u64;
    let mut sample_steps = Vec::with_capacity(sample_times.len());
    for &time in sample_times {
        if !(time.is_finite() && time > 0.0) {
            return Err(StudyError::InvalidInput {
                name: "sample time",
                value: time,
                reason: "must be finite and > 0 s",
            });
        }
        // The cast below would saturate at u64::MAX: a run that never ends.
        if time / step > f64::from(u32::MAX) {
            return Err(StudyError::InvalidInput {
                name: "sample time",
                value: time,
                reason: "is more than 2³² steps away: choose a longer step",
            });
        }
        sample_steps.push(to_steps(time));
    }
    sample_steps.sort_unstable();
    let window = match scene.coverage {
        Some(w)
            if w.start.is_finite() && w.end.is_finite() && 0.0 < w.start && w.start <= w.end =>
        {
            Some((to_steps(w.start), to_steps(w.end), w.viewport))
        }
        Some(w) => {
            return Err(StudyError::InvalidInput {
                name: "coverage window start",
                value: w.start,
                reason: "the window must satisfy 0 < start ≤ end, both finite (s)",
            });
        }
        None => None,
    };
    let mut accumulator = window
        .map(|(_, _, viewport)| CoverageAccumulator::new(viewport))
        .transpose()?;
    let mut sim = scene.simulation(method)?;
    let triangles = sim.triangles().to_vec();
    let mut trajectory = Trajectory {
        method,
        step,
        initial_energy: sim.total_energy(),
        snapshots: Vec::with_capacity(sample_steps.len()),
        coverage: None,
        cpu_seconds: 0.0,
        simulated_seconds: 0.0,
        diverged_at: None,
    };
    let last = sample_steps
        .last()
        .copied()
        .unwrap_or(0)
        .max(window.map_or(0, |(_, end, _)| end));
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
        let sample_now = sample_steps.get(next_sample) == Some(&taken);
        let cover_now = window.is_some_and(|(start, end, _)| (start..=end).contains(&taken));
        if sample_now || cover_now {
            trajectory.cpu_seconds += thread_cpu_seconds() - started;
            while sample_steps.get(next_sample) == Some(&taken) {
                trajectory.snapshots.push(Snapshot {
                    time: taken as f64 * step,
                    positions: sim.positions().to_vec(),
                    total_energy: sim.total_energy(),
                    max_strain: sim.max_strain(None),
                });
                next_sample += 1;
            }
            if cover_now && let Some(accumulator) = accumulator.as_mut() {
                accumulator.add(sim.positions(), &triangles)?;
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
    if trajectory.diverged_at.is_none() {
        trajectory.coverage = accumulator.and_then(|a| a.finish());
    }
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
