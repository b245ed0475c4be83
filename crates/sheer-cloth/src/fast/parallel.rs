//! Deterministic parallel building blocks.
//!
//! Every pass either writes one output element per index (the same arithmetic on one thread or many), or
//! reduces in fixed-size chunks summed in chunk order, so results are bit-identical whatever the thread
//! count. Nothing is scatter-added with atomics.
//!
//! Passes go to rayon's pool, or, inside [`TeamSlot::lead`], to a *team*: threads that belong to one
//! simulation and spin between passes. A small cloth's sub-step is eleven passes of a few microseconds
//! each; rayon's workers fall asleep between them and take longer to wake than a pass takes, while a
//! spinning team hands a pass over at the cost of a few cache-line transfers.

use std::cell::{Cell, UnsafeCell};
use std::marker::PhantomData;
use std::ops::Range;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::thread::{JoinHandle, Thread};

use rayon::prelude::*;

/// A pass over `0..len`, split into contiguous parts.
type Work<'a> = dyn Fn(Range<usize>) + Sync + 'a;

/// Spins before a waiting thread parks: 2048 `spin_loop` hints took 56 µs on the build machine (AMD
/// EPYC), far longer than a pass's hand-off and far shorter than the pause between two 60 Hz frames.
const SPINS_BEFORE_PARKING: u32 = 1 << 11;

/// The state a team's threads share.
struct Team {
    threads: usize,
    /// Bumped by the leader for every pass it hands out.
    generation: AtomicUsize,
    /// Helpers that have finished the current pass.
    finished: AtomicUsize,
    /// Whether the passes of the current [`TeamSlot::lead`] are claimed chunk by chunk (see
    /// [`Team::run`]); read and written by the leader only.
    claim: AtomicBool,
    /// A claimed pass: the next unclaimed index.
    next: AtomicUsize,
    stop: AtomicBool,
    helper_panicked: AtomicBool,
    /// Helpers parked (or about to park) waiting for a pass, and whether the leader is parked waiting
    /// for the helpers: whoever changes what the other waits for wakes it when this is non-zero.
    parked_helpers: AtomicUsize,
    parked_leader: AtomicUsize,
    /// The thread leading the current [`TeamSlot::lead`].
    leader: Mutex<Option<Thread>>,
    helpers: OnceLock<Vec<Thread>>,
    /// The current pass: written by the leader before it bumps `generation`, read by the helpers after
    /// they see the bump, and not rewritten before every helper has finished with it.
    pass: UnsafeCell<Pass>,
}

/// A pass as the leader hands it out: the work, its length and, for a long pass, the chunk that threads
/// claim one at a time (0 for a short pass, split into one part per thread).
#[derive(Clone, Copy)]
struct Pass {
    work: *const Work<'static>,
    len: usize,
    chunk: usize,
}

// SAFETY: `pass` is written only by the leader while no helper reads it (see the field's comment), and
// the closure it points to is `Sync`; the rest is atomics and locks.
unsafe impl Sync for Team {}
// SAFETY: as for `Sync`: the team's state is atomics, locks and the leader-owned `pass`.
unsafe impl Send for Team {}

thread_local! {
    /// The team this thread leads, if any.
    static LEADING: Cell<*const Team> = const { Cell::new(std::ptr::null()) };
}

/// Part `index` of `count` equal contiguous parts of `0..len`.
fn part(len: usize, count: usize, index: usize) -> Range<usize> {
    len * index / count..len * (index + 1) / count
}

/// Waits until `ready()` holds: spinning first (the next pass is normally microseconds away), then
/// parked, counted in `parked` so that the thread that makes `ready()` true unparks it.
fn wait_until(ready: impl Fn() -> bool, parked: &AtomicUsize) {
    for _ in 0..SPINS_BEFORE_PARKING {
        if ready() {
            return;
        }
        std::hint::spin_loop();
    }
    loop {
        // Sequentially consistent with the waker's store-then-load, so that either this check sees the
        // change or the waker sees `parked` and unparks (a token that `park` then consumes).
        parked.fetch_add(1, Ordering::SeqCst);
        let done = ready();
        if !done {
            std::thread::park();
        }
        parked.fetch_sub(1, Ordering::SeqCst);
        if done || ready() {
            return;
        }
    }
}

