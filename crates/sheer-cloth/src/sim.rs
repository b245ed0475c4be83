//! The simulation: state, `step(dt)`, pins, energies and divergence detection.
//!
//! State is kept in f64: with realistic fabric (a 1.75 cm cell of 0.2 kg/m² weighs 60 mg, so inverse
//! masses reach 10⁴–10⁵ kg⁻¹) the XPBD corrections are many orders of magnitude below the positions, and
//! f32 loses them — the precision failure reported for XPBD cloth in other engines. Renderers take f32
//! copies through [`Simulation::write_positions_f32`].

use std::ops::Range;

use glam::{DAffine3, DVec3, Vec3};

use crate::collision::Contacts;
use crate::error::{DivergenceReason, ModelError, ParamError, StepError};
use crate::fast::components::Xyz;
use crate::fast::grid_constraints::GridConstraints;
use crate::fast::grid_step::anchor_run_ends;
use crate::fast::grid_step::{GridSweep, PlanCache, Schedule};
use crate::fast::grid_wind::{
    BodyForce, SplitShares, add_grid_triangle_forces, grid_triangle_forces,
};
use crate::fast::parallel::{TeamSlot, fill, first_index_screened, sum};
use crate::fast::pipeline::Progress;
use crate::fast::vectorise::by_cpu;
use crate::model::{ClothModel, GridShape, Spring, SpringKind, check_length};
use crate::nearest::nearest_points;
use crate::params::{Method, SimParams, SpringParams, Wind};
use crate::wind::{WindField, corner_share_of_triangle_force};

/// Error building a [`Simulation`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SetupError {
    /// The cloth model cannot be simulated.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A parameter is outside its valid range.
    #[error(transparent)]
    Param(#[from] ParamError),
}

/// What a successful step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepInfo {
    /// Sub-steps the step was divided into (the method's `substeps`).
    pub substeps: u32,
    /// Implicit Euler only: the largest CG iteration count over the sub-steps.
    pub cg_iterations: u32,
    /// Implicit Euler only: the largest relative CG residual over the sub-steps.
    pub cg_relative_residual: f64,
}

/// What the packed constraints were built for: sub-step length, per-family (scale, α̃, γ), PBD or not.
pub(crate) type SolverKey = (f64, [(f64, f64, f64); 3], bool);

/// Summary of spring strains (dimensionless).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StrainStatistics {
    /// Mean strain over the springs.
    pub mean: f64,
    /// 99th-percentile strain: the one at index `⌊0.99 n⌋` of the `n` strains sorted ascending.
    pub p99: f64,
    /// Largest strain.
    pub max: f64,
}

/// Compressed incidence lists: for particle `i`, `items[offsets[i]..offsets[i + 1]]`.
#[derive(Clone, Debug, Default)]
pub(crate) struct Incidence {
    pub offsets: Vec<u32>,
    /// `element << 1 | side` for springs (side 0 = end `a`), the triangle index for triangles.
    pub items: Vec<u32>,
}

impl Incidence {
    fn build(particle_count: usize, pairs: impl Iterator<Item = (usize, u32)> + Clone) -> Self {
        let mut counts = vec![0u32; particle_count + 1];
        for (particle, _) in pairs.clone() {
            counts[particle + 1] += 1;
        }
        for i in 0..particle_count {
            counts[i + 1] += counts[i];
        }
        let mut cursor = counts.clone();
        let mut items = vec![0u32; counts[particle_count] as usize];
        for (particle, item) in pairs {
            items[cursor[particle] as usize] = item;
            cursor[particle] += 1;
        }
        Incidence {
            offsets: counts,
            items,
        }
    }

    #[inline]
    pub fn of(&self, particle: usize) -> &[u32] {
        &self.items[self.offsets[particle] as usize..self.offsets[particle + 1] as usize]
    }
}

/// Scratch vectors of the implicit solver, allocated once.
#[derive(Clone, Debug, Default)]
pub(crate) struct CgScratch {
    pub blocks: Vec<glam::DMat3>,
    pub diagonal: Vec<DVec3>,
    pub rhs: Vec<DVec3>,
    pub delta_velocity: Vec<DVec3>,
    pub residual: Vec<DVec3>,
    pub direction: Vec<DVec3>,
    pub product: Vec<DVec3>,
    pub preconditioned: Vec<DVec3>,
    pub spring_terms: Vec<DVec3>,
}

/// Particles per thread of a team from which it claims its passes chunk by chunk
/// ([`TeamSlot::lead`], [`team_claims_its_passes`]); below it each thread keeps its own part of the
/// cloth, and a grid's position-based step runs as one pass of the pipeline. Why 86 016 on two
/// threads: the pipeline was faster than claiming up to 82 944 particles and slower from 90 000, likely
/// where the data a step touches outgrows the two cores' caches; counted per thread because a larger
/// team gives each thread fewer rows of the same cloth.
pub(crate) const TEAM_CLAIMS_FROM_PARTICLES_PER_THREAD: usize = 43_008;

/// Rows of a grid per thread of its team: a team takes at most `rows / TEAM_ROWS_PER_THREAD`
/// threads, whatever rayon's pool holds. The pipeline needs each thread's rows to outnumber the
/// rows its stages reach (two up and one down, `pipeline.rs`), and its cuts follow the rows' work,
/// so a part may get a row less than the mean (with four rows a thread, 5 × 12 in three parts does
/// not fit; five fit every grid of 10–200 rows, `the_team_the_rows_allow_fits_the_pipeline`). A
/// team too large for it steps sub-step by sub-step, 220 hand-offs a frame of small-steps XPBD ×20
/// across all its threads: on a 16-core machine the default flag (46 rows) took 0.79–1.18 ms a frame
/// on teams of 4–11 threads and 1.5–53.8 ms on 12 and 16. At least two, so that a grid of few rows still runs on a team rather
/// than on rayon's pool, whose hand-off is slower than a pass.
pub(crate) const TEAM_ROWS_PER_THREAD: usize = 5;

/// The threads of the team that steps a grid of `rows` rows when rayon's pool holds `pool_threads`
/// ([`TEAM_ROWS_PER_THREAD`]).
pub(crate) fn team_threads_for_rows(pool_threads: usize, rows: usize) -> usize {
    pool_threads.min((rows / TEAM_ROWS_PER_THREAD).max(2))
}

/// Whether a team of `threads` claims its passes chunk by chunk on a cloth of `particles`
/// ([`TEAM_CLAIMS_FROM_PARTICLES_PER_THREAD`]).
pub(crate) fn team_claims_its_passes(particles: usize, threads: usize) -> bool {
    particles >= TEAM_CLAIMS_FROM_PARTICLES_PER_THREAD.saturating_mul(threads)
}

