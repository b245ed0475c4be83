//! The per-frame update allocates nothing itself: a counting global allocator watches repeated
//! updates, serial and on the rayon pool. (Its own test binary, so no other test allocates
//! meanwhile.)

use glam::Vec3;
use sheer_normals::{Execution, Light, NormalOptions, NormalUpdater, Weighting};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct CountingAllocator;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// A global allocator is an unsafe trait: the one unsafe item of this crate, test-only.
#[allow(unsafe_code)]
// SAFETY: forwards every call unchanged to the system allocator; only counts.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

const FRAMES: usize = 200;

/// Warm-up frames: the first parallel calls start rayon's pool and its worker threads.
const WARM_UP_FRAMES: usize = 5;

/// A 150 × 150 sheet (above `PARALLEL_MIN_VERTICES`, so `Parallel` really runs on the pool).
fn sheet() -> (Vec<Vec3>, Vec<u32>) {
    let side = 150;
    let positions = (0..side * side)
        .map(|k| Vec3::new((k % side) as f32, (k / side) as f32, 0.0) * 0.01)
        .collect();
    let mut indices = Vec::new();
    for j in 0..side - 1 {
        for i in 0..side - 1 {
            let v = (j * side + i) as u32;
            let s = side as u32;
            indices.extend_from_slice(&[v, v + 1, v + s, v + 1, v + s + 1, v + s]);
        }
    }
    (positions, indices)
}

/// Allocations made by `FRAMES` updates of a waving sheet after the warm-up.
fn allocations_per_run(weighting: Weighting, execution: Execution) -> usize {
    let (mut positions, indices) = sheet();
    let mut normals = vec![Vec3::ZERO; positions.len()];
    let options = NormalOptions {
        weighting,
        execution,
    };
    let mut updater = NormalUpdater::with_options(positions.len(), &indices, options).unwrap();
    let light = Light::Point {
        position: Vec3::new(0.5, 0.5, 1.0),
    };
    for _ in 0..WARM_UP_FRAMES {
        updater.update(&positions, &light, &mut normals).unwrap();
    }
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for frame in 0..FRAMES {
        for (k, p) in positions.iter_mut().enumerate() {
            p.z = 0.01 * ((k + frame) as f32 * 0.1).sin();
        }
        updater.update(&positions, &light, &mut normals).unwrap();
    }
    ALLOCATIONS.load(Ordering::Relaxed) - before
}

#[test]
fn updates_allocate_nothing() {
    // Every worker thread started and settled before anything is counted, and none ending while
    // counts run: the counter sees every thread of the process, and a rayon worker allocates when it
    // first takes work (its crossbeam-epoch registration) and when it exits (its epoch state pushed
    // onto a global queue). With a pool built and dropped inside the loop, a late-exiting worker once
    // landed in the next "outside the pool" count (5, in a CI run on a loaded machine).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    pool.broadcast(|_| ());
    rayon::broadcast(|_| ());
    for weighting in [Weighting::Area, Weighting::Angle] {
        // Serial: not a single allocation.
        assert_eq!(
            allocations_per_run(weighting, Execution::Serial),
            0,
            "{weighting:?}"
        );

        // Parallel, with the frame loop itself running on a rayon worker (as in a renderer that
        // drives its frame from the pool): not a single allocation either.
        let inside = pool.install(|| allocations_per_run(weighting, Execution::Parallel));
        assert_eq!(inside, 0, "{weighting:?} inside the pool");

        // Parallel, called from a thread outside the pool: each update enters the pool once, and
        // rayon's injector queue (crossbeam-deque) allocates one block per 63 entries. That, and
        // nothing else, is allowed: at most ⌈FRAMES / 63⌉ allocations.
        let outside = allocations_per_run(weighting, Execution::Parallel);
        assert!(
            outside <= FRAMES.div_ceil(63),
            "{weighting:?} outside the pool: {outside}"
        );
    }
}
