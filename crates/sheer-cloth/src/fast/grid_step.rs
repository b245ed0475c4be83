//! A grid's position-based sub-step (PBD, XPBD, small-steps XPBD) through the fast paths: the plain
//! sub-step of [`crate::solver`] (forces, predict, project batch by batch, velocities), laid out for
//! the machine, with the same bits.
//!
//! The batches are the grid's row strips ([`GridConstraints`]). The batches along rows share a pass
//! over the rows with the forces and the prediction before them, or with the attachments and the
//! velocities after them; a large grid runs its whole sub-step (wind, prediction, every batch) in one
//! pass, as a wavefront down the rows ([`Wavefront`]), and a whole step's sub-steps several to a pass,
//! and on a team of two as two opposed parts ([`Wavefront::opposed_parts`]). In parallel the
//! passes go to the simulation's team of threads ([`parts`]); on a team that splits its passes in
//! equal parts (a cloth below 43 008 particles a thread), the whole sub-step, or whole step, is one
//! hand-off, each thread on its own rows ([`Pipeline`]). Which of these runs is decided in one
//! place, [`Simulation::plan_grid_schedule`].
//!
//! Throughout a grid's step the state is split by component (`Simulation::split_positions`, …;
//! `components.rs`): every loop here reads and writes x, y and z as three plain arrays.

use glam::DVec3;

use std::ops::Range;

use crate::fast::components::{DisjointXyz, Xyz, XyzMut, XyzRef};
use crate::fast::grid_constraints::{GridConstraints, Strip, project_strips};
use crate::fast::grid_wind::{
    cells_around, predict_row_with_forces, split_cell_run, split_grid_triangle_forces,
};
use crate::fast::parallel::{
    DisjointSlice, one_index_per_thread, parts, team_in_equal_parts, team_threads,
};
use crate::fast::pipeline::{Pipeline, Progress, Stage};
use crate::fast::vectorise::by_cpu;
use crate::fast::wavefront::Wavefront;
use crate::params::SimParams;
use crate::params::{Method, Wind};
use crate::sim::{RowForces, Simulation, family_index};
use crate::solver::FamilyConstants;
use crate::solver::tethered;

/// A grid's sweeps run as one wavefront a sub-step from this many particles: below it the cloth's data
/// largely stays in the last-level cache from pass to pass, and pass by pass measured as fast or faster.
const WAVEFRONT_MIN_PARTICLES: usize = 262_144;

/// A grid's whole step runs as wavefronts of several sub-steps a pass from this many particles: below it
/// pass by pass measured as fast on one thread and faster on two (200 × 200), or faster (181 × 181);
/// at 256 × 256 the passes of several sub-steps took 0.90× as long on one thread (median), at 362 × 362
/// 0.61–0.83×: a row then comes from memory once for several sub-steps.
const WHOLE_STEP_WAVEFRONT_MIN_PARTICLES: usize = 65_536;

/// With threads, the wavefront of one sub-step needs this many rows per thread per row of its depth:
/// the seams around the cuts between the threads' parts, twice the depth each, run on one thread each.
const WAVEFRONT_ROWS_PER_DEPTH: usize = 10;

/// As [`WAVEFRONT_ROWS_PER_DEPTH`], for a pass of several sub-steps: 6 lets 512 × 372 take two
/// sub-steps a pass on two threads, 0.79–0.84× as long as one (10 rows).
const WHOLE_STEP_WAVEFRONT_ROWS_PER_DEPTH: usize = 6;

/// A whole step's wavefront takes as many sub-steps a pass as keep each thread's rows in flight within
/// about this many bytes of the last-level cache (so `n` threads keep `n` times as much; measured on two
/// threads sharing 32 MiB): measured best at 2 sub-steps a pass on 1 024 columns and 4 on 512 (6.0 MB
/// each).
const WAVEFRONT_WINDOW_BYTES: usize = 7 << 20;

/// About what a particle of a grid takes in the arrays a sub-step reads: positions, start positions
/// and velocities (72 bytes), mass and inverse mass (16), the wind's shares of its two cells (48), six
/// constraints' rest lengths and inverted divisors (96), its attachment (12).
const SUBSTEP_BYTES_PER_PARTICLE: usize = 244;

/// How many of a step's `substeps` sub-steps one pass of the wavefront runs on a grid of `columns`
/// columns, when a sub-step keeps `substep_depth` rows in flight: as many as fit
/// [`WAVEFRONT_WINDOW_BYTES`], at least one. (With threads the seams bound it further.)
fn substeps_in_flight(columns: usize, substep_depth: usize, substeps: usize) -> usize {
    let substep_bytes = substep_depth * columns * SUBSTEP_BYTES_PER_PARTICLE;
    (WAVEFRONT_WINDOW_BYTES / substep_bytes.max(1)).clamp(1, substeps.max(1))
}

thread_local! {
    /// One row of a grid's forces (N), copied from the cloth's and used by the prediction of that row on
    /// this thread (when the rows do not sum their forces themselves).
    static ROW_FORCES: std::cell::RefCell<Xyz> = std::cell::RefCell::new(Xyz::default());
}

/// Particles per rayon task in the per-particle passes.
const PARTICLE_GRAIN: usize = 4096;

impl Simulation {
    /// One sub-step of length `h` at time `t` on a grid: [`crate::solver`]'s sub-step through the fast
    /// paths, in the schedule `sweep` asks for ([`GridSweep::Auto`] in production). `pbd_stiffness`
    /// selects PBD with that dimensionless stiffness; `None` selects XPBD with compliance `1/k` from
    /// the springs.
    pub(crate) fn position_based_substep(
        &mut self,
        h: f64,
        t: f64,
        iterations: u32,
        pbd_stiffness: Option<f64>,
        sweep: GridSweep,
    ) {
        // The rows sum their forces where they predict them (`project_grid_constraints`) when they can.
        let row_forces = self.prepare_row_forces(t);
        let family = self.solver_constants(h, iterations, pbd_stiffness);
        let is_pbd = pbd_stiffness.is_some();
        // With one iteration every multiplier is used once, right after being reset: it is always 0 when
        // read, so small-steps XPBD skips the multipliers altogether (same arithmetic, same bits).
        let multipliers = iterations > 1 && !is_pbd;
        match (is_pbd, multipliers) {
            (true, _) => {
                self.project_constraints::<true, false>(h, iterations, family, row_forces, sweep)
            }
            (false, true) => {
                self.project_constraints::<false, true>(h, iterations, family, row_forces, sweep)
            }
            (false, false) => {
                self.project_constraints::<false, false>(h, iterations, family, row_forces, sweep)
            }
        }
        self.cached_forces_valid = false;
    }
}

/// Symplectic Euler prediction over sub-step `h` (s): `v += h w f`, then `x += h v`, keeping the start
/// positions in `previous` (Macklin et al. 2016, Algorithm 1, lines 3–4).
fn predict_positions(
    h: f64,
    inverse_masses: &[f64],
    forces: XyzRef<'_>,
    positions: XyzMut<'_>,
    velocities: XyzMut<'_>,
    previous: XyzMut<'_>,
) {
    predict_components(
        h,
        inverse_masses,
        forces.x,
        forces.y,
        forces.z,
        positions.x,
        positions.y,
        positions.z,
        velocities.x,
        velocities.y,
        velocities.z,
        previous.x,
        previous.y,
        previous.z,
    );
}

by_cpu! {
    /// The loop of [`predict_positions`], the components as separate slices (which the compiler knows
    /// do not overlap). The start positions are kept in the same loop: as three `copy_from_slice`
    /// before it, a row's copies were 1.8 % of the default flag's frame (`memmove`, mostly its calls).
    fn predict_components(
        h: f64,
        inverse_masses: &[f64],
        f_x: &[f64],
        f_y: &[f64],
        f_z: &[f64],
        x_x: &mut [f64],
        x_y: &mut [f64],
        x_z: &mut [f64],
        v_x: &mut [f64],
        v_y: &mut [f64],
        v_z: &mut [f64],
        previous_x: &mut [f64],
        previous_y: &mut [f64],
        previous_z: &mut [f64],
    ) {
        let n = inverse_masses.len();
        let (f_x, f_y, f_z) = (&f_x[..n], &f_y[..n], &f_z[..n]);
        let (x_x, x_y, x_z) = (&mut x_x[..n], &mut x_y[..n], &mut x_z[..n]);
        let (v_x, v_y, v_z) = (&mut v_x[..n], &mut v_y[..n], &mut v_z[..n]);
        let (previous_x, previous_y, previous_z) =
            (&mut previous_x[..n], &mut previous_y[..n], &mut previous_z[..n]);
        for i in 0..n {
            let start = DVec3::new(x_x[i], x_y[i], x_z[i]);
            (previous_x[i], previous_y[i], previous_z[i]) = (start.x, start.y, start.z);
            let mut v = DVec3::new(v_x[i], v_y[i], v_z[i]);
            v += h * inverse_masses[i] * DVec3::new(f_x[i], f_y[i], f_z[i]);
            let x = start + h * v;
            (v_x[i], v_y[i], v_z[i]) = (v.x, v.y, v.z);
            (x_x[i], x_y[i], x_z[i]) = (x.x, x.y, x.z);
        }
    }
}

/// Velocities from the position change over the sub-step, `v = (x − x_previous)/h` (Macklin et al.
/// 2016, Algorithm 1, line 16), with `inverse_h = 1/h` in 1/s.
fn velocities_from_positions(
    inverse_h: f64,
    positions: XyzRef<'_>,
    previous: XyzRef<'_>,
    velocities: XyzMut<'_>,
) {
    velocity_components(
        inverse_h,
        positions.x,
        positions.y,
        positions.z,
        previous.x,
        previous.y,
        previous.z,
        velocities.x,
        velocities.y,
        velocities.z,
    );
}

by_cpu! {
    /// The loop of [`velocities_from_positions`], the components as separate slices.
    fn velocity_components(
        inverse_h: f64,
        x_x: &[f64],
        x_y: &[f64],
        x_z: &[f64],
        previous_x: &[f64],
        previous_y: &[f64],
        previous_z: &[f64],
        v_x: &mut [f64],
        v_y: &mut [f64],
        v_z: &mut [f64],
    ) {
        let n = v_x.len();
        let (x_x, x_y, x_z) = (&x_x[..n], &x_y[..n], &x_z[..n]);
        let (previous_x, previous_y, previous_z) = (&previous_x[..n], &previous_y[..n], &previous_z[..n]);
        let (v_y, v_z) = (&mut v_y[..n], &mut v_z[..n]);
        for i in 0..n {
            let x = DVec3::new(x_x[i], x_y[i], x_z[i]);
            let start = DVec3::new(previous_x[i], previous_y[i], previous_z[i]);
            let v = (x - start) * inverse_h;
            (v_x[i], v_y[i], v_z[i]) = (v.x, v.y, v.z);
        }
    }
}

/// The long-range attachments of a sweep: each particle's anchor (an index into `pin_positions`) and
/// tether length (m), the pinned particles, and where they are.
struct Tethers<'a> {
    anchors: &'a [u32],
    lengths: &'a [f64],
    /// [`anchor_run_ends`] of `anchors`.
    run_ends: &'a [u32],
    pinned_indices: &'a [u32],
    pin_positions: DisjointSlice<'a, DVec3>,
}

/// The pins (indices into `pinned_indices`, which ascends) among the particles `particles`.
fn pins_among(pinned_indices: &[u32], particles: Range<usize>) -> Range<usize> {
    let at = |i: usize| pinned_indices.partition_point(|&k| (k as usize) < i);
    at(particles.start)..at(particles.end)
}

/// Per particle `i`, the index after the last of the particles `i, i + 1, …` anchored to the same pin
/// as `i`: the end of its run, computed once for [`Tethers::apply`].
pub(crate) fn anchor_run_ends(anchors: &[u32]) -> Vec<u32> {
    let mut ends = vec![anchors.len() as u32; anchors.len()];
    for i in (0..anchors.len().saturating_sub(1)).rev() {
        ends[i] = if anchors[i] == anchors[i + 1] {
            ends[i + 1]
        } else {
            i as u32 + 1
        };
    }
    ends
}

/// Particles per chunk of [`Tethers::apply_by_copies`]: a grid row of up to 1024 columns in one.
const ANCHOR_CHUNK: usize = 1024;

/// [`Tethers::apply`] takes the particles run by run when their runs of one anchor are this long on
/// average: copying each particle's anchor next to it (scalar, 15 instructions a particle) had been
/// 3.4 % of the default flag's frame, whose rows are each one run (`perf record -e cpu-clock` of
/// `fingerprint time 64x46 1 3000`).
const ANCHOR_RUN: usize = 16;

thread_local! {
    /// The anchors' positions (m) of the particles [`Tethers::apply`] is pulling on this thread.
    static ANCHOR_POSITIONS: std::cell::RefCell<Xyz> = std::cell::RefCell::new(Xyz::default());
}

