//! The per-fragment lit-side rule: the plain cases, the defined degenerate cases, and interpolated
//! normals crossing the terminator between two vertices whose normals were flipped differently.

mod common;

use glam::Vec3;
use sheer_normals::{Face, Light, LitSide, NormalsError, lit_side_cosines};

#[test]
fn front_lit_and_back_lit_pick_equation_7_and_8() {
    // Light above the sheet (+Z side), eye above: eq. (7); eye below: eq. (8) with μ := −μ.
    let to_light = Vec3::new(0.0, 0.6, 0.8);
    let above = lit_side_cosines(Vec3::Z, to_light, Vec3::new(0.8, 0.0, 0.6)).unwrap();
    assert_eq!(
        above,
        LitSide {
            mu0: 0.8,
            mu: 0.6,
            face: Face::Lit
        }
    );
    let below = lit_side_cosines(Vec3::Z, to_light, Vec3::new(0.8, 0.0, -0.6)).unwrap();
    assert_eq!(
        below,
        LitSide {
            mu0: 0.8,
            mu: 0.6,
            face: Face::Far
        }
    );
    // A normal handed in with the wrong sign, or unnormalised, changes nothing.
    assert_eq!(
        lit_side_cosines(-3.0 * Vec3::Z, 5.0 * to_light, Vec3::new(0.8, 0.0, 0.6)).unwrap(),
        above
    );
}

#[test]
fn degenerate_vectors_are_defined_cases() {
    let grazing = LitSide {
        mu0: 0.0,
        mu: 0.0,
        face: Face::Lit,
    };
    // Zero interpolated normal (two opposite vertex normals, halfway).
    assert_eq!(
        lit_side_cosines(Vec3::ZERO, Vec3::Z, Vec3::Z).unwrap(),
        grazing
    );
    // Light exactly at the fragment: μ0 = 0, the normal is kept as given.
    assert_eq!(
        lit_side_cosines(Vec3::Z, Vec3::ZERO, -Vec3::Z).unwrap(),
        LitSide {
            mu0: 0.0,
            mu: 1.0,
            face: Face::Far
        }
    );
    // Eye exactly at the fragment, and an eye grazing the surface: μ = 0 on the lit side.
    assert_eq!(
        lit_side_cosines(Vec3::Z, Vec3::Z, Vec3::ZERO).unwrap(),
        LitSide {
            mu0: 1.0,
            mu: 0.0,
            face: Face::Lit
        }
    );
    assert_eq!(
        lit_side_cosines(-Vec3::Z, Vec3::Z, Vec3::X).unwrap(),
        LitSide {
            mu0: 1.0,
            mu: 0.0,
            face: Face::Lit
        }
    );
    // Light in the tangent plane: μ0 = 0, the given sign of the normal decides the eye's side.
    assert_eq!(
        lit_side_cosines(Vec3::Z, Vec3::X, Vec3::Z).unwrap(),
        LitSide {
            mu0: 0.0,
            mu: 1.0,
            face: Face::Lit
        }
    );
    // Tiny and huge inputs normalise without underflow or overflow.
    let tiny = lit_side_cosines(
        Vec3::new(0.0, 0.0, 1e-30),
        Vec3::new(0.0, 0.0, 1e-30),
        Vec3::new(0.0, 0.0, -1e30),
    )
    .unwrap();
    assert_eq!(
        tiny,
        LitSide {
            mu0: 1.0,
            mu: 1.0,
            face: Face::Far
        }
    );
}

#[test]
fn non_finite_input_is_a_typed_error() {
    for (normal, to_light, to_eye, what) in [
        (Vec3::NAN, Vec3::Z, Vec3::Z, "normal"),
        (
            Vec3::Z,
            Vec3::new(0.0, f32::INFINITY, 0.0),
            Vec3::Z,
            "to_light",
        ),
        (
            Vec3::Z,
            Vec3::Z,
            Vec3::new(f32::NEG_INFINITY, 0.0, 0.0),
            "to_eye",
        ),
    ] {
        assert_eq!(
            lit_side_cosines(normal, to_light, to_eye),
            Err(NormalsError::NonFiniteVector { what })
        );
    }
}

/// Distance from the origin to the segment from `a` to `b`.
fn segment_distance_to_origin(a: Vec3, b: Vec3) -> f32 {
    let direction = b - a;
    let t = if direction == Vec3::ZERO {
        0.0
    } else {
        (-a.dot(direction) / direction.length_squared()).clamp(0.0, 1.0)
    };
    (a + t * direction).length()
}

