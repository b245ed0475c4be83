//! Translucent shadows (`render::shadow`): the GPU's transmittance shadow map against geometry and against
//! the CPU ray caster. Two parallel sheets: the far one's direct light is the near one's transmittance
//! e^{−τ1/μ0} times the unshadowed, on every evaluation path, away from the shadow's edge; an opaque
//! pole's shadow falls where the segment from the light meets the cylinder; a single flat sheet renders
//! bit for bit as without shadows; shadows never brighten a pixel; the all-orders path with the light
//! scattered through the near sheet matches the CPU reference per pixel.
//!
//! Without any adapter these tests fail, unless `SHEER_SKIP_GPU_TESTS=1`.

use std::sync::Arc;

use glam::{DVec3, Vec3};
use sheer_slab::render::{
    Background, Camera, EvaluationPath, HeadlessRenderer, LightTransmission, OpaqueMesh,
    RenderError, ShadingError, ShadingParams, ShadowCasters, Shadows, SlabFrame, SlabMesh,
    albedo_at, gpu_tests_may_be_skipped, optical_thickness_at, slab_values_lit_by,
};
use sheer_slab::{
    DiffuseTable, Scattering, default_table_path, load_all_orders_table, load_diffuse_table,
};

const SIZE: u32 = 96;
const TAU: f32 = 2.0;
const LIGHT: Vec3 = Vec3::new(0.0, 0.0, 3.0);

fn renderer() -> Option<HeadlessRenderer> {
    match HeadlessRenderer::new(SIZE, SIZE) {
        Ok(renderer) => Some(renderer),
        Err(error @ RenderError::NoAdapter { .. }) if gpu_tests_may_be_skipped() => {
            eprintln!("skipping GPU test (SHEER_SKIP_GPU_TESTS=1): {error}");
            None
        }
        Err(error) => panic!("GPU tests need an adapter: {error}"),
    }
}

/// Looks obliquely at the far sheet's lit face, past the near sheet.
fn camera() -> Camera {
    Camera {
        eye: Vec3::new(1.6, 0.0, 1.4),
        target: Vec3::new(-0.25, 0.0, 0.0),
        up: Vec3::Y,
        vertical_fov: 0.9,
        near: 0.05,
        far: 20.0,
    }
}

/// A square sheet of half-width `half` in the plane z = `z`, facing +z.
fn square(half: f32, z: f32, segments: u32) -> SlabMesh {
    SlabMesh::flat_sheet(
        Vec3::new(-half, -half, z),
        Vec3::X * 2.0 * half,
        Vec3::Y * 2.0 * half,
        Vec3::Z,
        segments,
        segments,
    )
    .unwrap()
}

/// Both meshes as one.
fn merged(a: SlabMesh, b: &SlabMesh) -> SlabMesh {
    let mut mesh = a;
    let base = mesh.positions.len() as u32;
    mesh.positions.extend(&b.positions);
    mesh.normals.extend(&b.normals);
    mesh.uvs.extend(&b.uvs);
    mesh.indices.extend(b.indices.iter().map(|i| base + i));
    mesh
}

/// The far sheet (z = 0, 2 m wide) and the near sheet (z = 1, 0.6 m wide) between it and the light.
const NEAR_HALF: f64 = 0.3;

fn two_sheets() -> SlabMesh {
    merged(square(1.0, 0.0, 48), &square(NEAR_HALF as f32, 1.0, 6))
}

fn with_shadows(shading: &ShadingParams) -> ShadingParams {
    ShadingParams {
        shadows: Some(Shadows::default()),
        ..shading.clone()
    }
}

fn render(
    renderer: &mut HeadlessRenderer,
    mesh: &SlabMesh,
    shading: &ShadingParams,
    path: EvaluationPath,
    opaque: &[OpaqueMesh],
) -> Vec<[f32; 4]> {
    let frame = SlabFrame {
        mesh,
        camera: &camera(),
        shading,
        background: &Background::Uniform([0.0; 3]),
        path,
        opaque,
        light_marker: None,
        scissor: None,
    };
    renderer.render_frames_timed(&[frame]).unwrap();
    renderer.read_target().unwrap().pixels
}

