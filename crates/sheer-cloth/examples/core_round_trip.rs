//! Measures how long a cache line takes to go from one core to the other and back: two threads pass a
//! counter back and forth through one atomic, and the mean time per round trip is printed in ns.
//!
//! `cargo run -p sheer-cloth --release --example core_round_trip`
//!
//! The team's threads hand each other rows of the cloth at every stage of a sub-step, so two-thread
//! timings of a small cloth move with this figure: on the 2-core virtual machines of this project it
//! has been seen anywhere between about 100 and 530 ns, as the host moved the virtual cores.
//! Print it next to two-thread benchmarks to tell a slower machine from a slower program.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

const ROUND_TRIPS: u64 = 200_000;

fn main() {
    let counter = AtomicU64::new(0);
    let elapsed = std::thread::scope(|scope| {
        // The other thread answers every odd value with the next even one.
        scope.spawn(|| {
            for trip in 0..ROUND_TRIPS {
                while counter.load(Ordering::Acquire) != 2 * trip + 1 {
                    std::hint::spin_loop();
                }
                counter.store(2 * trip + 2, Ordering::Release);
            }
        });
        let start = Instant::now();
        for trip in 0..ROUND_TRIPS {
            counter.store(2 * trip + 1, Ordering::Release);
            while counter.load(Ordering::Acquire) != 2 * trip + 2 {
                std::hint::spin_loop();
            }
        }
        start.elapsed()
    });
    println!(
        "{:.1} ns per round trip between two threads",
        elapsed.as_secs_f64() * 1e9 / ROUND_TRIPS as f64
    );
}
