//! The distance constraints of a grid cloth in row strips, projected by vectorised loops.
//!
//! A general mesh's constraints come in colour batches found by a greedy colouring, and each is projected
//! on its own: two particles gathered from anywhere, one square root, one division. That scalar loop is
//! most of a small-steps XPBD sub-step. On a grid the same constraints fall into twelve batches of
//! *strips*, runs of constraints whose ends sit at consecutive particle indices:
//!
//! - **apart** strips join a run of particles to another run further on (`a + k` to `b + k`): vertical
//!   stretch and bending, the two shear diagonals, all one row (pair) at a time;
//! - **along** strips join particles within one row: stretch `(2m, 2m + 1)` and bending
//!   `(4m + j, 4m + j + 2)`, `j ∈ {0, 1}`; with AVX-512 they go eight at a time through explicit
//!   permutes (`strips_avx512.rs`), where the vectoriser would gather and scatter.
//!
//! Within a batch no two constraints share a particle, so the order inside it does not matter and the
//! compiler may vectorise each strip ([`by_cpu!`]); the threads may share the strips with the same
//! result. Batches run bending first, then shear, then stretch, so that each sweep ends on the stiffest
//! family. The projection of one constraint is [`crate::solver::project`], the plain code's.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::DVec3;

use crate::fast::components::{DisjointXyz, XyzMut, XyzRef};
use crate::fast::parallel::{DisjointSlice, parts};
use crate::fast::vectorise::by_cpu;
use crate::model::{GridShape, Spring, SpringKind};
use crate::sim::{family_index, may_exceed_strain};
use crate::solver::{FamilyConstants, project};

/// How a strip's constraints sit in the particle array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Layout {
    /// Constraint `k` joins `a + k` and `b + k`, with `b ≥ a + count` (the two runs do not overlap).
    Apart { b: usize },
    /// Constraint `m·half + j` joins `a + 2m·half + j` and `a + 2m·half + j + half` (`j < half`).
    Along { half: usize },
}

/// A run of constraints of one family.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Strip {
    /// Index of the strip's first constraint in [`GridConstraints::springs`].
    pub first: usize,
    pub count: usize,
    /// First particle.
    pub a: usize,
    pub layout: Layout,
    /// The family of all its constraints (kept here so that the solver need not read a spring for it).
    pub kind: SpringKind,
}

impl Strip {
    /// The particles the strip touches, as index ranges (one for an along strip, two for an apart one).
    pub fn particle_ranges(&self) -> [Range<usize>; 2] {
        match self.layout {
            Layout::Apart { b } => [self.a..self.a + self.count, b..b + self.count],
            Layout::Along { .. } => [self.a..self.a + 2 * self.count, 0..0],
        }
    }

    /// Particle indices of constraint `k` of the strip.
    pub fn ends(&self, k: usize) -> (usize, usize) {
        match self.layout {
            Layout::Apart { b } => (self.a + k, b + k),
            Layout::Along { half } => {
                let (m, j) = (k / half, k % half);
                let a = self.a + 2 * m * half + j;
                (a, a + half)
            }
        }
    }
}

/// A grid cloth's constraints in strips and batches, with the per-constraint data the solver streams.
#[derive(Clone, Debug, Default)]
pub(crate) struct GridConstraints {
    /// The springs in strip order; the constants below are built from them.
    pub springs: Vec<Spring>,
    pub strips: Vec<Strip>,
    /// Ranges of `strips`; the constraints of one batch share no particle.
    pub batches: Vec<Range<usize>>,
    /// Per constraint, in strip order: rest length (m), the inverted divisor of the update (see
    /// `PackedConstraint::inverse_denominator`), and the XPBD multiplier.
    pub rest_lengths: Vec<f64>,
    pub inverse_denominators: Vec<f64>,
    pub lambdas: Vec<f64>,
    /// Per batch: its strips by the last particle row they touch, `by_last_row[batch].0[r]` (a range of
    /// `strips`), and how many rows each of them spans beyond its first (`.1`). Batches of span 0 lie
    /// within rows (the stretch and bending along rows): the solver projects them row by row in one pass
    /// with the per-particle work of the same rows; and the one-pass sweep
    /// ([`Wavefront`](crate::fast::wavefront::Wavefront)) runs every batch row by row.
    pub by_last_row: Vec<(Vec<Range<usize>>, usize)>,
}

impl GridConstraints {
    /// Strips and batches for `springs` when they are exactly the grid's own ([`GridShape::spring_pairs`],
    /// same ends in the same roles, any order); `None` otherwise (the general path then serves).
    pub fn new(shape: GridShape, springs: &[Spring]) -> Option<GridConstraints> {
        let (columns, rows) = (shape.columns, shape.rows);
        if columns < 2 || rows < 2 || springs.len() != shape.spring_pairs().len() {
            return None;
        }
        let by_ends = SpringsByEnds::new(columns, columns * rows, springs)?;
        let mut grid = GridConstraints::default();
        let mut batch: Vec<Strip> = Vec::new();
        // Adds a strip of constraints with the given ends, each found among `springs` with `kind`.
        let strip = |grid: &mut GridConstraints,
                     batch: &mut Vec<Strip>,
                     a: usize,
                     count: usize,
                     layout: Layout,
                     kind: SpringKind|
         -> Option<()> {
            if count == 0 {
                return Some(());
            }
            let strip = Strip {
                first: grid.springs.len(),
                count,
                a,
                layout,
                kind,
            };
            for k in 0..count {
                let spring = by_ends.get(springs, strip.ends(k))?;
                if spring.kind != kind {
                    return None;
                }
                grid.springs.push(*spring);
            }
            batch.push(strip);
            Some(())
        };
        let close_batch = |grid: &mut GridConstraints, batch: &mut Vec<Strip>| {
            if !batch.is_empty() {
                let start = grid.strips.len();
                grid.strips.append(batch);
                grid.batches.push(start..grid.strips.len());
            }
        };
        let row_start = |row: usize| row * columns;
        // Bending along rows: columns 4m + {0, 1} (from `first` = 0) or 4m + {2, 3} (`first` = 2).
        for first in [0, 2] {
            for row in 0..rows {
                let reach = columns.saturating_sub(first); // columns from `first` on
                let chunks = reach / 4;
                let a = row_start(row) + first;
                strip(
                    &mut grid,
                    &mut batch,
                    a,
                    2 * chunks,
                    Layout::Along { half: 2 },
                    SpringKind::Bend,
                )?;
                // A last column pair whose partner lies beyond the chunks: 4 chunks + 2 < reach.
                if 4 * chunks + 2 < reach {
                    let a = a + 4 * chunks;
                    strip(
                        &mut grid,
                        &mut batch,
                        a,
                        1,
                        Layout::Apart { b: a + 2 },
                        SpringKind::Bend,
                    )?;
                }
            }
            close_batch(&mut grid, &mut batch);
        }
        // Bending down columns: rows 4m + {0, 1}, then 4m + {2, 3}.
        for first in [0, 2] {
            for row in (0..rows.saturating_sub(2)).filter(|r| r % 4 == first || r % 4 == first + 1)
            {
                let a = row_start(row);
                let b = a + 2 * columns;
                let layout = Layout::Apart { b };
                strip(&mut grid, &mut batch, a, columns, layout, SpringKind::Bend)?;
            }
            close_batch(&mut grid, &mut batch);
        }
        // Shear: the diagonal (r, c)–(r+1, c+1) and the anti-diagonal (r, c+1)–(r+1, c), even rows then
        // odd rows of cells.
        for (offset, b_shift) in [(0, columns + 1), (1, columns - 1)] {
            for parity in [0, 1] {
                for row in (parity..rows - 1).step_by(2) {
                    let a = row_start(row) + offset;
                    let layout = Layout::Apart { b: a + b_shift };
                    strip(
                        &mut grid,
                        &mut batch,
                        a,
                        columns - 1,
                        layout,
                        SpringKind::Shear,
                    )?;
                }
                close_batch(&mut grid, &mut batch);
            }
        }
        // Stretch down columns (even rows, odd rows), then along rows (even columns, odd columns).
        for parity in [0, 1] {
            for row in (parity..rows - 1).step_by(2) {
                let a = row_start(row);
                let layout = Layout::Apart { b: a + columns };
                strip(
                    &mut grid,
                    &mut batch,
                    a,
                    columns,
                    layout,
                    SpringKind::Stretch,
                )?;
            }
            close_batch(&mut grid, &mut batch);
        }
        for parity in [0, 1] {
            for row in 0..rows {
                let count = (columns - parity) / 2;
                let layout = Layout::Along { half: 1 };
                let a = row_start(row) + parity;
                strip(&mut grid, &mut batch, a, count, layout, SpringKind::Stretch)?;
            }
            close_batch(&mut grid, &mut batch);
        }
        if grid.springs.len() != springs.len() {
            return None;
        }
        let n = grid.springs.len();
        grid.rest_lengths = grid.springs.iter().map(|s| s.rest_length).collect();
        grid.inverse_denominators = vec![0.0; n];
        grid.lambdas = vec![0.0; n];
        grid.by_last_row = grid
            .batches
            .iter()
            .map(|batch| {
                last_rows_of_batch(&grid.strips[batch.clone()], batch.start, columns, rows)
            })
            .collect::<Option<_>>()?;
        Some(grid)
    }

