//! How fast this machine's memory feeds one core and several, and how fast a core
//! reads what another core has just written, measured in one run. A large cloth's step waits on memory
//! for part of its time, and no second thread makes that part faster than the second row here makes
//! memory: these figures bound the two-thread speed-up of `sheer bench sim` on large grids
//! (`crates/sheer-cloth/README.md`, "Against the target"). Sizes are in MiB (2²⁰ bytes), rates in GB/s
//! (10⁹ bytes a second).
//!
//! `cargo run -p sheer-cloth --release --example memory -- [--csv] [--threads 1,2] [--seconds S]`

use std::fmt::Write as _;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use clap::Parser;

/// A one-line error for the command line.
#[derive(Debug)]
struct CliError(String);

impl CliError {
    fn new(message: impl Into<String>) -> CliError {
        CliError(message.into())
    }
}

/// The longest measuring time a case may ask for, seconds.
const MAX_SECONDS: f64 = 3600.0;

fn check_seconds(seconds: f64) -> Result<(), CliError> {
    if seconds.is_finite() && (0.0..=MAX_SECONDS).contains(&seconds) {
        Ok(())
    } else {
        Err(CliError::new(format!(
            "--seconds must lie in [0, {MAX_SECONDS}], got {seconds:?}"
        )))
    }
}

/// A line on standard output; a closed pipe is an error, not a panic.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)
            .map_err(|e| CliError::new(format!("cannot write to standard output: {e}")))
    }};
}

/// The most MiB the run may allocate in all (every streaming thread's buffer, or the hand-over's two):
/// beyond it a typo would take the machine's memory.
const MAX_MEBIBYTES: usize = 4096;

/// MiB each streaming thread takes unless told: well beyond a last-level cache (the build machine's is
/// 32 MiB), shrunk where that many threads would pass [`MAX_MEBIBYTES`].
const DEFAULT_MEBIBYTES: usize = 256;

/// MiB the hand-over case streams to evict its buffer from the caches: four times the build machine's
/// last-level cache.
const EVICT_MEBIBYTES: usize = 128;

/// Rounds of the hand-over case (each writes and reads the cache-sized buffer three times).
const HANDOVER_ROUNDS: usize = 24;

/// A value of the hand-over's turn counter that tells the other thread to stop (its partner panicked).
const STOP: usize = usize::MAX;

/// Memory bandwidth of one core and several, and the hand-over between two cores.
#[derive(Debug, Parser)]
struct BenchMemoryArgs {
    /// MiB each thread streams in the read and read-write cases, in [1, 4096], with all the threads
    /// together at most 4096: well beyond the last-level cache, so that they measure memory. Default:
    /// 256, or less where that many threads would pass 4096.
    #[arg(long, allow_negative_numbers = true)]
    mebibytes: Option<i64>,
    /// MiB of the hand-over case's buffer, in [1, 3968]: within the last-level cache, so that reading
    /// it after a write measures where the written data is (the build machine's two cores report
    /// 32 MiB; 6 is about what a thread's wavefront on a 1 024-column cloth keeps in flight).
    #[arg(long, default_value_t = 6, allow_negative_numbers = true)]
    cache_mebibytes: i64,
    /// Thread counts of the read and read-write cases (comma-separated), each at most the number of
    /// cores. Default: 1 and all cores.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    threads: Vec<i64>,
    /// Minimum measuring time per streaming case, seconds, in [0, 3600] (at least one pass is timed).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    seconds: f64,
    /// Print CSV: case,threads,mebibytes,gigabytes_per_s
    #[arg(long)]
    csv: bool,
}

/// A count given on the command line, checked to lie in `range`.
fn count_in(
    name: &str,
    value: i64,
    range: std::ops::RangeInclusive<usize>,
) -> Result<usize, CliError> {
    usize::try_from(value)
        .ok()
        .filter(|v| range.contains(v))
        .ok_or_else(|| {
            CliError::new(format!(
                "--{name} must lie in [{}, {}], got {value}",
                range.start(),
                range.end()
            ))
        })
}