impl<'a> Tethers<'a> {
    /// The attachments of a sub-step, if it has any. The pinned particles' positions are to be gathered
    /// ([`gather`](Tethers::gather)) after the prediction: they have inverse mass 0, so no projection
    /// moves them, and gathered once they stay right for the sub-step while no pass reads a position
    /// that another part writes.
    fn of_substep(
        simulation_params: &SimParams,
        pinned_indices: &'a [u32],
        anchors: &'a [u32],
        lengths: &'a [f64],
        run_ends: &'a [u32],
        pin_positions: &'a mut [DVec3],
    ) -> Option<Tethers<'a>> {
        if !simulation_params.long_range_attachments || pinned_indices.is_empty() {
            return None;
        }
        Some(Tethers {
            anchors,
            lengths,
            run_ends,
            pinned_indices,
            pin_positions: DisjointSlice::new(pin_positions),
        })
    }

    /// The pins (indices into `pinned_indices`) among the particles `particles`.
    fn pins_among(&self, particles: Range<usize>) -> Range<usize> {
        pins_among(self.pinned_indices, particles)
    }

    /// Gathers where the pinned particles among `particles` are now.
    ///
    /// # Safety
    /// No other thread may write those particles of `positions`, or read or write those pins' gathered
    /// positions, while this runs.
    unsafe fn gather(&self, particles: Range<usize>, positions: &DisjointXyz<'_>) {
        for k in self.pins_among(particles) {
            // SAFETY: by the caller's contract.
            unsafe {
                self.pin_positions
                    .set(k, positions.get(self.pinned_indices[k] as usize))
            };
        }
    }

    /// Pulls the particles in `range` back within their tethers.
    ///
    /// # Safety
    /// No other thread may touch `range` of `positions`, or write the gathered positions of the pins
    /// that `range`'s particles are anchored to, while this runs.
    unsafe fn apply(&self, range: Range<usize>, positions: &DisjointXyz<'_>) {
        // The runs in `range`, counted up to one more than go by runs.
        let most = range.len() / ANCHOR_RUN;
        let (mut runs, mut i) = (0, range.start);
        while i < range.end && runs <= most {
            i = self.run_ends[i] as usize;
            runs += 1;
        }
        if runs <= most {
            // SAFETY: by the caller's contract, which is `apply_by_runs`'s.
            unsafe { self.apply_by_runs(range, positions) }
        } else {
            // SAFETY: by the caller's contract, which is `apply_by_copies`'s.
            unsafe { self.apply_by_copies(range, positions) }
        }
    }

    /// [`apply`](Tethers::apply) for particles that come in runs anchored to one pin (a flag's hoist
    /// anchors each row to the row's pin): each run with its anchor's position broadcast.
    ///
    /// # Safety
    /// As [`apply`](Tethers::apply).
    unsafe fn apply_by_runs(&self, range: Range<usize>, positions: &DisjointXyz<'_>) {
        let mut start = range.start;
        while start < range.end {
            let pin = self.anchors[start];
            let run = start..(self.run_ends[start] as usize).min(range.end);
            // SAFETY: by the caller's contract, no one writes the pin's position now, and the run's
            // particles are this thread's.
            let (anchor, x) = unsafe {
                (
                    self.pin_positions.get(pin as usize),
                    positions.slice_mut(run.clone()),
                )
            };
            let lengths = &self.lengths[run.clone()];
            apply_tethers_to_anchor(x.x, x.y, x.z, anchor.x, anchor.y, anchor.z, lengths);
            start = run.end;
        }
    }

    /// [`apply`](Tethers::apply) for particles anchored to many different pins (a curtain's top edge
    /// anchors each column to its own pin).
    ///
    /// # Safety
    /// As [`apply`](Tethers::apply).
    unsafe fn apply_by_copies(&self, range: Range<usize>, positions: &DisjointXyz<'_>) {
        // Each particle's anchor is copied next to it first: the attachment loop then reads contiguous
        // memory and vectorises (a gather inside it kept the compiler from it). The copies go to this
        // thread's scratch, a chunk at a time so that it stays small and in the cache (a cloth-sized
        // array went to memory and back).
        ANCHOR_POSITIONS.with_borrow_mut(|anchors| {
            for start in range.clone().step_by(ANCHOR_CHUNK) {
                let chunk = start..range.end.min(start + ANCHOR_CHUNK);
                let count = chunk.len();
                if anchors.len() < count {
                    *anchors = Xyz::zeros(ANCHOR_CHUNK);
                }
                for (i, &k) in self.anchors[chunk.clone()].iter().enumerate() {
                    // SAFETY: by the caller's contract, no one writes these pins' positions now.
                    anchors.set(i, unsafe { self.pin_positions.get(k as usize) });
                }
                // SAFETY: exclusive by the caller's contract.
                let x = unsafe { positions.slice_mut(chunk.clone()) };
                apply_tethers(
                    x.x,
                    x.y,
                    x.z,
                    &anchors.x[..count],
                    &anchors.y[..count],
                    &anchors.z[..count],
                    &self.lengths[chunk],
                );
            }
        });
    }
}

