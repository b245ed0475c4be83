//! Times building a flag: `ClothModel::grid` with the hoist pinned, then `Simulation::new`, on grids
//! from the default flag up to 1024 × 745 (762 880 particles), or on the grids given as arguments.
//!
//! `cargo run -p sheer-cloth --release --example setup_time [-- 64x46 1024x745 …]`
//!
//! Construction builds the row strips of a grid's constraints and each particle's nearest pin for the
//! long-range attachments; both are linear (or `n log pins`) in the particle count, so the time per
//! particle printed last should stay roughly level from grid to grid.

use std::time::Instant;

use sheer_cloth::{ClothModel, GridSpec, SimParams, Simulation};

fn main() {
    let mut grids: Vec<(usize, usize)> = Vec::new();
    for arg in std::env::args().skip(1) {
        let parsed = arg
            .split_once('x')
            .and_then(|(c, r)| Some((c.parse().ok()?, r.parse().ok()?)));
        match parsed {
            Some(grid) => grids.push(grid),
            None => {
                eprintln!("error: expected a grid like 64x46, got {arg:?}");
                std::process::exit(2);
            }
        }
    }
    if grids.is_empty() {
        grids = vec![(64, 46), (256, 186), (512, 372), (1024, 745)];
    }
    println!("grid,particles,model_s,simulation_new_s,us_per_particle");
    for (columns, rows) in grids {
        let spec = GridSpec {
            columns,
            rows,
            ..GridSpec::default()
        };
        let start = Instant::now();
        let model = match ClothModel::grid(&spec).and_then(ClothModel::with_hoist_pinned) {
            Ok(model) => model,
            Err(error) => {
                eprintln!("error: {columns}x{rows}: {error}");
                std::process::exit(1);
            }
        };
        let model_s = start.elapsed().as_secs_f64();
        let particles = model.particle_count();
        let start = Instant::now();
        let simulation = match Simulation::new(model, SimParams::default()) {
            Ok(simulation) => simulation,
            Err(error) => {
                eprintln!("error: {columns}x{rows}: {error}");
                std::process::exit(1);
            }
        };
        let new_s = start.elapsed().as_secs_f64();
        drop(simulation);
        println!(
            "{columns}x{rows},{particles},{model_s:.3},{new_s:.3},{:.2}",
            1e6 * (model_s + new_s) / particles as f64
        );
    }
}
