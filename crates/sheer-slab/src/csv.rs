//! CSV evaluator behind `sheer slab`: reads rows `tau1,albedo,mu0,mu` and writes
//! `tau1,albedo,mu0,mu,alpha,l_plus,l_minus`, the direct transmission (eq. 9's α) and the single-scattered
//! radiances of eqs. (4) and (5) in W/(m²·sr) for a beam of unit irradiance normal to the beam (1 W/m²),
//! inserted into eqs. (4)–(5) according to an [`IrradianceConvention`] (paper-literal: `E(0) = μ0`).
//! With [`Scattering::AllOrders`] (`sheer slab --model all-orders`) `l_plus` and `l_minus` are the
//! all-orders diffuse radiances instead: eqs. (4)/(5) plus the table's multiply-scattered part.
//!
//! Input: an optional header line `tau1,albedo,mu0,mu` first; blank lines are skipped; fields may carry
//! surrounding spaces. Numbers are written with Rust's shortest round-trip formatting.

use std::io::{BufRead, Write};

use thiserror::Error;

use crate::all_orders::{Scattering, diffuse_radiance};
use crate::model::{
    Albedo, Cosine, Face, IrradianceConvention, OpticalThickness, SlabParameterError,
    direct_transmission,
};

/// The header accepted on input and always written on output (input columns).
pub const INPUT_HEADER: &str = "tau1,albedo,mu0,mu";
/// The header written on output.
pub const OUTPUT_HEADER: &str = "tau1,albedo,mu0,mu,alpha,l_plus,l_minus";

/// What is wrong with one row.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum RowProblem {
    /// Not exactly four comma-separated fields.
    #[error("expected 4 comma-separated columns (tau1,albedo,mu0,mu), found {0}")]
    ColumnCount(usize),
    /// A field is not a number.
    #[error("column {column} ({name}): cannot parse {text:?} as a number")]
    Unparsable {
        /// 1-based column.
        column: usize,
        /// Column name.
        name: &'static str,
        /// The field as written.
        text: String,
    },
    /// A number is outside the model's domain.
    #[error("{0}")]
    OutOfDomain(SlabParameterError),
}

/// Why [`evaluate_csv`] stopped.
#[derive(Debug, Error)]
pub enum SlabCsvError {
    /// A bad input row; `row` is the 1-based line number in the input (the header, if any, is line 1).
    #[error("row {row}: {problem}")]
    Row {
        /// 1-based line number.
        row: usize,
        /// What is wrong.
        problem: RowProblem,
    },
    /// Reading or writing failed.
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),
}

const COLUMN_NAMES: [&str; 4] = ["tau1", "albedo", "mu0", "mu"];

/// One evaluated row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlabRow {
    /// τ1.
    pub optical_thickness: f64,
    /// Λ.
    pub albedo: f64,
    /// μ0.
    pub mu0: f64,
    /// μ.
    pub mu: f64,
    /// `exp(−τ1/μ)`.
    pub alpha: f64,
    /// Eq. (4) (all orders: plus the multiple part) for unit beam-normal irradiance under the chosen
    /// convention, W/(m²·sr).
    pub l_plus: f64,
    /// Eq. (5) (all orders: plus the multiple part) likewise.
    pub l_minus: f64,
}

/// Parses and evaluates one line of `tau1,albedo,mu0,mu` with the paper's single-scattering model.
pub fn evaluate_row(line: &str, convention: IrradianceConvention) -> Result<SlabRow, RowProblem> {
    evaluate_row_with(line, convention, &Scattering::Single)
}

/// Parses and evaluates one line of `tau1,albedo,mu0,mu` with the chosen scattering model.
pub fn evaluate_row_with(
    line: &str,
    convention: IrradianceConvention,
    scattering: &Scattering,
) -> Result<SlabRow, RowProblem> {
    let fields: Vec<&str> = line.split(',').map(str::trim).collect();
    if fields.len() != 4 {
        return Err(RowProblem::ColumnCount(fields.len()));
    }
    let mut values = [0.0; 4];
    for (column, (field, value)) in fields.iter().zip(values.iter_mut()).enumerate() {
        *value = field.parse::<f64>().map_err(|_| RowProblem::Unparsable {
            column: column + 1,
            name: COLUMN_NAMES[column],
            text: (*field).to_string(),
        })?;
    }
    let [tau1, albedo, mu0, mu] = values;
    let tau = OpticalThickness::new(tau1).map_err(RowProblem::OutOfDomain)?;
    let lambda = Albedo::new(albedo).map_err(RowProblem::OutOfDomain)?;
    let cos0 = Cosine::new("mu0", mu0).map_err(RowProblem::OutOfDomain)?;
    let cos = Cosine::new("mu", mu).map_err(RowProblem::OutOfDomain)?;
    let irradiance = convention.inserted_irradiance(1.0, cos0);
    let radiance = |side| {
        diffuse_radiance(scattering, side, tau, lambda, cos0, cos).map_err(RowProblem::OutOfDomain)
    };
    Ok(SlabRow {
        optical_thickness: tau1,
        albedo,
        mu0,
        mu,
        alpha: direct_transmission(tau, cos),
        l_plus: radiance(Face::Lit)? * irradiance,
        l_minus: radiance(Face::Far)? * irradiance,
    })
}

