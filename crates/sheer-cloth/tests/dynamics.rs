//! Whole-cloth dynamics against closed-form physics: free fall, momentum conservation, a hanging sheet
//! at rest, and the transverse wave speed on a tensioned string.

mod common;

use common::{all_methods, mean_period, upward_zero_crossings};
use sheer_cloth::glam::DVec3;
use sheer_cloth::{
    ClothModel, GridSpec, Method, SimParams, Simulation, Spring, SpringKind, SpringParams, Wind,
};
use std::f64::consts::PI;

const G: f64 = 9.81;

fn small_grid() -> GridSpec {
    GridSpec {
        columns: 8,
        rows: 6,
        width: 0.7,
        height: 0.5,
        areal_density: 0.2,
        origin: DVec3::new(0.0, 2.0, 0.0),
    }
}

/// Gravity only, soft springs (1–10 N/m, so that even forward Euler stays tame over the test), no air.
fn quiet(method: Method) -> SimParams {
    SimParams {
        method,
        stretch: SpringParams::new(10.0, 0.001),
        shear: SpringParams::new(10.0, 0.001),
        bend: SpringParams::new(1.0, 0.0),
        gravity: DVec3::new(0.0, -G, 0.0),
        air_damping: 0.0,
        wind: Wind {
            velocity: DVec3::ZERO,
            ..Wind::default()
        },
        ..SimParams::default()
    }
}

#[test]
fn unstressed_cloth_falls_as_half_g_t_squared() {
    let frame = 1.0 / 60.0;
    for method in all_methods(10) {
        // Forward Euler amplifies rounding noise by exp(ω²ht/2) (ω up to 300 rad/s on the light
        // corner particles), so it needs h ≤ 2e-4 s to keep that below e^10 over one second.
        let method = match method {
            Method::ExplicitEuler { .. } => Method::ExplicitEuler { substeps: 100 },
            other => other,
        };
        let substeps = method.substeps();
        let h = frame / substeps as f64;
        let steps = 60 * substeps as usize;
        let mut sim =
            Simulation::new(ClothModel::grid(&small_grid()).unwrap(), quiet(method)).unwrap();
        for _ in 0..steps / substeps as usize {
            sim.step(frame)
                .unwrap_or_else(|e| panic!("{}: {e}", method.name()));
        }
        let t = steps as f64 * h;
        let drop = sim.rest_positions()[0].y - sim.positions()[0].y;
        // Each method's exact discrete answer for constant acceleration: velocity Verlet is exact;
        // symplectic Euler, backward Euler and the position-based methods (v first, then x) give
        // ½gh²n(n+1); forward Euler gives ½gh²n(n−1). All are within ½ g h t of ½ g t².
        let n = steps as f64;
        let discrete = match method {
            Method::Verlet { .. } => 0.5 * G * t * t,
            Method::ExplicitEuler { .. } => 0.5 * G * h * h * n * (n - 1.0),
            _ => 0.5 * G * h * h * n * (n + 1.0),
        };
        let tolerance = match method {
            // The CG solve stops at a relative residual of 1e-6, so Δv, and with it the drop, may err by
            // that fraction.
            Method::ImplicitEuler { .. } => 1e-6 * discrete,
            // Rounding: up to 1000 sub-steps, each rounding positions of a few metres (≈ 1e-15 m),
            // plus constraint corrections of rounding-sized violations.
            _ => 1e-10,
        };
        assert!(
            (drop - discrete).abs() < tolerance,
            "{}: fell {drop} m, discrete {discrete} m",
            method.name()
        );
        assert!((drop - 0.5 * G * t * t).abs() <= 0.5 * G * h * t + tolerance);
        // Uniform acceleration leaves every spring at rest length (up to the CG tolerance for the
        // implicit solve, which need not return an exactly uniform Δv).
        let strain_tolerance = match method {
            Method::ImplicitEuler { .. } => 1e-6,
            _ => 1e-12,
        };
        let strain = sim.max_strain(None).abs();
        assert!(
            strain < strain_tolerance,
            "{}: strain {strain}",
            method.name()
        );
    }
}

#[test]
fn momentum_is_conserved_without_external_forces() {
    let model = ClothModel::grid(&small_grid()).unwrap();
    let n = model.particle_count();
    // A stressed, moving state from a deterministic pseudo-random perturbation.
    let perturbed: Vec<DVec3> = model
        .positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let s = (i as f64 * 12.9898).sin() * 43758.5453;
            *p + 0.01 * DVec3::new(s.fract(), (s * 1.7).fract(), (s * 2.3).fract())
        })
        .collect();
    let velocities: Vec<DVec3> = (0..n)
        .map(|i| {
            let s = (i as f64 * 78.233).sin() * 12345.678;
            DVec3::new(s.fract(), (s * 1.3).fract(), (s * 3.1).fract())
        })
        .collect();
    for method in Method::all_with_substeps(10, 10) {
        let method = match method {
            Method::ImplicitEuler { substeps, .. } => Method::ImplicitEuler {
                substeps,
                cg_max_iterations: 500,
                cg_tolerance: 1e-13,
            },
            Method::ExplicitEuler { .. } => Method::ExplicitEuler { substeps: 100 },
            other => other,
        };
        let mut params = quiet(method);
        params.gravity = DVec3::ZERO;
        let mut sim = Simulation::new(model.clone(), params).unwrap();
        sim.set_state(&perturbed, &velocities).unwrap();
        let p0 = sim.momentum();
        for _ in 0..30 {
            sim.step(1.0 / 60.0).unwrap();
        }
        let scale = sim.masses().iter().sum::<f64>(); // kg × 1 m/s
        // Internal forces come in equal and opposite pairs, and position-based corrections are
        // weighted by inverse mass, so momentum changes only by rounding (1e-16 per operation);
        // the implicit solve leaves a CG residual of at most 1e-13 relative.
        let drift = (sim.momentum() - p0).length() / scale;
        assert!(drift < 1e-11, "{}: momentum drift {drift}", method.name());
    }
}

