//! A grid sub-step (or a whole step's sub-steps, one after another) on a team of threads in one
//! hand-off: each thread runs every stage on its own rows, and waits for a neighbour only where their
//! rows meet.
//!
//! Pass by pass, a small cloth's sub-step on two threads is a dozen passes of a few microseconds, each
//! ended by a barrier at which the faster thread waits for the slower (on the default flag the team's
//! threads spent 22 % of their time waiting there, `perf record` of `fingerprint time 64x46 2 3000`).
//! But a stage's work on row `r` (the wind's cells, the prediction, a batch of strips by their last row,
//! the end of a sweep) touches only rows `r − above ..= r + below` (at most two rows up and one down),
//! so two threads holding the upper and the lower rows of the cloth depend on each other only near the
//! cut between them.
//!
//! Each part runs the stages in order on its own rows. Its *boundary* items are those that touch a row
//! that a neighbouring part touches in any stage; the rest, its *interior*, touch nothing another part
//! touches. A part runs stage `s` as: wait until each neighbour has finished its boundary items of stage
//! `s − 1`; run its own boundary items of stage `s`; say so; run its interior items. If a neighbour has
//! not got that far yet, it runs its interior items first (they depend on no other part) and waits
//! after them: on the default flag on two threads the time spent waiting inside the pipeline fell by
//! about a quarter (`perf record -e cpu-clock` of `fingerprint time 64x46 2 3000`: the waiting loop's
//! samples 0.92 → 0.66 a frame). Two items that
//! touch a common row and belong to different parts are boundary items of neighbouring parts (parts are
//! at least `above + below` rows tall, so parts further apart share no row). If the item of stage `s`
//! comes first in pass-by-pass order (`s < t`), the other part waits for this part's boundary of
//! stage `t − 1 ≥ s` before it starts its own boundary of stage `t`; items of one stage never
//! conflict (a batch's strips share no particle; per-row work is per row). So every pair of items that
//! share a row runs in the order of pass by pass, every projection reads the positions it reads there,
//! and the results are the same bits (tested here on the schedule, and bit for bit in the solver's
//! tests). A part that runs ahead waits only when it would overtake its neighbour by a whole stage, so
//! the unevenness of single stages evens out over the sub-step.
//!
//! A stage can also wait for every part to have finished an earlier stage (`after_all`): the long-range
//! attachments read the pins' predicted positions, which the prediction writes row by row anywhere in
//! the cloth.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// One stage of a sub-step: items on rows `0..items`, item `r` touching (reading or writing) rows
/// `r − above ..= r + below` only.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Stage {
    pub items: usize,
    pub above: usize,
    pub below: usize,
    /// Every part must have finished this earlier stage before any part starts this one.
    pub after_all: Option<usize>,
}

/// The schedule of a sequence of stages over the rows of a grid, cut into parts of consecutive rows.
#[derive(Clone, Debug)]
pub(crate) struct Pipeline {
    stages: Vec<Stage>,
    /// The first row of each part, and the row after the last (`cuts[parts]` = rows).
    cuts: Vec<usize>,
    parts: usize,
    /// The most rows any stage's items reach up and down.
    above: usize,
    below: usize,
}

