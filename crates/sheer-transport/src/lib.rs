//! All-orders radiative transfer through a plane-parallel slab with isotropic scattering.
//!
//! This crate is the independent reference against which the single-scattering thin-slab model of
//! Frisvad, Christensen & Falster 2005 (section 3, eqs. (2)–(5)) is judged. It contains
//!
//! * [`expint`]: the exponential integrals `E_n(x)` (the kernels of plane-parallel transfer);
//! * [`single`]: the paper's single-scattering radiances, eqs. (4)–(5), and their Henyey–Greenstein
//!   generalisation (Blinn 1982);
//! * [`slab`]: the exact (all orders of scattering) solver: the integral equation for the source
//!   function along optical depth, solved by Nyström product integration (see the crate README for the
//!   choice of method and its convergence);
//! * [`hfunction`]: Chandrasekhar's H-function for isotropic scattering (the semi-infinite limit);
//! * [`monte_carlo`]: an analog photon-transport simulation of the same slab, used to check the solver,
//!   and of two parallel slabs (translucent shadows);
//! * [`table`]: a precomputed table of the multiply-scattered radiance over (τ1, μ0, μ, Λ) with its
//!   quadrilinear sampler, for real-time use;
//! * [`diffuse`]: the all-orders response `R_d(μ)`, `T_d(μ)` to uniform radiance over a whole face's
//!   hemisphere, and its table over (τ1, Λ, μ) on the same axes.
//!
//! Conventions used throughout: optical depths are dimensionless; `μ0` is the cosine between the surface
//! normal and the direction towards the light, `μ` the cosine between the normal of the surface the light
//! leaves through and the direction towards the viewer, both in `[0, 1]`. Radiances are in W m⁻² sr⁻¹ per
//! unit irradiance (W m⁻²) measured on a plane normal to the incident beam (so the flux crossing the lit
//! surface is `μ0` per unit area), which is eqs. (4)–(5) with `E(0) = 1` and `μ0` counted once.

// No unsafe code in this crate: forbidden here, where the workspace only denies it.
#![forbid(unsafe_code)]
// Standard output belongs to the program using the library: results and errors are returned.
#![warn(clippy::print_stdout)]

pub mod diffuse;
pub mod expint;
pub mod hfunction;
pub mod monte_carlo;
pub mod quadrature;
pub mod single;
pub mod slab;
pub mod table;

mod linalg;
mod validate;

pub use diffuse::{DiffuseResponse, DiffuseTable};
pub use hfunction::HFunction;
pub use monte_carlo::{
    FaceTally, Incidence, MonteCarloTally, SlabLayer, TwoSlabTally, simulate_photons,
    simulate_photons_diffuse, simulate_two_slabs,
};
pub use single::{
    henyey_greenstein_phase, single_scattered_reflected_radiance,
    single_scattered_reflected_radiance_hg, single_scattered_transmitted_radiance,
    single_scattered_transmitted_radiance_hg,
};
pub use slab::{Discretisation, SlabSolution, SlabSolver};
pub use table::{AllOrdersTable, TableFace, TableSpec};

/// Everything that can go wrong in this crate: bad physical input or a malformed table file.
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    /// Optical thickness must be finite and positive (a zero-thickness slab does not scatter).
    #[error("optical thickness must be finite and > 0, got {0}")]
    OpticalThickness(f64),
    /// Single-scattering albedo Λ = σs/σt must lie in [0, 1].
    #[error("single-scattering albedo must lie in [0, 1], got {0}")]
    Albedo(f64),
    /// A direction cosine (μ or μ0) must lie in its stated range.
    #[error("direction cosine {name} must lie in {range}, got {value}")]
    Cosine {
        /// Which cosine (`"mu"`, `"mu0"`).
        name: &'static str,
        /// The accepted range, in words.
        range: &'static str,
        /// The value given.
        value: f64,
    },
    /// Henyey–Greenstein asymmetry must lie strictly inside (−1, 1).
    #[error("Henyey-Greenstein asymmetry must lie in (-1, 1), got {0}")]
    Asymmetry(f64),
    /// Azimuth difference must be finite.
    #[error("azimuth difference must be finite, got {0}")]
    Azimuth(f64),
    /// A discretisation parameter is out of its sensible range.
    #[error("invalid discretisation: {0}")]
    Discretisation(&'static str),
    /// A query outside the range covered by the precomputed table.
    #[error("{name} = {value} lies outside the table range [{min}, {max}]")]
    OutsideTable {
        /// Which coordinate.
        name: &'static str,
        /// The value given.
        value: f64,
        /// Lower end of the table.
        min: f64,
        /// Upper end of the table.
        max: f64,
    },
    /// The file is not a valid all-orders or diffuse table.
    #[error("malformed table file: {0}")]
    TableFormat(String),
    /// Monte Carlo photon count must be positive.
    #[error("photon count must be > 0")]
    PhotonCount,
    /// Monte Carlo μ bins per face: 1 to [`monte_carlo::MAX_BINS`].
    #[error("bins per face must lie in [1, {max}], got {0}", max = monte_carlo::MAX_BINS)]
    Bins(usize),
    /// A tally count cannot exceed the photons launched.
    #[error("a count of {count} photons exceeds the {photons} launched")]
    Count {
        /// The count asked about.
        count: u64,
        /// Photons launched.
        photons: u64,
    },
    /// Reading or writing a table file failed.
    #[error("table i/o: {0}")]
    Io(#[from] std::io::Error),
}

/// Shorthand for results in this crate.
pub type Result<T> = std::result::Result<T, TransportError>;