#[test]
fn hanging_cloth_settles_and_stays_at_rest() {
    let spec = GridSpec {
        columns: 16,
        rows: 11,
        ..GridSpec::default()
    };
    for method in [
        Method::default(),
        Method::ImplicitEuler {
            substeps: 1,
            cg_max_iterations: 200,
            cg_tolerance: 1e-8,
        },
    ] {
        let model = ClothModel::grid(&spec)
            .unwrap()
            .with_top_edge_pinned()
            .unwrap();
        // The default fabric springs, gravity and some air damping.
        let mut params = SimParams {
            air_damping: 0.5,
            ..quiet(method)
        };
        let defaults = SimParams::default();
        (params.stretch, params.shear, params.bend) =
            (defaults.stretch, defaults.shear, defaults.bend);
        let mut sim = Simulation::new(model, params).unwrap();
        let h = 1.0 / 60.0;
        for _ in 0..600 {
            sim.step(h).unwrap();
        }
        let settled = sim.positions().to_vec();
        let mut max_speed = 0.0f64;
        for _ in 0..120 {
            sim.step(h).unwrap();
            max_speed = sim
                .velocities()
                .iter()
                .map(|v| v.length())
                .fold(max_speed, f64::max);
        }
        let creep = sim
            .positions()
            .iter()
            .zip(&settled)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f64::max);
        // At rest: no particle moves faster than 0.1 mm/s (the sag itself is centimetres) and none
        // creeps more than 10 µm over two further seconds.
        assert!(
            max_speed < 1e-4,
            "{}: jitter {max_speed} m/s",
            method.name()
        );
        assert!(creep < 1e-5, "{}: creep {creep} m", method.name());
        // It hangs where statics puts it: the springs (1000 N/m, ten in series per column carrying up
        // to 11 mg of 2.5 g each) stretch about a millimetre; with long-range attachments (the
        // position-based default) the tethers hold every particle within its rest distance of the
        // pinned edge, so it cannot sag below rest at all.
        let bottom = spec.columns * (spec.rows - 1);
        let sag = sim.rest_positions()[bottom].y - sim.positions()[bottom].y;
        match method {
            Method::ImplicitEuler { .. } => assert!(sag > 1e-4 && sag < 1e-2, "sag {sag}"),
            _ => assert!(sag.abs() < 1e-6, "sag {sag}"),
        }
    }
}

#[test]
fn transverse_waves_travel_at_sqrt_tension_over_linear_density() {
    // A string of beads: N particles of mass m at spacing a, springs of rest length 0.9a and stiffness
    // k, so the tension is T = 0.1 k a; both ends pinned.
    let beads = 41;
    let (spacing, mass, stiffness) = (0.01, 1e-3, 100.0); // m, kg, N/m
    let tension = stiffness * 0.1 * spacing; // N
    let density = mass / spacing; // kg/m
    let length = (beads - 1) as f64 * spacing;
    let amplitude = 1e-5; // m: keeps the tension change (≈ 5 (Δy/a)²) below 1e-6 relative
    let positions: Vec<DVec3> = (0..beads)
        .map(|i| {
            let x = i as f64 * spacing;
            DVec3::new(x, amplitude * (PI * x / length).sin(), 0.0)
        })
        .collect();
    let springs: Vec<Spring> = (0..beads - 1)
        .map(|i| Spring {
            a: i as u32,
            b: i as u32 + 1,
            kind: SpringKind::Stretch,
            rest_length: 0.9 * spacing,
        })
        .collect();
    let mut model =
        ClothModel::from_particles_and_springs(&positions, &vec![mass; beads], &springs).unwrap();
    model.pin(&[0, beads - 1]).unwrap();
    let params = SimParams::springs_only(
        Method::Verlet { substeps: 1 },
        SpringParams::new(stiffness, 0.0),
    );
    let mut sim = Simulation::new(model, params).unwrap();
    let h = 1e-4; // ω_max h = 2 sqrt(k/m) h = 0.063: far inside the stability limit
    let middle = beads / 2;
    let (mut times, mut signal) = (Vec::new(), Vec::new());
    for _ in 0..40_000 {
        sim.step(h).unwrap();
        times.push(sim.time());
        signal.push(sim.positions()[middle].y);
    }
    let period = mean_period(&upward_zero_crossings(&times, &signal));
    let measured_omega = 2.0 * PI / period;
    // The bead string's dispersion relation: ω = 2 sqrt(T/(m a)) sin(κa/2), κ = π/L.
    let discrete_omega =
        2.0 * (tension / (mass * spacing)).sqrt() * (PI * spacing / (2.0 * length)).sin();
    // Continuum: ω = c κ with c = sqrt(T/ρ).
    let wave_speed = (tension / density).sqrt();
    let continuum_omega = wave_speed * PI / length;
    // Verlet's own phase error at ωh = 8e-4 is (ωh)²/24 ≈ 3e-8, crossing interpolation less still.
    assert!(
        (measured_omega / discrete_omega - 1.0).abs() < 1e-5,
        "ω = {measured_omega}, bead-string prediction {discrete_omega}"
    );
    let dispersion = (discrete_omega / continuum_omega - 1.0).abs(); // (πa/2L)²/6 ≈ 1.3e-4
    let measured_speed = measured_omega * length / PI;
    assert!(
        (measured_speed / wave_speed - 1.0).abs() <= dispersion + 1e-5,
        "wave speed {measured_speed} m/s vs sqrt(T/ρ) = {wave_speed} m/s (dispersion {dispersion})"
    );
}