/// Which code a step runs: the fast paths (strips, row passes, wavefronts, threads) where a grid has
/// them, or the plain code of `solver.rs` for every cloth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Path {
    /// The fast paths on a grid, in the schedule the sweep asks for ([`GridSweep::Auto`] in
    /// production); a general mesh steps through the plain code.
    Fast(GridSweep),
    /// The plain code on every cloth: the tests' reference (production never asks for it).
    #[cfg_attr(not(test), allow(dead_code))]
    Plain,
}

/// A running cloth simulation. Build it from a [`ClothModel`] and [`SimParams`], then call
/// [`step`](Simulation::step).
#[derive(Clone, Debug)]
pub struct Simulation {
    pub(crate) params: SimParams,
    pub(crate) wind: WindField,
    pub(crate) grid: Option<GridShape>,
    /// The grid when the triangles are its own triangulation ([`GridShape::triangles`]): the wind pass
    /// then runs row by row ([`grid_triangle_forces`]).
    pub(crate) grid_triangulation: Option<GridShape>,
    pub(crate) rest_positions: Vec<DVec3>,
    pub(crate) masses: Vec<f64>,
    /// Zero for pinned particles.
    pub(crate) inverse_masses: Vec<f64>,
    pub(crate) pinned_indices: Vec<u32>,
    pub(crate) triangles: Vec<[u32; 3]>,
    /// Springs in colour order: the springs of `colours[c]` share no particle.
    pub(crate) springs: Vec<Spring>,
    pub(crate) colours: Vec<Range<usize>>,
    /// Springs that found no free colour among 64 (very high valence meshes): solved serially, last.
    pub(crate) uncoloured: Range<usize>,
    /// (stiffness N/m, damping N·s/m) per [`SpringKind`]; stiffness 0 means switched off.
    pub(crate) family: [(f64, f64); 3],
    pub(crate) spring_incidence: Incidence,
    pub(crate) triangle_incidence: Incidence,
    pub(crate) positions: Vec<DVec3>,
    pub(crate) velocities: Vec<DVec3>,
    /// Long-range attachments: particle `i` may lie at most `tether_lengths[i]` (m) from pinned particle
    /// `pinned_indices[tether_anchors[i]]`. Pinned particles (anchored to themselves), and every particle
    /// of a cloth without pins, have an infinite length (never pulled).
    pub(crate) tether_anchors: Vec<u32>,
    pub(crate) tether_lengths: Vec<f64>,
    /// Per particle, the index after the last of the particles from it on that share its anchor
    /// (`fast::grid_step::anchor_run_ends`).
    pub(crate) tether_run_ends: Vec<u32>,
    /// On a grid, how many rows at most lie between a particle and its anchor (0 without pins): how far
    /// ahead of a row's attachments the pins' positions must be known.
    pub(crate) tether_row_reach: usize,
    /// Scratch: where each pinned particle is, in `pinned_indices` order, read by the attachments; twice
    /// over, one copy per sub-step parity (a whole step in passes, `Simulation::whole_step`).
    pub(crate) tether_pin_positions: Vec<DVec3>,
    /// Where each pinned particle (in `pinned_indices` order) must be at the end of the next step.
    pub(crate) pin_targets: Vec<DVec3>,
    pub(crate) pin_starts: Vec<DVec3>,
    pub(crate) time: f64,
    pub(crate) step_count: u64,
    // Scratch, allocated once.
    pub(crate) forces: Vec<DVec3>,
    pub(crate) spring_forces: Vec<DVec3>,
    pub(crate) triangle_forces: Vec<DVec3>,
    /// The position-based methods' state during a step, split by component ([`Xyz`]): the positions,
    /// the velocities (split from and joined into `positions` and `velocities` at the ends of a step)
    /// and the start positions of the sub-step.
    pub(crate) split_positions: Xyz,
    pub(crate) split_velocities: Xyz,
    pub(crate) previous_positions: Xyz,
    /// The start positions of a sub-step on the joined state (a general mesh, `solver.rs`), made by
    /// the first plain sub-step: a grid's fast paths never need them.
    pub(crate) joined_previous: Vec<DVec3>,
    /// The position-based methods' wind shares on a grid ([`SplitShares`]).
    pub(crate) split_shares: SplitShares,
    pub(crate) lambdas: Vec<f64>,
    pub(crate) backup_positions: Vec<DVec3>,
    pub(crate) backup_velocities: Vec<DVec3>,
    /// Velocity Verlet reuses the end-of-step acceleration; any outside change invalidates it.
    pub(crate) cached_forces_valid: bool,
    /// The held aerodynamic forces must be recomputed (start of a step, or a renewal due by
    /// `wind.renewal_interval`).
    pub(crate) wind_stale: bool,
    pub(crate) cg: CgScratch,
    /// Position-based solvers: the constraints with their per-step constants, valid for `denominator_key`.
    pub(crate) packed: Vec<crate::solver::PackedConstraint>,
    pub(crate) denominator_key: Option<SolverKey>,
    /// Helper threads of the position-based grid solver (empty until a parallel step needs them).
    pub(crate) team: TeamSlot,
    /// The parts' progress through a pipelined sub-step ([`Pipeline`](crate::fast::pipeline::Pipeline)).
    pub(crate) progress: Progress,
    pub(crate) pipeline_plan: PlanCache,
    /// Grids: the constraints in row strips, which the position-based solvers project instead of the
    /// colour batches.
    pub(crate) grid_constraints: Option<GridConstraints>,
    /// Whether the next pass of two opposed parts sweeps part 0 upwards: they turn round every pass,
    /// from step to step too, so that each pass starts on the rows the one before ended on.
    pub(crate) opposed_upward_first: bool,
    /// The contact pairs and their scratch (`collision.rs`).
    pub(crate) contacts: Contacts,
}

/// What the rows of a grid's first pass add to each particle's body force
/// ([`Simulation::prepare_row_forces`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowForces {
    /// The wind's corner shares, in `Simulation::split_shares`: the wind acts.
    pub shares: bool,
    /// The shares are due to be renewed this sub-step, with these parameters and this air velocity
    /// (m/s), before the rows read them.
    pub renew: Option<(Wind, DVec3)>,
}

pub(crate) fn family_index(kind: SpringKind) -> usize {
    match kind {
        SpringKind::Stretch => 0,
        SpringKind::Shear => 1,
        SpringKind::Bend => 2,
    }
}

fn family_coefficients(params: &SimParams) -> [(f64, f64); 3] {
    let pick = |p: &SpringParams| {
        if p.enabled {
            (p.stiffness, p.damping)
        } else {
            (0.0, 0.0)
        }
    };
    [
        pick(&params.stretch),
        pick(&params.shear),
        pick(&params.bend),
    ]
}

