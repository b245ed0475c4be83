//! `sheer`: the thin-cloth engine's command line.
//!
//! Every failure prints one line, `error: …`, and exits with status 1 (usage errors: clap's status 2).

mod bench_sim;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// A one-line, user-facing error.
#[derive(Debug)]
pub struct CliError(String);

impl CliError {
    pub fn new(message: impl Into<String>) -> Self {
        CliError(message.into())
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
