//! Dense LU factorisation with partial pivoting (Golub & Van Loan, alg. 3.4.1) for the Nyström system.
//! The systems here are a few hundred to ~2000 unknowns and well conditioned (the scattering operator
//! has norm < 1 for a finite slab), so a plain row-major Doolittle elimination is adequate and keeps the
//! result independent of thread count.

/// An `n × n` matrix factorised in place as `P A = L U` (unit lower `L`).
#[derive(Clone, Debug)]
pub(crate) struct LuFactorisation {
    size: usize,
    factors: Vec<f64>,
    pivots: Vec<usize>,
}

impl LuFactorisation {
    /// Factorises the row-major `size × size` matrix `matrix`. Returns `None` if a pivot is exactly zero
    /// (the matrix is singular to working precision).
    pub(crate) fn new(size: usize, mut matrix: Vec<f64>) -> Option<Self> {
        debug_assert_eq!(matrix.len(), size * size);
        let mut pivots = vec![0; size];
        for column in 0..size {
            let (pivot_row, pivot_value) = (column..size)
                .map(|row| (row, matrix[row * size + column].abs()))
                .fold((column, -1.0), |best, candidate| {
                    if candidate.1 > best.1 {
                        candidate
                    } else {
                        best
                    }
                });
            if pivot_value == 0.0 || !pivot_value.is_finite() {
                return None;
            }
            pivots[column] = pivot_row;
            if pivot_row != column {
                for k in 0..size {
                    matrix.swap(column * size + k, pivot_row * size + k);
                }
            }
            let diagonal = matrix[column * size + column];
            let (upper, lower) = matrix.split_at_mut((column + 1) * size);
            let pivot_row_values = &upper[column * size..(column + 1) * size];
            for row in lower.chunks_exact_mut(size) {
                let multiplier = row[column] / diagonal;
                row[column] = multiplier;
                if multiplier != 0.0 {
                    for k in column + 1..size {
                        row[k] -= multiplier * pivot_row_values[k];
                    }
                }
            }
        }
        Some(Self {
            size,
            factors: matrix,
            pivots,
        })
    }

    /// Solves `A x = b`, overwriting `rhs` with `x`.
    pub(crate) fn solve_in_place(&self, rhs: &mut [f64]) {
        let n = self.size;
        for (column, &pivot) in self.pivots.iter().enumerate() {
            rhs.swap(column, pivot);
        }
        for row in 0..n {
            let factors = &self.factors[row * n..row * n + row];
            let sum = rhs[row]
                - factors
                    .iter()
                    .zip(&rhs[..row])
                    .map(|(l, x)| l * x)
                    .sum::<f64>();
            rhs[row] = sum;
        }
        for row in (0..n).rev() {
            let factors = &self.factors[row * n + row + 1..(row + 1) * n];
            let sum = rhs[row]
                - factors
                    .iter()
                    .zip(&rhs[row + 1..])
                    .map(|(u, x)| u * x)
                    .sum::<f64>();
            rhs[row] = sum / self.factors[row * n + row];
        }
    }
}