impl Pipeline {
    /// The schedule of `stages` over the rows, cut into `parts` parts of about equal work, `work[r]`
    /// being the cost of row `r` (any unit), each cut then moved by the rows `progress` has learnt
    /// ([`Progress::rebalance`]); `None` if a part would have fewer than `above + below + 1` rows, so
    /// that parts that are not neighbours might share a row.
    pub fn new(
        stages: Vec<Stage>,
        work: &[f64],
        parts: usize,
        progress: &Progress,
    ) -> Option<Pipeline> {
        let above = stages.iter().map(|s| s.above).max().unwrap_or(0);
        let below = stages.iter().map(|s| s.below).max().unwrap_or(0);
        let ordered = stages
            .iter()
            .enumerate()
            .all(|(s, stage)| stage.after_all.is_none_or(|k| k < s));
        // Ascending, and every part taller than the reach of its neighbours' items.
        let fits = |cuts: &[usize]| {
            cuts.windows(2)
                .all(|pair| pair[1] > pair[0] + above + below)
        };
        let balanced = balanced_cuts(work, parts);
        let moved = (progress.shifts.len() + 1 == parts).then(|| {
            let inner = balanced[1..parts].iter().zip(&progress.shifts);
            let inner = inner.map(|(&cut, &shift)| cut.saturating_add_signed(shift));
            std::iter::once(0)
                .chain(inner)
                .chain([work.len()])
                .collect::<Vec<usize>>()
        });
        // Moved cuts that leave a part too short are not taken.
        let cuts = match moved {
            Some(moved) if fits(&moved) => moved,
            _ => balanced,
        };
        (parts >= 1 && ordered && fits(&cuts)).then_some(Pipeline {
            stages,
            cuts,
            parts,
            above,
            below,
        })
    }

    pub fn parts(&self) -> usize {
        self.parts
    }

    /// First row of part `p` (`p = parts`: the row after the last).
    fn cut(&self, p: usize) -> usize {
        self.cuts[p]
    }

    /// The rows of stage `s` that part `p` runs: its boundary items next to the part above and next to
    /// the part below, and its interior items between them.
    fn ranges(&self, s: usize, p: usize) -> ([Range<usize>; 2], Range<usize>) {
        let stage = &self.stages[s];
        let (start, end) = (
            self.cut(p).min(stage.items),
            self.cut(p + 1).min(stage.items),
        );
        // The part above touches rows up to `cut(p) − 1 + below`; item `r` reaches up to `r − above`.
        let upper_end = if p > 0 {
            (self.cut(p) + self.below + stage.above).clamp(start, end)
        } else {
            start
        };
        // The part below touches rows from `cut(p + 1) − above`; item `r` reaches down to `r + below`.
        let lower_start = if p + 1 < self.parts {
            (self.cut(p + 1).saturating_sub(self.above + stage.below)).clamp(upper_end, end)
        } else {
            end
        };
        ([start..upper_end, lower_start..end], upper_end..lower_start)
    }

    /// Runs part `p`'s items, stage by stage, waiting for its neighbours where needed (see the module
    /// documentation): `work(stage, rows)` runs the items of `stage` on `rows` (not empty), in ascending
    /// order, a run of rows at a time, so that a stage's work on consecutive rows can go in one call
    /// (the strips of a batch: one call per strip had cost a fifth of their time). Every part must run
    /// at the same time, on its own thread, with the same `progress` (fresh: see [`Progress::reset`]); a
    /// part that panics makes the others panic instead of waiting for it.
    pub fn run_part(
        &self,
        p: usize,
        progress: &Progress,
        mut work: impl FnMut(usize, Range<usize>),
    ) {
        debug_assert!(p < self.parts && progress.counters.len() >= self.parts);
        let poison = progress.poison_if_unwinding();
        let started = progress.epoch.elapsed();
        let mut waited = Duration::ZERO;
        for (s, stage) in self.stages.iter().enumerate() {
            if let Some(k) = stage.after_all {
                for q in 0..self.parts {
                    waited += progress.wait(q, 2 * k + 2);
                }
            }
            let ([upper, lower], interior) = self.ranges(s, p);
            let neighbours = [p.checked_sub(1), (p + 1 < self.parts).then_some(p + 1)];
            let neighbours = neighbours.into_iter().flatten();
            let ready = s == 0 || neighbours.clone().all(|q| progress.reached(q, 2 * s - 1));
            let mut run = |rows: Range<usize>| {
                if !rows.is_empty() {
                    work(s, rows);
                }
            };
            if ready {
                run(upper);
                run(lower);
                progress.publish(p, 2 * s + 1);
                run(interior);
            } else {
                // A neighbour is behind: the interior first, which touches nothing another part
                // touches (and shares no particle with the stage's other items), then the boundary.
                run(interior);
                for q in neighbours {
                    waited += progress.wait(q, 2 * s - 1);
                }
                run(upper);
                run(lower);
                progress.publish(p, 2 * s + 1);
            }
            progress.publish(p, 2 * s + 2);
        }
        let timing = &progress.timings[p];
        timing
            .started
            .store(started.as_nanos() as u64, Ordering::Relaxed);
        let finished = progress.epoch.elapsed().as_nanos() as u64;
        timing.finished.store(finished, Ordering::Relaxed);
        timing
            .waited
            .store(waited.as_nanos() as u64, Ordering::Relaxed);
        poison.disarm();
    }
}