impl Team {
    fn helper(&self, index: usize) {
        let mut seen = 0;
        loop {
            wait_until(
                || {
                    self.generation.load(Ordering::SeqCst) != seen
                        || self.stop.load(Ordering::SeqCst)
                },
                &self.parked_helpers,
            );
            if self.stop.load(Ordering::SeqCst) {
                return;
            }
            seen = self.generation.load(Ordering::SeqCst);
            // SAFETY: the leader wrote the pass before bumping `generation` (seen above) and keeps it,
            // and the closure it points to alive, until every helper reports.
            let pass = unsafe { *self.pass.get() };
            // SAFETY: as above, `work` is alive.
            if catch_unwind(AssertUnwindSafe(|| self.work_on(pass, index))).is_err() {
                self.helper_panicked.store(true, Ordering::SeqCst);
            }
            self.finished.fetch_add(1, Ordering::SeqCst);
            if self.parked_leader.load(Ordering::SeqCst) > 0
                && let Some(leader) = &*self.leader.lock().unwrap_or_else(|e| e.into_inner())
            {
                leader.unpark();
            }
        }
    }

    /// Thread `index`'s share of `pass`: its own part of a short pass, chunks claimed until none is left
    /// of a long one.
    fn work_on(&self, pass: Pass, index: usize) {
        if pass.chunk == 0 {
            let range = part(pass.len, self.threads, index);
            if !range.is_empty() {
                // SAFETY: the leader keeps `work` alive until every thread has finished the pass.
                unsafe { (*pass.work)(range) }
            }
            return;
        }
        loop {
            let start = self.next.fetch_add(pass.chunk, Ordering::Relaxed);
            if start >= pass.len {
                return;
            }
            // SAFETY: the leader keeps `work` alive until every thread has finished the pass.
            unsafe { (*pass.work)(start..(start + pass.chunk).min(pass.len)) }
        }
    }

    /// Runs `work` over `0..len` with every thread of the team and returns when all parts are done.
    ///
    /// A small cloth's pass is split into one equal part per thread, so that each thread keeps working
    /// on the same particles, in its own core's cache, pass after pass. A large cloth's pass (see
    /// [`TeamSlot::lead`]) is claimed in chunks of `grain` instead: its data outgrows the caches
    /// anyway, and on a shared machine one core may run slower than the other, which equal parts would
    /// wait for.
    fn run(&self, len: usize, grain: usize, work: &Work<'_>) {
        let chunk = if self.claim.load(Ordering::Relaxed) {
            grain.max(1)
        } else {
            0
        };
        self.run_chunked(len, chunk, work);
    }

    /// Runs `work` over `0..len` with every thread of the team, claimed in chunks of `chunk`, or with
    /// `chunk` 0 in one equal part per thread, and returns when all parts are done.
    fn run_chunked(&self, len: usize, chunk: usize, work: &Work<'_>) {
        // SAFETY: only the lifetime is erased; `work` outlives the pass because this function waits for
        // every helper to finish it before returning (also when the leader's own part panics).
        let work: *const Work<'static> = unsafe { std::mem::transmute(work as *const Work<'_>) };
        // SAFETY: every helper has finished the previous pass (waited for below), so none reads `pass`.
        unsafe { *self.pass.get() = Pass { work, len, chunk } };
        self.next.store(0, Ordering::SeqCst);
        self.finished.store(0, Ordering::SeqCst);
        self.generation.fetch_add(1, Ordering::SeqCst);
        if self.parked_helpers.load(Ordering::SeqCst) > 0 {
            self.helpers
                .get()
                .into_iter()
                .flatten()
                .for_each(Thread::unpark);
        }
        let leader = catch_unwind(AssertUnwindSafe(|| {
            self.work_on(Pass { work, len, chunk }, 0)
        }));
        wait_until(
            || self.finished.load(Ordering::SeqCst) == self.threads - 1,
            &self.parked_leader,
        );
        if let Err(panic) = leader {
            std::panic::resume_unwind(panic);
        }
        assert!(
            !self.helper_panicked.swap(false, Ordering::SeqCst),
            "a solver thread panicked"
        );
    }
}

/// A simulation's team: `threads − 1` helper threads that live as long as it does (so that the
/// scheduler settles them on their own cores once), parked while it is not stepping.
#[derive(Default)]
pub(crate) struct TeamSlot {
    team: Option<(Arc<Team>, Vec<JoinHandle<()>>)>,
}

