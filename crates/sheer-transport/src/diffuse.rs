//! The slab's all-orders response to isotropic diffuse illumination (a face lit by uniform radiance
//! over its whole hemisphere, e.g. sky or room light on cloth), from the collimated solver of
//! [`crate::slab`] (Chandrasekhar 1960, ch. I §11 and ch. VII for reciprocity; the slab of Frisvad,
//! Christensen & Falster 2005, section 3), and a precomputed table of it for real-time use.
//!
//! # Equations
//! Let one face be lit by uniform radiance `L_in` from every direction of its hemisphere. The light
//! arriving within `dΩ = dμ0 dφ` around cosine μ0 is a beam of irradiance `L_in dΩ` normal to itself, and
//! the solver's radiances `L(μ; μ0)` are per unit irradiance normal to the beam and, for isotropic
//! scattering, do not depend on azimuth. Superposing the beams, the diffusely reflected radiance leaving
//! the lit face at cosine μ is `L_in R_d(μ)` and the diffusely transmitted radiance leaving the other face
//! is `L_in T_d(μ)`, with the dimensionless
//!
//! `R_d(μ) = 2π ∫_0^1 L_refl(μ; μ0) dμ0`,  `T_d(μ) = 2π ∫_0^1 L_trans(μ; μ0) dμ0`.
//!
//! `T_d` excludes the unscattered light (in a renderer that is the background seen through the cloth,
//! attenuated by `e^{−τ1/μ}`). Reciprocity, `L(μ; μ0)/μ0 = L(μ0; μ)/μ` for both faces, turns the integral
//! over incidence into one over emergence for a beam at μ: `R_d(μ) = F_refl(μ)/μ` and
//! `T_d(μ) = F_trans(μ)/μ`, where `F` are the diffuse fluxes leaving the slab under a beam at μ0 = μ
//! ([`crate::SlabSolution::reflected_flux`], [`crate::SlabSolution::transmitted_flux`]). Energy
//! conservation for that beam (incident flux μ) then reads
//!
//! `R_d(μ) + T_d(μ) + e^{−τ1/μ} + A(μ) = 1`,  `A(μ) = F_abs(μ)/μ`,
//!
//! with `A = 0` for Λ = 1. Since scattered light has been scattered at least once, each time with
//! probability Λ, `R_d + T_d ≤ Λ (1 − e^{−τ1/μ})`.
//!
//! # Quadrature (why this rule)
//! The route is the direct one: solutions at incidence cosines μ0 on a quadrature rule, one
//! factorisation serving all of them ([`crate::SlabSolver::solve`]). `L(μ; μ0)` has `μ0 ln μ0` terms as
//! μ0 → 0 (the surface source of a grazing beam, like `H(μ0)`), and for small μ it rises on the scale
//! μ0 ~ μ (the factor `μ0/(μ + μ0)` of eq. (4), a pole at `s = ±i√μ` below). The substitution `μ0 = s²`
//! (`dμ0 = 2s ds`) softens the logarithm to `s² ln s`, and Gauss–Legendre in `s` on the panels
//! `[0, 0.01, 0.1, 0.3, 1]`, 10 points each (40 solutions), resolves the rest: geometric panels keep any
//! singularity near `s = 0` at a fixed distance relative to each panel's width whatever μ, the first
//! panel holds only μ0 < 1e-4, and the break at 0.3 resolves the onset of the transmitted forcing
//! `e^{−τ1/μ0}` in thin slabs. Measured against a 168-point rule (panels `[0, 1e-6, 1e-5, …, 0.1, 1]`, 24
//! points each) for τ1 ∈ {0.01, 0.05, 0.2, 0.5, 1, 2, 5, 10}, Λ ∈ {1e-8, 0.5, 0.99, 1} and
//! μ ∈ {0, 1e-8, 1e-6, 1e-4, 0.0051, 0.02, 0.05, 0.15, 0.3, 0.6, 1}: at most 6.3e-8 relative in `R_d` and
//! `T_d` (`tests/diffuse.rs` checks a subset against 1e-7). Single-panel rules in `s` do as well for
//! μ ≳ 0.005 but lose accuracy as μ → 0 (5e-7 at μ = 1e-6 with 32 points).
//!
//! # Table
//! [`DiffuseTable`] stores `ln(R_d/Λ)` and `ln(T_d/Λ)` as `f32` on the axes of
//! [`crate::AllOrdersTable`] (same [`TableSpec`], τ1 axis `c = ln τ1 + τ1`, per-τ1-node albedo warp, √μ
//! cosine nodes; see [`crate::table`]), so that a renderer can share the axes. Dividing by Λ removes the
//! leading (single-scattering) Λ dependence; the logarithm makes the τ1 dependence near-linear. The
//! `Λ = 0` node holds the limit `R_d/Λ`, evaluated at the same albedo floor (1e-8) as the all-orders
//! table. Sampling is trilinear in the table's coordinates on the logarithms, times Λ.
//!
//! # File format (`assets/diffuse_table.bin` at the workspace root, little-endian)
//! `b"SHEERDIF"`, `u32` version (1), `u32` counts `n_tau, n_albedo, n_cosine`, `f64` τ1 range (min, max),
//! `u64` FNV-1a checksum over every byte but its own eight, then `f32` values `[face][tau][albedo][mu]`,
//! face 0 = reflected (`ln(R_d/Λ)`), 1 = transmitted (`ln(T_d/Λ)`). Header, checks and checksum are
//! those of the all-orders table's version 2.

