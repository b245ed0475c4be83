//! Frames per second at 512×512 for the three thin-slab evaluation paths, each with single scattering
//! (the paper) and with all orders (the table), and the baseline (Frisvad et al. 2005 §4: fragment
//! 300 fps, vertex 480 fps, CPU 190 fps on a 2005 laptop GPU), in one run on whatever adapter
//! `HeadlessRenderer` picks (lavapipe on a machine without a GPU). A frame = back-to-front sort, uploads
//! (and the rayon per-vertex evaluation on the CPU path), background + slab draw, and waiting for the
//! GPU; no read-back. Criterion measures each case; then an interleaved run prints fps, the ratio of each
//! case's frame time to the baseline's and, per path, all orders to single.
//!
//! `cargo bench -p sheer-slab --bench paths`

use std::time::{Duration, Instant};

use criterion::Criterion;
use glam::Vec3;
use sheer_slab::all_orders::{Scattering, default_table_path, load_all_orders_table};
use sheer_slab::render::{
    AllOrdersSampling, Background, Camera, EvaluationPath, HeadlessRenderer, ShadingParams,
    SlabMesh, Texture2d,
};

const SIZE: u32 = 512;

/// A waving flag, 64×40 quads (5120 triangles), normals turned toward the light.
fn waving_flag(light: Vec3) -> SlabMesh {
    let (columns, rows) = (64u32, 40u32);
    let mut mesh = SlabMesh::flat_sheet(
        Vec3::new(-0.75, -0.45, 0.0),
        Vec3::X * 1.5,
        Vec3::Y * 0.9,
        Vec3::Z,
        columns,
        rows,
    )
    .expect("valid sheet");
    for (position, normal) in mesh.positions.iter_mut().zip(mesh.normals.iter_mut()) {
        let x = position[0];
        // z = a·sin(kx + φ(y)): the wave folds the flag toward and away from the camera.
        let (amplitude, wavenumber) = (0.12, 7.0);
        let phase = 1.5 * position[1];
        position[2] = amplitude * (wavenumber * x + phase).sin();
        let slope_x = amplitude * wavenumber * (wavenumber * x + phase).cos();
        let slope_y = amplitude * 1.5 * (wavenumber * x + phase).cos();
        let mut n = Vec3::new(-slope_x, -slope_y, 1.0).normalize();
        if n.dot(light - Vec3::from(*position)) < 0.0 {
            n = -n;
        }
        *normal = n.to_array();
    }
    mesh
}

struct Scene {
    mesh: SlabMesh,
    camera: Camera,
    shading: ShadingParams,
    background: Background,
}

fn scene() -> Scene {
    let light = Vec3::new(0.8, 0.6, 1.5);
    let albedo = Texture2d::new(
        8,
        8,
        (0..64)
            .map(|i| {
                if (i / 8) % 4 == 1 || (i % 8) % 4 == 1 {
                    [0.1, 0.2, 0.9, 1.0]
                } else {
                    [0.9, 0.9, 0.9, 1.0]
                }
            })
            .collect(),
    )
    .expect("valid texture");
    let mut shading = ShadingParams::uniform(2.0, 1.0, light, 60.0).expect("valid parameters");
    shading.albedo_texture = albedo;
    let background_texels = (0..SIZE * SIZE)
        .map(|i| {
            let (x, y) = (
                (i % SIZE) as f32 / SIZE as f32,
                (i / SIZE) as f32 / SIZE as f32,
            );
            [0.1 + 0.2 * x, 0.15, 0.1 + 0.3 * y, 1.0]
        })
        .collect();
    Scene {
        mesh: waving_flag(light),
        camera: Camera {
            eye: Vec3::new(0.2, 0.1, 1.6),
            target: Vec3::ZERO,
            up: Vec3::Y,
            vertical_fov: 0.9,
            near: 0.05,
            far: 10.0,
        },
        shading,
        background: Background::Image(
            Texture2d::new(SIZE, SIZE, background_texels).expect("valid image"),
        ),
    }
}

/// One measured configuration: a path and a scattering model.
struct Case {
    name: String,
    path: EvaluationPath,
    shading: ShadingParams,
}

fn frame(renderer: &mut HeadlessRenderer, scene: &Scene, case: &Case) {
    renderer
        .render_frame(
            &scene.mesh,
            &scene.camera,
            &case.shading,
            &scene.background,
            case.path,
        )
        .expect("frame renders");
}

