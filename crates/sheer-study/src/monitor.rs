//! Progress and interruption: an `indicatif` bar plus a cancel flag that the program's Ctrl-C handler sets.
//!
//! Every long loop of the study calls [`Monitor::check`] between frames, so Ctrl-C stops a sweep within
//! one frame of simulated time and the study returns [`StudyError::Interrupted`].

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use indicatif::{ProgressBar, ProgressStyle};

use crate::StudyError;

/// Progress bar and cancel flag shared by the study's loops.
#[derive(Clone, Debug)]
pub struct Monitor {
    bar: ProgressBar,
    cancel: Arc<AtomicBool>,
    /// Standard error is not a terminal (a log file, CI): the bar is not drawn, so print one line per
    /// finished run instead.
    log_lines: bool,
}

impl Monitor {
    /// No bar and a cancel flag nobody sets (tests, library use).
    pub fn hidden() -> Monitor {
        Monitor {
            bar: ProgressBar::hidden(),
            cancel: Arc::new(AtomicBool::new(false)),
            log_lines: false,
        }
    }

    /// A bar on standard error and the caller's cancel flag (a program sets it from its Ctrl-C
    /// handler; the study stops within one frame once it is set).
    pub fn with_progress_bar(cancel: Arc<AtomicBool>) -> Monitor {
        let bar = ProgressBar::new(0);
        bar.set_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} runs  {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        let log_lines = !std::io::IsTerminal::is_terminal(&std::io::stderr());
        Monitor {
            bar,
            cancel,
            log_lines,
        }
    }

    /// `Err(Interrupted)` once the cancel flag is set.
    pub fn check(&self) -> Result<(), StudyError> {
        if self.cancel.load(Ordering::Relaxed) {
            Err(StudyError::Interrupted)
        } else {
            Ok(())
        }
    }

    /// Adds `runs` to the bar's total.
    pub fn add_work(&self, runs: u64) {
        self.bar.inc_length(runs);
    }

    /// One run finished; `message` says which.
    pub fn finish_run(&self, message: &str) {
        self.bar.set_message(message.to_string());
        self.bar.inc(1);
        if self.log_lines {
            let length = self.bar.length().unwrap_or(0);
            eprintln!("[{}/{}] {message}", self.bar.position(), length);
        }
    }

    /// Prints a line above the bar (or to standard error when hidden bars print nothing).
    pub fn println(&self, line: &str) {
        if self.log_lines {
            eprintln!("{line}");
        } else if !self.bar.is_hidden() {
            self.bar.println(line);
        }
    }

    /// Clears the bar at the end.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
