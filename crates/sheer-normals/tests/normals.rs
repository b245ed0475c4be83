//! Behaviour of the vertex-normal update: exact plane normals, convergence on a refined sphere,
//! flipping with the light, winding invariance, degenerate input, the μ0 = 0 tie-break, errors.

mod common;

use common::{bits, flat_grid, icosphere, rewind, wavy_grid};
use glam::{DVec3, Vec3};
use sheer_normals::{
    Execution, Light, MAX_COORDINATE, NormalOptions, NormalUpdater, NormalsError, Weighting,
    vertex_normals_toward_light,
};

const WEIGHTINGS: [Weighting; 2] = [Weighting::Area, Weighting::Angle];

fn normals_with(
    positions: &[Vec3],
    indices: &[u32],
    light: &Light,
    weighting: Weighting,
) -> Vec<Vec3> {
    let options = NormalOptions {
        weighting,
        execution: Execution::Serial,
    };
    let mut updater = NormalUpdater::with_options(positions.len(), indices, options).unwrap();
    let mut normals = vec![Vec3::NAN; positions.len()];
    updater.update(positions, light, &mut normals).unwrap();
    normals
}

/// Angle between two directions, radians, accurate near 0 (atan2 form, in f64).
fn angle_between(a: Vec3, b: DVec3) -> f64 {
    let a = a.as_dvec3();
    a.cross(b).length().atan2(a.dot(b))
}

#[test]
fn flat_sheet_gives_the_exact_plane_normal_toward_a_light_on_either_side() {
    // Mixed windings on purpose (every third cell reversed).
    let (positions, indices) = flat_grid(9, 0.125, |cell| cell % 3 == 0);
    for weighting in WEIGHTINGS {
        for (light, expected) in [
            (
                Light::Point {
                    position: Vec3::new(0.4, 0.7, 0.3),
                },
                Vec3::Z,
            ),
            (
                Light::Point {
                    position: Vec3::new(5.0, -3.0, -0.01),
                },
                -Vec3::Z,
            ),
            (
                Light::Directional {
                    direction_to_light: Vec3::new(0.2, 0.1, 1.0),
                },
                Vec3::Z,
            ),
            (
                Light::Directional {
                    direction_to_light: Vec3::new(-3.0, 0.0, -0.5),
                },
                -Vec3::Z,
            ),
        ] {
            // In-plane edges have zero z, so every cross product is exactly (0, 0, c): the result
            // is exact, and is compared exactly.
            for normal in normals_with(&positions, &indices, &light, weighting) {
                assert_eq!(normal, expected, "{weighting:?} {light:?}");
            }
        }
    }
}

#[test]
fn tilted_flat_sheet_gives_the_plane_normal_within_rounding() {
    let plane_normal = Vec3::new(1.0, 2.0, 2.0) / 3.0;
    let u = Vec3::new(2.0, -1.0, 0.0).normalize();
    let v = plane_normal.cross(u).normalize();
    let side = 11;
    let spacing = 0.1f32;
    let (grid, indices) = flat_grid(side, spacing, |cell| cell % 2 == 1);
    let positions: Vec<Vec3> = grid.iter().map(|p| p.x * u + p.y * v).collect();
    // Reference: the exact normal of the plane spanned by the rounded u and v.
    let reference = u.as_dvec3().cross(v.as_dvec3()).normalize();
    // Tolerance: each position is off the plane by ~2 roundings of its largest component,
    // u = ε/2 each, so an edge of length `spacing` tilts by at most ~2ε·max|p|/spacing (×√3 for
    // three components); normalisation and summation add a few ε. Doubled for margin.
    let largest = positions
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0, f32::max);
    let tolerance = 2.0
        * (2.0 * 3f64.sqrt() * f64::from(f32::EPSILON * largest / spacing)
            + 8.0 * f64::from(f32::EPSILON));
    for weighting in WEIGHTINGS {
        for side_sign in [1.0f32, -1.0] {
            let light = Light::Point {
                position: 0.5 * (u + v) + side_sign * plane_normal,
            };
            for normal in normals_with(&positions, &indices, &light, weighting) {
                let error = angle_between(normal, reference * f64::from(side_sign));
                assert!(
                    error <= tolerance,
                    "{weighting:?}: error {error} > {tolerance}"
                );
            }
        }
    }
}

