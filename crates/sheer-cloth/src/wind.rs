//! Wind: a deterministic gust signal and the flat-plate aerodynamic force on one triangle.
//!
//! The air velocity is uniform in space and varies in time: `u(t) = U (1 + g s₁(t)) + T |U| (s₂(t) e₁ +
//! s₃(t) e₂)`, where `s_k` are sums of four sinusoids whose frequencies (around the gust frequency) and
//! phases come from the seed, normalised to |s| ≤ 1, and e₁, e₂ are unit vectors across the wind. A
//! spatially uniform field is enough for a flag: its travelling waves come from the cloth's own dynamics,
//! and evaluating a field per triangle would cost more than the rest of the wind model.

use glam::DVec3;

use crate::error::ParamError;
use crate::params::Wind;

const TERMS: usize = 4;

/// One seeded signal: `Σ a_k sin(2π f_k t + φ_k) / Σ a_k`.
#[derive(Clone, Copy, Debug)]
struct Signal {
    frequency: [f64; TERMS],
    phase: [f64; TERMS],
    amplitude: [f64; TERMS],
}

impl Signal {
    fn new(state: &mut u64, base_frequency: f64) -> Signal {
        let mut signal = Signal {
            frequency: [0.0; TERMS],
            phase: [0.0; TERMS],
            amplitude: [0.0; TERMS],
        };
        for k in 0..TERMS {
            // Octave-spaced frequencies with jitter, decreasing amplitudes: a crude 1/f gust spectrum.
            let octave = (1u32 << k) as f64;
            signal.frequency[k] = base_frequency * octave * (0.75 + 0.5 * unit_random(state));
            signal.phase[k] = std::f64::consts::TAU * unit_random(state);
            signal.amplitude[k] = 1.0 / octave;
        }
        signal
    }