impl Clone for TeamSlot {
    /// A clone starts its own team when it first needs one.
    fn clone(&self) -> Self {
        TeamSlot::default()
    }
}

impl std::fmt::Debug for TeamSlot {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let threads = self.team.as_ref().map_or(1, |(team, _)| team.threads);
        write!(f, "TeamSlot {{ threads: {threads} }}")
    }
}

impl Drop for TeamSlot {
    fn drop(&mut self) {
        if let Some((team, helpers)) = self.team.take() {
            team.stop.store(true, Ordering::SeqCst);
            for helper in helpers {
                helper.thread().unpark();
                // A helper that panicked outside a pass has nothing left to report.
                let _ = helper.join();
            }
        }
    }
}

impl TeamSlot {
    /// Runs `body` leading a team of `threads` threads (this one and `threads − 1` helpers, started
    /// when the count first differs from the last team's), which serves the [`parts`] passes `body`
    /// makes on this thread: claimed chunk by chunk when `claim`, in equal parts otherwise (see
    /// [`Team::run`]). With fewer than two threads, or when the helpers cannot be started, `body` runs
    /// with rayon as before.
    pub(crate) fn lead<R>(&mut self, threads: usize, claim: bool, body: impl FnOnce() -> R) -> R {
        if threads < 2 || !LEADING.get().is_null() {
            return body();
        }
        if self.team.as_ref().map(|(team, _)| team.threads) != Some(threads) {
            *self = TeamSlot::default();
            self.team = start_team(threads);
        }
        let Some((team, _)) = &self.team else {
            return body();
        };
        *team.leader.lock().unwrap_or_else(|e| e.into_inner()) = Some(std::thread::current());
        team.claim.store(claim, Ordering::Relaxed);
        /// Stops leading however `body` ends.
        struct Resign;
        impl Drop for Resign {
            fn drop(&mut self) {
                LEADING.set(std::ptr::null());
            }
        }
        LEADING.set(Arc::as_ptr(team));
        let _resign = Resign;
        body()
    }
}

/// Starts the helpers of a team of `threads`; `None` if the system refuses a thread.
fn start_team(threads: usize) -> Option<(Arc<Team>, Vec<JoinHandle<()>>)> {
    let team = Arc::new(Team {
        threads,
        generation: AtomicUsize::new(0),
        finished: AtomicUsize::new(0),
        claim: AtomicBool::new(false),
        next: AtomicUsize::new(0),
        stop: AtomicBool::new(false),
        helper_panicked: AtomicBool::new(false),
        parked_helpers: AtomicUsize::new(0),
        parked_leader: AtomicUsize::new(0),
        leader: Mutex::new(None),
        helpers: OnceLock::new(),
        pass: UnsafeCell::new(Pass {
            work: std::ptr::null::<fn(Range<usize>)>() as *const Work<'static>,
            len: 0,
            chunk: 0,
        }),
    });
    let mut handles = Vec::with_capacity(threads - 1);
    for index in 1..threads {
        let helper = Arc::clone(&team);
        match std::thread::Builder::new()
            .name(format!("sheer-cloth team {index}"))
            .spawn(move || helper.helper(index))
        {
            Ok(handle) => handles.push(handle),
            Err(_) => {
                team.stop.store(true, Ordering::SeqCst);
                for handle in handles {
                    handle.thread().unpark();
                    let _ = handle.join();
                }
                return None;
            }
        }
    }
    let _ = team
        .helpers
        .set(handles.iter().map(|h| h.thread().clone()).collect());
    Some((team, handles))
}

/// `f` of the team this thread leads, `None` without one.
fn with_leading_team<R>(f: impl FnOnce(&Team) -> R) -> Option<R> {
    // SAFETY: `LEADING` points at a live team while `TeamSlot::lead` runs its body on this thread, and
    // the reference does not outlive this call.
    let team = unsafe { LEADING.get().as_ref() }?;
    Some(f(team))
}

/// The number of threads of the team this thread leads, when the team splits its passes into equal
/// parts ([`Team::run`]): then a pass over `0..threads` gives each thread one index, and all of them run
/// at once. `None` without a team, or when its passes are claimed chunk by chunk.
pub(crate) fn team_in_equal_parts() -> Option<usize> {
    with_leading_team(|team| (!team.claim.load(Ordering::Relaxed)).then_some(team.threads))
        .flatten()
}