/// Largest edge length of a mesh, m.
fn longest_edge(positions: &[Vec3], indices: &[u32]) -> f64 {
    indices
        .chunks_exact(3)
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| f64::from(positions[a as usize].distance(positions[b as usize])))
        .fold(0.0, f64::max)
}

/// Largest angle between each vertex normal and the analytic sphere normal −p̂ (light at the
/// centre, so every normal must point inward).
fn sphere_error(level: usize, weighting: Weighting) -> f64 {
    let (positions, indices) = icosphere(level);
    let normals = normals_with(
        &positions,
        &indices,
        &Light::Point {
            position: Vec3::ZERO,
        },
        weighting,
    );
    positions
        .iter()
        .zip(&normals)
        .map(|(p, n)| angle_between(*n, -p.as_dvec3().normalize()))
        .fold(0.0, f64::max)
}

#[test]
fn refined_sphere_normals_approach_the_analytic_normal() {
    for weighting in WEIGHTINGS {
        // Level 1 is exact up to rounding by symmetry; the asymptotic regime starts at level 2.
        let errors: Vec<f64> = (2..=5)
            .map(|level| sphere_error(level, weighting))
            .collect();
        // Shown with --nocapture; the README's accuracy table comes from here.
        eprintln!("{weighting:?}: max angle error, levels 2..=5: {errors:?}");
        // On a midpoint-refined icosphere the triangles are not uniform, and both area and angle
        // weighting are first-order accurate there (Jin, Lewis & West 2005, "A comparison of
        // algorithms for vertex normal computation"): each level halves h, so the error halves.
        // Allow 10% over the predicted ratio 1/2.
        for pair in errors.windows(2) {
            assert!(
                pair[1] <= 0.55 * pair[0],
                "{weighting:?}: errors {errors:?}"
            );
        }
        // First order: error ≤ C·h; measured C ≈ 0.09 (area) and 0.04 (angle); C = 0.25 fails a
        // scheme that is off by a constant angle, or converges slower than first order.
        let (positions, indices) = icosphere(5);
        let h = longest_edge(&positions, &indices);
        assert!(
            errors[3] <= 0.25 * h,
            "{weighting:?}: error {} vs h {h}",
            errors[3]
        );
    }
}

#[test]
fn angle_weighting_is_more_accurate_than_area_weighting_on_the_sphere() {
    // Measured ratio ≈ 0.44 at every level; the claim in the README is "about half".
    for level in 2..=4 {
        assert!(sphere_error(level, Weighting::Angle) < 0.5 * sphere_error(level, Weighting::Area));
    }
}

#[test]
fn sphere_normals_toward_a_distant_light_follow_the_lit_hemisphere() {
    let level = 4;
    let (positions, indices) = icosphere(level);
    let h = longest_edge(&positions, &indices) as f32;
    let direction = Vec3::new(0.3, -0.5, 0.8).normalize();
    let distant = Light::Directional {
        direction_to_light: direction,
    };
    let centre = Light::Point {
        position: Vec3::ZERO,
    };
    for weighting in WEIGHTINGS {
        let toward_distant = normals_with(&positions, &indices, &distant, weighting);
        let toward_centre = normals_with(&positions, &indices, &centre, weighting);
        for ((p, n), inward) in positions.iter().zip(&toward_distant).zip(&toward_centre) {
            assert!(n.dot(direction) >= 0.0);
            assert!((n.length() - 1.0).abs() <= 4.0 * f32::EPSILON);
            // Away from the terminator (every face of the fan within ~h of p̂, so all of them on
            // the same side of the light) the result is the centre-light normal, exactly negated
            // on the lit hemisphere (the same oriented terms, all negated) and equal on the other.
            let cosine = p.dot(direction);
            if cosine > 2.0 * h {
                assert_eq!(*n, -*inward);
            } else if cosine < -2.0 * h {
                assert_eq!(*n, *inward);
            }
        }
    }
}