/// The first row of each of `parts` parts, and the row after the last: part `p` starts at the row
/// boundary nearest to `p/parts` of the work, `work[r]` being row `r`'s.
fn balanced_cuts(work: &[f64], parts: usize) -> Vec<usize> {
    // The work before each row (and in all rows, last).
    let before: Vec<f64> = std::iter::once(0.0)
        .chain(work.iter().scan(0.0, |sum, w| {
            *sum += w;
            Some(*sum)
        }))
        .collect();
    let total = before[work.len()];
    (0..=parts)
        .map(|p| {
            if p == parts {
                return work.len();
            }
            let target = total * p as f64 / parts as f64;
            let after = before.partition_point(|&b| b < target).min(work.len());
            match after.checked_sub(1) {
                Some(b) if target - before[b] < before[after] - target => b,
                _ => after,
            }
        })
        .collect()
}

/// An atomic counter alone on its cache line, so that one part's progress does not move the line that
/// another part spins on.
#[derive(Default)]
#[repr(align(128))]
struct Counter(AtomicUsize);

/// When a part started and finished its run, in nanoseconds since [`Progress`]'s epoch, and how long
/// it waited for other parts meanwhile (ns).
#[derive(Default)]
#[repr(align(128))]
struct Timing {
    started: AtomicU64,
    finished: AtomicU64,
    waited: AtomicU64,
}

/// How far each part of a [`Pipeline`] has come: `2s + 1` once its boundary items of stage `s` are done,
/// `2s + 2` once all its items of stage `s` are. Also how long the parts were busy, from which it learns
/// how far to move the cuts so that they are equally busy ([`rebalance`](Progress::rebalance)). Two
/// opposed parts of a wavefront use its counters too, each counting the units it has finished
/// ([`Wavefront::run_opposed_part`](crate::fast::wavefront::Wavefront::run_opposed_part)).
pub(crate) struct Progress {
    counters: Vec<Counter>,
    poisoned: AtomicBool,
    epoch: Instant,
    timings: Vec<Timing>,
    /// Per cut between parts `k` and `k + 1`: rows it is moved by, and how much busier (ns, smoothed)
    /// part `k` has been than part `k + 1`.
    shifts: Vec<isize>,
    lateness: Vec<f64>,
    /// How often a cut has moved.
    moves: u64,
}

impl Default for Progress {
    fn default() -> Self {
        Progress {
            counters: Vec::new(),
            poisoned: AtomicBool::new(false),
            epoch: Instant::now(),
            timings: Vec::new(),
            shifts: Vec::new(),
            lateness: Vec::new(),
            moves: 0,
        }
    }
}

impl Clone for Progress {
    /// Counters are reset before every use, so a clone starts with none.
    fn clone(&self) -> Self {
        Progress::default()
    }
}

impl std::fmt::Debug for Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Progress {{ parts: {} }}", self.counters.len())
    }
}

impl Progress {
    /// Zero progress for `parts` parts. Must happen before the parts start (the team's hand-off orders
    /// it before them).
    pub fn reset(&mut self, parts: usize) {
        self.counters.resize_with(parts, Counter::default);
        for counter in &self.counters {
            counter.0.store(0, Ordering::Relaxed);
        }
        self.timings.resize_with(parts, Timing::default);
        if self.shifts.len() + 1 != parts {
            self.shifts = vec![0; parts.saturating_sub(1)];
            self.lateness = vec![0.0; parts.saturating_sub(1)];
            self.moves += 1;
        }
        *self.poisoned.get_mut() = false;
    }

