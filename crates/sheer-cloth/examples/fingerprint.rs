//! Prints a fingerprint of the simulator's results, to show that a change to the solver leaves them
//! bit-identical, and times one setting, to compare two builds of the library in interleaved runs.
//!
//! `cargo run -p sheer-cloth --release --example fingerprint` waves the default flag, a larger grid and
//! a long narrow one with five methods, the wind updated every sub-step and every 4, on one thread and
//! on two; then a general triangle mesh, a grid without wind, and a grid of 262 144 particles, large
//! enough for the wavefronts of several sub-steps a pass on both thread counts (small-steps XPBD ×20,
//! three frames). Each case prints a hash of the final positions and velocities (and of the frame a run
//! diverged at, if it did), and `TOTAL` hashes them all: two builds with the same `TOTAL` gave the same
//! bits in every case.
//!
//! `cargo run -p sheer-cloth --release --example fingerprint -- time 64x46 2 150` prints the mean
//! milliseconds per 60 Hz frame of small-steps XPBD ×20 on that grid (hoist pinned, 6 m/s wind with its
//! forces renewed every sub-step, where `SimParams::waving_flag` holds them up to 2 ms, so a frame here
//! takes longer than `sheer bench sim`'s on the same grid) with that many threads (two or more: the
//! parallel code paths forced on) over that many frames, after ten frames of warm-up. Copy this file
//! into another checkout's `crates/sheer-cloth/examples/` to build the same program against another
//! version of the library.
//!
//! `cargo run -p sheer-cloth --release --example fingerprint -- threads 1,2,4,8,16` runs nine cases
//! (teams in equal parts, claimed opposed parts and parts, the triangle path; small-steps
//! XPBD, XPBD with multipliers and PBD) on each of those thread counts and exits non-zero unless
//! every case gave the same bits on all of them: the determinism check for a machine with more cores
//! than the build machine's two, on which the tests run up to 16 threads.
//!
//! `cargo run -p sheer-cloth --release --example fingerprint -- together 64x46 400` says how much of two
//! cores the machine gives right now: it times that setting on one thread alone, then two independent
//! one-thread runs at the same time, then one alone again, and prints how many runs' work the two did
//! in the time one took alone (the mean of the two): 2.00 for two full cores; less on a virtual machine
//! whose host shares its cores. `… -- handoff` prints how long one thread takes to see what another has
//! just written (`thread_handoff_latency` below): where the host puts the two virtual CPUs on
//! cores far apart, this grows and so does the two-thread step's cost.

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use sheer_cloth::glam::DVec3;
use sheer_cloth::{ClothModel, GridSpec, Method, SimParams, Simulation};

const FRAME: f64 = 1.0 / 60.0;

/// The flag in a 6 m/s wind (or none), `threads` > 1 forcing the parallel code paths on.
fn flag(model: ClothModel, method: Method, wind_every: Option<u32>, threads: usize) -> Simulation {
    let mut params = SimParams {
        method,
        ..SimParams::default()
    };
    if let Some(interval) = wind_every {
        params.wind.velocity = DVec3::new(6.0, 0.0, 1.0);
        // Held for `interval` sub-steps: the renewal interval is a time (0: every evaluation).
        params.wind.renewal_interval = if interval > 1 {
            f64::from(interval) * FRAME / f64::from(method.substeps())
        } else {
            0.0
        };
    }
    params.parallel_min_particles = if threads > 1 { 0 } else { usize::MAX };
    Simulation::new(model, params).expect("a valid flag")
}

/// Hash of `frames` frames of `sim`, run on a pool of `threads`: final positions and velocities, and the
/// frame at which it diverged (0 if it did not).
fn fingerprint(threads: usize, frames: u64, sim: impl FnOnce() -> Simulation + Send) -> u64 {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    pool.install(|| {
        let mut sim = sim();
        let diverged_at = (0..frames)
            .find(|_| sim.step(FRAME).is_err())
            .map_or(0, |frame| frame + 1);
        let mut hash = DefaultHasher::new();
        for x in sim.positions().iter().chain(sim.velocities()) {
            x.to_array().map(f64::to_bits).hash(&mut hash);
        }
        diverged_at.hash(&mut hash);
        hash.finish()
    })
}

fn grid(columns: usize, rows: usize) -> ClothModel {
    let spec = GridSpec {
        columns,
        rows,
        ..GridSpec::default()
    };
    ClothModel::grid(&spec).expect("a valid grid")
}

