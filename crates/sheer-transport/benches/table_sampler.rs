//! Criterion benchmarks: solver cost per slab and per incidence angle.

use criterion::{Criterion, criterion_group, criterion_main};
use sheer_transport::SlabSolver;
use std::hint::black_box;

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

criterion_group!(benches, solver);
criterion_main!(benches);
