//! Regenerates `assets/all_orders_table.bin` (the multiply-scattered radiance table) with the all-orders
//! solver and reports its size and its interpolation error against the solver at off-grid points.
//!
//! `cargo run -p sheer-transport --release --example make_table`

use sheer_transport::{AllOrdersTable, SlabSolver, TableSpec};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let start = std::time::Instant::now();
    let table = AllOrdersTable::generate(TableSpec::default())?;
    let path = AllOrdersTable::DEFAULT_PATH;
    table.write(path)?;
    let bytes = std::fs::metadata(path)?.len();
    println!(
        "wrote {path}: {bytes} bytes, spec {:?}, generated in {:.1} s",
        table.spec(),
        start.elapsed().as_secs_f64()
    );
    // Interpolation error at points halfway between nodes on every axis (the worst case of
    // multilinear interpolation), over a coarse sweep.
    let spec = table.spec();
    let mut worst_total: f64 = 0.0;
    let mut worst_multiple: f64 = 0.0;
    let mut worst_at = (0.0, 0.0, 0.0, 0.0);
    for t in (0..spec.tau_count - 1).step_by(4) {
        let log_tau = spec.log10_tau_min
            + (t as f64 + 0.5) / (spec.tau_count - 1) as f64
                * (spec.log10_tau_max - spec.log10_tau_min);
        let tau1 = 10f64.powf(log_tau);
        for a in (0..spec.albedo_count - 1).step_by(2) {
            let s = (a as f64 + 0.5) / (spec.albedo_count - 1) as f64;
            let albedo = 1.0 - s * s;
            let solver = SlabSolver::new(tau1, albedo)?;
            for k in (0..spec.cosine_count - 1).step_by(3) {
                let x0 = (k as f64 + 0.5) / (spec.cosine_count - 1) as f64;
                let mu0 = x0 * x0;
                let solution = solver.solve(mu0)?;
                for j in (0..spec.cosine_count - 1).step_by(3) {
                    let x = (j as f64 + 0.5) / (spec.cosine_count - 1) as f64;
                    let mu = x * x;
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
                        if total_error > worst_total {
                            worst_total = total_error;
                            worst_at = (tau1, albedo, mu0, mu);
                        }
                        worst_multiple = worst_multiple
                            .max(((approx_multiple - exact_multiple) / exact_multiple).abs());
                    }
                }
            }
        }
    }
    println!(
        "mid-cell interpolation error: all-orders radiance max {worst_total:.2e} (at tau1, albedo, \
         mu0, mu = {worst_at:?}), multiple-scattering part max {worst_multiple:.2e}"
    );
    Ok(())
}