    /// Zero progress for the `parts` parts of a wavefront
    /// ([`Wavefront::run_opposed_part`](crate::fast::wavefront::Wavefront::run_opposed_part)): one
    /// counter per part, the cuts a pipeline learnt left as they are. Must happen before the parts start.
    pub fn reset_counters(&mut self, parts: usize) {
        if self.counters.len() < parts {
            self.counters.resize_with(parts, Counter::default);
        }
        for counter in &self.counters[..parts] {
            counter.0.store(0, Ordering::Relaxed);
        }
        *self.poisoned.get_mut() = false;
    }

    /// How often [`rebalance`](Progress::rebalance) has moved a cut: a pipeline built before the
    /// latest move has its cuts elsewhere.
    pub fn cuts_moved(&self) -> u64 {
        self.moves
    }

    /// After every part of `pipeline` has run: moves a cut by a row when the part above it has been
    /// busier (or less busy) than the part below by more than a row's time, smoothed over runs. The
    /// threads of a virtual machine do not run equally fast, and rows next to a cut cost more than
    /// others (their lines move between the cores); where the cuts lie does not change a bit of the
    /// results.
    ///
    /// Busy time is the time a part ran less the time it waited for other parts. Their finishing times,
    /// which this compared before, hide the imbalance: a part with less work catches up with its
    /// neighbour at some stage's boundary, waits there, and then finishes with it. On the default flag
    /// on two threads the first part had waited 3.6–6 µs per sub-step at the third stage alone (`rdtsc`
    /// around the waits, `fingerprint time 64x46 2 1000`, a temporary instrumentation), while the cut
    /// stayed where it was.
    pub fn rebalance(&mut self, pipeline: &Pipeline) {
        if self.shifts.len() + 1 != pipeline.parts {
            return;
        }
        let busy = |p: usize| {
            let t = &self.timings[p];
            let (started, finished, waited) = (
                t.started.load(Ordering::Relaxed),
                t.finished.load(Ordering::Relaxed),
                t.waited.load(Ordering::Relaxed),
            );
            finished.saturating_sub(started).saturating_sub(waited) as f64
        };
        for k in 0..self.shifts.len() {
            let (busy_above, busy_below) = (busy(k), busy(k + 1));
            // The rows of the two parts the cut divides.
            let rows = pipeline.cut(k + 2) - pipeline.cut(k);
            let row_time = (busy_above + busy_below) / rows as f64;
            let late = &mut self.lateness[k];
            *late = 0.8 * *late + 0.2 * (busy_above - busy_below);
            let limit = rows as isize / 4;
            let shift = &mut self.shifts[k];
            let step = if *late > row_time && *shift > -limit {
                -1
            } else if *late < -row_time && *shift < limit {
                1
            } else {
                continue;
            };
            *shift += step;
            *late = 0.0;
            self.moves += 1;
        }
    }

    /// Whether part `q` has reached `value` (acquiring what it wrote before, as [`wait`](Self::wait)).
    fn reached(&self, q: usize, value: usize) -> bool {
        self.counters[q].0.load(Ordering::Acquire) >= value
    }

    pub(crate) fn publish(&self, p: usize, value: usize) {
        // Release: what the part wrote before is seen by whoever sees the value (`wait`'s acquire).
        self.counters[p].0.store(value, Ordering::Release);
    }

    /// Waits until counter `q` has reached `value`, as [`wait`](Self::wait), and returns the value it saw
    /// (at least `value`), so that a caller can skip the counter's cache line until it needs more.
    pub(crate) fn wait_at_least(&self, q: usize, value: usize) -> usize {
        self.wait(q, value);
        self.counters[q].0.load(Ordering::Acquire)
    }

