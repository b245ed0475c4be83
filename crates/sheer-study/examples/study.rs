//! The study without the app: a thin wrapper over [`sheer_study::StudyArgs`] and [`sheer_study::run`],
//! the same two the app's `sheer study …` subcommand uses, for running the study from this crate alone.
//!
//! `cargo run -p sheer-study --release --example study -- choose --quick --out /tmp/study` (seconds);
//! the published results come from `cargo run --release -- study all --out docs`.

use clap::Parser;
use sheer_study::{StudyArgs, run};

#[derive(Parser)]
#[command(
    name = "study",
    about = "Speed against accuracy of the sheer cloth simulator"
)]
struct Cli {
    #[command(flatten)]
    study: StudyArgs,
}

fn main() {
    let cli = Cli::parse();
    if let Err(error) = run(&cli.study) {
        eprintln!("error: {error}");
        std::process::exit(1);
    }
}
