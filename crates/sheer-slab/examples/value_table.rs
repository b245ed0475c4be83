//! Prints the README's table of exact values of the thin-slab model: α, L+ (eq. 4) and L− (eq. 5) in
//! W/(m²·sr) for a beam of unit irradiance normal to the beam, from the `f64` reference.
//!
//! `cargo run -p sheer-slab --release --example value_table`

use sheer_slab::IrradianceConvention;
use sheer_slab::csv::{REFERENCE_TABLE_INPUTS, evaluate_row, markdown_row};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("| tau1 | albedo | mu0 | mu | alpha | l_plus | l_minus |");
    println!("|---|---|---|---|---|---|---|");
    for [tau1, albedo, mu0, mu] in REFERENCE_TABLE_INPUTS {
        let row = evaluate_row(
            &format!("{tau1},{albedo},{mu0},{mu}"),
            IrradianceConvention::NormalToBeam,
        )?;
        println!("{}", markdown_row(&row));
    }
    Ok(())
}
