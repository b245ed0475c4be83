//! Wind: a deterministic gust signal and the flat-plate aerodynamic force on one triangle.
//!
//! The air velocity is uniform in space and varies in time: `u(t) = U (1 + g s₁(t)) + T |U| (s₂(t) e₁ +
//! s₃(t) e₂)`, where `s_k` are sums of four sinusoids whose frequencies (around the gust frequency) and
//! phases come from the seed, normalised to |s| ≤ 1, and e₁, e₂ are unit vectors across the wind. A
//! spatially uniform field is enough for a flag: its travelling waves come from the cloth's own dynamics,
//! and evaluating a field per triangle would cost more than the rest of the wind model.

use glam::DVec3;

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
    pub fn new(params: &Wind) -> WindField {
        let mut state = params.seed;
        let along = Signal::new(&mut state, params.gust_frequency);
        let across = [
            Signal::new(&mut state, params.gust_frequency),
            Signal::new(&mut state, params.gust_frequency),
        ];
        WindField {
            params: *params,
            along,
            across,
        }
    }

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
/// wind pass over a grid vectorises; the arithmetic of the regular case is the same either way.
#[inline]
pub fn aerodynamic_force(
    params: &Wind,
    area_normal: DVec3,
    triangle_velocity: DVec3,
    air_velocity: DVec3,
) -> DVec3 {
    let twice_area = area_normal.length();
    let normal = area_normal * (1.0 / twice_area);
    let area = 0.5 * twice_area;
    let relative = air_velocity - triangle_velocity;
    let speed = relative.length();
    let normal_component = relative.dot(normal);
    let pressure = 0.5 * params.air_density * area * speed * normal_component;
    let drag = params.drag_coefficient * pressure * normal;
    let flow = relative * (1.0 / speed);
    let across_flow = normal - normal.dot(flow) * flow;
    let lift = params.lift_coefficient * pressure * across_flow;
    if twice_area == 0.0 || speed == 0.0 {
        DVec3::ZERO
    } else {
        drag + lift
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
    // Multiplied by a third rather than divided by 3: six fewer divisions per triangle, which bound the
    // wind pass.
    const THIRD: f64 = 1.0 / 3.0;
    let area_normal = (b - a).cross(c - a);
    let velocity = (velocity_a + velocity_b + velocity_c) * THIRD;
    aerodynamic_force(params, area_normal, velocity, air_velocity) * THIRD
}
