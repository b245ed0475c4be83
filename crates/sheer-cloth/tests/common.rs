//! Shared builders for the simulation tests.
#![allow(dead_code)]

use sheer_cloth::glam::DVec3;
use sheer_cloth::{ClothModel, Method, SimParams, Simulation, Spring, SpringKind, SpringParams};

/// A unit-mass particle on a spring of rest length 1 m whose other end is pinned at the origin,
/// displaced by `amplitude` along the spring: a 1-D harmonic oscillator of angular frequency
/// `sqrt(stiffness / mass)`.
pub fn oscillator(
    method: Method,
    mass: f64,
    stiffness: f64,
    damping: f64,
    amplitude: f64,
) -> Simulation {
    let positions = [DVec3::ZERO, DVec3::new(1.0 + amplitude, 0.0, 0.0)];
    let springs = [Spring {
        a: 0,
        b: 1,
        kind: SpringKind::Stretch,
        rest_length: 1.0,
    }];
    let mut model = ClothModel::from_particles_and_springs(&positions, &[mass, mass], &springs)
        .expect("valid oscillator");
    model.pin(&[0]).expect("pin in range");
    let params = SimParams::springs_only(method, SpringParams::new(stiffness, damping));
    Simulation::new(model, params).expect("valid simulation")
}

/// Displacement of the oscillator's free particle from rest, m.
pub fn displacement(sim: &Simulation) -> f64 {
    sim.positions()[1].x - 1.0
}

/// Times (s) at which `signal` crosses zero going upward, linearly interpolated between samples.
pub fn upward_zero_crossings(times: &[f64], signal: &[f64]) -> Vec<f64> {
    let mut crossings = Vec::new();
    for k in 1..signal.len() {
        if signal[k - 1] < 0.0 && signal[k] >= 0.0 {
            let fraction = -signal[k - 1] / (signal[k] - signal[k - 1]);
            crossings.push(times[k - 1] + fraction * (times[k] - times[k - 1]));
        }
    }
    crossings
}

/// Mean period from upward zero crossings (first to last).
pub fn mean_period(crossings: &[f64]) -> f64 {
    (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64
}

/// Every force-based and position-based method at the given sub-step count.
pub fn all_methods(substeps: u32) -> Vec<Method> {
    Method::all_with_substeps(substeps, 10).to_vec()
}
