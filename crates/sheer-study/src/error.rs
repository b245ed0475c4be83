//! Typed errors of the study: bad setups, interrupted runs, output that cannot be written.

use thiserror::Error;

/// Why a study step could not produce its result.
#[derive(Debug, Error)]
pub enum StudyError {
    #[error(transparent)]
    Setup(#[from] sheer_cloth::SetupError),
    #[error(transparent)]
    Model(#[from] sheer_cloth::ModelError),
    #[error("invalid study input `{name}` = {value}: {reason}")]
    InvalidInput {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    #[error(
        "the reference run of scene `{scene}` diverged at t = {time} s; it cannot serve as a reference"
    )]
    ReferenceDiverged { scene: String, time: f64 },
    #[error("the study was interrupted (Ctrl-C)")]
    Interrupted,
    #[error("cannot start the single-thread pool: {0}")]
    ThreadPool(String),
    #[error("cannot read or write {path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "{path} is a full study's choice, which a `--quick` run would replace; choose another --out, \
         or add --force"
    )]
    WouldReplaceFullStudy { path: String },
    #[error(
        "{path} is not a study's choice file ({reason}), and a `--quick` run would replace it; choose \
         another --out, or add --force"
    )]
    WouldReplaceUnknownFile { path: String, reason: String },
    #[error("cannot draw the chart {path}: {message}")]
    Chart { path: String, message: String },
    #[error("cannot read the chart font {path}: {message}")]
    Font { path: String, message: String },
    #[error("cannot encode {path}: {message}")]
    Encode { path: String, message: String },
}
