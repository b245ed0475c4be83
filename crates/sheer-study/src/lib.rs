//! # sheer-study
//!
//! Speed against accuracy for the `sheer-cloth` simulator: a converged reference solution per scene,
//! error metrics against it at fixed simulated times, measured CPU cost, work–precision charts,
//! stability maps (time step × stiffness), an ablation table of the model's parts, a phase-insensitive
//! accuracy measure for the chaotic flag (time-averaged coverage, [`coverage`]) and an automatic
//! choice of the cheapest method that meets an error budget (written to `docs/choice.toml`).
//!
//! Every run is timed on one rayon thread with the thread's own CPU clock, so the costs compare across
//! methods and do not count time the thread spent waiting for the CPU (see [`cpu`]).
//!
//! ```no_run
//! use sheer_study::{Scene, StudyConfig, Monitor, reference, work_precision};
//!
//! let config = StudyConfig::quick();
//! let scene = Scene::flag(config.sweep_grid)?;
//! let monitor = Monitor::hidden();
//! let reference = reference(&scene, &config.sample_times, &monitor)?;
//! let rows = work_precision(&scene, &reference, &config.sweep(&scene), &monitor)?;
//! assert!(!rows.is_empty());
//! # Ok::<(), sheer_study::StudyError>(())
//! ```

// Standard output belongs to the program using the library: results and errors are returned.
#![warn(clippy::print_stdout)]

pub mod ablation;
pub mod chart;
pub mod choose;
pub mod coverage;
pub mod cpu;
mod error;
pub mod metrics;
pub mod monitor;
pub mod outputs;
pub mod reference;
pub mod run;
pub mod scene;
pub mod seeds;
pub mod silhouette;
pub mod stability;
mod whole_file;
pub mod work_precision;

pub use ablation::{AblationRow, CostRatio, CostTiming, ablation};
pub use choose::{Budget, Choice, ChoiceFile, DEFAULT_COVERAGE_BUDGET, choose};
pub use coverage::{CoverageWindow, MeanCoverage, coverage_difference};
pub use error::StudyError;
pub use metrics::{ErrorMetrics, position_errors};
pub use monitor::Monitor;
pub use reference::{HalvingCheck, Reference, reference};
pub use run::{Snapshot, Trajectory, simulate};
pub use scene::{Pinning, Scene};
pub use seeds::{SeedRow, SeedSummary, across_seeds};
pub use stability::{StabilityCell, StabilityClass, stability_map};
pub use work_precision::{Row, StudyConfig, Sweep, work_precision};
