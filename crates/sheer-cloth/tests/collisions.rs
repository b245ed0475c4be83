//! Contacts: the flag does not pass through itself, a sheet rests on a sphere and on itself, the
//! pole's capsule holds the flag off, bad values are refused, and the bits do not depend on the
//! thread count. Intersections are counted by `intersecting_triangle_pairs`, which shares no code
//! with the solver's contacts.

use sheer_cloth::glam::{DQuat, DVec3};
use sheer_cloth::{
    ClothModel, Collider, Collisions, GridSpec, Method, SimParams, Simulation,
    intersecting_triangle_pairs,
};

const FRAME: f64 = 1.0 / 60.0;

/// The flag's pole, as the app hangs it.
fn pole() -> Collider {
    Collider::flag_pole(&GridSpec::default(), Collisions::default().thickness)
}

/// The default waving flag with self-collision and the pole.
fn colliding_flag() -> Simulation {
    let flag = ClothModel::grid(&GridSpec::default())
        .and_then(|m| m.with_hoist_pinned())
        .expect("default flag");
    let mut params = SimParams::waving_flag();
    params.collisions = Collisions {
        self_collision: true,
        colliders: vec![pole()],
        ..Collisions::default()
    };
    Simulation::new(flag, params).expect("valid flag")
}

/// The frames among `frames` at 60 Hz in which the flag passes through itself, and the most pairs in one.
fn frames_passing_through(sim: &mut Simulation, frames: usize) -> (usize, usize) {
    let triangles = sim.triangles().to_vec();
    let (mut bad_frames, mut most) = (0, 0);
    for _ in 0..frames {
        sim.step(FRAME).expect("stable");
        let pairs = intersecting_triangle_pairs(sim.positions(), &triangles);
        bad_frames += usize::from(pairs > 0);
        most = most.max(pairs);
    }
    (bad_frames, most)
}

#[test]
fn without_contacts_the_default_flag_passes_through_itself() {
    // The control: the check sees what the contacts remove.
    let flag = ClothModel::grid(&GridSpec::default())
        .and_then(|m| m.with_hoist_pinned())
        .expect("default flag");
    let mut sim = Simulation::new(flag, SimParams::waving_flag()).expect("valid flag");
    let (bad_frames, most) = frames_passing_through(&mut sim, 600);
    assert!(
        bad_frames > 0 && most > 0,
        "{bad_frames} frames, {most} pairs"
    );
}

#[test]
fn the_default_flag_never_passes_through_itself_in_sixty_seconds() {
    let mut sim = colliding_flag();
    // On every thread the pool has (the same bits as on one: tested below), to keep the test short.
    let mut params = sim.params().clone();
    params.parallel_min_particles = 0;
    sim.set_params(params).expect("valid");
    let triangles = sim.triangles().to_vec();
    for frame in 0..3600 {
        sim.step(FRAME).expect("stable");
        let pairs = intersecting_triangle_pairs(sim.positions(), &triangles);
        assert_eq!(pairs, 0, "frame {frame}: {pairs} intersecting pairs");
    }
}

/// A `n × n` sheet of side `side` (m), horizontal (in the x–z plane), centred above the origin at
/// `height` (m), no pins.
fn horizontal_sheet(n: usize, side: f64, height: f64) -> ClothModel {
    let mut model = ClothModel::grid(&GridSpec {
        columns: n,
        rows: n,
        width: side,
        height: side,
        areal_density: 0.2,
        origin: DVec3::new(-side / 2.0, side / 2.0, 0.0),
    })
    .expect("sheet");
    let lay_flat = DQuat::from_rotation_x(-std::f64::consts::FRAC_PI_2);
    for x in &mut model.positions {
        *x = lay_flat * *x + DVec3::new(0.0, height, 0.0);
    }
    model
}

fn still_air(collisions: Collisions) -> SimParams {
    let mut params = SimParams::waving_flag();
    params.wind.velocity = DVec3::ZERO;
    params.wind.gust_strength = 0.0;
    params.wind.turbulence = 0.0;
    params.collisions = collisions;
    params
}

#[test]
fn a_sheet_dropped_on_a_sphere_rests_on_it() {
    let (center, radius) = (DVec3::ZERO, 0.2);
    let collisions = Collisions {
        self_collision: true,
        colliders: vec![Collider::Sphere { center, radius }],
        ..Collisions::default()
    };
    let gap = collisions.thickness / 2.0;
    let mut sim = Simulation::new(horizontal_sheet(30, 0.8, 0.3), still_air(collisions))
        .expect("valid sheet");
    let triangles = sim.triangles().to_vec();
    for frame in 0..180 {
        sim.step(FRAME).expect("stable");
        // Contacts are projected last in every sub-step: every particle keeps the gap, to rounding.
        let nearest = sim
            .positions()
            .iter()
            .map(|x| x.distance(center))
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest >= (radius + gap) * (1.0 - 1e-12),
            "frame {frame}: {nearest}"
        );
        assert_eq!(intersecting_triangle_pairs(sim.positions(), &triangles), 0);
    }
    // At rest on top: the sheet's centre particle sits on the sphere, and it no longer falls.
    let centre = sim.positions()[15 * 30 + 15];
    assert!(centre.y > radius && centre.y < radius + 0.02, "{centre}");
    let speed = sim
        .velocities()
        .iter()
        .map(|v| v.length())
        .fold(0.0, f64::max);
    assert!(speed < 0.5, "{speed} m/s");
}