#[test]
fn interpolated_normals_crossing_the_terminator_keep_mu0_nonnegative_and_continuous() {
    // With a fixed light direction a convex combination of two normals with n · ω0′ > 0 keeps
    // n · ω0′ > 0, so interpolation crosses the terminator only where ω0′ varies along an edge: a
    // point light close to the surface. This coarse wavy sheet with a light 3 cm under it has such
    // edges (the test asserts that it does).
    let (positions, indices) = common::wavy_grid(6);
    let light_position = Vec3::new(0.70, 0.3855, -0.0265);
    let eye = Vec3::new(0.5, 0.5, 2.0);
    let normals = sheer_normals::vertex_normals_toward_light(
        &positions,
        &indices,
        &Light::Point {
            position: light_position,
        },
    )
    .unwrap();
    // Every vertex itself satisfies the rule.
    for (p, n) in positions.iter().zip(&normals) {
        assert!(n.dot(light_position - *p) >= 0.0);
    }

    let mut edges: Vec<(usize, usize)> = indices
        .chunks_exact(3)
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b) as usize, a.max(b) as usize))
        .collect();
    edges.sort_unstable();
    edges.dedup();

    let samples = 4_000;
    let dt = 1.0 / samples as f32;
    let mut terminator_edges = 0;
    for (a, b) in edges {
        let mut previous: Option<(LitSide, f32, f32, Vec3)> = None;
        let mut crossings = 0;
        for step in 0..=samples {
            let t = step as f32 * dt;
            let fragment = positions[a].lerp(positions[b], t);
            let normal = normals[a].lerp(normals[b], t);
            let side = lit_side_cosines(normal, light_position - fragment, eye - fragment).unwrap();
            // μ0, μ ∈ [0, 1] up to the rounding of a unit dot product (a few ε).
            assert!(side.mu0 >= 0.0 && side.mu0 <= 1.0 + 4.0 * f32::EPSILON);
            assert!(side.mu >= 0.0 && side.mu <= 1.0 + 4.0 * f32::EPSILON);
            let raw_light = normal.dot(light_position - fragment);
            let raw_eye = normal.dot(eye - fragment);
            if let Some((before, raw_light_before, raw_eye_before, normal_before)) = previous {
                // Lipschitz bound between neighbouring samples: the unit normal turns by at most
                // |Δn|/min|n| (min over the step, exact since n is linear in t), the unit light and
                // eye directions by at most |Δp|/distance, and a cosine of two unit vectors moves by
                // at most the sum of their turns. Doubled, plus 8ε, for f32 rounding.
                let turn_normal = (normal - normal_before).length()
                    / segment_distance_to_origin(normal_before, normal);
                let step_length = (positions[b] - positions[a]).length() * dt;
                let turn_light = step_length / (light_position - fragment).length();
                let turn_eye = step_length / (eye - fragment).length();
                let bound_mu0 = 2.0 * (turn_normal + turn_light) + 8.0 * f32::EPSILON;
                let bound_mu = 2.0 * (turn_normal + turn_eye) + 8.0 * f32::EPSILON;
                assert!(
                    (side.mu0 - before.mu0).abs() <= bound_mu0,
                    "edge {a}-{b} t {t}: mu0 {} -> {}",
                    before.mu0,
                    side.mu0
                );
                assert!(
                    (side.mu - before.mu).abs() <= bound_mu,
                    "edge {a}-{b} t {t}: mu {} -> {}",
                    before.mu,
                    side.mu
                );
                if (raw_light < 0.0) != (raw_light_before < 0.0) {
                    crossings += 1;
                    // At the terminator μ0 comes down to 0 from both sides (within one step), so
                    // eq. (4) and (5), both ∝ μ0 (and E ∝ μ0 by eq. 6), vanish there: the diffuse
                    // term is continuous although the equation used changes.
                    assert!(side.mu0.min(before.mu0) <= bound_mu0);
                    // The re-orientation flips the normal, so unless the eye itself crossed the
                    // tangent plane in the same step, the eye changes side: eq. (7) ↔ eq. (8).
                    if (raw_eye < 0.0) == (raw_eye_before < 0.0) {
                        assert_ne!(side.face, before.face);
                    }
                }
            }
            previous = Some((side, raw_light, raw_eye, normal));
        }
        // Both ends satisfy n · ω0′ ≥ 0, so an edge that dips below crosses back out.
        assert_eq!(crossings % 2, 0, "edge {a}-{b}");
        if crossings > 0 {
            terminator_edges += 1;
        }
    }
    assert!(
        terminator_edges >= 1,
        "the configuration no longer exercises the terminator"
    );
}

/// The rule in `f64` (CPU references): the same face as in `f32` and the cosines within `f32`'s
/// rounding of them, on the plain cases, a flipped normal, the defined degenerate cases and bad input.
#[test]
fn the_f64_rule_agrees_with_the_f32_rule() {
    use glam::DVec3;
    let cases = [
        (Vec3::Z, Vec3::new(0.0, 0.6, 0.8), Vec3::new(0.8, 0.0, 0.6)),
        (Vec3::Z, Vec3::new(0.0, 0.6, 0.8), Vec3::new(0.8, 0.0, -0.6)),
        (
            -3.0 * Vec3::Z,
            Vec3::new(0.1, -2.0, 0.3),
            Vec3::new(-1.0, 0.5, 4.0),
        ),
        (
            Vec3::new(0.3, -0.2, 0.9),
            Vec3::new(-1.0, 0.5, -0.2),
            Vec3::new(0.2, 0.1, -3.0),
        ),
        (Vec3::ZERO, Vec3::Z, Vec3::Z),
        (Vec3::Z, Vec3::ZERO, -Vec3::Z),
        (Vec3::Z, Vec3::Z, Vec3::ZERO),
    ];
    for (normal, to_light, to_eye) in cases {
        let single = lit_side_cosines(normal, to_light, to_eye).unwrap();
        let double =
            lit_side_cosines(normal.as_dvec3(), to_light.as_dvec3(), to_eye.as_dvec3()).unwrap();
        assert_eq!(single.face, double.face, "{normal} {to_light} {to_eye}");
        // A few f32 ulps: the f32 rule rounds each normalisation and dot product.
        for (f32_value, f64_value) in [(single.mu0, double.mu0), (single.mu, double.mu)] {
            assert!((f64::from(f32_value) - f64_value).abs() <= 4.0 * f64::from(f32::EPSILON));
        }
    }
    assert!(matches!(
        lit_side_cosines(DVec3::new(f64::NAN, 0.0, 1.0), DVec3::Z, DVec3::Z),
        Err(NormalsError::NonFiniteVector { what: "normal" })
    ));
}
