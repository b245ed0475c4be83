//! Waves the default flag (1.1 m × 0.8 m, 64 × 46 particles, 0.2 kg/m², hoist pinned) in a 6 m/s wind for
//! a few seconds with every method and prints where the fly-end corner is and what a frame cost.
//!
//! `cargo run -p sheer-cloth --release --example flag [seconds]`

use std::time::Instant;

use sheer_cloth::glam::DVec3;
use sheer_cloth::{ClothModel, GridSpec, Method, SimParams, Simulation};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seconds: f64 = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(3.0);
    let frame = 1.0 / 60.0;
    let frames = (seconds / frame).round() as usize;
    let spec = GridSpec::default();
    println!(
        "{:<18} {:>9} {:>28} {:>12}",
        "method", "ms/frame", "fly-end corner (m)", "max strain"
    );
    for method in Method::NAMES
        .iter()
        .filter_map(|name| Method::stable_flag_setting(name))
    {
        let model = ClothModel::grid(&spec)?.with_hoist_pinned()?;
        let mut params = SimParams {
            method,
            ..SimParams::default()
        };
        params.wind.velocity = DVec3::new(6.0, 0.0, 1.0);
        let mut sim = Simulation::new(model, params)?;
        let fly_end = spec.columns - 1; // top row, last column
        let start = Instant::now();
        let mut outcome = String::new();
        for _ in 0..frames {
            if let Err(error) = sim.step(frame) {
                outcome = format!("  ({error})");
                break;
            }
        }
        let ms = start.elapsed().as_secs_f64() * 1e3 / frames as f64;
        let corner = sim.positions()[fly_end];
        println!(
            "{:<18} {:>9.3} {:>28} {:>12.4}{}",
            method.name(),
            ms,
            format!("({:.3}, {:.3}, {:.3})", corner.x, corner.y, corner.z),
            sim.max_strain(None),
            outcome
        );
    }
    Ok(())
}
