//! The wind pass of a grid cloth, one row of cells at a time, written so that the compiler vectorises it.
//!
//! Per sub-step the wind costs one [`aerodynamic_force`](crate::wind::aerodynamic_force) per triangle:
//! one square root, one division and about forty other operations (the mean velocity and the corner
//! share are multiplied by a third). One triangle at a time, the divider bounds the pass. On a grid the two triangles of cell (row, column)
//! read corners that sit at consecutive indices along a row, so the loop below reads contiguous memory and
//! the compiler turns it into 4- or 8-wide vector arithmetic. The arithmetic per triangle is exactly that
//! of the general path ([`corner_share_of_triangle_force`]), so the results are bit-identical (IEEE 754
//! vector division and square root round like their scalar forms, and Rust never fuses a multiply and an
//! add on its own).
//!
//! The loop is compiled once per instruction set and picked at run time ([`by_cpu!`]). The shares are then
//! added to the particles row by row too ([`add_grid_triangle_forces`]), each particle taking its six
//! triangles in ascending order, as the general path's scatter does.
//!
//! The position-based methods keep their state split by component (`components.rs`), and have their own
//! copies of these passes ([`split_cell_rows`], [`predict_row_with_forces`]): the same arithmetic on each
//! component, into shares split the same way ([`SplitShares`]), so that neither the cells nor the sums
//! transpose 24-byte vectors with permutes (the sums had been almost nothing but permutes: 162 of 216
//! vector operations, `perf annotate`). Tested bit for bit against the joined passes.

use std::ops::Range;

use crate::fast::components::{Xyz, XyzMut, XyzRef};
use crate::fast::parallel::{DisjointSlice, parts};
use crate::fast::vectorise::by_cpu;
use crate::model::GridShape;
use crate::params::Wind;
use crate::wind::corner_share_of_triangle_force;
use glam::DVec3;

/// Writes each triangle's corner share of its aerodynamic force (N) into `out`, indexed like
/// [`GridShape::triangles`]. Rows of cells are shared among the threads when `parallel` ([`parts`]).
pub(crate) fn grid_triangle_forces(
    shape: GridShape,
    wind: &Wind,
    air_velocity: DVec3,
    positions: &[DVec3],
    velocities: &[DVec3],
    out: &mut [DVec3],
    parallel: bool,
) {
    let cells_per_row = shape.columns - 1;
    let (out, _) = out.as_chunks_mut::<2>();
    assert_eq!(out.len(), cells_per_row * (shape.rows - 1));
    let out = DisjointSlice::new(out);
    // Eight rows of cells per rayon task: enough work to cover rayon's hand-off.
    parts(shape.rows - 1, parallel, 8, |rows| {
        // SAFETY: the parts of the rows are disjoint, so are their cells.
        let out = unsafe { out.slice_mut(rows.start * cells_per_row..rows.end * cells_per_row) };
        cell_rows(
            shape.columns,
            wind,
            air_velocity,
            positions,
            velocities,
            rows,
            out,
        );
    });
}

/// The cells above and below particle row `row` of a grid of `rows` particle rows (those that exist):
/// cell rows `row − 1` and `row`, each as `cell_row` gives it (the shares of that row's cells, joined or
/// split).
pub(crate) fn cells_around<T>(
    rows: usize,
    row: usize,
    cell_row: impl Fn(usize) -> T,
) -> [Option<T>; 2] {
    [
        row.checked_sub(1).map(&cell_row),
        (row + 1 < rows).then(|| cell_row(row)),
    ]
}

/// Cells per block of the wind pass: eight `f64` lanes of AVX-512.
const CELL_BLOCK: usize = 8;

/// The first cells of the blocks of a row of `cells` cells (at least [`CELL_BLOCK`]): whole blocks, the
/// last overlapping the one before it where the row does not fill it (a cell's shares are a pure
/// function of the state, so computing a few twice gives the same bits).
fn cell_block_starts(cells: usize) -> impl Iterator<Item = usize> {
    (0..cells - CELL_BLOCK)
        .step_by(CELL_BLOCK)
        .chain([cells - CELL_BLOCK])
}