/// Running sums of [`sum`]: 16 vector registers' worth of two `f64` each even on baseline x86-64,
/// so that the adds (each waiting for the one before in its sum) keep up with the loads. The 6 MiB
/// buffer just written by the reading thread measured 62.4–69.5 GB/s with 8 sums and 64.6–77.0 with
/// 32 (five runs each on the build machine): it comes from the last-level cache at about that rate,
/// and the adds did not hold it back.
const SUMS: usize = 32;

/// The sum of `buffer` in [`SUMS`] running sums, which the compiler keeps in vector registers: a
/// stream of loads.
fn sum(buffer: &[f64]) -> f64 {
    let mut lanes = [0.0; SUMS];
    for chunk in buffer.chunks_exact(SUMS) {
        for (lane, x) in lanes.iter_mut().zip(chunk) {
            *lane += x;
        }
    }
    lanes.iter().sum::<f64>() + buffer.chunks_exact(SUMS).remainder().iter().sum::<f64>()
}

/// Reads and writes every element of `buffer` once (a map that keeps the values bounded, towards 2).
fn update(buffer: &mut [f64]) {
    for x in buffer {
        *x = *x * 0.5 + 1.0;
    }
}

/// Gigabytes a second of `bytes` moved in `time`.
fn gigabytes_per_s(bytes: usize, time: Duration) -> f64 {
    bytes as f64 / time.as_secs_f64().max(1e-9) * 1e-9
}

/// `f64`s in `mebibytes` MiB.
fn elements_in(mebibytes: usize) -> usize {
    mebibytes * (1 << 20) / 8
}

/// What a streaming case does to its thread's buffer in one pass, and how many bytes that moves.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Stream {
    /// Every element read.
    Read,
    /// Every element read and written.
    ReadWrite,
}

impl Stream {
    fn name(self) -> &'static str {
        match self {
            Stream::Read => "read",
            Stream::ReadWrite => "read_write",
        }
    }

    fn pass(self, buffer: &mut [f64]) {
        match self {
            Stream::Read => {
                std::hint::black_box(sum(std::hint::black_box(&*buffer)));
            }
            Stream::ReadWrite => update(std::hint::black_box(buffer)),
        }
    }

    /// Bytes moved by a pass over `elements` elements.
    fn bytes(self, elements: usize) -> usize {
        match self {
            Stream::Read => 8 * elements,
            Stream::ReadWrite => 16 * elements,
        }
    }
}

/// `threads` threads (at most one a core) each making `passes` passes of `stream` over a buffer of its
/// own (`elements` long, written first by that thread, so that it lies in that thread's memory), all
/// starting together: the bytes all moved over the time the slowest took, GB/s.
fn stream_together(stream: Stream, threads: usize, elements: usize, passes: usize) -> f64 {
    let ready = AtomicUsize::new(0);
    let times: Vec<Duration> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                let ready = &ready;
                scope.spawn(move || {
                    let mut buffer = vec![1.0; elements];
                    stream.pass(&mut buffer);
                    // Spinning rather than parking, so that every thread holds its core.
                    ready.fetch_add(1, Ordering::AcqRel);
                    while ready.load(Ordering::Acquire) < threads {
                        std::hint::spin_loop();
                    }
                    let start = Instant::now();
                    for _ in 0..passes {
                        stream.pass(&mut buffer);
                    }
                    start.elapsed()
                })
            })
            .collect();
        workers
            .into_iter()
            .map(|w| w.join().expect("a streaming thread panicked"))
            .collect()
    });
    let slowest = times.into_iter().max().unwrap_or_default();
    gigabytes_per_s(threads * passes * stream.bytes(elements), slowest)
}