#[test]
fn moving_a_point_light_through_the_sheet_flips_every_normal() {
    let (positions, indices) = flat_grid(7, 0.5, |cell| cell % 2 == 0);
    let mut updater = NormalUpdater::new(positions.len(), &indices).unwrap();
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for step in -10..=10 {
        let height = step as f32 * 0.25;
        let light = Light::Point {
            position: Vec3::new(1.2, 1.7, height),
        };
        updater.update(&positions, &light, &mut normals).unwrap();
        // In the plane (height 0) every face is perpendicular to the light: the canonical sign +Z.
        let expected = if height < 0.0 { -Vec3::Z } else { Vec3::Z };
        assert!(
            normals.iter().all(|&n| n == expected),
            "height {height}: {normals:?}"
        );
    }
}

#[test]
fn reversing_a_directional_light_negates_every_normal_exactly() {
    // For a curved sheet: each orientation test sees exactly the negated dot product, so every
    // decision flips and the sums are exact negations.
    let (positions, indices) = wavy_grid(40);
    for weighting in WEIGHTINGS {
        let direction = Vec3::new(0.1, 0.2, 1.0);
        let above = normals_with(
            &positions,
            &indices,
            &Light::Directional {
                direction_to_light: direction,
            },
            weighting,
        );
        let below = normals_with(
            &positions,
            &indices,
            &Light::Directional {
                direction_to_light: -direction,
            },
            weighting,
        );
        for (a, b) in above.iter().zip(&below) {
            assert_eq!(*b, -*a);
            assert!(a.dot(direction) > 0.0);
        }
    }
}

#[test]
fn any_winding_or_rotation_of_the_triangles_gives_bit_identical_normals() {
    let (sphere_positions, sphere_indices) = icosphere(3);
    let (sheet_positions, sheet_indices) = wavy_grid(30);
    let light = Light::Point {
        position: Vec3::new(0.2, 0.4, 0.3),
    };
    for weighting in WEIGHTINGS {
        for (positions, indices) in [
            (&sphere_positions, &sphere_indices),
            (&sheet_positions, &sheet_indices),
        ] {
            let reference = bits(&normals_with(positions, indices, &light, weighting));
            let reversed: Vec<u32> = indices
                .chunks_exact(3)
                .flat_map(|t| [t[0], t[2], t[1]])
                .collect();
            assert_eq!(
                bits(&normals_with(positions, &reversed, &light, weighting)),
                reference
            );
            for seed in 1..4 {
                let rewound = rewind(indices, seed);
                assert_eq!(
                    bits(&normals_with(positions, &rewound, &light, weighting)),
                    reference
                );
            }
        }
    }
}

#[test]
fn an_edge_on_light_keeps_the_canonical_sign_for_either_winding() {
    // μ0 = 0 exactly at every vertex: the documented tie-break keeps the face normal whose first
    // non-zero component is positive, here +Z, whichever side of the sheet the light grazes from.
    for flip in [0usize, 1, 2] {
        let (positions, indices) = flat_grid(6, 0.2, |cell| (cell + flip) % 3 == 0);
        for weighting in WEIGHTINGS {
            for light in [
                Light::Directional {
                    direction_to_light: Vec3::X,
                },
                Light::Directional {
                    direction_to_light: Vec3::new(-1.0, 0.5, 0.0),
                },
                Light::Point {
                    position: Vec3::new(-3.0, 0.4, 0.0),
                },
            ] {
                for normal in normals_with(&positions, &indices, &light, weighting) {
                    assert_eq!(normal, Vec3::Z, "{light:?}");
                }
            }
        }
    }
}

#[test]
fn an_almost_edge_on_light_on_a_tilted_sheet_gives_one_consistent_normal() {
    // The light lies in the sheet's plane up to rounding: orientation tests are rounding noise, and
    // the tie tolerance must keep all faces on one (canonical) side instead of cancelling them.
    let plane_normal = Vec3::new(1.0, 2.0, 2.0) / 3.0;
    let u = Vec3::new(2.0, -1.0, 0.0).normalize();
    let v = plane_normal.cross(u).normalize();
    let (grid, indices) = flat_grid(8, 0.1, |cell| cell % 2 == 0);
    let positions: Vec<Vec3> = grid.iter().map(|p| p.x * u + p.y * v).collect();
    let light = Light::Directional {
        direction_to_light: u,
    };
    let reference = u.as_dvec3().cross(v.as_dvec3()).normalize();
    for weighting in WEIGHTINGS {
        let normals = normals_with(&positions, &indices, &light, weighting);
        // Canonical sign: first non-zero component positive, and the plane normal's x is 1/3 > 0.
        for normal in &normals {
            // Same tolerance derivation as the tilted-sheet test (largest |p| < 1, spacing 0.1).
            assert!(
                angle_between(*normal, reference)
                    < 2.0
                        * (2.0 * 3f64.sqrt() * f64::from(f32::EPSILON) * 10.0
                            + 8.0 * f64::from(f32::EPSILON))
            );
        }
    }
}