/// The corner shares of the two triangles of one cell, from the positions and velocities of its
/// corners, `[left, right]` on its top and bottom rows; same corners and order as
/// [`GridShape::triangles`].
#[inline(always)]
fn cell(
    wind: &Wind,
    air_velocity: DVec3,
    [top_left, top_right]: [DVec3; 2],
    [bottom_left, bottom_right]: [DVec3; 2],
    [top_left_v, top_right_v]: [DVec3; 2],
    [bottom_left_v, bottom_right_v]: [DVec3; 2],
) -> [DVec3; 2] {
    [
        corner_share_of_triangle_force(
            wind,
            [top_left, bottom_left, bottom_right],
            [top_left_v, bottom_left_v, bottom_right_v],
            air_velocity,
        ),
        corner_share_of_triangle_force(
            wind,
            [top_left, bottom_right, top_right],
            [top_left_v, bottom_right_v, top_right_v],
            air_velocity,
        ),
    ]
}

by_cpu! {
    /// The corner shares of the triangles of the cells in `rows` (rows of cells, not of particles), into
    /// `out` (two triangles per cell, cells row by row).
    fn cell_rows(
        columns: usize,
        wind: &Wind,
        air_velocity: DVec3,
        positions: &[DVec3],
        velocities: &[DVec3],
        rows: Range<usize>,
        out: &mut [[DVec3; 2]],
    ) {
        let cells = columns - 1;
        for (row, out) in rows.zip(out.chunks_exact_mut(cells)) {
            let top = row * columns;
            let bottom = top + columns;
            // Exact-length slices let the compiler drop the bounds checks inside the loop.
            let (top_x, bottom_x) = (
                &positions[top..top + columns],
                &positions[bottom..bottom + columns],
            );
            let (top_v, bottom_v) = (
                &velocities[top..top + columns],
                &velocities[bottom..bottom + columns],
            );
            // Blocks of `CELL_BLOCK` cells, each a loop of known length over arrays of known length, which
            // the vectoriser turns into straight vector code. A row's cells rarely fill whole blocks (the
            // default flag has 63), and a loop's scalar remainder cost a third of the pass (`perf
            // annotate`); the cells are a pure function of the positions and velocities, so the last
            // block instead overlaps the one before it and recomputes a few cells, to the same bits.
            if cells < CELL_BLOCK {
                for left in 0..cells {
                    out[left] = cell(
                        wind,
                        air_velocity,
                        [top_x[left], top_x[left + 1]],
                        [bottom_x[left], bottom_x[left + 1]],
                        [top_v[left], top_v[left + 1]],
                        [bottom_v[left], bottom_v[left + 1]],
                    );
                }
                continue;
            }
            for start in cell_block_starts(cells) {
                let corners = |row: &[DVec3]| -> [DVec3; CELL_BLOCK + 1] {
                    row[start..start + CELL_BLOCK + 1].try_into().unwrap()
                };
                let (tx, bx, tv, bv) = (
                    corners(top_x),
                    corners(bottom_x),
                    corners(top_v),
                    corners(bottom_v),
                );
                let out: &mut [[DVec3; 2]; CELL_BLOCK] =
                    (&mut out[start..start + CELL_BLOCK]).try_into().unwrap();
                for k in 0..CELL_BLOCK {
                    out[k] = cell(
                        wind,
                        air_velocity,
                        [tx[k], tx[k + 1]],
                        [bx[k], bx[k + 1]],
                        [tv[k], tv[k + 1]],
                        [bv[k], bv[k + 1]],
                    );
                }
            }
        }
    }
}

/// Gravity and air damping on each particle, `m (g − c v)` (N), the force every particle starts from.
pub(crate) struct BodyForce<'a> {
    /// Particle masses (kg).
    pub masses: &'a [f64],
    /// Particle velocities (m/s).
    pub velocities: &'a [DVec3],
    /// Gravitational acceleration (m/s²).
    pub gravity: DVec3,
    /// Air damping rate `c` (1/s).
    pub air_damping: f64,
}