/// Greedy colouring: each spring gets the lowest colour used by neither of its particles. Springs that
/// find no colour among the first 64 go to a last batch that is solved serially.
fn colour_springs(
    particle_count: usize,
    springs: &[Spring],
) -> (Vec<Spring>, Vec<Range<usize>>, Range<usize>) {
    let mut used = vec![0u64; particle_count];
    let mut buckets: Vec<Vec<Spring>> = vec![Vec::new(); 65];
    for spring in springs {
        let (a, b) = (spring.a as usize, spring.b as usize);
        let free = !(used[a] | used[b]);
        let colour = free.trailing_zeros() as usize; // 64 when every colour is taken
        if colour < 64 {
            used[a] |= 1 << colour;
            used[b] |= 1 << colour;
        }
        buckets[colour].push(*spring);
    }
    let uncoloured_bucket = buckets.pop().unwrap_or_default();
    let mut ordered = Vec::with_capacity(springs.len());
    let mut ranges = Vec::new();
    for bucket in buckets {
        if !bucket.is_empty() {
            let start = ordered.len();
            ordered.extend(bucket);
            ranges.push(start..ordered.len());
        }
    }
    let start = ordered.len();
    ordered.extend(uncoloured_bucket);
    let uncoloured = start..ordered.len();
    (ordered, ranges, uncoloured)
}

impl Simulation {
    /// Builds a simulation at rest in the model's positions.
    pub fn new(model: ClothModel, params: SimParams) -> Result<Simulation, SetupError> {
        params.validate()?;
        // The model's fields are public: one built or edited by hand is checked here.
        model.validate()?;
        let n = model.positions.len();
        let (springs, colours, uncoloured) = colour_springs(n, &model.springs);
        let spring_incidence = Incidence::build(
            n,
            springs.iter().enumerate().flat_map(|(s, sp)| {
                [
                    (sp.a as usize, (s as u32) << 1),
                    (sp.b as usize, (s as u32) << 1 | 1),
                ]
            }),
        );
        let triangle_incidence = Incidence::build(
            n,
            model
                .triangles
                .iter()
                .enumerate()
                .flat_map(|(t, tri)| tri.map(|v| (v as usize, t as u32))),
        );
        let inverse_masses = model
            .masses
            .iter()
            .zip(&model.pinned)
            .map(|(&m, &p)| if p { 0.0 } else { 1.0 / m })
            .collect();
        let pinned_indices: Vec<u32> = (0..n as u32)
            .filter(|&i| model.pinned[i as usize])
            .collect();
        let pin_targets: Vec<DVec3> = pinned_indices
            .iter()
            .map(|&i| model.positions[i as usize])
            .collect();
        let spring_count = springs.len();
        let triangle_count = model.triangles.len();
        // Nearest pinned particle at rest, by straight-line distance (the geodesic on a flat sheet).
        // A pinned particle is anchored to itself, so that its row's attachments read no other row's pin.
        let mut pins_so_far = 0;
        let (tether_anchors, tether_lengths): (Vec<u32>, Vec<f64>) =
            nearest_points(&pin_targets, &model.positions)
                .into_iter()
                .zip(&model.pinned)
                .map(|(nearest, &pinned)| match nearest {
                    Some(anchor) if !pinned => anchor,
                    _ if pinned => {
                        pins_so_far += 1;
                        (pins_so_far - 1, f64::INFINITY)
                    }
                    _ => (0, f64::INFINITY),
                })
                .unzip();
        let tether_row_reach = match model.grid {
            Some(shape) if !pinned_indices.is_empty() => tether_anchors
                .iter()
                .enumerate()
                .map(|(i, &k)| {
                    let anchor = pinned_indices[k as usize] as usize;
                    (anchor / shape.columns).abs_diff(i / shape.columns)
                })
                .max()
                .unwrap_or(0),
            _ => 0,
        };
        let grid_triangulation = model
            .grid
            .filter(|shape| model.triangles == shape.triangles());
        // The wind's shares of a grid's cells, split ([`SplitShares`]).
        let cells = grid_triangulation.map_or(0, |g| (g.columns - 1) * (g.rows - 1));
        // Only a grid's state is ever split (`steps_split`); a general mesh never needs the arrays.
        let split = |n: usize| {
            if model.grid.is_some() {
                Xyz::zeros(n)
            } else {
                Xyz::default()
            }
        };
        Ok(Simulation {
            wind: WindField::new(&params.wind)?,
            family: family_coefficients(&params),
            params,
            grid_constraints: model
                .grid
                .and_then(|shape| GridConstraints::new(shape, &model.springs)),
            opposed_upward_first: false,
            grid_triangulation,
            grid: model.grid,
            masses: model.masses,
            inverse_masses,
            pin_starts: pin_targets.clone(),
            tether_run_ends: anchor_run_ends(&tether_anchors),
            tether_anchors,
            tether_lengths,
            tether_row_reach,
            tether_pin_positions: vec![DVec3::ZERO; 2 * pinned_indices.len()],
            pin_targets,
            pinned_indices,
            triangles: model.triangles,
            springs,
            colours,
            uncoloured,
            spring_incidence,
            triangle_incidence,
            velocities: vec![DVec3::ZERO; n],
            positions: model.positions.clone(),
            rest_positions: model.positions,
            time: 0.0,
            step_count: 0,
            forces: vec![DVec3::ZERO; n],
            spring_forces: vec![DVec3::ZERO; spring_count],
            triangle_forces: vec![DVec3::ZERO; triangle_count],
            split_positions: split(n),
            split_velocities: split(n),
            previous_positions: split(n),
            joined_previous: Vec::new(),
            split_shares: [Xyz::zeros(cells), Xyz::zeros(cells)],
            lambdas: vec![0.0; spring_count],
            backup_positions: vec![DVec3::ZERO; n],
            backup_velocities: vec![DVec3::ZERO; n],
            cached_forces_valid: false,
            wind_stale: true,
            cg: CgScratch::default(),
            packed: Vec::new(),
            denominator_key: None,
            team: TeamSlot::default(),
            progress: Progress::default(),
            pipeline_plan: PlanCache::default(),
            contacts: Contacts::default(),
        })
    }

    /// Advances the simulation by `dt` seconds, split into the method's sub-steps.
    ///
    /// On divergence (a non-finite value, a speed or a strain beyond [`DivergenceLimits`](crate::DivergenceLimits))
    /// the step is undone and [`StepError::Diverged`] returned: the state stays the last good one.
    pub fn step(&mut self, dt: f64) -> Result<StepInfo, StepError> {
        let (info, _) = self.step_through(dt, Path::Fast(GridSweep::Auto))?;
        Ok(info)
    }

