//! The fast paths of a grid's position-based step: the same arithmetic as [`crate::solver`]'s plain
//! sub-step, in the same order for every particle, laid out for the machine. The tests in `solver.rs`
//! hold every one of them to the plain code's bits.
//!
//! - [`grid_step`]: the sub-step on the state split by component, the grid's constraints in row
//!   strips, and the choice of schedule — pass by pass, the pipeline of a team of threads, or
//!   wavefronts of one or several sub-steps a pass down the rows (in parts, opposed or as a chain);
//! - [`grid_constraints`]: the twelve strip batches and their loops ([`strips_avx512`] with AVX-512);
//! - [`grid_wind`]: the wind's shares and the forces summed row by row, vectorised;
//! - [`wavefront`], [`pipeline`], [`parallel`]: the schedules and the team of threads they run on;
//! - [`components`], [`staggered`], [`vectorise`]: the split state, its allocation and the CPU dispatch.
//!
//! All of sheer-cloth's `unsafe` lives here, each block with a `// SAFETY:` comment: parallel passes
//! write disjoint parts of one buffer (a colouring or a partition guarantees no index is touched by two
//! threads at once), and the AVX-512 strips use raw-pointer loads and stores.

pub(crate) mod components;
pub(crate) mod grid_constraints;
pub(crate) mod grid_step;
pub(crate) mod grid_wind;
pub(crate) mod parallel;
pub(crate) mod pipeline;
pub(crate) mod staggered;
#[cfg(target_arch = "x86_64")]
pub(crate) mod strips_avx512;
pub(crate) mod vectorise;
pub(crate) mod wavefront;