/// Adds each triangle's corner share in `shares` (indexed like [`GridShape::triangles`]) to its three
/// corners' entries of `forces`. Each particle takes its (up to six) triangles in ascending triangle
/// order, the order in which the general path scatters them, so the sums are the same bits. With `body`,
/// each row of `forces` is first set to the body force, in the same pass (the sum starts from it, as the
/// general path's does).
pub(crate) fn add_grid_triangle_forces(
    shape: GridShape,
    shares: &[DVec3],
    forces: &mut [DVec3],
    parallel: bool,
    body: Option<&BodyForce<'_>>,
) {
    let columns = shape.columns;
    assert_eq!(forces.len(), columns * shape.rows);
    let (cells, _) = shares.as_chunks::<2>();
    let cells_per_row = columns - 1;
    assert_eq!(cells.len(), cells_per_row * (shape.rows - 1));
    let cell_row = |r: usize| &cells[r * cells_per_row..(r + 1) * cells_per_row];
    let forces = DisjointSlice::new(forces);
    parts(shape.rows, parallel, 8, |rows| {
        for r in rows {
            let particles = r * columns..(r + 1) * columns;
            // SAFETY: the parts of the rows are disjoint.
            let forces = unsafe { forces.slice_mut(particles.clone()) };
            let around = cells_around(shape.rows, r, cell_row);
            match body {
                Some(body) => row_forces(
                    Some(around),
                    &body.masses[particles.clone()],
                    &body.velocities[particles],
                    body.gravity,
                    body.air_damping,
                    forces,
                ),
                None => add_to_particle_row(around[0], around[1], forces),
            }
        }
    });
}

/// The forces on one particle row (N) into `forces`: the body force `m (g − c v)` from the row's
/// `masses` (kg) and `velocities` (m/s), gravity (m/s²) and air damping (1/s), plus, with `cells`, the
/// corner shares of the triangles of the cell rows above and below it ([`cells_around`]) in ascending
/// triangle order — what [`add_grid_triangle_forces`] with a body force gives that row.
pub(crate) fn row_forces(
    cells: Option<[Option<&[[DVec3; 2]]>; 2]>,
    masses: &[f64],
    velocities: &[DVec3],
    gravity: DVec3,
    air_damping: f64,
    forces: &mut [DVec3],
) {
    body_force_row(masses, velocities, gravity, air_damping, forces);
    if let Some([above, below]) = cells {
        add_to_particle_row(above, below, forces);
    }
}

by_cpu! {
    /// `forces[i] = m_i (g − c v_i)` (N) over one row; see [`BodyForce`].
    fn body_force_row(
        masses: &[f64],
        velocities: &[DVec3],
        gravity: DVec3,
        air_damping: f64,
        forces: &mut [DVec3],
    ) {
        let n = forces.len();
        let (masses, velocities) = (&masses[..n], &velocities[..n]);
        for i in 0..n {
            forces[i] = masses[i] * (gravity - air_damping * velocities[i]);
        }
    }
}

/// The triangles of cell row `above` (if any) then `below` (if any) that touch particle `column`, in
/// ascending order: the cell above-left's two, the cell above's first, the cell below-left's second, the
/// cell below's two (see [`GridShape::triangles`] for which corners each triangle has).
#[inline(always)]
fn add_at_particle(
    force: &mut DVec3,
    column: usize,
    above: Option<&[[DVec3; 2]]>,
    below: Option<&[[DVec3; 2]]>,
    has_left: bool,
    has_right: bool,
) {
    if let Some(above) = above {
        if has_left {
            *force += above[column - 1][0];
            *force += above[column - 1][1];
        }
        if has_right {
            *force += above[column][0];
        }
    }
    if let Some(below) = below {
        if has_left {
            *force += below[column - 1][1];
        }
        if has_right {
            *force += below[column][0];
            *force += below[column][1];
        }
    }
}

