//! Input validation shared by the public functions: typed errors, never silent clamps.

use crate::{Result, TransportError};

/// Optical thickness τ1: finite and > 0.
pub(crate) fn optical_thickness(tau1: f64) -> Result<f64> {
    if tau1.is_finite() && tau1 > 0.0 {
        Ok(tau1)
    } else {
        Err(TransportError::OpticalThickness(tau1))
    }
}

/// Single-scattering albedo Λ in [0, 1].
pub(crate) fn albedo(albedo: f64) -> Result<f64> {
    if (0.0..=1.0).contains(&albedo) {
        Ok(albedo)
    } else {
        Err(TransportError::Albedo(albedo))
    }
}

/// Incident cosine μ0 in (0, 1]: grazing incidence carries no flux and is not a beam.
pub(crate) fn incident_cosine(mu0: f64) -> Result<f64> {
    if mu0 > 0.0 && mu0 <= 1.0 {
        Ok(mu0)
    } else {
        Err(TransportError::Cosine {
            name: "mu0",
            range: "(0, 1]",
            value: mu0,
        })
    }
}

/// Emergent cosine μ in [0, 1]; μ = 0 is the grazing limit, which is finite.
pub(crate) fn emergent_cosine(mu: f64) -> Result<f64> {
    if (0.0..=1.0).contains(&mu) {
        Ok(mu)
    } else {
        Err(TransportError::Cosine {
            name: "mu",
            range: "[0, 1]",
            value: mu,
        })
    }
}
