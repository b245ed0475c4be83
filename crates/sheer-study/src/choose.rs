//! The automatic choice: the cheapest measured setting whose error meets a budget.

use sheer_cloth::Method;

use crate::work_precision::Row;

/// An error budget: RMS position error at most `max_rms_position_error` (m) at simulated time `time` (s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Budget {
    pub time: f64,
    pub max_rms_position_error: f64,
}

impl Default for Budget {
    /// "RMS position error below 5 mm after 1 s".
    fn default() -> Self {
        Budget {
            time: 1.0,
            max_rms_position_error: 5e-3,
        }
    }
}

/// The chosen setting with its measured error and cost.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    pub scene: String,
    pub method: Method,
    /// RMS position error at the budget's time, m.
    pub rms_position_error: f64,
    /// CPU milliseconds per simulated second (one thread).
    pub cpu_ms_per_simulated_second: f64,
    /// How many measured settings met the budget.
    pub candidates: usize,
}

/// The cheapest row at the budget's time that did not diverge and whose RMS error is within the
/// budget; ties go to the smaller error. `None` if no measured setting meets it.
pub fn choose(budget: &Budget, rows: &[Row]) -> Option<Choice> {
    let meeting: Vec<(&Row, f64)> = rows
        .iter()
        .filter(|r| (r.metrics.time - budget.time).abs() < 1e-9 && !r.metrics.diverged)
        .filter_map(|r| {
            let rms = r.metrics.rms_position_error?;
            (rms <= budget.max_rms_position_error).then_some((r, rms))
        })
        .collect();
    let (best, rms) = meeting.iter().min_by(|(a, ea), (b, eb)| {
        a.cpu_ms_per_simulated_second
            .total_cmp(&b.cpu_ms_per_simulated_second)
            .then(ea.total_cmp(eb))
    })?;
    Some(Choice {
        scene: best.scene.clone(),
        method: best.method,
        rms_position_error: *rms,
        cpu_ms_per_simulated_second: best.cpu_ms_per_simulated_second,
        candidates: meeting.len(),
    })
}
