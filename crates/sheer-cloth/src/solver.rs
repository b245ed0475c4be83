//! The position-based sub-step on one screen, in plain vector code: PBD (Müller, Heidelberger, Hennix &
//! Ratcliff 2007), XPBD (Macklin, Müller & Chentanez 2016) and small-steps XPBD (Macklin et al. 2019).
//!
//! Per sub-step of length `h` (s), after Macklin et al. 2016, Algorithm 1:
//! 1. **forces**: gravity, air damping and the wind's held corner shares, `f = m(g − c v) + Σ shares`;
//! 2. **predict**: `v += h w f`, `x = x⁰ + h v` (lines 3–4);
//! 3. **project** the distance constraints batch by batch, each batch's constraints independent of one
//!    another (eqs. 18 and 26, [`project`]), then pull every particle back within its long-range
//!    attachment (Kim, Chentanez & Müller 2012); `iterations` times (lines 5–14);
//! 4. **update velocities**: `v = (x − x⁰)/h` (line 16).
//!
//! A general triangle mesh steps here. A grid steps through the fast paths of [`crate::fast`] (strips,
//! row passes, wavefronts, threads), which must give exactly these bits: the tests at the end of this
//! file run both and compare every position and velocity.

use glam::DVec3;

use crate::fast::grid_constraints::GridConstraints;
use crate::fast::parallel::fill;
use crate::model::Spring;
use crate::sim::{Simulation, family_index};
use crate::wind::corner_share_of_triangle_force;

impl Simulation {
    /// One position-based sub-step of length `h` (s) at time `t` (s) on the joined state (`positions`,
    /// `velocities`). `pbd_stiffness`: PBD with that stiffness; `None`: XPBD with compliance `1/k`.
    pub(crate) fn plain_position_based_substep(
        &mut self,
        h: f64,
        t: f64,
        iterations: u32,
        pbd_stiffness: Option<f64>,
    ) {
        let family = self.solver_constants(h, iterations, pbd_stiffness);
        self.sum_external_forces(t);
        // 2. Predict (Algorithm 1, lines 3–4); `joined_previous` keeps the start positions x⁰.
        self.joined_previous
            .resize(self.positions.len(), DVec3::ZERO);
        for i in 0..self.positions.len() {
            let start = self.positions[i];
            self.joined_previous[i] = start;
            self.velocities[i] += h * self.inverse_masses[i] * self.forces[i];
            self.positions[i] = start + h * self.velocities[i];
        }
        // Pinned particles have w = 0: no projection moves them, so their attachments' anchors are
        // where the prediction put them.
        let pins = self.pinned_indices.len();
        for k in 0..pins {
            self.tether_pin_positions[k] = self.positions[self.pinned_indices[k] as usize];
        }
        // 3. Project (lines 5–14). With one iteration each multiplier is read once, right after being
        // reset: always 0, so the multipliers are left out (the same bits).
        match (pbd_stiffness.is_some(), iterations > 1) {
            (true, _) => self.project_sweeps::<true, false>(iterations, &family),
            (false, true) => self.project_sweeps::<false, true>(iterations, &family),
            (false, false) => self.project_sweeps::<false, false>(iterations, &family),
        }
        // 4. Velocities from the position change (line 16).
        let inverse_h = 1.0 / h;
        for i in 0..self.positions.len() {
            self.velocities[i] = (self.positions[i] - self.joined_previous[i]) * inverse_h;
        }
        self.cached_forces_valid = false;
    }

    /// Step 1: `f = m(g − c v)` per particle (N), then each triangle's corner share of the wind's force
    /// added to its corners in ascending triangle order. The shares are held between renewals
    /// (`wind.renewal_interval`) and renewed from the sub-step's start state when due.
    fn sum_external_forces(&mut self, t: f64) {
        if let Some((wind, air_velocity)) = self.due_wind_renewal(t) {
            for (share, triangle) in self.triangle_forces.iter_mut().zip(&self.triangles) {
                let corners = triangle.map(|i| i as usize);
                *share = corner_share_of_triangle_force(
                    &wind,
                    corners.map(|i| self.positions[i]),
                    corners.map(|i| self.velocities[i]),
                    air_velocity,
                );
            }
        }
        let (gravity, air_damping) = (self.params.gravity, self.params.air_damping);
        for i in 0..self.forces.len() {
            self.forces[i] = self.masses[i] * (gravity - air_damping * self.velocities[i]);
        }
        if self.wind_acts() {
            for (triangle, &share) in self.triangles.iter().zip(&self.triangle_forces) {
                for &corner in triangle {
                    self.forces[corner as usize] += share;
                }
            }
        }
    }

