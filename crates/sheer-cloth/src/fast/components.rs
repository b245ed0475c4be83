//! Vectors split by component: x, y and z of every particle in three arrays of `f64`.
//!
//! The position-based solvers keep their state this way during a step (`Simulation::step` splits the
//! positions and velocities at its start and joins them at its end). A loop over consecutive particles
//! then reads and writes each component with plain vector loads and stores; over `DVec3` (24 bytes, three
//! to a vector lane's 8) it had to transpose every group of eight particles with permutes in and out,
//! which were a third of the vector operations of the constraint loops and the wind pass and nearly all
//! of the force sums (`perf annotate` of `fingerprint time 64x46 1 1500`). The arithmetic is the same
//! operation for operation, so the results are the same bits.

use std::ops::Range;

use glam::DVec3;

use crate::fast::parallel::DisjointSlice;
use crate::fast::staggered::Staggered;
use crate::fast::vectorise::by_cpu;

/// Owned vectors split by component, each a [`Staggered`] array: it starts on a line of its page of its
/// own and is followed by a page of unused capacity ([`GAP`](crate::fast::staggered::GAP)).
///
/// The gap: allocated one after another, the components lay end to start: the last rows of a grid's x
/// (which the last thread of a team works on) shared cache lines and a page with the first rows of its
/// y (the first thread's), and so on. A thread reading its rows there, with the hardware prefetcher
/// running on within the page, took lines the other thread was writing, every sub-step. With the time
/// of each row's items counted by `rdtsc` (a temporary instrumentation of the pipeline, `fingerprint
/// time 64x46 2 1000`, five runs), the first three rows took 1.3–4.1× as long as the rows below them
/// and the last two 1.15–1.6×; with the gap, as long as the rest. The frame: 0.95× as long (median of
/// 30 interleaved runs of `fingerprint time 64x46 2 200`, quartiles 0.91 and 1.01).
#[derive(Clone, Debug, Default)]
pub(crate) struct Xyz {
    pub x: Staggered,
    pub y: Staggered,
    pub z: Staggered,
}

impl Xyz {
    /// `n` zero vectors.
    pub(crate) fn zeros(n: usize) -> Xyz {
        Xyz {
            x: Staggered::zeros(n),
            y: Staggered::zeros(n),
            z: Staggered::zeros(n),
        }
    }

    /// The vectors of `vectors`, split.
    #[cfg(test)]
    pub(crate) fn of(vectors: &[DVec3]) -> Xyz {
        let mut split = Xyz::zeros(vectors.len());
        split.split_from(vectors);
        split
    }

    pub(crate) fn len(&self) -> usize {
        self.x.len()
    }

    /// Overwrites these vectors with `vectors` (the same count).
    pub(crate) fn split_from(&mut self, vectors: &[DVec3]) {
        split(vectors, &mut self.x, &mut self.y, &mut self.z);
    }

    /// Writes these vectors into `vectors` (the same count).
    pub(crate) fn join_into(&self, vectors: &mut [DVec3]) {
        join(&self.x, &self.y, &self.z, vectors);
    }

    /// The vectors joined.
    #[cfg(test)]
    pub(crate) fn to_vec3s(&self) -> Vec<DVec3> {
        let mut joined = vec![DVec3::ZERO; self.len()];
        self.join_into(&mut joined);
        joined
    }

    pub(crate) fn set(&mut self, i: usize, v: DVec3) {
        (self.x[i], self.y[i], self.z[i]) = (v.x, v.y, v.z);
    }

    pub(crate) fn as_ref(&self) -> XyzRef<'_> {
        XyzRef {
            x: &self.x,
            y: &self.y,
            z: &self.z,
        }
    }

    #[cfg(test)]
    pub(crate) fn as_mut(&mut self) -> XyzMut<'_> {
        XyzMut {
            x: &mut self.x,
            y: &mut self.y,
            z: &mut self.z,
        }
    }

    /// For passes that share the particles among threads.
    pub(crate) fn disjoint(&mut self) -> DisjointXyz<'_> {
        DisjointXyz {
            x: DisjointSlice::new(&mut self.x),
            y: DisjointSlice::new(&mut self.y),
            z: DisjointSlice::new(&mut self.z),
        }
    }
}

by_cpu! {
    /// `vectors` into its components (each at least as long).
    fn split(vectors: &[DVec3], x: &mut [f64], y: &mut [f64], z: &mut [f64]) {
        let n = vectors.len();
        let (x, y, z) = (&mut x[..n], &mut y[..n], &mut z[..n]);
        for (i, v) in vectors.iter().enumerate() {
            (x[i], y[i], z[i]) = (v.x, v.y, v.z);
        }
    }
}

by_cpu! {
    /// Components (each at least as long as `vectors`) into `vectors`.
    fn join(x: &[f64], y: &[f64], z: &[f64], vectors: &mut [DVec3]) {
        let n = vectors.len();
        let (x, y, z) = (&x[..n], &y[..n], &z[..n]);
        for (i, v) in vectors.iter_mut().enumerate() {
            *v = DVec3::new(x[i], y[i], z[i]);
        }
    }
}