    /// A guard that poisons the progress if it is dropped, so that parts waiting for the one that holds
    /// it panic instead of waiting for ever if that one unwinds; [`Poison::disarm`] it at the end.
    pub(crate) fn poison_if_unwinding(&self) -> Poison<'_> {
        Poison(self)
    }

    /// Waits until part `q` has reached `value`: spinning (a neighbour is normally microseconds behind),
    /// then yielding the core, in case the neighbour's thread is waiting for one.
    /// Returns how long it waited (zero, without reading the clock, if it did not).
    fn wait(&self, q: usize, value: usize) -> Duration {
        if self.counters[q].0.load(Ordering::Acquire) >= value {
            return Duration::ZERO;
        }
        let start = Instant::now();
        let mut spins = 0u32;
        while self.counters[q].0.load(Ordering::Acquire) < value {
            assert!(
                !self.poisoned.load(Ordering::Relaxed),
                "another part of the sub-steps panicked"
            );
            if spins < SPINS_BEFORE_YIELDING {
                spins += 1;
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
        start.elapsed()
    }
}

/// `spin_loop` hints before a waiting part yields its core: about 30 µs on the AMD EPYC build machine,
/// several times a stage's work on the default flag.
const SPINS_BEFORE_YIELDING: u32 = 1 << 10;

/// Poisons the progress if dropped, which `run_part` (and an opposed part) prevents unless its part
/// unwinds.
pub(crate) struct Poison<'a>(&'a Progress);

impl Poison<'_> {
    /// The part finished: nothing to poison.
    pub(crate) fn disarm(self) {
        std::mem::forget(self);
    }
}