/// The end of a sweep for the particles in `range`: the long-range attachments if any, then on the last
/// sweep the velocities from the position change over the sub-step (`inverse_h = 1/h`, 1/s).
///
/// # Safety
/// No other thread may touch `range` of `positions` or `velocities`, write it in `previous`, or write
/// the gathered positions of the pins its particles are anchored to, while this runs.
unsafe fn end_sweep(
    range: Range<usize>,
    tethers: Option<&Tethers<'_>>,
    velocities: Option<(&DisjointXyz<'_>, f64)>,
    positions: &DisjointXyz<'_>,
    previous: &DisjointXyz<'_>,
) {
    if let Some(tethers) = tethers {
        // SAFETY: by the caller's contract, which includes `Tethers::apply`'s.
        unsafe { tethers.apply(range.clone(), positions) };
    }
    if let Some((velocities, inverse_h)) = velocities {
        // SAFETY: by the caller's contract, `range` of all three buffers is this thread's alone.
        unsafe {
            velocities_from_positions(
                inverse_h,
                positions.slice(range.clone()),
                previous.slice(range.clone()),
                velocities.slice_mut(range),
            )
        }
    }
}

impl Simulation {
    /// Runs a whole step of `substeps` sub-steps of `h` (s) from time `time` (s) in passes over the
    /// rows, with the pins prescribed and placed row by row inside them, as `sweep` asks
    /// ([`GridSweep::Auto`] in production), and returns the schedule it ran
    /// ([`plan_grid_schedule`](Simulation::plan_grid_schedule)): on a team in equal parts (below
    /// `TEAM_CLAIMS_FROM_PARTICLES_PER_THREAD` a thread) as one pipelined pass of the team; else,
    /// from `WHOLE_STEP_WAVEFRONT_MIN_PARTICLES`, as wavefronts of several sub-steps a pass (on one
    /// thread, or on a team that claims its passes). When it did not (a method with multipliers, a
    /// mesh, a small grid without a team in equal parts, a cloth too short for its parts,
    /// attachments reaching too far for the prediction to join the wavefront, …) nothing has
    /// changed and the caller steps sub-step by sub-step.
    ///
    /// Sub-step by sub-step, each sub-step is one pass, ended by a barrier at which the leader waits for
    /// the helper, followed by the leader's serial work (the pins, the wind's renewal, the solver's
    /// set-up), during which the helper waits; on the default flag on two threads these took about
    /// 3 µs of each 50 µs sub-step. In one pass the sub-steps follow each other like the stages within
    /// one: a part waits for its neighbour only where their rows meet. Same bits as sub-step by
    /// sub-step (tested).
    ///
    /// A large grid's whole step goes as wavefronts instead ([`Wavefront`]), each pass running as many
    /// sub-steps one behind the other as keep the rows in flight within [`WAVEFRONT_WINDOW_BYTES`]:
    /// sub-step by sub-step, every sub-step streamed the whole cloth from memory once; with `k` sub-steps
    /// a pass, once every `k` (same bits, tested).
    pub(crate) fn whole_step(
        &mut self,
        h: f64,
        time: f64,
        substeps: u32,
        sweep: GridSweep,
    ) -> Option<Schedule> {
        let (iterations, pbd_stiffness) = match self.params.method {
            Method::Pbd {
                iterations,
                stiffness,
                ..
            } => (iterations, Some(stiffness)),
            Method::Xpbd { iterations, .. } => (iterations, None),
            Method::SmallStepsXpbd { .. } => (1, None),
            _ => return None,
        };
        let multipliers = iterations > 1 && pbd_stiffness.is_none();
        // Contacts are projected between sub-steps (`Simulation::project_contacts`).
        if multipliers
            || self.params.collisions.any()
            || self.grid_constraints.is_none()
            || (self.wind_acts() && self.grid_triangulation.is_none())
        {
            return None;
        }
        // The wind's renewals, sub-step by sub-step as `Simulation::step` and `prepare_row_forces` make
        // them; undone if the step cannot go whole.
        let stale = self.wind_stale;
        let wind = self.params.wind;
        let renewals: Vec<_> = (0..substeps)
            .map(|s| {
                if wind.renewal_due(s, h) {
                    self.wind_stale = true;
                }
                self.due_wind_renewal(time + s as f64 * h)
            })
            .collect();
        let renewed: Vec<bool> = renewals.iter().map(Option::is_some).collect();
        let schedule = self.plan_grid_schedule(sweep, iterations, &renewed, true);
        if !matches!(schedule, Schedule::Pipeline | Schedule::Wavefronts(_)) {
            self.wind_stale = stale;
            return None;
        }
        let step = WholeStep { renewals };
        let row_forces = RowForces {
            shares: self.wind_acts(),
            renew: None,
        };
        let family = self.solver_constants(h, iterations, pbd_stiffness);
        // The first sub-step's pins; the pass moves them on at the end of each sub-step.
        self.prescribe_pins(0, substeps, h, true);
        if pbd_stiffness.is_some() {
            self.project_grid_constraints::<true, false>(
                h,
                iterations,
                family,
                Some(row_forces),
                &schedule,
                Some(&step),
            );
        } else {
            self.project_grid_constraints::<false, false>(
                h,
                iterations,
                family,
                Some(row_forces),
                &schedule,
                Some(&step),
            );
        }
        self.cached_forces_valid = false;
        Some(schedule)
    }

    /// The constraint sweeps of a grid's sub-step of length `h` (s), with `row_forces`, in the schedule
    /// `sweep` asks for ([`project_grid_constraints`](Simulation::project_grid_constraints)).
    fn project_constraints<const PBD: bool, const MULTIPLIERS: bool>(
        &mut self,
        h: f64,
        iterations: u32,
        family: [FamilyConstants; 3],
        row_forces: Option<RowForces>,
        sweep: GridSweep,
    ) {
        let renewed = [row_forces.and_then(|r| r.renew).is_some()];
        let schedule = self.plan_grid_schedule(sweep, iterations, &renewed, false);
        self.project_grid_constraints::<PBD, MULTIPLIERS>(
            h, iterations, family, row_forces, &schedule, None,
        );
    }

    /// How a grid's sub-step (`whole_step` false, one entry in `renewed`), or a whole step of
    /// `renewed.len()` sub-steps, goes, each sub-step `iterations` sweeps and `renewed[s]` saying
    /// whether sub-step `s` renews the wind's shares. [`GridSweep::Auto`] decides by the cloth's size
    /// and the team of threads leading the step (each threshold's constant says what it was measured
    /// on):
    ///
    /// 1. Below `WAVEFRONT_MIN_PARTICLES` (a sub-step) or `WHOLE_STEP_WAVEFRONT_MIN_PARTICLES` (a whole
    ///    step) the cloth stays in the caches from pass to pass: no wavefronts.
    /// 2. On a team in equal parts (`TEAM_CLAIMS_FROM_PARTICLES_PER_THREAD`), the pipeline: one
    ///    hand-off, each thread on its own rows.
    /// 3. Else wavefronts, cut into one part per thread: as many sub-steps a pass as
    ///    `WAVEFRONT_WINDOW_BYTES` holds, or fewer, down to one, until every part has room for its
    ///    seams (`…_ROWS_PER_DEPTH` rows per row of depth). On a team of two whose attachments read
    ///    their own rows' pins, two opposed parts instead where those hold more sub-steps a pass than
    ///    parts would. A whole step goes in wavefronts only where the attachments let the prediction
    ///    into them (`WaveItem::of_substep`).
    /// 4. Else pass by pass ([`Schedule::Passes`]); a whole step then goes sub-step by sub-step.
    ///
    /// The other sweeps force a schedule, for the tests. A whole step that cannot go as forced goes
    /// sub-step by sub-step, except that opposed parts without a team of two, and a pipeline whose
    /// parts do not fit the rows, panic. A lone sub-step panics where forced wavefront parts do not
    /// fit or the pipeline has no team in equal parts (or its parts do not fit); opposed parts run
    /// it pass by pass. Only the pipeline's stages are kept, in `pipeline_plan`, built again when
    /// what they depend on changed.
    fn plan_grid_schedule(
        &mut self,
        sweep: GridSweep,
        iterations: u32,
        renewed: &[bool],
        whole_step: bool,
    ) -> Schedule {
        let parallel = self.parallel();
        let Simulation {
            params,
            inverse_masses,
            tether_row_reach,
            grid: Some(shape),
            grid_constraints: Some(grid),
            progress,
            pipeline_plan,
            ..
        } = self
        else {
            unreachable!("a grid schedule for a simulation without grid constraints");
        };
        let (columns, rows) = (shape.columns, shape.rows);
        let substep_count = renewed.len();
        // A whole step's passes and a lone sub-step's wavefront pay from different sizes, and need
        // different room for their seams.
        let (wavefront_min_particles, rows_per_depth) = if whole_step {
            (
                WHOLE_STEP_WAVEFRONT_MIN_PARTICLES,
                WHOLE_STEP_WAVEFRONT_ROWS_PER_DEPTH,
            )
        } else {
            (WAVEFRONT_MIN_PARTICLES, WAVEFRONT_ROWS_PER_DEPTH)
        };
        // The team's threads where one leads (it may hold fewer than rayon's pool:
        // `TEAM_ROWS_PER_THREAD`).
        let threads = if parallel {
            team_threads().unwrap_or_else(rayon::current_num_threads)
        } else {
            1
        };
        let equal_parts = if parallel {
            team_in_equal_parts()
        } else {
            None
        };
        // Opposed parts sweep a whole step on a team of exactly two threads.
        let team_of_two = whole_step && parallel && team_threads() == Some(2);
        let wavefronts = 'plan: {
            // Decided before the passes are built, so that a small cloth's sub-step builds none.
            let (parts, forced_per_pass) = match sweep {
                GridSweep::Passes | GridSweep::BatchByBatch | GridSweep::Pipeline => {
                    break 'plan None;
                }
                GridSweep::Wavefront {
                    substeps_per_pass: 0,
                    ..
                } if whole_step => break 'plan None,
                GridSweep::Wavefront {
                    parts,
                    substeps_per_pass,
                } => (parts, Some(substeps_per_pass)),
                GridSweep::Opposed { .. } if !whole_step => break 'plan None,
                GridSweep::Opposed { substeps_per_pass } => (2, Some(substeps_per_pass)),
                GridSweep::Auto
                    if inverse_masses.len() < wavefront_min_particles || equal_parts.is_some() =>
                {
                    break 'plan None;
                }
                GridSweep::Auto => (threads, None),
            };
            let reach = if params.long_range_attachments {
                *tether_row_reach
            } else {
                0
            };
            // The items of sub-steps `substeps`, one after another.
            let items_of = |substeps: Range<usize>| -> Vec<(WaveItem, usize)> {
                substeps
                    .flat_map(|s| {
                        WaveItem::of_substep(s, renewed[s], &grid.by_last_row, iterations, reach)
                    })
                    .collect()
            };
            let one = items_of(0..1);
            // A sub-step can follow another in the same pass only with its prediction among the items
            // (its attachments' pins near enough).
            if whole_step && !WaveItem::has_prediction(&one) {
                break 'plan None;
            }
            let most = match forced_per_pass {
                Some(per_pass) => per_pass.clamp(1, substep_count),
                None => substeps_in_flight(
                    columns,
                    WaveItem::wavefront(&one, rows).depth() + 1,
                    substep_count,
                ),
            };
            // Passes of `per_pass` sub-steps each, the last pass fewer.
            let passes_of = |per_pass: usize| -> Vec<(Wavefront, Vec<(WaveItem, usize)>)> {
                (0..substep_count)
                    .step_by(per_pass)
                    .map(|first| {
                        let items = items_of(first..(first + per_pass).min(substep_count));
                        (WaveItem::wavefront(&items, rows), items)
                    })
                    .collect()
            };
            // Two parts sweeping opposite ways: each part's strips need the other's only across the
            // cut, where the attachments would read the pins of rows across it too if they reached
            // beyond their own row.
            let opposed = |most: usize| WavefrontPlan {
                passes: passes_of(most),
                most_per_pass: most,
                way: PassesGo::Opposed,
            };
            if let GridSweep::Opposed { .. } = sweep {
                assert!(team_of_two, "opposed parts need a team of two threads");
                break 'plan (reach == 0).then(|| opposed(most));
            }
            // In parts: as many sub-steps a pass as fit the parts, at most `most`.
            let in_parts = (1..=most).rev().find_map(|per_pass| {
                let passes = passes_of(per_pass);
                let fit = passes.iter().all(|(plan, _)| {
                    plan.fits(parts)
                        && !(sweep == GridSweep::Auto
                            && threads > 1
                            && rows < rows_per_depth * threads * plan.depth())
                });
                fit.then_some(WavefrontPlan {
                    passes,
                    most_per_pass: per_pass,
                    way: PassesGo::InParts(parts),
                })
            });
            // On a team of two whose attachments read their own rows' pins, two parts sweeping
            // opposite ways where their passes hold more sub-steps than passes in parts would: each
            // thread keeps its own rows, as in parts, without seams to make room for.
            if let (GridSweep::Auto, true, 0) = (sweep, team_of_two, reach)
                && in_parts
                    .as_ref()
                    .is_some_and(|plan| most > plan.most_per_pass)
            {
                break 'plan Some(opposed(most));
            }
            // A test's fixed order: refusing it would let the test compare pass by pass with itself (a
            // whole step that does not fit goes sub-step by sub-step, and is checked there).
            if let (None, GridSweep::Wavefront { parts, .. }, false) =
                (&in_parts, sweep, whole_step)
            {
                panic!("{parts} parts do not fit {rows} rows");
            }
            in_parts
        };
        if let Some(plan) = wavefronts {
            return Schedule::Wavefronts(plan);
        }
        // The whole sub-step (or step) as one hand-off to a team whose threads each keep their own rows.
        let parts = match (sweep, equal_parts) {
            (GridSweep::BatchByBatch, _) => return Schedule::BatchByBatch,
            (GridSweep::Pipeline | GridSweep::Auto, Some(parts)) => parts,
            // A whole step falls back to sub-steps, the first of which panics here.
            (GridSweep::Pipeline, None) if !whole_step => {
                panic!("the pipeline needs a team in equal parts")
            }
            _ => return Schedule::Passes,
        };
        // The stages of the sub-step before serve unless one of the things they depend on changed.
        let moves = progress.cuts_moved();
        let current = pipeline_plan.key.as_ref().is_some_and(|key| {
            key.0 == renewed && (key.1, key.2, key.3) == (iterations, parts, moves)
        });
        if !current {
            pipeline_plan.plan = PipelineStages::new(
                renewed,
                &grid.strips,
                &grid.by_last_row,
                grid.middle_batches(),
                iterations,
                columns,
                parts,
                progress,
            );
            pipeline_plan.key = Some((renewed.to_vec(), iterations, parts, moves));
        }
        if sweep == GridSweep::Pipeline {
            assert!(
                pipeline_plan.plan.is_some(),
                "{parts} parts do not fit {rows} rows"
            );
        }
        if pipeline_plan.plan.is_some() {
            Schedule::Pipeline
        } else {
            Schedule::Passes
        }
    }

    /// A grid's sub-step after [`crate::solver`] (the plain code it must match bit for bit): strip by
    /// strip in its twelve batches ([`GridConstraints`]), the sub-step's wind shares (when due), forces
    /// and prediction over `h` (s) first, in `schedule`. The batches within rows that open and close a
    /// sweep (bending and stretch along rows) share a pass over the rows with the per-particle work
    /// next to them (the forces and the prediction; the attachments and the velocities): every row is
    /// independent there, so each part of the team keeps its rows from one to the next, and a sub-step
    /// takes eleven passes instead of sixteen, with the same arithmetic in the same order for every
    /// particle (tested). On a team in equal parts the whole sub-step is one hand-off instead, each
    /// thread on its own rows ([`Pipeline`]); a large grid runs the whole sub-step (the wind's shares,
    /// the forces and the prediction, then every batch) in one pass, as a wavefront down the rows
    /// ([`Wavefront`], [`WaveItem`]). Same bits either way, tested.
    ///
    /// `row_forces` ([`Simulation::prepare_row_forces`]): `Some` when the prediction of each row sums
    /// the row's forces itself, `None` when they are in `self.forces` already. `step`: a whole step's
    /// sub-steps instead of one ([`Simulation::whole_step`]), whose `schedule` is the pipeline or
    /// wavefronts.
    fn project_grid_constraints<const PBD: bool, const MULTIPLIERS: bool>(
        &mut self,
        h: f64,
        iterations: u32,
        family: [FamilyConstants; 3],
        row_forces: Option<RowForces>,
        schedule: &Schedule,
        step: Option<&WholeStep>,
    ) {
        let parallel = self.parallel();
        // A switched-off family (stiffness 0) has every inverse divisor 0, so its constraints move
        // nothing (`solver::project`); its batches are skipped rather than computed to no
        // effect, so that switching a part of the model off saves its cost (the plain code projects
        // them: same bits, tested in `solver.rs`).
        let active: [bool; 3] = std::array::from_fn(|f| self.family[f].0 != 0.0);
        let Simulation {
            split_positions: positions,
            split_velocities: velocities,
            previous_positions,
            forces,
            tether_anchors,
            tether_lengths,
            tether_run_ends,
            tether_pin_positions,
            pinned_indices,
            pin_starts,
            pin_targets,
            params,
            inverse_masses,
            masses,
            split_shares,
            grid: Some(shape),
            grid_constraints: Some(grid),
            progress,
            pipeline_plan,
            opposed_upward_first,
            ..
        } = self
        else {
            unreachable!("project_grid_constraints on a simulation without grid constraints");
        };
        let shape = *shape;
        let (columns, rows) = (shape.columns, shape.rows);
        let inverse_masses = &inverse_masses[..];
        let (gravity, air_damping) = (params.gravity, params.air_damping);
        // The batches within rows that open a sweep, those that close it, and the rest.
        let middle = if matches!(schedule, Schedule::BatchByBatch) {
            0..grid.batches.len()
        } else {
            grid.middle_batches()
        };
        let GridConstraints {
            springs: _,
            strips,
            batches,
            rest_lengths,
            inverse_denominators,
            lambdas,
            by_last_row,
        } = grid;
        if MULTIPLIERS {
            lambdas.fill(0.0);
        }
        let (opening, closing) = (middle.start, middle.end..batches.len());
        let renew = row_forces.and_then(|r| r.renew);
        // The wind's renewal in each sub-step: one sub-step's, or a whole step's in one pass.
        let this_substep = [renew];
        let renewals = step.map_or(&this_substep[..], |step| &step.renewals[..]);
        let substep_count = renewals.len();
        let (wavefront, pipeline) = match schedule {
            Schedule::Wavefronts(plan) => (Some(plan), None),
            Schedule::Pipeline => {
                let stages = pipeline_plan.plan.as_ref();
                (
                    None,
                    Some(stages.expect("planned with the pipeline's stages")),
                )
            }
            Schedule::Passes | Schedule::BatchByBatch => (None, None),
        };
        // Whether the wavefront does the wind and the prediction itself.
        let prediction_in_wavefront =
            wavefront.is_some_and(|plan| WaveItem::has_prediction(&plan.passes[0].1));
        if pipeline.is_none()
            && !prediction_in_wavefront
            && let Some((wind, air_velocity)) = renew
        {
            split_grid_triangle_forces(
                shape,
                &wind,
                air_velocity,
                positions.as_ref(),
                velocities.as_ref(),
                split_shares,
                parallel,
            );
        }
        let shares_on = row_forces.is_some_and(|r| r.shares);
        let row_forces_on = row_forces.is_some();
        let cells_per_row = columns - 1;
        let [first_cells, second_cells] = split_shares.each_mut().map(|s| s.disjoint());
        let forces = DisjointSlice::new(forces);
        let lambdas = DisjointSlice::new(lambdas);
        let positions = positions.disjoint();
        let previous = previous_positions.disjoint();
        let velocities = velocities.disjoint();
        // The pins' gathered positions, in two buffers: a whole step's sub-steps take turns, so that a
        // part gathering the next sub-step's pins cannot overwrite those a slower part's attachments
        // still read (in the pipeline it gathers the sub-step after next only once every part has
        // finished the next sub-step's prediction: `Stage::after_all`; in a wavefront of several
        // sub-steps the sub-step after next runs a whole sub-step's depth of rows, at least the
        // attachments' reach, behind: checked on the schedule,
        // `in_a_pass_of_several_sub_steps_each_pins_buffer_is_read_before_it_is_gathered_again`).
        let (first_buffer, second_buffer) = tether_pin_positions.split_at_mut(pinned_indices.len());
        let tethers = [first_buffer, second_buffer].map(|buffer| {
            Tethers::of_substep(
                params,
                pinned_indices,
                tether_anchors,
                tether_lengths,
                tether_run_ends,
                buffer,
            )
        });
        let tethers_of = |substep: usize| tethers[substep % 2].as_ref();
        let project_these = |strips: &[Strip]| {
            // A batch holds one family.
            if strips.iter().all(|s| !active[family_index(s.kind)]) {
                return;
            }
            // SAFETY: the strips of a batch touch disjoint particle ranges (checked by the
            // `grid_strips_*` tests); a pass over rows gives each row to one part, the pipeline's parts
            // touch no row at once that another part touches (`Pipeline`), the wavefront's concurrent
            // parts and seams touch disjoint rows (`Wavefront::fits`), and two opposed parts touch a
            // row at once only with units of the same item, which write nothing in common (a batch's
            // strips share no particle, as in a pass over them; two cell rows of the wind only read
            // the particle row between them) (`Wavefront::run_opposed_part`); each strip owns its
            // constraints' multipliers.
            unsafe {
                project_strips::<PBD, MULTIPLIERS>(
                    strips,
                    &positions,
                    &previous,
                    inverse_masses,
                    rest_lengths,
                    inverse_denominators,
                    &lambdas,
                    &family,
                )
            }
        };
        // The strips of batch `batch` whose last row is in `rows`: consecutive, as a batch's strips come
        // in ascending last rows (`last_rows_of_batch`).
        let strips_of_rows = |batch: usize, rows: Range<usize>| {
            let by_row = &by_last_row[batch].0[rows];
            let first = by_row.iter().find(|r| !r.is_empty());
            let last = by_row.iter().rfind(|r| !r.is_empty());
            match (first, last) {
                (Some(first), Some(last)) => &strips[first.start..last.end],
                _ => &strips[0..0],
            }
        };
        // The strips of batches `group` whose last row is in `rows`, batch by batch, each batch's in one
        // call.
        let project_rows = |group: Range<usize>, rows: Range<usize>| {
            for batch in group {
                project_these(strips_of_rows(batch, rows.clone()));
            }
        };
        let particles_of = |row: usize| row * columns..(row + 1) * columns;
        let row_grain = PARTICLE_GRAIN.div_ceil(columns);
        // The sub-step's forces (unless summed already) and prediction on row `row`, and the gather of
        // the row's pins' predicted positions for the attachments (no projection moves a pin: inverse
        // mass 0).
        let predict_row = |tethers: Option<&Tethers<'_>>, row: usize| {
            let range = particles_of(row);
            // SAFETY: each row goes to one part of a pass; the cells around it are written by the wind
            // before (a pass before, the pipeline's stage before on any part, or the wavefront's wind
            // item, a row ahead).
            unsafe {
                let predict = |forces: XyzRef<'_>| {
                    predict_positions(
                        h,
                        &inverse_masses[range.clone()],
                        forces,
                        positions.slice_mut(range.clone()),
                        velocities.slice_mut(range.clone()),
                        previous.slice_mut(range.clone()),
                    )
                };
                if row_forces_on {
                    // Summed on the way: not into `forces`, whose writes and reads went to memory on a
                    // large cloth, nor into a row of scratch read back by a second loop.
                    let cell_row = |r: usize| {
                        let cells = r * cells_per_row..(r + 1) * cells_per_row;
                        [first_cells.slice(cells.clone()), second_cells.slice(cells)]
                    };
                    let around = shares_on.then(|| cells_around(rows, row, cell_row));
                    predict_row_with_forces(
                        h,
                        around,
                        &masses[range.clone()],
                        &inverse_masses[range.clone()],
                        gravity,
                        air_damping,
                        positions.slice_mut(range.clone()),
                        velocities.slice_mut(range.clone()),
                        previous.slice_mut(range.clone()),
                    );
                } else {
                    // Copied into this thread's row of scratch, split by component.
                    ROW_FORCES.with_borrow_mut(|row_forces| {
                        if row_forces.len() != columns {
                            *row_forces = Xyz::zeros(columns);
                        }
                        row_forces.split_from(forces.slice(range.clone()));
                        predict(row_forces.as_ref());
                    });
                }
            };
            if let Some(tethers) = tethers {
                // SAFETY: no attachment reads the row's pins meanwhile, in this buffer: a pass runs
                // none, the pipeline's stage runs them only after every part has finished it
                // (`Stage::after_all`), and the wavefront keeps them behind this item by the tethers'
                // reach (`WaveItem::of_substep`) and, in a pass of several sub-steps, those of the
                // sub-step two before (the same buffer) ahead of it (see `tethers`
                // above).
                unsafe { tethers.gather(particles_of(row), &positions) };
            }
        };
        // The attachments and, on the last sweep, the velocities of row `row`.
        let end_row = |tethers: Option<&Tethers<'_>>, row: usize, last: bool| {
            // SAFETY: a pass, the pipeline's stage and the wavefront each give a row's end of a sweep
            // to one part or seam, after every strip that touches the row in that sweep, before any of
            // the next, after the pins its attachments read were gathered, and before they are gathered
            // again into the same buffer two sub-steps on (see `tethers` above).
            unsafe {
                end_sweep(
                    particles_of(row),
                    tethers,
                    last.then_some((&velocities, 1.0 / h)),
                    &positions,
                    &previous,
                )
            };
        };
        // The end of a sweep on `rows`: the closing batches, the attachments, on the last sweep the
        // velocities, else the next sweep's opening batches. Each touches a row alone (the attachments
        // read the pins' gathered positions besides), so batch by batch over the rows gives the bits
        // of row by row.
        let close_rows = |tethers: Option<&Tethers<'_>>, rows: Range<usize>, last: bool| {
            project_rows(closing.clone(), rows.clone());
            rows.clone().for_each(|row| end_row(tethers, row, last));
            if !last {
                project_rows(0..opening, rows);
            }
        };
        // The wind's shares of cell rows `rows`, from particle rows `rows.start..=rows.end`.
        let wind_cell_rows = |renewal: Option<(Wind, DVec3)>, rows: Range<usize>| {
            let (wind, air_velocity) = renewal.expect("a wind item renews the shares");
            let particle_rows = rows.start * columns..(rows.end + 1) * columns;
            // SAFETY: the pipeline and the wavefront run a cell row on one part, while no part writes
            // the particle rows it joins or reads the cell row.
            unsafe {
                let cells = rows.start * cells_per_row..rows.end * cells_per_row;
                split_cell_run(
                    columns,
                    rows.len(),
                    &wind,
                    air_velocity,
                    positions.slice(particle_rows.clone()),
                    velocities.slice(particle_rows),
                    first_cells.slice_mut(cells.clone()),
                    second_cells.slice_mut(cells),
                )
            };
        };
        // In a whole step's pass, the end of sub-step `substep` on row `row`: the row's pins put on their
        // paths and given the velocity that carries them along them over the next sub-step, as
        // `Simulation::place_pins` and `Simulation::prescribe_pins` do between sub-steps (the same
        // expressions: the same bits). No item of the sub-step runs on the row after this, and every item
        // of the next that reads the row runs after it.
        let move_pins_of_row = |substep: usize, row: usize| {
            let pin_position = |k: usize, s: usize| {
                pin_starts[k].lerp(pin_targets[k], s as f64 / substep_count as f64)
            };
            for k in pins_among(pinned_indices, particles_of(row)) {
                let i = pinned_indices[k] as usize;
                let from = pin_position(k, substep + 1);
                // SAFETY: the row is this part's while its end of the sub-step runs.
                unsafe {
                    positions.set(i, from);
                    if substep + 1 < substep_count {
                        let to = pin_position(k, substep + 2);
                        velocities.set(i, (to - from) / h);
                    }
                }
            }
        };
        if let Some(plan) = pipeline {
            progress.reset(plan.pipeline.parts());
            let shared_progress = &*progress;
            let run_items = |stage: usize, rows: Range<usize>| {
                let substep = plan.substeps[stage];
                match plan.kinds[stage] {
                    StageKind::Wind => wind_cell_rows(renewals[substep], rows),
                    StageKind::Open => {
                        rows.clone()
                            .for_each(|row| predict_row(tethers_of(substep), row));
                        project_rows(0..opening, rows);
                    }
                    StageKind::Batch(batch) => project_these(strips_of_rows(batch, rows)),
                    StageKind::Close { last } => {
                        close_rows(tethers_of(substep), rows.clone(), last);
                        if last && step.is_some() {
                            rows.for_each(|row| move_pins_of_row(substep, row));
                        }
                    }
                }
            };
            // One index per thread of the team (`team_in_equal_parts`), all at once.
            parts(plan.pipeline.parts(), parallel, 1, |part| {
                part.for_each(|p| plan.pipeline.run_part(p, shared_progress, run_items))
            });
            progress.rebalance(&plan.pipeline);
            return;
        }
        // First pass (unless the wavefront does it): the forces (unless summed already), the prediction
        // and the pins' gather of each part's rows, then, pass by pass, the opening batches over them.
        if !prediction_in_wavefront {
            parts(rows, parallel, row_grain, |rows| {
                rows.clone().for_each(|row| predict_row(tethers_of(0), row));
                if wavefront.is_none() {
                    project_rows(0..opening, rows);
                }
            });
        }
        if let Some(WavefrontPlan { passes, way, .. }) = wavefront {
            let run_item =
                |items: &[(WaveItem, usize)], item: usize, row: usize| match items[item].0 {
                    // Last row `row` of the cell row above it (none above the first row).
                    WaveItem::Wind { substep } => {
                        if row > 0 {
                            wind_cell_rows(renewals[substep], row - 1..row)
                        }
                    }
                    WaveItem::Predict { substep } => predict_row(tethers_of(substep), row),
                    WaveItem::Batch(batch) => project_these(strips_of_rows(batch, row..row + 1)),
                    WaveItem::End { substep, last } => {
                        end_row(tethers_of(substep), row, last);
                        if last && step.is_some() {
                            move_pins_of_row(substep, row);
                        }
                    }
                };
            let parts_count = match *way {
                PassesGo::InParts(parts) => parts,
                PassesGo::Opposed => {
                    for (plan, items) in passes {
                        let run_item = |item: usize, row: usize| run_item(items, item, row);
                        // Each pass starts on the rows the pass before ended on, also from step to
                        // step: the two parts reach the middle row at the end of one pass and leave
                        // it at the start of the next.
                        let halves = plan.opposed_parts(rows / 2, *opposed_upward_first);
                        *opposed_upward_first = !*opposed_upward_first;
                        progress.reset_counters(2);
                        let progress = &*progress;
                        // One part per thread of the team, the same thread for the same part from
                        // pass to pass, and both at once: they wait for each other.
                        one_index_per_thread(2, |part| {
                            plan.run_opposed_part(&halves, part, progress, run_item)
                        });
                    }
                    return;
                }
            };
            for (plan, items) in passes {
                let run_item = |item: usize, row: usize| run_item(items, item, row);
                // Each part's own strips need nothing across a cut, so the parts run at once; the seams
                // around the cuts need both neighbours' parts done, and touch disjoint rows of their
                // own. Both passes have one index per part, so that each thread of the team takes one
                // (seam `s` lies at the top of part `s`, and part 0 has none).
                parts(parts_count, parallel, 1, |part| {
                    part.for_each(|p| plan.run_part(p, parts_count, run_item))
                });
                parts(parts_count, parallel, 1, |seams| {
                    seams
                        .filter(|&s| s > 0)
                        .for_each(|s| plan.run_seam(s, parts_count, run_item))
                });
            }
            return;
        }
        for iteration in 0..iterations {
            for batch in middle.clone() {
                let strips = &strips[batches[batch].clone()];
                parts(strips.len(), parallel, 4, |range| {
                    project_these(&strips[range])
                });
            }
            let last = iteration + 1 == iterations;
            // Last pass of the sweep: the closing batches, the attachments and, on the last sweep, the
            // velocities, else the next sweep's opening batches, over each part's rows.
            parts(rows, parallel, row_grain, |rows| {
                close_rows(tethers_of(0), rows, last)
            });
        }
    }
}

