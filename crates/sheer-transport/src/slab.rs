//! The exact (all orders of scattering) plane-parallel slab with isotropic scattering under collimated
//! incidence (Chandrasekhar 1960, ch. I §11 and ch. IX; Frisvad et al. 2005, eqs. (2)–(3)).
//!
//! # Equations
//! With optical depth `τ ∈ [0, τ1]` measured from the lit face, albedo Λ and a beam of unit irradiance
//! normal to itself arriving at `μ0`, the source function is `J = S0 + J_m` with the single-scattering
//! source `S0(τ) = Λ/(4π) e^{−τ/μ0}` and the multiply-scattered part obeying
//!
//! `J_m(τ) = (Λ/2) ∫_0^τ1 E1(|τ−t|) J_m(t) dt + (Λ/2) ∫_0^τ1 E1(|τ−t|) S0(t) dt`.
//!
//! The emergent radiances are `L_refl(μ) = ∫ J(t) e^{−t/μ} dt/μ` and
//! `L_trans(μ) = ∫ J(t) e^{−(τ1−t)/μ} dt/μ`; the `S0` parts are exactly eqs. (4)–(5).
//!
//! # Discretisation (Nyström with product integration)
//! `J_m` is represented as piecewise quadratic (Lagrange, on elements of two equal cells) on a mesh
//! graded geometrically towards both faces, where it behaves like `τ ln τ`; every node is a collocation
//! point. The kernel is integrated against the basis functions cell by cell: on cells within four cell
//! widths of the collocation point `E1(x) = −γ − ln x + R(x)` with `R` entire, the logarithm integrated
//! in closed form and `R` by Gauss–Legendre; on farther cells `E1` is smooth and Gauss–Legendre alone is
//! used. The forcing term `∫ E1(|τ−t|) e^{−t/μ0} dt` is evaluated without interpolating `e^{−t/μ0}`,
//! from `E1(x) = ∫_0^1 e^{−x/u} du/u`: the inner `t` integral is elementary and the outer one is done by
//! composite Gauss–Legendre in `ln u`. Emergent radiances integrate the piecewise-quadratic `J_m` against
//! the exponential exactly. Only `J_m`, which is of order Λ τ1 relative to `S0` for thin slabs, carries
//! discretisation error, so the single-vs-all-orders comparison stays accurate at small τ1.

use std::sync::Arc;

use crate::expint::e1;
use crate::linalg::LuFactorisation;
use crate::quadrature::{composite_gauss_legendre, gauss_legendre, graded_unit_breaks};
use crate::single::{ISOTROPIC_PHASE, reflected_path_factor, transmitted_path_factor};
use crate::{Result, TransportError, validate};

/// Mesh and quadrature parameters of the solver. [`Discretisation::default`] is accurate to about
/// 1e-6 relative in the multiply-scattered radiance (measured by refinement, see the README).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Discretisation {
    /// Optical thickness of the cell touching each face.
    pub first_cell: f64,
    /// Ratio between the thicknesses of consecutive cells going inwards (≥ 1).
    pub growth: f64,
    /// Largest cell optical thickness (the interior is uniform at this size).
    pub max_cell: f64,
    /// Gauss–Legendre points per unit of `ln u` for the forcing integral over `u ∈ (e^{−36}, 1]`.
    pub forcing_points_per_unit_log: usize,
}

impl Default for Discretisation {
    fn default() -> Self {
        Self {
            first_cell: 1.0e-6,
            growth: 1.1,
            max_cell: 0.05,
            forcing_points_per_unit_log: 8,
        }
    }
}

impl Discretisation {
    /// A finer discretisation (cells roughly halved everywhere, more forcing points), for convergence
    /// checks.
    pub fn refined(self) -> Self {
        Self {
            first_cell: self.first_cell * 0.1,
            growth: self.growth.sqrt(),
            max_cell: self.max_cell * 0.5,
            forcing_points_per_unit_log: self.forcing_points_per_unit_log + 4,
        }
    }

