//! Force-based integrators of the mass–spring model: explicit Euler, symplectic Euler, velocity Verlet
//! and implicit (backward) Euler with a conjugate-gradient solve (Baraff & Witkin 1998).
//!
//! Each runs one sub-step of length `h` (s) at time `t` (s); pinned particles have zero inverse mass and
//! the velocity `Simulation::step` prescribed for them, so they follow their path whatever the method.

use glam::{DMat3, DVec3};
use rayon::prelude::*;

use crate::fast::parallel::{fill, sum};
use crate::sim::{CgScratch, Simulation, family_index};

/// `update(i, &mut x_i, &mut v_i)` for every particle.
fn update_particles<F>(positions: &mut [DVec3], velocities: &mut [DVec3], parallel: bool, update: F)
where
    F: Fn(usize, &mut DVec3, &mut DVec3) + Sync + Send,
{
    if parallel {
        positions
            .par_iter_mut()
            .zip(velocities.par_iter_mut())
            .enumerate()
            .for_each(|(i, (x, v))| update(i, x, v));
    } else {
        for (i, (x, v)) in positions.iter_mut().zip(velocities.iter_mut()).enumerate() {
            update(i, x, v);
        }
    }
}

impl Simulation {
    /// Forward Euler: `x' = x + h v`, `v' = v + h M⁻¹ f(x, v)`.
    pub(crate) fn explicit_euler_substep(&mut self, h: f64, t: f64) {
        self.compute_forces(t, true);
        let parallel = self.parallel();
        let (forces, inverse_masses) = (&self.forces, &self.inverse_masses);
        update_particles(
            &mut self.positions,
            &mut self.velocities,
            parallel,
            |i, x, v| {
                *x += h * *v;
                *v += h * inverse_masses[i] * forces[i];
            },
        );
        self.cached_forces_valid = false;
    }

    /// Semi-implicit Euler: `v' = v + h M⁻¹ f(x, v)`, `x' = x + h v'`.
    pub(crate) fn symplectic_euler_substep(&mut self, h: f64, t: f64) {
        self.compute_forces(t, true);
        let parallel = self.parallel();
        let (forces, inverse_masses) = (&self.forces, &self.inverse_masses);
        update_particles(
            &mut self.positions,
            &mut self.velocities,
            parallel,
            |i, x, v| {
                *v += h * inverse_masses[i] * forces[i];
                *x += h * *v;
            },
        );
        self.cached_forces_valid = false;
    }

    /// Velocity Verlet (Swope, Andersen, Berens & Wilson 1982): half kick, drift, force at the new
    /// positions, half kick. The end-of-step force is reused as the next step's start force, so one force
    /// evaluation per sub-step; velocity-dependent forces (damping, wind) see the half-step velocity.
    pub(crate) fn verlet_substep(&mut self, h: f64, t: f64) {
        if !self.cached_forces_valid {
            self.compute_forces(t, true);
        }
        let parallel = self.parallel();
        {
            let (forces, inverse_masses) = (&self.forces, &self.inverse_masses);
            update_particles(
                &mut self.positions,
                &mut self.velocities,
                parallel,
                |i, x, v| {
                    *v += 0.5 * h * inverse_masses[i] * forces[i];
                    *x += h * *v;
                },
            );
        }
        self.compute_forces(t + h, true);
        let (forces, inverse_masses) = (&self.forces, &self.inverse_masses);
        update_particles(
            &mut self.positions,
            &mut self.velocities,
            parallel,
            |i, _, v| {
                *v += 0.5 * h * inverse_masses[i] * forces[i];
            },
        );
        self.cached_forces_valid = true;
    }