#[test]
fn degenerate_and_collapsed_meshes_give_finite_defined_normals() {
    let light_position = Vec3::new(1.0, 2.0, 3.0);
    let light = Light::Point {
        position: light_position,
    };
    for weighting in WEIGHTINGS {
        // All vertices in one point: no triangle has area, every normal points at the light.
        let collapsed = vec![Vec3::new(0.5, 0.5, 0.5); 6];
        let indices = [0, 1, 2, 3, 4, 5, 0, 2, 4];
        let toward = (light_position - collapsed[0]).normalize();
        for n in normals_with(&collapsed, &indices, &light, weighting) {
            assert!((n - toward).length() <= 4.0 * f32::EPSILON, "{n}");
        }
        // Exactly collinear vertices (integer multiples of (1, 2, 3)).
        let line: Vec<Vec3> = (0..5)
            .map(|k| k as f32 * Vec3::new(1.0, 2.0, 3.0))
            .collect();
        for (p, n) in line.iter().zip(normals_with(
            &line,
            &[0, 1, 2, 2, 3, 4, 0, 4, 2],
            &light,
            weighting,
        )) {
            match (light_position - *p).try_normalize() {
                Some(toward) => assert!((n - toward).length() <= 4.0 * f32::EPSILON),
                // Vertex 1 is the light's own position: the documented +Z.
                None => assert_eq!(n, Vec3::Z),
            }
        }
        // Repeated indices, an unreferenced vertex, and a point light exactly on it.
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(4.0, 4.0, 4.0)];
        let on_isolated = Light::Point {
            position: positions[3],
        };
        let normals = normals_with(
            &positions,
            &[0, 0, 1, 0, 1, 2, 2, 2, 2],
            &on_isolated,
            weighting,
        );
        assert_eq!(normals[3], Vec3::Z);
        for n in &normals[..3] {
            assert!(n.is_finite() && (n.length() - 1.0).abs() <= 4.0 * f32::EPSILON);
        }
        // The lit side of the one real triangle: the light at (4,4,4) is on its +Z side.
        assert_eq!(&normals[..3], &[Vec3::Z; 3]);
    }
}

#[test]
fn zero_area_triangles_contribute_nothing() {
    let (positions, indices) = wavy_grid(12);
    let light = Light::Point {
        position: Vec3::new(0.5, 0.5, 2.0),
    };
    // Add a duplicate-index triangle and a collinear one (three points on a grid row of the flat
    // direction are not collinear on the wavy sheet, so use repeated vertices instead).
    let mut degenerate = indices.clone();
    degenerate.extend_from_slice(&[5, 5, 17, 30, 31, 30, 7, 7, 7]);
    for weighting in WEIGHTINGS {
        assert_eq!(
            bits(&normals_with(&positions, &degenerate, &light, weighting)),
            bits(&normals_with(&positions, &indices, &light, weighting))
        );
    }
    // A genuinely collinear triangle of three distinct vertices: extra vertices on a line.
    let mut line_positions = positions.clone();
    line_positions.extend([
        Vec3::new(2.0, 2.0, 2.0),
        Vec3::new(3.0, 3.0, 3.0),
        Vec3::new(5.0, 5.0, 5.0),
    ]);
    let base = positions.len() as u32;
    let mut with_line = indices.clone();
    with_line.extend_from_slice(&[base, base + 1, base + 2]);
    for weighting in WEIGHTINGS {
        let normals = normals_with(&line_positions, &with_line, &light, weighting);
        let without = normals_with(&positions, &indices, &light, weighting);
        assert_eq!(bits(&normals[..positions.len()]), bits(&without));
        for (p, n) in line_positions[positions.len()..]
            .iter()
            .zip(&normals[positions.len()..])
        {
            let toward = (Vec3::new(0.5, 0.5, 2.0) - *p).normalize();
            assert!((*n - toward).length() <= 4.0 * f32::EPSILON);
        }
    }
}