    fn validate(&self) -> Result<()> {
        if !(self.first_cell > 0.0 && self.first_cell.is_finite()) {
            return Err(TransportError::Discretisation(
                "first_cell must be finite and > 0",
            ));
        }
        if !(self.growth >= 1.0 && self.growth <= 2.0) {
            return Err(TransportError::Discretisation("growth must lie in [1, 2]"));
        }
        if !(self.max_cell >= self.first_cell && self.max_cell.is_finite()) {
            return Err(TransportError::Discretisation(
                "max_cell must be finite and >= first_cell",
            ));
        }
        if self.forcing_points_per_unit_log < 2 {
            return Err(TransportError::Discretisation(
                "forcing_points_per_unit_log must be >= 2",
            ));
        }
        Ok(())
    }

    /// Mesh nodes on `[0, τ1]`, graded symmetrically towards both faces; an odd number of nodes, node
    /// `2e` to `2e + 2` forming element `e` with two equal cells.
    fn mesh(&self, tau1: f64) -> Result<Vec<f64>> {
        let half = 0.5 * tau1;
        let mut elements = Vec::new();
        let mut cell = self.first_cell;
        let mut total = 0.0;
        while total < half {
            elements.push(2.0 * cell);
            total += 2.0 * cell;
            cell = (cell * self.growth * self.growth).min(self.max_cell);
            if elements.len() > 100_000 {
                return Err(TransportError::Discretisation(
                    "mesh would exceed 200000 elements; coarsen it",
                ));
            }
        }
        // Scale so the half-mesh ends exactly at τ1/2 (a uniform stretch keeps the grading ratio).
        let scale = half / total;
        let mut nodes = Vec::with_capacity(4 * elements.len() + 1);
        nodes.push(0.0);
        let mut position = 0.0;
        for width in &elements {
            nodes.push(position + 0.5 * width * scale);
            position += width * scale;
            nodes.push(position);
        }
        let last = nodes.len() - 1;
        nodes[last] = half;
        for i in (0..last).rev() {
            nodes.push(tau1 - nodes[i]);
        }
        // A τ1 near the smallest `f64` leaves no room for cells (τ1/2 rounds to 0 at 5e-324), and a
        // mesh with repeated nodes makes the collocation system singular.
        if nodes.len() < 3 || nodes.windows(2).any(|pair| pair[0] >= pair[1]) {
            return Err(TransportError::Discretisation(
                "the mesh's nodes are not distinct at this tau1 (tau1 too small, or first_cell too \
                 fine against it)",
            ));
        }
        Ok(nodes)
    }
}

/// Lower end of the `ln u` range of the forcing integral; the integrand is below `2u` there, so the
/// truncated tail is below `2 e^{−36} ≈ 5e-16`.
const LOG_U_MIN: f64 = -36.0;

/// A factorised Nyström system for one slab (τ1, Λ); solving for any number of incidence angles reuses
/// the factorisation.
#[derive(Clone, Debug)]
pub struct SlabSolver {
    tau1: f64,
    albedo: f64,
    mesh: Arc<[f64]>,
    system: LuFactorisation,
    forcing_nodes: Vec<f64>,
    forcing_weights: Vec<f64>,
}

impl SlabSolver {
    /// Builds the solver for optical thickness `tau1` > 0 and single-scattering albedo Λ ∈ [0, 1] with
    /// the default discretisation.
    pub fn new(tau1: f64, albedo: f64) -> Result<Self> {
        Self::with_discretisation(tau1, albedo, Discretisation::default())
    }

