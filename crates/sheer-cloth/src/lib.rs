//! # sheer-cloth
//!
//! A cloth simulator with every integrator a speed-versus-accuracy comparison needs, behind one
//! [`Simulation::step`]: mass–spring models integrated by explicit Euler, symplectic Euler, velocity
//! Verlet and implicit Euler (Baraff & Witkin 1998), and position-based PBD (Müller et al. 2007), XPBD
//! (Macklin et al. 2016) and small-steps XPBD (Macklin et al. 2019).
//!
//! The API is plain data plus a `step`, after rapier: a [`ClothModel`] (particles, triangles, springs,
//! pins), [`SimParams`] (SI units, serde), and a [`Simulation`] that owns the state.
//!
//! ```
//! use sheer_cloth::{ClothModel, GridSpec, SimParams, Simulation};
//!
//! let flag = ClothModel::grid(&GridSpec::default())?.with_hoist_pinned()?;
//! let mut sim = Simulation::new(flag, SimParams::default())?;
//! for _ in 0..60 {
//!     sim.step(1.0 / 60.0)?; // one second at 60 Hz
//! }
//! assert!(sim.positions().iter().all(|p| p.is_finite()));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Units: metres, kilograms, seconds, newtons. Results are bit-identical whatever rayon's thread count.
//!
//! Reading the source: `sim.rs` is the step; `solver.rs` the position-based sub-step on one screen
//! (forces, predict, project in batches, update velocities), which every fast path in `fast/` (a grid's
//! strips, vectorised loops, threads and wavefronts) is tested against bit for bit; `mass_spring.rs` the
//! force-based methods; `collision.rs` the contacts.

// Standard output belongs to the program using the library: results and errors are returned.
#![warn(clippy::print_stdout)]

// Unsafe code is denied workspace-wide and allowed only in the modules of `fast` that need it (and the
// CPU-dispatch blocks `fast::vectorise::by_cpu!` expands), each block with a `// SAFETY:` comment.
mod collision;
mod error;
mod fast;
mod intersections;
mod mass_spring;
mod model;
mod nearest;
mod params;
mod sim;
mod solver;
pub mod wind;

pub use error::{DivergenceReason, ModelError, ParamError, StepError};
pub use intersections::intersecting_triangle_pairs;
pub use model::{ClothModel, GridShape, GridSpec, Spring, SpringKind};
pub use params::{
    Collider, Collisions, DEFAULT_FLAG_WIND_RENEWAL_INTERVAL, DivergenceLimits, FLAG_POLE_RADIUS,
    Method, SimParams, SpringParams, Wind,
};
pub use sim::{SetupError, Simulation, StepInfo, StrainStatistics};

/// Re-exported so users need not depend on glam themselves.
pub use glam;
