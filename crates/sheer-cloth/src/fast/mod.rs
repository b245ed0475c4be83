//! The fast paths of a grid's position-based step: the same arithmetic as [`crate::solver`]'s plain
//! sub-step, in the same order for every particle, laid out for the machine. The tests in `solver.rs`
//! hold the schedules a step picks to the plain code's bits, and the schedule tests in `grid_step.rs`
//! hold every schedule a test can force to pass by pass.
//!
//! - [`grid_step`]: the sub-step on the state split by component, the grid's constraints in row
//!   strips, and the choice of schedule in one function (`Simulation::plan_grid_schedule`) — pass by
//!   pass, the pipeline of a team of threads, or wavefronts of one or several sub-steps a pass down
//!   the rows (in parts, or opposed on two threads);
//! - [`grid_constraints`]: the twelve strip batches and their loops ([`strips_avx512`] with AVX-512);
//! - [`grid_wind`]: the wind's shares and the forces summed row by row, vectorised;
//! - [`wavefront`], [`pipeline`], [`parallel`]: the schedules and the team of threads they run on;
//! - [`components`], [`staggered`], [`vectorise`]: the split state, its allocation and the CPU dispatch.
//!
//! All of sheer-cloth's `unsafe` lives in the modules here that allow it (and in the CPU-dispatch blocks
//! [`vectorise::by_cpu`] expands), each block with a `// SAFETY:` comment: parallel passes write
//! disjoint parts of one buffer (a partition of the rows or particles, and a batch's constraints sharing
//! no particle, guarantee no index is touched by two threads at once), and the AVX-512 strips use
//! raw-pointer loads and stores.

#[allow(unsafe_code)]
pub(crate) mod components;
#[allow(unsafe_code)]
pub(crate) mod grid_constraints;
#[allow(unsafe_code)]
pub(crate) mod grid_step;
#[allow(unsafe_code)]
pub(crate) mod grid_wind;
#[allow(unsafe_code)]
pub(crate) mod parallel;
pub(crate) mod pipeline;
pub(crate) mod staggered;
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
pub(crate) mod strips_avx512;
pub(crate) mod vectorise;
pub(crate) mod wavefront;