impl Drop for Poison<'_> {
    fn drop(&mut self) {
        self.0.poisoned.store(true, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    /// Runs every part of `pipeline` on its own thread and returns, per stage and row, the position of
    /// its item in the order in which the items ran; and how often a part ran a stage's interior
    /// before its boundary (its neighbour was behind).
    fn run_logged(pipeline: &Pipeline, slow_first_part: bool) -> (Vec<Vec<usize>>, usize) {
        let mut progress = Progress::default();
        progress.reset(pipeline.parts());
        let clock = AtomicUsize::new(0);
        let log: Vec<Vec<Mutex<Vec<usize>>>> = pipeline
            .stages
            .iter()
            .map(|stage| (0..stage.items).map(|_| Mutex::new(Vec::new())).collect())
            .collect();
        std::thread::scope(|scope| {
            for p in 0..pipeline.parts() {
                let (progress, clock, log) = (&progress, &clock, &log);
                scope.spawn(move || {
                    pipeline.run_part(p, progress, |s, rows| {
                        for row in rows {
                            // A little work, unevenly spread, so that the parts drift apart; with
                            // `slow_first_part`, much more on the first part's rows in every third stage,
                            // so that its neighbours find it behind.
                            let slow = slow_first_part && p == 0 && s % 3 == 0;
                            for _ in 0..(row * 7 + s * 13) % 50 + if slow { 3000 } else { 0 } {
                                std::hint::spin_loop();
                            }
                            let now = clock.fetch_add(1, Ordering::SeqCst);
                            log[s][row].lock().unwrap().push(now);
                        }
                    })
                });
            }
        });
        let order = log
            .into_iter()
            .map(|stage| {
                stage
                    .into_iter()
                    .map(|item| {
                        let runs = item.into_inner().unwrap();
                        assert_eq!(runs.len(), 1, "every item runs once");
                        runs[0]
                    })
                    .collect()
            })
            .collect::<Vec<Vec<usize>>>();
        let first_of = |s: usize, rows: Range<usize>| rows.map(|row| order[s][row]).min();
        let interior_first = (0..pipeline.stages.len())
            .flat_map(|s| (0..pipeline.parts()).map(move |p| (s, p)))
            .filter(|&(s, p)| {
                let ([upper, lower], interior) = pipeline.ranges(s, p);
                let boundary = [first_of(s, upper), first_of(s, lower)]
                    .into_iter()
                    .flatten()
                    .min();
                matches!((first_of(s, interior), boundary), (Some(i), Some(b)) if i < b)
            })
            .count();
        (order, interior_first)
    }

    /// The rows item `row` of `stage` touches.
    fn touched(stage: &Stage, row: usize) -> Range<usize> {
        row.saturating_sub(stage.above)..row + stage.below + 1
    }

    /// Every item runs on exactly one part, and every item that touches a row which an item of another
    /// part touches is among its part's boundary items (without regard to timing).
    fn check_boundaries(pipeline: &Pipeline) {
        let parts = pipeline.parts();
        for (s, stage) in pipeline.stages.iter().enumerate() {
            let mut owners = vec![0; stage.items];
            for p in 0..parts {
                let ([upper, lower], interior) = pipeline.ranges(s, p);
                for row in upper.clone().chain(lower.clone()).chain(interior.clone()) {
                    owners[row] += 1;
                }
                for row in interior {
                    let mine = touched(stage, row);
                    for q in (0..parts).filter(|&q| q != p) {
                        for (t, other) in pipeline.stages.iter().enumerate() {
                            let ([a, b], c) = pipeline.ranges(t, q);
                            for theirs in a.chain(b).chain(c).map(|r| touched(other, r)) {
                                assert!(
                                    mine.end <= theirs.start || theirs.end <= mine.start,
                                    "part {p}'s interior row {row} of stage {s} meets part {q}'s \
                                     stage {t}"
                                );
                            }
                        }
                    }
                }
            }
            assert!(owners.iter().all(|&n| n == 1), "stage {s}: {owners:?}");
        }
    }

    /// Every pair of items of different stages that touch a common row ran in stage order, and every
    /// `after_all` stage ran after all of its stage: checked on runs of real threads, for stage shapes
    /// like the solver's and for 2 to 4 parts over tall and short grids.
    #[test]
    fn items_that_share_a_row_run_in_stage_order() {
        // Parts run a stage's interior before its boundary when a neighbour is behind: half of the
        // runs slow the first part down so that this happens (asserted below).
        let solver_like = |rows: usize| {
            let stage = |items, above, below, after_all| Stage {
                items,
                above,
                below,
                after_all,
            };
            let mut stages = vec![stage(rows - 1, 0, 1, None), stage(rows, 1, 0, None)];
            for span in [2, 2, 1, 1, 1, 1, 1, 1] {
                stages.push(stage(rows, span, 0, None));
            }
            stages.push(stage(rows, 0, 0, Some(1)));
            for span in [2, 2, 1, 1] {
                stages.push(stage(rows, span, 0, None));
            }
            stages.push(stage(rows, 0, 0, Some(1)));
            stages
        };
        for (rows, parts) in [(46, 2), (12, 3), (9, 2), (131, 4), (24, 4)] {
            let stages = solver_like(rows);
            // Uneven work, so that the cuts fall elsewhere than at equal rows.
            let work: Vec<f64> = (0..rows).map(|r| 1.0 + (r % 5) as f64).collect();
            let pipeline = Pipeline::new(stages.clone(), &work, parts, &Progress::default())
                .expect("tall enough parts");
            check_boundaries(&pipeline);
            let mut interior_first = 0;
            for run in 0..20 {
                let (order, early) = run_logged(&pipeline, run % 2 == 1);
                interior_first += early;
                for (s, first) in stages.iter().enumerate() {
                    for (t, second) in stages.iter().enumerate().skip(s + 1) {
                        for r in 0..first.items {
                            for q in 0..second.items {
                                let shared = r.saturating_sub(first.above) <= q + second.below
                                    && q.saturating_sub(second.above) <= r + first.below;
                                if shared || second.after_all == Some(s) {
                                    assert!(
                                        order[s][r] < order[t][q],
                                        "{rows} rows, {parts} parts: stage {s} row {r} ran after \
                                         stage {t} row {q}"
                                    );
                                }
                            }
                        }
                    }
                }
            }
            // Parts found a neighbour behind and ran a stage's interior first (checked above too).
            assert!(
                interior_first > 0,
                "{rows} rows, {parts} parts: never interior first"
            );
        }
    }

    #[test]
    fn parts_share_the_work_evenly() {
        let stage = Stage {
            items: 12,
            above: 1,
            below: 0,
            after_all: None,
        };
        let cuts = |work: &[f64], parts| {
            Pipeline::new(vec![stage], work, parts, &Progress::default())
                .unwrap()
                .cuts
        };
        assert_eq!(cuts(&[1.0; 12], 2), [0, 6, 12]);
        assert_eq!(cuts(&[1.0; 12], 3), [0, 4, 8, 12]);
        // The heavier first rows go to a shorter first part.
        let work = [3.0, 3.0, 3.0, 3.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        assert_eq!(cuts(&work, 2), [0, 3, 12]);
    }

    /// The cut moves towards the busier part, by busy time: a part that waited for its neighbour gets
    /// rows although both finished together, and parts equally busy keep theirs.
    #[test]
    fn the_cut_moves_by_busy_time_not_by_finishing_time() {
        let stage = Stage {
            items: 24,
            above: 1,
            below: 0,
            after_all: None,
        };
        // Busy 10 µs and 12 µs (a row: 22/24 µs), both finishing at 100 µs; returns the cuts after
        // `runs` rebalancings.
        let cuts_after = |waited_above: u64, runs: usize| {
            let mut progress = Progress::default();
            progress.reset(2);
            let mut pipeline = Pipeline::new(vec![stage], &[1.0; 24], 2, &progress).unwrap();
            for _ in 0..runs {
                for (p, waited) in [(0, waited_above), (1, 0)] {
                    let t = &progress.timings[p];
                    t.started.store(100_000 - 12_000, Ordering::Relaxed);
                    t.finished.store(100_000, Ordering::Relaxed);
                    t.waited.store(waited, Ordering::Relaxed);
                }
                progress.rebalance(&pipeline);
                pipeline = Pipeline::new(vec![stage], &[1.0; 24], 2, &progress).unwrap();
            }
            pipeline.cuts
        };
        assert_eq!(cuts_after(0, 20), [0, 12, 24]);
        // One run is not enough (smoothed); a few move the cut a row down, and more move it again.
        assert_eq!(cuts_after(2_000, 1), [0, 12, 24]);
        assert_eq!(cuts_after(2_000, 3), [0, 13, 24]);
        assert!(cuts_after(2_000, 20)[1] > 13);
    }

    #[test]
    fn parts_too_short_for_their_reach_are_refused() {
        let stage = Stage {
            items: 10,
            above: 2,
            below: 1,
            after_all: None,
        };
        // 10 rows in 3 parts: 3, 3 and 4 rows, each needing more than 3.
        assert!(Pipeline::new(vec![stage; 2], &[1.0; 10], 3, &Progress::default()).is_none());
        assert!(Pipeline::new(vec![stage; 2], &[1.0; 10], 2, &Progress::default()).is_some());
        // Work that puts all but a row in one half leaves the other too short.
        let mut work = [1.0; 10];
        work[9] = 100.0;
        assert!(Pipeline::new(vec![stage; 2], &work, 2, &Progress::default()).is_none());
        // An `after_all` must name an earlier stage.
        let waiting = Stage {
            after_all: Some(1),
            ..stage
        };
        assert!(Pipeline::new(vec![stage, waiting], &[1.0; 10], 2, &Progress::default()).is_none());
    }

    #[test]
    fn a_panicking_part_makes_the_others_panic_instead_of_waiting() {
        let stage = Stage {
            items: 20,
            above: 1,
            below: 1,
            after_all: None,
        };
        let pipeline = Pipeline::new(vec![stage; 4], &[1.0; 20], 2, &Progress::default()).unwrap();
        let mut progress = Progress::default();
        progress.reset(2);
        let outcomes: Vec<bool> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..2)
                .map(|p| {
                    let (pipeline, progress) = (&pipeline, &progress);
                    scope.spawn(move || {
                        pipeline.run_part(p, progress, |s, _| assert!(!(p == 1 && s == 1)))
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().is_err()).collect()
        });
        assert_eq!(outcomes, [true, true]);
    }
}
