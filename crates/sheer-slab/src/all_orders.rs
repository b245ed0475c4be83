//! The scattering model choice: `single` (the paper, Frisvad, Christensen & Falster 2005, eqs. (4)–(5))
//! or `all-orders` (eqs. (4)–(5) in closed form plus the multiply-scattered radiance of the same
//! isotropically scattering plane-parallel slab, interpolated from the table that `sheer-transport`
//! precomputes with its all-orders solver, `assets/all_orders_table.bin`).
//!
//! The table stores `ln f = ln(L_m/(Λ² μ0))`, the reduced orders-≥-2 radiance, over (τ1, Λ, μ0, μ) and
//! is sampled quadrilinearly in that logarithm (see `sheer_transport::table`). So the all-orders
//! diffuse radiance per unit irradiance normal to the beam (sr⁻¹) is
//!
//! `L = Λ·S(τ1, μ0, μ) + Λ²·μ0·e^{ln f(τ1, Λ, μ0, μ)}`,
//!
//! with `S` the single-scattering shape of eq. (4) (lit face) or eq. (5) (unlit face) divided by Λ. Per
//! unit albedo, as the renderer's per-vertex paths carry it: `L/Λ = S + Λ·μ0·e^{ln f}`. Direct
//! transmission `α = e^{−τ1/μ}` is the same in both models. The irradiance convention multiplies the
//! whole diffuse radiance, as it does eqs. (4)–(5).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use thiserror::Error;

pub use sheer_transport::AllOrdersTable;
pub(crate) use sheer_transport::{TableFace, TransportError};

use crate::model::{
    Albedo, Cosine, Face, IrradianceConvention, OpticalThickness, SlabParameterError, SlabShading,
    shading_from_diffuse_radiance, single_scattered_radiance,
};

/// Which orders of scattering, named without the table that all orders need: what a scene file says.
/// With the `serde` feature: `single` or `all-orders`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ScatteringOrders {
    /// Single scattering only: eqs. (4)–(5), the paper's model.
    #[default]
    #[cfg_attr(feature = "serde", serde(rename = "single"))]
    Single,
    /// All orders: eqs. (4)–(5) plus the multiply-scattered part from a precomputed table.
    #[cfg_attr(feature = "serde", serde(rename = "all-orders"))]
    All,
}

impl ScatteringOrders {
    /// The user-facing name, as in a scene file: `single` or `all-orders`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Single => "single",
            Self::All => "all-orders",
        }
    }
}

/// A name that is neither `single` nor `all-orders`.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("unknown scattering model {0:?}: expected single or all-orders")]
pub struct UnknownScatteringOrders(pub String);

impl std::str::FromStr for ScatteringOrders {
    type Err = UnknownScatteringOrders;

    fn from_str(name: &str) -> Result<Self, Self::Err> {
        [Self::Single, Self::All]
            .into_iter()
            .find(|orders| orders.name() == name)
            .ok_or_else(|| UnknownScatteringOrders(name.to_owned()))
    }
}

/// Which orders of scattering the slab's diffuse radiance includes.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Scattering {
    /// Single scattering only: eqs. (4)–(5), the paper's model.
    #[default]
    Single,
    /// All orders: eqs. (4)–(5) plus the multiply-scattered part from the precomputed table.
    AllOrders(Arc<AllOrdersTable>),
}

impl Scattering {
    /// `orders` with, for all orders, the table `all_orders_table` gives (called only then).
    pub fn with_orders<E>(
        orders: ScatteringOrders,
        all_orders_table: impl FnOnce() -> Result<Arc<AllOrdersTable>, E>,
    ) -> Result<Self, E> {
        Ok(match orders {
            ScatteringOrders::Single => Self::Single,
            ScatteringOrders::All => Self::AllOrders(all_orders_table()?),
        })
    }

    /// Which orders, without the table.
    pub fn orders(&self) -> ScatteringOrders {
        match self {
            Self::Single => ScatteringOrders::Single,
            Self::AllOrders(_) => ScatteringOrders::All,
        }
    }

    /// The user-facing name: `single` or `all-orders`.
    pub fn name(&self) -> &'static str {
        self.orders().name()
    }
}

/// Why the all-orders table could not be loaded.
#[derive(Debug, Error)]
pub enum TableLoadError {
    /// The file is missing or unreadable.
    #[error("cannot read the all-orders table {path}: {source}")]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// The file is not an all-orders table (bad magic, version, size or values).
    #[error("{path} is not a valid all-orders table: {reason}")]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
}

/// The shipped table: `assets/all_orders_table.bin` at the workspace root (regenerate with
/// `cargo run -p sheer-transport --release --example make_table`).
pub fn default_table_path() -> &'static Path {
    Path::new(AllOrdersTable::DEFAULT_PATH)
}

