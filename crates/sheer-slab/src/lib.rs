//! Thin-slab shading after Frisvad, Christensen & Falster (2005), "Efficient light scattering through thin
//! semi-transparent objects": the single-scattering model of a locally plane-parallel, optically thin slab
//! (their eqs. 4–9) on the CPU ([`model`], the `f64` reference) and on wgpu ([`render`]), plus a CSV
//! evaluator for checking the model from outside ([`csv`]) and, for tests (the `test-support` feature),
//! independent numerics (`reference`).
//! [`all_orders`] adds the choice of scattering model: `single` (the paper) or `all-orders` (eqs. 4–5
//! plus the multiply-scattered radiance from `sheer-transport`'s precomputed table), on every path.
//!
//! See `README.md` for the irradiance-convention finding and the cancellation-free form of eq. (5).

// No unsafe code in this crate: forbidden here, where the workspace only denies it.
#![forbid(unsafe_code)]
// Standard output belongs to the program using the library: results and errors are returned.
#![warn(clippy::print_stdout)]

pub mod all_orders;
pub mod csv;
pub mod model;
#[cfg(any(test, feature = "test-support"))]
pub mod reference;
pub mod render;
pub mod sky;

pub use all_orders::{
    AllOrdersTable, Scattering, ScatteringOrders, TableLoadError, UnknownScatteringOrders,
    default_table_path, load_all_orders_table,
};
pub use csv::{SlabCsvError, evaluate_csv, evaluate_csv_with};
pub use model::{
    Albedo, Cosine, Face, IrradianceConvention, NormalsError, OpticalThickness, SlabParameterError,
    SlabShading, direct_transmission, point_light_beam_normal_irradiance,
    point_light_surface_irradiance, single_scattered_reflected_radiance,
    single_scattered_transmitted_radiance, slab_shading,
};
pub use sky::{DiffuseEnvironment, DiffuseTable, SkyError, SkyLight, load_diffuse_table};
