//! Regenerates `assets/all_orders_table.bin` at the workspace root (the multiply-scattered radiance
//! table) with the all-orders solver and reports its size and its interpolation error against the solver
//! at off-grid points.
//!
//! `cargo run -p sheer-transport --release --example make_table` (or `-- OUTPUT.bin` to write elsewhere)

use sheer_transport::{AllOrdersTable, SlabSolver, TableSpec};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let start = std::time::Instant::now();
    let table = AllOrdersTable::generate(TableSpec::default())?;
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| AllOrdersTable::DEFAULT_PATH.to_string());
    table.write(&path)?;
    let bytes = std::fs::metadata(&path)?.len();
    println!(
        "wrote {path}: {bytes} bytes, spec {:?}, generated in {:.1} s",
        table.spec(),
        start.elapsed().as_secs_f64()
    );
    // Interpolation error at points halfway between nodes on every axis (the worst case of
    // multilinear interpolation), over a coarse sweep.
    let spec = table.spec();
    // Two regimes: all cosines, and cosines >= 0.05 (angles below 87 degrees from the normal).
    // Indexed [side][regime], side 0 = reflected, 1 = transmitted.
    let mut worst_total = [[0.0f64; 2]; 2];
    let mut worst_multiple = [[0.0f64; 2]; 2];
    let mut worst_at = [[(0.0, 0.0, 0.0, 0.0); 2]; 2];
    for t in (0..spec.tau_count - 1).step_by(3) {
        let tau1 = spec.tau_at(t as f64 + 0.5);
        for a in (0..spec.albedo_count - 1).step_by(2) {
            let albedo = spec.albedo_at(a as f64 + 0.5, tau1);
            let solver = SlabSolver::new(tau1, albedo)?;
            for k in (0..spec.cosine_count - 1).step_by(2) {
                let mu0 = spec.cosine_at(k as f64 + 0.5);
                let solution = solver.solve(mu0)?;
                for j in (0..spec.cosine_count - 1).step_by(2) {
                    let mu = spec.cosine_at(j as f64 + 0.5);
                    for reflected in [true, false] {
                        let (exact, exact_multiple, approx, approx_multiple) = if reflected {
                            (
                                solution.reflected_radiance(mu)?,
                                solution.multiple_reflected_radiance(mu)?,
                                table.reflected_radiance(tau1, albedo, mu0, mu)?,
                                table.multiple_reflected_radiance(tau1, albedo, mu0, mu)?,
                            )
                        } else {
                            (
                                solution.transmitted_radiance(mu)?,
                                solution.multiple_transmitted_radiance(mu)?,
                                table.transmitted_radiance(tau1, albedo, mu0, mu)?,
                                table.multiple_transmitted_radiance(tau1, albedo, mu0, mu)?,
                            )
                        };
                        let total_error = ((approx - exact) / exact).abs();
                        let multiple_error =
                            ((approx_multiple - exact_multiple) / exact_multiple).abs();
                        let regimes: &[usize] = if mu0.min(mu) >= 0.05 { &[0, 1] } else { &[0] };
                        let side = usize::from(!reflected);
                        for &r in regimes {
                            if total_error > worst_total[side][r] {
                                worst_total[side][r] = total_error;
                                worst_at[side][r] = (tau1, albedo, mu0, mu);
                            }
                            worst_multiple[side][r] = worst_multiple[side][r].max(multiple_error);
                        }
                    }
                }
            }
        }
    }
    for (side, side_name) in ["reflected", "transmitted"].iter().enumerate() {
        for (r, name) in ["all cosines", "mu, mu0 >= 0.05"].iter().enumerate() {
            println!(
                "mid-cell interpolation error, {side_name} ({name}): all-orders radiance max {:.2e} \
                 at (tau1, albedo, mu0, mu) = {:?}; multiple-scattering part max {:.2e}",
                worst_total[side][r], worst_at[side][r], worst_multiple[side][r]
            );
        }
    }
    Ok(())
}