/// Read bandwidths of a cache-sized buffer, GB/s, each the median of its rounds, as one thread (the
/// reader) finds it: just written by itself, just written by the other thread (the writer), and
/// written by itself and then evicted. Both threads spin between their turns, so on two or more cores
/// they very likely run on two (nothing pins them).
struct Handover {
    own: f64,
    other: f64,
    evicted: f64,
}

/// Tells the partner thread to stop waiting if this one unwinds, so that a panic ends the case
/// instead of leaving the other spinning.
struct StopOnUnwind<'a>(&'a AtomicUsize);

impl Drop for StopOnUnwind<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(STOP, Ordering::Release);
        }
    }
}

/// Waits until `turn` is `value` (`true`) or [`STOP`] (`false`).
fn wait_for(turn: &AtomicUsize, value: usize) -> bool {
    loop {
        match turn.load(Ordering::Acquire) {
            v if v == value => return true,
            STOP => return false,
            _ => std::hint::spin_loop(),
        }
    }
}

/// The hand-over case on a buffer of `elements`, evicted by streaming `evict_elements` of the reader's
/// own.
fn handover(elements: usize, evict_elements: usize) -> Handover {
    let shared = Mutex::new(vec![1.0; elements]);
    let turn = AtomicUsize::new(0);
    let bytes = 8 * elements;
    std::thread::scope(|scope| {
        // The writer: rewrites the buffer on its turn.
        scope.spawn(|| {
            let _stop = StopOnUnwind(&turn);
            for round in 0..HANDOVER_ROUNDS {
                if !wait_for(&turn, 2 * round) {
                    return;
                }
                update(&mut shared.lock().expect("the reader panicked"));
                turn.store(2 * round + 1, Ordering::Release);
            }
        });
        let reader = scope.spawn(|| {
            let _stop = StopOnUnwind(&turn);
            let mut evict = vec![1.0; evict_elements];
            let mut rates = [const { Vec::new() }; 3];
            let timed_read = |buffer: &[f64]| {
                let start = Instant::now();
                std::hint::black_box(sum(std::hint::black_box(buffer)));
                gigabytes_per_s(bytes, start.elapsed())
            };
            for round in 0..HANDOVER_ROUNDS {
                if !wait_for(&turn, 2 * round + 1) {
                    panic!("the writing thread panicked");
                }
                let mut buffer = shared.lock().expect("the writer panicked");
                rates[1].push(timed_read(&buffer));
                update(&mut buffer);
                rates[0].push(timed_read(&buffer));
                update(&mut buffer);
                std::hint::black_box(sum(std::hint::black_box(&evict)));
                update(&mut evict);
                rates[2].push(timed_read(&buffer));
                drop(buffer);
                turn.store(2 * round + 2, Ordering::Release);
            }
            rates.map(|mut r| {
                r.sort_by(f64::total_cmp);
                r[r.len() / 2]
            })
        });
        let [own, other, evicted] = reader.join().expect("the reading thread panicked");
        Handover {
            own,
            other,
            evicted,
        }
    })
}

fn main() {
    if let Err(CliError(message)) = run(&BenchMemoryArgs::parse()) {
        eprintln!("error: {message}");
        std::process::exit(1);
    }
}