by_cpu! {
    /// One particle row of [`add_grid_triangle_forces`]: the end particles apart, so that the loop over
    /// the interior has no conditions and vectorises.
    fn add_to_particle_row(
        above: Option<&[[DVec3; 2]]>,
        below: Option<&[[DVec3; 2]]>,
        forces: &mut [DVec3],
    ) {
        let last = forces.len() - 1;
        // Rows of `last` cells: with that length known, the interior loop needs no bounds checks.
        let (above, below) = (above.map(|a| &a[..last]), below.map(|b| &b[..last]));
        add_at_particle(&mut forces[0], 0, above, below, false, true);
        // An index loop: the neighbours' cells are indexed around `column` (see `cell_rows`).
        #[allow(clippy::needless_range_loop)]
        for column in 1..last {
            add_at_particle(&mut forces[column], column, above, below, true, true);
        }
        add_at_particle(&mut forces[last], last, above, below, true, false);
    }
}

/// The corner shares of a grid's cells split by component, for the position-based methods, whose state
/// is split the same way (`components.rs`): `[first, second]`, the first and the second triangle of
/// every cell ([`GridShape::triangles`]), indexed by cell. A particle's six triangles are then at the
/// same index or one before it in four arrays (see [`add_at_particle`]), so their sums read contiguous
/// memory with no permutes.
pub(crate) type SplitShares = [Xyz; 2];

/// [`grid_triangle_forces`] on the split state, into split shares.
pub(crate) fn split_grid_triangle_forces(
    shape: GridShape,
    wind: &Wind,
    air_velocity: DVec3,
    positions: XyzRef<'_>,
    velocities: XyzRef<'_>,
    shares: &mut SplitShares,
    parallel: bool,
) {
    let cells_per_row = shape.columns - 1;
    assert_eq!(shares[0].len(), cells_per_row * (shape.rows - 1));
    assert_eq!(shares[1].len(), shares[0].len());
    let [first, second] = shares.each_mut().map(|s| s.disjoint());
    // Eight rows of cells per rayon task: enough work to cover rayon's hand-off.
    parts(shape.rows - 1, parallel, 8, |rows| {
        let cells = rows.start * cells_per_row..rows.end * cells_per_row;
        // SAFETY: the parts of the rows are disjoint, so are their cells.
        let (first, second) = unsafe { (first.slice_mut(cells.clone()), second.slice_mut(cells)) };
        split_cell_rows(
            shape.columns,
            wind,
            air_velocity,
            positions,
            velocities,
            rows,
            first,
            second,
        );
    });
}

/// Consecutive rows of [`split_grid_triangle_forces`], for a caller that shares the rows out itself: the
/// shares of `cell_rows` cell rows from the `cell_rows + 1` particle rows they join (`positions` and
/// `velocities` hold those rows), into those rows' cells of `first` and `second`. In one call rather than
/// one a row: the run-time dispatch and the set-up of each call had been paid per row.
#[allow(clippy::too_many_arguments)]
pub(crate) fn split_cell_run(
    columns: usize,
    cell_rows: usize,
    wind: &Wind,
    air_velocity: DVec3,
    positions: XyzRef<'_>,
    velocities: XyzRef<'_>,
    first: XyzMut<'_>,
    second: XyzMut<'_>,
) {
    split_cell_rows(
        columns,
        wind,
        air_velocity,
        positions,
        velocities,
        0..cell_rows,
        first,
        second,
    );
}