/// The point of the far sheet (z = 0) a pixel centre sees, if the eye's ray reaches it inside the sheet
/// (less `margin`) without crossing the near sheet (plus `margin`).
fn far_point(x: u32, y: u32, margin: f64) -> Option<DVec3> {
    let (origin, direction) = camera()
        .pixel_ray(f64::from(x) + 0.5, f64::from(y) + 0.5, SIZE, SIZE)
        .unwrap();
    let at_z = |z: f64| origin + direction * ((z - origin.z) / direction.z);
    let p = at_z(0.0);
    let q = at_z(1.0);
    let inside = |v: DVec3, half: f64| v.x.abs() < half && v.y.abs() < half;
    (inside(p, 1.0 - margin) && !inside(q, NEAR_HALF + margin)).then_some(p)
}

/// Where the segment from the light to `p` crosses the near sheet's plane, and its cosine there.
fn near_crossing(p: DVec3) -> (DVec3, f64) {
    let light = LIGHT.as_dvec3();
    let direction = (p - light).normalize();
    (
        light + (p - light) * ((light.z - 1.0) / (light.z - p.z)),
        direction.z.abs(),
    )
}

#[test]
fn the_far_sheet_gets_the_near_sheets_transmittance_on_every_path() {
    let Some(mut renderer) = renderer() else {
        return;
    };
    let mesh = two_sheets();
    let shading = ShadingParams::uniform(TAU, 0.9, LIGHT, 60.0).unwrap();
    let shadowed = with_shadows(&shading);
    // Away from the shadow's edge: 5 cm on the far sheet (two of its triangles, which the per-vertex
    // paths interpolate across; many shadow-map texels), 2/3 of that at the near sheet.
    let margin = 0.05;
    for path in [
        EvaluationPath::PerFragment,
        EvaluationPath::PerVertex,
        EvaluationPath::Cpu,
    ] {
        let off = render(&mut renderer, &mesh, &shading, path, &[]);
        let on = render(&mut renderer, &mesh, &shadowed, path, &[]);
        let (mut in_shadow, mut in_light, mut worst) = (0, 0, 0.0f64);
        for y in 0..SIZE {
            for x in 0..SIZE {
                let Some(p) = far_point(x, y, margin) else {
                    continue;
                };
                let (q, mu0) = near_crossing(p);
                let depth = NEAR_HALF - q.x.abs().max(q.y.abs());
                let expected = if depth > margin * 2.0 / 3.0 {
                    in_shadow += 1;
                    (-f64::from(TAU) / mu0).exp()
                } else if depth < -margin * 2.0 / 3.0 {
                    in_light += 1;
                    1.0
                } else {
                    continue;
                };
                let i = (y * SIZE + x) as usize;
                for c in 0..3 {
                    let ratio = f64::from(on[i][c]) / f64::from(off[i][c]);
                    let error = (ratio / expected - 1.0).abs();
                    worst = worst.max(error);
                    assert!(
                        error < 0.01,
                        "{}: pixel ({x}, {y}) on/off {ratio} vs e^(-τ1/μ0) = {expected}",
                        path.name()
                    );
                }
            }
        }
        println!(
            "{}: {in_shadow} pixels in the shadow, {in_light} in the light, worst relative error {worst:.2e}",
            path.name()
        );
        assert!(in_shadow > 100 && in_light > 100);
    }
}

