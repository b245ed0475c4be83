//! `sheer slab`: the thin-slab model evaluated for CSV rows `tau1,albedo,mu0,mu` (stdin or a file),
//! written as `tau1,albedo,mu0,mu,alpha,l_plus,l_minus` with radiance per unit irradiance normal to the
//! beam (E = 1). Bad rows are reported by number.

use std::io::{BufRead, BufReader};
use std::path::PathBuf;

use clap::Args;
use sheer_slab::{IrradianceConvention, evaluate_csv};

use crate::CliError;

#[derive(Debug, Args)]
pub struct SlabArgs {
    /// Input CSV (default: standard input). An optional header `tau1,albedo,mu0,mu` is skipped.
    pub input: Option<PathBuf>,
    /// Insert eq. (6)'s surface irradiance Φμ0/(4πr²) as printed in the paper (counts μ0 twice).
    #[arg(long)]
    pub paper_literal: bool,
}

pub fn run(args: &SlabArgs) -> Result<(), CliError> {
    let convention = if args.paper_literal {
        IrradianceConvention::PaperLiteral
    } else {
        IrradianceConvention::NormalToBeam
    };
    let input: Box<dyn BufRead> = match &args.input {
        Some(path) => {
            Box::new(BufReader::new(std::fs::File::open(path).map_err(|e| {
                CliError::new(format!("cannot read {}: {e}", path.display()))
            })?))
        }
        None => Box::new(std::io::stdin().lock()),
    };
    let stdout = std::io::stdout();
    evaluate_csv(input, stdout.lock(), convention).map_err(|e| CliError::new(e.to_string()))
}