    /// Builds the solver with an explicit discretisation.
    pub fn with_discretisation(
        tau1: f64,
        albedo: f64,
        discretisation: Discretisation,
    ) -> Result<Self> {
        validate::optical_thickness(tau1)?;
        validate::albedo(albedo)?;
        discretisation.validate()?;
        let mesh: Arc<[f64]> = discretisation.mesh(tau1)?.into();
        let matrix = nystrom_matrix(&mesh, albedo);
        let system = LuFactorisation::new(mesh.len(), matrix).ok_or(
            TransportError::Discretisation("Nystrom matrix is singular to working precision"),
        )?;
        let panels = (-LOG_U_MIN).ceil() as usize;
        let breaks: Vec<f64> = (0..=panels)
            .map(|k| LOG_U_MIN + (k as f64) * (-LOG_U_MIN) / panels as f64)
            .collect();
        let (log_nodes, forcing_weights) =
            composite_gauss_legendre(&breaks, discretisation.forcing_points_per_unit_log);
        let forcing_nodes = log_nodes.iter().map(|v| v.exp()).collect();
        Ok(Self {
            tau1,
            albedo,
            mesh,
            system,
            forcing_nodes,
            forcing_weights,
        })
    }

    /// Optical thickness τ1 of the slab.
    pub fn optical_thickness(&self) -> f64 {
        self.tau1
    }

    /// Single-scattering albedo Λ.
    pub fn albedo(&self) -> f64 {
        self.albedo
    }

    /// Mesh nodes (optical depths) carrying the source function.
    pub fn mesh(&self) -> &[f64] {
        &self.mesh
    }

    /// Solves for the source function under a beam at `mu0` ∈ (0, 1] of unit irradiance normal to it.
    pub fn solve(&self, mu0: f64) -> Result<SlabSolution> {
        validate::incident_cosine(mu0)?;
        // (Λ/2) · Λ/(4π) · ∫ E1(|τ−t|) e^{−t/μ0} dt at every node.
        let prefactor = 0.5 * self.albedo * self.albedo * ISOTROPIC_PHASE;
        let mut multiple: Vec<f64> = self
            .mesh
            .iter()
            .map(|&tau| prefactor * self.beam_forcing(tau, mu0))
            .collect();
        self.system.solve_in_place(&mut multiple);
        Ok(SlabSolution {
            tau1: self.tau1,
            albedo: self.albedo,
            mu0,
            mesh: Arc::clone(&self.mesh),
            multiple,
        })
    }

    /// `G(τ) = ∫_0^τ1 E1(|τ−t|) e^{−t/μ0} dt` via `E1(x) = ∫_0^1 e^{−x/u} du/u` with the `t` integral
    /// done in closed form and the `u` integral by Gauss–Legendre in `ln u` (integrand `I1 + I2`).
    fn beam_forcing(&self, tau: f64, mu0: f64) -> f64 {
        let beam = (-tau / mu0).exp();
        let below = self.tau1 - tau;
        let mut sum = 0.0;
        for (&u, &w) in self.forcing_nodes.iter().zip(&self.forcing_weights) {
            // I1 = ∫_0^τ e^{−(τ−t)/u} e^{−t/μ0} dt = (e^{−τ/μ0} − e^{−τ/u}) / d, d = 1/u − 1/μ0.
            let d = 1.0 / u - 1.0 / mu0;
            // Empty integrals at the faces are 0, also where a cosine so small that 1/μ0 overflows
            // would make them 0·∞.
            let from_above = if tau == 0.0 {
                0.0
            } else if d == 0.0 {
                tau * beam
            } else if d > 0.0 {
                beam * -(-tau * d).exp_m1() / d
            } else {
                (-tau / u).exp() * (tau * d).exp_m1() / d
            };
            // I2 = ∫_τ^τ1 e^{−(t−τ)/u} e^{−t/μ0} dt = e^{−τ/μ0} (1 − e^{−(τ1−τ) c}) / c, c = 1/u + 1/μ0.
            let c = 1.0 / u + 1.0 / mu0;
            let from_below = if below == 0.0 {
                0.0
            } else {
                beam * -(-below * c).exp_m1() / c
            };
            // du/u = d(ln u): the Jacobian cancels the 1/u of the E1 representation.
            sum += w * (from_above + from_below);
        }
        sum
    }
}

/// Euler–Mascheroni constant γ.
const EULER_GAMMA: f64 = 0.577_215_664_901_532_9;