#[test]
fn the_cpu_ray_caster_gives_the_geometrys_transmittance() {
    let mesh = two_sheets();
    let shading = with_shadows(&ShadingParams::uniform(TAU, 0.9, LIGHT, 60.0).unwrap());
    let casters = ShadowCasters::new(&mesh, &[], LIGHT, 1024);
    for (x, y) in [
        (0.0, 0.0),
        (0.2, -0.1),
        (0.35, 0.1),
        (0.9, 0.9),
        (-0.44, 0.2),
    ] {
        let p = DVec3::new(x, y, 0.0);
        let (q, mu0) = near_crossing(p);
        let light = casters.light_transmission(p, &shading, None);
        let expected = if q.x.abs().max(q.y.abs()) < NEAR_HALF {
            (-f64::from(TAU) / mu0).exp()
        } else {
            1.0
        };
        for c in 0..3 {
            assert!((light.direct[c] - expected).abs() < 1e-12, "{p}: {light:?}");
        }
        assert_eq!(light.diffuse, [0.0; 3]);
    }
    // A point on the near sheet itself is not shadowed by it.
    let light = casters.light_transmission(DVec3::new(0.1, 0.1, 1.0), &shading, None);
    assert_eq!(light, LightTransmission::UNSHADOWED);
}

/// A vertical pole (axis (0, ·, 1)) of radius 10 cm between the light and the far sheet.
const POLE_RADIUS: f64 = 0.1;

fn pole() -> OpaqueMesh {
    OpaqueMesh::cylinder(
        Vec3::new(0.0, -1.2, 1.0),
        Vec3::new(0.0, 1.2, 1.0),
        POLE_RADIUS as f32,
        32,
        [0.5; 3],
    )
    .unwrap()
}

#[test]
fn an_opaque_pole_casts_its_shadow_where_geometry_says() {
    let Some(mut renderer) = renderer() else {
        return;
    };
    let mesh = square(1.0, 0.0, 96);
    let shading = ShadingParams::uniform(TAU, 0.9, LIGHT, 60.0).unwrap();
    let shadowed = with_shadows(&shading);
    let poles = [pole()];
    let off = render(
        &mut renderer,
        &mesh,
        &shading,
        EvaluationPath::PerFragment,
        &poles,
    );
    let on = render(
        &mut renderer,
        &mesh,
        &shadowed,
        EvaluationPath::PerFragment,
        &poles,
    );
    let casters = ShadowCasters::new(&mesh, &poles, LIGHT, 1024);
    let light = LIGHT.as_dvec3();
    let (mut blocked, mut clear) = (0, 0);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let Some(p) = far_point(x, y, 0.02) else {
                continue;
            };
            // The segment from the light to p in the x–z plane against the circle of radius r around
            // (0, 1): blocked where it passes inside the 32-gon's inscribed circle (r·cos(π/32)), clear
            // outside r; 2.5 cm of margin there: the lookup is per vertex and interpolated across the
            // sheet's 2.1 cm triangles (1.4 cm seen at the pole's distance), plus the map's texels
            // (about 3 mm) and filtering.
            let (a, b) = (
                glam::DVec2::new(light.x, light.z),
                glam::DVec2::new(p.x, p.z),
            );
            let centre = glam::DVec2::new(0.0, 1.0);
            let along = (b - a).normalize();
            let distance = (centre - a).perp_dot(along).abs();
            let i = (y * SIZE + x) as usize;
            let cpu = casters.light_transmission(p, &shadowed, None);
            if distance < POLE_RADIUS * (std::f64::consts::PI / 32.0).cos() - 0.025 {
                blocked += 1;
                assert_eq!(
                    &on[i][..3],
                    &[0.0; 3],
                    "pixel ({x}, {y}) should be in the pole's shadow"
                );
                assert_eq!(cpu.direct, [0.0; 3]);
            } else if distance > POLE_RADIUS + 0.025 {
                clear += 1;
                assert_eq!(on[i], off[i], "pixel ({x}, {y}) should be lit");
                assert_eq!(cpu, LightTransmission::UNSHADOWED);
            }
        }
    }
    println!("pole: {blocked} pixels in its shadow, {clear} clear of it");
    assert!(blocked > 20 && clear > 1000);
}