/// A `columns × rows` grid, or the general triangle mesh of its triangles when `mesh`, with its hoist
/// (first column) pinned.
fn hoisted(columns: usize, rows: usize, mesh: bool) -> ClothModel {
    let grid = grid(columns, rows);
    let mut model = if mesh {
        let indices = grid.triangle_indices();
        ClothModel::from_triangle_mesh(&grid.positions, &indices, 0.2).expect("a valid mesh")
    } else {
        grid
    };
    let hoist: Vec<usize> = (0..rows).map(|row| row * columns).collect();
    model.pin(&hoist).expect("pins in range");
    model
}

/// Mean milliseconds per frame of small-steps XPBD ×20 on a `columns × rows` flag on `threads` threads
/// over `frames` frames, after ten frames of warm-up.
fn time_frames(columns: usize, rows: usize, threads: usize, frames: u32) -> f64 {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    pool.install(|| {
        let model = grid(columns, rows).with_hoist_pinned().expect("a grid");
        let mut sim = flag(
            model,
            Method::SmallStepsXpbd { substeps: 20 },
            Some(1),
            threads,
        );
        for _ in 0..10 {
            sim.step(FRAME).expect("a stable flag");
        }
        let start = Instant::now();
        for _ in 0..frames {
            sim.step(FRAME).expect("a stable flag");
        }
        start.elapsed().as_secs_f64() * 1e3 / frames as f64
    })
}

/// The grid, thread count and frame count of `time` (`together` passes 1 thread), the counts at least 1.
fn parse_case(grid: &str, count: &str, frames: &str) -> Option<((usize, usize), usize, u32)> {
    let (columns, rows) = grid.split_once('x')?;
    let (columns, rows) = (columns.parse().ok()?, rows.parse().ok()?);
    // The library refuses smaller grids (`GridTooSmall`); a usage error here rather than its panic below.
    if columns < 2 || rows < 2 {
        return None;
    }
    let count = count.parse::<usize>().ok().filter(|&n| n > 0)?;
    let frames = frames.parse::<u32>().ok().filter(|&f| f > 0)?;
    Some(((columns, rows), count, frames))
}