    /// Step 3: `iterations` sweeps over the constraint batches, each followed by the attachments. A grid's
    /// batches are its twelve row-strip batches, a mesh's its colours, then the springs no colour took,
    /// one by one. A switched-off family's constraints are projected too, to no effect (their inverted
    /// divisors are 0): the fast paths skip them, and the tests hold that to the same bits.
    fn project_sweeps<const PBD: bool, const MULTIPLIERS: bool>(
        &mut self,
        iterations: u32,
        families: &[FamilyConstants; 3],
    ) {
        let attachments = self.params.long_range_attachments && !self.pinned_indices.is_empty();
        let Simulation {
            positions: x,
            joined_previous: start,
            inverse_masses: w,
            grid_constraints,
            packed,
            colours,
            uncoloured,
            lambdas,
            tether_anchors,
            tether_lengths,
            tether_pin_positions: anchors,
            ..
        } = self;
        let (start, w) = (&start[..], &w[..]);
        if MULTIPLIERS {
            lambdas.fill(0.0);
            if let Some(grid) = grid_constraints.as_mut() {
                grid.lambdas.fill(0.0);
            }
        }
        for _ in 0..iterations {
            if let Some(grid) = grid_constraints.as_mut() {
                for batch in &grid.batches {
                    for strip in &grid.strips[batch.clone()] {
                        let family = family_index(strip.kind);
                        for k in 0..strip.count {
                            let ((a, b), c) = (strip.ends(k), strip.first + k);
                            let constraint = Constraint {
                                a,
                                b,
                                rest_length: grid.rest_lengths[c],
                                inverse_denominator: grid.inverse_denominators[c],
                                family: families[family],
                            };
                            let lambda = &mut grid.lambdas[c];
                            project_constraint::<PBD, MULTIPLIERS>(x, start, w, constraint, lambda);
                        }
                    }
                }
            } else {
                for c in colours.iter().cloned().flatten().chain(uncoloured.clone()) {
                    let k = packed[c];
                    let constraint = Constraint {
                        a: k.a as usize,
                        b: k.b as usize,
                        rest_length: k.rest_length,
                        inverse_denominator: k.inverse_denominator,
                        family: families[k.family as usize],
                    };
                    project_constraint::<PBD, MULTIPLIERS>(
                        x,
                        start,
                        w,
                        constraint,
                        &mut lambdas[c],
                    );
                }
            }
            // Long-range attachments (Kim, Chentanez & Müller 2012): a particle farther than its tether
            // length from its pin (where the prediction put it) is put back on that sphere.
            if attachments {
                for i in 0..x.len() {
                    let anchor = anchors[tether_anchors[i] as usize];
                    x[i] = tethered(x[i], anchor, tether_lengths[i]);
                }
            }
        }
    }
}

/// One distance constraint as a sweep meets it: its ends, rest length (m), the inverted divisor of its
/// update and its family's constants.
struct Constraint {
    a: usize,
    b: usize,
    rest_length: f64,
    inverse_denominator: f64,
    family: FamilyConstants,
}

/// Projects `constraint` on the positions `x` (m), with start positions `start` (m), inverse masses `w`
/// (1/kg) and its multiplier `lambda`: [`project`], whose damping term a family without damping
/// (γ = 0) leaves out, as the strips do.
fn project_constraint<const PBD: bool, const MULTIPLIERS: bool>(
    x: &mut [DVec3],
    start: &[DVec3],
    w: &[f64],
    constraint: Constraint,
    lambda: &mut f64,
) {
    let Constraint { a, b, .. } = constraint;
    let (mut x_a, mut x_b) = (x[a], x[b]);
    let project = if constraint.family.gamma != 0.0 {
        project::<PBD, MULTIPLIERS, true>
    } else {
        project::<PBD, MULTIPLIERS, false>
    };
    project(
        &mut x_a,
        &mut x_b,
        start[a],
        start[b],
        w[a],
        w[b],
        constraint.rest_length,
        constraint.inverse_denominator,
        lambda,
        constraint.family,
    );
    (x[a], x[b]) = (x_a, x_b);
}

