//! Property tests over random meshes and lights: unit, finite normals obeying the μ0 ≥ 0 rule,
//! independent of winding; the per-fragment rule always yields cosines in [0, 1].

use glam::Vec3;
use proptest::prelude::*;
use sheer_normals::{Face, Light, NormalUpdater, lit_side_cosines};

/// Unit length to within the rounding of one square root and one division per component (a few
/// ulps of 1): 4ε.
const UNIT_TOLERANCE: f32 = 4.0 * f32::EPSILON;

/// The documented tie tolerance of the orientation test: n · ω0′ may be below zero only by the
/// rounding error of that dot product, 4ε·Σ|n_i||ω_i| (see `NormalUpdater::update`).
const TIE_TOLERANCE: f32 = 4.0 * f32::EPSILON;

/// Coordinates either on a coarse lattice (so coincident, collinear and coplanar vertices are
/// common) or anywhere in a 4 m box.
fn coordinate() -> impl Strategy<Value = f32> {
    prop_oneof![(-2i32..=2).prop_map(|k| k as f32 * 0.5), -2.0f32..2.0]
}

fn position() -> impl Strategy<Value = Vec3> {
    (coordinate(), coordinate(), coordinate()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Random mesh: 1–30 vertices, 1–40 triangles with arbitrary (possibly repeated) indices.
fn mesh() -> impl Strategy<Value = (Vec<Vec3>, Vec<u32>)> {
    prop::collection::vec(position(), 1..30).prop_flat_map(|positions| {
        let n = positions.len() as u32;
        let triangles = prop::collection::vec((0..n, 0..n, 0..n), 1..40).prop_map(|t| {
            t.into_iter()
                .flat_map(|(a, b, c)| [a, b, c])
                .collect::<Vec<u32>>()
        });
        (Just(positions), triangles)
    })
}

fn light() -> impl Strategy<Value = Light> {
    prop_oneof![
        position().prop_map(|p| Light::Point { position: p * 1.5 }),
        position()
            .prop_filter("non-zero direction", |d| *d != Vec3::ZERO)
            .prop_map(|d| Light::Directional {
                direction_to_light: d
            }),
    ]
}

fn to_light(light: &Light, position: Vec3) -> Vec3 {
    match *light {
        Light::Point { position: light } => light - position,
        Light::Directional { direction_to_light } => direction_to_light,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2_000))]

    #[test]
    fn normals_are_unit_finite_and_face_the_light((positions, indices) in mesh(), light in light()) {
        let mut updater = NormalUpdater::new(positions.len(), &indices).unwrap();
        let mut normals = vec![Vec3::NAN; positions.len()];
        updater.update(&positions, &light, &mut normals).unwrap();
        for (p, n) in positions.iter().zip(&normals) {
            prop_assert!(n.is_finite());
            prop_assert!((n.length() - 1.0).abs() <= UNIT_TOLERANCE, "|n| = {}", n.length());
            // The direction the crate itself uses: normalised for a directional light.
            let l = match light {
                Light::Directional { direction_to_light } => direction_to_light.normalize(),
                Light::Point { .. } => to_light(&light, *p),
            };
            let mu0 = n.dot(l);
            prop_assert!(mu0 >= -TIE_TOLERANCE * n.abs().dot(l.abs()), "n {n} l {l} mu0 {mu0}");
        }

        // Winding invariance: reversing every triangle changes no bit.
        let reversed: Vec<u32> = indices.chunks_exact(3).flat_map(|t| [t[2], t[1], t[0]]).collect();
        let mut reversed_normals = vec![Vec3::NAN; positions.len()];
        NormalUpdater::new(positions.len(), &reversed).unwrap().update(&positions, &light, &mut reversed_normals).unwrap();
        for (a, b) in normals.iter().zip(&reversed_normals) {
            prop_assert_eq!(a.to_array().map(f32::to_bits), b.to_array().map(f32::to_bits));
        }
    }

    #[test]
    fn fragment_cosines_are_in_range(normal in position(), to_light in position(), to_eye in position()) {
        let side = lit_side_cosines(normal, to_light, to_eye).unwrap();
        prop_assert!(side.mu0 >= 0.0 && side.mu0 <= 1.0 + UNIT_TOLERANCE);
        prop_assert!(side.mu >= 0.0 && side.mu <= 1.0 + UNIT_TOLERANCE);
        // The rule itself: μ0 = |n̂ · l̂|, μ = |n̂ · ê|, eye on the lit side iff the eye and the light
        // are on the same side of the tangent plane (ties to the lit side).
        if let (Some(n), Some(l), Some(e)) = (normal.try_normalize(), to_light.try_normalize(), to_eye.try_normalize()) {
            // Different normalisation arithmetic from the crate's: allow a few ε.
            prop_assert!((side.mu0 - n.dot(l).abs()).abs() <= 8.0 * f32::EPSILON);
            prop_assert!((side.mu - n.dot(e).abs()).abs() <= 8.0 * f32::EPSILON);
            let (nl, ne) = (n.dot(l), n.dot(e));
            if nl.abs() > 8.0 * f32::EPSILON && ne.abs() > 8.0 * f32::EPSILON {
                prop_assert_eq!(side.face == Face::Lit, (nl > 0.0) == (ne > 0.0));
            }
        }
    }
}