fn main() {
    let mut renderer = HeadlessRenderer::new(SIZE, SIZE).expect("an adapter (lavapipe or a GPU)");
    println!("adapter: {}", renderer.adapter_description());
    let scene = scene();
    let table = load_all_orders_table(default_table_path()).expect("the shipped all-orders table");
    let mut cases = Vec::new();
    for path in EvaluationPath::ALL {
        let mut models = vec![(Scattering::Single, AllOrdersSampling::default())];
        if path != EvaluationPath::Baseline {
            models.push((
                Scattering::AllOrders(table.clone()),
                AllOrdersSampling::PerVertex,
            ));
        }
        if path == EvaluationPath::PerFragment {
            // The table looked up in every fragment instead of once per vertex.
            models.push((
                Scattering::AllOrders(table.clone()),
                AllOrdersSampling::PerFragment,
            ));
        }
        for (scattering, sampling) in models {
            let name = match (path, &scattering, sampling) {
                (EvaluationPath::Baseline, _, _) => path.name().to_string(),
                (EvaluationPath::PerFragment, Scattering::AllOrders(_), _) => format!(
                    "{}/{} (table {})",
                    path.name(),
                    scattering.name(),
                    sampling.name()
                ),
                _ => format!("{}/{}", path.name(), scattering.name()),
            };
            cases.push(Case {
                name,
                path,
                shading: ShadingParams {
                    scattering,
                    all_orders_sampling: sampling,
                    ..scene.shading.clone()
                },
            });
        }
    }
    for case in &cases {
        frame(&mut renderer, &scene, case); // compile pipelines, upload the table, outside the measurement
    }

    let mut criterion = Criterion::default()
        .sample_size(20)
        .measurement_time(Duration::from_secs(4))
        .configure_from_args();
    {
        let mut group = criterion.benchmark_group("frame_512x512");
        for case in &cases {
            group.bench_function(&case.name, |b| {
                b.iter(|| frame(&mut renderer, &scene, case))
            });
        }
        group.finish();
    }
    criterion.final_summary();

    // Interleaved rounds so that drift of the machine affects every case alike; each round's frame
    // times are divided by that round's baseline (and single-scattering) time and the median over rounds
    // is reported, which discounts bursts of load from other processes.
    let rounds = 40;
    let frames_per_round = 5;
    let mut per_round: Vec<Vec<f64>> = vec![Vec::new(); cases.len()];
    for _ in 0..rounds {
        for (slot, case) in cases.iter().enumerate() {
            let start = Instant::now();
            for _ in 0..frames_per_round {
                frame(&mut renderer, &scene, case);
            }
            per_round[slot].push(start.elapsed().as_secs_f64() / f64::from(frames_per_round));
        }
    }
    let median = |mut values: Vec<f64>| {
        values.sort_by(f64::total_cmp);
        0.5 * (values[(values.len() - 1) / 2] + values[values.len() / 2])
    };
    let ratio = |a: usize, b: usize| {
        median(
            per_round[a]
                .iter()
                .zip(&per_round[b])
                .map(|(x, y)| x / y)
                .collect(),
        )
    };
    let baseline = cases.len() - 1;
    println!(
        "\n512x512, {} triangles, {rounds} interleaved rounds of {frames_per_round} frames per case",
        scene.mesh.indices.len() / 3
    );
    println!(
        "| case | median ms/frame | fps | frame time / baseline | all-orders / single | paper fps |"
    );
    println!("|---|---|---|---|---|---|");
    for (slot, case) in cases.iter().enumerate() {
        let per_frame = median(per_round[slot].clone());
        let single_slot = cases
            .iter()
            .position(|c| c.path == case.path && c.shading.scattering == Scattering::Single);
        let against_single = match (&case.shading.scattering, single_slot) {
            (Scattering::AllOrders(_), Some(single)) => format!("{:.3}", ratio(slot, single)),
            _ => "-".to_string(),
        };
        let paper = match case.path {
            EvaluationPath::PerFragment => "300",
            EvaluationPath::PerVertex => "480",
            EvaluationPath::Cpu => "190",
            EvaluationPath::Baseline => "-",
        };
        println!(
            "| {} | {:.2} | {:.1} | {:.3} | {against_single} | {paper} |",
            case.name,
            1e3 * per_frame,
            1.0 / per_frame,
            ratio(slot, baseline),
        );
    }
}