/// `R(x) = E1(x) + γ + ln x = Σ_{k≥1} (−1)^{k+1} x^k / (k·k!)` (A&S 5.1.11), entire; summed directly
/// for the `x ≤ 10` used on near cells (terms peak near k = x, so the alternating sum loses < 5 digits).
fn e1_regular_part(x: f64) -> f64 {
    let mut sum = 0.0;
    let mut term = 1.0;
    for k in 1..200 {
        let kf = k as f64;
        term *= -x / kf;
        let contribution = -term / kf;
        sum += contribution;
        if contribution.abs() < 1.0e-17 * sum.abs() {
            break;
        }
    }
    sum
}

/// `∫_0^1 s^m ln(c + s) ds` for `m = 0, 1, 2` and `c ≥ 0` (elementary antiderivatives).
fn log_moments(c: f64) -> [f64; 3] {
    let c_log_c = |power: i32| {
        if c == 0.0 {
            0.0
        } else {
            c.powi(power) * c.ln()
        }
    };
    let log_one_plus_c = c.ln_1p();
    [
        (1.0 + c) * log_one_plus_c - c_log_c(1) - 1.0,
        0.5 * (1.0 - c * c) * log_one_plus_c + 0.5 * c_log_c(2) - 0.25 + 0.5 * c,
        (1.0 + c * c * c) / 3.0 * log_one_plus_c
            - c_log_c(3) / 3.0
            - (1.0 / 3.0 - 0.5 * c + c * c) / 3.0,
    ]
}

/// Gauss–Legendre rules on [0, 1] used for the kernel moments.
struct KernelRules {
    near: (Vec<f64>, Vec<f64>),
    middle: (Vec<f64>, Vec<f64>),
    far: (Vec<f64>, Vec<f64>),
}

impl KernelRules {
    fn new() -> Self {
        Self {
            near: gauss_legendre(8, 0.0, 1.0),
            middle: gauss_legendre(8, 0.0, 1.0),
            far: gauss_legendre(4, 0.0, 1.0),
        }
    }

    /// `I_m = ∫_0^h (x/h)^m E1(a + x) dx`, m = 0, 1, 2, for a cell of width `h` whose near end is at
    /// distance `a ≥ 0` from the collocation point.
    ///
    /// `a ≤ 4h`: `E1 = −γ − ln x + R(x)`, logarithm exact, `R` by 8-point Gauss (R is entire; on
    /// `[0, 5h]` with `h ≤ 2` its degree-16 Taylor remainder is below 1e-16 relative).
    /// `4h < a ≤ 20h`: 8-point Gauss on `E1`, whose nearest singularity lies ≥ 9 half-widths from the
    /// cell centre, so the error is below `17.9^{−16} ≈ 1e-20` relative (Bernstein-ellipse bound).
    /// `a > 20h`: 4-point Gauss, error below `82^{−8} ≈ 5e-16` relative by the same bound.
    fn moments(&self, a: f64, h: f64) -> [f64; 3] {
        let ratio = a / h;
        if ratio <= 4.0 {
            let logs = log_moments(ratio);
            let (nodes, weights) = &self.near;
            let mut regular = [0.0; 3];
            for (&s, &w) in nodes.iter().zip(weights) {
                let r = w * e1_regular_part(a + h * s);
                regular[0] += r;
                regular[1] += r * s;
                regular[2] += r * s * s;
            }
            let ln_h = h.ln();
            std::array::from_fn(|m| {
                let inverse = 1.0 / (m as f64 + 1.0);
                // ln(a + h s) = ln h + ln(c + s).
                h * (-EULER_GAMMA * inverse - (ln_h * inverse + logs[m]) + regular[m])
            })
        } else {
            let (nodes, weights) = if ratio <= 20.0 {
                &self.middle
            } else {
                &self.far
            };
            let mut moments = [0.0; 3];
            for (&s, &w) in nodes.iter().zip(weights) {
                let value = w * e1(a + h * s);
                moments[0] += value;
                moments[1] += value * s;
                moments[2] += value * s * s;
            }
            moments.map(|m| h * m)
        }
    }
}