#[test]
fn angle_weighting_ignores_how_a_fan_is_split_and_area_weighting_does_not() {
    // A roof: vertex 0 on the ridge, one slope a single triangle, the other slope the same wedge
    // split in two. Angle weighting sees the same total angle per slope either way.
    let positions = vec![
        Vec3::ZERO,
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 1.0),
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(0.0, -1.0, 0.3),
        Vec3::new(0.5, -1.0, 0.3),
    ];
    let whole = [0, 1, 2, 1, 3, 2, 0, 4, 1];
    let split = [0, 1, 2, 1, 3, 2, 0, 4, 5, 0, 5, 1];
    let light = Light::Point {
        position: Vec3::new(0.3, 0.2, 3.0),
    };
    let angle_whole = normals_with(&positions, &whole, &light, Weighting::Angle)[0];
    let angle_split = normals_with(&positions, &split, &light, Weighting::Angle)[0];
    // Same planes and same total angles, different summation: a few ε.
    assert!((angle_whole - angle_split).length() <= 8.0 * f32::EPSILON);
    let area_whole = normals_with(&positions, &whole, &light, Weighting::Area)[0];
    let area_split = normals_with(&positions, &split, &light, Weighting::Area)[0];
    assert!((area_whole - area_split).length() > 1e-3);
}

#[test]
fn serial_and_rayon_agree_bit_for_bit() {
    let (positions, indices) = wavy_grid(120);
    assert!(positions.len() >= sheer_normals::PARALLEL_MIN_VERTICES);
    let light = Light::Point {
        position: Vec3::new(0.3, 0.6, 0.5),
    };
    for weighting in WEIGHTINGS {
        let mut results = Vec::new();
        for execution in [Execution::Serial, Execution::Parallel] {
            let options = NormalOptions {
                weighting,
                execution,
            };
            let mut updater =
                NormalUpdater::with_options(positions.len(), &indices, options).unwrap();
            let mut normals = vec![Vec3::ZERO; positions.len()];
            updater.update(&positions, &light, &mut normals).unwrap();
            results.push(bits(&normals));
        }
        assert_eq!(results[0], results[1]);
    }
}

#[test]
fn the_convenience_function_matches_the_updater() {
    let (positions, indices) = icosphere(2);
    let light = Light::Point {
        position: Vec3::new(3.0, 0.0, 0.0),
    };
    let mut updater = NormalUpdater::new(positions.len(), &indices).unwrap();
    let mut normals = vec![Vec3::ZERO; positions.len()];
    updater.update(&positions, &light, &mut normals).unwrap();
    assert_eq!(
        vertex_normals_toward_light(&positions, &indices, &light).unwrap(),
        normals
    );
    assert_eq!(updater.vertex_count(), positions.len());
    assert_eq!(updater.triangle_count(), indices.len() / 3);
    assert_eq!(updater.options(), NormalOptions::default());
}