/// The number of threads of the team this thread leads, however it splits its passes: a pass over
/// `0..threads` runs every index at once, on a thread of its own, in equal parts; claimed index by
/// index, a thread that has finished its index claims one nobody has yet, so an index that waits for
/// another never waits for one left unclaimed. `None` without a team.
pub(crate) fn team_threads() -> Option<usize> {
    with_leading_team(|team| team.threads)
}

/// Runs `work(i)` for every `i` of `0..threads` on the team this thread leads, which must have
/// `threads` threads: index `i` on the team's thread `i`, all at once, also when the team claims its
/// passes. For passes whose indices wait for each other and keep to their own rows from pass to pass
/// (two opposed parts: `Wavefront::run_opposed_part`).
pub(crate) fn one_index_per_thread(threads: usize, work: impl Fn(usize) + Sync) {
    let each = |range: Range<usize>| range.for_each(&work);
    with_leading_team(|team| {
        assert_eq!(team.threads, threads, "one index per thread of the team");
        team.run_chunked(threads, 0, &each);
    })
    .expect("one index per thread needs a team");
}

/// Runs `work` on parts of `0..len` that together cover it once: on the team this thread leads (see
/// [`Team::run`] for how it splits a pass; whatever `grain`, since a team's hand-off costs less than any
/// pass), else on rayon's pool when `parallel` (parts of `grain` indices), else in one call. Callers must
/// give the same result however `0..len` is split, which holds when each index is independent of the
/// others.
pub(crate) fn parts(len: usize, parallel: bool, grain: usize, work: impl Fn(Range<usize>) + Sync) {
    let on_team = parallel
        && with_leading_team(|team| {
            if len >= team.threads {
                team.run(len, grain, &work);
            } else {
                work(0..len);
            }
        })
        .is_some();
    if on_team {
        return;
    }
    if !parallel || len <= grain {
        work(0..len);
        return;
    }
    (0..len.div_ceil(grain))
        .into_par_iter()
        .for_each(|task| work(task * grain..((task + 1) * grain).min(len)));
}

/// Chunk length of reductions; fixed so the summation order never depends on the thread count.
const REDUCTION_CHUNK: usize = 4096;

/// Sets `out[i] = value(i)` for every `i`, on rayon's pool when `parallel`.
pub(crate) fn fill<T, F>(out: &mut [T], parallel: bool, value: F)
where
    T: Send + Copy,
    F: Fn(usize) -> T + Sync + Send,
{
    let out = DisjointSlice::new(out);
    parts(out.len, parallel, 1024, |range| {
        // SAFETY: the parts are disjoint.
        let out = unsafe { out.slice_mut(range.clone()) };
        for (o, i) in out.iter_mut().zip(range) {
            *o = value(i);
        }
    });
}

/// The smallest `i < len` for which `test(i)` holds, if any (the same whatever the split); the plain
/// search that [`first_index_screened`] narrows down.
#[cfg(test)]
pub(crate) fn first_index(
    len: usize,
    parallel: bool,
    test: impl Fn(usize) -> bool + Sync,
) -> Option<usize> {
    let first = AtomicUsize::new(usize::MAX);
    parts(len, parallel, 4096, |range| {
        if let Some(i) = range.into_iter().find(|&i| test(i)) {
            first.fetch_min(i, Ordering::Relaxed);
        }
    });
    Some(first.into_inner()).filter(|&i| i != usize::MAX)
}

/// Indices per block of [`first_index_screened`].
const SCREEN_BLOCK: usize = 256;

/// The smallest `i < len` for which `test(i)` holds, as the tests' plain search `first_index` finds
/// it, with `test` run only inside blocks of indices that `screen` flags. `screen(block)` must hold for
/// every block that contains an index passing `test`; it is meant to be a loop without early exits,
/// which vectorises where `test`'s search (which stops at the first hit) does not.
pub(crate) fn first_index_screened(
    len: usize,
    parallel: bool,
    screen: impl Fn(Range<usize>) -> bool + Sync,
    test: impl Fn(usize) -> bool + Sync,
) -> Option<usize> {
    let first = AtomicUsize::new(usize::MAX);
    parts(len, parallel, 4096, |range| {
        let mut start = range.start;
        while start < range.end {
            let block = start..(start + SCREEN_BLOCK).min(range.end);
            start = block.end;
            if screen(block.clone())
                && let Some(i) = block.into_iter().find(|&i| test(i))
            {
                first.fetch_min(i, Ordering::Relaxed);
                return;
            }
        }
    });
    Some(first.into_inner()).filter(|&i| i != usize::MAX)
}

