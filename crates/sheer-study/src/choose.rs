//! The automatic choice: the cheapest measured setting whose error meets a budget, and the
//! machine-readable record of it (`docs/choice.toml`) that the app's default scene is tested against.

use serde::{Deserialize, Serialize};
use sheer_cloth::{GridSpec, Method, SimParams};

use crate::work_precision::Row;

/// The default coverage budget of the flag: a time-averaged coverage difference of at most 4 % of the
/// reference's mean covered area. Sized by the measured difference between the converged 32 × 23 and
/// 64 × 46 flags (see `docs/study.md`): an integrator closer to the 64 × 46 reference than that
/// is not worth more CPU, because halving the cloth's resolution would change the picture as much.
pub const DEFAULT_COVERAGE_BUDGET: f64 = 0.04;

/// An error budget.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// RMS position error at most `max_error` (m) at simulated time `time` (s). Meaningful for the
    /// flag only inside its predictability horizon (≈ 0.25 s): later it measures decorrelation.
    RmsPosition {
        /// Simulated time of the comparison, s.
        time: f64,
        /// The largest RMS position error allowed, m.
        max_error: f64,
    },
    /// Time-averaged coverage difference ([`crate::coverage`]) at most `max_difference`
    /// (dimensionless), over the scene's coverage window. Insensitive to the flutter's phase.
    Coverage {
        /// The largest time-averaged coverage difference allowed (dimensionless, in [0, 1]).
        max_difference: f64,
    },
}

impl Default for Budget {
    /// The flag's default: [`Budget::Coverage`] with [`DEFAULT_COVERAGE_BUDGET`].
    fn default() -> Self {
        Budget::Coverage {
            max_difference: DEFAULT_COVERAGE_BUDGET,
        }
    }
}

impl Budget {
    /// The measured error this budget constrains, for one row: RMS position error (m) at the budget's
    /// time, or the run's coverage difference. `None` when the row does not carry it (another time, a
    /// diverged run, no coverage).
    pub fn error_of(&self, row: &Row) -> Option<f64> {
        match *self {
            Budget::RmsPosition { time, .. } => {
                if (row.metrics.time - time).abs() < 1e-9 && !row.metrics.diverged {
                    row.metrics.rms_position_error
                } else {
                    None
                }
            }
            Budget::Coverage { .. } => row.coverage_difference,
        }
    }

    /// The bound.
    pub fn limit(&self) -> f64 {
        match *self {
            Budget::RmsPosition { max_error, .. } => max_error,
            Budget::Coverage { max_difference } => max_difference,
        }
    }

    /// In words, e.g. "RMS position error ≤ 5 mm at t = 0.25 s".
    pub fn describe(&self) -> String {
        match *self {
            Budget::RmsPosition { time, max_error } => {
                format!(
                    "RMS position error ≤ {} mm at t = {time} s",
                    max_error * 1e3
                )
            }
            Budget::Coverage { max_difference } => format!(
                "time-averaged coverage difference ≤ {max_difference} ({} % of the reference's mean covered area)",
                max_difference * 100.0
            ),
        }
    }
}

/// The chosen setting with its measured error and cost.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    /// Name of the scene the choice was made for.
    pub scene: String,
    /// The cheapest measured method (with its sub-steps and iterations) that meets the budget.
    pub method: Method,
    /// The budget it meets.
    pub budget: Budget,
    /// The measured error the budget constrains ([`Budget::error_of`]).
    pub error: f64,
    /// CPU milliseconds per simulated second (one thread).
    pub cpu_ms_per_simulated_second: f64,
    /// How many measured settings met the budget.
    pub candidates: usize,
}

/// The cheapest setting whose error is within the budget; ties go to the smaller error. Each method
/// setting counts once (a run has a row per sample time). `None` if no measured setting meets it.
pub fn choose(budget: &Budget, rows: &[Row]) -> Option<Choice> {
    let mut meeting: Vec<(&Row, f64)> = Vec::new();
    for row in rows {
        let Some(error) = budget.error_of(row) else {
            continue;
        };
        if error <= budget.limit() && !meeting.iter().any(|(r, _)| r.method == row.method) {
            meeting.push((row, error));
        }
    }
    let (best, error) = meeting.iter().min_by(|(a, ea), (b, eb)| {
        a.cpu_ms_per_simulated_second
            .total_cmp(&b.cpu_ms_per_simulated_second)
            .then(ea.total_cmp(eb))
    })?;
    Some(Choice {
        scene: best.scene.clone(),
        method: best.method,
        budget: *budget,
        error: *error,
        cpu_ms_per_simulated_second: best.cpu_ms_per_simulated_second,
        candidates: meeting.len(),
    })
}