use std::f64::consts::PI;
use std::path::Path;

use rayon::prelude::*;

use crate::quadrature::composite_gauss_legendre;
use crate::slab::SlabSolver;
use crate::table::{
    ALBEDO_FLOOR, AlbedoWarps, TableFileFormat, TableSpec, axis_position, decode_table_file,
    encode_table_file, write_table_file,
};
use crate::{Result, TransportError, validate};

/// Panel breaks in `s = √μ0` of the incidence quadrature (module docs, "Quadrature").
const INCIDENCE_BREAKS: [f64; 5] = [0.0, 0.01, 0.1, 0.3, 1.0];
/// Gauss–Legendre points on each panel.
const INCIDENCE_POINTS: usize = 10;

/// The diffuse table's file format (module docs).
const DIFFUSE_FORMAT: TableFileFormat = TableFileFormat {
    magic: b"SHEERDIF",
    version: 1,
    example: "make_diffuse_table",
    value_count: |spec| {
        spec.tau_count
            .checked_mul(spec.albedo_count)?
            .checked_mul(spec.cosine_count)?
            .checked_mul(2)
    },
};

/// The slab's response at one emergent cosine μ to uniform incident radiance over a whole face's
/// hemisphere, per unit incident radiance (both dimensionless).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DiffuseResponse {
    /// `R_d(μ)`: radiance leaving the lit face at μ.
    pub reflectance: f64,
    /// `T_d(μ)`: scattered radiance leaving the other face at μ (unscattered light excluded).
    pub transmittance: f64,
}

/// Incidence cosines μ0 = s² and weights `2s w_s` of the rule for `∫_0^1 f(μ0) dμ0`.
fn incidence_rule() -> (Vec<f64>, Vec<f64>) {
    let (nodes, weights) = composite_gauss_legendre(&INCIDENCE_BREAKS, INCIDENCE_POINTS);
    let cosines = nodes.iter().map(|s| s * s).collect();
    let jacobian_weights = nodes
        .iter()
        .zip(&weights)
        .map(|(s, w)| 2.0 * s * w)
        .collect();
    (cosines, jacobian_weights)
}

impl SlabSolver {
    /// `R_d(μ)` and `T_d(μ)` at `mu` ∈ [0, 1] (μ = 0 is the grazing limit): radiance leaving each face
    /// per unit uniform radiance incident over the lit face's hemisphere (module docs).
    pub fn diffuse_response(&self, mu: f64) -> Result<DiffuseResponse> {
        let responses = self.diffuse_responses(&[mu])?;
        Ok(responses[0])
    }