    /// Backward Euler, linearised (Baraff & Witkin 1998, eqs. (15)–(18)):
    /// `(M − h ∂f/∂v − h² ∂f/∂x) Δv = h (f₀ + h ∂f/∂x v₀)`, solved by Jacobi-preconditioned CG with
    /// pinned particles filtered out (their section 5.3). Each spring's stiffness block drops the
    /// transverse term of compressed springs (Choi & Ko 2002) so the system stays positive definite.
    /// Returns the CG iteration count and the final relative residual.
    pub(crate) fn implicit_euler_substep(
        &mut self,
        h: f64,
        t: f64,
        max_iterations: u32,
        tolerance: f64,
    ) -> (u32, f64) {
        self.compute_forces(t, true);
        let parallel = self.parallel();
        let n = self.positions.len();
        let spring_count = self.springs.len();
        let Simulation {
            positions,
            velocities,
            springs,
            family,
            forces,
            masses,
            inverse_masses,
            spring_incidence,
            params,
            cg,
            ..
        } = self;
        let CgScratch {
            blocks,
            diagonal,
            rhs,
            delta_velocity,
            residual,
            direction,
            product,
            preconditioned,
            spring_terms,
        } = cg;
        for buffer in [
            &mut *diagonal,
            &mut *rhs,
            &mut *delta_velocity,
            &mut *residual,
            &mut *direction,
            &mut *product,
            &mut *preconditioned,
        ] {
            buffer.resize(n, DVec3::ZERO);
        }
        blocks.resize(spring_count, DMat3::ZERO);
        spring_terms.resize(spring_count, DVec3::ZERO);
        let air = 1.0 + h * params.air_damping;
        let free = |i: usize| inverse_masses[i] != 0.0;

        // Per spring: S = −h ∂f/∂v − h² ∂f/∂x (block of end a), and ∂f/∂x · (v_a − v_b) for the rhs.
        {
            let (positions, velocities) = (&positions[..], &velocities[..]);
            let per_spring: &(dyn Fn(usize) -> (DMat3, DVec3) + Sync) = &|s| {
                let sp = &springs[s];
                let (stiffness, damping) = family[family_index(sp.kind)];
                let (a, b) = (sp.a as usize, sp.b as usize);
                let delta = positions[b] - positions[a];
                let length = delta.length();
                if stiffness == 0.0 || length == 0.0 {
                    return (DMat3::ZERO, DVec3::ZERO);
                }
                let u = delta / length;
                let axial = DMat3::from_cols(u * u.x, u * u.y, u * u.z);
                let transverse = (1.0 - sp.rest_length / length).max(0.0);
                // ∂f_a/∂x_a = −k [u uᵀ + (1 − L/l)⁺ (I − u uᵀ)];  ∂f_a/∂v_a = −c u uᵀ.
                let stiffness_block = -stiffness * (axial + transverse * (DMat3::IDENTITY - axial));
                let system_block = h * damping * axial - h * h * stiffness_block;
                (
                    system_block,
                    stiffness_block * (velocities[a] - velocities[b]),
                )
            };
            if parallel {
                blocks
                    .par_iter_mut()
                    .zip(spring_terms.par_iter_mut())
                    .enumerate()
                    .for_each(|(s, (block, term))| (*block, *term) = per_spring(s));
            } else {
                for (s, (block, term)) in blocks.iter_mut().zip(spring_terms.iter_mut()).enumerate()
                {
                    (*block, *term) = per_spring(s);
                }
            }
        }
        let gather = |i: usize, terms: &[DVec3]| {
            let mut total = DVec3::ZERO;
            for &item in spring_incidence.of(i) {
                let term = terms[(item >> 1) as usize];
                total += if item & 1 == 0 { term } else { -term };
            }
            total
        };
        fill(rhs, parallel, |i| {
            if free(i) {
                h * (forces[i] + h * gather(i, spring_terms))
            } else {
                DVec3::ZERO
            }
        });
        fill(diagonal, parallel, |i| {
            let mut d = DVec3::splat(masses[i] * air);
            for &item in spring_incidence.of(i) {
                let block = &blocks[(item >> 1) as usize];
                d += DVec3::new(block.x_axis.x, block.y_axis.y, block.z_axis.z);
            }
            d
        });

        let dot = |x: &[DVec3], y: &[DVec3]| sum(n, parallel, |i| x[i].dot(y[i]));
        let rhs_norm = dot(rhs, rhs).sqrt();
        delta_velocity.fill(DVec3::ZERO);
        let mut iterations = 0;
        let mut relative_residual = 0.0;
        if rhs_norm > 0.0 {
            residual.copy_from_slice(rhs);
            fill(preconditioned, parallel, |i| residual[i] / diagonal[i]);
            direction.copy_from_slice(preconditioned);
            let mut rz = dot(residual, preconditioned);
            relative_residual = 1.0;
            while iterations < max_iterations && relative_residual > tolerance {
                // product = A · direction
                fill(spring_terms, parallel, |s| {
                    let sp = &springs[s];
                    blocks[s] * (direction[sp.a as usize] - direction[sp.b as usize])
                });
                fill(product, parallel, |i| {
                    if free(i) {
                        masses[i] * air * direction[i] + gather(i, spring_terms)
                    } else {
                        DVec3::ZERO
                    }
                });
                let curvature = dot(direction, product);
                if curvature <= 0.0 {
                    break; // direction lies in the filtered null space: nothing left to solve
                }
                let step = rz / curvature;
                for i in 0..n {
                    delta_velocity[i] += step * direction[i];
                    residual[i] -= step * product[i];
                }
                fill(preconditioned, parallel, |i| residual[i] / diagonal[i]);
                let rz_next = dot(residual, preconditioned);
                let beta = rz_next / rz;
                rz = rz_next;
                for i in 0..n {
                    direction[i] = preconditioned[i] + beta * direction[i];
                }
                iterations += 1;
                relative_residual = dot(residual, residual).sqrt() / rhs_norm;
            }
        }
        let delta_velocity = &delta_velocity[..];
        update_particles(positions, velocities, parallel, |i, x, v| {
            *v += delta_velocity[i];
            *x += h * *v;
        });
        self.cached_forces_valid = false;
        (iterations, relative_residual)
    }
}