fn all_orders(shading: &ShadingParams, diffuse: &Arc<DiffuseTable>) -> ShadingParams {
    ShadingParams {
        scattering: Scattering::AllOrders(
            load_all_orders_table(default_table_path()).expect("the shipped table"),
        ),
        shadows: Some(Shadows {
            diffuse_table: Some(Arc::clone(diffuse)),
            ..Shadows::default()
        }),
        ..shading.clone()
    }
}

fn diffuse_table() -> Arc<DiffuseTable> {
    load_diffuse_table(DiffuseTable::DEFAULT_PATH).expect("the shipped diffuse table")
}

#[test]
fn a_single_flat_sheet_renders_as_without_shadows() {
    let Some(mut renderer) = renderer() else {
        return;
    };
    let mesh = square(1.0, 0.0, 16);
    let diffuse = diffuse_table();
    // Front-lit and back-lit (eye on the far side).
    for light in [LIGHT, Vec3::new(0.5, 0.3, -2.0)] {
        let single = ShadingParams::uniform(TAU, 0.9, light, 60.0).unwrap();
        let all = all_orders(&single, &diffuse);
        let all_off = ShadingParams {
            shadows: None,
            ..all.clone()
        };
        for path in [
            EvaluationPath::PerFragment,
            EvaluationPath::PerVertex,
            EvaluationPath::Cpu,
        ] {
            let off = render(&mut renderer, &mesh, &single, path, &[]);
            let on = render(&mut renderer, &mesh, &with_shadows(&single), path, &[]);
            assert!(off == on, "{}: single scattering changed", path.name());
            let off = render(&mut renderer, &mesh, &all_off, path, &[]);
            let on = render(&mut renderer, &mesh, &all, path, &[]);
            assert!(off == on, "{}: all orders changed", path.name());
        }
    }
}

/// A sheet folded twice (a Z seen edge-on from the light's side): three layers one behind the other.
fn folded_sheet() -> SlabMesh {
    let mut mesh = square(0.6, 0.0, 24);
    for (p, n) in mesh.positions.iter_mut().zip(&mut mesh.normals) {
        // z = 0.25·sin(2π·1.2·x), a wave whose crests hide its troughs from a low light.
        let phase = std::f32::consts::TAU * 1.2 * p[0];
        p[2] = 0.25 * phase.sin();
        let slope = 0.25 * std::f32::consts::TAU * 1.2 * phase.cos();
        *n = Vec3::new(-slope, 0.0, 1.0).normalize().to_array();
    }
    mesh
}

#[test]
fn shadows_never_brighten_a_pixel() {
    let Some(mut renderer) = renderer() else {
        return;
    };
    let mesh = folded_sheet();
    let diffuse = diffuse_table();
    let mut darker = 0;
    for light in [Vec3::new(2.5, 0.2, 0.6), Vec3::new(-2.0, 0.5, -0.8)] {
        let single = ShadingParams::uniform(TAU, 0.9, light, 60.0).unwrap();
        let all = all_orders(&single, &diffuse);
        let cases = [
            (single.clone(), with_shadows(&single)),
            (
                ShadingParams {
                    shadows: None,
                    ..all.clone()
                },
                all,
            ),
        ];
        for (off_shading, on_shading) in &cases {
            for path in [
                EvaluationPath::PerFragment,
                EvaluationPath::PerVertex,
                EvaluationPath::Cpu,
            ] {
                let off = render(&mut renderer, &mesh, off_shading, path, &[]);
                let on = render(&mut renderer, &mesh, on_shading, path, &[]);
                for (i, (a, b)) in on.iter().zip(&off).enumerate() {
                    for c in 0..3 {
                        // f32 rounding of the same sums in another order: a few ulps.
                        assert!(
                            a[c] <= b[c] * (1.0 + 1e-5) + 1e-9,
                            "{}: pixel {i} channel {c} brighter with shadows: {} > {}",
                            path.name(),
                            a[c],
                            b[c]
                        );
                    }
                    darker += usize::from(a[0] < b[0] * 0.99);
                }
            }
        }
    }
    // The wave does shadow itself.
    assert!(darker > 500, "only {darker} pixels darkened");
}

