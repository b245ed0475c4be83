//! Deterministic parallel building blocks.
//!
//! Every pass either writes one output element per index (the same arithmetic on one thread or many), or
//! reduces in fixed-size chunks summed in chunk order, so results are bit-identical whatever the thread
//! count. Nothing is scatter-added with atomics.

use std::marker::PhantomData;

use rayon::prelude::*;

/// Chunk length of reductions; fixed so the summation order never depends on the thread count.
const REDUCTION_CHUNK: usize = 4096;

/// Sets `out[i] = value(i)` for every `i`, on rayon's pool when `parallel`.
pub(crate) fn fill<T, F>(out: &mut [T], parallel: bool, value: F)
where
    T: Send,
    F: Fn(usize) -> T + Sync + Send,
{
    if parallel {
        out.par_iter_mut()
            .enumerate()
            .for_each(|(i, o)| *o = value(i));
    } else {
        for (i, o) in out.iter_mut().enumerate() {
            *o = value(i);
        }
    }
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
/// Constraint batches come from a graph colouring in which no two constraints of one colour share a
/// particle, so the threads of one batch never touch the same element.
pub(crate) struct DisjointSlice<'a, T> {
    ptr: *mut T,
    len: usize,
    _borrow: PhantomData<&'a mut [T]>,
}

// SAFETY: access goes through `get`/`set`, whose callers guarantee that no index is touched by two threads
// at once (the colouring invariant, checked when the colouring is built).
unsafe impl<T: Send> Send for DisjointSlice<'_, T> {}
unsafe impl<T: Send> Sync for DisjointSlice<'_, T> {}

impl<'a, T: Copy> DisjointSlice<'a, T> {
    pub(crate) fn new(slice: &'a mut [T]) -> Self {
        DisjointSlice {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _borrow: PhantomData,
        }
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

    /// # Safety
    /// No other thread may read or write index `i` concurrently.
    #[inline]
    pub(crate) unsafe fn set(&self, i: usize, value: T) {
        assert!(i < self.len);
        // SAFETY: in bounds (checked above); exclusive by the caller's contract.
        unsafe { *self.ptr.add(i) = value }
    }
}