/// Runs each case of `threads` on every count in `counts` (the parallel paths forced on from two) and
/// prints its hashes; whether every case gave the same bits on all of them.
///
/// On two threads the cases take these ways of sharing out a step: a team in equal parts (the
/// default flag, and 288 × 288, below 43 008 particles a thread), claimed passes of two opposed
/// parts (362 × 362) and of wavefronts in parts (1 024 × 745), and the general triangle path; for
/// small-steps XPBD, XPBD with multipliers and PBD. On three, 362 × 362 goes as wavefronts in
/// parts. Not the sub-step-by-sub-step wavefront of 262 144 particles and more. More threads
/// keep their own rows on larger grids (362 × 362 from four, 1 024 × 745 from eighteen).
fn same_bits_on_thread_counts(counts: &[usize]) -> bool {
    let small_steps = Method::SmallStepsXpbd { substeps: 20 };
    let xpbd = Method::Xpbd {
        substeps: 2,
        iterations: 20,
    };
    let pbd = Method::Pbd {
        substeps: 4,
        iterations: 10,
        stiffness: 1.0,
    };
    let cases = [
        ((64, 46), small_steps, false, 60),
        ((64, 46), xpbd, false, 60),
        ((64, 46), pbd, false, 60),
        ((64, 46), small_steps, true, 30),
        ((288, 288), small_steps, false, 4),
        ((288, 288), xpbd, false, 4),
        ((362, 362), small_steps, false, 4),
        ((362, 362), xpbd, false, 4),
        ((1024, 745), small_steps, false, 2),
    ];
    let mut all_same = true;
    for ((columns, rows), method, mesh, frames) in cases {
        let hashes: Vec<u64> = counts
            .iter()
            .map(|&threads| {
                fingerprint(threads, frames, || {
                    flag(hoisted(columns, rows, mesh), method, Some(1), threads)
                })
            })
            .collect();
        let same = hashes.iter().all(|&hash| hash == hashes[0]);
        all_same &= same;
        let shown: Vec<String> = hashes.iter().map(|hash| format!("{hash:016x}")).collect();
        let path = if mesh { "triangle mesh" } else { "grid" };
        println!(
            "{columns}x{rows} {path} {} ({frames} frames) on {counts:?} threads: {} {}",
            method.name(),
            shown.join(" "),
            if same { "same" } else { "DIFFERENT" }
        );
    }
    println!(
        "{}",
        if all_same {
            "same bits on every thread count"
        } else {
            "DIFFERENT bits between thread counts"
        }
    );
    all_same
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("time") => {
            let parsed = match &args[1..] {
                [grid, threads, frames] => parse_case(grid, threads, frames),
                _ => None,
            };
            let Some(((columns, rows), threads, frames)) = parsed else {
                eprintln!("usage: fingerprint time COLUMNSxROWS THREADS FRAMES");
                std::process::exit(2);
            };
            println!("{:.4}", time_frames(columns, rows, threads, frames));
            return;
        }
        Some("together") => {
            let parsed = match &args[1..] {
                [grid, frames] => parse_case(grid, "1", frames),
                _ => None,
            };
            let Some(((columns, rows), _, frames)) = parsed else {
                eprintln!("usage: fingerprint together COLUMNSxROWS FRAMES");
                std::process::exit(2);
            };
            // Alone before and after the two, so that a change of the host's pace shows.
            let before = time_frames(columns, rows, 1, frames);
            let [first, second] = std::thread::scope(|scope| {
                [(); 2]
                    .map(|()| scope.spawn(|| time_frames(columns, rows, 1, frames)))
                    .map(|run| run.join().expect("a timed run"))
            });
            let after = time_frames(columns, rows, 1, frames);
            let alone = 0.5 * (before + after);
            println!(
                "alone {before:.4} and {after:.4} ms; two at once {first:.4} and {second:.4} ms: \
                 {:.2} runs' work in the time of one",
                alone / first + alone / second
            );
            return;
        }
        Some("threads") => {
            let counts: Option<Vec<usize>> = args.get(1).and_then(|list| {
                list.split(',')
                    .map(|n| n.parse::<usize>().ok().filter(|&n| n > 0))
                    .collect()
            });
            let Some(counts) = counts.filter(|counts| counts.len() >= 2) else {
                eprintln!("usage: fingerprint threads N,M,... (two or more thread counts)");
                std::process::exit(2);
            };
            std::process::exit(if same_bits_on_thread_counts(&counts) {
                0
            } else {
                1
            });
        }
        Some("handoff") => {
            match thread_handoff_latency(Duration::from_millis(100)) {
                Some(latency) => println!("{} ns", latency.as_nanos()),
                None => println!("one CPU: no hand-off to measure"),
            }
            return;
        }
        _ => {}
    }
    let methods = [
        Method::Pbd {
            substeps: 4,
            iterations: 10,
            stiffness: 1.0,
        },
        Method::Xpbd {
            substeps: 2,
            iterations: 20,
        },
        Method::SmallStepsXpbd { substeps: 20 },
        Method::SmallStepsXpbd { substeps: 40 },
        Method::Verlet { substeps: 200 },
    ];
    let mut total = DefaultHasher::new();
    let mut report = |case: String, hash: u64| {
        println!("{case}: {hash:016x}");
        hash.hash(&mut total);
    };
    for (columns, rows, frames) in [(64, 46, 90), (131, 127, 20), (31, 211, 20)] {
        for method in methods {
            for wind_every in [1, 4] {
                for threads in [1, 2] {
                    let hash = fingerprint(threads, frames, || {
                        let model = grid(columns, rows).with_hoist_pinned().expect("a grid");
                        flag(model, method, Some(wind_every), threads)
                    });
                    let name = method.name();
                    report(
                        format!(
                            "{columns}x{rows} {name} wind every {wind_every}, {threads} threads"
                        ),
                        hash,
                    );
                }
            }
        }
    }
    let (columns, rows) = (40, 29);
    for (case, mesh, wind) in [
        ("triangle mesh", true, Some(1)),
        ("grid without wind", false, None),
    ] {
        for method in methods {
            for threads in [1, 2] {
                let hash = fingerprint(threads, 60, || {
                    flag(hoisted(columns, rows, mesh), method, wind, threads)
                });
                report(format!("{case} {}, {threads} threads", method.name()), hash);
            }
        }
    }
    for threads in [1, 2] {
        let hash = fingerprint(threads, 3, || {
            let model = grid(512, 512).with_hoist_pinned().expect("a grid");
            flag(
                model,
                Method::SmallStepsXpbd { substeps: 20 },
                Some(1),
                threads,
            )
        });
        report(format!("512x512 small_steps_xpbd, {threads} threads"), hash);
    }
    println!("TOTAL {:016x}", total.finish());
}