/// Which schedule a grid's position-based sub-step, or whole step, runs
/// ([`Simulation::plan_grid_schedule`]). Every choice gives the same bits; production always asks for
/// `Auto`, and the tests force the others to compare them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) enum GridSweep {
    /// Chosen by the cloth's size and the team ([`Simulation::plan_grid_schedule`]).
    Auto,
    /// A pass over the cloth per batch (the batches along rows sharing theirs with the per-row work).
    Passes,
    /// A pass over the cloth per batch, the batches along rows too.
    BatchByBatch,
    /// The one-pass wavefront in this many parts ([`Wavefront`]), if they fit; a whole step's
    /// sub-steps up to `substeps_per_pass` a pass (fewer where they do not fit), or with 0 each
    /// sub-step on its own.
    Wavefront {
        parts: usize,
        substeps_per_pass: usize,
    },
    /// On a team in equal parts, the whole sub-step in one hand-off, each thread on its own rows
    /// ([`Pipeline`]); it must fit.
    Pipeline,
    /// On a team of two threads (it must have one), a whole step's passes of up to
    /// `substeps_per_pass` sub-steps each as two parts sweeping opposite ways
    /// ([`Wavefront::opposed_parts`]); sub-step by sub-step pass by pass where a whole step cannot go
    /// in wavefronts, or where the attachments read pins of other rows.
    Opposed { substeps_per_pass: usize },
}