by_cpu! {
    /// [`cell_rows`] on the split state: the shares of the cells in `rows`, into `first` and `second`
    /// (those rows' cells), in blocks of eight cells as there, each component read and written with plain
    /// vector loads and stores.
    fn split_cell_rows(
        columns: usize,
        wind: &Wind,
        air_velocity: DVec3,
        positions: XyzRef<'_>,
        velocities: XyzRef<'_>,
        rows: Range<usize>,
        first: XyzMut<'_>,
        second: XyzMut<'_>,
    ) {
        let cells = columns - 1;
        let XyzMut { x: first_x, y: first_y, z: first_z } = first;
        let XyzMut { x: second_x, y: second_y, z: second_z } = second;
        for (r, row) in rows.enumerate() {
            let top = row * columns;
            let bottom = top + columns;
            let (top_x, bottom_x) = (
                positions.range(top..top + columns),
                positions.range(bottom..bottom + columns),
            );
            let (top_v, bottom_v) = (
                velocities.range(top..top + columns),
                velocities.range(bottom..bottom + columns),
            );
            let out = r * cells;
            if cells < CELL_BLOCK {
                for left in 0..cells {
                    let [a, b] = cell(
                        wind,
                        air_velocity,
                        [top_x.at(left), top_x.at(left + 1)],
                        [bottom_x.at(left), bottom_x.at(left + 1)],
                        [top_v.at(left), top_v.at(left + 1)],
                        [bottom_v.at(left), bottom_v.at(left + 1)],
                    );
                    let i = out + left;
                    (first_x[i], first_y[i], first_z[i]) = (a.x, a.y, a.z);
                    (second_x[i], second_y[i], second_z[i]) = (b.x, b.y, b.z);
                }
                continue;
            }
            for start in cell_block_starts(cells) {
                let corners = |v: XyzRef<'_>| {
                    let block = |c: &[f64], from: usize| -> [f64; CELL_BLOCK] {
                        c[from..from + CELL_BLOCK].try_into().unwrap()
                    };
                    BlockCorners {
                        left: [block(v.x, start), block(v.y, start), block(v.z, start)],
                        right: [block(v.x, start + 1), block(v.y, start + 1), block(v.z, start + 1)],
                    }
                };
                let (tx, bx, tv, bv) = (
                    corners(top_x),
                    corners(bottom_x),
                    corners(top_v),
                    corners(bottom_v),
                );
                let [first, second] = split_cell_block(wind, air_velocity, tx, bx, tv, bv);
                let o = out + start..out + start + CELL_BLOCK;
                first_x[o.clone()].copy_from_slice(&first[0]);
                first_y[o.clone()].copy_from_slice(&first[1]);
                first_z[o.clone()].copy_from_slice(&first[2]);
                second_x[o.clone()].copy_from_slice(&second[0]);
                second_y[o.clone()].copy_from_slice(&second[1]);
                second_z[o].copy_from_slice(&second[2]);
            }
        }
    }
}

/// One row's corners of a block of cells, by component: the left corners of the block's cells and their
/// right corners (the same run of particles, one further on).
///
/// As two arrays rather than one of `CELL_BLOCK + 1`: the right corners were then read from the local
/// copy one element on, a vector load straddling two of the copy's stores, which the CPU cannot forward
/// from a store and waits out (the loads after the copies took a fifth of the wind pass's samples, `perf
/// annotate` of `fingerprint time 64x46 1 3000`).
struct BlockCorners {
    left: [[f64; CELL_BLOCK]; 3],
    right: [[f64; CELL_BLOCK]; 3],
}

/// The shares of a block of cells from its corners (`[x, y, z]` of the top and bottom rows' positions
/// and velocities): `[first, second]` triangles' `[x, y, z]`. On arrays of its own, so that the compiler
/// vectorises it across the block.
#[inline(always)]
fn split_cell_block(
    wind: &Wind,
    air_velocity: DVec3,
    top_x: BlockCorners,
    bottom_x: BlockCorners,
    top_v: BlockCorners,
    bottom_v: BlockCorners,
) -> [[[f64; CELL_BLOCK]; 3]; 2] {
    let at = |c: &[[f64; CELL_BLOCK]; 3], k: usize| DVec3::new(c[0][k], c[1][k], c[2][k]);
    let mut shares = [[[0.0; CELL_BLOCK]; 3]; 2];
    // An index loop: the corners are indexed around `k`, as in `cell_rows`.
    #[allow(clippy::needless_range_loop)]
    for k in 0..CELL_BLOCK {
        let [a, b] = cell(
            wind,
            air_velocity,
            [at(&top_x.left, k), at(&top_x.right, k)],
            [at(&bottom_x.left, k), at(&bottom_x.right, k)],
            [at(&top_v.left, k), at(&top_v.right, k)],
            [at(&bottom_v.left, k), at(&bottom_v.right, k)],
        );
        for c in 0..3 {
            shares[0][c][k] = a[c];
            shares[1][c][k] = b[c];
        }
    }
    shares
}

/// One component of a cell row's `[first, second]` shares, `None` where there is no such row.
type CellRowShares<'a> = [Option<&'a [f64]>; 2];