    /// The batches between those along rows (span 0) that open a sweep (`0..start`) and those that
    /// close it (`end..`): the solver runs the opening and closing ones row by row with the per-row
    /// work before and after them.
    pub fn middle_batches(&self) -> Range<usize> {
        let within_rows = |batch: &&(Vec<Range<usize>>, usize)| batch.1 == 0;
        let opening = self.by_last_row.iter().take_while(within_rows).count();
        let closing = self.by_last_row[opening..]
            .iter()
            .rev()
            .take_while(within_rows)
            .count();
        opening..self.by_last_row.len() - closing
    }

    /// Whether any constraint may be strained beyond `max_strain` at `positions`
    /// ([`may_exceed_strain`]: conservative, for the divergence check to screen with), strip by strip.
    pub fn any_near_strain(&self, positions: &[DVec3], max_strain: f64, parallel: bool) -> bool {
        let found = AtomicBool::new(false);
        parts(self.strips.len(), parallel, 64, |strips| {
            let any = self.strips[strips].iter().any(|strip| {
                let rest = &self.rest_lengths[strip.first..strip.first + strip.count];
                let [first, second] = strip.particle_ranges();
                match strip.layout {
                    Layout::Apart { .. } => {
                        apart_near_strain(&positions[first], &positions[second], rest, max_strain)
                    }
                    Layout::Along { half: 1 } => along_near_strain::<1, 2>(
                        positions[first].as_chunks().0,
                        rest.as_chunks().0,
                        max_strain,
                    ),
                    Layout::Along { .. } => along_near_strain::<2, 4>(
                        positions[first].as_chunks().0,
                        rest.as_chunks().0,
                        max_strain,
                    ),
                }
            });
            if any {
                found.store(true, Ordering::Relaxed);
            }
        });
        found.into_inner()
    }
}

by_cpu! {
    /// [`may_exceed_strain`] over an apart strip: constraint `k` joins `x_a[k]` and `x_b[k]`.
    fn apart_near_strain(x_a: &[DVec3], x_b: &[DVec3], rest_lengths: &[f64], max_strain: f64) -> bool {
        let n = x_a.len();
        let (x_b, rest_lengths) = (&x_b[..n], &rest_lengths[..n]);
        let mut any = false;
        for k in 0..n {
            any |= may_exceed_strain(x_a[k], x_b[k], rest_lengths[k], max_strain);
        }
        any
    }
}

by_cpu! {
    /// [`may_exceed_strain`] over an along strip (see [`project_along_loop`] for the layout).
    fn along_near_strain<const HALF: usize, const CHUNK: usize>(
        x: &[[DVec3; CHUNK]],
        rest_lengths: &[[f64; HALF]],
        max_strain: f64,
    ) -> bool {
        let n = x.len().min(rest_lengths.len());
        let mut any = false;
        for m in 0..n {
            for j in 0..HALF {
                any |= may_exceed_strain(x[m][j], x[m][j + HALF], rest_lengths[m][j], max_strain);
            }
        }
        any
    }
}

/// The springs of a grid cloth by their ends `(a, b)`, for the strips to look up. Every spring of a grid
/// joins a particle to one a fixed offset further on (1 or 2 along a row, `columns` ± 1 across a cell,
/// `columns` or `2·columns` down), so a table of `particles × offsets` entries holds them all: built in
/// one pass, without the hashing (a hash map of the 3 million springs of 10⁶ particles took about 4 s to
/// build, most of `Simulation::new`).
struct SpringsByEnds {
    /// The distinct offsets `b − a` of the grid's springs, ascending.
    offsets: Vec<usize>,
    /// Per particle `a` and offset: the index in `springs` of the spring from `a`, or `u32::MAX`.
    index: Vec<u32>,
}

impl SpringsByEnds {
    /// `None` when a spring does not join a particle to one at a grid offset further on, or when two
    /// springs join the same ends: then they are not the grid's own set.
    fn new(columns: usize, particles: usize, springs: &[Spring]) -> Option<SpringsByEnds> {
        let mut offsets = vec![1, 2, columns - 1, columns, columns + 1, 2 * columns];
        offsets.sort_unstable();
        offsets.dedup();
        let mut table = SpringsByEnds {
            index: vec![u32::MAX; particles * offsets.len()],
            offsets,
        };
        for (i, spring) in springs.iter().enumerate() {
            let slot = table.slot(spring.a as usize, spring.b as usize)?;
            if table.index[slot] != u32::MAX {
                return None; // a repeated spring
            }
            table.index[slot] = u32::try_from(i).ok()?;
        }
        Some(table)
    }

    fn slot(&self, a: usize, b: usize) -> Option<usize> {
        let offset = b.checked_sub(a)?;
        let k = self.offsets.iter().position(|&o| o == offset)?;
        let slot = a * self.offsets.len() + k;
        (slot < self.index.len()).then_some(slot)
    }

    /// The spring joining `a` to `b`, if any.
    fn get<'s>(&self, springs: &'s [Spring], (a, b): (usize, usize)) -> Option<&'s Spring> {
        let i = self.index[self.slot(a, b)?];
        springs.get(i as usize)
    }
}

/// A batch's strips (the first at index `first` of all strips) by the last of the `rows` rows of
/// `columns` particles they touch, and the rows each spans beyond its first; `None` unless the strips
/// come in ascending last rows and all span alike.
fn last_rows_of_batch(
    strips: &[Strip],
    first: usize,
    columns: usize,
    rows: usize,
) -> Option<(Vec<Range<usize>>, usize)> {
    let mut by_row = vec![0..0; rows];
    let mut span = None;
    let mut previous_row = 0;
    for (k, strip) in strips.iter().enumerate() {
        let touched = strip.particle_ranges();
        let last = touched
            .iter()
            .filter(|r| !r.is_empty())
            .map(|r| (r.end - 1) / columns)
            .max()?;
        let first_row = strip.a / columns;
        if *span.get_or_insert(last - first_row) != last - first_row || last < previous_row {
            return None;
        }
        let index = first + k;
        if by_row[last].is_empty() {
            by_row[last] = index..index;
        }
        by_row[last].end = index + 1;
        previous_row = last;
    }
    Some((by_row, span.unwrap_or(0)))
}

