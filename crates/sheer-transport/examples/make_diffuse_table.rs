//! Regenerates `assets/diffuse_table.bin` at the workspace root (the slab's response `R_d(μ)`, `T_d(μ)`
//! to uniform radiance over a face's hemisphere) with the all-orders solver and reports its size, its
//! generation time and its interpolation error against `SlabSolver::diffuse_response` at points halfway
//! between nodes on all three axes (the worst case of multilinear interpolation).
//!
//! `cargo run -p sheer-transport --release --example make_diffuse_table` (or `-- OUTPUT.bin` to write
//! elsewhere)

use rayon::prelude::*;
use sheer_transport::{DiffuseTable, SlabSolver, TableSpec};

/// Worst error found in one (face, regime): relative, absolute (per unit incident radiance) and where.
#[derive(Clone, Copy, Debug, Default)]
struct Worst {
    relative: f64,
    absolute: f64,
    at: (f64, f64, f64),
}

impl Worst {
    fn record(&mut self, exact: f64, approx: f64, at: (f64, f64, f64)) {
        let relative = ((approx - exact) / exact).abs();
        if relative > self.relative {
            self.relative = relative;
            self.at = at;
        }
        self.absolute = self.absolute.max((approx - exact).abs());
    }

    fn merged(mut self, other: Self) -> Self {
        if other.relative > self.relative {
            self.relative = other.relative;
            self.at = other.at;
        }
        self.absolute = self.absolute.max(other.absolute);
        self
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let start = std::time::Instant::now();
    let table = DiffuseTable::generate(TableSpec::default())?;
    let generation = start.elapsed().as_secs_f64();
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| DiffuseTable::DEFAULT_PATH.to_string());
    table.write(&path)?;
    let bytes = std::fs::metadata(&path)?.len();
    println!(
        "wrote {path}: {bytes} bytes, spec {:?}, generated in {generation:.1} s on {} threads",
        table.spec(),
        rayon::current_num_threads()
    );
    // Every other τ1 cell, every albedo cell, every μ cell, at their midpoints.
    let spec = table.spec();
    let mus: Vec<f64> = (0..spec.cosine_count - 1)
        .map(|j| spec.cosine_at(j as f64 + 0.5))
        .collect();
    let jobs: Vec<(usize, usize)> = (0..spec.tau_count - 1)
        .step_by(2)
        .flat_map(|t| (0..spec.albedo_count - 1).map(move |a| (t, a)))
        .collect();
    // Indexed [face][regime]: face 0 = reflected, 1 = transmitted; regime 0 = all μ, 1 = μ ≥ 0.05.
    let worst = jobs
        .par_iter()
        .map(
            |&(t, a)| -> Result<[[Worst; 2]; 2], sheer_transport::TransportError> {
                let tau1 = spec.tau_at(t as f64 + 0.5);
                let albedo = spec.albedo_at(a as f64 + 0.5, tau1);
                let exact = SlabSolver::new(tau1, albedo)?.diffuse_responses(&mus)?;
                let mut worst = [[Worst::default(); 2]; 2];
                for (&mu, response) in mus.iter().zip(&exact) {
                    let regimes: &[usize] = if mu >= 0.05 { &[0, 1] } else { &[0] };
                    let approx = [
                        table.reflectance(tau1, albedo, mu)?,
                        table.transmittance(tau1, albedo, mu)?,
                    ];
                    let exact = [response.reflectance, response.transmittance];
                    for face in 0..2 {
                        for &r in regimes {
                            worst[face][r].record(exact[face], approx[face], (tau1, albedo, mu));
                        }
                    }
                }
                Ok(worst)
            },
        )
        .try_reduce(
            || [[Worst::default(); 2]; 2],
            |x, y| {
                Ok(std::array::from_fn(|f| {
                    std::array::from_fn(|r| x[f][r].merged(y[f][r]))
                }))
            },
        )?;
    for (face, face_name) in ["reflected R_d", "transmitted T_d"].iter().enumerate() {
        for (r, regime) in ["all mu", "mu >= 0.05"].iter().enumerate() {
            let w = worst[face][r];
            println!(
                "mid-cell interpolation error, {face_name} ({regime}): relative max {:.2e} at \
                 (tau1, albedo, mu) = ({:.4}, {:.4}, {:.4}); absolute max {:.2e}",
                w.relative, w.at.0, w.at.1, w.at.2, w.absolute
            );
        }
    }
    println!("total time {:.1} s", start.elapsed().as_secs_f64());
    Ok(())
}