    /// [`Self::diffuse_response`] at every cosine of `mus`, from one set of incidence solutions (the
    /// expensive part: one solve per quadrature node, whatever the number of cosines).
    pub fn diffuse_responses(&self, mus: &[f64]) -> Result<Vec<DiffuseResponse>> {
        for &mu in mus {
            validate::emergent_cosine(mu)?;
        }
        let mut responses = vec![DiffuseResponse::default(); mus.len()];
        let (cosines, weights) = incidence_rule();
        for (&mu0, &weight) in cosines.iter().zip(&weights) {
            let solution = self.solve(mu0)?;
            for (response, &mu) in responses.iter_mut().zip(mus) {
                response.reflectance += weight * solution.reflected_radiance(mu)?;
                response.transmittance += weight * solution.transmitted_radiance(mu)?;
            }
        }
        // The azimuth integral of an azimuth-independent radiance.
        for response in &mut responses {
            response.reflectance *= 2.0 * PI;
            response.transmittance *= 2.0 * PI;
        }
        Ok(responses)
    }
}

/// The diffuse-illumination table and its sampler.
#[derive(Clone, Debug, PartialEq)]
pub struct DiffuseTable {
    spec: TableSpec,
    /// `ln(R_d/Λ)`, `ln(T_d/Λ)`, `[face][tau][albedo][mu]`.
    values: Vec<f32>,
    /// The albedo warp of every τ1 node (derived from `spec`).
    warps: AlbedoWarps,
}

/// `[mu]` rows (reflected, transmitted) of `ln(R_d/Λ)`, `ln(T_d/Λ)` for one (τ1, Λ).
fn generate_row(spec: &TableSpec, tau1: f64, albedo: f64) -> Result<(Vec<f32>, Vec<f32>)> {
    let albedo = albedo.max(ALBEDO_FLOOR);
    let solver = SlabSolver::new(tau1, albedo)?;
    let mus: Vec<f64> = (0..spec.cosine_count)
        .map(|j| spec.cosine_node(j))
        .collect();
    let responses = solver.diffuse_responses(&mus)?;
    let to_log = |value: f64| -> Result<f32> {
        let reduced = value / albedo;
        if reduced > 0.0 && reduced.is_finite() {
            Ok(reduced.ln() as f32)
        } else {
            Err(TransportError::TableFormat(format!(
                "non-positive diffuse response {value} at tau1 {tau1}, albedo {albedo}"
            )))
        }
    };
    let reflected = responses
        .iter()
        .map(|r| to_log(r.reflectance))
        .collect::<Result<_>>()?;
    let transmitted = responses
        .iter()
        .map(|r| to_log(r.transmittance))
        .collect::<Result<_>>()?;
    Ok((reflected, transmitted))
}