/// Coefficients of the quadratic Lagrange basis on an element, in the element coordinate σ ∈ [0, 1]
/// with nodes at 0, 1/2, 1: `ℓ_j(σ) = c0 + c1 σ + c2 σ²`.
const QUADRATIC_BASIS: [[f64; 3]; 3] = [[1.0, -3.0, 2.0], [0.0, 4.0, -4.0], [0.0, -1.0, 2.0]];

/// Beyond this distance (optical depths) `E1 < 1e-19`, far below the accuracy of anything else here.
const KERNEL_CUTOFF: f64 = 40.0;

/// The Nyström matrix `I − (Λ/2) W` with product-integration weights `W_ij = ∫ E1(|τ_i − t|) φ_j(t) dt`
/// for the piecewise-quadratic basis functions `φ_j` of the mesh.
fn nystrom_matrix(mesh: &[f64], albedo: f64) -> Vec<f64> {
    let n = mesh.len();
    let rules = KernelRules::new();
    let mut matrix = vec![0.0; n * n];
    for i in 0..n {
        let tau = mesh[i];
        let row = &mut matrix[i * n..(i + 1) * n];
        for element in 0..(n - 1) / 2 {
            let first = 2 * element;
            let h = mesh[first + 2] - mesh[first + 1];
            for (cell_start, left_sigma) in [(first, 0.0), (first + 1, 0.5)] {
                let (start, end) = (mesh[cell_start], mesh[cell_start + 1]);
                // The collocation point is a node, so it never lies inside a cell. σ = α + β s with
                // s ∈ [0, 1] measured from the cell end nearer the point.
                let (a, alpha, beta) = if tau <= start {
                    (start - tau, left_sigma, 0.5)
                } else {
                    (tau - end, left_sigma + 0.5, -0.5)
                };
                if a > KERNEL_CUTOFF {
                    continue;
                }
                let moments = rules.moments(a.max(0.0), h);
                for (j, c) in QUADRATIC_BASIS.iter().enumerate() {
                    // ℓ_j(α + β s) as a polynomial in s.
                    let p0 = c[0] + c[1] * alpha + c[2] * alpha * alpha;
                    let p1 = c[1] * beta + 2.0 * c[2] * alpha * beta;
                    let p2 = c[2] * beta * beta;
                    let weight = p0 * moments[0] + p1 * moments[1] + p2 * moments[2];
                    row[first + j] -= 0.5 * albedo * weight;
                }
            }
        }
        row[i] += 1.0;
    }
    matrix
}

/// The source function of one solved slab and incidence, with its emergent radiances and fluxes.
#[derive(Clone, Debug)]
pub struct SlabSolution {
    tau1: f64,
    albedo: f64,
    mu0: f64,
    mesh: Arc<[f64]>,
    multiple: Vec<f64>,
}

/// Exact weights `q ∫_0^1 ℓ_j(σ) e^{−qσ} dσ` of the three quadratic basis functions of an element of
/// optical thickness `q μ` seen at cosine `μ`, σ measured from the element end nearer the viewer.
fn exponential_quadratic_weights(q: f64) -> [f64; 3] {
    // Moments m_k = q ∫_0^1 σ^k e^{−qσ} dσ.
    let moments: [f64; 3] = if q < 1.0 {
        // Series m_k = q Σ_n (−q)^n / (n! (n + k + 1)); 25 terms leave < 1/25! relative.
        let mut m = [0.0; 3];
        let mut term = q;
        for n in 0..25 {
            for (k, value) in m.iter_mut().enumerate() {
                *value += term / (n + k + 1) as f64;
            }
            term *= -q / (n + 1) as f64;
        }
        m
    } else {
        // Upward recursion m_k = k m_{k−1}/q − e^{−q} amplifies error by k/q ≤ 2 per step.
        let decay = (-q).exp();
        let m0 = -(-q).exp_m1();
        let m1 = m0 / q - decay;
        let m2 = 2.0 * m1 / q - decay;
        [m0, m1, m2]
    };
    QUADRATIC_BASIS.map(|c| c[0] * moments[0] + c[1] * moments[1] + c[2] * moments[2])
}