/// Projects `strips` one after another (the strips of a batch, or of a batch's rows), on the whole
/// cloth's arrays: `positions`, `previous` (start positions) and `inverse_masses` per particle,
/// `rest_lengths`, `inverse_denominators` and `lambdas` per constraint, and each family's constants.
/// With AVX-512 each run of strips of one family and layout goes in one call
/// ([`strips_avx512::project_apart_strips`](crate::fast::strips_avx512::project_apart_strips),
/// [`strips_avx512::project_along_strips`](crate::fast::strips_avx512::project_along_strips)); without it,
/// one strip at a time through [`project_strip`]. The same bits either way
/// (`batches_in_one_call_match_the_one_constraint_projection`, the strip tests at every length, and the
/// solver's tests on both paths).
///
/// # Safety
/// No other thread may touch the strips' particles in `positions`, write them in `previous`, or touch
/// their constraints' multipliers while it runs.
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn project_strips<const PBD: bool, const MULTIPLIERS: bool>(
    strips: &[Strip],
    positions: &DisjointXyz<'_>,
    previous: &DisjointXyz<'_>,
    inverse_masses: &[f64],
    rest_lengths: &[f64],
    inverse_denominators: &[f64],
    lambdas: &DisjointSlice<'_, f64>,
    families: &[FamilyConstants; 3],
) {
    // With AVX-512, the whole cloth's arrays, which every run indexes from.
    #[cfg(target_arch = "x86_64")]
    let arrays = std::arch::is_x86_feature_detected!("avx512f").then(|| {
        let (previous, previous_len) = previous.pointers();
        crate::fast::strips_avx512::StripArrays::new(
            positions.pointers(),
            (previous.map(<*mut f64>::cast_const), previous_len),
            inverse_masses,
            rest_lengths,
            inverse_denominators,
            (lambdas.as_mut_ptr(), lambdas.len()),
        )
    });
    let mut left = strips;
    while let Some(strip) = left.first() {
        let family = families[family_index(strip.kind)];
        #[cfg(target_arch = "x86_64")]
        if let Some(arrays) = arrays {
            // The strips from here of the same family and layout (for an along strip, the same half).
            let run = left
                .iter()
                .take_while(|s| {
                    s.kind == strip.kind
                        && match (s.layout, strip.layout) {
                            (Layout::Apart { .. }, Layout::Apart { .. }) => true,
                            (Layout::Along { half }, Layout::Along { half: h }) => half == h,
                            _ => false,
                        }
                })
                .count();
            let (this, next) = left.split_at(run);
            // SAFETY: the CPU has AVX-512F (checked above); the arrays are valid for the lengths given,
            // an apart strip's runs do not overlap (`Layout::Apart`), and the rest is the caller's
            // contract.
            unsafe { project_run::<PBD, MULTIPLIERS>(arrays, this, family) };
            left = next;
            continue;
        }
        let constraints = strip.first..strip.first + strip.count;
        let (rest, denominators) = (
            &rest_lengths[constraints.clone()],
            &inverse_denominators[constraints.clone()],
        );
        // SAFETY: by the caller's contract.
        unsafe {
            let lambdas = lambdas.slice_mut(constraints);
            let project = if family.gamma != 0.0 {
                project_strip::<PBD, MULTIPLIERS, true>
            } else {
                project_strip::<PBD, MULTIPLIERS, false>
            };
            project(
                strip,
                positions,
                previous,
                inverse_masses,
                rest,
                denominators,
                lambdas,
                family,
            );
        }
        left = &left[1..];
    }
}

/// A run of strips of one family and layout (see [`project_strips`]) in one AVX-512 call.
///
/// # Safety
/// As [`strips_avx512::project_apart_strips`](crate::fast::strips_avx512::project_apart_strips).
#[cfg(target_arch = "x86_64")]
unsafe fn project_run<const PBD: bool, const MULTIPLIERS: bool>(
    arrays: crate::fast::strips_avx512::StripArrays,
    strips: &[Strip],
    family: FamilyConstants,
) {
    use crate::fast::strips_avx512::{project_along_strips, project_apart_strips};
    let Some(strip) = strips.first() else {
        return;
    };
    let apart = strips.iter().filter_map(|s| match s.layout {
        Layout::Apart { b } => Some((s.a, b, s.first, s.count)),
        Layout::Along { .. } => None,
    });
    let along = strips.iter().map(|s| (s.a, s.first, s.count));
    // SAFETY: by the caller's contract.
    unsafe {
        match (strip.layout, family.gamma != 0.0) {
            (Layout::Apart { .. }, true) => {
                project_apart_strips::<PBD, MULTIPLIERS, true>(arrays, apart, family)
            }
            (Layout::Apart { .. }, false) => {
                project_apart_strips::<PBD, MULTIPLIERS, false>(arrays, apart, family)
            }
            (Layout::Along { half: 1 }, true) => {
                project_along_strips::<PBD, MULTIPLIERS, true, 1>(arrays, along, family)
            }
            (Layout::Along { half: 1 }, false) => {
                project_along_strips::<PBD, MULTIPLIERS, false, 1>(arrays, along, family)
            }
            (Layout::Along { .. }, true) => {
                project_along_strips::<PBD, MULTIPLIERS, true, 2>(arrays, along, family)
            }
            (Layout::Along { .. }, false) => {
                project_along_strips::<PBD, MULTIPLIERS, false, 2>(arrays, along, family)
            }
        }
    }
}

/// Projects one strip of a batch: `positions`, `previous` (start positions) and `inverse_masses` are the
/// whole cloth's; `rest_lengths`, `inverse_denominators` and `lambdas` the strip's own constraints'.
///
/// # Safety
/// No other thread may touch the strip's particles ([`Strip::particle_ranges`]) in `positions` or
/// write them in `previous` while it runs.
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn project_strip<const PBD: bool, const MULTIPLIERS: bool, const DAMPED: bool>(
    strip: &Strip,
    positions: &DisjointXyz<'_>,
    previous: &DisjointXyz<'_>,
    inverse_masses: &[f64],
    rest_lengths: &[f64],
    inverse_denominators: &[f64],
    lambdas: &mut [f64],
    family: FamilyConstants,
) {
    let [first, second] = strip.particle_ranges();
    match strip.layout {
        Layout::Apart { .. } => {
            // SAFETY: exclusive by the caller's contract; the two ranges do not overlap
            // (`Layout::Apart` has b ≥ a + count).
            let (x_a, x_b, previous_a, previous_b) = unsafe {
                (
                    positions.slice_mut(first.clone()),
                    positions.slice_mut(second.clone()),
                    previous.slice(first.clone()),
                    previous.slice(second.clone()),
                )
            };
            project_apart_loop::<PBD, MULTIPLIERS, DAMPED>(
                x_a,
                x_b,
                previous_a,
                previous_b,
                &inverse_masses[first],
                &inverse_masses[second],
                rest_lengths,
                inverse_denominators,
                lambdas,
                family,
            );
        }
        Layout::Along { half } => {
            // SAFETY: exclusive by the caller's contract.
            let (x, previous) = unsafe {
                (
                    positions.slice_mut(first.clone()),
                    previous.slice(first.clone()),
                )
            };
            let w = &inverse_masses[first];
            let (rest, denominators) = (rest_lengths, inverse_denominators);
            if half == 1 {
                project_along_loop::<PBD, MULTIPLIERS, DAMPED, 1>(
                    x,
                    previous,
                    w,
                    rest,
                    denominators,
                    lambdas,
                    family,
                );
            } else {
                project_along_loop::<PBD, MULTIPLIERS, DAMPED, 2>(
                    x,
                    previous,
                    w,
                    rest,
                    denominators,
                    lambdas,
                    family,
                );
            }
        }
    }
}