#[test]
fn a_sheet_folded_onto_itself_keeps_its_layers_apart() {
    // A strip on the ground folded in two: its right half turned over a half-circle of radius 1 cm
    // and held 2 cm above its left half, then let fall onto it.
    let collisions = Collisions {
        self_collision: true,
        colliders: vec![Collider::Plane {
            point: DVec3::ZERO,
            normal: DVec3::Y,
        }],
        ..Collisions::default()
    };
    let thickness = collisions.thickness;
    let (n, side, radius) = (24, 0.6, 0.01);
    let model = horizontal_sheet(n, side, thickness / 2.0);
    // Without bending springs, so that the fold stays folded.
    let mut params = still_air(collisions);
    params.bend = sheer_cloth::SpringParams::disabled();
    let mut sim = Simulation::new(model, params).expect("valid strip");
    let spacing = side / (n - 1) as f64;
    let turn = std::f64::consts::PI * radius;
    let folded: Vec<DVec3> = sim
        .positions()
        .iter()
        .map(|x| {
            let (s, ground) = (x.x, thickness / 2.0);
            if s <= 0.0 {
                *x
            } else if s < turn {
                let angle = s / radius;
                DVec3::new(
                    radius * angle.sin(),
                    ground + radius * (1.0 - angle.cos()),
                    x.z,
                )
            } else {
                DVec3::new(-(s - turn), ground + 2.0 * radius, x.z)
            }
        })
        .collect();
    let is_top: Vec<bool> = sim
        .positions()
        .iter()
        .map(|x| x.x > turn + 3.0 * spacing)
        .collect();
    let still = vec![DVec3::ZERO; folded.len()];
    sim.set_state(&folded, &still).expect("finite");
    let triangles = sim.triangles().to_vec();
    let mut lowest = f64::INFINITY;
    for frame in 0..120 {
        sim.step(FRAME).expect("stable");
        let pairs = intersecting_triangle_pairs(sim.positions(), &triangles);
        assert_eq!(pairs, 0, "frame {frame}");
        let top_height = sim
            .positions()
            .iter()
            .zip(&is_top)
            .filter(|(_, top)| **top)
            .map(|(x, _)| x.y)
            .fold(f64::INFINITY, f64::min);
        lowest = lowest.min(top_height);
    }
    let speed = sim
        .velocities()
        .iter()
        .map(|v| v.length())
        .fold(0.0, f64::max);
    println!(
        "lowest top-layer particle {lowest} m (bottom layer at {} m), speed {speed}",
        thickness / 2.0
    );
    // The top layer came down (it started 2 cm up) and lies on the bottom one: a layer's thickness
    // above it, less at most half of it.
    assert!(lowest < 2.0 * radius, "{lowest}");
    assert!(lowest >= thickness / 2.0 + thickness / 2.0, "{lowest} m");
}

#[test]
fn contacts_give_the_same_bits_on_one_thread_and_on_two() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let mut sim = colliding_flag();
            let mut params = sim.params().clone();
            params.parallel_min_particles = 0;
            sim.set_params(params).expect("valid");
            for _ in 0..120 {
                sim.step(FRAME).expect("stable");
            }
            sim.positions()
                .iter()
                .chain(sim.velocities())
                .flat_map(|v| v.to_array().map(f64::to_bits))
                .collect::<Vec<u64>>()
        })
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn bad_contact_settings_are_refused_naming_the_key() {
    let flag = || {
        ClothModel::grid(&GridSpec::default())
            .and_then(|m| m.with_hoist_pinned())
            .expect("default flag")
    };
    let refused = |collisions: Collisions, method: Method| {
        let mut params = SimParams::waving_flag();
        params.method = method;
        params.collisions = collisions;
        match Simulation::new(flag(), params) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("accepted"),
        }
    };
    let xpbd = Method::default();
    let negative = Collisions {
        self_collision: true,
        thickness: -0.001,
        ..Collisions::default()
    };
    assert!(refused(negative, xpbd).contains("collisions.thickness"));
    let nan_ball = Collisions {
        colliders: vec![Collider::Sphere {
            center: DVec3::ZERO,
            radius: f64::NAN,
        }],
        ..Collisions::default()
    };
    assert!(refused(nan_ball, xpbd).contains("collisions.colliders.radius"));
    let flat_plane = Collisions {
        colliders: vec![Collider::Plane {
            point: DVec3::ZERO,
            normal: DVec3::ZERO,
        }],
        ..Collisions::default()
    };
    assert!(refused(flat_plane, xpbd).contains("collisions.colliders.normal"));
    let on = Collisions {
        self_collision: true,
        ..Collisions::default()
    };
    let message = refused(on, Method::Verlet { substeps: 200 });
    assert!(message.contains("position-based"), "{message}");
}