/// Above this cost (CPU ms per simulated second, one thread) a default leaves the app less than half
/// of each frame for normals, shading and drawing: not a real-time choice.
pub const REAL_TIME_CPU_MS_PER_SIMULATED_SECOND: f64 = 500.0;

/// `docs/choice.toml`: the automatic choice for the app's default flag, what it was measured on and
/// against which budget. The app tests that its default scene uses this method on this flag.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChoiceFile {
    /// Written by a `--quick` run (small grids, short window): a smoke test, not a choice for the app.
    pub quick: bool,
    /// The chosen method and what it measured.
    pub choice: ChoiceRecord,
    /// The budget it was chosen against.
    pub budget: BudgetRecord,
    /// The converged reference and the yardsticks the budget is sized by.
    pub reference: ReferenceRecord,
    /// The flag the choice was measured on (the app's default, method included).
    pub scene: SceneRecord,
}

/// The chosen method and what it measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChoiceRecord {
    /// [`Method::name`].
    pub method: String,
    /// [`Method::substeps`]: sub-steps per 1/60 s frame.
    pub substeps: u32,
    /// [`Method::iterations`] (1 for single-iteration methods; the CG cap for implicit Euler).
    pub iterations: u32,
    /// The budgeted error: coverage difference (dimensionless) or RMS position error (m).
    pub error: f64,
    /// Time-averaged coverage difference against the reference, when measured.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub coverage_difference: Option<f64>,
    /// RMS position error against the reference, m, as `[time_s, error_m]` pairs.
    pub rms_position_error_m: Vec<[f64; 2]>,
    /// CPU milliseconds per simulated second (one thread).
    pub cpu_ms_per_simulated_second: f64,
    /// Whether the cost is within [`REAL_TIME_CPU_MS_PER_SIMULATED_SECOND`].
    pub real_time: bool,
    /// How many measured settings met the budget.
    pub candidates: usize,
}

/// The budget in data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BudgetRecord {
    /// `coverage` or `rms_position`.
    pub kind: String,
    /// Coverage: the largest coverage difference; RMS: the largest RMS position error, m.
    pub max: f64,
    /// RMS: the simulated time of the comparison, s.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub time_s: Option<f64>,
    /// Coverage: the averaging window, s.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub window_s: Option<[f64; 2]>,
}

/// The reference and the yardsticks the budget is sized by.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceRecord {
    /// [`Method::name`] of the converged reference run.
    pub method: String,
    /// Its sub-steps per 1/60 s frame.
    pub substeps: u32,
    /// Coverage difference between the reference and the same at twice its step.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub coverage_halving: Option<f64>,
    /// RMS position difference between the reference and the same at twice its step, m, as
    /// `[time_s, difference_m]` pairs.
    pub rms_halving_m: Vec<[f64; 2]>,
    /// The grid of the coarser converged reference.
    pub coarse_grid: [usize; 2],
    /// Coverage difference between the coarser grid's converged reference and this one.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub resolution_coverage_difference: Option<f64>,
}

/// The measured flag.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneRecord {
    /// The particle grid: counts, size (m), areal density (kg/m²) and placement.
    pub flag: GridSpec,
    /// The simulation parameters, the chosen method included.
    pub simulation: SimParams,
}

impl BudgetRecord {
    /// The record of `budget`, with the coverage `window` (s) when it applies.
    pub fn of(budget: &Budget, window: [f64; 2]) -> BudgetRecord {
        match *budget {
            Budget::RmsPosition { time, max_error } => BudgetRecord {
                kind: "rms_position".into(),
                max: max_error,
                time_s: Some(time),
                window_s: None,
            },
            Budget::Coverage { max_difference } => BudgetRecord {
                kind: "coverage".into(),
                max: max_difference,
                time_s: None,
                window_s: Some(window),
            },
        }
    }
}
