//! Runs the study from the command line, exactly as `sheer study …` will:
//!
//! `cargo run -p sheer-study --release --example study -- all --out docs` (about 10 minutes; add
//! `--quick` for a smoke run of seconds).

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
