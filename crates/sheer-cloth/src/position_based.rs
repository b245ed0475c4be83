//! Position-based integrators: PBD (Müller, Heidelberger, Hennix & Ratcliff 2007), XPBD (Macklin,
//! Müller & Chentanez 2016) and small-steps XPBD (Macklin, Storey, Lu, Terdiman, Chentanez, Jeschke &
//! Müller 2019) — one loop, three settings.
//!
//! Per sub-step: external forces into velocities, predict positions, project the distance constraints
//! colour batch by colour batch (Gauss–Seidel across batches, independent within a batch, so a batch
//! can run in parallel with the same result), then velocities from the position change.

use glam::DVec3;
use rayon::prelude::*;

use crate::parallel::{DisjointSlice, fill};
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
            if parallel {
                const CHUNK: usize = 4096;
                positions
                    .par_chunks_mut(CHUNK)
                    .zip(velocities.par_chunks_mut(CHUNK))
                    .zip(previous_positions.par_chunks_mut(CHUNK))
                    .enumerate()
                    .for_each(|(chunk, ((x, v), previous))| {
                        let range = chunk * CHUNK..chunk * CHUNK + x.len();
                        predict_positions(
                            h,
                            &inverse_masses[range.clone()],
                            &forces[range],
                            x,
                            v,
                            previous,
                        );
                    });
            } else {
                predict_positions(
                    h,
                    inverse_masses,
                    forces,
                    positions,
                    velocities,
                    previous_positions,
                );
            }
        }
        // With one iteration every multiplier is used once, right after being reset: it is always 0 when
        // read, so small-steps XPBD skips the multipliers altogether (same arithmetic, same bits).
        let keep_multipliers = iterations > 1;
        if keep_multipliers {
            self.lambdas.fill(0.0);
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
                ..
            } = self;
            packed.resize(springs.len(), PackedConstraint::default());
            fill(packed, parallel, |c| {
                let sp = &springs[c];
                let family = family_index(sp.kind);
                let (scale, scaled_compliance, gamma) = constants[family];
                let (wa, wb) = (inverse_masses[sp.a as usize], inverse_masses[sp.b as usize]);
                let w = wa + wb;
                let inverse_denominator = if scale == 0.0 || w == 0.0 {
                    0.0
                } else if is_pbd {
                    scale / w
                } else {
                    1.0 / ((1.0 + gamma) * w + scaled_compliance)
                };
                PackedConstraint {
                    a: sp.a,
                    b: sp.b,
                    rest_length: sp.rest_length,
                    inverse_denominator,
                    family: family as u8,
                }
            });
            self.denominator_key = Some(key);
        }
        let Simulation {
            positions,
            previous_positions,
            colours,
            uncoloured,
            lambdas,
            packed,
            tethers,
            pinned_indices,
            params,
            inverse_masses,
            ..
        } = self;
        let inverse_masses = &inverse_masses[..];
        // (α̃, γ) per family, indexed by `PackedConstraint::family`.
        let family_constants: [(f64, f64); 3] =
            std::array::from_fn(|f| (constants[f].1, constants[f].2));
        let long_range_attachments = params.long_range_attachments && !pinned_indices.is_empty();
        let positions = DisjointSlice::new(positions);
        let lambdas = DisjointSlice::new(lambdas);
        let previous = &previous_positions[..];
        let packed = &packed[..];
        let solve = |c: usize| {
            let k = &packed[c];
            if k.inverse_denominator == 0.0 {
                return; // switched-off family or both ends pinned
            }
            let (a, b) = (k.a as usize, k.b as usize);
            // SAFETY: the colouring puts no two springs sharing a particle in one batch, and each spring
            // owns its multiplier, so no index is touched by two threads at once.
            let (xa, xb) = unsafe { (positions.get(a), positions.get(b)) };
            let delta = xa - xb;
            let length = delta.length();
            if length == 0.0 {
                return; // coincident ends: no gradient direction
            }
            let gradient = delta * (1.0 / length);
            let constraint = length - k.rest_length;
            let correction = if is_pbd {
                -constraint * k.inverse_denominator
            } else {
                let rate = gradient.dot((xa - previous[a]) - (xb - previous[b]));
                let (scaled_compliance, gamma) = family_constants[k.family as usize];
                // SAFETY: see above.
                let lambda = if keep_multipliers {
                    unsafe { lambdas.get(c) }
                } else {
                    0.0
                };
                let delta_lambda = (-constraint - scaled_compliance * lambda - gamma * rate)
                    * k.inverse_denominator;
                if keep_multipliers {
                    unsafe { lambdas.set(c, lambda + delta_lambda) };
                }
                delta_lambda
            };
            let step = correction * gradient;
            // SAFETY: see above.
            unsafe {
                positions.set(a, xa + inverse_masses[a] * step);
                positions.set(b, xb - inverse_masses[b] * step);
            }
        };
        for _ in 0..iterations {
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
            if long_range_attachments {
                // Each tether moves only its own free particle towards a pinned one: independent.
                let tether = |i: usize| {
                    if let Some((k, rest)) = tethers[i] {
                        let anchor_index = pinned_indices[k as usize] as usize;
                        // SAFETY: tether i writes only particle i, and reads a pinned particle, which
                        // no tether writes.
                        let (x, anchor) =
                            unsafe { (positions.get(i), positions.get(anchor_index)) };
                        let offset = x - anchor;
                        let distance = offset.length();
                        if distance > rest {
                            unsafe { positions.set(i, anchor + offset * (rest / distance)) };
                        }
                    }
                };
                if parallel {
                    (0..tethers.len())
                        .into_par_iter()
                        .with_min_len(1024)
                        .for_each(tether);
                } else {
                    (0..tethers.len()).for_each(tether);
                }
            }
        }
        let Simulation {
            positions,
            velocities,
            previous_positions,
            ..
        } = self;
        let inverse_h = 1.0 / h;
        if parallel {
            const CHUNK: usize = 4096;
            velocities
                .par_chunks_mut(CHUNK)
                .zip(positions.par_chunks(CHUNK))
                .zip(previous_positions.par_chunks(CHUNK))
                .for_each(|((v, x), previous)| {
                    velocities_from_positions(inverse_h, x, previous, v)
                });
        } else {
            velocities_from_positions(inverse_h, positions, previous_positions, velocities);
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