impl DiffuseTable {
    /// Path of the shipped table: `assets/diffuse_table.bin` at the workspace root (resolved at compile
    /// time from this crate's location).
    pub const DEFAULT_PATH: &'static str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../assets/diffuse_table.bin"
    );

    /// Generates a table with the all-orders solver (parallel over (τ1, Λ); the result does not depend
    /// on the thread count since every row is computed independently and stored in order).
    /// [`TableSpec::default`] gives the shipped table, on the same axes as the all-orders one.
    pub fn generate(spec: TableSpec) -> Result<Self> {
        spec.validate()?;
        let jobs: Vec<(usize, usize)> = (0..spec.tau_count)
            .flat_map(|t| (0..spec.albedo_count).map(move |a| (t, a)))
            .collect();
        let rows: Vec<(Vec<f32>, Vec<f32>)> = jobs
            .par_iter()
            .map(|&(t, a)| {
                let tau1 = spec.tau_node(t);
                generate_row(&spec, tau1, spec.albedo_node(a, tau1))
            })
            .collect::<Result<_>>()?;
        let mut values = Vec::with_capacity(2 * rows.len() * spec.cosine_count);
        values.extend(rows.iter().flat_map(|(r, _)| r.iter().copied()));
        values.extend(rows.iter().flat_map(|(_, t)| t.iter().copied()));
        Ok(Self::from_parts(spec, values))
    }

    /// A table from validated grid sizes and values, with the derived per-node albedo warp.
    fn from_parts(spec: TableSpec, values: Vec<f32>) -> Self {
        Self {
            warps: AlbedoWarps::new(&spec),
            spec,
            values,
        }
    }

    /// The grid sizes.
    pub fn spec(&self) -> TableSpec {
        self.spec
    }

    /// The stored values `ln(R_d/Λ)` (face 0) and `ln(T_d/Λ)` (face 1), laid out
    /// `[face][tau][albedo][mu]`, each axis on the nodes of [`crate::AllOrdersTable`] with the same
    /// spec: for uploading to a GPU.
    pub fn log_values(&self) -> &[f32] {
        &self.values
    }

    /// The albedo warp strength β of every τ1 node (as [`crate::AllOrdersTable::albedo_warp_strengths`]:
    /// the same for the same spec), for samplers elsewhere.
    pub fn albedo_warp_strengths(&self) -> &[f64] {
        self.warps.strengths()
    }

    /// The τ1 axis in its coordinate `c = ln τ1 + τ1`: `(c(tau_min), c(tau_max))`.
    pub fn tau_coordinate_range(&self) -> (f64, f64) {
        self.spec.tau_coordinate_range()
    }

    /// Serialises to the file format described in the module docs.
    pub fn to_bytes(&self) -> Vec<u8> {
        encode_table_file(&DIFFUSE_FORMAT, &self.spec, &self.values)
    }

    /// Parses the file format, checking magic, version, sizes, that every value is finite and at most
    /// [`crate::table::LOG_VALUE_MAX`], and the checksum.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let (spec, values) = decode_table_file(&DIFFUSE_FORMAT, bytes)?;
        Ok(Self::from_parts(spec, values))
    }

    /// Writes the table file, beside it under a hidden temporary name and renamed into place, so that
    /// an interrupted write never leaves a partial table under the table's name.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        write_table_file(path.as_ref(), &self.to_bytes())
    }

    /// Reads a table file.
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        Self::from_bytes(&std::fs::read(path)?)
    }

    /// `R_d(μ)`, interpolated: radiance leaving the lit face at `mu` ∈ [0, 1] per unit uniform radiance
    /// incident over its hemisphere (dimensionless). `tau1` must lie in the table's range, Λ in [0, 1].
    pub fn reflectance(&self, tau1: f64, albedo: f64, mu: f64) -> Result<f64> {
        Ok(albedo * self.interpolate(0, tau1, albedo, mu)?.exp())
    }

    /// `T_d(μ)`, interpolated: scattered radiance leaving the unlit face at `mu` per unit uniform
    /// radiance incident over the lit face's hemisphere (dimensionless; unscattered light excluded).
    pub fn transmittance(&self, tau1: f64, albedo: f64, mu: f64) -> Result<f64> {
        Ok(albedo * self.interpolate(1, tau1, albedo, mu)?.exp())
    }

    /// Trilinear interpolation of the stored logarithm of one face in (τ1 coordinate, warped albedo, √μ).
    fn interpolate(&self, face: usize, tau1: f64, albedo: f64, mu: f64) -> Result<f64> {
        let (t0, wt) = self.spec.tau_position(tau1)?;
        validate::albedo(albedo)?;
        validate::emergent_cosine(mu)?;
        let spec = &self.spec;
        let n = spec.cosine_count;
        let (j0, wj) = axis_position(mu.sqrt(), n);
        let face_offset = face * spec.tau_count * spec.albedo_count * n;
        let s = (1.0 - albedo).sqrt();
        let mut sum = 0.0;
        for (dt, ft) in [(0, 1.0 - wt), (1, wt)] {
            let (a0, wa) = self.warps.position(t0 + dt, s);
            for (da, fa) in [(0, 1.0 - wa), (1, wa)] {
                let base = face_offset + ((t0 + dt) * spec.albedo_count + a0 + da) * n + j0;
                let linear = (1.0 - wj) * f64::from(self.values[base])
                    + wj * f64::from(self.values[base + 1]);
                sum += ft * fa * linear;
            }
        }
        Ok(sum)
    }
}
