//! Thin-slab shading after Frisvad, Christensen & Falster (2005), "Efficient light scattering through thin
//! semi-transparent objects": the single-scattering model of a locally plane-parallel, optically thin slab
//! (their eqs. 4–9) on the CPU ([`model`], the `f64` reference) and on wgpu ([`render`]), plus a CSV
//! evaluator for checking the model from outside ([`csv`]) and independent numerics ([`mod@reference`]).
//!
//! See `README.md` for the irradiance-convention finding and the cancellation-free form of eq. (5).

pub mod csv;
pub mod model;
pub mod reference;
pub mod render;

pub use csv::{SlabCsvError, evaluate_csv};
pub use model::{
    Albedo, Cosine, IrradianceConvention, LitSide, OpticalThickness, SlabParameterError,
    SlabShading, direct_transmission, point_light_beam_normal_irradiance,
    point_light_surface_irradiance, single_scattered_reflected_radiance,
    single_scattered_transmitted_radiance, slab_shading,
};
