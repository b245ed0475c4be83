//! Position-based integrators: PBD (Müller, Heidelberger, Hennix & Ratcliff 2007), XPBD (Macklin,
//! Müller & Chentanez 2016) and small-steps XPBD (Macklin, Storey, Lu, Terdiman, Chentanez, Jeschke &
//! Müller 2019) — one loop, three settings.
//!
//! Per sub-step: external forces into velocities, predict positions, project the distance constraints
//! batch by batch (Gauss–Seidel across batches, independent within a batch, so a batch can run in
//! parallel with the same result), then velocities from the position change. The batches are a grid's
//! row strips ([`GridConstraints`]) or, for any other mesh, a greedy colouring. In parallel, a grid's
//! passes go to the simulation's team of threads ([`parts`]), a mesh's to rayon.

use glam::DVec3;
use rayon::prelude::*;

use crate::grid_constraints::{
    FamilyConstants, GridConstraints, Layout, Strip, project, project_along, project_apart,
};
use crate::model::Spring;
use crate::parallel::{DisjointSlice, fill, parts};
use crate::sim::{Simulation, family_index};
use crate::vectorise::by_cpu;

/// One distance constraint as the solver streams it, in colour order. 32 bytes: per-family constants
/// live in a 3-entry table and inverse masses in the particle array, so that the constraints of large
/// cloths take half the cache and memory bandwidth a 64-byte record did (the solver streams all of
/// them every sub-step). Rebuilt when the sub-step length or the parameters change.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PackedConstraint {
    a: u32,
    b: u32,
    rest_length: f64,
    /// PBD: k'/(w_a + w_b); XPBD: 1/((1 + γ)(w_a + w_b) + α̃); 0 when the constraint is inactive.
    inverse_denominator: f64,
    /// Index into the per-family (α̃, γ) table of the sub-step.
    family: u8,
}

/// Batches smaller than this run on one thread even in parallel mode: rayon's fork–join costs more.
const MIN_PARALLEL_BATCH: usize = 2048;

/// Particles per rayon task in the per-particle passes.
const PARTICLE_GRAIN: usize = 4096;

