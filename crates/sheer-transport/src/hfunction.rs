//! Chandrasekhar's H-function for isotropic scattering with albedo Λ (Chandrasekhar 1960, ch. V,
//! eqs. (V.3) and (V.19)): `H(μ) = 1 + (Λ/2) μ H(μ) ∫_0^1 H(μ')/(μ+μ') dμ'`, solved here in the
//! equivalent form `1/H(μ) = √(1−Λ) + (Λ/2) ∫_0^1 μ' H(μ')/(μ+μ') dμ'` (Chandrasekhar eq. (V.34);
//! the two agree because `(Λ/2)∫H = 1 − √(1−Λ)`), iterated with averaging of successive iterates (the plain
//! iteration settles into a two-cycle for Λ = 1).
//!
//! It gives the semi-infinite (τ1 → ∞) reflected radiance `L(μ) = Λ/(4π) μ0/(μ+μ0) H(μ) H(μ0)` per unit
//! irradiance normal to the beam (Chandrasekhar ch. IV §26), the thick-slab limit of [`crate::slab`].

use crate::quadrature::{composite_gauss_legendre, graded_unit_breaks};
use crate::single::ISOTROPIC_PHASE;
use crate::{Result, TransportError, validate};

/// Fixed-point iterations stop when no node value changes by more than this (relative).
const ITERATION_TOLERANCE: f64 = 1.0e-14;
/// Ample for Λ = 1, the slowest case (the error contracts by roughly a constant factor per sweep).
const MAX_ITERATIONS: usize = 20_000;

/// The H-function tabulated at Gauss–Legendre nodes; values elsewhere follow from the integral equation
/// itself (Nyström interpolation), so they are as accurate as the node values.
#[derive(Clone, Debug)]
pub struct HFunction {
    albedo: f64,
    nodes: Vec<f64>,
    weights: Vec<f64>,
    values: Vec<f64>,
}

impl HFunction {
    /// Solves for the H-function of isotropic scattering with single-scattering albedo Λ ∈ [0, 1].
    pub fn new(albedo: f64) -> Result<Self> {
        validate::albedo(albedo)?;
        // Panels graded towards μ = 0, where H has a μ ln μ term.
        let (nodes, weights) = composite_gauss_legendre(&graded_unit_breaks(6), 16);
        let mut function = Self {
            albedo,
            values: vec![1.0; nodes.len()],
            nodes,
            weights,
        };
        for _ in 0..MAX_ITERATIONS {
            let updated: Vec<f64> = function
                .nodes
                .iter()
                .zip(&function.values)
                .map(|(&mu, &old)| 0.5 * (old + function.evaluate(mu)))
                .collect();
            let change = updated
                .iter()
                .zip(&function.values)
                .map(|(new, old)| ((new - old) / new).abs())
                .fold(0.0, f64::max);
            function.values = updated;
            if change < ITERATION_TOLERANCE {
                return Ok(function);
            }
        }
        Err(TransportError::Discretisation(
            "H-function iteration did not converge",
        ))
    }

    /// `H(μ)` from the integral equation with the current node values.
    fn evaluate(&self, mu: f64) -> f64 {
        let integral: f64 = self
            .nodes
            .iter()
            .zip(&self.weights)
            .zip(&self.values)
            .map(|((&node, &weight), &value)| weight * node * value / (mu + node))
            .sum();
        1.0 / ((1.0 - self.albedo).sqrt() + 0.5 * self.albedo * integral)
    }

    /// `H(μ)` for `mu` ∈ [0, 1] (dimensionless).
    pub fn value(&self, mu: f64) -> Result<f64> {
        validate::emergent_cosine(mu)?;
        Ok(self.evaluate(mu))
    }

    /// Moment `∫_0^1 μ^n H(μ) dμ` (dimensionless); `n = 0` is `2(1 − √(1−Λ))/Λ` analytically.
    pub fn moment(&self, order: i32) -> f64 {
        self.nodes
            .iter()
            .zip(&self.weights)
            .zip(&self.values)
            .map(|((&node, &weight), &value)| weight * node.powi(order) * value)
            .sum()
    }

    /// Diffusely reflected radiance of a semi-infinite medium, `Λ/(4π) μ0/(μ+μ0) H(μ) H(μ0)`, per unit
    /// irradiance normal to the beam (sr⁻¹); `mu0` ∈ (0, 1] towards the light, `mu` ∈ [0, 1].
    pub fn semi_infinite_reflected_radiance(&self, mu0: f64, mu: f64) -> Result<f64> {
        validate::incident_cosine(mu0)?;
        validate::emergent_cosine(mu)?;
        Ok(self.albedo * ISOTROPIC_PHASE * mu0 / (mu + mu0)
            * self.evaluate(mu)
            * self.evaluate(mu0))
    }
}
