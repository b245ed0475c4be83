//! Typed errors of the study: bad setups, interrupted runs, output that cannot be written.

use thiserror::Error;

/// Why a study step could not produce its result.
#[derive(Debug, Error)]
pub enum StudyError {
    /// The scene's cloth or parameters could not start a simulation.
    #[error(transparent)]
    Setup(#[from] sheer_cloth::SetupError),
    /// The scene's cloth model is invalid.
    #[error(transparent)]
    Model(#[from] sheer_cloth::ModelError),
    /// A study input (time step, sample time, grid size, seed count …) outside its valid range.
    #[error("invalid study input `{name}` = {value}: {reason}")]
    InvalidInput {
        /// The input as the user names it, e.g. `"step"` or `"sample time"`.
        name: &'static str,
        /// The value given, in the input's own unit (seconds for times).
        value: f64,
        /// What the value must be instead.
        reason: &'static str,
    },
    /// The converged reference run itself diverged, so no error can be measured against it.
    #[error(
        "the reference run of scene `{scene}` diverged at t = {time} s; it cannot serve as a reference"
    )]
    ReferenceDiverged {
        /// The scene's name.
        scene: String,
        /// Simulated time of the step that diverged, s.
        time: f64,
    },
    /// Ctrl-C stopped the study.
    #[error("the study was interrupted (Ctrl-C)")]
    Interrupted,
    /// Rayon could not build the one-thread pool the runs are timed on (the payload: its message).
    #[error("cannot start the single-thread pool: {0}")]
    ThreadPool(String),
    /// A file could not be read or written.
    #[error("cannot read or write {path}: {source}")]
    Io {
        /// The file's path, as displayed.
        path: String,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A `--quick` run would overwrite the choice file of a full study (without `--force`).
    #[error(
        "{path} is a full study's choice, which a `--quick` run would replace; choose another --out, \
         or add --force"
    )]
    WouldReplaceFullStudy {
        /// The existing choice file's path.
        path: String,
    },
    /// A `--quick` run would overwrite a file that is not a study's choice file (without `--force`).
    #[error(
        "{path} is not a study's choice file ({reason}), and a `--quick` run would replace it; choose \
         another --out, or add --force"
    )]
    WouldReplaceUnknownFile {
        /// The existing file's path.
        path: String,
        /// Why it is not a choice file: not TOML, or no `quick` flag.
        reason: String,
    },
    /// plotters could not draw or write a chart.
    #[error("cannot draw the chart {path}: {message}")]
    Chart {
        /// The chart's output path.
        path: String,
        /// plotters' message.
        message: String,
    },
    /// The font for a chart's labels could not be read or parsed.
    #[error("cannot read the chart font {path}: {message}")]
    Font {
        /// The font file's path.
        path: String,
        /// What went wrong.
        message: String,
    },
    /// A result could not be encoded (e.g. the choice as TOML) before writing.
    #[error("cannot encode {path}: {message}")]
    Encode {
        /// The file the encoded text was for.
        path: String,
        /// The encoder's message.
        message: String,
    },
}
