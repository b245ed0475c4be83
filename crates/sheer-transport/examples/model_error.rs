//! The error budget behind the renderer's default scattering model: for each (τ1, Λ), the largest
//! share of the diffuse radiance that single scattering (Frisvad et al. 2005, eqs. (4)–(5)) misses, and
//! the largest relative error of the all-orders table the renderer samples, both against the all-orders
//! solver, over four light/view geometries (μ0, μ) and both faces. Prints a Markdown table
//! (docs/shading-model.md).
//!
//! `cargo run -p sheer-transport --release --example model_error`

use sheer_transport::{
    AllOrdersTable, SlabSolver, single_scattered_reflected_radiance,
    single_scattered_transmitted_radiance,
};

/// (μ0, μ): head-on, oblique, grazing light, grazing view.
const GEOMETRIES: [(f64, f64); 4] = [(1.0, 1.0), (0.7, 0.4), (0.3, 0.9), (0.9, 0.15)];
const TAUS: [f64; 8] = [0.01, 0.05, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0];
const ALBEDOS: [f64; 3] = [0.5, 0.9, 1.0];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let table = AllOrdersTable::read(AllOrdersTable::DEFAULT_PATH)?;
    println!(
        "| τ1 | single scattering misses, Λ = 0.5 | Λ = 0.9 | Λ = 1 | all-orders table's error, Λ = 0.5 | Λ = 0.9 | Λ = 1 |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for tau in TAUS {
        let mut missing = Vec::new();
        let mut table_error = Vec::new();
        for albedo in ALBEDOS {
            let solver = SlabSolver::new(tau, albedo)?;
            let (mut worst_missing, mut worst_table) = (0.0f64, 0.0f64);
            for (mu0, mu) in GEOMETRIES {
                let solution = solver.solve(mu0)?;
                let faces = [
                    (
                        solution.reflected_radiance(mu)?,
                        single_scattered_reflected_radiance(tau, albedo, mu0, mu)?,
                        table.reflected_radiance(tau, albedo, mu0, mu)?,
                    ),
                    (
                        solution.transmitted_radiance(mu)?,
                        single_scattered_transmitted_radiance(tau, albedo, mu0, mu)?,
                        table.transmitted_radiance(tau, albedo, mu0, mu)?,
                    ),
                ];
                for (exact, single, tabulated) in faces {
                    worst_missing = worst_missing.max(1.0 - single / exact);
                    worst_table = worst_table.max((tabulated - exact).abs() / exact);
                }
            }
            missing.push(worst_missing);
            table_error.push(worst_table);
        }
        let percent = |v: f64| format!("{:.1} %", 100.0 * v);
        println!(
            "| {tau} | {} | {} | {} | {} | {} | {} |",
            percent(missing[0]),
            percent(missing[1]),
            percent(missing[2]),
            percent(table_error[0]),
            percent(table_error[1]),
            percent(table_error[2])
        );
    }
    Ok(())
}