/// `x` (m) pulled back onto the sphere of radius `length` (m) around `anchor` (m) if it lies outside.
#[inline(always)]
pub(crate) fn tethered(x: DVec3, anchor: DVec3, length: f64) -> DVec3 {
    let offset = x - anchor;
    let distance = offset.length();
    if distance > length {
        anchor + offset * (length / distance)
    } else {
        x
    }
}

/// Per-sub-step constants of one constraint family: `(α̃, γ)` of XPBD (Macklin et al. 2016 eqs. (18) and
/// (26)); unused by PBD.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct FamilyConstants {
    /// `α̃ = α/h²`, with compliance `α = 1/k` (m/N) and sub-step `h` (s): 1/kg.
    pub scaled_compliance: f64,
    /// `γ = α β / h` with damping `β` (N·s/m): dimensionless.
    pub gamma: f64,
}

/// Projects one distance constraint `|x_a − x_b| = rest` (Macklin, Müller & Chentanez 2016, eq. (18) with
/// the damping of eq. (26); PBD: Müller et al. 2007 §3.3 with the divisor folded into
/// `inverse_denominator`). Nothing moves when the constraint is inactive (`inverse_denominator` = 0: a
/// switched-off family or both ends pinned) or the ends coincide (no gradient direction; ends closer than
/// about 1.5·10⁻¹⁵⁴ m, whose squared distance is not a normal `f64`, count as coincident). With
/// `MULTIPLIERS` the accumulated multiplier λ is read and updated; without it λ is taken as 0 (one
/// iteration: it is always 0 when read). Without `DAMPED` (a family with no damping, γ = 0) the damping
/// term is left out, and with it the start positions it needs (a sixth of the bytes a projection reads).
///
/// With `d = x_a − x_b`, `L = |d|`, the gradient `∇C = d/L` and the start-to-now displacement
/// `m = (x_a − x_a⁰) − (x_b − x_b⁰)`, eq. (18)/(26) give `Δλ = (−C − α̃λ − γ ∇C·m) / ((1 + γ) w + α̃)` and
/// the step `Δx_a = w_a Δλ ∇C`. Written over `L² = d·d` instead of `L`,
///
/// `Δλ/L = ((rest − L − α̃λ) L − γ d·m) · inverse_denominator / L²`, `Δx_a = w_a (Δλ/L) d`,
///
/// the one division (`1/L²`) no longer waits for the square root, and nothing but the elastic term
/// does: the chain of dependent operations from the particles' loads to their stores is about a third
/// shorter (the square root's result used to feed a division, then the gradient, the damping rate and
/// the step, one after the other). The strip loops were bound by that chain, not by their operation
/// count: too few blocks of eight fit in the CPU's window to cover it. Mathematically the same update; the rounding differs from `Δλ·(d·(1/L))` by a few ulp.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn project<const PBD: bool, const MULTIPLIERS: bool, const DAMPED: bool>(
    x_a: &mut DVec3,
    x_b: &mut DVec3,
    previous_a: DVec3,
    previous_b: DVec3,
    inverse_mass_a: f64,
    inverse_mass_b: f64,
    rest_length: f64,
    inverse_denominator: f64,
    lambda: &mut f64,
    family: FamilyConstants,
) {
    let delta = *x_a - *x_b;
    let squared_length = delta.dot(delta);
    let inverse_squared_length = 1.0 / squared_length;
    let length = squared_length.sqrt();
    // −C, less α̃λ with multipliers (without them λ is 0 and so is its term, α̃ being finite: left out).
    let elastic = if !PBD && MULTIPLIERS {
        (rest_length - length) - family.scaled_compliance * *lambda
    } else {
        rest_length - length
    };
    // (Δλ·L²)/inverse_denominator: the elastic term times L, less the damping's γ·(d·m) (∇C·m = d·m/L).
    let numerator = if !PBD && DAMPED {
        let moved = (*x_a - previous_a) - (*x_b - previous_b);
        elastic * length - family.gamma * delta.dot(moved)
    } else {
        elastic * length
    };
    // Selected, not branched on, so that the strip loops vectorise. A squared length below the normal
    // range would make `1/L²` infinite.
    let active = inverse_denominator != 0.0 && squared_length >= f64::MIN_POSITIVE;
    // Δλ/L.
    let coefficient = if active {
        numerator * (inverse_denominator * inverse_squared_length)
    } else {
        0.0
    };
    if MULTIPLIERS {
        *lambda += if active { coefficient * length } else { 0.0 };
    }
    let step = if active {
        coefficient * delta
    } else {
        DVec3::ZERO
    };
    *x_a += inverse_mass_a * step;
    *x_b -= inverse_mass_b * step;
}