    fn value(&self, time: f64) -> f64 {
        let mut sum = 0.0;
        let mut norm = 0.0;
        for k in 0..TERMS {
            sum += self.amplitude[k]
                * (std::f64::consts::TAU * self.frequency[k] * time + self.phase[k]).sin();
            norm += self.amplitude[k];
        }
        sum / norm
    }
}

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny seeded generator, enough for gust phases.
fn unit_random(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// The wind field of a run: [`Wind`] parameters plus the signals drawn from its seed.
#[derive(Clone, Debug)]
pub struct WindField {
    params: Wind,
    along: Signal,
    across: [Signal; 2],
}

impl WindField {
    /// The field of `params`, which must be valid (finite velocity, non-negative coefficients, a
    /// positive gust frequency: as [`SimParams::validate`](crate::SimParams::validate) checks them).
    pub fn new(params: &Wind) -> Result<WindField, ParamError> {
        params.validate()?;
        let mut state = params.seed;
        let along = Signal::new(&mut state, params.gust_frequency);
        let across = [
            Signal::new(&mut state, params.gust_frequency),
            Signal::new(&mut state, params.gust_frequency),
        ];
        Ok(WindField {
            params: *params,
            along,
            across,
        })
    }

    /// The wind parameters the field was drawn from.
    pub fn params(&self) -> &Wind {
        &self.params
    }

    /// Air velocity at time `time` (s), m/s.
    pub fn air_velocity(&self, time: f64) -> DVec3 {
        let mean = self.params.velocity;
        let speed = mean.length();
        if speed == 0.0 {
            return DVec3::ZERO;
        }
        let direction = mean / speed;
        let (e1, e2) = direction.any_orthonormal_pair();
        let mut velocity = mean;
        if self.params.gust_strength != 0.0 {
            velocity += mean * (self.params.gust_strength * self.along.value(time));
        }
        if self.params.turbulence != 0.0 {
            let lateral = self.params.turbulence * speed;
            velocity +=
                lateral * (self.across[0].value(time) * e1 + self.across[1].value(time) * e2);
        }
        velocity
    }
}

/// Aerodynamic force on a flat triangle (N) moving with velocity `triangle_velocity` through air moving
/// with `air_velocity`, after the flat-plate model of Ling, Damodaran & Gay (1996):
///
/// - drag along the normal: `F_D = ½ ρ C_D A |u| (u·n) n`, magnitude `½ ρ C_D A |u|² cos θ`;
/// - lift across the flow: `F_L = ½ ρ C_L A |u| (u·n) (n − (n·û) û)`, magnitude `½ ρ C_L A |u|² cos θ sin θ`;
///
/// with `u` the air velocity relative to the triangle, `n` its unit normal and θ the angle between
/// them. Both terms contain `n` twice, so the force does not depend on the triangle's winding. A
/// degenerate triangle or air at rest relative to it feels no force.
///
/// Written without early returns (the degenerate cases are selected at the end), so that the row-wise
/// wind pass over a grid vectorises.
#[inline]
pub fn aerodynamic_force(
    params: &Wind,
    area_normal: DVec3,
    triangle_velocity: DVec3,
    air_velocity: DVec3,
) -> DVec3 {
    scaled_aerodynamic_force(params, area_normal, triangle_velocity, air_velocity, 1.0)
}

/// `factor` × [`aerodynamic_force`], the factor folded into one product.
///
/// With the area normal `N` (`|N| = 2A`, `n = N/|N|`) and `s = |u|`, the pressure term is
/// `½ ρ A s (u·n) = ¼ ρ s (u·N)`, and the two terms together are
/// `F_D + F_L = ¼ ρ (u·N) / (|N| s) · ((C_D + C_L) s² N − C_L (u·N) u)`: one square root and one division
/// instead of two of each (`|N|`, `|u|`, `n` and `û`), and about half the arithmetic; the wind pass, two
/// of these per grid cell, had been a fifth of the default flag's frame (`perf record -e cpu-clock` of
/// `fingerprint time 64x46 1 600`). Tested against the form above to 10⁻¹³ and against the two
/// magnitudes and directions (`tests` below).
#[inline(always)]
pub(crate) fn scaled_aerodynamic_force(
    params: &Wind,
    area_normal: DVec3,
    triangle_velocity: DVec3,
    air_velocity: DVec3,
    factor: f64,
) -> DVec3 {
    let relative = air_velocity - triangle_velocity;
    let flux = relative.dot(area_normal);
    let speed_squared = relative.length_squared();
    let area_normal_squared = area_normal.length_squared();
    // |N|² s² is zero exactly when the triangle is degenerate or the air is at rest relative to it.
    let both_squared = area_normal_squared * speed_squared;
    let scale = factor * 0.25 * params.air_density * flux / both_squared.sqrt();
    let along_normal = (params.drag_coefficient + params.lift_coefficient) * speed_squared;
    let along_flow = params.lift_coefficient * flux;
    let force = scale * (along_normal * area_normal - along_flow * relative);
    if both_squared == 0.0 {
        DVec3::ZERO
    } else {
        force
    }
}

/// The share of triangle `[a, b, c]`'s aerodynamic force (N) that each of its corners receives: a third
/// of [`aerodynamic_force`] on the triangle moving with its corners' mean velocity.
#[inline(always)]
pub(crate) fn corner_share_of_triangle_force(
    params: &Wind,
    [a, b, c]: [DVec3; 3],
    [velocity_a, velocity_b, velocity_c]: [DVec3; 3],
    air_velocity: DVec3,
) -> DVec3 {
    // Multiplied by a third rather than divided by 3, and the share's third folded into the force's
    // scale: fewer operations in the wind pass, which they bound.
    const THIRD: f64 = 1.0 / 3.0;
    let area_normal = (b - a).cross(c - a);
    let velocity = (velocity_a + velocity_b + velocity_c) * THIRD;
    scaled_aerodynamic_force(params, area_normal, velocity, air_velocity, THIRD)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The flat-plate force as the doc of [`aerodynamic_force`] writes it, unit vectors and all.
    fn textbook_force(params: &Wind, area_normal: DVec3, relative: DVec3) -> DVec3 {
        let twice_area = area_normal.length();
        let normal = area_normal / twice_area;
        let speed = relative.length();
        let flow = relative / speed;
        let pressure = 0.5 * params.air_density * (0.5 * twice_area) * speed * relative.dot(normal);
        let drag = params.drag_coefficient * pressure * normal;
        let lift = params.lift_coefficient * pressure * (normal - normal.dot(flow) * flow);
        drag + lift
    }

    /// Pseudo-random vectors with components in [−scale, scale).
    fn vectors(seed: u64, scale: f64) -> impl Iterator<Item = DVec3> {
        let mut state = seed;
        std::iter::repeat_with(move || {
            let mut unit = || {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
            };
            DVec3::new(unit(), unit(), unit()) * scale
        })
    }

    #[test]
    fn the_force_is_the_textbook_flat_plate_force() {
        let params = Wind::default();
        // Area normals of cloth cells (1 mm to 10 cm across) and of whole sheets, relative speeds from
        // 1 mm/s to 100 m/s.
        for (scale_n, scale_u) in [(1e-6, 1e-3), (3e-4, 5.0), (1e-2, 100.0), (2.0, 0.3)] {
            for (n, u) in vectors(1, scale_n).zip(vectors(2, scale_u)).take(2000) {
                let expected = textbook_force(&params, n, u);
                let got = aerodynamic_force(&params, n, DVec3::ZERO, u);
                // Each term is at most ½ ρ C A s² in magnitude: the error is measured against that.
                let bound = 0.5 * params.air_density * 0.5 * n.length() * u.length_squared();
                assert!(
                    (got - expected).length() <= 1e-13 * bound,
                    "N {n}, u {u}: {got} against {expected}"
                );
            }
        }
    }

    #[test]
    fn drag_and_lift_have_the_flat_plate_magnitudes_and_directions() {
        // A unit-area plate facing +z in a 10 m/s flow at angle θ from its normal, in the x–z plane.
        let area = 1.0;
        let normal = DVec3::Z;
        let speed = 10.0;
        for degrees in [0.0_f64, 10.0, 30.0, 45.0, 60.0, 80.0] {
            let theta = degrees.to_radians();
            let flow = DVec3::new(theta.sin(), 0.0, theta.cos());
            let drag_only = Wind {
                lift_coefficient: 0.0,
                ..Wind::default()
            };
            let lift_only = Wind {
                drag_coefficient: 0.0,
                ..Wind::default()
            };
            let force = |params: &Wind| {
                aerodynamic_force(params, 2.0 * area * normal, DVec3::ZERO, speed * flow)
            };
            let q = 0.5 * drag_only.air_density * area * speed * speed;
            // F_D = ½ ρ C_D A |u|² cos θ along n.
            let drag = force(&drag_only);
            let expected = q * drag_only.drag_coefficient * theta.cos() * normal;
            assert!(
                (drag - expected).length() <= 1e-12 * q,
                "{degrees}°: {drag}"
            );
            // F_L = ½ ρ C_L A |u|² cos θ sin θ, across the flow.
            let lift = force(&lift_only);
            let magnitude = q * lift_only.lift_coefficient * theta.cos() * theta.sin();
            assert!(
                (lift.length() - magnitude).abs() <= 1e-12 * q,
                "{degrees}°: {lift}"
            );
            assert!(
                lift.dot(flow).abs() <= 1e-12 * q,
                "{degrees}°: lift along the flow"
            );
            // Either winding of the triangle: the same force.
            let flipped = aerodynamic_force(&drag_only, -2.0 * normal, DVec3::ZERO, speed * flow);
            assert_eq!(flipped, drag);
        }
    }

    #[test]
    fn a_degenerate_triangle_or_still_air_feels_nothing() {
        let params = Wind::default();
        let v = DVec3::new(1.0, 2.0, 3.0);
        assert_eq!(
            aerodynamic_force(&params, DVec3::ZERO, DVec3::ZERO, v),
            DVec3::ZERO
        );
        assert_eq!(aerodynamic_force(&params, DVec3::Z, v, v), DVec3::ZERO);
    }
}