/// [`project_apart`] on split vectors: each component passed as its own slice.
#[allow(clippy::too_many_arguments)]
pub(crate) fn project_apart_loop<const PBD: bool, const MULTIPLIERS: bool, const DAMPED: bool>(
    x_a: XyzMut<'_>,
    x_b: XyzMut<'_>,
    previous_a: XyzRef<'_>,
    previous_b: XyzRef<'_>,
    w_a: &[f64],
    w_b: &[f64],
    rest_lengths: &[f64],
    inverse_denominators: &[f64],
    lambdas: &mut [f64],
    family: FamilyConstants,
) {
    project_apart::<PBD, MULTIPLIERS, DAMPED>(
        x_a.x,
        x_a.y,
        x_a.z,
        x_b.x,
        x_b.y,
        x_b.z,
        previous_a.x,
        previous_a.y,
        previous_a.z,
        previous_b.x,
        previous_b.y,
        previous_b.z,
        w_a,
        w_b,
        rest_lengths,
        inverse_denominators,
        lambdas,
        family,
    );
}

by_cpu! {
    /// An apart strip in a loop the compiler vectorises (the solver's path without AVX-512, see
    /// [`project_strips`]): constraint `k` joins particle `k` of
    /// `a` and of `b`, each given by component (separate slices, which the compiler knows do not
    /// overlap, so the loop needs no run-time checks).
    pub(crate) fn project_apart<const PBD: bool, const MULTIPLIERS: bool, const DAMPED: bool>(
        a_x: &mut [f64],
        a_y: &mut [f64],
        a_z: &mut [f64],
        b_x: &mut [f64],
        b_y: &mut [f64],
        b_z: &mut [f64],
        previous_a_x: &[f64],
        previous_a_y: &[f64],
        previous_a_z: &[f64],
        previous_b_x: &[f64],
        previous_b_y: &[f64],
        previous_b_z: &[f64],
        inverse_mass_a: &[f64],
        inverse_mass_b: &[f64],
        rest_lengths: &[f64],
        inverse_denominators: &[f64],
        lambdas: &mut [f64],
        family: FamilyConstants,
    ) {
        // Exact lengths: no bounds checks in the loop.
        let n = a_x.len();
        let (a_y, a_z, b_x, b_y, b_z) =
            (&mut a_y[..n], &mut a_z[..n], &mut b_x[..n], &mut b_y[..n], &mut b_z[..n]);
        let (previous_a_x, previous_a_y, previous_a_z) =
            (&previous_a_x[..n], &previous_a_y[..n], &previous_a_z[..n]);
        let (previous_b_x, previous_b_y, previous_b_z) =
            (&previous_b_x[..n], &previous_b_y[..n], &previous_b_z[..n]);
        let (inverse_mass_a, inverse_mass_b) = (&inverse_mass_a[..n], &inverse_mass_b[..n]);
        let (rest_lengths, inverse_denominators) = (&rest_lengths[..n], &inverse_denominators[..n]);
        let lambdas = &mut lambdas[..n];
        for k in 0..n {
            let mut a = DVec3::new(a_x[k], a_y[k], a_z[k]);
            let mut b = DVec3::new(b_x[k], b_y[k], b_z[k]);
            project::<PBD, MULTIPLIERS, DAMPED>(
                &mut a,
                &mut b,
                DVec3::new(previous_a_x[k], previous_a_y[k], previous_a_z[k]),
                DVec3::new(previous_b_x[k], previous_b_y[k], previous_b_z[k]),
                inverse_mass_a[k],
                inverse_mass_b[k],
                rest_lengths[k],
                inverse_denominators[k],
                &mut lambdas[k],
                family,
            );
            (a_x[k], a_y[k], a_z[k]) = (a.x, a.y, a.z);
            (b_x[k], b_y[k], b_z[k]) = (b.x, b.y, b.z);
        }
    }
}

