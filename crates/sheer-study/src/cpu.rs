//! CPU time of the calling thread, s: `clock_gettime(CLOCK_THREAD_CPUTIME_ID)` (POSIX).
//!
//! The study times runs on one thread while other processes may share the machine; the thread's CPU
//! clock counts only the time it ran, so a busy machine slows the study down but barely changes the
//! costs it reports (caches and memory bandwidth are still shared: the docs say what else was running).

/// CPU seconds consumed by the calling thread so far.
#[allow(unsafe_code)] // the FFI call below: std has no per-thread CPU clock.
pub fn thread_cpu_seconds() -> f64 {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `now` is a valid, writable timespec; CLOCK_THREAD_CPUTIME_ID is supported on Linux and
    // every POSIX system with thread CPU clocks. On failure the struct stays zero and we fall back below.
    let status = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut now) };
    if status != 0 {
        return fallback_seconds();
    }
    now.tv_sec as f64 + now.tv_nsec as f64 * 1e-9
}

/// Wall-clock seconds since the first call: used only where the thread clock is unavailable.
fn fallback_seconds() -> f64 {
    use std::sync::OnceLock;
    use std::time::Instant;
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_clock_advances_with_work() {
        let before = thread_cpu_seconds();
        // Busy work the optimiser cannot remove; a few million additions take well over the clock's
        // resolution (1 ns on Linux), so the difference must be positive.
        let mut accumulator = 0u64;
        for i in 0..20_000_000u64 {
            accumulator = std::hint::black_box(accumulator.wrapping_add(i ^ (accumulator >> 3)));
        }
        std::hint::black_box(accumulator);
        assert!(thread_cpu_seconds() > before);
    }
}