/// Reads and checks an all-orders table file (magic, version, sizes, every value finite).
pub fn load_all_orders_table(
    path: impl AsRef<Path>,
) -> Result<Arc<AllOrdersTable>, TableLoadError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| TableLoadError::Unreadable {
        path: path.to_path_buf(),
        source,
    })?;
    AllOrdersTable::from_bytes(&bytes)
        .map(Arc::new)
        .map_err(|error| TableLoadError::Corrupt {
            path: path.to_path_buf(),
            reason: match error {
                TransportError::TableFormat(reason) => reason,
                other => other.to_string(),
            },
        })
}

/// Relative slack on the table's τ1 range admitted by the renderer: τ1 arrives there in `f32`, where the
/// table's ends are not representable (`0.01f32 < 0.01`). Values inside the slack are evaluated at the
/// end node; the slack is 17 `f32` ulps, far below any physical meaning.
pub(crate) const TABLE_RANGE_SLACK: f64 = 1e-6;

/// The table's τ1 range `(min, max)`.
pub(crate) fn table_tau_range(table: &AllOrdersTable) -> (f64, f64) {
    let spec = table.spec();
    (spec.tau_min, spec.tau_max)
}

fn face(side: Face) -> TableFace {
    match side {
        Face::Lit => TableFace::Reflected,
        Face::Far => TableFace::Transmitted,
    }
}

/// The multiply-scattered (orders ≥ 2) radiance per unit albedo and unit irradiance normal to the beam,
/// `L_m/Λ = Λ·μ0·e^{ln f}` (sr⁻¹), on the face the eye is on. τ1 must lie in the table's range.
pub(crate) fn multiple_scattered_radiance_per_albedo(
    table: &AllOrdersTable,
    side: Face,
    optical_thickness: OpticalThickness,
    albedo: Albedo,
    mu0: Cosine,
    mu: Cosine,
) -> Result<f64, SlabParameterError> {
    let (tau1, lambda, mu0, mu) = (optical_thickness.get(), albedo.get(), mu0.get(), mu.get());
    let log_value = table
        .log_reduced_multiple_radiance(face(side), tau1, lambda, mu0, mu)
        .map_err(|error| match error {
            TransportError::OutsideTable {
                value, min, max, ..
            } => SlabParameterError::OutsideTable { value, min, max },
            _ => SlabParameterError::TableQuery {
                tau1,
                albedo: lambda,
                mu0,
                mu,
            },
        })?;
    Ok(lambda * mu0 * log_value.exp())
}

/// [`multiple_scattered_radiance_per_albedo`] for the three colour channels at once (the table's
/// cosine and τ1 positions are shared where they can be); equal to three single calls bit for bit.
pub(crate) fn multiple_scattered_radiance_per_albedo_rgb(
    table: &AllOrdersTable,
    side: Face,
    optical_thickness: [OpticalThickness; 3],
    albedo: [Albedo; 3],
    mu0: Cosine,
    mu: Cosine,
) -> Result<[f64; 3], SlabParameterError> {
    let (tau1, lambda) = (optical_thickness.map(|t| t.get()), albedo.map(|a| a.get()));
    let log_values = table
        .log_reduced_multiple_radiance_channels(face(side), tau1, lambda, mu0.get(), mu.get())
        .map_err(|error| match error {
            TransportError::OutsideTable {
                value, min, max, ..
            } => SlabParameterError::OutsideTable { value, min, max },
            _ => SlabParameterError::TableQuery {
                tau1: tau1[0],
                albedo: lambda[0],
                mu0: mu0.get(),
                mu: mu.get(),
            },
        })?;
    Ok([0, 1, 2].map(|c| lambda[c] * mu0.get() * log_values[c].exp()))
}

/// Diffuse radiance on the face the eye is on, per unit irradiance normal to the beam (sr⁻¹), for the
/// chosen model: eq. (4) or (5), plus for `AllOrders` the interpolated multiply-scattered part.
pub fn diffuse_radiance(
    scattering: &Scattering,
    side: Face,
    optical_thickness: OpticalThickness,
    albedo: Albedo,
    mu0: Cosine,
    mu: Cosine,
) -> Result<f64, SlabParameterError> {
    let single = single_scattered_radiance(side, optical_thickness, albedo, mu0, mu);
    match scattering {
        Scattering::Single => Ok(single),
        Scattering::AllOrders(table) => {
            let per_albedo = multiple_scattered_radiance_per_albedo(
                table,
                side,
                optical_thickness,
                albedo,
                mu0,
                mu,
            )?;
            Ok(single + albedo.get() * per_albedo)
        }
    }
}