impl Simulation {
    /// The per-family constants of a sub-step of length `h` (s) with `iterations` sweeps (PBD with
    /// stiffness `pbd_stiffness`, else XPBD), with the constraints' inverted divisors brought up to date.
    pub(crate) fn solver_constants(
        &mut self,
        h: f64,
        iterations: u32,
        pbd_stiffness: Option<f64>,
    ) -> [FamilyConstants; 3] {
        let parallel = self.parallel();
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
        family_constants
    }
}

/// One distance constraint as the solver streams it, in colour order. 32 bytes: per-family constants
/// live in a 3-entry table and inverse masses in the particle array, so that the constraints of large
/// cloths take half the cache and memory bandwidth a 64-byte record did (the solver streams all of
/// them every sub-step). Rebuilt when the sub-step length or the parameters change.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PackedConstraint {
    pub a: u32,
    pub b: u32,
    pub rest_length: f64,
    /// PBD: k'/(w_a + w_b); XPBD: 1/((1 + γ)(w_a + w_b) + α̃); 0 when the constraint is inactive.
    pub inverse_denominator: f64,
    /// Index into the per-family (α̃, γ) table of the sub-step.
    pub family: u8,
}

/// Where the tests move a flag's pins in frame `frame`: turning about the pole, which leaves them where
/// they are, and swaying, which moves them (and so gives them a velocity in every sub-step).
#[cfg(test)]
pub(crate) fn hoist_sway_and_turn(frame: usize) -> glam::DAffine3 {
    let sway = DVec3::new(0.01, 0.0, 0.02) * (0.5 * frame as f64).sin();
    glam::DAffine3::from_translation(sway) * glam::DAffine3::from_rotation_y(0.01 * frame as f64)
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use crate::fast::grid_step::GridSweep;
    use crate::model::{ClothModel, GridSpec};
    use crate::params::{Collider, Method, SimParams, SpringParams};
    use crate::sim::{Path, Simulation};

    use super::hoist_sway_and_turn;

    /// `frames` 60 Hz frames of `sim` through `path` on a pool of `threads` threads, the hoist swaying and
    /// turning a little every frame (so the pins move within every sub-step); the bits of the positions
    /// and velocities after each frame.
    fn bits_per_frame(
        mut sim: Simulation,
        path: Path,
        threads: usize,
        frames: usize,
    ) -> Vec<Vec<[u64; 3]>> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            (0..frames)
                .map(|frame| {
                    sim.move_pins(hoist_sway_and_turn(frame)).unwrap();
                    sim.step_through(1.0 / 60.0, path).unwrap();
                    let state = sim.positions().iter().chain(sim.velocities());
                    state.map(|v| v.to_array().map(f64::to_bits)).collect()
                })
                .collect()
        })
    }

    /// A `columns` × `rows` flag with its hoist pinned, `params` changed by `change`; the parallel code
    /// paths forced on when `parallel`.
    fn flag(
        columns: usize,
        rows: usize,
        parallel: bool,
        change: impl FnOnce(&mut SimParams),
    ) -> Simulation {
        let spec = GridSpec {
            columns,
            rows,
            ..GridSpec::default()
        };
        let model = ClothModel::grid(&spec)
            .unwrap()
            .with_hoist_pinned()
            .unwrap();
        let mut params = SimParams::waving_flag();
        params.parallel_min_particles = if parallel { 0 } else { usize::MAX };
        change(&mut params);
        Simulation::new(model, params).unwrap()
    }

    /// The fast paths against the plain code, frame by frame, on `threads` threads.
    fn assert_fast_gives_the_plain_bits(
        sim: Simulation,
        threads: usize,
        frames: usize,
        case: &str,
    ) {
        let plain = bits_per_frame(sim.clone(), Path::Plain, 1, frames);
        let fast = bits_per_frame(sim, Path::Fast(GridSweep::Auto), threads, frames);
        for (frame, (fast, plain)) in fast.iter().zip(&plain).enumerate() {
            assert!(
                fast == plain,
                "{case}, {threads} threads: frame {frame} differs"
            );
        }
    }

    /// The default flag (small-steps XPBD ×40, the wind's forces held 2 ms): sub-step by sub-step on one
    /// thread, as the team's pipeline on two.
    #[test]
    fn the_default_flag_gives_the_plain_bits() {
        for (threads, parallel) in [(1, false), (2, true)] {
            assert_fast_gives_the_plain_bits(
                flag(64, 46, parallel, |_| ()),
                threads,
                30,
                "default",
            );
        }
    }

    /// PBD and XPBD with several iterations (multipliers), the wind renewed every sub-step and none at
    /// all, no attachments, a switched-off family (which the fast paths skip and the plain code projects
    /// to no effect): every way a grid's sub-step can sweep.
    #[test]
    fn every_method_and_model_part_gives_the_plain_bits() {
        let methods = [
            Method::Pbd {
                substeps: 4,
                iterations: 5,
                stiffness: 1.0,
            },
            Method::Xpbd {
                substeps: 4,
                iterations: 5,
            },
        ];
        type Change = (&'static str, fn(&mut SimParams));
        let changes: [Change; 5] = [
            ("wind every sub-step", |p| p.wind.renewal_interval = 0.0),
            ("no wind", |p| p.wind.velocity = DVec3::ZERO),
            ("no attachments", |p| p.long_range_attachments = false),
            ("no bending", |p| p.bend = SpringParams::disabled()),
            ("no shear", |p| p.shear = SpringParams::disabled()),
        ];
        for method in methods {
            for (name, change) in changes {
                for (threads, parallel) in [(1, false), (2, true)] {
                    let sim = flag(32, 23, parallel, |p| {
                        p.method = method;
                        change(p);
                    });
                    assert_fast_gives_the_plain_bits(
                        sim,
                        threads,
                        10,
                        &format!("{method:?}, {name}"),
                    );
                }
            }
        }
    }

    /// A grid large enough for the wavefronts of several sub-steps a pass on one thread, and in parts on
    /// two.
    #[test]
    fn a_large_grid_in_wavefronts_gives_the_plain_bits() {
        for (threads, parallel) in [(1, true), (2, true)] {
            let sim = flag(256, 256, parallel, |p| {
                p.method = Method::SmallStepsXpbd { substeps: 20 }
            });
            assert_fast_gives_the_plain_bits(sim, threads, 2, "256 x 256");
        }
    }

    /// Self-collision and the pole collider, projected between sub-steps.
    #[test]
    fn contacts_give_the_plain_bits() {
        for (threads, parallel) in [(1, false), (2, true)] {
            let sim = flag(32, 23, parallel, |p| {
                p.collisions.self_collision = true;
                let spec = GridSpec {
                    columns: 32,
                    rows: 23,
                    ..GridSpec::default()
                };
                p.collisions.colliders = vec![Collider::flag_pole(&spec, p.collisions.thickness)];
            });
            assert_fast_gives_the_plain_bits(sim, threads, 20, "contacts");
        }
    }

    /// Colliders alone (a sphere through the middle of the flag and the pole), which keep each
    /// particle off where it lies instead of projecting on the joined state.
    #[test]
    fn colliders_alone_give_the_plain_bits() {
        for (threads, parallel) in [(1, false), (2, true)] {
            let sim = flag(32, 23, parallel, |p| {
                let spec = GridSpec {
                    columns: 32,
                    rows: 23,
                    ..GridSpec::default()
                };
                let center = spec.origin + DVec3::new(0.6 * spec.width, -0.5 * spec.height, 0.0);
                p.collisions.colliders = vec![
                    Collider::Sphere {
                        center,
                        radius: 0.1,
                    },
                    Collider::flag_pole(&spec, p.collisions.thickness),
                ];
            });
            // The colliders act: without them the flag ends elsewhere.
            let alone = bits_per_frame(sim.clone(), Path::Plain, 1, 20);
            let free = bits_per_frame(flag(32, 23, parallel, |_| ()), Path::Plain, 1, 20);
            assert!(alone.last() != free.last(), "the colliders touch the flag");
            assert_fast_gives_the_plain_bits(sim, threads, 20, "colliders");
        }
    }
}