/// One component of [`add_at_particle`]: `force` plus the `[first, second]` shares of the cell rows
/// above and below. Summed in a local and returned rather than added into the force in place: through
/// `&mut f64` each addition was stored and loaded again (a bounds check's panic between two would see
/// the force), a chain of store-to-load forwards that made the sums 10 % of the default flag's frame.
#[inline(always)]
fn add_component_at_particle(
    force: f64,
    column: usize,
    [above_first, above_second]: CellRowShares<'_>,
    [below_first, below_second]: CellRowShares<'_>,
    has_left: bool,
    has_right: bool,
) -> f64 {
    let mut force = force;
    if let (Some(first), Some(second)) = (above_first, above_second) {
        if has_left {
            force += first[column - 1];
            force += second[column - 1];
        }
        if has_right {
            force += first[column];
        }
    }
    if let (Some(first), Some(second)) = (below_first, below_second) {
        if has_left {
            force += second[column - 1];
        }
        if has_right {
            force += first[column];
            force += second[column];
        }
    }
    force
}

/// The prediction of one row with its forces summed on the way (the joined [`row_forces`] followed by
/// the prediction, `fast::grid_step::predict_components`, in one loop per component: the same operations
/// in the same order, so the same bits): the row's body force plus, with `cells`, the wind's shares of the
/// cell rows above and below; then `v += h w f`, the start position kept, `x += h v`.
///
/// Summed into a row of scratch and predicted from it in a second loop, the sums had cost 11 % of the
/// default flag's frame and the prediction 6 %, plus the scratch's thread-local look-up (`perf record -e
/// cpu-clock` of `fingerprint time 64x46 1 3000`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn predict_row_with_forces(
    h: f64,
    cells: Option<[Option<[XyzRef<'_>; 2]>; 2]>,
    masses: &[f64],
    inverse_masses: &[f64],
    gravity: DVec3,
    air_damping: f64,
    positions: XyzMut<'_>,
    velocities: XyzMut<'_>,
    previous: XyzMut<'_>,
) {
    fn component<'a>(shares: Option<[XyzRef<'a>; 2]>, c: usize) -> [Option<&'a [f64]>; 2] {
        shares.map_or([None; 2], |pair| pair.map(|s| Some([s.x, s.y, s.z][c])))
    }
    let [above, below] = cells.unwrap_or([None, None]);
    let XyzMut {
        x: x_x,
        y: x_y,
        z: x_z,
    } = positions;
    let XyzMut {
        x: v_x,
        y: v_y,
        z: v_z,
    } = velocities;
    let XyzMut {
        x: p_x,
        y: p_y,
        z: p_z,
    } = previous;
    let gravity = gravity.to_array();
    for (c, (x, v, p)) in [(x_x, v_x, p_x), (x_y, v_y, p_y), (x_z, v_z, p_z)]
        .into_iter()
        .enumerate()
    {
        let [above_first, above_second] = component(above, c);
        let [below_first, below_second] = component(below, c);
        predict_component_with_forces(
            h,
            masses,
            inverse_masses,
            gravity[c],
            air_damping,
            above_first,
            above_second,
            below_first,
            below_second,
            x,
            v,
            p,
        );
    }
}

by_cpu! {
    /// One component of [`predict_row_with_forces`]: the force as [`row_forces`] sums it (component by
    /// component), then the prediction as `predict_components` makes it.
    fn predict_component_with_forces(
        h: f64,
        masses: &[f64],
        inverse_masses: &[f64],
        gravity: f64,
        air_damping: f64,
        above_first: Option<&[f64]>,
        above_second: Option<&[f64]>,
        below_first: Option<&[f64]>,
        below_second: Option<&[f64]>,
        x: &mut [f64],
        v: &mut [f64],
        previous: &mut [f64],
    ) {
        let n = x.len();
        let last = n - 1;
        let (masses, inverse_masses) = (&masses[..n], &inverse_masses[..n]);
        // Rows of `last` cells: with that length known, the interior loop needs no bounds checks.
        let above = [above_first.map(|s| &s[..last]), above_second.map(|s| &s[..last])];
        let below = [below_first.map(|s| &s[..last]), below_second.map(|s| &s[..last])];
        let (x, v, previous) = (&mut x[..n], &mut v[..n], &mut previous[..n]);
        // Through a function rather than a closure, which the compiler called per particle.
        let cells = (above, below);
        let ends = (h, gravity, air_damping);
        predict_particle(0, [false, true], ends, masses, inverse_masses, cells, x, v, previous);
        for i in 1..last {
            predict_particle(i, [true, true], ends, masses, inverse_masses, cells, x, v, previous);
        }
        predict_particle(last, [true, false], ends, masses, inverse_masses, cells, x, v, previous);
    }
}