impl SlabSolution {
    /// Optical thickness τ1.
    pub fn optical_thickness(&self) -> f64 {
        self.tau1
    }

    /// Single-scattering albedo Λ.
    pub fn albedo(&self) -> f64 {
        self.albedo
    }

    /// Incident cosine μ0.
    pub fn incident_cosine(&self) -> f64 {
        self.mu0
    }

    /// Source function `J(τ)` (sr⁻¹ per unit normal irradiance) at optical depth `tau` ∈ [0, τ1].
    pub fn source_function(&self, tau: f64) -> Result<f64> {
        if !(0.0..=self.tau1).contains(&tau) {
            return Err(TransportError::OpticalThickness(tau));
        }
        let elements = (self.mesh.len() - 1) / 2;
        let element =
            (self.mesh.partition_point(|&t| t <= tau).max(1) - 1).min(2 * elements - 1) / 2;
        let first = 2 * element;
        let sigma = (tau - self.mesh[first]) / (self.mesh[first + 2] - self.mesh[first]);
        let multiple: f64 = QUADRATIC_BASIS
            .iter()
            .enumerate()
            .map(|(j, c)| self.multiple[first + j] * (c[0] + c[1] * sigma + c[2] * sigma * sigma))
            .sum();
        Ok(self.albedo * ISOTROPIC_PHASE * (-tau / self.mu0).exp() + multiple)
    }

    /// Multiply-scattered (orders ≥ 2) radiance leaving the lit face at `mu` ∈ [0, 1] (sr⁻¹).
    pub fn multiple_reflected_radiance(&self, mu: f64) -> Result<f64> {
        validate::emergent_cosine(mu)?;
        Ok(self.multiple_reflected(mu))
    }

    /// Multiply-scattered (orders ≥ 2) radiance leaving the unlit face at `mu` ∈ [0, 1] (sr⁻¹).
    pub fn multiple_transmitted_radiance(&self, mu: f64) -> Result<f64> {
        validate::emergent_cosine(mu)?;
        Ok(self.multiple_transmitted(mu))
    }

    /// All-orders diffuse radiance leaving the lit face at `mu` ∈ [0, 1], per unit irradiance normal to
    /// the beam (sr⁻¹): eq. (4) plus [`Self::multiple_reflected_radiance`].
    pub fn reflected_radiance(&self, mu: f64) -> Result<f64> {
        validate::emergent_cosine(mu)?;
        Ok(self.reflected(mu))
    }

    /// All-orders diffuse radiance leaving the unlit face at `mu` ∈ [0, 1], per unit irradiance normal to
    /// the beam (sr⁻¹): eq. (5) plus [`Self::multiple_transmitted_radiance`]. The unscattered beam is
    /// not included (see [`Self::direct_transmitted_flux`]).
    pub fn transmitted_radiance(&self, mu: f64) -> Result<f64> {
        validate::emergent_cosine(mu)?;
        Ok(self.transmitted(mu))
    }

    /// Reflected diffuse flux `2π ∫_0^1 L_refl(μ) μ dμ` (per unit normal irradiance), by composite
    /// Gauss–Legendre on panels graded towards grazing angles.
    pub fn reflected_flux(&self) -> f64 {
        self.flux(0.0, 1.0, true)
    }

    /// Transmitted diffuse flux `2π ∫_0^1 L_trans(μ) μ dμ` (per unit normal irradiance).
    pub fn transmitted_flux(&self) -> f64 {
        self.flux(0.0, 1.0, false)
    }

    /// Unscattered transmitted flux `μ0 e^{−τ1/μ0}` (per unit normal irradiance).
    pub fn direct_transmitted_flux(&self) -> f64 {
        self.mu0 * (-self.tau1 / self.mu0).exp()
    }