/// How long a thread takes to see a value another thread has just stored: half the round trip of a
/// counter bounced between two spinning threads (the median over batches of 64 round trips, so that a
/// thread descheduled now and then does not count), over about `measuring_time` (at most 4000
/// batches). `None` where the machine offers fewer than two CPUs, or where no round trip came back
/// within four times `measuring_time` (two threads that cannot run at once; always for a zero time).
///
/// A team hands rows from core to core at every stage of a sub-step, so this latency is part of the
/// cost of a step on two threads: on a virtual machine whose host sometimes places its two CPUs on cores
/// far apart (about 30 ns near, about 150 ns far on a 2-core virtual machine), the default flag's
/// frame on two threads follows it.
fn thread_handoff_latency(measuring_time: std::time::Duration) -> Option<std::time::Duration> {
    use std::sync::atomic::AtomicU64;
    use std::time::Instant;
    /// Round trips timed together: a look at the clock for each would add its own cost to each.
    const BATCH: u32 = 64;
    const MOST_BATCHES: usize = 4000;
    const STOP: u64 = u64::MAX;
    if std::thread::available_parallelism().map_or(1, |n| n.get()) < 2 {
        return None;
    }
    /// On cache lines of its own, so that nothing else shares its transfers.
    #[repr(align(128))]
    struct Counter(AtomicU64);
    let counter = Counter(AtomicU64::new(0));
    let counter = &counter.0;
    // The counter once it is above `after` (the other thread has stored), or `STOP`; `None` if `give_up`
    // says so first (looked at every few thousand spins, when the core is also yielded: on a machine
    // whose other CPU is busy the two threads take turns on one, and would otherwise spin away whole
    // time slices).
    let await_above = |after: u64, give_up: &dyn Fn() -> bool| {
        let mut spins = 0u32;
        loop {
            let value = counter.load(Ordering::Acquire);
            if value == STOP || value > after {
                return Some(value);
            }
            spins = spins.wrapping_add(1);
            if spins.is_multiple_of(4096) {
                if give_up() {
                    return None;
                }
                std::thread::yield_now();
            }
            std::hint::spin_loop();
        }
    };
    std::thread::scope(|scope| {
        scope.spawn(|| {
            let mut seen = 0;
            // Answers each value with the next until told to stop.
            while let Some(value) = await_above(seen, &|| false) {
                if value == STOP {
                    return;
                }
                counter.store(value + 1, Ordering::Release);
                seen = value + 1;
            }
        });
        let began = Instant::now();
        // A machine too busy to run both threads at once would take a time slice a round trip.
        let too_long = || began.elapsed() > measuring_time.saturating_mul(4);
        // One round trip before the clock starts: the other thread is spinning by then.
        counter.store(1, Ordering::Release);
        let mut value = await_above(1, &too_long);
        let start = Instant::now();
        // The time of each batch of `BATCH` round trips.
        let mut batches = Vec::new();
        'measuring: while batches.len() < MOST_BATCHES && start.elapsed() < measuring_time {
            let batch_start = Instant::now();
            for _ in 0..BATCH {
                let Some(last) = value else {
                    break 'measuring;
                };
                counter.store(last + 1, Ordering::Release);
                value = await_above(last + 1, &too_long);
            }
            batches.push(batch_start.elapsed());
        }
        counter.store(STOP, Ordering::Release);
        batches.sort_unstable();
        (!batches.is_empty()).then(|| batches[batches.len() / 2] / (2 * BATCH))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hand-off is measured wherever two threads can run, and returns (the other thread told to
    /// stop and joined); on one CPU there is nothing to measure.
    #[test]
    fn the_handoff_latency_is_measured_where_two_threads_run() {
        // Long enough for two threads that must take turns with the other tests' (up to four times
        // this before it gives up); it stops after its 4000 batches, about 20 ms, where they need not.
        let measuring_time = std::time::Duration::from_millis(250);
        let latency = thread_handoff_latency(measuring_time);
        if std::thread::available_parallelism().map_or(1, |n| n.get()) < 2 {
            assert_eq!(latency, None);
            return;
        }
        let latency = latency.expect("two CPUs: a round trip comes back");
        // Half a round trip: more than nothing, and within the time it was measured over.
        assert!(latency > std::time::Duration::ZERO && latency < measuring_time);
        // No time to measure in: nothing measured (and no panic for the longest time either, which
        // stops after its 4000 batches).
        assert_eq!(thread_handoff_latency(std::time::Duration::ZERO), None);
        assert!(thread_handoff_latency(std::time::Duration::MAX).is_some());
    }
}
