//! Arrays of `f64` that each begin at an offset of their own within a 4 KiB page.
//!
//! The solver streams a dozen and more arrays of `f64` side by side, all indexed by particle: the
//! components of the positions, velocities, start positions and wind shares, and the inverse masses.
//! Each large array is a fresh allocation, which the system allocator maps page-aligned (plus its own
//! header, the same for every array), so element `i` of every array sat at the same offset within its
//! page: in the same set of the L1 data cache (64 sets of 64 B lines repeat every 4 KiB), and, for a
//! store to one array and a load from another, matching in the 12 address bits the core compares to
//! decide whether a load must wait for an earlier store ("4K aliasing"). A [`Staggered`] array starts
//! where a counter says instead: the `k`-th array at line `(k · 23) mod 64` of its page (23 is odd, so
//! 64 arrays in a row all start on different lines). Only where the data lies changes, never the
//! arithmetic, so the results are the same bits. Only
//! the split components (`components.rs`) are made this way: staggering the inverse masses and the
//! constraints' constants as well was measured and gained nothing more.

use std::ops::{Deref, DerefMut};
use std::sync::atomic::{AtomicUsize, Ordering};

const PAGE_BYTES: usize = 4096;
const LINE_BYTES: usize = 64;
const LINES_PER_PAGE: usize = PAGE_BYTES / LINE_BYTES;
/// Lines between the starts of consecutively made arrays (odd: coprime with the 64 lines of a page).
const LINE_STRIDE: usize = 23;
const F64_BYTES: usize = std::mem::size_of::<f64>();

/// Unused `f64` allocated after each array: one 4 KiB page, so that the end of one array and the start
/// of the next (which different threads may write) never share a page for the hardware prefetcher to
/// run on into (`components.rs`, where this was measured).
pub(crate) const GAP: usize = PAGE_BYTES / F64_BYTES;

/// Counts the arrays made so far, to give each the next starting line.
static ARRAYS_MADE: AtomicUsize = AtomicUsize::new(0);

/// An owned array of `f64` that starts on a line of its page chosen to differ from the arrays made just
/// before and after it (see the module documentation); it dereferences to its slice.
pub(crate) struct Staggered {
    /// Leading padding, then the elements, then (as spare capacity) [`GAP`] more.
    storage: Vec<f64>,
    /// Index of the first element in `storage`.
    start: usize,
}

/// The line of its page on which the `made`-th array starts.
fn line_of(made: usize) -> usize {
    made * LINE_STRIDE % LINES_PER_PAGE
}

/// The line of its page on which the next array starts.
fn next_line() -> usize {
    line_of(ARRAYS_MADE.fetch_add(1, Ordering::Relaxed))
}

impl Staggered {
    /// `n` zeros.
    pub(crate) fn zeros(n: usize) -> Staggered {
        Staggered::zeros_on(n, next_line())
    }

    /// `n` zeros starting on line `line` of their page.
    fn zeros_on(n: usize, line: usize) -> Staggered {
        let mut array = Staggered::empty_on(n, line);
        array.storage.resize(array.start + n, 0.0);
        array
    }

    /// A copy of `values`.
    pub(crate) fn copy_of(values: &[f64]) -> Staggered {
        Staggered::copy_on(values, next_line())
    }

    /// A copy of `values` starting on line `line` of its page.
    fn copy_on(values: &[f64], line: usize) -> Staggered {
        let mut array = Staggered::empty_on(values.len(), line);
        array.storage.resize(array.start, 0.0);
        array.storage.extend_from_slice(values);
        array
    }

    /// Unused `f64` of capacity after the elements.
    #[cfg(test)]
    pub(crate) fn spare_capacity(&self) -> usize {
        self.storage.capacity() - self.storage.len()
    }

    /// An empty array with room for the padding, `n` elements and the gap, its start on line `line`.
    fn empty_on(n: usize, line: usize) -> Staggered {
        let storage: Vec<f64> = Vec::with_capacity(PAGE_BYTES / F64_BYTES + n + GAP);
        let wanted = line * LINE_BYTES;
        let address = storage.as_ptr() as usize % PAGE_BYTES;
        // Both are multiples of 8 (the allocation is aligned for f64), so this is a whole count.
        let start = (wanted + PAGE_BYTES - address) % PAGE_BYTES / F64_BYTES;
        Staggered { storage, start }
    }
}

impl Deref for Staggered {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.storage[self.start..]
    }
}

impl DerefMut for Staggered {
    fn deref_mut(&mut self) -> &mut [f64] {
        &mut self.storage[self.start..]
    }
}

impl Clone for Staggered {
    /// A copy on a line of its own (a derived clone would copy the padding and lose the gap).
    fn clone(&self) -> Staggered {
        Staggered::copy_of(self)
    }
}

impl Default for Staggered {
    /// Empty, without allocating or taking a line (an empty array has nothing to place).
    fn default() -> Staggered {
        Staggered {
            storage: Vec::new(),
            start: 0,
        }
    }
}

impl std::fmt::Debug for Staggered {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every array starts on the line chosen for it, holds what it was given, keeps a page of spare
    /// capacity after it, and so do clones; 64 arrays made one after another get 64 different lines.
    #[test]
    fn each_array_starts_on_its_own_line() {
        let mut lines: Vec<usize> = (0..LINES_PER_PAGE).map(line_of).collect();
        lines.sort_unstable();
        lines.dedup();
        assert_eq!(lines.len(), LINES_PER_PAGE);

        // Whatever the allocator's alignment of each allocation, the first element lies on the line
        // chosen for it.
        let values: Vec<f64> = (0..40_000).map(|i| i as f64 * 0.5).collect();
        let arrays: Vec<(Staggered, usize)> = (0..8)
            .flat_map(|k| {
                let (copy, zeros) = (line_of(2 * k), line_of(2 * k + 1));
                [
                    (Staggered::copy_on(&values, copy), copy),
                    (Staggered::zeros_on(values.len(), zeros), zeros),
                ]
            })
            .collect();
        for (array, line) in &arrays {
            assert_eq!(array.as_ptr() as usize % PAGE_BYTES, line * LINE_BYTES);
        }
        let arrays: Vec<Staggered> = arrays.into_iter().map(|(array, _)| array).collect();
        // A clone starts on some line too (which one depends on the arrays other tests made meanwhile).
        let clone = arrays[0].clone();
        assert_eq!(clone.as_ptr() as usize % LINE_BYTES, 0);
        for array in arrays.iter().chain([&clone]) {
            assert_eq!(array.len(), values.len());
            assert!(array.spare_capacity() >= GAP);
        }
        assert_eq!(&arrays[0][..], &values[..]);
        assert_eq!(&arrays[0].clone()[..], &values[..]);
        assert!(arrays[1].iter().all(|&v| v == 0.0));
        assert!(Staggered::default().is_empty());
    }
}