/// How a grid's sub-step, or a whole step, goes ([`Simulation::plan_grid_schedule`]).
pub(crate) enum Schedule {
    /// A pass over the cloth per batch, the batches along rows sharing theirs with the per-row work.
    Passes,
    /// A pass over the cloth per batch, the batches along rows too (the tests' reference for `Passes`).
    BatchByBatch,
    /// One hand-off to a team in equal parts, each thread on its own rows ([`Pipeline`]), in the stages
    /// kept in `Simulation::pipeline_plan`.
    Pipeline,
    /// Wavefronts down the rows.
    Wavefronts(WavefrontPlan),
}

/// How a grid's sub-step, or a whole step, goes as wavefronts
/// ([`Simulation::project_grid_constraints`]).
pub(crate) struct WavefrontPlan {
    /// Each pass and its items.
    passes: Vec<(Wavefront, Vec<(WaveItem, usize)>)>,
    /// The most sub-steps a pass holds.
    most_per_pass: usize,
    /// How the passes share out the rows among the threads.
    way: PassesGo,
}

/// How the passes of a [`WavefrontPlan`] share out the rows among the threads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum PassesGo {
    /// Each pass cut into this many parts, the seams around the cuts after them (`Wavefront::run_part`).
    InParts(usize),
    /// Each pass as two opposed parts on a team of two threads (`Wavefront::opposed_parts`).
    Opposed,
}

/// What an item of a grid sub-step's wavefront ([`Wavefront`]) does on its last row.
#[derive(Clone, Copy, Debug, PartialEq)]
enum WaveItem {
    /// The wind's shares of the cell row above the row (span 1: the cell row joins two particle rows).
    Wind { substep: usize },
    /// The forces and the prediction of the row; the row's pins gathered for the attachments.
    Predict { substep: usize },
    /// The strips of a batch that end on the row.
    Batch(usize),
    /// The end of a sweep on the row ([`end_sweep`]); `last`: the sub-step's last sweep (in a whole
    /// step's pass it also moves the row's pins on to the next sub-step).
    End { substep: usize, last: bool },
}

impl WaveItem {
    /// The items of a sub-step of `sweeps` sweeps over the batches `by_last_row`, with their row spans:
    /// the wind's shares when `renew`, the prediction, then each sweep's batches and its end.
    ///
    /// The wind and the prediction join the wavefront only when the attachments allow it: a row's end
    /// reads the gathered positions of pins up to `tether_row_reach` rows away, so their prediction must
    /// run at least that many rows ahead of the first sweep's end, which runs as many rows behind it as
    /// the batches' spans add up to (`wavefront.rs`: item `i` runs `lagᵢ` rows behind the first). If they
    /// do not, the prediction is a pass of its own before the wavefront (and the pins gathered after it).
    ///
    /// `substep` numbers the sub-step within its step, for a whole step in passes (0 for a lone
    /// sub-step).
    fn of_substep(
        substep: usize,
        renew: bool,
        by_last_row: &[(Vec<Range<usize>>, usize)],
        sweeps: u32,
        tether_row_reach: usize,
    ) -> Vec<(WaveItem, usize)> {
        let lag_of_first_end: usize = by_last_row.iter().map(|(_, span)| span).sum();
        let mut items = Vec::new();
        if tether_row_reach <= lag_of_first_end {
            if renew {
                items.push((WaveItem::Wind { substep }, 1));
            }
            items.push((WaveItem::Predict { substep }, 0));
        }
        for sweep in 0..sweeps {
            let batches = by_last_row.iter().enumerate();
            items.extend(batches.map(|(batch, (_, span))| (WaveItem::Batch(batch), *span)));
            let last = sweep + 1 == sweeps;
            items.push((WaveItem::End { substep, last }, 0));
        }
        items
    }

    /// The wavefront of `items` over `rows` rows: their row spans, in order.
    fn wavefront(items: &[(WaveItem, usize)], rows: usize) -> Wavefront {
        Wavefront::new(items.iter().map(|(_, span)| *span).collect(), rows)
    }

    /// Whether the items run the sub-step's prediction (and the wind's shares) themselves.
    fn has_prediction(items: &[(WaveItem, usize)]) -> bool {
        items
            .iter()
            .any(|(item, _)| matches!(item, WaveItem::Predict { .. }))
    }
}

/// What a stage of the pipelined sub-step does on its rows.
#[derive(Clone, Copy, Debug)]
enum StageKind {
    /// The wind's shares of one cell row.
    Wind,
    /// The forces, the prediction and the opening batches of one particle row; the row's pins gathered.
    Open,
    /// A batch of strips, by their last row.
    Batch(usize),
    /// The end of a sweep on one row ([`end_sweep`] and the batches along rows around it).
    Close { last: bool },
}

/// A whole step's sub-steps, for one pipelined pass or for wavefronts of several sub-steps a pass
/// ([`Simulation::whole_step`]).
pub(crate) struct WholeStep {
    /// Per sub-step, the wind's parameters and air velocity where its shares are renewed.
    renewals: Vec<Option<(Wind, DVec3)>>,
}

/// The pipelined sub-step's plan, kept for the next sub-step: building it takes a pass over the rows'
/// strips and a few allocations, serial work that the team's other threads would wait for.
#[derive(Clone, Debug, Default)]
pub(crate) struct PlanCache {
    /// What the plan was made for: in which sub-steps the wind is renewed, the sweeps, the parts, and
    /// how often the cuts had moved ([`Progress::cuts_moved`]).
    key: Option<(Vec<bool>, u32, usize, u64)>,
    plan: Option<PipelineStages>,
}

/// A grid's sub-steps as [`Pipeline`] stages: what each does and in which sub-step, and the schedule.
#[derive(Clone, Debug)]
struct PipelineStages {
    kinds: Vec<StageKind>,
    substeps: Vec<usize>,
    pipeline: Pipeline,
}

/// The cost of one row's work in the pipeline, relative to projecting one constraint of an apart strip:
/// per constraint along a row, per cell of the wind, per particle (forces, prediction, attachments,
/// velocities). From `perf record -e cpu-clock` of `fingerprint time 64x46 1 1500` (AMD EPYC): apart
/// strips 30.8 % of the samples for 11 366 constraints, along strips 21.2 % for
/// 5 750, the wind's cells 18.2 % for 2 835, the per-particle loops 20.7 % for 2 944 particles.
const COST_ALONG: f64 = 1.37;
const COST_CELL: f64 = 2.4;
const COST_PARTICLE: f64 = 2.6;

impl PipelineStages {
    /// The stages of one sub-step per element of `renewed`, one after another, each of `iterations`
    /// sweeps (the wind first where it is `renewed`), over a grid of `columns` columns whose batches are
    /// `by_last_row` (the `middle` ones between the batches along rows), in `parts` parts of about equal
    /// work; `None` when the parts are too short ([`Pipeline::new`]).
    #[allow(clippy::too_many_arguments)]
    fn new(
        renewed: &[bool],
        strips: &[Strip],
        by_last_row: &[(Vec<Range<usize>>, usize)],
        middle: Range<usize>,
        iterations: u32,
        columns: usize,
        parts: usize,
        progress: &Progress,
    ) -> Option<PipelineStages> {
        let rows = by_last_row.first().map_or(0, |(by_row, _)| by_row.len());
        let stage = |items, above, below, after_all| Stage {
            items,
            above,
            below,
            after_all,
        };
        let (mut kinds, mut substeps, mut stages) = (Vec::new(), Vec::new(), Vec::new());
        for (substep, &renewed) in renewed.iter().enumerate() {
            let open = stages.len() + usize::from(renewed);
            let mut push = |kind, stage| {
                kinds.push(kind);
                substeps.push(substep);
                stages.push(stage);
            };
            if renewed {
                // Cell row r reads particle rows r and r + 1 and writes its cells (counted as row r's).
                push(StageKind::Wind, stage(rows - 1, 0, 1, None));
            }
            // Row r reads the cells of rows r − 1 and r.
            push(StageKind::Open, stage(rows, 1, 0, None));
            for sweep in 0..iterations {
                for batch in middle.clone() {
                    push(
                        StageKind::Batch(batch),
                        stage(rows, by_last_row[batch].1, 0, None),
                    );
                }
                let last = sweep + 1 == iterations;
                // The attachments read every pin's gathered position.
                push(
                    StageKind::Close { last },
                    stage(rows, 0, 0, (sweep == 0).then_some(open)),
                );
            }
        }
        let renewals = renewed.iter().filter(|&&r| r).count();
        let work: Vec<f64> = (0..rows)
            .map(|row| {
                let constraints: f64 = by_last_row
                    .iter()
                    .enumerate()
                    .map(|(batch, (by_row, _))| {
                        let count: usize =
                            strips[by_row[row].clone()].iter().map(|s| s.count).sum();
                        let cost = if middle.contains(&batch) {
                            1.0
                        } else {
                            COST_ALONG
                        };
                        cost * count as f64
                    })
                    .sum();
                let cells = if row + 1 < rows {
                    renewals * (columns - 1)
                } else {
                    0
                };
                renewed.len() as f64
                    * (iterations as f64 * constraints + COST_PARTICLE * columns as f64)
                    + COST_CELL * cells as f64
            })
            .collect();
        Some(PipelineStages {
            kinds,
            substeps,
            pipeline: Pipeline::new(stages, &work, parts, progress)?,
        })
    }
}

by_cpu! {
    /// Long-range attachments (Kim, Chentanez & Müller 2012, "Long Range Attachments"): particle `i`
    /// (`x_x[i]`, `x_y[i]`, `x_z[i]`) is pulled back onto the sphere of radius `lengths[i]` (m) around
    /// its anchor (`anchor_x[i]`, …) when it lies outside it, and left alone otherwise.
    fn apply_tethers(
        x_x: &mut [f64],
        x_y: &mut [f64],
        x_z: &mut [f64],
        anchor_x: &[f64],
        anchor_y: &[f64],
        anchor_z: &[f64],
        lengths: &[f64],
    ) {
        let n = lengths.len();
        let (x_x, x_y, x_z) = (&mut x_x[..n], &mut x_y[..n], &mut x_z[..n]);
        let (anchor_x, anchor_y, anchor_z) = (&anchor_x[..n], &anchor_y[..n], &anchor_z[..n]);
        for i in 0..n {
            let x = DVec3::new(x_x[i], x_y[i], x_z[i]);
            let anchor = DVec3::new(anchor_x[i], anchor_y[i], anchor_z[i]);
            let x = tethered(x, anchor, lengths[i]);
            (x_x[i], x_y[i], x_z[i]) = (x.x, x.y, x.z);
        }
    }
}

