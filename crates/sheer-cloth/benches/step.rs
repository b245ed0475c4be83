//! Criterion benchmark: one 60 Hz frame of the default flag for every method, and small-steps XPBD on
//! growing grids with one thread and with all threads (for the rayon speed-up).
//!
//! `cargo bench -p sheer-cloth --bench step`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use sheer_cloth::{ClothModel, GridSpec, Method, SimParams, Simulation};

const FRAME: f64 = 1.0 / 60.0;

fn flag(columns: usize, rows: usize, method: Method, parallel_min_particles: usize) -> Simulation {
    let spec = GridSpec {
        columns,
        rows,
        ..GridSpec::default()
    };
    let model = ClothModel::grid(&spec)
        .and_then(|m| m.with_hoist_pinned())
        .expect("valid grid");
    // The app's default flag (its wind held for at most 2 ms) at this grid.
    let params = SimParams {
        method,
        parallel_min_particles,
        ..SimParams::waving_flag()
    };
    let mut sim = Simulation::new(model, params).expect("valid simulation");
    // Warm up into a waving state so every method measures the same kind of frame.
    for _ in 0..10 {
        if sim.step(FRAME).is_err() {
            sim.reset();
        }
    }
    sim
}

fn methods(c: &mut Criterion) {
    let mut group = c.benchmark_group("default_flag_frame");
    group.sample_size(20);
    // Sub-steps at which each method is stable on the default flag (see `sheer bench sim`).
    for method in [
        Method::SymplecticEuler { substeps: 200 },
        Method::Verlet { substeps: 200 },
        Method::ImplicitEuler {
            substeps: 1,
            cg_max_iterations: 100,
            cg_tolerance: 1e-4,
        },
        Method::Pbd {
            substeps: 4,
            iterations: 10,
            stiffness: 1.0,
        },
        Method::Xpbd {
            substeps: 1,
            iterations: 20,
        },
        Method::SmallStepsXpbd { substeps: 20 },
    ] {
        let mut sim = flag(64, 46, method, usize::MAX);
        group.bench_function(BenchmarkId::from_parameter(method.name()), |b| {
            b.iter(|| {
                if sim.step(FRAME).is_err() {
                    sim.reset();
                }
            })
        });
    }
    group.finish();
}

fn scaling(c: &mut Criterion) {
    let mut group = c.benchmark_group("small_steps_xpbd_scaling");
    group.sample_size(10);
    for (columns, rows) in [(64, 46), (256, 186), (512, 372)] {
        for (label, threshold) in [("serial", usize::MAX), ("parallel", 0)] {
            let mut sim = flag(
                columns,
                rows,
                Method::SmallStepsXpbd { substeps: 20 },
                threshold,
            );
            group.bench_function(BenchmarkId::new(label, format!("{columns}x{rows}")), |b| {
                b.iter(|| {
                    if sim.step(FRAME).is_err() {
                        sim.reset();
                    }
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, methods, scaling);
criterion_main!(benches);