impl Simulation {
    /// One sub-step of length `h` at time `t`. `pbd_stiffness` selects PBD with that dimensionless
    /// stiffness; `None` selects XPBD with compliance `1/k` from the springs.
    pub(crate) fn position_based_substep(
        &mut self,
        h: f64,
        t: f64,
        iterations: u32,
        pbd_stiffness: Option<f64>,
    ) {
        self.compute_forces(t, false);
        let parallel = self.parallel();
        {
            let Simulation {
                positions,
                velocities,
                previous_positions,
                forces,
                inverse_masses,
                ..
            } = self;
            let (inverse_masses, forces) = (&inverse_masses[..], &forces[..]);
            let (positions, velocities, previous_positions) = (
                DisjointSlice::new(positions),
                DisjointSlice::new(velocities),
                DisjointSlice::new(previous_positions),
            );
            parts(inverse_masses.len(), parallel, PARTICLE_GRAIN, |range| {
                // SAFETY: the parts are disjoint.
                unsafe {
                    predict_positions(
                        h,
                        &inverse_masses[range.clone()],
                        &forces[range.clone()],
                        positions.slice_mut(range.clone()),
                        velocities.slice_mut(range.clone()),
                        previous_positions.slice_mut(range),
                    )
                }
            });
        }
        // PBD: Müller et al. 2007 §3.3 make the stiffness independent of the iteration count by
        // k' = 1 − (1 − k)^(1/n). Each family keeps its stiffness relative to stretch.
        let stretch_stiffness = self.family[0].0;
        let pbd_family: [f64; 3] = std::array::from_fn(|f| match pbd_stiffness {
            Some(k) if self.family[f].0 > 0.0 => {
                let relative = if stretch_stiffness > 0.0 {
                    (self.family[f].0 / stretch_stiffness).min(1.0)
                } else {
                    1.0
                };
                1.0 - (1.0 - k * relative).powf(1.0 / iterations as f64)
            }
            _ => 0.0,
        });
        // Per-family constants of this sub-step. XPBD, Macklin et al. 2016 eqs. (18) and (26):
        // α̃ = α/h², γ = α β / h with α = 1/k (m/N) and β = c (N·s/m). PBD: the correction is scaled by k'.
        let constants: [(f64, f64, f64); 3] = std::array::from_fn(|f| {
            let (stiffness, damping) = self.family[f];
            if stiffness == 0.0 {
                (0.0, 0.0, 0.0)
            } else if pbd_stiffness.is_some() {
                (pbd_family[f], 0.0, 0.0)
            } else {
                let compliance = 1.0 / stiffness;
                (1.0, compliance / (h * h), compliance * damping / h)
            }
        });
        let is_pbd = pbd_stiffness.is_some();
        // The divisor of each constraint's update depends only on h, the parameters and the masses, so
        // it is inverted once and reused until one of them changes: the inner loop then has a single
        // division and a single square root, which bound its throughput.
        let key = (h, constants, is_pbd);
        if self.denominator_key != Some(key) {
            let Simulation {
                springs,
                inverse_masses,
                packed,
                grid_constraints,
                ..
            } = self;
            let inverse_denominator = |spring: &Spring| {
                let (scale, scaled_compliance, gamma) = constants[family_index(spring.kind)];
                let w = inverse_masses[spring.a as usize] + inverse_masses[spring.b as usize];
                if scale == 0.0 || w == 0.0 {
                    0.0
                } else if is_pbd {
                    scale / w
                } else {
                    1.0 / ((1.0 + gamma) * w + scaled_compliance)
                }
            };
            if let Some(grid) = grid_constraints {
                let GridConstraints {
                    springs,
                    inverse_denominators,
                    ..
                } = grid;
                fill(inverse_denominators, parallel, |c| {
                    inverse_denominator(&springs[c])
                });
            } else {
                packed.resize(springs.len(), PackedConstraint::default());
                fill(packed, parallel, |c| {
                    let spring = &springs[c];
                    PackedConstraint {
                        a: spring.a,
                        b: spring.b,
                        rest_length: spring.rest_length,
                        inverse_denominator: inverse_denominator(spring),
                        family: family_index(spring.kind) as u8,
                    }
                });
            }
            self.denominator_key = Some(key);
        }
        let family_constants: [FamilyConstants; 3] = std::array::from_fn(|f| FamilyConstants {
            scaled_compliance: constants[f].1,
            gamma: constants[f].2,
        });
        // With one iteration every multiplier is used once, right after being reset: it is always 0 when
        // read, so small-steps XPBD skips the multipliers altogether (same arithmetic, same bits).
        let multipliers = iterations > 1 && !is_pbd;
        let inverse_h = 1.0 / h;
        match (is_pbd, multipliers) {
            (true, _) => {
                self.project_constraints::<true, false>(iterations, family_constants, inverse_h)
            }
            (false, true) => {
                self.project_constraints::<false, true>(iterations, family_constants, inverse_h)
            }
            (false, false) => {
                self.project_constraints::<false, false>(iterations, family_constants, inverse_h)
            }
        }
        self.cached_forces_valid = false;
    }
}

by_cpu! {
    /// Symplectic Euler prediction over sub-step `h` (s): `v += h w f`, then `x += h v`, keeping the start
    /// positions in `previous` (Macklin et al. 2016, Algorithm 1, lines 3–4).
    fn predict_positions(
        h: f64,
        inverse_masses: &[f64],
        forces: &[DVec3],
        positions: &mut [DVec3],
        velocities: &mut [DVec3],
        previous: &mut [DVec3],
    ) {
        previous.copy_from_slice(positions);
        for ((x, v), (&w, &f)) in positions
            .iter_mut()
            .zip(velocities.iter_mut())
            .zip(inverse_masses.iter().zip(forces))
        {
            *v += h * w * f;
            *x += h * *v;
        }
    }
}