    /// Flux absorbed inside the slab (per unit normal irradiance): `(1 − Λ) ∫ (4π J/Λ) dτ`, since
    /// `4π J/Λ` is the total (diffuse plus beam) intensity integrated over the sphere. The `S0` part is
    /// integrated exactly, `J_m` by Simpson's rule on each element (exact for its quadratic).
    pub fn absorbed_flux(&self) -> f64 {
        let beam_path = self.mu0 * -(-self.tau1 / self.mu0).exp_m1();
        if self.albedo == 0.0 {
            return beam_path;
        }
        let multiple_integral: f64 = (0..self.mesh.len() - 1)
            .step_by(2)
            .map(|first| {
                (self.mesh[first + 2] - self.mesh[first]) / 6.0
                    * (self.multiple[first]
                        + 4.0 * self.multiple[first + 1]
                        + self.multiple[first + 2])
            })
            .sum();
        (1.0 - self.albedo) * (beam_path + multiple_integral / (self.albedo * ISOTROPIC_PHASE))
    }

    /// Diffuse flux `2π ∫_{μa}^{μb} L(μ) μ dμ` leaving the lit (`reflected = true`) or unlit face through
    /// the cosine band `[mu_low, mu_high]`, `0 ≤ mu_low ≤ mu_high ≤ 1` (per unit normal irradiance).
    pub fn flux_between(&self, mu_low: f64, mu_high: f64, reflected: bool) -> Result<f64> {
        validate::emergent_cosine(mu_low)?;
        validate::emergent_cosine(mu_high)?;
        if mu_low > mu_high {
            return Err(TransportError::Cosine {
                name: "mu_high",
                range: "[mu_low, 1]",
                value: mu_high,
            });
        }
        Ok(self.flux(mu_low, mu_high, reflected))
    }

    fn flux(&self, mu_low: f64, mu_high: f64, reflected: bool) -> f64 {
        let mut breaks: Vec<f64> = graded_unit_breaks(6)
            .into_iter()
            .filter(|&m| m > mu_low && m < mu_high)
            .collect();
        breaks.insert(0, mu_low);
        breaks.push(mu_high);
        let (nodes, weights) = composite_gauss_legendre(&breaks, 16);
        let integral: f64 = nodes
            .iter()
            .zip(&weights)
            .map(|(&mu, &w)| {
                let radiance = if reflected {
                    self.reflected(mu)
                } else {
                    self.transmitted(mu)
                };
                w * mu * radiance
            })
            .sum();
        2.0 * std::f64::consts::PI * integral
    }

    fn reflected(&self, mu: f64) -> f64 {
        self.albedo * ISOTROPIC_PHASE * reflected_path_factor(self.tau1, self.mu0, mu)
            + self.multiple_reflected(mu)
    }

    fn transmitted(&self, mu: f64) -> f64 {
        self.albedo * ISOTROPIC_PHASE * transmitted_path_factor(self.tau1, self.mu0, mu)
            + self.multiple_transmitted(mu)
    }

    fn multiple_reflected(&self, mu: f64) -> f64 {
        if mu == 0.0 {
            return self.multiple[0];
        }
        let mut sum = 0.0;
        for first in (0..self.mesh.len() - 1).step_by(2) {
            let attenuation = (-self.mesh[first] / mu).exp();
            if attenuation == 0.0 {
                break;
            }
            let weights =
                exponential_quadratic_weights((self.mesh[first + 2] - self.mesh[first]) / mu);
            sum += attenuation
                * (weights[0] * self.multiple[first]
                    + weights[1] * self.multiple[first + 1]
                    + weights[2] * self.multiple[first + 2]);
        }
        sum
    }

    fn multiple_transmitted(&self, mu: f64) -> f64 {
        let last = self.mesh.len() - 1;
        if mu == 0.0 {
            return self.multiple[last];
        }
        let mut sum = 0.0;
        for end in (2..=last).rev().step_by(2) {
            let attenuation = (-(self.tau1 - self.mesh[end]) / mu).exp();
            if attenuation == 0.0 {
                break;
            }
            let weights = exponential_quadratic_weights((self.mesh[end] - self.mesh[end - 2]) / mu);
            sum += attenuation
                * (weights[0] * self.multiple[end]
                    + weights[1] * self.multiple[end - 1]
                    + weights[2] * self.multiple[end - 2]);
        }
        sum
    }
}