#[test]
fn bad_input_is_a_typed_error() {
    assert_eq!(
        NormalUpdater::new(3, &[]).unwrap_err(),
        NormalsError::EmptyMesh
    );
    assert_eq!(
        NormalUpdater::new(3, &[0, 1]).unwrap_err(),
        NormalsError::IndexCountNotMultipleOfThree { index_count: 2 }
    );
    assert_eq!(
        NormalUpdater::new(3, &[0, 1, 2, 2, 3, 0]).unwrap_err(),
        NormalsError::IndexOutOfRange {
            slot: 4,
            index: 3,
            vertex_count: 3
        }
    );
    assert_eq!(
        NormalUpdater::new(usize::MAX, &[0, 1, 2]).unwrap_err(),
        NormalsError::TooManyVertices {
            vertex_count: usize::MAX,
            max: (u32::MAX as usize).saturating_add(1)
        }
    );
    let positions = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let mut updater = NormalUpdater::new(3, &[0, 1, 2]).unwrap();
    let mut normals = [Vec3::ZERO; 3];
    let light = Light::Point { position: Vec3::Z };
    assert_eq!(
        updater
            .update(&positions[..2], &light, &mut normals)
            .unwrap_err(),
        NormalsError::LengthMismatch {
            what: "positions",
            expected: 3,
            actual: 2
        }
    );
    assert_eq!(
        updater
            .update(&positions, &light, &mut normals[..1])
            .unwrap_err(),
        NormalsError::LengthMismatch {
            what: "normals",
            expected: 3,
            actual: 1
        }
    );
    for bad_light in [
        Light::Point {
            position: Vec3::new(f32::NAN, 0.0, 0.0),
        },
        Light::Directional {
            direction_to_light: Vec3::new(0.0, f32::INFINITY, 0.0),
        },
    ] {
        assert_eq!(
            updater
                .update(&positions, &bad_light, &mut normals)
                .unwrap_err(),
            NormalsError::NonFiniteLight
        );
    }
    assert_eq!(
        updater
            .update(
                &positions,
                &Light::Directional {
                    direction_to_light: Vec3::ZERO
                },
                &mut normals
            )
            .unwrap_err(),
        NormalsError::ZeroLightDirection
    );
    assert_eq!(
        updater
            .update(
                &positions,
                &Light::Point {
                    position: Vec3::splat(2.0 * MAX_COORDINATE)
                },
                &mut normals
            )
            .unwrap_err(),
        NormalsError::LightOutOfRange {
            limit: MAX_COORDINATE
        }
    );
    let untouched = [Vec3::splat(7.0); 3];
    for (bad, expected) in [
        (
            Vec3::new(0.0, f32::NAN, 0.0),
            NormalsError::NonFinitePosition { vertex: 1 },
        ),
        (
            Vec3::new(0.0, 0.0, f32::NEG_INFINITY),
            NormalsError::NonFinitePosition { vertex: 1 },
        ),
        (
            Vec3::new(0.0, 1e10, 0.0),
            NormalsError::PositionOutOfRange {
                vertex: 1,
                limit: MAX_COORDINATE,
            },
        ),
    ] {
        let mut normals = untouched;
        let positions = [Vec3::ZERO, bad, Vec3::Y];
        assert_eq!(
            updater
                .update(&positions, &light, &mut normals)
                .unwrap_err(),
            expected
        );
        // Nothing is written on error.
        assert_eq!(normals, untouched);
    }
}

#[test]
fn positions_at_the_coordinate_limit_give_finite_unit_normals() {
    // The largest accepted coordinates, where an unscaled normalisation would overflow.
    let m = MAX_COORDINATE;
    let positions = [
        Vec3::new(-m, -m, 0.0),
        Vec3::new(m, -m, 0.0),
        Vec3::new(-m, m, m),
        Vec3::new(m, m, -m),
    ];
    let light = Light::Point {
        position: Vec3::new(m, m, m),
    };
    for weighting in WEIGHTINGS {
        for n in normals_with(&positions, &[0, 1, 2, 1, 3, 2], &light, weighting) {
            assert!(
                n.is_finite() && (n.length() - 1.0).abs() <= 4.0 * f32::EPSILON,
                "{n}"
            );
        }
        // Tiny triangles (edges 1e-20 m, squares underflow in f32) still give finite output.
        let tiny = [
            Vec3::ZERO,
            Vec3::new(1e-20, 0.0, 0.0),
            Vec3::new(0.0, 1e-20, 0.0),
        ];
        for n in normals_with(&tiny, &[0, 1, 2], &light, weighting) {
            assert!(
                n.is_finite() && (n.length() - 1.0).abs() <= 4.0 * f32::EPSILON,
                "{n}"
            );
        }
    }
}

#[test]
fn light_direction_from_a_point_follows_the_documented_convention() {
    let directional = Light::Directional {
        direction_to_light: Vec3::new(0.0, 0.0, 5.0),
    };
    // Directional: the given direction, normalised, wherever the point is.
    assert_eq!(
        directional.direction_from(Vec3::new(3.0, -2.0, 1.0)),
        Ok(Some(Vec3::Z))
    );
    let point = Light::Point {
        position: Vec3::new(0.0, 2.0, 0.0),
    };
    assert_eq!(point.direction_from(Vec3::ZERO), Ok(Some(Vec3::Y)));
    // Undefined exactly at the light.
    assert_eq!(point.direction_from(Vec3::new(0.0, 2.0, 0.0)), Ok(None));
    assert_eq!(
        Light::Directional {
            direction_to_light: Vec3::ZERO
        }
        .direction_from(Vec3::ZERO),
        Err(NormalsError::ZeroLightDirection)
    );
}