by_cpu! {
    /// Velocities from the position change over the sub-step, `v = (x − x_previous)/h` (Macklin et al.
    /// 2016, Algorithm 1, line 16), with `inverse_h = 1/h` in 1/s.
    fn velocities_from_positions(
        inverse_h: f64,
        positions: &[DVec3],
        previous: &[DVec3],
        velocities: &mut [DVec3],
    ) {
        for (v, (&x, &start)) in velocities.iter_mut().zip(positions.iter().zip(previous)) {
            *v = (x - start) * inverse_h;
        }
    }
}

impl Simulation {
    /// `iterations` Gauss–Seidel sweeps over the constraints, batch by batch, each followed by the
    /// long-range attachments, then the velocities from the position change (`inverse_h = 1/h`, 1/s) in
    /// the same pass as the last attachments. Grids go strip by strip ([`GridConstraints`]), other meshes
    /// constraint by constraint in their colour batches; both project with [`project`].
    fn project_constraints<const PBD: bool, const MULTIPLIERS: bool>(
        &mut self,
        iterations: u32,
        family: [FamilyConstants; 3],
        inverse_h: f64,
    ) {
        let parallel = self.parallel();
        let Simulation {
            positions,
            velocities,
            previous_positions,
            colours,
            uncoloured,
            lambdas,
            packed,
            tether_anchors,
            tether_lengths,
            tether_anchor_positions: anchors,
            tether_pin_positions: pin_positions,
            pinned_indices,
            params,
            inverse_masses,
            grid_constraints,
            ..
        } = self;
        let particle_count = positions.len();
        let inverse_masses = &inverse_masses[..];
        let long_range_attachments = params.long_range_attachments && !pinned_indices.is_empty();
        if MULTIPLIERS {
            lambdas.fill(0.0);
            if let Some(grid) = grid_constraints.as_mut() {
                grid.lambdas.fill(0.0);
            }
        }
        let previous = &previous_positions[..];
        let positions = DisjointSlice::new(positions);
        let lambdas = DisjointSlice::new(lambdas);
        let packed = &packed[..];
        let solve = |c: usize| {
            let k = &packed[c];
            let (a, b) = (k.a as usize, k.b as usize);
            // SAFETY: the colouring puts no two springs sharing a particle in one batch, and each spring
            // owns its multiplier, so no index is touched by two threads at once.
            unsafe {
                let (mut x_a, mut x_b) = (positions.get(a), positions.get(b));
                let mut lambda = if MULTIPLIERS { lambdas.get(c) } else { 0.0 };
                project::<PBD, MULTIPLIERS>(
                    &mut x_a,
                    &mut x_b,
                    previous[a],
                    previous[b],
                    inverse_masses[a],
                    inverse_masses[b],
                    k.rest_length,
                    k.inverse_denominator,
                    &mut lambda,
                    family[k.family as usize],
                );
                positions.set(a, x_a);
                positions.set(b, x_b);
                if MULTIPLIERS {
                    lambdas.set(c, lambda);
                }
            }
        };
        let velocities = DisjointSlice::new(velocities);
        let anchors = DisjointSlice::new(anchors);
        for iteration in 0..iterations {
            if let Some(grid) = grid_constraints.as_mut() {
                let GridConstraints {
                    springs,
                    strips,
                    batches,
                    rest_lengths,
                    inverse_denominators,
                    lambdas,
                } = grid;
                let lambdas = DisjointSlice::new(lambdas);
                let project_strip = |strip: &Strip| {
                    let family = family[family_index(springs[strip.first].kind)];
                    let constraints = strip.first..strip.first + strip.count;
                    let (rest, inverse_denominators) = (
                        &rest_lengths[constraints.clone()],
                        &inverse_denominators[constraints.clone()],
                    );
                    // SAFETY: the strips of a batch touch disjoint particle ranges (checked by the
                    // `grid_strips_*` tests), each strip owns its constraints' multipliers, and one
                    // strip's two ranges do not overlap (`Layout::Apart` has b ≥ a + count).
                    unsafe {
                        let lambdas = lambdas.slice_mut(constraints);
                        let [first, second] = strip.particle_ranges();
                        match strip.layout {
                            Layout::Apart { .. } => {
                                project_apart::<PBD, MULTIPLIERS>(
                                    positions.slice_mut(first.clone()),
                                    positions.slice_mut(second.clone()),
                                    &previous[first.clone()],
                                    &previous[second.clone()],
                                    &inverse_masses[first],
                                    &inverse_masses[second],
                                    rest,
                                    inverse_denominators,
                                    lambdas,
                                    family,
                                );
                            }
                            Layout::Along { half } => {
                                let x = positions.slice_mut(first.clone());
                                let (previous, w) =
                                    (&previous[first.clone()], &inverse_masses[first]);
                                if half == 1 {
                                    project_along::<PBD, MULTIPLIERS, 1, 2>(
                                        x.as_chunks_mut().0,
                                        previous.as_chunks().0,
                                        w.as_chunks().0,
                                        rest.as_chunks().0,
                                        inverse_denominators.as_chunks().0,
                                        lambdas.as_chunks_mut().0,
                                        family,
                                    );
                                } else {
                                    project_along::<PBD, MULTIPLIERS, 2, 4>(
                                        x.as_chunks_mut().0,
                                        previous.as_chunks().0,
                                        w.as_chunks().0,
                                        rest.as_chunks().0,
                                        inverse_denominators.as_chunks().0,
                                        lambdas.as_chunks_mut().0,
                                        family,
                                    );
                                }
                            }
                        }
                    }
                };
                for batch in batches.iter() {
                    let strips = &strips[batch.clone()];
                    parts(strips.len(), parallel, 4, |range| {
                        strips[range].iter().for_each(project_strip)
                    });
                }
            } else {
                for range in colours.iter() {
                    if parallel && range.len() >= MIN_PARALLEL_BATCH {
                        range
                            .clone()
                            .into_par_iter()
                            .with_min_len(256)
                            .for_each(solve);
                    } else {
                        range.clone().for_each(solve);
                    }
                }
                uncoloured.clone().for_each(solve);
            }
            let last = iteration + 1 == iterations;
            if long_range_attachments {
                // The anchors are pinned (inverse mass 0): no projection moves them. Their positions are
                // gathered once here, so that the parallel pass below reads no position another part
                // writes.
                for (anchor, &i) in pin_positions.iter_mut().zip(pinned_indices.iter()) {
                    // SAFETY: no pass is running.
                    *anchor = unsafe { positions.get(i as usize) };
                }
            }
            let pin_positions = &pin_positions[..];
            if long_range_attachments || last {
                parts(particle_count, parallel, PARTICLE_GRAIN, |range| {
                    // SAFETY: the parts are disjoint.
                    unsafe {
                        let x = positions.slice_mut(range.clone());
                        if long_range_attachments {
                            // Each particle's anchor is copied next to it first: the attachment loop
                            // then reads contiguous memory and vectorises (a gather inside it kept the
                            // compiler from it).
                            let anchors = anchors.slice_mut(range.clone());
                            for (anchor, &k) in
                                anchors.iter_mut().zip(&tether_anchors[range.clone()])
                            {
                                *anchor = pin_positions[k as usize];
                            }
                            apply_tethers(x, anchors, &tether_lengths[range.clone()]);
                        }
                        if last {
                            let v = velocities.slice_mut(range.clone());
                            velocities_from_positions(inverse_h, x, &previous[range], v);
                        }
                    }
                });
            }
        }
    }
}

by_cpu! {
    /// Long-range attachments (Kim, Chentanez & Müller 2012, "Long Range Attachments"): particle `i` is
    /// pulled back onto the sphere of radius `lengths[i]` (m) around `anchors[i]` when it lies outside
    /// it, and left alone otherwise.
    fn apply_tethers(positions: &mut [DVec3], anchors: &[DVec3], lengths: &[f64]) {
        let n = positions.len();
        let (anchors, lengths) = (&anchors[..n], &lengths[..n]);
        for i in 0..n {
            let (x, anchor, rest) = (positions[i], anchors[i], lengths[i]);
            let offset = x - anchor;
            let distance = offset.length();
            positions[i] = if distance > rest {
                anchor + offset * (rest / distance)
            } else {
                x
            };
        }
    }
}