by_cpu! {
    /// [`apply_tethers`] for particles that share one anchor, (`anchor_x`, `anchor_y`, `anchor_z`) (m).
    fn apply_tethers_to_anchor(
        x_x: &mut [f64],
        x_y: &mut [f64],
        x_z: &mut [f64],
        anchor_x: f64,
        anchor_y: f64,
        anchor_z: f64,
        lengths: &[f64],
    ) {
        let n = lengths.len();
        let (x_x, x_y, x_z) = (&mut x_x[..n], &mut x_y[..n], &mut x_z[..n]);
        let anchor = DVec3::new(anchor_x, anchor_y, anchor_z);
        for i in 0..n {
            let x = tethered(DVec3::new(x_x[i], x_y[i], x_z[i]), anchor, lengths[i]);
            (x_x[i], x_y[i], x_z[i]) = (x.x, x.y, x.z);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{GridSweep, PassesGo, Schedule};
    use crate::model::{ClothModel, GridSpec};
    use crate::params::{Method, SimParams};
    use crate::sim::{Path, Simulation};
    use glam::DVec3;

    /// The wind's renewal interval (s) that holds its forces for `substeps` sub-steps of `method` in the
    /// 60 Hz steps of these tests (0, every evaluation, for 1).
    fn held_for(substeps: u32, method: Method) -> f64 {
        if substeps == 1 {
            0.0
        } else {
            f64::from(substeps) / 60.0 / f64::from(method.substeps())
        }
    }

    /// A grid of `columns` × `rows` particles and `height` m, hoist pinned, in a 6 m/s wind, stepped with
    /// `method`; the parallel code paths on with `parallel` (and off without).
    fn windy_flag(
        columns: usize,
        rows: usize,
        height: f64,
        method: Method,
        parallel: bool,
    ) -> Simulation {
        windy_grid(columns, rows, height, method, parallel, |model| {
            model.with_hoist_pinned().unwrap()
        })
    }

    /// As [`windy_flag`], with the grid pinned by `pin` instead of at the hoist.
    fn windy_grid(
        columns: usize,
        rows: usize,
        height: f64,
        method: Method,
        parallel: bool,
        pin: impl FnOnce(ClothModel) -> ClothModel,
    ) -> Simulation {
        let spec = GridSpec {
            columns,
            rows,
            height,
            ..GridSpec::default()
        };
        let model = pin(ClothModel::grid(&spec).unwrap());
        let mut params = SimParams {
            method,
            ..SimParams::default()
        };
        params.wind.velocity = DVec3::new(6.0, 0.0, 1.5);
        params.parallel_min_particles = if parallel { 0 } else { usize::MAX };
        Simulation::new(model, params).unwrap()
    }

    /// Small-steps XPBD, XPBD with several iterations and PBD with several: each way a grid's sub-step
    /// can sweep.
    const THREE_POSITION_BASED: [Method; 3] = [
        Method::SmallStepsXpbd { substeps: 20 },
        Method::Xpbd {
            substeps: 2,
            iterations: 5,
        },
        Method::Pbd {
            substeps: 2,
            iterations: 5,
            stiffness: 1.0,
        },
    ];

    /// The bits of the positions and the velocities.
    fn state_bits(sim: &Simulation) -> (Vec<[u64; 3]>, Vec<[u64; 3]>) {
        let bits = |v: &[DVec3]| -> Vec<[u64; 3]> {
            v.iter().map(|p| p.to_array().map(f64::to_bits)).collect()
        };
        (bits(sim.positions()), bits(sim.velocities()))
    }

    /// The bits of `sim` after `frames` frames on a pool of `threads` threads, its pole turning a little
    /// further and swaying every frame.
    fn turning_pole_bits(
        mut sim: Simulation,
        sweep: GridSweep,
        threads: usize,
        frames: usize,
    ) -> StateBits {
        turning_pole(&mut sim, sweep, threads, frames);
        state_bits(&sim)
    }

    /// How a step went.
    #[derive(Clone, Copy, Debug, PartialEq)]
    enum LastStep {
        /// Sub-step by sub-step.
        SubSteps,
        /// Whole, as one pass of the pipeline.
        Pipeline,
        /// Whole, as wavefronts of at most this many sub-steps a pass, shared out this way.
        Wavefronts(usize, PassesGo),
    }

    /// `frames` frames of `sim` in the schedule `sweep` asks for on a pool of `threads` threads, its
    /// pole turning a little further and swaying every frame. Returns how the last frame's step went.
    fn turning_pole(
        sim: &mut Simulation,
        sweep: GridSweep,
        threads: usize,
        frames: usize,
    ) -> LastStep {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut last = LastStep::SubSteps;
            for frame in 0..frames {
                sim.move_pins(crate::solver::hoist_sway_and_turn(frame))
                    .unwrap();
                let (_, whole) = sim.step_through(1.0 / 60.0, Path::Fast(sweep)).unwrap();
                last = match whole {
                    None => LastStep::SubSteps,
                    Some(Schedule::Pipeline) => LastStep::Pipeline,
                    Some(Schedule::Wavefronts(plan)) => {
                        LastStep::Wavefronts(plan.most_per_pass, plan.way)
                    }
                    Some(Schedule::Passes | Schedule::BatchByBatch) => {
                        unreachable!("a whole step goes as the pipeline or as wavefronts")
                    }
                };
            }
            last
        })
    }

    /// The most sub-steps a pass of a whole step in wavefronts ran (0: none ran).
    fn per_pass(how: LastStep) -> usize {
        match how {
            LastStep::Wavefronts(per_pass, _) => per_pass,
            LastStep::SubSteps | LastStep::Pipeline => 0,
        }
    }

    /// The grid solver's shared row passes (forces, prediction and the batches along rows in one pass;
    /// the batches along rows, the attachments and the velocities in another) give the bits of the same
    /// work done pass by pass: batch by batch, and the forces summed beforehand by the general path.
    #[test]
    fn the_row_passes_give_the_bits_of_batch_by_batch() {
        for method in THREE_POSITION_BASED {
            let run = |batch_by_batch: bool, forces_beforehand: bool| {
                let height = GridSpec::default().height;
                let mut sim = windy_flag(23, 13, height, method, false);
                let grid = sim.grid_constraints.as_ref().unwrap();
                assert!(grid.by_last_row.iter().any(|(_, span)| *span == 0));
                let sweep = if batch_by_batch {
                    GridSweep::BatchByBatch
                } else {
                    GridSweep::Auto
                };
                if forces_beforehand {
                    sim.grid_triangulation = None; // the general triangle path, summed into `forces`
                }
                for _ in 0..20 {
                    sim.step_through(1.0 / 60.0, Path::Fast(sweep)).unwrap();
                }
                state_bits(&sim)
            };
            let shared = run(false, false);
            assert_eq!(shared, run(true, false), "{method:?}: batch by batch");
            assert_eq!(shared, run(false, true), "{method:?}: forces beforehand");
            assert_eq!(shared, run(true, true), "{method:?}: both");
        }
    }

    /// The one-pass wavefront gives the bits of pass by pass, on one part and on as many as fit (each
    /// part's own strips, then the seams), for one sweep per sub-step and for several, with wind, the
    /// long-range attachments and a moving pole.
    #[test]
    fn the_wavefront_gives_the_bits_of_pass_by_pass() {
        // (method, sweeps per sub-step, part counts): a sweep's wavefront is 10 rows deep, with the wind
        // and the prediction 11, and each part needs twice the depth, so 133 rows take up to 6 parts of
        // one sweep and 3 of two (21 deep).
        let cases = [
            (
                Method::SmallStepsXpbd { substeps: 20 },
                1,
                vec![1, 2, 3, 4, 6],
            ),
            (
                Method::Xpbd {
                    substeps: 2,
                    iterations: 2,
                },
                2,
                vec![1, 2, 3],
            ),
            (
                Method::Pbd {
                    substeps: 2,
                    iterations: 2,
                    stiffness: 1.0,
                },
                2,
                vec![1, 3],
            ),
        ];
        let rows = 133;
        // The batches' row spans, as the schedule's own test takes them (`wavefront.rs`).
        let sim = windy_flag(9, rows, 3.0, Method::default(), false);
        let by_last_row = &sim.grid_constraints.as_ref().unwrap().by_last_row;
        let spans: Vec<usize> = by_last_row.iter().map(|(_, span)| *span).collect();
        assert_eq!(spans, [0, 0, 2, 2, 1, 1, 1, 1, 1, 1, 0, 0]);
        for (method, sweeps, part_counts) in cases {
            // `threads` > 1: on a pool of that many threads, the parallel code paths forced on.
            let run = |sweep: GridSweep, threads: usize| {
                let sim = windy_flag(9, rows, 3.0, method, threads > 1);
                turning_pole_bits(sim, sweep, threads, 12)
            };
            let passes = run(GridSweep::Passes, 1);
            for parts in part_counts {
                assert!(rows >= parts * 2 * (1 + 10 * sweeps), "{parts} parts fit");
                // The parts one after another on one thread, and on as many threads as parts (two
                // when one part: a team of two on one part and one seam-less pass).
                for threads in [1, parts.max(2)] {
                    assert_eq!(
                        passes,
                        run(
                            GridSweep::Wavefront {
                                parts,
                                substeps_per_pass: 0
                            },
                            threads
                        ),
                        "{method:?}: the wavefront in {parts} parts on {threads} threads"
                    );
                }
            }
        }
    }

    /// The attachments of a row read the pins' positions that the prediction of rows up to the reach away
    /// gathers: in the wavefront's schedule every such prediction runs surely before (earlier on the same
    /// part or seam, or on a part while the attachments run on a seam), for the solver's items with and
    /// without the wind, one sweep and two, every reach `WaveItem::of_substep` lets in and every number
    /// of parts that fits; and one row more of reach would break it, so its bound is the exact one.
    #[test]
    fn the_prediction_runs_before_every_attachment_that_reads_its_pins() {
        use super::WaveItem;
        use crate::fast::wavefront::tests::{before, schedule};
        let sim = windy_flag(9, 20, 3.0, Method::default(), false);
        let by_last_row = &sim.grid_constraints.as_ref().unwrap().by_last_row;
        // Whether every end of a sweep runs surely after the predictions within `reach` rows of it.
        let ordered = |items: &[(WaveItem, usize)], reach: usize, rows: usize, parts: usize| {
            let slots = schedule(&WaveItem::wavefront(items, rows), parts);
            let predict = items
                .iter()
                .position(|(item, _)| matches!(item, WaveItem::Predict { .. }));
            let predict = predict.expect("the prediction is in the wavefront");
            items
                .iter()
                .enumerate()
                .filter(|(_, (item, _))| matches!(item, WaveItem::End { .. }))
                .all(|(end, _)| {
                    (0..rows).all(|row| {
                        let pins = row.saturating_sub(reach)..(row + reach + 1).min(rows);
                        pins.clone()
                            .all(|pin_row| before(slots[&(predict, pin_row)], slots[&(end, row)]))
                    })
                })
        };
        let mut checked = 0;
        for sweeps in [1, 2] {
            for renew in [true, false] {
                for reach in 0..=12 {
                    let items = WaveItem::of_substep(0, renew, by_last_row, sweeps, reach);
                    let fused = WaveItem::has_prediction(&items);
                    assert_eq!(fused, reach <= 10, "reach {reach}");
                    if !fused {
                        continue;
                    }
                    for rows in [40, 61, 131, 240] {
                        let plan = WaveItem::wavefront(&items, rows);
                        for parts in (1..=6).filter(|&parts| plan.fits(parts)) {
                            assert!(
                                ordered(&items, reach, rows, parts),
                                "reach {reach}, {sweeps} sweeps, wind {renew}: {rows} rows, \
                                 {parts} parts"
                            );
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert!(checked > 100, "{checked} schedules checked");
        // The same items at a reach of 11: somewhere an end of a sweep would not follow a prediction it
        // reads.
        let items = WaveItem::of_substep(0, true, by_last_row, 1, 10);
        let broken = [40, 61, 131, 240].into_iter().any(|rows| {
            let plan = WaveItem::wavefront(&items, rows);
            (1..=6)
                .filter(|&parts| plan.fits(parts))
                .any(|parts| !ordered(&items, 11, rows, parts))
        });
        assert!(
            broken,
            "a reach of 11 would be safe too: the bound is not the exact one"
        );
    }

    /// The wavefront with the wind's shares and the prediction among its items gives the bits of pass by
    /// pass, and so does the wavefront that leaves them to a pass of their own: with the wind renewed
    /// every sub-step, held for three and off, and pins whose attachments reach 0, 1, 10, 11 and 66 rows
    /// (the last two too far for the prediction to run in the wavefront), on one part and three, on one
    /// thread and three; and with the forces summed beforehand by the general triangle path. Each sub-step
    /// on its own, and a whole step in passes of up to 1, 2, 3 and 20 sub-steps: with reaches of 1 and 10
    /// rows the attachments read pins gathered rows away, from one of two buffers that the prediction two
    /// sub-steps on gathers into again (one buffer for all sub-steps fails it).
    #[test]
    fn the_wavefront_with_the_prediction_gives_the_bits_of_pass_by_pass() {
        let (columns, rows) = (9, 133);
        let hoist = |every: usize| -> Vec<usize> {
            (0..rows).step_by(every).map(|r| r * columns).collect()
        };
        // (pinned particles, rows between a particle and its anchor at most, prediction in the
        // wavefront, forces summed beforehand by the general triangle path)
        let cases = [
            (hoist(1), 0, true, false),
            (hoist(1), 0, true, true),
            (hoist(3), 1, true, false),
            (hoist(21), 10, true, false),
            (hoist(22), 11, false, false),
            (vec![0, (rows - 1) * columns], 66, false, false),
        ];
        let winds = [(6.0, 1), (6.0, 3), (0.0, 1)];
        for (pins, reach, in_wavefront, general) in cases {
            for (speed, interval) in winds {
                let run = |sweep: GridSweep, threads: usize| {
                    let spec = GridSpec {
                        columns,
                        rows,
                        height: 3.0,
                        ..GridSpec::default()
                    };
                    let mut model = ClothModel::grid(&spec).unwrap();
                    model.pin(&pins).unwrap();
                    let mut params = SimParams {
                        method: Method::SmallStepsXpbd { substeps: 20 },
                        ..SimParams::default()
                    };
                    params.wind.velocity = DVec3::new(speed, 0.0, 0.25 * speed);
                    params.wind.renewal_interval = held_for(interval, params.method);
                    params.parallel_min_particles = if threads > 1 { 0 } else { usize::MAX };
                    let mut sim = Simulation::new(model, params).unwrap();
                    assert_eq!(sim.tether_row_reach, reach);
                    let by_last_row = &sim.grid_constraints.as_ref().unwrap().by_last_row;
                    let items = super::WaveItem::of_substep(0, true, by_last_row, 1, reach);
                    assert_eq!(
                        items[0].0 == super::WaveItem::Wind { substep: 0 },
                        in_wavefront
                    );
                    if general {
                        sim.grid_triangulation = None; // summed into `forces` by the general path
                    }
                    let how = turning_pole(&mut sim, sweep, threads, 8);
                    (state_bits(&sim), per_pass(how))
                };
                let (passes, _) = run(GridSweep::Passes, 1);
                // A whole step goes in passes only with the prediction in the wavefront and the wind's
                // shares on the grid's own rows.
                let whole_steps = in_wavefront && !(general && speed > 0.0);
                for (parts, threads) in [(1, 1), (3, 1), (3, 3)] {
                    // 0: sub-step by sub-step; else up to that many sub-steps a pass.
                    for substeps_per_pass in [0, 1, 2, 3, 20] {
                        let sweep = GridSweep::Wavefront {
                            parts,
                            substeps_per_pass,
                        };
                        let (bits, per_pass) = run(sweep, threads);
                        let what = format!(
                            "reach {reach}, wind {speed} m/s every {interval}, general path \
                             {general}: {parts} parts on {threads} threads, up to \
                             {substeps_per_pass} sub-steps a pass"
                        );
                        assert_eq!(passes, bits, "{what}");
                        if whole_steps && substeps_per_pass > 0 {
                            assert!((1..=substeps_per_pass).contains(&per_pass), "{what}");
                            // One part of 133 rows holds three sub-steps of at most 11 rows each.
                            if parts == 1 && substeps_per_pass <= 3 {
                                assert_eq!(per_pass, substeps_per_pass, "{what}");
                            }
                        } else {
                            assert_eq!(per_pass, 0, "{what}");
                        }
                    }
                }
            }
        }
    }

    /// Methods for the whole-step tests: two that go in whole steps (small-steps XPBD, PBD with two
    /// sweeps) and XPBD with multipliers, which goes sub-step by sub-step.
    const WHOLE_STEP_METHODS: [Method; 3] = [
        Method::SmallStepsXpbd { substeps: 20 },
        Method::Pbd {
            substeps: 3,
            iterations: 2,
            stiffness: 1.0,
        },
        Method::Xpbd {
            substeps: 2,
            iterations: 2,
        },
    ];

    /// Winds for the whole-step tests, (speed in m/s, sub-steps it is held for): renewed every sub-step,
    /// held for three, none.
    const WHOLE_STEP_WINDS: [(f64, u32); 3] = [(6.0, 1), (6.0, 3), (0.0, 1)];

    /// A whole step in wavefronts of several sub-steps a pass (the pins moved on and the wind renewed
    /// inside the pass) gives the bits of pass by pass: small-steps XPBD and PBD, with the wind renewed
    /// every sub-step, held for three and off, a turning and swaying pole, passes of 1, 2, 3 and up to
    /// all sub-steps, in 1–3 parts on one thread and on as many as parts. Where a pass of that many
    /// sub-steps does not fit the parts it takes fewer (checked to happen), and XPBD with multipliers
    /// steps sub-step by sub-step.
    #[test]
    fn a_whole_step_in_wavefronts_of_several_sub_steps_gives_the_bits_of_pass_by_pass() {
        let (methods, winds) = (WHOLE_STEP_METHODS, WHOLE_STEP_WINDS);
        let rows = 133;
        let mut fewer = 0;
        for method in methods {
            let whole_steps = !matches!(method, Method::Xpbd { .. });
            for (speed, interval) in winds {
                // The bits after eight frames, and the most sub-steps a pass of the last step ran.
                let run = |sweep: GridSweep, threads: usize| {
                    let mut sim = windy_flag(9, rows, 3.0, method, threads > 1);
                    sim.params.wind.velocity = DVec3::new(speed, 0.0, 0.25 * speed);
                    sim.params.wind.renewal_interval = held_for(interval, method);
                    let how = turning_pole(&mut sim, sweep, threads, 8);
                    (state_bits(&sim), per_pass(how))
                };
                let (passes, none) = run(GridSweep::Passes, 1);
                assert_eq!(none, 0, "pass by pass runs no wavefront");
                for (parts, threads) in [(1, 1), (2, 2), (3, 1), (3, 3)] {
                    for substeps_per_pass in [1, 2, 3, 20] {
                        let sweep = GridSweep::Wavefront {
                            parts,
                            substeps_per_pass,
                        };
                        let (bits, per_pass) = run(sweep, threads);
                        let what = format!(
                            "{method:?}, wind {speed} m/s every {interval}: {parts} parts on \
                             {threads} threads, up to {substeps_per_pass} sub-steps a pass"
                        );
                        assert_eq!(passes, bits, "{what}");
                        let most = substeps_per_pass.min(method.substeps() as usize);
                        if whole_steps {
                            assert!((1..=most).contains(&per_pass), "{what}: {per_pass}");
                            fewer += usize::from(per_pass < most);
                            // One part of 133 rows holds three sub-steps of at most 21 rows each
                            // (two sweeps of PBD).
                            if parts == 1 && substeps_per_pass <= 3 {
                                assert_eq!(per_pass, most, "{what}");
                            }
                        } else {
                            assert_eq!(per_pass, 0, "{what}: multipliers go sub-step by sub-step");
                        }
                    }
                }
            }
        }
        assert!(fewer > 0, "some pass was cut down to fit its parts");
    }

    /// The bits of a simulation's positions and velocities.
    type StateBits = (Vec<[u64; 3]>, Vec<[u64; 3]>);

    /// `sim` in a wind of `speed` m/s along x (a quarter of it along z) held for `interval` sub-steps,
    /// swept `sweep`, after `frames` frames of a turning and swaying pole on `threads` threads: its
    /// bits, and how its last whole step went (sub-steps a pass at most, whether as opposed parts).
    fn whole_step_run(
        mut sim: Simulation,
        speed: f64,
        interval: u32,
        sweep: GridSweep,
        threads: usize,
        frames: usize,
    ) -> (StateBits, (usize, bool)) {
        let method = sim.params.method;
        sim.params.wind.velocity = DVec3::new(speed, 0.0, 0.25 * speed);
        sim.params.wind.renewal_interval = held_for(interval, method);
        let how = turning_pole(&mut sim, sweep, threads, frames);
        let opposed = matches!(how, LastStep::Wavefronts(_, PassesGo::Opposed));
        (state_bits(&sim), (per_pass(how), opposed))
    }

    /// A whole step as two opposed parts on a team of two threads (passes of 1, 2, 3 and all
    /// sub-steps, so that the parts meet and leave the middle row by turns) gives the bits of pass by
    /// pass: small-steps XPBD and PBD, with the wind renewed every sub-step, held for three and off,
    /// a turning and swaying pole; XPBD with multipliers steps sub-step by sub-step, and so does a
    /// grid whose attachments read the pins of other rows (pinned every third row: a reach of one).
    #[test]
    fn a_whole_step_as_two_opposed_parts_gives_the_bits_of_pass_by_pass() {
        for method in WHOLE_STEP_METHODS {
            let whole_steps = !matches!(method, Method::Xpbd { .. });
            for (speed, interval) in WHOLE_STEP_WINDS {
                for every_third_row in [false, true] {
                    let run = |sweep: GridSweep, threads: usize| {
                        let sim = windy_grid(9, 61, 1.5, method, threads > 1, |mut model| {
                            if !every_third_row {
                                return model.with_hoist_pinned().unwrap();
                            }
                            let pins: Vec<usize> = (0..61).step_by(3).map(|row| row * 9).collect();
                            model.pin(&pins).unwrap();
                            model
                        });
                        assert_eq!(sim.tether_row_reach, usize::from(every_third_row));
                        whole_step_run(sim, speed, interval, sweep, threads, 6)
                    };
                    let (passes, _) = run(GridSweep::Passes, 1);
                    for substeps_per_pass in [1, 2, 3, 20] {
                        let sweep = GridSweep::Opposed { substeps_per_pass };
                        let (bits, (per_pass, opposed)) = run(sweep, 2);
                        let what = format!(
                            "{method:?}, wind {speed} m/s every {interval}, pinned every third row \
                             {every_third_row}: up to {substeps_per_pass} sub-steps a pass"
                        );
                        assert_eq!(passes, bits, "{what}");
                        if whole_steps && !every_third_row {
                            let most = substeps_per_pass.min(method.substeps() as usize);
                            assert_eq!((per_pass, opposed), (most, true), "{what}");
                        } else {
                            assert_eq!((per_pass, opposed), (0, false), "{what}");
                        }
                    }
                }
            }
        }
    }

    /// Left to choose, a grid above `WHOLE_STEP_WAVEFRONT_MIN_PARTICLES` takes several sub-steps a
    /// pass (as many as `WAVEFRONT_WINDOW_BYTES` holds) and gives the bits of pass by pass, with
    /// the wind held for two sub-steps. On one thread in one part. On a team (whose threads claim
    /// the passes index by index at these sizes, `TEAM_CLAIMS_FROM_PARTICLES_PER_THREAD`) where
    /// passes in parts would hold fewer: on two threads as two opposed parts, as many sub-steps a
    /// pass as on one (384 × 288, against at most two in parts); on three and four in parts, fewer
    /// sub-steps a pass (384 × 456, so that their threads claim). Else in parts: 1 400 columns on
    /// two threads (one sub-step a pass every way); and sub-step by sub-step where no pass fits the
    /// parts: 144 rows on three threads.
    #[test]
    fn left_to_choose_a_large_grid_takes_several_sub_steps_a_pass_with_the_same_bits() {
        let method = Method::SmallStepsXpbd { substeps: 20 };
        // (columns, rows, threads, whether a team runs fewer sub-steps a pass in parts than one
        // thread would: None where the step goes sub-step by sub-step).
        let cases = [
            (384, 288, [1, 2].as_slice(), Some(true)),
            (384, 456, [3, 4].as_slice(), Some(true)),
            (1400, 144, [1, 2].as_slice(), Some(false)),
            (1400, 144, [3].as_slice(), None),
        ];
        for (columns, rows, thread_counts, fewer_in_parts) in cases {
            assert!(columns * rows >= super::WHOLE_STEP_WAVEFRONT_MIN_PARTICLES);
            for &threads in thread_counts.iter().filter(|&&threads| threads > 1) {
                assert!(crate::sim::team_claims_its_passes(columns * rows, threads));
            }
            let run = |sweep: GridSweep, threads: usize| {
                let mut sim = windy_flag(columns, rows, 0.6, method, threads > 1);
                sim.params.wind.renewal_interval = held_for(2, method);
                let how = turning_pole(&mut sim, sweep, threads, 2);
                (state_bits(&sim), how)
            };
            let (passes, _) = run(GridSweep::Passes, 1);
            // A sub-step keeps 12 rows in flight: its depth, 11 (the wind's 1 and a sweep's 10), and
            // one.
            let most = super::substeps_in_flight(columns, 12, 20);
            for &threads in thread_counts {
                let what = format!("{columns} × {rows} on {threads} threads");
                let (bits, how) = run(GridSweep::Auto, threads);
                assert!(bits == passes, "{what}: not the bits of pass by pass");
                match (threads, fewer_in_parts) {
                    (1, _) => {
                        let expected = LastStep::Wavefronts(most, PassesGo::InParts(1));
                        assert_eq!(how, expected, "{what}");
                    }
                    (2, Some(true)) => {
                        let expected = LastStep::Wavefronts(most, PassesGo::Opposed);
                        assert_eq!(how, expected, "{what}");
                        assert!(most > 2, "{what}: {most} sub-steps a pass");
                    }
                    (_, Some(true)) => {
                        let LastStep::Wavefronts(per_pass, way) = how else {
                            panic!("{what}: {how:?}")
                        };
                        assert_eq!(way, PassesGo::InParts(threads), "{what}");
                        assert!((1..most).contains(&per_pass), "{what}: {per_pass}");
                    }
                    (_, Some(false)) => {
                        let expected = LastStep::Wavefronts(1, PassesGo::InParts(threads));
                        assert_eq!(how, expected, "{what}");
                    }
                    (_, None) => assert_eq!(how, LastStep::SubSteps, "{what}"),
                }
            }
        }
    }

    /// Left to choose, a grid from `WHOLE_STEP_WAVEFRONT_MIN_PARTICLES` on takes several sub-steps
    /// a pass on one thread; on a team whose threads have fewer than
    /// `TEAM_CLAIMS_FROM_PARTICLES_PER_THREAD` particles each, and so keep their own rows, it goes
    /// as one pass of the pipeline for the whole step (its plan holding all 20 sub-steps) instead
    /// of wavefronts; on a team with more, as wavefronts claimed chunk by chunk. 256 × 288 (73 728
    /// particles) runs the pipeline on two and three threads; 256 × 400 (102 400) wavefronts on two
    /// and the pipeline on three, the count being per thread. The bits are those of pass by pass
    /// every way.
    #[test]
    fn left_to_choose_a_team_in_equal_parts_runs_a_large_grid_as_the_pipeline() {
        use crate::sim::{TEAM_CLAIMS_FROM_PARTICLES_PER_THREAD, team_claims_its_passes};
        let method = Method::SmallStepsXpbd { substeps: 20 };
        for (columns, rows) in [(256, 288), (256, 400)] {
            let particles = columns * rows;
            assert!(
                (super::WHOLE_STEP_WAVEFRONT_MIN_PARTICLES
                    ..3 * TEAM_CLAIMS_FROM_PARTICLES_PER_THREAD)
                    .contains(&particles)
            );
            let run = |sweep: GridSweep, threads: usize| {
                let mut sim = windy_flag(columns, rows, 0.6, method, threads > 1);
                sim.params.wind.renewal_interval = held_for(2, method);
                let how = turning_pole(&mut sim, sweep, threads, 2);
                let run = (
                    how,
                    sim.pipeline_plan
                        .plan
                        .as_ref()
                        .map(|plan| plan.pipeline.parts()),
                    // The sub-steps the pipeline's plan was made for (its renewals, one a sub-step).
                    sim.pipeline_plan.key.as_ref().map(|key| key.0.len()),
                );
                (state_bits(&sim), run)
            };
            let (passes, _) = run(GridSweep::Passes, 1);
            let most = super::substeps_in_flight(columns, 12, 20);
            for threads in [1, 2, 3] {
                let (bits, how) = run(GridSweep::Auto, threads);
                let what = format!("{columns} × {rows} on {threads} threads");
                assert!(bits == passes, "{what}: not the bits of pass by pass");
                if threads == 1 {
                    let one_part = LastStep::Wavefronts(most, PassesGo::InParts(1));
                    assert_eq!(how, (one_part, None, None), "{what}");
                } else if team_claims_its_passes(particles, threads) {
                    assert!(per_pass(how.0) > 1 && how.1.is_none(), "{what}: {how:?}");
                } else {
                    let pipeline = (LastStep::Pipeline, Some(threads), Some(20));
                    assert_eq!(how, pipeline, "{what}");
                }
            }
            // Each grid's own case: 256 × 400 claims on two threads, 256 × 288 does not.
            assert_eq!(team_claims_its_passes(particles, 2), rows == 400);
            assert!(!team_claims_its_passes(particles, 3));
        }
    }

    /// A team takes no more threads than a fifth of the grid's rows (`TEAM_ROWS_PER_THREAD`), so
    /// that the pipeline fits: the default flag's 46 rows on a pool of 16 threads run as the
    /// pipeline in 9 parts, where a team of 16 would step sub-step by sub-step; on 8, in 8. The
    /// bits are those of one thread either way.
    #[test]
    fn a_team_takes_no_more_threads_than_the_rows_of_its_grid_allow() {
        use crate::sim::team_threads_for_rows;
        let method = Method::SmallStepsXpbd { substeps: 20 };
        let (columns, rows) = (64, 46);
        let run = |threads: usize| {
            let mut sim = windy_flag(columns, rows, 0.8, method, threads > 1);
            turning_pole(&mut sim, GridSweep::Auto, threads, 3);
            let parts = sim
                .pipeline_plan
                .plan
                .as_ref()
                .map(|plan| plan.pipeline.parts());
            (state_bits(&sim), parts)
        };
        let (serial, _) = run(1);
        for (threads, parts) in [(16, 9), (8, 8)] {
            assert_eq!(team_threads_for_rows(threads, rows), parts);
            let (bits, how) = run(threads);
            assert!(bits == serial, "{threads} threads: not the bits of one");
            assert_eq!(how, Some(parts), "{threads} threads");
        }
        // At least two, however few the rows; never more than the pool.
        assert_eq!(team_threads_for_rows(16, 7), 2);
        assert_eq!(team_threads_for_rows(3, 1000), 3);
    }

    /// The team that `team_threads_for_rows` allows a grid fits the pipeline, whatever the pool:
    /// every grid of 10–200 rows and 2, 5 and 64 columns, 1, 3, 10 and 20 sweeps, a whole step with
    /// the wind renewed in every sub-step, in none and in every other, and one sub-step with and
    /// without, on a pool of 1 024 threads. The cuts follow the rows' work, which is less in the
    /// first and last rows, so a part can get fewer rows than the mean: with four rows a thread, 5
    /// × 12 in three parts does not fit.
    #[test]
    fn the_team_the_rows_allow_fits_the_pipeline() {
        use super::PipelineStages;
        use crate::fast::pipeline::Progress;
        use crate::sim::team_threads_for_rows;
        for columns in [2, 5, 64] {
            for rows in 10..=200 {
                let sim = windy_flag(columns, rows, 1.0, Method::default(), false);
                let grid = sim.grid_constraints.as_ref().unwrap();
                let parts = team_threads_for_rows(1024, rows);
                for iterations in [1, 3, 10, 20] {
                    let every_other: Vec<bool> = (0..20).map(|s| s % 2 == 0).collect();
                    for renewed in [
                        vec![true; 20],
                        vec![false; 20],
                        every_other,
                        vec![true],
                        vec![false],
                    ] {
                        let stages = PipelineStages::new(
                            &renewed,
                            &grid.strips,
                            &grid.by_last_row,
                            grid.middle_batches(),
                            iterations,
                            columns,
                            parts,
                            &Progress::default(),
                        );
                        assert!(
                            stages.is_some(),
                            "{columns} × {rows}, {iterations} sweeps, {parts} parts"
                        );
                    }
                }
            }
        }
    }

    /// In a pass of several sub-steps the attachments of a sub-step (at the end of each of its sweeps)
    /// read the pins' positions its prediction gathered into one of two buffers, which the prediction two
    /// sub-steps later gathers into again: in the schedule every attachment runs surely after the
    /// predictions within the reach of its sub-step, and surely before those of the sub-step after next,
    /// for passes of two to four sub-steps of one sweep and of two, the wind renewed in every sub-step,
    /// in none and in every other, every reach that lets the prediction into the wavefront, and every
    /// number of parts that fits. The same check with one buffer (the next sub-step's prediction) fails.
    #[test]
    fn in_a_pass_of_several_sub_steps_each_pins_buffer_is_read_before_it_is_gathered_again() {
        use super::WaveItem;
        use crate::fast::wavefront::tests::{before, schedule};
        let sim = windy_flag(9, 20, 3.0, Method::default(), false);
        let by_last_row = &sim.grid_constraints.as_ref().unwrap().by_last_row;
        // Whether the schedule keeps every attachment after its sub-step's predictions within `reach`
        // and before those of the sub-step `reuse` on (the one that gathers into its buffer again).
        let ordered = |items: &[(WaveItem, usize)], reach, rows, parts, reuse| {
            let slots = schedule(&WaveItem::wavefront(items, rows), parts);
            let predict_of = |s| {
                items
                    .iter()
                    .position(|(item, _)| *item == WaveItem::Predict { substep: s })
            };
            items.iter().enumerate().all(|(end, (item, _))| {
                let WaveItem::End { substep, .. } = *item else {
                    return true;
                };
                let predict = predict_of(substep).expect("the prediction is in the wavefront");
                let again = predict_of(substep + reuse);
                (0..rows).all(|row| {
                    let read = slots[&(end, row)];
                    let pins = row.saturating_sub(reach)..(row + reach + 1).min(rows);
                    pins.clone().all(|pin_row| {
                        before(slots[&(predict, pin_row)], read)
                            && again.is_none_or(|again| before(read, slots[&(again, pin_row)]))
                    })
                })
            })
        };
        let (mut checked, mut on_parts, mut one_buffer_broken) = (0, 0, false);
        for substeps in 2..=4 {
            for sweeps in [1, 2] {
                for renewing in [|_| true, |_| false, |s: usize| s.is_multiple_of(2)] {
                    for reach in 0..=10 {
                        let items: Vec<(WaveItem, usize)> = (0..substeps)
                            .flat_map(|s| {
                                WaveItem::of_substep(s, renewing(s), by_last_row, sweeps, reach)
                            })
                            .collect();
                        for rows in [61, 131, 240] {
                            let plan = WaveItem::wavefront(&items, rows);
                            for parts in (1..=4).filter(|&parts| plan.fits(parts)) {
                                assert!(
                                    ordered(&items, reach, rows, parts, 2),
                                    "{substeps} sub-steps of {sweeps} sweeps, reach {reach}, \
                                     {rows} rows, {parts} parts"
                                );
                                one_buffer_broken |= !ordered(&items, reach, rows, parts, 1);
                                checked += 1;
                                on_parts += usize::from(parts > 1);
                            }
                        }
                    }
                }
            }
        }
        assert!(
            checked > 300 && on_parts > 100,
            "{checked} schedules checked, {on_parts} in parts"
        );
        assert!(
            one_buffer_broken,
            "one buffer would do: the check cannot fail"
        );
    }

    /// The pipelined sub-step (each thread of a team on its own rows, one hand-off per sub-step) gives
    /// the bits of pass by pass: for small-steps XPBD, XPBD with several sweeps and PBD; on teams of two
    /// to four threads; with the wind renewed every sub-step (its forces from the grid's rows and from
    /// the general triangle path), held for three, and without wind; with the long-range attachments and
    /// a turning pole. The cuts move between sub-steps as the parts' times differ, so the runs also cover
    /// several cuts.
    #[test]
    fn the_pipeline_gives_the_bits_of_pass_by_pass() {
        let methods = [
            Method::SmallStepsXpbd { substeps: 20 },
            Method::Xpbd {
                substeps: 2,
                iterations: 3,
            },
            Method::Pbd {
                substeps: 3,
                iterations: 2,
                stiffness: 1.0,
            },
        ];
        // (wind speed, sub-steps per renewal, the general triangle path): renewed every sub-step by rows
        // and by triangles, held, none.
        let winds = [
            (6.0, 1, false),
            (6.0, 1, true),
            (6.0, 3, false),
            (0.0, 1, false),
        ];
        for method in methods {
            for (speed, interval, general) in winds {
                // `threads` > 1: on a pool of that many threads, the parallel code paths forced on.
                let run = |sweep: GridSweep, threads: usize| {
                    let height = GridSpec::default().height;
                    let mut sim = windy_flag(21, 29, height, method, threads > 1);
                    sim.params.wind.velocity = DVec3::new(speed, 0.0, 0.25 * speed);
                    sim.params.wind.renewal_interval = held_for(interval, method);
                    if general {
                        sim.grid_triangulation = None; // summed into `forces` by the general path
                    }
                    turning_pole_bits(sim, sweep, threads, 15)
                };
                let passes = run(GridSweep::Passes, 1);
                for threads in [2, 3, 4] {
                    assert_eq!(
                        passes,
                        run(GridSweep::Pipeline, threads),
                        "{method:?}, wind {speed} m/s every {interval} (general {general}): the \
                         pipeline on {threads} threads"
                    );
                }
                // Left to choose, a team on this small grid takes the pipeline: the same bits.
                assert_eq!(passes, run(GridSweep::Auto, 2), "{method:?}: auto");
            }
        }
    }
}

#[cfg(test)]
mod tether_tests {
    use super::{ANCHOR_RUN, Tethers, anchor_run_ends};
    use crate::fast::components::Xyz;
    use crate::fast::parallel::DisjointSlice;
    use glam::DVec3;

    /// A deterministic pseudo-random number in [−0.5, 0.5).
    fn jitter(i: usize, k: u64) -> f64 {
        let mut z = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ k;
        z = (z ^ (z >> 31)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }

    /// The attachments run by runs of one anchor and by copied anchors give the same bits, whatever the
    /// runs' lengths (one particle to the whole range), for particles inside and outside their tethers; `apply` takes the runs exactly when they average `ANCHOR_RUN` or more.
    #[test]
    fn runs_of_one_anchor_give_the_bits_of_copied_anchors() {
        let n = 203;
        let mut pin_positions: Vec<DVec3> = (0..7)
            .map(|k| DVec3::new(jitter(k, 1), jitter(k, 2), jitter(k, 3)))
            .collect();
        for run in [1, 2, 7, 16, 17, 64, n] {
            let anchors: Vec<u32> = (0..n).map(|i| ((i / run) % 7) as u32).collect();
            let lengths: Vec<f64> = (0..n).map(|i| 0.7 + 0.5 * jitter(i, 4)).collect();
            let start: Vec<DVec3> = (0..n)
                .map(|i| DVec3::new(jitter(i, 5), jitter(i, 6), jitter(i, 7)) * 1.5)
                .collect();
            let run_ends = anchor_run_ends(&anchors);
            let tethers = Tethers {
                anchors: &anchors,
                lengths: &lengths,
                run_ends: &run_ends,
                pinned_indices: &[],
                pin_positions: DisjointSlice::new(&mut pin_positions),
            };
            let moved = |how: &dyn Fn(&Tethers<'_>, &mut Xyz)| {
                let mut x = Xyz::of(&start);
                how(&tethers, &mut x);
                x.to_vec3s()
            };
            // SAFETY: one thread, and nothing writes the pins' positions.
            let by_runs = moved(&|t, x| unsafe { t.apply_by_runs(3..n, &x.disjoint()) });
            // SAFETY: as above.
            let by_copies = moved(&|t, x| unsafe { t.apply_by_copies(3..n, &x.disjoint()) });
            // SAFETY: as above.
            let chosen = moved(&|t, x| unsafe { t.apply(3..n, &x.disjoint()) });
            let bits = |v: &[DVec3]| {
                v.iter()
                    .map(|p| p.to_array().map(f64::to_bits))
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&by_runs), bits(&by_copies), "runs of {run}");
            assert_eq!(bits(&chosen), bits(&by_copies), "runs of {run}");
            assert_eq!(bits(&by_runs[..3]), bits(&start[..3]), "outside the range");
            let pulled = (3..n).filter(|&i| by_runs[i] != start[i]).count();
            assert!(
                pulled > 20 && pulled < n - 20,
                "{pulled} particles pulled back"
            );
            let runs = 1 + anchors[3..].windows(2).filter(|p| p[0] != p[1]).count();
            assert_eq!(
                runs * ANCHOR_RUN <= n - 3,
                run >= 17,
                "runs of {run}: {runs} runs"
            );
        }
    }
}