/// Particle `i` of [`predict_component_with_forces`]: its force (its body force, then its shares, as
/// [`row_forces`] adds them, `[has_left, has_right]` saying which cells it has), then
/// its prediction as `predict_components` makes it (`h * w * f`: glam's scalar times vector, component
/// by component): the start position kept, `v += h w f`, `x += h v`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn predict_particle(
    i: usize,
    [has_left, has_right]: [bool; 2],
    (h, gravity, air_damping): (f64, f64, f64),
    masses: &[f64],
    inverse_masses: &[f64],
    (above, below): (CellRowShares<'_>, CellRowShares<'_>),
    x: &mut [f64],
    v: &mut [f64],
    previous: &mut [f64],
) {
    let body = masses[i] * (gravity - air_damping * v[i]);
    let force = add_component_at_particle(body, i, above, below, has_left, has_right);
    let start = x[i];
    previous[i] = start;
    let velocity = v[i] + h * inverse_masses[i] * force;
    v[i] = velocity;
    x[i] = start + h * velocity;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fast::components::Xyz;

    /// The row-wise pass (in whichever instruction set this CPU runs it) gives the same bits as the
    /// general per-triangle path, including degenerate triangles and triangles at rest in the air.
    #[test]
    fn the_row_wise_pass_matches_the_per_triangle_force_bit_for_bit() {
        // 18 cells a row (two blocks of eight and an overlapping last one), 8 (one block) and 5 (fewer
        // than a block).
        for (columns, rows) in [(19, 7), (9, 3), (6, 4)] {
            check_row_wise_pass(GridShape { columns, rows });
        }
    }

    fn check_row_wise_pass(shape: GridShape) {
        let degenerate_cases = shape.columns >= 11 && shape.rows >= 6;
        let n = shape.columns * shape.rows;
        // A crumpled sheet: deterministic pseudo-random offsets.
        let jitter = |i: usize, k: u64| {
            let mut z = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ k;
            z = (z ^ (z >> 31)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut positions: Vec<DVec3> = (0..n)
            .map(|i| {
                let (row, column) = (i / shape.columns, i % shape.columns);
                DVec3::new(0.02 * column as f64, -0.02 * (row as f64), 0.0)
                    + 0.01 * DVec3::new(jitter(i, 1), jitter(i, 2), jitter(i, 3))
            })
            .collect();
        let air = DVec3::new(6.0, 0.5, 1.0);
        let mut velocities: Vec<DVec3> = (0..n)
            .map(|i| 2.0 * DVec3::new(jitter(i, 4), jitter(i, 5), jitter(i, 6)))
            .collect();
        // Degenerate cells: three coincident corners; a cell moving with the air.
        if degenerate_cases {
            positions[shape.index(2, 4)] = positions[shape.index(3, 4)];
            positions[shape.index(2, 5)] = positions[shape.index(3, 4)];
            positions[shape.index(3, 5)] = positions[shape.index(3, 4)];
            for (row, column) in [(4, 9), (4, 10), (5, 9), (5, 10)] {
                velocities[shape.index(row, column)] = air;
            }
        }
        let wind = Wind {
            velocity: air,
            ..Wind::default()
        };
        let triangles = shape.triangles();
        let expected: Vec<DVec3> = triangles
            .iter()
            .map(|t| {
                corner_share_of_triangle_force(
                    &wind,
                    t.map(|i| positions[i as usize]),
                    t.map(|i| velocities[i as usize]),
                    air,
                )
            })
            .collect();
        assert!(
            !degenerate_cases || expected.contains(&DVec3::ZERO),
            "a degenerate case is covered"
        );
        // The split path, into split shares, and the split row forces against the joined ones.
        let (split_x, split_v) = (Xyz::of(&positions), Xyz::of(&velocities));
        let cell_count = triangles.len() / 2;
        for parallel in [false, true] {
            let mut shares = [
                Xyz::of(&vec![DVec3::NAN; cell_count]),
                Xyz::of(&vec![DVec3::NAN; cell_count]),
            ];
            split_grid_triangle_forces(
                shape,
                &wind,
                air,
                split_x.as_ref(),
                split_v.as_ref(),
                &mut shares,
                parallel,
            );
            let [first, second] = shares.each_ref().map(Xyz::to_vec3s);
            for (t, want) in expected.iter().enumerate() {
                let got = [first[t / 2], second[t / 2]][t % 2];
                assert_eq!(
                    got.to_array().map(f64::to_bits),
                    want.to_array().map(f64::to_bits),
                    "triangle {t}, split, parallel {parallel}"
                );
            }
            let joined_cells: Vec<[DVec3; 2]> =
                first.iter().zip(&second).map(|(&a, &b)| [a, b]).collect();
            let cells_per_row = shape.columns - 1;
            let masses: Vec<f64> = (0..n).map(|i| 1e-4 * (1.0 + jitter(i, 7))).collect();
            let gravity = DVec3::new(0.1, -9.81, 0.2);
            for row in 0..shape.rows {
                let particles = row * shape.columns..(row + 1) * shape.columns;
                let joined_row =
                    |r: usize| &joined_cells[r * cells_per_row..(r + 1) * cells_per_row];
                let split_row = |r: usize| {
                    shares
                        .each_ref()
                        .map(|s| s.as_ref().range(r * cells_per_row..(r + 1) * cells_per_row))
                };
                for with_cells in [false, true] {
                    let mut want = vec![DVec3::NAN; shape.columns];
                    row_forces(
                        with_cells.then(|| cells_around(shape.rows, row, joined_row)),
                        &masses[particles.clone()],
                        &velocities[particles.clone()],
                        gravity,
                        0.3,
                        &mut want,
                    );
                    // The prediction from those forces, as the joined path makes it.
                    let (h, inverse_masses) =
                        (1e-3, masses.iter().map(|m| 1.0 / m).collect::<Vec<_>>());
                    let start = &positions[particles.clone()];
                    let mut velocity = velocities[particles.clone()].to_vec();
                    let mut predicted = start.to_vec();
                    for (k, f) in want.iter().enumerate() {
                        velocity[k] += h * inverse_masses[particles.start + k] * *f;
                        predicted[k] = start[k] + h * velocity[k];
                    }
                    let (mut x, mut v) = (Xyz::of(start), Xyz::of(&velocities[particles.clone()]));
                    let mut kept = Xyz::zeros(shape.columns);
                    predict_row_with_forces(
                        h,
                        with_cells.then(|| cells_around(shape.rows, row, split_row)),
                        &masses[particles.clone()],
                        &inverse_masses[particles.clone()],
                        gravity,
                        0.3,
                        x.as_mut(),
                        v.as_mut(),
                        kept.as_mut(),
                    );
                    let bits = |v: &[DVec3]| {
                        v.iter()
                            .map(|f| f.to_array().map(f64::to_bits))
                            .collect::<Vec<_>>()
                    };
                    let case = format!("row {row}, cells {with_cells}");
                    assert_eq!(bits(&x.to_vec3s()), bits(&predicted), "{case}: positions");
                    assert_eq!(bits(&v.to_vec3s()), bits(&velocity), "{case}: velocities");
                    assert_eq!(
                        bits(&kept.to_vec3s()),
                        bits(start),
                        "{case}: start positions"
                    );
                }
            }
        }
        for parallel in [false, true] {
            let mut out = vec![DVec3::NAN; triangles.len()];
            grid_triangle_forces(
                shape,
                &wind,
                air,
                &positions,
                &velocities,
                &mut out,
                parallel,
            );
            for (t, (got, want)) in out.iter().zip(&expected).enumerate() {
                assert_eq!(
                    got.to_array().map(f64::to_bits),
                    want.to_array().map(f64::to_bits),
                    "triangle {t}, parallel {parallel}"
                );
            }
        }
    }
}