#[test]
fn the_gpu_map_matches_the_cpu_ray_caster_with_all_orders() {
    let Some(mut renderer) = renderer() else {
        return;
    };
    let mesh = two_sheets();
    let diffuse = diffuse_table();
    let shading = all_orders(
        &ShadingParams::uniform(TAU, 0.9, LIGHT, 60.0).unwrap(),
        &diffuse,
    );
    let on = render(
        &mut renderer,
        &mesh,
        &shading,
        EvaluationPath::PerFragment,
        &[],
    );
    let casters = ShadowCasters::new(&mesh, &[], LIGHT, 1024);
    let eye = camera().eye.as_dvec3();
    let (mut compared, mut worst) = (0, 0.0f64);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let Some(p) = far_point(x, y, 0.02) else {
                continue;
            };
            let (q, _) = near_crossing(p);
            // The shadow's edge, blurred by the per-vertex lookup over the far sheet's 4.2 cm triangles
            // (2.8 cm at the near sheet).
            if (NEAR_HALF - q.x.abs().max(q.y.abs())).abs() < 0.04 {
                continue;
            }
            let uv = [(p.x as f32 + 1.0) / 2.0, (1.0 - p.y as f32) / 2.0];
            let tau = optical_thickness_at(&shading, uv);
            let albedo = albedo_at(&shading, uv);
            let light = casters.light_transmission(p, &shading, Some(&diffuse));
            let (radiance, _) =
                slab_values_lit_by(p, DVec3::Z, tau, albedo, eye, &shading, &light).unwrap();
            let i = (y * SIZE + x) as usize;
            for c in 0..3 {
                let expected = albedo[c] * radiance[c];
                // The f32 table lookup (≤ 1e-4), half floats in the map (t and D: 2^-11 relative) and
                // the target's own rounding.
                let error = (f64::from(on[i][c]) / expected - 1.0).abs();
                worst = worst.max(error);
                assert!(
                    error < 2e-3,
                    "pixel ({x}, {y}) channel {c}: GPU {} vs CPU {expected}",
                    on[i][c]
                );
            }
            compared += 1;
        }
    }
    println!("all orders: {compared} pixels, worst relative error GPU vs CPU {worst:.2e}");
    assert!(compared > 1000);
}

#[test]
fn bad_shadow_settings_are_typed_errors() {
    let single = ShadingParams::uniform(TAU, 0.9, LIGHT, 60.0).unwrap();
    let tiny = ShadingParams {
        shadows: Some(Shadows {
            resolution: 8,
            ..Shadows::default()
        }),
        ..single.clone()
    };
    assert!(matches!(
        tiny.validate(),
        Err(ShadingError::ShadowResolution(8))
    ));
    let without_table = ShadingParams {
        scattering: Scattering::AllOrders(
            load_all_orders_table(default_table_path()).expect("the shipped table"),
        ),
        ..with_shadows(&single)
    };
    assert!(matches!(
        without_table.validate(),
        Err(ShadingError::ShadowDiffuseTable)
    ));
    let Some(mut renderer) = renderer() else {
        return;
    };
    let huge = ShadingParams {
        shadows: Some(Shadows {
            resolution: 1 << 20,
            ..Shadows::default()
        }),
        ..single
    };
    let frame = SlabFrame {
        mesh: &square(1.0, 0.0, 2),
        camera: &camera(),
        shading: &huge,
        background: &Background::Uniform([0.0; 3]),
        path: EvaluationPath::PerFragment,
        opaque: &[],
        light_marker: None,
        scissor: None,
    };
    assert!(matches!(
        renderer.render_frames_timed(&[frame]),
        Err(RenderError::TextureTooLarge { .. })
    ));
}
