//! Bit-for-bit identical normals whatever the rayon thread count (1, 2, 4) and whether the update
//! runs serially or in parallel, for both weightings.

mod common;

use common::{bits, icosphere, wavy_grid};
use glam::Vec3;
use sheer_normals::{
    Execution, Light, NormalOptions, NormalUpdater, PARALLEL_MIN_VERTICES, Weighting,
};

#[test]
fn thread_count_does_not_change_a_single_bit() {
    let meshes = [wavy_grid(130), icosphere(6)];
    let light = Light::Point {
        position: Vec3::new(0.3, 0.2, 0.9),
    };
    for (positions, indices) in &meshes {
        // Large enough that the parallel path really splits the work.
        assert!(positions.len() >= 2 * PARALLEL_MIN_VERTICES);
        for weighting in [Weighting::Area, Weighting::Angle] {
            let serial = {
                let options = NormalOptions {
                    weighting,
                    execution: Execution::Serial,
                };
                let mut updater =
                    NormalUpdater::with_options(positions.len(), indices, options).unwrap();
                let mut normals = vec![Vec3::ZERO; positions.len()];
                updater.update(positions, &light, &mut normals).unwrap();
                bits(&normals)
            };
            for threads in [1, 2, 4] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let options = NormalOptions {
                    weighting,
                    execution: Execution::Parallel,
                };
                let mut updater =
                    NormalUpdater::with_options(positions.len(), indices, options).unwrap();
                let mut normals = vec![Vec3::ZERO; positions.len()];
                pool.install(|| updater.update(positions, &light, &mut normals))
                    .unwrap();
                assert_eq!(bits(&normals), serial, "{weighting:?}, {threads} threads");
            }
        }
    }
}