/// Inputs `(τ1, Λ, μ0, μ)` of the table of exact values in the crate README (printed by
/// `examples/value_table.rs`, checked against the README and against quadrature by `tests/readme_table.rs`).
#[cfg(any(test, feature = "test-support"))]
pub const REFERENCE_TABLE_INPUTS: [[f64; 4]; 12] = [
    [2.0, 1.0, 1.0, 1.0],
    [2.0, 1.0, 0.5, 0.5],
    [2.0, 1.0, 0.5, 0.9],
    [2.0, 1.0, 0.9, 0.5],
    [0.2, 1.0, 1.0, 1.0],
    [0.2, 0.5, 0.3, 0.3],
    [0.001, 1.0, 0.01, 0.01],
    [10.0, 1.0, 0.05, 0.05],
    [10.0, 0.8, 1.0, 0.01],
    [1.0, 0.0, 0.5, 0.5],
    [0.5, 1.0, 0.999999, 1.0],
    [1e-6, 1.0, 1.0, 1e-6],
];

/// One Markdown table row `| tau1 | albedo | mu0 | mu | alpha | l_plus | l_minus |`, outputs with 10
/// significant digits.
#[cfg(any(test, feature = "test-support"))]
pub fn markdown_row(row: &SlabRow) -> String {
    format!(
        "| {} | {} | {} | {} | {:.9e} | {:.9e} | {:.9e} |",
        row.optical_thickness, row.albedo, row.mu0, row.mu, row.alpha, row.l_plus, row.l_minus
    )
}

/// Reads CSV rows from `input`, writes [`OUTPUT_HEADER`] and one evaluated row per input row to `output`,
/// with the paper's single-scattering model. Stops at the first bad row with an error naming its 1-based
/// line number.
pub fn evaluate_csv(
    input: impl BufRead,
    output: impl Write,
    convention: IrradianceConvention,
) -> Result<(), SlabCsvError> {
    evaluate_csv_with(input, output, convention, &Scattering::Single)
}

/// [`evaluate_csv`] with the chosen scattering model (`all-orders`: rows whose τ1 lies outside the
/// table's range are bad rows).
pub fn evaluate_csv_with(
    input: impl BufRead,
    mut output: impl Write,
    convention: IrradianceConvention,
    scattering: &Scattering,
) -> Result<(), SlabCsvError> {
    writeln!(output, "{OUTPUT_HEADER}")?;
    let mut seen_content = false;
    for (index, line) in input.lines().enumerate() {
        let line = line?;
        let trimmed = line.trim();
        if trimmed.is_empty() {
            continue;
        }
        let first_content = !seen_content;
        seen_content = true;
        if first_content && is_header(trimmed) {
            continue;
        }
        let row = evaluate_row_with(trimmed, convention, scattering).map_err(|problem| {
            SlabCsvError::Row {
                row: index + 1,
                problem,
            }
        })?;
        // `{:?}`: the shortest digits that read back to the same f64, with an exponent outside
        // [1e-5, 1e16) (`{}` writes 1e308 with 309 digits).
        writeln!(
            output,
            "{:?},{:?},{:?},{:?},{:?},{:?},{:?}",
            row.optical_thickness, row.albedo, row.mu0, row.mu, row.alpha, row.l_plus, row.l_minus
        )?;
    }
    output.flush()?;
    Ok(())
}

