//! Error metrics of a run against the reference at one simulated time.

use sheer_cloth::glam::DVec3;

use crate::run::{Snapshot, Trajectory};

/// How far a run is from the reference at one simulated time. Errors are `None` when the run diverged
/// before that time (there is nothing to compare; never NaN).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorMetrics {
    /// Simulated time of the comparison, s.
    pub time: f64,
    /// Root-mean-square particle position error, m.
    pub rms_position_error: Option<f64>,
    /// Largest particle position error, m.
    pub max_position_error: Option<f64>,
    /// The run's own energy drift `(E(t) − E(0)) / |E(0)|` (dimensionless; energies as
    /// `Simulation::total_energy`, gravitational potential zero at y = 0).
    pub relative_energy_drift: Option<f64>,
    /// The reference's drift at the same time, for comparison (a driven or damped scene drifts).
    pub reference_energy_drift: f64,
    /// Largest spring strain `length/rest − 1` of the run (dimensionless).
    pub max_strain: Option<f64>,
    /// Whether the run diverged before this time.
    pub diverged: bool,
}

/// RMS and maximum distance between corresponding positions, m. Both are zero exactly when the
/// positions are identical. `None` when the slices differ in length or are empty.
pub fn position_errors(run: &[DVec3], reference: &[DVec3]) -> Option<(f64, f64)> {
    if run.len() != reference.len() || run.is_empty() {
        return None;
    }
    let mut sum_squares = 0.0;
    let mut max = 0.0f64;
    for (a, b) in run.iter().zip(reference) {
        let d2 = a.distance_squared(*b);
        sum_squares += d2;
        max = max.max(d2);
    }
    Some(((sum_squares / run.len() as f64).sqrt(), max.sqrt()))
}

fn drift(energy: f64, initial: f64) -> f64 {
    // E(0) is never zero in the study's scenes (gravitational energy of a cloth above y = 0); guard
    // anyway so a degenerate scene yields the absolute drift rather than a division by zero.
    if initial != 0.0 {
        (energy - initial) / initial.abs()
    } else {
        energy - initial
    }
}

impl ErrorMetrics {
    /// Compares `run` with `reference` at `time` (both must have a snapshot there; the run may lack it
    /// if it diverged). `None` when the reference has no snapshot at `time`.
    pub fn at(run: &Trajectory, reference: &Trajectory, time: f64) -> Option<ErrorMetrics> {
        let expected: &Snapshot = reference.at(time)?;
        let reference_energy_drift = drift(expected.total_energy, reference.initial_energy);
        let Some(actual) = run.at(time) else {
            return Some(ErrorMetrics {
                time,
                rms_position_error: None,
                max_position_error: None,
                relative_energy_drift: None,
                reference_energy_drift,
                max_strain: None,
                diverged: true,
            });
        };
        let (rms, max) = position_errors(&actual.positions, &expected.positions)?;
        Some(ErrorMetrics {
            time,
            rms_position_error: Some(rms),
            max_position_error: Some(max),
            relative_energy_drift: Some(drift(actual.total_energy, run.initial_energy)),
            reference_energy_drift,
            max_strain: Some(actual.max_strain),
            diverged: false,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn position_errors_vanish_for_identical_positions_only() {
        let a = vec![DVec3::new(0.0, 1.0, 2.0), DVec3::new(-1.0, 0.5, 0.0)];
        assert_eq!(position_errors(&a, &a), Some((0.0, 0.0)));
        let mut b = a.clone();
        b[1].z += 3e-3;
        let (rms, max) = position_errors(&b, &a).unwrap();
        // One of two particles off by 3 mm: max 3 mm, RMS sqrt(9e-6 / 2). Exact up to rounding of a
        // handful of operations (1e-15 relative).
        assert!((max - 3e-3).abs() < 1e-15);
        assert!((rms - (9e-6f64 / 2.0).sqrt()).abs() < 1e-15);
        assert_eq!(position_errors(&a, &a[..1]), None);
    }
}