    /// [`step`](Simulation::step) through the fast paths where the cloth has them (`Path::Fast(_)`), or
    /// through the plain code everywhere (`Path::Plain`, which the fast paths are tested against);
    /// with the schedule of a grid's step where it went whole
    /// ([`whole_step`](Simulation::whole_step)), for the tests to know what they compared.
    pub(crate) fn step_through(
        &mut self,
        dt: f64,
        path: Path,
    ) -> Result<(StepInfo, Option<Schedule>), StepError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(StepError::InvalidTimeStep(dt));
        }
        self.backup_positions.copy_from_slice(&self.positions);
        self.backup_velocities.copy_from_slice(&self.velocities);
        for (k, &i) in self.pinned_indices.iter().enumerate() {
            self.pin_starts[k] = self.positions[i as usize];
        }
        let substeps = self.params.method.substeps();
        let h = dt / substeps as f64;
        self.wind_stale = true;
        let mut info = StepInfo {
            substeps,
            ..StepInfo::default()
        };
        let wind = self.params.wind;
        // Position-based methods on a grid run their sub-steps on a team of rayon's thread count, or
        // fewer on a grid of few rows (`TeamSlot`, `TEAM_ROWS_PER_THREAD`): eleven short passes per
        // sub-step on a grid, too short for rayon's hand-off.
        // The position-based methods on a grid work on the state split by component from here to the end
        // of the step (`components.rs`); on a general mesh they step the joined state (`solver.rs`).
        let sweep = match path {
            Path::Fast(sweep) if self.steps_split() => Some(sweep),
            _ => None,
        };
        let split = sweep.is_some();
        let team_threads = match self.grid {
            Some(grid) if split && self.parallel() => {
                team_threads_for_rows(rayon::current_num_threads(), grid.rows)
            }
            _ => 1,
        };
        if split {
            self.split_positions.split_from(&self.positions);
            self.split_velocities.split_from(&self.velocities);
        }
        let mut team = std::mem::take(&mut self.team);
        // Each thread keeps its own rows, in its core's caches, while its share of the cloth is small
        // enough for that to pay (measured: `TEAM_CLAIMS_FROM_PARTICLES_PER_THREAD`); beyond that the
        // team's passes are claimed chunk by chunk, since one core may run slower than the other.
        let claim = team_claims_its_passes(self.positions.len(), team_threads);
        let (divergence, whole) = team.lead(team_threads, claim, || {
            // A grid's position-based step as one pass of the team, or as wavefronts of several
            // sub-steps, where it can go so; else (and always for the other methods) sub-step by
            // sub-step.
            let whole = sweep.and_then(|sweep| self.whole_step(h, self.time, substeps, sweep));
            for s in (0..substeps).filter(|_| whole.is_none()) {
                let t = self.time + s as f64 * h;
                // `wind.renewal_interval` > 0: the held aerodynamic forces are renewed at the first
                // force evaluation of every k-th sub-step (0 renews them at every evaluation).
                if wind.renewal_due(s, h) {
                    self.wind_stale = true;
                }
                self.prescribe_pins(s, substeps, h, split);
                match self.params.method {
                    Method::ExplicitEuler { .. } => self.explicit_euler_substep(h, t),
                    Method::SymplecticEuler { .. } => self.symplectic_euler_substep(h, t),
                    Method::Verlet { .. } => self.verlet_substep(h, t),
                    Method::ImplicitEuler {
                        cg_max_iterations,
                        cg_tolerance,
                        ..
                    } => {
                        let (iterations, residual) =
                            self.implicit_euler_substep(h, t, cg_max_iterations, cg_tolerance);
                        info.cg_iterations = info.cg_iterations.max(iterations);
                        info.cg_relative_residual = info.cg_relative_residual.max(residual);
                    }
                    Method::Pbd {
                        iterations,
                        stiffness,
                        ..
                    } => self.position_based(sweep, h, t, iterations, Some(stiffness)),
                    Method::Xpbd { iterations, .. } => {
                        self.position_based(sweep, h, t, iterations, None)
                    }
                    Method::SmallStepsXpbd { .. } => self.position_based(sweep, h, t, 1, None),
                }
                if self.params.collisions.any() {
                    self.project_contacts(h, split);
                }
                self.place_pins(s, substeps, split);
            }
            if split {
                self.join_split_state();
            }
            (self.divergence(), whole)
        });
        self.team = team;
        if let Some(reason) = divergence {
            self.positions.copy_from_slice(&self.backup_positions);
            self.velocities.copy_from_slice(&self.backup_velocities);
            self.cached_forces_valid = false;
            return Err(StepError::Diverged {
                step: self.step_count,
                reason,
            });
        }
        self.time += dt;
        self.step_count += 1;
        Ok((info, whole))
    }

    /// Where pinned particle `k` is after `fraction` of the current step (linear in time).
    fn pin_position(&self, k: usize, fraction: f64) -> DVec3 {
        self.pin_starts[k].lerp(self.pin_targets[k], fraction)
    }

    /// Whether a step works on the state split by component: the position-based methods on a grid.
    pub(crate) fn steps_split(&self) -> bool {
        self.params.method.is_position_based() && self.grid_constraints.is_some()
    }

    /// One position-based sub-step: on a grid's split state through the fast paths in the schedule
    /// `sweep` asks for, else plain.
    fn position_based(
        &mut self,
        sweep: Option<GridSweep>,
        h: f64,
        t: f64,
        iterations: u32,
        pbd: Option<f64>,
    ) {
        if let Some(sweep) = sweep {
            self.position_based_substep(h, t, iterations, pbd, sweep);
        } else {
            self.plain_position_based_substep(h, t, iterations, pbd);
        }
    }

    /// Gives pinned particles the velocity that carries them along their path during sub-step `s`, in
    /// the split state (`split`) or the joined one.
    pub(crate) fn prescribe_pins(&mut self, s: u32, substeps: u32, h: f64, split: bool) {
        for k in 0..self.pinned_indices.len() {
            let from = self.pin_position(k, s as f64 / substeps as f64);
            let to = self.pin_position(k, (s + 1) as f64 / substeps as f64);
            let i = self.pinned_indices[k] as usize;
            let velocity = (to - from) / h;
            if split {
                self.split_positions.set(i, from);
                self.split_velocities.set(i, velocity);
            } else {
                self.positions[i] = from;
                self.velocities[i] = velocity;
            }
        }
    }

    /// Puts pinned particles exactly on their path at the end of sub-step `s`.
    pub(crate) fn place_pins(&mut self, s: u32, substeps: u32, split: bool) {
        for k in 0..self.pinned_indices.len() {
            let i = self.pinned_indices[k] as usize;
            let at = self.pin_position(k, (s + 1) as f64 / substeps as f64);
            if split {
                self.split_positions.set(i, at);
            } else {
                self.positions[i] = at;
            }
        }
    }

    /// Projects the contacts of a position-based sub-step of `h` (s) on the split state (`split`) or the
    /// joined one, and adds what they moved a particle over `h` to its velocity: as if projected before
    /// the velocity update.
    pub(crate) fn project_contacts(&mut self, h: f64, split: bool) {
        // Large cloths list their contact pairs on rayon's threads (the same list).
        let parallel = self.parallel();
        let Simulation {
            params,
            contacts,
            rest_positions,
            inverse_masses,
            triangles,
            split_positions,
            split_velocities,
            previous_positions,
            positions,
            velocities,
            joined_previous,
            ..
        } = self;
        // What the contacts moved: particle, from, to (m).
        let mut moves = std::mem::take(&mut contacts.moves);
        moves.clear();
        if params.collisions.self_collision {
            let n = rest_positions.len();
            contacts.start.resize(n, DVec3::ZERO);
            contacts.now.resize(n, DVec3::ZERO);
            if split {
                previous_positions.join_into(&mut contacts.start);
                split_positions.join_into(&mut contacts.now);
            } else {
                contacts.start.copy_from_slice(joined_previous);
                contacts.now.copy_from_slice(positions);
            }
            contacts.project(
                &params.collisions,
                rest_positions,
                inverse_masses,
                triangles,
                parallel,
            );
            for (i, &after) in contacts.now.iter().enumerate() {
                let before = if split {
                    split_positions.as_ref().at(i)
                } else {
                    positions[i]
                };
                if after != before {
                    moves.push((i, before, after));
                }
            }
        } else {
            // Colliders alone move each particle by itself: only those in a collider's box are read
            // whole and kept off where they lie, nothing joined.
            if split {
                let x = split_positions.as_ref();
                contacts.list_near_colliders(&params.collisions, inverse_masses, |i| x.at(i));
            } else {
                contacts.list_near_colliders(&params.collisions, inverse_masses, |i| positions[i]);
            }
            for &i in &contacts.near_colliders {
                let i = i as usize;
                let (start, before) = if split {
                    let (start, now) = (previous_positions.as_ref(), split_positions.as_ref());
                    (start.at(i), now.at(i))
                } else {
                    (joined_previous[i], positions[i])
                };
                let after = contacts.kept_off_colliders(&params.collisions, start, before);
                if after != before {
                    moves.push((i, before, after));
                }
            }
        }
        for &(i, before, after) in &moves {
            let moved = (after - before) / h;
            if split {
                split_positions.set(i, after);
                let v = split_velocities.as_ref().at(i);
                split_velocities.set(i, v + moved);
            } else {
                positions[i] = after;
                velocities[i] += moved;
            }
        }
        contacts.moves = moves;
    }

    /// Writes the position-based methods' split state into `positions` and `velocities`: at the end of
    /// a step, and before a pass that reads them there ([`compute_forces`](Self::compute_forces)).
    pub(crate) fn join_split_state(&mut self) {
        self.split_positions.join_into(&mut self.positions);
        self.split_velocities.join_into(&mut self.velocities);
    }

    pub(crate) fn parallel(&self) -> bool {
        self.positions.len() >= self.params.parallel_min_particles
    }

    /// Whether the wind exerts any force: it blows and there are triangles for it to act on.
    pub(crate) fn wind_acts(&self) -> bool {
        self.params.wind.is_active() && !self.triangles.is_empty()
    }

    /// Whether the triangles' corner shares of the aerodynamic force are due to be renewed at time `time`
    /// (s): if so, the wind's parameters and the air velocity (m/s) to renew them with, and they count as
    /// renewed from here on.
    pub(crate) fn due_wind_renewal(&mut self, time: f64) -> Option<(Wind, DVec3)> {
        let refresh =
            self.wind_acts() && (self.wind_stale || self.params.wind.updated_every_substep());
        refresh.then(|| {
            self.wind_stale = false;
            (*self.wind.params(), self.wind.air_velocity(time))
        })
    }

    /// Renews the triangles' corner shares of the aerodynamic force (N) at time `time` in
    /// `self.triangle_forces` when they are due; whether the wind acts at all.
    fn refresh_wind_shares(&mut self, time: f64) -> bool {
        let wind_active = self.wind_acts();
        let Some((wind_params, air_velocity)) = self.due_wind_renewal(time) else {
            return wind_active;
        };
        let parallel = self.parallel();
        let Simulation {
            positions,
            velocities,
            triangle_forces,
            triangles,
            grid_triangulation,
            ..
        } = self;
        let (positions, velocities) = (&positions[..], &velocities[..]);
        if let Some(shape) = *grid_triangulation {
            grid_triangle_forces(
                shape,
                &wind_params,
                air_velocity,
                positions,
                velocities,
                triangle_forces,
                parallel,
            );
        } else {
            fill(triangle_forces, parallel, |t| {
                let corners = triangles[t].map(|i| i as usize);
                corner_share_of_triangle_force(
                    &wind_params,
                    corners.map(|i| positions[i]),
                    corners.map(|i| velocities[i]),
                    air_velocity,
                )
            });
        }
        wind_active
    }

    /// For the position-based solvers on a grid, which sum each row's forces in their first pass over
    /// the rows ([`predict_row_with_forces`](crate::fast::grid_wind::predict_row_with_forces)): what the rows add to the body force
    /// ([`RowForces`]), or, when the triangles are not the grid's own, `None` after summing the forces
    /// into `self.forces` ([`compute_forces`](Simulation::compute_forces)).
    pub(crate) fn prepare_row_forces(&mut self, time: f64) -> Option<RowForces> {
        let shares = self.wind_acts();
        if shares && self.grid_triangulation.is_none() {
            self.join_split_state();
            self.compute_forces(time, false);
            return None;
        }
        Some(RowForces {
            shares,
            renew: self.due_wind_renewal(time),
        })
    }

    /// Total force on every particle (N) into `self.forces`: springs (if `with_springs`), gravity, air
    /// damping and wind at time `time`.
    pub(crate) fn compute_forces(&mut self, time: f64, with_springs: bool) {
        let wind_active = self.refresh_wind_shares(time);
        let parallel = self.parallel();
        let Simulation {
            positions,
            velocities,
            springs,
            family,
            spring_forces,
            triangle_forces,
            triangles,
            forces,
            masses,
            params,
            grid_triangulation,
            spring_incidence,
            triangle_incidence,
            ..
        } = self;
        let (positions, velocities) = (&positions[..], &velocities[..]);
        let gravity = params.gravity;
        let air_damping = params.air_damping;
        let body_force = |i: usize| masses[i] * (gravity - air_damping * velocities[i]);
        if let (true, false, Some(shape)) = (wind_active, with_springs, *grid_triangulation) {
            // The body force and the wind in one pass over the grid's rows, summed in the same order.
            let body = BodyForce {
                masses,
                velocities,
                gravity,
                air_damping,
            };
            add_grid_triangle_forces(shape, triangle_forces, forces, parallel, Some(&body));
            return;
        }
        if !parallel {
            // One thread: scatter-add in element order. Each particle receives its terms in the same
            // order as the parallel gather below (springs, then triangles, each ascending), so both
            // paths give identical bits; the scatter just skips the extra pass.
            for (i, f) in forces.iter_mut().enumerate() {
                *f = body_force(i);
            }
            if with_springs {
                for (spring, stored) in springs.iter().zip(spring_forces.iter_mut()) {
                    let f = spring_force_on_a(spring, family, positions, velocities);
                    *stored = f;
                    forces[spring.a as usize] += f;
                    forces[spring.b as usize] += -f;
                }
            }
            if wind_active {
                if let Some(shape) = *grid_triangulation {
                    add_grid_triangle_forces(shape, triangle_forces, forces, false, None);
                } else {
                    for (tri, &f) in triangles.iter().zip(triangle_forces.iter()) {
                        for &v in tri {
                            forces[v as usize] += f;
                        }
                    }
                }
            }
            return;
        }
        if with_springs {
            fill(spring_forces, parallel, |s| {
                spring_force_on_a(&springs[s], family, positions, velocities)
            });
        }
        let (spring_forces, triangle_forces) = (&spring_forces[..], &triangle_forces[..]);
        let gather_triangles = wind_active && grid_triangulation.is_none();
        fill(forces, parallel, |i| {
            let mut force = body_force(i);
            if with_springs {
                for &item in spring_incidence.of(i) {
                    let f = spring_forces[(item >> 1) as usize];
                    force += if item & 1 == 0 { f } else { -f };
                }
            }
            if gather_triangles {
                for &t in triangle_incidence.of(i) {
                    force += triangle_forces[t as usize];
                }
            }
            force
        });
        if let (true, Some(shape)) = (wind_active, *grid_triangulation) {
            add_grid_triangle_forces(shape, triangle_forces, forces, parallel, None);
        }
    }

    /// Checks the state after a step; `None` when it is sound.
    fn divergence(&self) -> Option<DivergenceReason> {
        let parallel = self.parallel();
        let limits = self.params.divergence;
        let bad_particle =
            |i: usize| particle_unsound(self.positions[i], self.velocities[i], limits.max_speed);
        let (positions, velocities) = (&self.positions[..], &self.velocities[..]);
        let particle = first_index_screened(
            positions.len(),
            parallel,
            |block| {
                any_unsound_particle(
                    &positions[block.clone()],
                    &velocities[block],
                    limits.max_speed,
                )
            },
            bad_particle,
        );
        if let Some(particle) = particle {
            let (x, v) = (self.positions[particle], self.velocities[particle]);
            return Some(if !x.is_finite() || !v.is_finite() {
                DivergenceReason::NonFinite { particle }
            } else {
                DivergenceReason::Speed {
                    particle,
                    speed: v.length(),
                    limit: limits.max_speed,
                }
            });
        }
        let strain = |s: usize| {
            let sp = &self.springs[s];
            self.positions[sp.a as usize].distance(self.positions[sp.b as usize]) / sp.rest_length
                - 1.0
        };
        let bad_spring = |s: usize| strain(s) > limits.max_strain;
        let springs = &self.springs[..];
        // A grid's springs are screened all at once through its strips, whose ends sit at consecutive
        // particles (the loop vectorises without gathers); only if that flags one are they searched.
        let grid_screen = self
            .grid_constraints
            .as_ref()
            .map(|grid| grid.any_near_strain(positions, limits.max_strain, parallel));
        let spring = match grid_screen {
            Some(false) => None,
            Some(true) => first_index_screened(springs.len(), parallel, |_| true, bad_spring),
            None => first_index_screened(
                springs.len(),
                parallel,
                |block| any_spring_near_strain(&springs[block], positions, limits.max_strain),
                bad_spring,
            ),
        };
        spring.map(|spring| DivergenceReason::Strain {
            spring,
            strain: strain(spring),
            limit: limits.max_strain,
        })
    }

    // ---- parameters ------------------------------------------------------------------------------

    /// The parameters in force (those given to [`Simulation::new`] or the latest [`Simulation::set_params`]).
    pub fn params(&self) -> &SimParams {
        &self.params
    }

    /// Replaces the parameters between steps. Positions and velocities carry over unchanged and the
    /// XPBD multipliers restart every step anyway, so changing a stiffness, the method or the wind
    /// mid-run does not jerk the cloth (tested).
    pub fn set_params(&mut self, params: SimParams) -> Result<(), ParamError> {
        params.validate()?;
        if params.wind != self.params.wind {
            self.wind = WindField::new(&params.wind)?;
        }
        self.family = family_coefficients(&params);
        self.params = params;
        self.cached_forces_valid = false;
        Ok(())
    }

    // ---- pins ------------------------------------------------------------------------------------

    /// Indices of the pinned particles.
    pub fn pinned(&self) -> &[u32] {
        &self.pinned_indices
    }

    /// Sets where pinned particle `particle` must be at the end of the next step; it moves there along a
    /// straight line during the step, dragging the cloth smoothly.
    pub fn set_pin_target(&mut self, particle: usize, target: DVec3) -> Result<(), ModelError> {
        let k = self
            .pinned_indices
            .binary_search(&(particle as u32))
            .map_err(|_| ModelError::PinOutOfRange {
                index: particle,
                particle_count: self.positions.len(),
            })?;
        if !target.is_finite() {
            return Err(ModelError::NonFinitePosition(particle));
        }
        self.pin_targets[k] = target;
        Ok(())
    }

    /// Moves every pinned particle to `transform` applied to its rest position by the end of the next
    /// step (an animated pole: a translation, a rotation about the pole, or both).
    pub fn move_pins(&mut self, transform: DAffine3) -> Result<(), ModelError> {
        if !transform.is_finite() {
            return Err(ModelError::NonFinitePinTransform);
        }
        for (k, &i) in self.pinned_indices.iter().enumerate() {
            self.pin_targets[k] = transform.transform_point3(self.rest_positions[i as usize]);
        }
        Ok(())
    }

    // ---- state -----------------------------------------------------------------------------------

    /// Positions, m.
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// Velocities, m/s.
    pub fn velocities(&self) -> &[DVec3] {
        &self.velocities
    }

    /// Replaces `out` with the positions in `f32`, for a renderer (reusing its allocation).
    pub fn write_positions_f32(&self, out: &mut Vec<Vec3>) {
        out.clear();
        out.extend(self.positions.iter().map(|p| p.as_vec3()));
    }

    /// Replaces positions and velocities (for tests, studies and restarts). Pinned particles keep their
    /// new positions as pin targets.
    pub fn set_state(
        &mut self,
        positions: &[DVec3],
        velocities: &[DVec3],
    ) -> Result<(), ModelError> {
        let particle_count = self.positions.len();
        check_length("positions", positions.len(), particle_count)?;
        check_length("velocities", velocities.len(), particle_count)?;
        if let Some(i) = positions
            .iter()
            .zip(velocities)
            .position(|(x, v)| !x.is_finite() || !v.is_finite())
        {
            return Err(ModelError::NonFinitePosition(i));
        }
        self.positions.copy_from_slice(positions);
        self.velocities.copy_from_slice(velocities);
        for (k, &i) in self.pinned_indices.iter().enumerate() {
            self.pin_targets[k] = positions[i as usize];
        }
        self.cached_forces_valid = false;
        Ok(())
    }

    /// Back to the rest state at time 0.
    pub fn reset(&mut self) {
        self.positions.copy_from_slice(&self.rest_positions);
        self.velocities.fill(DVec3::ZERO);
        for (k, &i) in self.pinned_indices.iter().enumerate() {
            self.pin_targets[k] = self.rest_positions[i as usize];
        }
        self.time = 0.0;
        self.step_count = 0;
        self.cached_forces_valid = false;
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken so far.
    pub fn step_count(&self) -> u64 {
        self.step_count
    }

    /// Number of particles in the cloth.
    pub fn particle_count(&self) -> usize {
        self.positions.len()
    }

    /// The model's rest positions (where [`reset`](Simulation::reset) puts the particles), m.
    pub fn rest_positions(&self) -> &[DVec3] {
        &self.rest_positions
    }

    /// Lumped particle masses, kg.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// The model's triangles, as particle indices (the wind acts on them; renderers draw them).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Springs, in the greedy colour order of the general constraint solver.
    pub fn springs(&self) -> &[Spring] {
        &self.springs
    }

    /// Number of batches of the position-based constraint solver: the grid's twelve strip batches on a
    /// grid cloth, the greedy colours otherwise.
    pub fn colour_count(&self) -> usize {
        match &self.grid_constraints {
            Some(grid) => grid.batches.len(),
            None => self.colours.len(),
        }
    }

    /// The grid's shape when the cloth was built by [`ClothModel::grid`](crate::ClothModel::grid).
    pub fn grid(&self) -> Option<GridShape> {
        self.grid
    }

    // ---- diagnostics -----------------------------------------------------------------------------

    /// Kinetic energy `Σ ½ m v²`, J.
    pub fn kinetic_energy(&self) -> f64 {
        sum(self.positions.len(), self.parallel(), |i| {
            0.5 * self.masses[i] * self.velocities[i].length_squared()
        })
    }

    /// Potential energy: gravity `−Σ m g·x` plus elastic `Σ ½ k (l − L)²` over the enabled springs, J.
    pub fn potential_energy(&self) -> f64 {
        let gravity = self.params.gravity;
        let parallel = self.parallel();
        let gravitational = sum(self.positions.len(), parallel, |i| {
            -self.masses[i] * gravity.dot(self.positions[i])
        });
        let elastic = sum(self.springs.len(), parallel, |s| {
            let sp = &self.springs[s];
            let stiffness = self.family[family_index(sp.kind)].0;
            let extension = self.positions[sp.a as usize].distance(self.positions[sp.b as usize])
                - sp.rest_length;
            0.5 * stiffness * extension * extension
        });
        gravitational + elastic
    }

    /// Kinetic plus potential energy, J.
    pub fn total_energy(&self) -> f64 {
        self.kinetic_energy() + self.potential_energy()
    }

    /// Total linear momentum `Σ m v`, kg·m/s.
    pub fn momentum(&self) -> DVec3 {
        let parallel = self.parallel();
        DVec3::new(
            sum(self.positions.len(), parallel, |i| {
                self.masses[i] * self.velocities[i].x
            }),
            sum(self.positions.len(), parallel, |i| {
                self.masses[i] * self.velocities[i].y
            }),
            sum(self.positions.len(), parallel, |i| {
                self.masses[i] * self.velocities[i].z
            }),
        )
    }

    /// Mean, 99th percentile and maximum of the strain `l/L − 1` over the springs of `kind` (all kinds
    /// when `None`). Allocates; meant for diagnostics and studies, not for every frame.
    pub fn strain_statistics(&self, kind: Option<SpringKind>) -> StrainStatistics {
        let mut strains: Vec<f64> = self
            .springs
            .iter()
            .filter(|sp| kind.is_none_or(|k| k == sp.kind))
            .map(|sp| {
                self.positions[sp.a as usize].distance(self.positions[sp.b as usize])
                    / sp.rest_length
                    - 1.0
            })
            .collect();
        if strains.is_empty() {
            return StrainStatistics::default();
        }
        strains.sort_by(f64::total_cmp);
        StrainStatistics {
            mean: strains.iter().sum::<f64>() / strains.len() as f64,
            p99: strains[(strains.len() * 99 / 100).min(strains.len() - 1)],
            max: strains[strains.len() - 1],
        }
    }

    /// Largest strain `l/L − 1` over the enabled springs of `kind` (all kinds when `None`).
    pub fn max_strain(&self, kind: Option<SpringKind>) -> f64 {
        self.springs
            .iter()
            .filter(|sp| kind.is_none_or(|k| k == sp.kind))
            .map(|sp| {
                self.positions[sp.a as usize].distance(self.positions[sp.b as usize])
                    / sp.rest_length
                    - 1.0
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

/// Hooke spring plus dashpot: force on end `a` of `spring`, N (the force on `b` is its negative).
#[inline]
pub(crate) fn spring_force_on_a(
    spring: &Spring,
    family: &[(f64, f64); 3],
    positions: &[DVec3],
    velocities: &[DVec3],
) -> DVec3 {
    let (stiffness, damping) = family[family_index(spring.kind)];
    if stiffness == 0.0 {
        return DVec3::ZERO;
    }
    let (a, b) = (spring.a as usize, spring.b as usize);
    let delta = positions[b] - positions[a];
    let length = delta.length();
    if length == 0.0 {
        // Coincident ends: the direction is undefined, so the spring exerts no force this instant.
        return DVec3::ZERO;
    }
    let direction = delta / length;
    let extension_rate = (velocities[b] - velocities[a]).dot(direction);
    (stiffness * (length - spring.rest_length) + damping * extension_rate) * direction
}

by_cpu! {
    /// Whether any particle of a block is unsound ([`particle_unsound`]), evaluated for every particle
    /// without stopping, so that the loop vectorises; the search for the first unsound particle then
    /// runs only in a block this flags.
    fn any_unsound_particle(positions: &[DVec3], velocities: &[DVec3], max_speed: f64) -> bool {
        let n = positions.len();
        let velocities = &velocities[..n];
        let mut any = false;
        for i in 0..n {
            any |= particle_unsound(positions[i], velocities[i], max_speed);
        }
        any
    }
}

/// Whether a particle at `x` (m) moving at `v` (m/s) is unsound: a non-finite position or velocity, or
/// a speed above `max_speed` (m/s). Without branches (`|`, not `||`), so that loops over it vectorise.
#[inline(always)]
fn particle_unsound(x: DVec3, v: DVec3, max_speed: f64) -> bool {
    let finite = |v: DVec3| v.x.is_finite() & v.y.is_finite() & v.z.is_finite();
    !finite(x) | !finite(v) | (v.length() > max_speed)
}

by_cpu! {
    /// Whether any spring of a block may be strained beyond `max_strain` ([`may_exceed_strain`]), so that
    /// the exact test (one square root and one division per spring) runs only in blocks this flags.
    fn any_spring_near_strain(springs: &[Spring], positions: &[DVec3], max_strain: f64) -> bool {
        let mut any = false;
        for spring in springs {
            let (a, b) = (positions[spring.a as usize], positions[spring.b as usize]);
            any |= may_exceed_strain(a, b, spring.rest_length, max_strain);
        }
        any
    }
}

/// Whether the spring from `a` to `b` (m) of rest length `rest` (m) may be strained beyond `max_strain`:
/// its squared length is not clearly below `((1 + max_strain) · rest)²`. Conservative: the divergence
/// check's strain, `|a − b| / rest − 1` in floating point, exceeds the limit only when the squared length
/// exceeds the square of the limit length to within a few ulps, far inside the margin of 10⁻⁹; a length
/// that is not finite is flagged too. No square root and no division, and no branch, so that loops over
/// it vectorise.
#[inline(always)]
pub(crate) fn may_exceed_strain(a: DVec3, b: DVec3, rest: f64, max_strain: f64) -> bool {
    const MARGIN: f64 = 1.0 - 1e-9;
    let limit = (1.0 + max_strain) * rest;
    let clearly_shorter = (a - b).length_squared() < limit * limit * MARGIN;
    !clearly_shorter
}

#[cfg(test)]
mod divergence_tests {
    use super::*;
    use crate::model::GridSpec;

    /// The divergence check as it was before the screens: the first unsound particle, else the first
    /// spring strained beyond the limit, each by a plain search.
    fn unscreened(sim: &Simulation) -> Option<DivergenceReason> {
        let limits = sim.params.divergence;
        let (x, v) = (&sim.positions, &sim.velocities);
        if let Some(particle) = (0..x.len())
            .find(|&i| !x[i].is_finite() || !v[i].is_finite() || v[i].length() > limits.max_speed)
        {
            return Some(if !x[particle].is_finite() || !v[particle].is_finite() {
                DivergenceReason::NonFinite { particle }
            } else {
                DivergenceReason::Speed {
                    particle,
                    speed: v[particle].length(),
                    limit: limits.max_speed,
                }
            });
        }
        let strain = |s: &Spring| x[s.a as usize].distance(x[s.b as usize]) / s.rest_length - 1.0;
        sim.springs
            .iter()
            .position(|s| strain(s) > limits.max_strain)
            .map(|spring| DivergenceReason::Strain {
                spring,
                strain: strain(&sim.springs[spring]),
                limit: limits.max_strain,
            })
    }

    /// The screens never miss a spring strained beyond the limit: springs whose length lies within
    /// a few hundred ulps of the limit length, of rest lengths and limits over many magnitudes, in many
    /// directions. And they do flag nothing clearly below it.
    #[test]
    fn the_strain_screen_flags_every_spring_the_exact_strain_flags() {
        let mut flagged_exactly = 0;
        for rest in [1e-4, 0.0175, 0.35, 1.0, 37.0] {
            for max_strain in [1e-3, 0.5, 10.0, 1e3] {
                for direction in 0..12 {
                    let angle = 0.7 * direction as f64;
                    let unit = DVec3::new(angle.cos(), angle.sin() * 0.6, angle.sin() * 0.8);
                    let limit_length = (1.0 + max_strain) * rest;
                    let a = DVec3::new(0.3, -1.7, 0.9);
                    for k in -300i64..=300 {
                        let length = limit_length * (1.0 + k as f64 * f64::EPSILON);
                        let b = a + unit * length;
                        let exact = a.distance(b) / rest - 1.0 > max_strain;
                        flagged_exactly += exact as usize;
                        assert!(
                            !exact || may_exceed_strain(a, b, rest, max_strain),
                            "rest {rest}, max strain {max_strain}, {k} ulps"
                        );
                    }
                    let short = a + unit * (0.999 * limit_length);
                    assert!(!may_exceed_strain(a, short, rest, max_strain));
                }
            }
        }
        assert!(
            flagged_exactly > 10_000,
            "both sides of the limit are covered"
        );
        let a = DVec3::ZERO;
        for b in [DVec3::NAN, DVec3::INFINITY, DVec3::new(1e200, 0.0, 0.0)] {
            assert!(may_exceed_strain(a, b, 0.0175, 10.0), "{b}");
        }
    }

    /// The screened check reports what the plain search reports — which particle or spring, and why —
    /// on a grid (screened through its strips) and on a general mesh (block by block), for states with
    /// particles too fast or not finite and springs strained just beyond and just within the limit, on
    /// one thread and on a team.
    #[test]
    fn the_screened_check_reports_what_the_plain_search_reports() {
        let grid = ClothModel::grid(&GridSpec {
            columns: 37,
            rows: 23,
            ..GridSpec::default()
        })
        .unwrap();
        let mut mesh = grid.clone();
        mesh.grid = None; // the same springs, through the general path
        for model in [grid, mesh] {
            for parallel in [false, true] {
                let params = SimParams {
                    parallel_min_particles: if parallel { 0 } else { usize::MAX },
                    ..SimParams::default()
                };
                let mut sim = Simulation::new(model.clone(), params).unwrap();
                assert_eq!(sim.grid_constraints.is_some(), model.grid.is_some());
                let rest = sim.positions.clone();
                let n = rest.len();
                let limits = sim.params.divergence;
                let mut kinds = std::collections::BTreeSet::new();
                for case in 0..60usize {
                    let (mut x, mut v) = (rest.clone(), vec![DVec3::ZERO; n]);
                    // A particle pulled away from its neighbours, so that its springs end near the
                    // strain limit: beyond it for some cases, within for others.
                    let i = (case * 97) % n;
                    let spacing = rest[1].x - rest[0].x;
                    let stretched = ((1.0 + limits.max_strain).powi(2) - 1.0).sqrt();
                    let reach = spacing * stretched * (1.0 + (case as f64 - 30.0) * 1e-6);
                    x[i] += DVec3::new(0.0, 0.0, reach);
                    match case % 6 {
                        0 => v[(case * 31) % n] = DVec3::new(0.0, limits.max_speed * 1.001, 0.0),
                        1 => v[(case * 31) % n] = DVec3::new(0.0, limits.max_speed * 0.999, 0.0),
                        _ => {}
                    }
                    sim.positions.copy_from_slice(&x);
                    sim.velocities.copy_from_slice(&v);
                    if case % 10 == 9 {
                        sim.positions[(case * 13) % n].y = f64::NAN;
                    }
                    let expected = unscreened(&sim);
                    kinds.insert(format!("{expected:?}").chars().take(9).collect::<String>());
                    let mut team = TeamSlot::default();
                    let got = if parallel {
                        team.lead(2, false, || sim.divergence())
                    } else {
                        sim.divergence()
                    };
                    assert_eq!(
                        format!("{got:?}"),
                        format!("{expected:?}"),
                        "case {case}, grid {}, parallel {parallel}",
                        model.grid.is_some()
                    );
                }
                // Every outcome is covered: none, a fast particle, a non-finite one, a strained spring.
                assert_eq!(kinds.len(), 4, "{kinds:?}");
            }
        }
    }
}