fn run(args: &BenchMemoryArgs) -> Result<(), CliError> {
    check_seconds(args.seconds)?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut threads: Vec<usize> = if args.threads.is_empty() {
        vec![1, cores]
    } else {
        args.threads
            .iter()
            .map(|&t| count_in("threads", t, 1..=cores))
            .collect::<Result<_, _>>()?
    };
    threads.sort_unstable();
    threads.dedup();
    // Every thread streams a buffer of its own, all at once.
    let most_threads = threads.last().copied().unwrap_or(1);
    let mebibytes = match args.mebibytes {
        Some(given) => {
            let mebibytes = count_in("mebibytes", given, 1..=MAX_MEBIBYTES)?;
            if most_threads * mebibytes > MAX_MEBIBYTES {
                return Err(CliError::new(format!(
                    "--threads × --mebibytes must be at most {MAX_MEBIBYTES} (every thread streams a \
                     buffer of its own), got {most_threads} × {mebibytes}"
                )));
            }
            mebibytes
        }
        None => DEFAULT_MEBIBYTES.min(MAX_MEBIBYTES / most_threads),
    };
    let cache_mebibytes = count_in(
        "cache-mebibytes",
        args.cache_mebibytes,
        1..=MAX_MEBIBYTES - EVICT_MEBIBYTES,
    )?;
    let elements = elements_in(mebibytes);
    let row = |case: &str, threads: usize, mebibytes: usize, rate: f64| {
        let mut line = String::new();
        if args.csv {
            let _ = write!(line, "{case},{threads},{mebibytes},{rate:.2}");
        } else {
            let _ = write!(line, "{case:<20} {threads:>7} {mebibytes:>10} {rate:>10.2}");
        }
        outln!("{line}")
    };
    if args.csv {
        outln!("case,threads,mebibytes,gigabytes_per_s")?;
    } else {
        outln!(
            "{:<20} {:>7} {:>10} {:>10}",
            "case",
            "threads",
            "MiB each",
            "GB/s"
        )?;
    }
    let mut ratios = Vec::new();
    for stream in [Stream::Read, Stream::ReadWrite] {
        // Passes enough for the minimum time, from one timed pass of one thread.
        let mut buffer = vec![1.0; elements];
        stream.pass(&mut buffer);
        let start = Instant::now();
        stream.pass(&mut buffer);
        let pass = start.elapsed().as_secs_f64().max(1e-9);
        drop(buffer);
        let passes = ((args.seconds / pass).ceil() as usize).max(1);
        let rates: Vec<(usize, f64)> = threads
            .iter()
            .map(|&t| (t, stream_together(stream, t, elements, passes)))
            .collect();
        for &(t, rate) in &rates {
            row(stream.name(), t, mebibytes, rate)?;
        }
        // Against one thread, when it was measured.
        if let (Some(&(1, one)), Some(&(many, rate))) = (rates.first(), rates.last())
            && many > 1
        {
            ratios.push(format!("{} {:.2}×", stream.name(), rate / one));
        }
    }
    if cores >= 2 {
        // Two threads take part: the writer and the reader.
        let found = handover(elements_in(cache_mebibytes), elements_in(EVICT_MEBIBYTES));
        row("read_own_written", 2, cache_mebibytes, found.own)?;
        row("read_other_written", 2, cache_mebibytes, found.other)?;
        row("read_evicted", 2, cache_mebibytes, found.evicted)?;
    } else {
        eprintln!("the hand-over case needs two cores; this machine shows one");
    }
    if !ratios.is_empty() {
        // To stderr, so that the CSV stays CSV.
        eprintln!(
            "{most_threads} threads against one: {} (a step waiting on memory gains no more from them)",
            ratios.join(", ")
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sum covers every element, the remainder after the blocks of running sums too.
    #[test]
    fn the_sum_adds_every_element() {
        for n in [0, 1, SUMS - 1, SUMS, SUMS + 1, 100] {
            let buffer: Vec<f64> = (1..=n).map(|i| i as f64).collect();
            assert_eq!(sum(&buffer), (n * (n + 1) / 2) as f64, "{n} elements");
        }
    }

    /// Streaming and handing over a small buffer give finite, positive rates.
    #[test]
    fn every_case_measures_a_finite_positive_rate() {
        for stream in [Stream::Read, Stream::ReadWrite] {
            for threads in [1, 2] {
                let rate = stream_together(stream, threads, 1 << 12, 3);
                assert!(
                    rate.is_finite() && rate > 0.0,
                    "{stream:?} on {threads}: {rate}"
                );
            }
        }
        let found = handover(1 << 12, 1 << 14);
        for rate in [found.own, found.other, found.evicted] {
            assert!(rate.is_finite() && rate > 0.0, "{rate}");
        }
    }
}