/// [`crate::model::slab_shading`] for either model: α and `L·E(0)` for the side the eye is on
/// (`beam_normal_irradiance` in W/m²).
#[allow(clippy::too_many_arguments)] // the model's inputs, each a validated physical quantity
pub fn slab_shading_with(
    scattering: &Scattering,
    optical_thickness: OpticalThickness,
    albedo: Albedo,
    mu0: Cosine,
    mu: Cosine,
    side: Face,
    beam_normal_irradiance: f64,
    convention: IrradianceConvention,
) -> Result<SlabShading, SlabParameterError> {
    shading_from_diffuse_radiance(
        optical_thickness,
        mu0,
        mu,
        beam_normal_irradiance,
        convention,
        || diffuse_radiance(scattering, side, optical_thickness, albedo, mu0, mu),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::slab_shading;

    fn table() -> Arc<AllOrdersTable> {
        load_all_orders_table(default_table_path()).expect("the shipped table")
    }

    #[test]
    fn single_is_the_paper_model_bit_for_bit() {
        let (tau, albedo) = (
            OpticalThickness::new(2.0).unwrap(),
            Albedo::new(0.9).unwrap(),
        );
        let (mu0, mu) = (
            Cosine::new("mu0", 0.6).unwrap(),
            Cosine::new("mu", 0.8).unwrap(),
        );
        for side in [Face::Lit, Face::Far] {
            let ours = slab_shading_with(
                &Scattering::Single,
                tau,
                albedo,
                mu0,
                mu,
                side,
                3.0,
                IrradianceConvention::NormalToBeam,
            )
            .unwrap();
            let paper = slab_shading(
                tau,
                albedo,
                mu0,
                mu,
                side,
                3.0,
                IrradianceConvention::NormalToBeam,
            )
            .unwrap();
            assert_eq!(ours, paper);
        }
    }

    #[test]
    fn all_orders_adds_the_tables_multiple_part() {
        let table = table();
        let all = Scattering::AllOrders(Arc::clone(&table));
        let (tau, albedo) = (
            OpticalThickness::new(2.0).unwrap(),
            Albedo::new(0.9).unwrap(),
        );
        let (mu0, mu) = (
            Cosine::new("mu0", 0.6).unwrap(),
            Cosine::new("mu", 0.8).unwrap(),
        );
        // The sum equals sheer-transport's own all-orders sampler (eq. (4)/(5) there is a different
        // closed form of the same expression: agreement to a few ulps).
        let ours = diffuse_radiance(&all, Face::Lit, tau, albedo, mu0, mu).unwrap();
        let theirs = table.reflected_radiance(2.0, 0.9, 0.6, 0.8).unwrap();
        assert!((ours - theirs).abs() <= 1e-14 * theirs, "{ours} {theirs}");
        let ours = diffuse_radiance(&all, Face::Far, tau, albedo, mu0, mu).unwrap();
        let theirs = table.transmitted_radiance(2.0, 0.9, 0.6, 0.8).unwrap();
        assert!((ours - theirs).abs() <= 1e-14 * theirs, "{ours} {theirs}");
        // Λ = 0 scatters nothing in either model.
        let zero = Albedo::new(0.0).unwrap();
        assert_eq!(
            diffuse_radiance(&all, Face::Far, tau, zero, mu0, mu).unwrap(),
            0.0
        );
    }

    #[test]
    fn outside_the_table_is_a_typed_error() {
        let all = Scattering::AllOrders(table());
        let albedo = Albedo::new(0.9).unwrap();
        let cosine = Cosine::new("mu", 0.5).unwrap();
        for tau in [1e-3, 20.0] {
            let error = diffuse_radiance(
                &all,
                Face::Lit,
                OpticalThickness::new(tau).unwrap(),
                albedo,
                cosine,
                cosine,
            )
            .unwrap_err();
            assert!(
                matches!(error, SlabParameterError::OutsideTable { value, .. } if value == tau),
                "{error}"
            );
        }
    }

    #[test]
    fn missing_and_corrupt_files_are_typed_errors() {
        let dir = std::env::temp_dir().join(format!("sheer-slab-table-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let missing = dir.join("missing.bin");
        assert!(matches!(
            load_all_orders_table(&missing),
            Err(TableLoadError::Unreadable { .. })
        ));
        let corrupt = dir.join("corrupt.bin");
        let mut bytes = std::fs::read(default_table_path()).unwrap();
        bytes.truncate(bytes.len() / 2);
        std::fs::write(&corrupt, &bytes).unwrap();
        let error = load_all_orders_table(&corrupt).unwrap_err();
        assert!(
            matches!(&error, TableLoadError::Corrupt { reason, .. } if reason.contains("bytes")),
            "{error}"
        );
        std::fs::write(&corrupt, b"not a table").unwrap();
        let error = load_all_orders_table(&corrupt).unwrap_err();
        assert!(
            matches!(&error, TableLoadError::Corrupt { reason, .. } if reason.contains("magic")),
            "{error}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