/// `Σ term(i)` for `i < len`, summed in fixed chunks so the result is independent of the thread count.
pub(crate) fn sum<F>(len: usize, parallel: bool, term: F) -> f64
where
    F: Fn(usize) -> f64 + Sync + Send,
{
    let chunk_sum = |chunk: usize| {
        let start = chunk * REDUCTION_CHUNK;
        let end = (start + REDUCTION_CHUNK).min(len);
        (start..end).map(&term).sum::<f64>()
    };
    let chunks = len.div_ceil(REDUCTION_CHUNK);
    if parallel && chunks > 1 {
        let partial: Vec<f64> = (0..chunks).into_par_iter().map(chunk_sum).collect();
        partial.into_iter().sum()
    } else {
        (0..chunks).map(chunk_sum).sum()
    }
}

/// A slice that several threads write at disjoint indices.
///
/// The threads of one pass own disjoint rows or parts of the cloth, and the constraints of one strip
/// batch share no particle, so no two threads touch the same element.
pub(crate) struct DisjointSlice<'a, T> {
    ptr: *mut T,
    len: usize,
    _borrow: PhantomData<&'a mut [T]>,
}

// SAFETY: access goes through `get`/`set`, whose callers guarantee that no index is touched by two threads
// at once (each pass's partition of the rows or particles, and each batch's constraints sharing no particle).
unsafe impl<T: Send> Send for DisjointSlice<'_, T> {}
// SAFETY: as for `Send`: shared access is only through `get`/`set` on indices no other thread touches.
unsafe impl<T: Send> Sync for DisjointSlice<'_, T> {}

impl<'a, T: Copy> DisjointSlice<'a, T> {
    pub(crate) fn new(slice: &'a mut [T]) -> Self {
        DisjointSlice {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _borrow: PhantomData,
        }
    }

    /// The first element, for a caller that indexes the slice itself (see [`len`](Self::len)).
    pub(crate) fn as_mut_ptr(&self) -> *mut T {
        self.ptr
    }

    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// # Safety
    /// No other thread may write index `i` concurrently.
    #[inline]
    pub(crate) unsafe fn get(&self, i: usize) -> T {
        assert!(i < self.len);
        // SAFETY: in bounds (checked above); no concurrent writer by the caller's contract.
        unsafe { *self.ptr.add(i) }
    }

    /// The elements in `range` as a mutable slice.
    ///
    /// # Safety
    /// No other thread may touch an index of `range` while the slice lives, and no other live slice or
    /// `get`/`set` of this thread may overlap it.
    #[inline]
    #[allow(clippy::mut_from_ref)]
    pub(crate) unsafe fn slice_mut(&self, range: std::ops::Range<usize>) -> &mut [T] {
        assert!(range.start <= range.end && range.end <= self.len);
        // SAFETY: in bounds (checked above); exclusive by the caller's contract.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.len()) }
    }

    /// The elements in `range` as a shared slice.
    ///
    /// # Safety
    /// No thread may write an index of `range` while the slice lives.
    #[inline]
    pub(crate) unsafe fn slice(&self, range: std::ops::Range<usize>) -> &[T] {
        assert!(range.start <= range.end && range.end <= self.len);
        // SAFETY: in bounds (checked above); unwritten by the caller's contract.
        unsafe { std::slice::from_raw_parts(self.ptr.add(range.start), range.len()) }
    }

