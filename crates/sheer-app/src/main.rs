//! `sheer`: the thin-cloth engine's command line.
//!
//! Every failure prints one line, `error: …`, and exits with status 1 (usage errors: clap's status 2).

mod bench_sim;
mod scene;
mod simulate;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// A one-line, user-facing error.
#[derive(Debug)]
pub struct CliError(String);

impl CliError {
    pub fn new(message: impl Into<String>) -> Self {
        CliError(message.into())
    }

    /// Appends the line number of `span` in `text`, when there is one.
    pub fn with_span(self, text: &str, span: Option<std::ops::Range<usize>>) -> Self {
        match span {
            Some(span) => {
                let start = span.start.min(text.len());
                let line = text[..start].matches('\n').count() + 1;
                let source = text.lines().nth(line - 1).unwrap_or("").trim();
                CliError(format!("{} (line {line}: `{source}`)", self.0))
            }
            None => self,
        }
    }
}

impl std::fmt::Display for CliError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // One line, whatever the source said.
        f.write_str(&self.0.replace('\n', " "))
    }
}

impl From<sheer_cloth::ModelError> for CliError {
    fn from(e: sheer_cloth::ModelError) -> Self {
        CliError(e.to_string())
    }
}

impl From<sheer_cloth::SetupError> for CliError {
    fn from(e: sheer_cloth::SetupError) -> Self {
        CliError(e.to_string())
    }
}

/// The scene at `path`, or the default scene when `None`.
pub fn load_scene(path: Option<&std::path::Path>) -> Result<scene::Scene, CliError> {
    match path {
        Some(path) => scene::Scene::load(path),
        None => {
            let default = scene::Scene::default();
            let path = default.base_dir.join("default.scene.toml");
            if path.exists() {
                scene::Scene::load(&path)
            } else {
                Ok(default)
            }
        }
    }
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
pub fn progress_bar(length: u64, message: &'static str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(length);
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(message);
    bar
}

#[derive(Debug, Parser)]
#[command(
    name = "sheer",
    version,
    about = "Thin cloth, simulated and rendered as thin slabs (Frisvad et al. 2005)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate a scene's flag and write every frame's mesh as OBJ.
    Simulate(simulate::SimulateArgs),
    /// Benchmarks.
    #[command(subcommand)]
    Bench(BenchCommand),
}

#[derive(Debug, Subcommand)]
enum BenchCommand {
    /// Simulation cost per 60 Hz frame for each method and grid.
    Sim(bench_sim::BenchSimArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Simulate(args) => simulate::run(args),
        Command::Bench(BenchCommand::Sim(args)) => bench_sim::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::FAILURE
        }
    }
}