by_cpu! {
    /// Projects an along strip of `HALF` interleaved constraints per chunk of `2·HALF` particles
    /// (constraint `m·HALF + j` joins particles `2·HALF·m + j` and `2·HALF·m + j + HALF`) one
    /// constraint at a time: the path of a CPU without AVX-512 (compiled per instruction set,
    /// [`by_cpu!`]), and the reference the AVX-512 blocks
    /// ([`strips_avx512::project_along_strips`](crate::fast::strips_avx512::project_along_strips)) are
    /// tested against.
    pub(crate) fn project_along_loop<
        const PBD: bool,
        const MULTIPLIERS: bool,
        const DAMPED: bool,
        const HALF: usize,
    >(
        x: XyzMut<'_>,
        previous: XyzRef<'_>,
        inverse_masses: &[f64],
        rest_lengths: &[f64],
        inverse_denominators: &[f64],
        lambdas: &mut [f64],
        family: FamilyConstants,
    ) {
        let constraints = rest_lengths.len();
        assert!(
            constraints.is_multiple_of(HALF),
            "whole chunks of {HALF} constraints"
        );
        assert!(x.len() == 2 * constraints && previous.len() == x.len());
        assert!(inverse_masses.len() == x.len() && inverse_denominators.len() == constraints);
        for c in 0..constraints {
            let a = 2 * HALF * (c / HALF) + c % HALF;
            let b = a + HALF;
            let mut x_a = DVec3::new(x.x[a], x.y[a], x.z[a]);
            let mut x_b = DVec3::new(x.x[b], x.y[b], x.z[b]);
            project::<PBD, MULTIPLIERS, DAMPED>(
                &mut x_a,
                &mut x_b,
                previous.at(a),
                previous.at(b),
                inverse_masses[a],
                inverse_masses[b],
                rest_lengths[c],
                inverse_denominators[c],
                &mut lambdas[c],
                family,
            );
            (x.x[a], x.y[a], x.z[a]) = (x_a.x, x_a.y, x_a.z);
            (x.x[b], x.y[b], x.z[b]) = (x_b.x, x_b.y, x_b.z);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fast::components::Xyz;

    /// [`joined_along`] of one layout.
    type JoinedAlong =
        fn(&mut [DVec3], &[DVec3], &[f64], &[f64], &[f64], &mut [f64], usize, FamilyConstants);
    use crate::model::{ClothModel, GridSpec};

    fn grid_springs(columns: usize, rows: usize) -> (GridShape, Vec<Spring>) {
        let spec = GridSpec {
            columns,
            rows,
            ..GridSpec::default()
        };
        let model = ClothModel::grid(&spec).unwrap();
        (model.grid.unwrap(), model.springs)
    }

    #[test]
    fn grid_strips_cover_every_spring_once_and_no_batch_shares_a_particle() {
        for (columns, rows) in [
            (2, 2),
            (3, 2),
            (2, 5),
            (5, 3),
            (6, 4),
            (7, 7),
            (8, 9),
            (11, 6),
            (64, 46),
        ] {
            let (shape, springs) = grid_springs(columns, rows);
            let grid = GridConstraints::new(shape, &springs)
                .unwrap_or_else(|| panic!("{columns}×{rows}: the grid's own springs"));
            let mut expected: Vec<(u32, u32)> = springs.iter().map(|s| (s.a, s.b)).collect();
            let mut got: Vec<(u32, u32)> = grid.springs.iter().map(|s| (s.a, s.b)).collect();
            expected.sort_unstable();
            got.sort_unstable();
            assert_eq!(got, expected, "{columns}×{rows}: each spring exactly once");
            let mut next = 0;
            for batch in &grid.batches {
                let mut touched = vec![false; columns * rows];
                for strip in &grid.strips[batch.clone()] {
                    assert_eq!(strip.first, next, "strips are consecutive");
                    next += strip.count;
                    let [first, second] = strip.particle_ranges();
                    assert!(first.end <= second.start || second.is_empty());
                    for k in 0..strip.count {
                        let spring = grid.springs[strip.first + k];
                        let (a, b) = strip.ends(k);
                        assert_eq!((spring.a as usize, spring.b as usize), (a, b));
                        assert!(first.contains(&a) && (first.contains(&b) || second.contains(&b)));
                    }
                    for particle in first.chain(second) {
                        assert!(
                            !touched[particle],
                            "{columns}×{rows}: particle {particle} twice in a batch"
                        );
                        touched[particle] = true;
                    }
                }
            }
            assert_eq!(next, springs.len());
        }
    }

    #[test]
    fn springs_that_are_not_the_grids_own_take_the_general_path() {
        let (shape, springs) = grid_springs(6, 5);
        assert!(GridConstraints::new(shape, &springs).is_some());
        let mut missing = springs.clone();
        missing.pop();
        assert!(GridConstraints::new(shape, &missing).is_none());
        let mut extra = springs.clone();
        extra.push(springs[0]);
        assert!(GridConstraints::new(shape, &extra).is_none());
        let mut swapped = springs.clone();
        let spring = &mut swapped[3];
        (spring.a, spring.b) = (spring.b, spring.a);
        assert!(GridConstraints::new(shape, &swapped).is_none());
        let mut other_kind = springs.clone();
        other_kind[0].kind = SpringKind::Bend;
        assert!(GridConstraints::new(shape, &other_kind).is_none());
        // The same count, but one spring twice in place of another.
        let mut repeated = springs.clone();
        repeated[1] = repeated[0];
        assert!(GridConstraints::new(shape, &repeated).is_none());
        // A pair at a grid offset that is no grid neighbour: the end of one row to the start of the next.
        let mut wrapped = springs.clone();
        let end_of_row = shape.index(0, shape.columns - 1) as u32;
        let i = wrapped
            .iter()
            .position(|s| s.kind == SpringKind::Stretch && s.b == s.a + 1)
            .unwrap();
        (wrapped[i].a, wrapped[i].b) = (end_of_row, end_of_row + 1);
        assert!(GridConstraints::new(shape, &wrapped).is_none());
        // An end beyond the last particle.
        let mut beyond = springs.clone();
        let last = (shape.columns * shape.rows) as u32;
        (beyond[i].a, beyond[i].b) = (last, last + 1);
        assert!(GridConstraints::new(shape, &beyond).is_none());
        // Grids so narrow that the offsets coincide (2 columns: 1 = columns − 1, 2 = columns; 3 columns:
        // 2 = columns − 1) still take their own springs.
        for (columns, rows) in [(2, 2), (2, 5), (3, 3), (3, 6)] {
            let (shape, springs) = grid_springs(columns, rows);
            assert!(
                GridConstraints::new(shape, &springs).is_some(),
                "{columns}×{rows}"
            );
        }
    }

    /// The run kernels' view of whole split arrays (particles and constraints), for the strip tests.
    #[cfg(target_arch = "x86_64")]
    fn whole_arrays(
        x: &mut Xyz,
        previous: &Xyz,
        w: &[f64],
        rest: &[f64],
        denominators: &[f64],
        lambdas: &mut [f64],
    ) -> crate::fast::strips_avx512::StripArrays {
        crate::fast::strips_avx512::StripArrays::new(
            x.disjoint().pointers(),
            (
                [&previous.x, &previous.y, &previous.z].map(|c| c.as_ptr()),
                previous.len(),
            ),
            w,
            rest,
            denominators,
            (lambdas.as_mut_ptr(), lambdas.len()),
        )
    }

    /// The solver's apart strip (`STRIP`: with AVX-512 [`strips_avx512::project_apart_strips`], else the
    /// loop) or the loop [`project_apart_loop`] alone, on the first `count` constraints of a strip
    /// joining particle `k` to particle `n + k` of `x` (`2n` particles): the whole arrays split, those
    /// constraints projected, the arrays joined back, so that a write past the strip would show in them.
    #[allow(clippy::too_many_arguments)]
    fn joined_apart<
        const PBD: bool,
        const MULTIPLIERS: bool,
        const DAMPED: bool,
        const STRIP: bool,
    >(
        x: &mut [DVec3],
        previous: &[DVec3],
        w: &[f64],
        rest: &[f64],
        denominators: &[f64],
        lambdas: &mut [f64],
        count: usize,
        family: FamilyConstants,
    ) {
        let n = x.len() / 2;
        let mut split = Xyz::of(x);
        let previous = Xyz::of(previous);
        #[cfg(target_arch = "x86_64")]
        if STRIP && std::arch::is_x86_feature_detected!("avx512f") {
            let arrays = whole_arrays(&mut split, &previous, w, rest, denominators, lambdas);
            // SAFETY: the CPU has AVX-512F; the arrays are as long as given; one thread.
            unsafe {
                crate::fast::strips_avx512::project_apart_strips::<PBD, MULTIPLIERS, DAMPED>(
                    arrays,
                    [(0, n, 0, count)].into_iter(),
                    family,
                )
            };
            split.join_into(x);
            return;
        }
        let (a, b) = split.as_mut().split_at_mut(n);
        let (x_a, _) = a.split_at_mut(count);
        let (x_b, _) = b.split_at_mut(count);
        let previous = previous.as_ref();
        let (previous_a, previous_b) = (previous.range(0..count), previous.range(n..n + count));
        project_apart_loop::<PBD, MULTIPLIERS, DAMPED>(
            x_a,
            x_b,
            previous_a,
            previous_b,
            &w[..count],
            &w[n..n + count],
            &rest[..count],
            &denominators[..count],
            &mut lambdas[..count],
            family,
        );
        split.join_into(x);
    }

    /// The solver's along strip (with AVX-512 [`strips_avx512::project_along_strips`], else the loop;
    /// with `LOOP` the loop [`project_along_loop`] alone) on the first `chunks` chunks of joined vectors,
    /// split and joined back whole as in [`joined_apart`].
    #[allow(clippy::too_many_arguments)]
    fn joined_along<
        const PBD: bool,
        const MULTIPLIERS: bool,
        const DAMPED: bool,
        const HALF: usize,
        const LOOP: bool,
    >(
        x: &mut [DVec3],
        previous: &[DVec3],
        w: &[f64],
        rest: &[f64],
        denominators: &[f64],
        lambdas: &mut [f64],
        chunks: usize,
        family: FamilyConstants,
    ) {
        let (particles, constraints) = (2 * HALF * chunks, HALF * chunks);
        let (mut split, previous) = (Xyz::of(x), Xyz::of(previous));
        #[cfg(target_arch = "x86_64")]
        if !LOOP && std::arch::is_x86_feature_detected!("avx512f") {
            let arrays = whole_arrays(&mut split, &previous, w, rest, denominators, lambdas);
            // SAFETY: the CPU has AVX-512F; the arrays are as long as given; one thread.
            unsafe {
                crate::fast::strips_avx512::project_along_strips::<PBD, MULTIPLIERS, DAMPED, HALF>(
                    arrays,
                    [(0, 0, constraints)].into_iter(),
                    family,
                )
            };
            split.join_into(x);
            return;
        }
        let (moved, _) = split.as_mut().split_at_mut(particles);
        project_along_loop::<PBD, MULTIPLIERS, DAMPED, HALF>(
            moved,
            previous.as_ref().range(0..particles),
            &w[..particles],
            &rest[..constraints],
            &denominators[..constraints],
            &mut lambdas[..constraints],
            family,
        );
        split.join_into(x);
    }

    /// The vectorised strip loops give the bits of [`project`] called one constraint at a time, for
    /// PBD, XPBD with and without multipliers, with inactive constraints and coincident ends.
    #[test]
    fn strip_loops_match_the_one_constraint_projection_bit_for_bit() {
        // 26 pair chunks and 13 quad chunks: three whole blocks of eight constraints (AVX-512) and a
        // remainder each.
        let n = 52;
        let jitter = |i: usize, k: u64| {
            let mut z = (i as u64 + 7).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ k;
            z = (z ^ (z >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut x: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new(0.02 * i as f64, jitter(i, 1) * 0.01, jitter(i, 2) * 0.01))
            .collect();
        x[5] = x[5 + n / 2]; // coincident ends of constraint 5 (apart) and of an along pair
        x[10] = x[11];
        let previous: Vec<DVec3> = x
            .iter()
            .enumerate()
            .map(|(i, p)| *p + 1e-3 * DVec3::new(jitter(i, 3), jitter(i, 4), jitter(i, 5)))
            .collect();
        let w: Vec<f64> = (0..n).map(|i| 1e4 * (1.0 + jitter(i, 6))).collect();
        let half = n / 2;
        let rest: Vec<f64> = (0..half).map(|k| 0.018 + 1e-3 * jitter(k, 7)).collect();
        let mut denominators: Vec<f64> = (0..half).map(|k| 2e-5 * (1.5 + jitter(k, 8))).collect();
        denominators[7] = 0.0; // switched off
        let family = FamilyConstants {
            scaled_compliance: 9.0,
            gamma: 0.3,
        };
        let bits = |v: &[DVec3]| -> Vec<[u64; 3]> {
            v.iter().map(|p| p.to_array().map(f64::to_bits)).collect()
        };
        fn check<const PBD: bool, const MULTIPLIERS: bool, const DAMPED: bool>(
            x: &[DVec3],
            previous: &[DVec3],
            w: &[f64],
            rest: &[f64],
            denominators: &[f64],
            family: FamilyConstants,
            bits: &dyn Fn(&[DVec3]) -> Vec<[u64; 3]>,
        ) {
            let half = x.len() / 2;
            let lambdas0: Vec<f64> = (0..half).map(|k| 1e-4 * k as f64).collect();
            // Apart: constraint k joins k and k + half.
            let (mut expected, mut expected_lambdas) = (x.to_vec(), lambdas0.clone());
            for k in 0..half {
                let (low, high) = expected.split_at_mut(half);
                project::<PBD, MULTIPLIERS, DAMPED>(
                    &mut low[k],
                    &mut high[k],
                    previous[k],
                    previous[k + half],
                    w[k],
                    w[k + half],
                    rest[k],
                    denominators[k],
                    &mut expected_lambdas[k],
                    family,
                );
            }
            let (mut got, mut got_lambdas) = (x.to_vec(), lambdas0.clone());
            joined_apart::<PBD, MULTIPLIERS, DAMPED, false>(
                &mut got,
                previous,
                w,
                rest,
                denominators,
                &mut got_lambdas,
                half,
                family,
            );
            assert_eq!(bits(&got), bits(&expected), "apart, PBD {PBD}");
            assert_eq!(got_lambdas, expected_lambdas);
            // Along, pairs: constraint m joins 2m and 2m + 1.
            let (mut expected, mut expected_lambdas) = (x.to_vec(), lambdas0.clone());
            for m in 0..half {
                let (low, high) = expected.split_at_mut(2 * m + 1);
                project::<PBD, MULTIPLIERS, DAMPED>(
                    &mut low[2 * m],
                    &mut high[0],
                    previous[2 * m],
                    previous[2 * m + 1],
                    w[2 * m],
                    w[2 * m + 1],
                    rest[m],
                    denominators[m],
                    &mut expected_lambdas[m],
                    family,
                );
            }
            // The dispatching function (AVX-512 blocks where the CPU has it) and the loop alone.
            let projections = [
                (
                    "",
                    joined_along::<PBD, MULTIPLIERS, DAMPED, 1, false> as JoinedAlong,
                ),
                (" (loop)", joined_along::<PBD, MULTIPLIERS, DAMPED, 1, true>),
            ];
            for (path, project) in projections {
                let (mut got, mut got_lambdas) = (x.to_vec(), lambdas0.clone());
                let chunks = x.len() / 2;
                project(
                    &mut got,
                    previous,
                    w,
                    rest,
                    denominators,
                    &mut got_lambdas,
                    chunks,
                    family,
                );
                assert_eq!(bits(&got), bits(&expected), "along pairs{path}, PBD {PBD}");
                assert_eq!(got_lambdas, expected_lambdas);
                assert_ne!(bits(&got), bits(x), "the constraints moved the particles");
            }
            // Along, quads: constraint 2m + j joins 4m + j and 4m + j + 2.
            let (mut expected, mut expected_lambdas) = (x.to_vec(), lambdas0.clone());
            for c in 0..half {
                let (m, j) = (c / 2, c % 2);
                let a = 4 * m + j;
                let (low, high) = expected.split_at_mut(a + 2);
                project::<PBD, MULTIPLIERS, DAMPED>(
                    &mut low[a],
                    &mut high[0],
                    previous[a],
                    previous[a + 2],
                    w[a],
                    w[a + 2],
                    rest[c],
                    denominators[c],
                    &mut expected_lambdas[c],
                    family,
                );
            }
            // The dispatching function (AVX-512 blocks where the CPU has it) and the loop alone.
            let projections = [
                (
                    "",
                    joined_along::<PBD, MULTIPLIERS, DAMPED, 2, false> as JoinedAlong,
                ),
                (" (loop)", joined_along::<PBD, MULTIPLIERS, DAMPED, 2, true>),
            ];
            for (path, project) in projections {
                let (mut got, mut got_lambdas) = (x.to_vec(), lambdas0.clone());
                let chunks = x.len() / 4;
                project(
                    &mut got,
                    previous,
                    w,
                    rest,
                    denominators,
                    &mut got_lambdas,
                    chunks,
                    family,
                );
                assert_eq!(bits(&got), bits(&expected), "along quads{path}, PBD {PBD}");
                assert_eq!(got_lambdas, expected_lambdas);
                assert_ne!(bits(&got), bits(x), "the constraints moved the particles");
            }
        }
        check::<true, false, true>(&x, &previous, &w, &rest, &denominators, family, &bits);
        check::<false, false, true>(&x, &previous, &w, &rest, &denominators, family, &bits);
        check::<false, true, true>(&x, &previous, &w, &rest, &denominators, family, &bits);
        let undamped = FamilyConstants {
            gamma: 0.0,
            ..family
        };
        check::<false, false, false>(&x, &previous, &w, &rest, &denominators, undamped, &bits);
        check::<false, true, false>(&x, &previous, &w, &rest, &denominators, undamped, &bits);
    }

    /// An along strip of any length (whole blocks of eight constraints and a partial one of every size)
    /// gives the loop's bits, multipliers included, and leaves the particles and multipliers after it
    /// untouched: for PBD and for XPBD with and without multipliers and damping, with switched-off
    /// constraints, constraints exactly at rest length (whose correction is −0, which shows where a
    /// position is −0: only if the negation flips the sign bit, as Rust's does) and a non-finite particle.
    /// The family constants of the strip tests: XPBD with damping.
    const STRIP_TEST_FAMILY: FamilyConstants = FamilyConstants {
        scaled_compliance: 9.0,
        gamma: 0.3,
    };

    /// Bits, with every NaN as one: Rust leaves a NaN's sign and payload open, and the vectoriser may
    /// commute the operands that pass one on (a diverged state is rolled back anyway).
    fn nan_blind(v: f64) -> u64 {
        if v.is_nan() { u64::MAX } else { v.to_bits() }
    }

    fn nan_blind_scalar_bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|&l| nan_blind(l)).collect()
    }

    fn nan_blind_bits(v: &[DVec3]) -> Vec<[u64; 3]> {
        v.iter().map(|p| p.to_array().map(nan_blind)).collect()
    }

    /// Data for `count` constraints with ends `ends(k)` among `x`: rest lengths, inverted divisors and
    /// multipliers; every fifth constraint exactly at its rest length with a multiplier of −0, every
    /// seventh switched off.
    #[allow(clippy::type_complexity)]
    fn constraint_data(
        x: &[DVec3],
        count: usize,
        ends: &dyn Fn(usize) -> (usize, usize),
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let rest = (0..count)
            .map(|k| {
                let (a, b) = ends(k);
                if k % 5 == 2 {
                    (x[a] - x[b]).length()
                } else {
                    0.019
                }
            })
            .collect();
        let denominators = (0..count)
            .map(|k| if k % 7 == 3 { 0.0 } else { 2e-5 })
            .collect();
        let lambdas = (0..count)
            .map(|k| if k % 5 == 2 { -0.0 } else { 1e-5 * k as f64 })
            .collect();
        (rest, denominators, lambdas)
    }

    /// An apart strip of any length, as the solver projects it (with AVX-512 in blocks of eight, the
    /// last one masked), gives the bits of [`project`] one constraint at a time,
    /// and touches no particle and no multiplier past the strip; with NaN, coincident ends, constraints
    /// switched off and at rest length, for PBD and XPBD with and without multipliers and damping.
    #[test]
    fn apart_strips_of_every_length_match_the_projection_and_touch_nothing_beyond() {
        let n = 24;
        let wobble = |i: usize| ((i * 7919) % 13) as f64 * 1e-3;
        // Run a (particles 0..n) joined to run b (particles n..2n), one row apart.
        let mut x: Vec<DVec3> = (0..2 * n)
            .map(|i| {
                DVec3::new(
                    0.02 * (i % n) as f64,
                    -0.02 * (i / n) as f64 + wobble(i),
                    0.0,
                )
            })
            .collect();
        x[5].y = f64::NAN;
        x[n + 9] = x[9]; // coincident ends
        for k in (0..n).filter(|k| k % 5 == 2) {
            x[k].z = -0.0;
            x[n + k].z = -0.0;
        }
        let previous: Vec<DVec3> = (0..2 * n)
            .map(|i| x[i] - DVec3::new(1e-4, 3e-5 * (i % 3) as f64, 1e-5))
            .collect();
        let w: Vec<f64> = (0..2 * n).map(|i| 1e4 + i as f64).collect();
        let (rest, denominators, lambdas0) = constraint_data(&x, n, &|k| (k, n + k));
        let family = STRIP_TEST_FAMILY;
        let (bits, scalar_bits) = (nan_blind_bits, nan_blind_scalar_bits);
        macro_rules! check {
            ($pbd:literal, $multipliers:literal, $damped:literal) => {{
                for count in 0..=19 {
                    let run = |strip: bool| {
                        let (mut x, mut lambdas) = (x.clone(), lambdas0.clone());
                        if strip {
                            joined_apart::<$pbd, $multipliers, $damped, true>(
                                &mut x,
                                &previous,
                                &w,
                                &rest,
                                &denominators,
                                &mut lambdas,
                                count,
                                family,
                            );
                        } else {
                            let (a, b) = x.split_at_mut(n);
                            for k in 0..count {
                                project::<$pbd, $multipliers, $damped>(
                                    &mut a[k],
                                    &mut b[k],
                                    previous[k],
                                    previous[n + k],
                                    w[k],
                                    w[n + k],
                                    rest[k],
                                    denominators[k],
                                    &mut lambdas[k],
                                    family,
                                );
                            }
                        }
                        (x, lambdas)
                    };
                    let (got, expected) = (run(true), run(false));
                    let case = format!(
                        "PBD {}, multipliers {}, damped {}, {count} constraints",
                        $pbd, $multipliers, $damped
                    );
                    assert_eq!(bits(&got.0), bits(&expected.0), "{case}");
                    assert_eq!(scalar_bits(&got.1), scalar_bits(&expected.1), "{case}");
                    for run in [count..n, n + count..2 * n] {
                        assert_eq!(bits(&got.0[run.clone()]), bits(&x[run]), "{case}");
                    }
                    assert_eq!(
                        scalar_bits(&got.1[count..]),
                        scalar_bits(&lambdas0[count..]),
                        "{case}"
                    );
                    if count > 3 {
                        assert_ne!(bits(&got.0), bits(&x), "{case}: the particles moved");
                    }
                }
            }};
        }
        check!(false, true, true);
        check!(false, true, false);
        check!(false, false, true);
        check!(false, false, false);
        check!(true, false, false);
    }

    #[test]
    fn along_strips_of_every_length_match_the_loop_and_touch_nothing_beyond() {
        let n = 80;
        let mut x: Vec<DVec3> = (0..n)
            .map(|i| {
                let wobble = ((i * 7919) % 13) as f64 * 1e-3;
                DVec3::new(0.02 * i as f64, wobble, 0.5 * wobble)
            })
            .collect();
        x[37].y = f64::NAN;
        // Equal shifts give a zero damping rate; every fourth particle moved otherwise.
        let previous: Vec<DVec3> = (0..n)
            .map(|i| {
                x[i] - DVec3::splat(1e-4) - DVec3::new(0.0, 3e-5, 0.0) * (i % 4 == 3) as u8 as f64
            })
            .collect();
        let w: Vec<f64> = (0..n).map(|i| 1e4 + i as f64).collect();
        let family = STRIP_TEST_FAMILY;
        let (bits, scalar_bits) = (nan_blind_bits, nan_blind_scalar_bits);
        macro_rules! check {
            ($pbd:literal, $multipliers:literal, $damped:literal, $half:literal, $chunk:literal) => {{
                let half: usize = $half;
                let ends = |k: usize| {
                    let a = 2 * half * (k / half) + k % half;
                    (a, a + half)
                };
                // The ends of the constraints at rest length at z = −0: there the sign of a zero
                // correction shows in the positions.
                let mut x = x.clone();
                for k in (0..n / 2).filter(|k| k % 5 == 2) {
                    let (a, b) = ends(k);
                    x[a].z = -0.0;
                    x[b].z = -0.0;
                }
                let (rest, denominators, lambdas0) = constraint_data(&x, n / 2, &ends);
                for chunks in 0..=19 {
                    let run = |looped: bool| {
                        let (mut x, mut lambdas) = (x.clone(), lambdas0.clone());
                        let project = if looped {
                            joined_along::<$pbd, $multipliers, $damped, $half, true>
                        } else {
                            joined_along::<$pbd, $multipliers, $damped, $half, false>
                        };
                        project(
                            &mut x,
                            &previous,
                            &w,
                            &rest,
                            &denominators,
                            &mut lambdas,
                            chunks,
                            family,
                        );
                        (x, lambdas)
                    };
                    let (got, expected) = (run(false), run(true));
                    let case = format!(
                        "half {}, PBD {}, multipliers {}, damped {}, {chunks} chunks",
                        $half, $pbd, $multipliers, $damped
                    );
                    assert_eq!(bits(&got.0), bits(&expected.0), "{case}");
                    assert_eq!(scalar_bits(&got.1), scalar_bits(&expected.1), "{case}");
                    let touched = 2 * $half * chunks;
                    assert_eq!(bits(&got.0[touched..]), bits(&x[touched..]), "{case}");
                    let constraints = $half * chunks;
                    assert_eq!(
                        scalar_bits(&got.1[constraints..]),
                        scalar_bits(&lambdas0[constraints..]),
                        "{case}"
                    );
                    if chunks > 2 {
                        assert_ne!(bits(&got.0), bits(&x), "{case}: the particles moved");
                    }
                }
            }};
        }
        check!(false, true, true, 1, 2);
        check!(false, true, true, 2, 4);
        check!(false, true, false, 1, 2);
        check!(false, false, true, 2, 4);
        check!(false, false, false, 1, 2);
        check!(true, false, false, 1, 2);
        check!(true, false, false, 2, 4);
        check!(true, false, true, 2, 4);
    }

    /// Whole batches of a grid through [`project_strips`] (with AVX-512, runs of strips in one call each)
    /// give the bits of [`project`] constraint by constraint in strip order, multipliers included, with
    /// damping on some families and off on another; on grids whose rows end in partial blocks.
    #[test]
    fn batches_in_one_call_match_the_one_constraint_projection() {
        for (columns, rows) in [(37, 9), (64, 6), (12, 5)] {
            let (shape, springs) = grid_springs(columns, rows);
            let grid = GridConstraints::new(shape, &springs).expect("the grid's own springs");
            let n = columns * rows;
            let wobble =
                |i: usize, k: usize| (((i * 7919 + k * 104_729) % 97) as f64 / 97.0 - 0.5) * 4e-3;
            let x: Vec<DVec3> = (0..n)
                .map(|i| {
                    let (c, r) = ((i % columns) as f64, (i / columns) as f64);
                    DVec3::new(
                        0.02 * c + wobble(i, 1),
                        -0.02 * r + wobble(i, 2),
                        wobble(i, 3),
                    )
                })
                .collect();
            let previous: Vec<DVec3> = (0..n)
                .map(|i| x[i] - DVec3::splat(1e-4 + wobble(i, 4) * 0.1))
                .collect();
            let w: Vec<f64> = (0..n)
                .map(|i| {
                    if i % columns == 0 {
                        0.0
                    } else {
                        1e4 + i as f64
                    }
                })
                .collect();
            let constraints = grid.springs.len();
            let rest = grid.rest_lengths.clone();
            let denominators: Vec<f64> = (0..constraints)
                .map(|k| 2e-5 * (1.0 + (k % 5) as f64 * 0.1))
                .collect();
            let lambdas0: Vec<f64> = (0..constraints).map(|k| 1e-6 * (k % 11) as f64).collect();
            let families = [
                FamilyConstants {
                    scaled_compliance: 1e3,
                    gamma: 0.3,
                },
                FamilyConstants {
                    scaled_compliance: 1e4,
                    gamma: 0.0,
                },
                FamilyConstants {
                    scaled_compliance: 1e5,
                    gamma: 0.1,
                },
            ];
            macro_rules! check {
                ($multipliers:literal) => {{
                    let (mut expected, mut expected_lambdas) = (x.clone(), lambdas0.clone());
                    for strip in &grid.strips {
                        let family = families[family_index(strip.kind)];
                        for k in 0..strip.count {
                            let (a, b) = strip.ends(k);
                            let c = strip.first + k;
                            let (mut xa, mut xb) = (expected[a], expected[b]);
                            let project_one = if family.gamma != 0.0 {
                                project::<false, $multipliers, true>
                            } else {
                                project::<false, $multipliers, false>
                            };
                            project_one(
                                &mut xa,
                                &mut xb,
                                previous[a],
                                previous[b],
                                w[a],
                                w[b],
                                rest[c],
                                denominators[c],
                                &mut expected_lambdas[c],
                                family,
                            );
                            (expected[a], expected[b]) = (xa, xb);
                        }
                    }
                    let (mut split, mut previous) = (Xyz::of(&x), Xyz::of(&previous));
                    let mut lambdas = lambdas0.clone();
                    {
                        let positions = split.disjoint();
                        let previous = previous.disjoint();
                        let lambdas = DisjointSlice::new(&mut lambdas);
                        for batch in &grid.batches {
                            // SAFETY: one thread.
                            unsafe {
                                project_strips::<false, $multipliers>(
                                    &grid.strips[batch.clone()],
                                    &positions,
                                    &previous,
                                    &w,
                                    &rest,
                                    &denominators,
                                    &lambdas,
                                    &families,
                                )
                            };
                        }
                    }
                    let mut got = x.clone();
                    split.join_into(&mut got);
                    let bits = |v: &[DVec3]| {
                        v.iter()
                            .map(|p| p.to_array().map(f64::to_bits))
                            .collect::<Vec<_>>()
                    };
                    assert_eq!(
                        bits(&got),
                        bits(&expected),
                        "{columns}×{rows}, multipliers {}",
                        $multipliers
                    );
                    assert_eq!(
                        lambdas.iter().map(|l| l.to_bits()).collect::<Vec<_>>(),
                        expected_lambdas
                            .iter()
                            .map(|l| l.to_bits())
                            .collect::<Vec<_>>()
                    );
                    assert_ne!(bits(&got), bits(&x), "the particles moved");
                }};
            }
            check!(false);
            check!(true);
        }
    }

    /// Ends so close that `1/L²` would overflow count as coincident: nothing moves and nothing turns
    /// infinite or NaN; a little further apart they are pulled towards the rest length, finitely, and a
    /// stretched constraint's multiplier is the same as through the gradient `d/L` (within rounding).
    #[test]
    fn ends_too_close_for_the_squared_length_count_as_coincident() {
        // Near the origin, so that the tiny gaps are not lost to the positions' rounding.
        let start = DVec3::new(1e-300, 0.0, 0.0);
        let project_at = |gap: f64| {
            let (mut a, mut b) = (start, start + DVec3::new(gap, 0.0, 0.0));
            let mut lambda = 0.0;
            let family = FamilyConstants {
                scaled_compliance: 1e-3,
                gamma: 0.2,
            };
            let previous = (a - DVec3::splat(1e-6), b);
            project::<false, true, true>(
                &mut a,
                &mut b,
                previous.0,
                previous.1,
                2.0,
                3.0,
                0.02,
                0.1,
                &mut lambda,
                family,
            );
            (a, b, lambda)
        };
        for gap in [1e-160, 1e-155, 0.0] {
            let (a, b, lambda) = project_at(gap);
            assert_eq!((a, lambda), (start, 0.0), "gap {gap:e}");
            assert!(b.is_finite(), "gap {gap:e}");
        }
        for gap in [1e-150, 1e-3, 0.05] {
            let (a, b, lambda) = project_at(gap);
            assert!(
                a.is_finite() && b.is_finite() && lambda.is_finite(),
                "gap {gap:e}"
            );
            assert_ne!(a, start, "gap {gap:e}: moved");
        }
        // The multiplier's change against eq. (18)/(26) written with the unit gradient.
        let (gap, rest, inverse_denominator) = (0.05, 0.02, 0.1);
        let (_, _, lambda) = project_at(gap);
        let (a, b) = (start, start + DVec3::new(gap, 0.0, 0.0));
        let d = a - b;
        let gradient = d / d.length();
        let moved = DVec3::splat(1e-6);
        let expected = (-(d.length() - rest) - 0.2 * gradient.dot(moved)) * inverse_denominator;
        assert!(
            (lambda - expected).abs() <= 1e-14 * expected.abs(),
            "{lambda} vs {expected}"
        );
    }

    /// Leaving the damping term out changes nothing when the family has none (γ = 0), and something
    /// when it has.
    #[test]
    fn the_undamped_projection_is_the_damped_one_at_zero_damping() {
        let project_with = |damped: bool, gamma: f64| {
            let (mut a, mut b) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.0213, 0.001, -0.002));
            let (start_a, start_b) = (DVec3::new(1e-4, 0.0, 0.0), DVec3::new(0.0208, 0.0, 0.0));
            let family = FamilyConstants {
                scaled_compliance: 1440.0,
                gamma,
            };
            let mut lambda = 2e-6;
            let project = if damped {
                project::<false, true, true>
            } else {
                project::<false, true, false>
            };
            project(
                &mut a,
                &mut b,
                start_a,
                start_b,
                1.6e4,
                1.7e4,
                0.0175,
                1.0 / 3.5e4,
                &mut lambda,
                family,
            );
            (a, b, lambda)
        };
        assert_eq!(project_with(true, 0.0), project_with(false, 0.0));
        assert_ne!(project_with(true, 0.3), project_with(false, 0.3));
    }
}