    /// # Safety
    /// No other thread may read or write index `i` concurrently.
    #[inline]
    pub(crate) unsafe fn set(&self, i: usize, value: T) {
        assert!(i < self.len);
        // SAFETY: in bounds (checked above); exclusive by the caller's contract.
        unsafe { *self.ptr.add(i) = value }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    /// Which threads ran which indices of one pass.
    fn run_pass(
        slot: &mut TeamSlot,
        threads: usize,
        len: usize,
        claim: bool,
    ) -> (Vec<usize>, usize) {
        let hits: Vec<AtomicUsize> = (0..len).map(|_| AtomicUsize::new(0)).collect();
        let runners = Mutex::new(HashSet::new());
        slot.lead(threads, claim, || {
            parts(len, true, 3, |range| {
                runners.lock().unwrap().insert(std::thread::current().id());
                for i in range {
                    hits[i].fetch_add(1, Ordering::Relaxed);
                }
            })
        });
        let hits = hits.into_iter().map(AtomicUsize::into_inner).collect();
        (hits, runners.into_inner().unwrap().len())
    }

    #[test]
    fn a_team_covers_every_index_once_on_all_its_threads() {
        let mut slot = TeamSlot::default();
        for threads in [2, 3, 4] {
            // Whatever the grain (3 here), the team splits even a pass shorter than it.
            for len in [threads, 7, 1000] {
                for _ in 0..3 {
                    let (hits, runners) = run_pass(&mut slot, threads, len, false);
                    assert!(hits.iter().all(|&h| h == 1), "{threads} threads, {len}");
                    assert_eq!(runners, threads, "{threads} threads, {len}");
                    // Claimed chunk by chunk: which thread takes which chunk varies, but every index is
                    // taken once.
                    let (hits, _) = run_pass(&mut slot, threads, len, true);
                    assert!(
                        hits.iter().all(|&h| h == 1),
                        "{threads} threads, {len}, claimed"
                    );
                }
            }
        }
        // Shorter than the team: one call on the leader.
        let (hits, runners) = run_pass(&mut slot, 4, 3, false);
        assert_eq!((hits, runners), (vec![1, 1, 1], 1));
        // A clone starts with no team of its own and still works.
        let mut clone = slot.clone();
        assert_eq!(run_pass(&mut clone, 2, 10, false).1, 2);
    }

    #[test]
    fn a_panicking_part_reaches_the_leader_instead_of_hanging_the_team() {
        let mut slot = TeamSlot::default();
        for bad in [0, 99] {
            // Index 0 lies in the leader's part, 99 in the helper's.
            let outcome = catch_unwind(AssertUnwindSafe(|| {
                slot.lead(2, false, || {
                    parts(100, true, 1, |range| assert!(!range.contains(&bad)));
                })
            }));
            assert!(outcome.is_err(), "part with index {bad}");
            // The team is left usable.
            let (hits, runners) = run_pass(&mut slot, 2, 50, false);
            assert!(hits.iter().all(|&h| h == 1));
            assert_eq!(runners, 2);
        }
    }

    #[test]
    fn first_index_is_the_same_on_a_team_and_on_one_thread() {
        let test = |i: usize| i % 97 == 96 || i == 5000;
        let serial = first_index(10_000, false, test);
        assert_eq!(serial, Some(96));
        let mut slot = TeamSlot::default();
        assert_eq!(
            slot.lead(2, false, || first_index(10_000, true, test)),
            serial
        );
        assert_eq!(
            slot.lead(3, true, || first_index(10_000, true, |i| i == 9_999)),
            Some(9_999)
        );
        assert_eq!(
            slot.lead(2, true, || first_index(10_000, true, |_| false)),
            None
        );
    }

    #[test]
    fn a_screened_search_finds_what_the_plain_one_finds() {
        let hits = [96, 97, 255, 256, 5000, 9_999];
        for len in [0, 1, 255, 256, 257, 10_000] {
            for &hit in &hits {
                let test = |i: usize| i == hit || i == 7_777;
                // The exact screen, and one that flags every block.
                let screen = |block: Range<usize>| block.into_iter().any(test);
                let expected = first_index(len, false, test);
                assert_eq!(first_index_screened(len, false, screen, test), expected);
                assert_eq!(first_index_screened(len, false, |_| true, test), expected);
                let mut slot = TeamSlot::default();
                for claim in [false, true] {
                    let found =
                        slot.lead(2, claim, || first_index_screened(len, true, screen, test));
                    assert_eq!(found, expected, "{len} {hit} {claim}");
                }
            }
        }
        // A screen that misses a block hides the hit there: the screen decides where to look.
        assert_eq!(
            first_index_screened(1000, false, |b| b.start != 0, |i| i == 3 || i == 600),
            Some(600)
        );
    }
}
