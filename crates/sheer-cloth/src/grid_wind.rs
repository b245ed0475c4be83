//! The wind pass of a grid cloth, one row of cells at a time, written so that the compiler vectorises it.
//!
//! Per sub-step the wind costs one [`aerodynamic_force`](crate::wind::aerodynamic_force) per triangle:
//! two square roots and eight divisions (the mean velocity and the corner share are divided by 3). One
//! triangle at a time, the divider bounds the pass. On a grid the two triangles of cell (row, column)
//! read corners that sit at consecutive indices along a row, so the loop below reads contiguous memory and
//! the compiler turns it into 4- or 8-wide vector arithmetic. The arithmetic per triangle is exactly that
//! of the general path ([`corner_share_of_triangle_force`]), so the results are bit-identical (IEEE 754
//! vector division and square root round like their scalar forms, and Rust never fuses a multiply and an
//! add on its own).
//!
//! The loop is compiled once per instruction set and picked at run time (x86-64: AVX-512, AVX2, or the
//! baseline SSE2), so one binary runs on any x86-64 machine.

use std::ops::Range;

use glam::DVec3;
use rayon::prelude::*;

use crate::model::GridShape;
use crate::params::Wind;
use crate::wind::corner_share_of_triangle_force;

/// Writes each triangle's corner share of its aerodynamic force (N) into `out`, indexed like
/// [`GridShape::triangles`]. Rows of cells are shared among rayon's threads when `parallel`.
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
    let rows = |first_row: usize, out: &mut [[DVec3; 2]]| {
        let rows = first_row..first_row + out.len() / cells_per_row;
        cell_rows_dispatch(
            shape.columns,
            wind,
            air_velocity,
            positions,
            velocities,
            rows,
            out,
        );
    };
    if parallel {
        // Eight rows of cells per task: enough work to cover rayon's hand-off.
        const ROWS_PER_TASK: usize = 8;
        out.par_chunks_mut(ROWS_PER_TASK * cells_per_row)
            .enumerate()
            .for_each(|(task, out)| rows(task * ROWS_PER_TASK, out));
    } else {
        rows(0, out);
    }
}

/// Runs [`cell_rows`] compiled for the widest vector instructions the CPU has.
fn cell_rows_dispatch(
    columns: usize,
    wind: &Wind,
    air_velocity: DVec3,
    positions: &[DVec3],
    velocities: &[DVec3],
    rows: Range<usize>,
    out: &mut [[DVec3; 2]],
) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU has AVX-512F, checked just above.
            return unsafe {
                cell_rows_avx512(
                    columns,
                    wind,
                    air_velocity,
                    positions,
                    velocities,
                    rows,
                    out,
                )
            };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe {
                cell_rows_avx2(
                    columns,
                    wind,
                    air_velocity,
                    positions,
                    velocities,
                    rows,
                    out,
                )
            };
        }
    }
    cell_rows(
        columns,
        wind,
        air_velocity,
        positions,
        velocities,
        rows,
        out,
    )
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn cell_rows_avx512(
    columns: usize,
    wind: &Wind,
    air_velocity: DVec3,
    positions: &[DVec3],
    velocities: &[DVec3],
    rows: Range<usize>,
    out: &mut [[DVec3; 2]],
) {
    cell_rows(
        columns,
        wind,
        air_velocity,
        positions,
        velocities,
        rows,
        out,
    )
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn cell_rows_avx2(
    columns: usize,
    wind: &Wind,
    air_velocity: DVec3,
    positions: &[DVec3],
    velocities: &[DVec3],
    rows: Range<usize>,
    out: &mut [[DVec3; 2]],
) {
    cell_rows(
        columns,
        wind,
        air_velocity,
        positions,
        velocities,
        rows,
        out,
    )
}

/// The corner shares of the triangles of the cells in `rows` (rows of cells, not of particles), into
/// `out` (two triangles per cell, cells row by row).
#[inline(always)]
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
        // An index loop over exact-length slices: the form the vectoriser recognises (an iterator over
        // `out` alone leaves bounds checks on `left + 1` and measured 30 % slower overall).
        #[allow(clippy::needless_range_loop)]
        for left in 0..cells {
            let right = left + 1;
            // Same corners and order as `GridShape::triangles`.
            out[left] = [
                corner_share_of_triangle_force(
                    wind,
                    [top_x[left], bottom_x[left], bottom_x[right]],
                    [top_v[left], bottom_v[left], bottom_v[right]],
                    air_velocity,
                ),
                corner_share_of_triangle_force(
                    wind,
                    [top_x[left], bottom_x[right], top_x[right]],
                    [top_v[left], bottom_v[right], top_v[right]],
                    air_velocity,
                ),
            ];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The row-wise pass (in whichever instruction set this CPU runs it) gives the same bits as the
    /// general per-triangle path, including degenerate triangles and triangles at rest in the air.
    #[test]
    fn the_row_wise_pass_matches_the_per_triangle_force_bit_for_bit() {
        let shape = GridShape {
            columns: 19,
            rows: 7,
        };
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
        positions[shape.index(2, 4)] = positions[shape.index(3, 4)];
        positions[shape.index(2, 5)] = positions[shape.index(3, 4)];
        positions[shape.index(3, 5)] = positions[shape.index(3, 4)];
        for (row, column) in [(4, 9), (4, 10), (5, 9), (5, 10)] {
            velocities[shape.index(row, column)] = air;
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
            expected.contains(&DVec3::ZERO),
            "a degenerate case is covered"
        );
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
