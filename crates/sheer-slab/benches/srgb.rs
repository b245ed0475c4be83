//! The display encoding of a 512 × 512 frame, 786 432 channel values in [0, 1.2): `linear_to_srgb8`
//! (a table lookup, branch-free) against the formula it reproduces, `round(255·linear_to_srgb(v))`
//! with its `powf`, on the same values in one run.
//!
//! `cargo bench -p sheer-slab --bench srgb`

use std::hint::black_box;

use criterion::Criterion;
use sheer_slab::render::{linear_to_srgb, linear_to_srgb8};

/// Values spread over [0, 1.2) in no order (a fixed linear congruential sequence), as a frame's
/// channels come: the table's cost does not hide behind a predictable branch.
fn frame_values() -> Vec<f32> {
    let mut state = 12_345u64;
    (0..512 * 512 * 3)
        .map(|_| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 40) as f32 / (1u64 << 24) as f32 * 1.2
        })
        .collect()
}

/// The code the table reproduces: the formula, rounded to eight bits.
fn srgb8_by_formula(value: f32) -> u8 {
    (linear_to_srgb(value) * 255.0).round() as u8
}

fn main() {
    let values = frame_values();
    let by_table: Vec<u8> = values.iter().map(|&v| linear_to_srgb8(v)).collect();
    let by_formula: Vec<u8> = values.iter().map(|&v| srgb8_by_formula(v)).collect();
    assert_eq!(
        by_table, by_formula,
        "the table must give the formula's codes"
    );
    let mut criterion = Criterion::default().configure_from_args();
    let mut group = criterion.benchmark_group("srgb8_512x512");
    group.bench_function("table", |b| {
        b.iter(|| {
            black_box(&values)
                .iter()
                .map(|&v| u32::from(linear_to_srgb8(v)))
                .sum::<u32>()
        })
    });
    group.bench_function("formula", |b| {
        b.iter(|| {
            black_box(&values)
                .iter()
                .map(|&v| u32::from(srgb8_by_formula(v)))
                .sum::<u32>()
        })
    });
    group.finish();
    criterion.final_summary();
}