/// Borrowed vectors split by component, all three of one length.
#[derive(Clone, Copy, Debug)]
pub(crate) struct XyzRef<'a> {
    pub x: &'a [f64],
    pub y: &'a [f64],
    pub z: &'a [f64],
}

impl<'a> XyzRef<'a> {
    #[inline]
    pub(crate) fn len(self) -> usize {
        self.x.len()
    }

    #[inline(always)]
    pub(crate) fn range(self, range: Range<usize>) -> XyzRef<'a> {
        XyzRef {
            x: &self.x[range.clone()],
            y: &self.y[range.clone()],
            z: &self.z[range],
        }
    }

    #[inline(always)]
    pub(crate) fn at(self, i: usize) -> DVec3 {
        DVec3::new(self.x[i], self.y[i], self.z[i])
    }
}

/// Mutably borrowed vectors split by component, all three of one length.
#[derive(Debug)]
pub(crate) struct XyzMut<'a> {
    pub x: &'a mut [f64],
    pub y: &'a mut [f64],
    pub z: &'a mut [f64],
}

impl<'a> XyzMut<'a> {
    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.x.len()
    }

    /// The first `mid` vectors and the rest.
    #[cfg(test)]
    pub(crate) fn split_at_mut(self, mid: usize) -> (XyzMut<'a>, XyzMut<'a>) {
        let (x, x_rest) = self.x.split_at_mut(mid);
        let (y, y_rest) = self.y.split_at_mut(mid);
        let (z, z_rest) = self.z.split_at_mut(mid);
        (
            XyzMut { x, y, z },
            XyzMut {
                x: x_rest,
                y: y_rest,
                z: z_rest,
            },
        )
    }
}

/// [`DisjointSlice`] of each component: shared among threads that touch disjoint particles.
pub(crate) struct DisjointXyz<'a> {
    x: DisjointSlice<'a, f64>,
    y: DisjointSlice<'a, f64>,
    z: DisjointSlice<'a, f64>,
}

impl DisjointXyz<'_> {
    /// The first element of each component, and how many there are, for a caller that indexes them
    /// itself.
    pub(crate) fn pointers(&self) -> ([*mut f64; 3], usize) {
        (
            [
                self.x.as_mut_ptr(),
                self.y.as_mut_ptr(),
                self.z.as_mut_ptr(),
            ],
            self.x.len(),
        )
    }

    /// # Safety
    /// No other thread may write particle `i` concurrently.
    #[inline]
    pub(crate) unsafe fn get(&self, i: usize) -> DVec3 {
        // SAFETY: by the caller's contract.
        unsafe { DVec3::new(self.x.get(i), self.y.get(i), self.z.get(i)) }
    }

    /// # Safety
    /// No other thread may read or write particle `i` concurrently.
    #[inline]
    pub(crate) unsafe fn set(&self, i: usize, v: DVec3) {
        // SAFETY: by the caller's contract.
        unsafe {
            self.x.set(i, v.x);
            self.y.set(i, v.y);
            self.z.set(i, v.z);
        }
    }

    /// # Safety
    /// As [`DisjointSlice::slice`], for the particles of `range`.
    #[inline]
    pub(crate) unsafe fn slice(&self, range: Range<usize>) -> XyzRef<'_> {
        // SAFETY: by the caller's contract.
        unsafe {
            XyzRef {
                x: self.x.slice(range.clone()),
                y: self.y.slice(range.clone()),
                z: self.z.slice(range),
            }
        }
    }

    /// # Safety
    /// As [`DisjointSlice::slice_mut`], for the particles of `range`.
    #[inline]
    #[allow(clippy::mut_from_ref)]
    pub(crate) unsafe fn slice_mut(&self, range: Range<usize>) -> XyzMut<'_> {
        // SAFETY: by the caller's contract.
        unsafe {
            XyzMut {
                x: self.x.slice_mut(range.clone()),
                y: self.y.slice_mut(range.clone()),
                z: self.z.slice_mut(range),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each component keeps a page of unused capacity after it, new or cloned, so that no two
    /// components share a page end to start.
    #[test]
    fn every_component_is_followed_by_a_gap() {
        let state = Xyz::zeros(2944);
        for copy in [&state, &state.clone()] {
            for component in [&copy.x, &copy.y, &copy.z] {
                assert_eq!(component.len(), 2944);
                assert!(component.spare_capacity() >= crate::fast::staggered::GAP);
            }
        }
        let vectors: Vec<DVec3> = (0..5).map(|i| DVec3::splat(i as f64)).collect();
        let mut split = Xyz::zeros(5);
        split.split_from(&vectors);
        assert_eq!(split.clone().to_vec3s(), vectors);
    }
}
