//! Criterion benchmarks: the table sampler (the real-time path) and the solver it replaces.
//!
//! `cargo bench -p sheer-transport --bench table_sampler`

use criterion::{Criterion, criterion_group, criterion_main};
use sheer_transport::{AllOrdersTable, SlabSolver};
use std::hint::black_box;

fn sampler(c: &mut Criterion) {
    let table = AllOrdersTable::read(AllOrdersTable::DEFAULT_PATH).expect("shipped table");
    c.bench_function("table_reflected_and_transmitted_radiance", |b| {
        b.iter(|| {
            let r = table.reflected_radiance(
                black_box(2.0),
                black_box(0.95),
                black_box(0.6),
                black_box(0.8),
            );
            let t = table.transmitted_radiance(
                black_box(2.0),
                black_box(0.95),
                black_box(0.6),
                black_box(0.8),
            );
            (r, t)
        })
    });
}

fn solver(c: &mut Criterion) {
    c.bench_function("solver_factorise_tau1_2_albedo_1", |b| {
        b.iter(|| SlabSolver::new(black_box(2.0), black_box(1.0)))
    });
    let slab = SlabSolver::new(2.0, 1.0).expect("valid slab");
    c.bench_function("solver_solve_and_radiance_tau1_2", |b| {
        b.iter(|| {
            let solution = slab.solve(black_box(0.5)).expect("valid cosine");
            solution.reflected_radiance(black_box(0.7))
        })
    });
}

criterion_group!(benches, sampler, solver);
criterion_main!(benches);
