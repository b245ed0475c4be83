//! Per-vertex normals always turned toward the lit side, for any triangle mesh.
//!
//! Frisvad, Christensen & Falster, "Efficient Light Scattering through Thin Semi-Transparent
//! Objects" (2005), render a thin slab (a flag, a curtain) as a surface whose normals "are always
//! turned outwards such that μ0 = cos θ0 > 0", i.e. toward the light. Which side the eye is on then
//! picks eq. (7) (front-lit, with L+ of eq. 4) or eq. (8) (back-lit, with L− of eq. 5). This crate
//! owns that convention:
//! - [`NormalUpdater`]: topology analysed once, then per frame unit vertex normals with
//!   n · ω0′ ≥ 0 toward a [`Light`] (point or directional), in place, allocation-free,
//!   deterministic, parallel with rayon;
//! - [`lit_side_cosines`] (and the same rule in WGSL, [`LIT_SIDE_WGSL`]): per fragment, turn the
//!   interpolated normal toward the light again and decide eq. (7) or (8) with μ0 and μ.
//!
//! Units: positions in metres (any consistent length unit works: only directions are output).
//!
//! ```
//! use glam::Vec3;
//! use sheer_normals::{Face, Light, NormalUpdater, lit_side_cosines};
//!
//! // One quad in the plane z = 0, its two triangles wound inconsistently.
//! let positions = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)];
//! let indices = [0, 1, 2, 1, 2, 3];
//! let mut updater = NormalUpdater::new(positions.len(), &indices)?;
//! let mut normals = [Vec3::ZERO; 4];
//!
//! // A light below the sheet: every normal is exactly −Z.
//! let light = Vec3::new(0.5, 0.5, -1.0);
//! updater.update(&positions, &Light::Point { position: light }, &mut normals)?;
//! assert!(normals.iter().all(|&n| n == -Vec3::Z));
//!
//! // An eye above the sheet sees it back-lit: eq. (8).
//! let side = lit_side_cosines(normals[0], light - positions[0], Vec3::new(0.0, 0.0, 2.0))?;
//! assert!(side.face == Face::Far && side.mu0 > 0.0 && side.mu > 0.0);
//! # Ok::<(), sheer_normals::NormalsError>(())
//! ```

// No unsafe code in this crate: forbidden here, where the workspace only denies it.
#![forbid(unsafe_code)]
// Standard output belongs to the program using the library: results and errors are returned.
#![warn(clippy::print_stdout)]

mod error;
mod light;
mod lit_side;
mod updater;
mod vector;

pub use error::NormalsError;
pub use light::{Light, MAX_COORDINATE};
pub use lit_side::{Face, LIT_SIDE_WGSL, LitSide, LitSideVector, lit_side_cosines};
pub use updater::{
    Execution, NormalOptions, NormalUpdater, PARALLEL_MIN_VERTICES, Weighting,
    vertex_normals_toward_light,
};
