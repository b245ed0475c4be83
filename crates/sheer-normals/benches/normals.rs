//! Criterion benchmark of the per-frame vertex-normal update on square grids of 10⁴, 10⁵ and 10⁶
//! vertices: serial vs rayon, area vs angle weighting.
//!
//! Run: `cargo bench -p sheer-normals --bench normals` (about two minutes; figures in the README).

use criterion::{BenchmarkId, Criterion, SamplingMode, criterion_group, criterion_main};
use glam::Vec3;
use sheer_normals::{Execution, Light, NormalOptions, NormalUpdater, Weighting};
use std::hint::black_box;
use std::time::Duration;

/// A gently waving `side × side` vertex sheet, 1 m across, two triangles per cell.
fn wavy_grid(side: usize) -> (Vec<Vec3>, Vec<u32>) {
    let spacing = 1.0 / (side - 1) as f32;
    let positions = (0..side * side)
        .map(|k| {
            let (i, j) = ((k % side) as f32 * spacing, (k / side) as f32 * spacing);
            Vec3::new(i, j, 0.05 * (7.0 * i).sin() * (5.0 * j).cos())
        })
        .collect();
    let mut indices = Vec::with_capacity(6 * (side - 1) * (side - 1));
    for j in 0..side - 1 {
        for i in 0..side - 1 {
            let v = (j * side + i) as u32;
            let s = side as u32;
            indices.extend_from_slice(&[v, v + 1, v + s, v + 1, v + s + 1, v + s]);
        }
    }
    (positions, indices)
}

fn bench_update(c: &mut Criterion) {
    let mut group = c.benchmark_group("update");
    // Flat sampling (the same iteration count in every sample) and 20 samples: the machine is
    // shared, so the README reports the fastest sample (least disturbed) next to the median.
    group
        .sampling_mode(SamplingMode::Flat)
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    let light = Light::Point {
        position: Vec3::new(0.3, 0.6, 0.8),
    };
    // 100² = 10⁴, 317² ≈ 1.005·10⁵, 1000² = 10⁶ vertices.
    for side in [100usize, 317, 1000] {
        let (positions, indices) = wavy_grid(side);
        let mut normals = vec![Vec3::ZERO; positions.len()];
        for (weighting, weighting_name) in [(Weighting::Area, "area"), (Weighting::Angle, "angle")]
        {
            for (execution, execution_name) in [
                (Execution::Serial, "serial"),
                (Execution::Parallel, "rayon"),
            ] {
                let options = NormalOptions {
                    weighting,
                    execution,
                };
                let mut updater =
                    NormalUpdater::with_options(positions.len(), &indices, options).unwrap();
                group.bench_with_input(
                    BenchmarkId::new(
                        format!("{weighting_name}/{execution_name}"),
                        positions.len(),
                    ),
                    &positions,
                    |b, positions| {
                        b.iter(|| {
                            updater
                                .update(black_box(positions), &light, &mut normals)
                                .unwrap();
                            black_box(&normals);
                        })
                    },
                );
            }
        }
    }
    group.finish();
}

criterion_group!(benches, bench_update);
criterion_main!(benches);