fn is_header(line: &str) -> bool {
    let names: Vec<&str> = line.split(',').map(str::trim).collect();
    names.len() == 4
        && names
            .iter()
            .zip(COLUMN_NAMES)
            .all(|(found, expected)| found.eq_ignore_ascii_case(expected))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(input: &str, convention: IrradianceConvention) -> Result<String, SlabCsvError> {
        let mut out = Vec::new();
        evaluate_csv(input.as_bytes(), &mut out, convention)?;
        Ok(String::from_utf8(out).unwrap())
    }

    #[test]
    fn numbers_are_written_in_their_shortest_round_trip_form() {
        let out = run("1e308,1,1e-7,0.5\n", IrradianceConvention::NormalToBeam).unwrap();
        let row = out.lines().nth(1).unwrap();
        assert!(row.starts_with("1e308,1.0,1e-7,0.5,"), "{row}");
        assert!(row.len() < 120, "{row}");
        // Every field reads back to the value computed.
        let with = run("2,1,0.3,0.7\n", IrradianceConvention::NormalToBeam).unwrap();
        let fields: Vec<f64> = with
            .lines()
            .nth(1)
            .unwrap()
            .split(',')
            .map(|f| f.parse().unwrap())
            .collect();
        let exact = evaluate_row("2,1,0.3,0.7", IrradianceConvention::NormalToBeam).unwrap();
        assert_eq!(
            fields,
            [
                exact.optical_thickness,
                exact.albedo,
                exact.mu0,
                exact.mu,
                exact.alpha,
                exact.l_plus,
                exact.l_minus
            ]
        );
    }

    #[test]
    fn evaluates_rows_with_and_without_header() {
        let with = run(
            "tau1,albedo,mu0,mu\n2,1,0.5,0.5\n",
            IrradianceConvention::NormalToBeam,
        )
        .unwrap();
        let without = run("2, 1, 0.5, 0.5\n\n", IrradianceConvention::NormalToBeam).unwrap();
        assert_eq!(with, without);
        let lines: Vec<&str> = with.lines().collect();
        assert_eq!(lines[0], OUTPUT_HEADER);
        let v: Vec<f64> = lines[1].split(',').map(|f| f.parse().unwrap()).collect();
        // α = e^{−4}; L+ = (1/4π)(1/2)(1 − e^{−8}); L− = (1/4π)·4·e^{−4} (the μ = μ0 limit).
        let pi4 = 4.0 * std::f64::consts::PI;
        let expected = [
            2.0,
            1.0,
            0.5,
            0.5,
            (-4.0f64).exp(),
            0.5 * (1.0 - (-8.0f64).exp()) / pi4,
            4.0 * (-4.0f64).exp() / pi4,
        ];
        for (a, b) in v.iter().zip(expected) {
            // Each value is a handful of correctly rounded operations: 8 ulps.
            assert!((a - b).abs() <= 8.0 * f64::EPSILON * b.abs(), "{a} vs {b}");
        }
    }

    #[test]
    fn paper_literal_scales_by_mu0() {
        let normal = run("1,0.8,0.25,0.6\n", IrradianceConvention::NormalToBeam).unwrap();
        let literal = run("1,0.8,0.25,0.6\n", IrradianceConvention::PaperLiteral).unwrap();
        let parse = |s: &str| -> Vec<f64> {
            s.lines()
                .nth(1)
                .unwrap()
                .split(',')
                .map(|f| f.parse().unwrap())
                .collect()
        };
        let (n, l) = (parse(&normal), parse(&literal));
        assert_eq!(n[4], l[4]);
        // Multiplication by 0.25 is exact in binary floating point.
        assert_eq!(n[5] * 0.25, l[5]);
        assert_eq!(n[6] * 0.25, l[6]);
    }

    #[test]
    fn bad_rows_name_the_row_and_the_problem() {
        let cases: [(&str, usize, &str); 8] = [
            (
                "tau1,albedo,mu0,mu\n1,1,1\n",
                2,
                "expected 4 comma-separated columns",
            ),
            ("1,1,1,1\n1,x,1,1\n", 2, "column 2 (albedo)"),
            ("0,1,1,1\n", 1, "tau1 = 0"),
            ("NaN,1,1,1\n", 1, "tau1 = NaN"),
            ("1,1.5,1,1\n", 1, "Lambda = 1.5"),
            ("1,1,0,1\n", 1, "mu0 = 0"),
            ("\n1,1,1,1\n1,1,1,1.01\n", 3, "mu = 1.01"),
            ("1,-0.1,1,1\n", 1, "Lambda = -0.1"),
        ];
        for (input, row, needle) in cases {
            let err = run(input, IrradianceConvention::NormalToBeam).unwrap_err();
            let message = err.to_string();
            assert!(
                matches!(err, SlabCsvError::Row { row: r, .. } if r == row),
                "{input:?}: {message}"
            );
            assert!(message.starts_with(&format!("row {row}: ")), "{message}");
            assert!(message.contains(needle), "{input:?}: {message}");
        }
    }
}
