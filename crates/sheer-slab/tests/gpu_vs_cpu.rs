//! GPU against CPU: flat sheets of known geometry rendered headless (lavapipe/llvmpipe in CI) compared
//! pixel by pixel with the `f64` model plus eq. (9) over a known background; two overlapping sheets for
//! back-to-front layering; per-vertex and CPU paths against per-fragment on a finely tessellated sheet;
//! the same for the all-orders scattering model, and single scattering unchanged by it.
//!
//! Without any adapter these tests fail, unless `SHEER_SKIP_GPU_TESTS=1`.

use std::sync::Arc;

use glam::{DVec3, Vec3};
use sheer_slab::all_orders::{
    Scattering, default_table_path, load_all_orders_table, slab_shading_with,
};
use sheer_slab::model::{
    Albedo, Cosine, Face, IrradianceConvention, OpticalThickness,
    point_light_beam_normal_irradiance, slab_shading,
};
use sheer_slab::render::{
    AllOrdersSampling, Background, Camera, EvaluationPath, HeadlessRenderer, LinearImage,
    RenderError, ShadingParams, SlabMesh, TargetFormat, Texture2d, gpu_tests_may_be_skipped,
    slab_values_at,
};

const WIDTH: u32 = 96;
const HEIGHT: u32 = 64;

/// A renderer with four samples per pixel, as the app renders by default: every comparison below holds
/// away from edges (the comparisons skip pixels whose neighbours see other surfaces).
fn renderer(width: u32, height: u32) -> Option<HeadlessRenderer> {
    match HeadlessRenderer::with_samples(width, height, 4) {
        Ok(renderer) => {
            eprintln!(
                "adapter: {} target {:?}",
                renderer.adapter_description(),
                renderer.target_format()
            );
            Some(renderer)
        }
        Err(error @ RenderError::NoAdapter { .. }) if gpu_tests_may_be_skipped() => {
            eprintln!("skipping GPU test (SHEER_SKIP_GPU_TESTS=1): {error}");
            None
        }
        Err(error) => {
            panic!("GPU tests need an adapter (set SHEER_SKIP_GPU_TESTS=1 to skip): {error}")
        }
    }
}

/// Relative precision of the target's channels: one ulp of f32 or of half float (one ulp, not half: the
/// GL driver's f32 → f16 store may truncate rather than round).
fn format_epsilon(renderer: &HeadlessRenderer) -> f64 {
    match renderer.target_format() {
        TargetFormat::Rgba32Float => f64::from(f32::EPSILON),
        TargetFormat::Rgba16Float => 2f64.powi(-10),
    }
}

/// A planar sheet: `origin + s·u + t·v`, (s, t) ∈ [0, 1]², with outward normal `normal`.
#[derive(Clone, Copy)]
struct Sheet {
    origin: DVec3,
    u: DVec3,
    v: DVec3,
    normal: DVec3,
}

impl Sheet {
    fn mesh(&self, segments: u32) -> SlabMesh {
        SlabMesh::flat_sheet(
            self.origin.as_vec3(),
            self.u.as_vec3(),
            self.v.as_vec3(),
            self.normal.as_vec3(),
            segments,
            segments,
        )
        .unwrap()
    }

    /// Ray–parallelogram intersection: the hit point if inside.
    fn hit(&self, origin: DVec3, direction: DVec3) -> Option<DVec3> {
        let plane_normal = self.u.cross(self.v);
        let denominator = plane_normal.dot(direction);
        if denominator.abs() < 1e-15 {
            return None;
        }
        let distance = plane_normal.dot(self.origin - origin) / denominator;
        if distance <= 0.0 {
            return None;
        }
        let point = origin + distance * direction;
        let relative = point - self.origin;
        // Solve relative = s·u + t·v in the plane (u, v need not be orthogonal).
        let (uu, uv, vv) = (self.u.dot(self.u), self.u.dot(self.v), self.v.dot(self.v));
        let (ru, rv) = (relative.dot(self.u), relative.dot(self.v));
        let det = uu * vv - uv * uv;
        let s = (ru * vv - rv * uv) / det;
        let t = (rv * uu - ru * uv) / det;
        ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t)).then_some(point)
    }
}

/// The paper's convention at a point of a sheet lit by a point light at `light`: the normal turned toward
/// the light (μ0 > 0), then (μ0, |μ|, the side the eye is on, distance to the light in m).
fn shading_geometry(
    point: DVec3,
    normal: DVec3,
    eye: DVec3,
    light: DVec3,
) -> (f64, f64, Face, f64) {
    let to_light = light - point;
    let mut n = normal.normalize();
    if n.dot(to_light) < 0.0 {
        n = -n;
    }
    let mu0 = n.dot(to_light.normalize());
    let signed_mu = n.dot((eye - point).normalize());
    let side = if signed_mu >= 0.0 {
        Face::Lit
    } else {
        Face::Far
    };
    (mu0, signed_mu.abs(), side, to_light.length())
}

/// The CPU model at a point of a sheet lit by a point light (position, flux Φ in W), grey τ1 and Λ:
/// (L_source, α), straight from `sheer_slab::model`.
fn model_at(
    point: DVec3,
    normal: DVec3,
    eye: DVec3,
    (light, flux): (DVec3, f64),
    tau: f64,
    albedo: f64,
    convention: IrradianceConvention,
) -> (f64, f64) {
    let (mu0, mu, side, distance) = shading_geometry(point, normal, eye, light);
    let shading = slab_shading(
        OpticalThickness::new(tau).unwrap(),
        Albedo::new(albedo).unwrap(),
        Cosine::new("mu0", mu0).unwrap(),
        Cosine::new("mu", mu).unwrap(),
        side,
        point_light_beam_normal_irradiance(flux, distance).unwrap(),
        convention,
    )
    .unwrap();
    (shading.source_radiance, shading.transmittance)
}

struct Comparison {
    compared: usize,
    covered: usize,
    worst_ratio: f64,
    worst_relative: f64,
}

/// [`model_at`] for either scattering model: (L_source, α, multiply-scattered part of L_source).
#[allow(clippy::too_many_arguments)]
fn model_at_with(
    scattering: &Scattering,
    point: DVec3,
    normal: DVec3,
    eye: DVec3,
    (light, flux): (DVec3, f64),
    tau: f64,
    albedo: f64,
    convention: IrradianceConvention,
) -> (f64, f64, f64) {
    let (mu0, mu, side, distance) = shading_geometry(point, normal, eye, light);
    let shade = |scattering: &Scattering| {
        slab_shading_with(
            scattering,
            OpticalThickness::new(tau).unwrap(),
            Albedo::new(albedo).unwrap(),
            Cosine::new("mu0", mu0).unwrap(),
            Cosine::new("mu", mu).unwrap(),
            side,
            point_light_beam_normal_irradiance(flux, distance).unwrap(),
            convention,
        )
        .unwrap()
    };
    let shading = shade(scattering);
    let single = shade(&Scattering::Single);
    (
        shading.source_radiance,
        shading.transmittance,
        shading.source_radiance - single.source_radiance,
    )
}

/// Where the four samples of a 4× multisampled pixel lie, relative to its centre, px: Vulkan's standard
/// sample locations. A pixel whose samples all see what its centre sees is the one-sample pixel.
const SAMPLE_OFFSETS: [(f64, f64); 4] = [
    (-0.125, -0.375),
    (0.375, -0.125),
    (-0.375, 0.125),
    (0.125, 0.375),
];

/// Compares every pixel whose centre, four neighbours (±1 px) and four samples agree on which sheets
/// they hit.
/// `expected(x, y)` gives (rgb, alpha) at a sub-pixel position and `coverage(x, y)` a key of what is hit.
/// Tolerance per pixel: 1/8 of the largest change of the expected value to a neighbour 1 px away (the
/// rasteriser snaps vertices to ≤ 1/16 px in Vulkan, moving the interpolated surface point by at most that;
/// factor 2 margin) plus 64 format
/// epsilons relative (f32 evaluation of exp/divisions in the shader, a few tens of roundings) plus 1e-7
/// absolute (for values near zero).
fn compare(
    image: &LinearImage,
    epsilon: f64,
    mut expected: impl FnMut(f64, f64) -> ([f64; 3], f64),
    coverage: impl Fn(f64, f64) -> u32,
) -> Comparison {
    compare_with_slack(
        image,
        epsilon,
        |x, y| {
            let (rgb, alpha) = expected(x, y);
            (rgb, alpha, [0.0; 3])
        },
        coverage,
    )
}

/// [`compare`] with an extra absolute tolerance per colour channel, the third value `expected` returns.
fn compare_with_slack(
    image: &LinearImage,
    epsilon: f64,
    mut expected: impl FnMut(f64, f64) -> ([f64; 3], f64, [f64; 3]),
    coverage: impl Fn(f64, f64) -> u32,
) -> Comparison {
    let mut result = Comparison {
        compared: 0,
        covered: 0,
        worst_ratio: 0.0,
        worst_relative: 0.0,
    };
    for y in 0..image.height {
        for x in 0..image.width {
            let (cx, cy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            let key = coverage(cx, cy);
            let offsets = [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)];
            if offsets
                .iter()
                .chain(&SAMPLE_OFFSETS)
                .any(|(dx, dy)| coverage(cx + dx, cy + dy) != key)
            {
                continue;
            }
            let (rgb, alpha, slack) = expected(cx, cy);
            let neighbours: Vec<([f64; 3], f64)> = offsets
                .iter()
                .map(|(dx, dy)| {
                    let (n, a, _) = expected(cx + dx, cy + dy);
                    (n, a)
                })
                .collect();
            let got = image.pixel(x, y).unwrap();
            for channel in 0..4 {
                let value = if channel < 3 { rgb[channel] } else { alpha };
                let spread = neighbours
                    .iter()
                    .map(|(n, a)| ((if channel < 3 { n[channel] } else { *a }) - value).abs())
                    .fold(0.0, f64::max);
                let extra = if channel < 3 { slack[channel] } else { 0.0 };
                let tolerance = spread / 8.0 + 64.0 * epsilon * value.abs() + 1e-7 + extra;
                let error = (f64::from(got[channel]) - value).abs();
                assert!(
                    error <= tolerance,
                    "pixel ({x}, {y}) channel {channel}: GPU {} vs CPU {value} (tolerance {tolerance:e})",
                    got[channel]
                );
                result.worst_ratio = result.worst_ratio.max(error / tolerance);
                result.worst_relative = result.worst_relative.max(error / value.abs().max(1e-7));
            }
            result.compared += 1;
            if key != 0 {
                result.covered += 1;
            }
        }
    }
    result
}

/// The error bound of linear interpolation over the triangles of a sheet of `segments` × `segments`
/// quads, for the per-channel value `composite(s, t)` at sheet coordinates (s, t) ∈ [0, 1]²: (h²/8)·|f''|
/// per direction, with second differences at the vertex spacing h estimating h²·f'' along u, v and the
/// diagonal; their largest sum / 8, times 2 for safety.
fn interpolation_bound(segments: u32, composite: impl Fn(f64, f64) -> [f64; 3]) -> f64 {
    let second_difference = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
        (0..3)
            .map(|k| (a[k] - 2.0 * b[k] + c[k]).abs())
            .fold(0.0, f64::max)
    };
    let h = 1.0 / f64::from(segments);
    let mut curvature: f64 = 0.0;
    for i in 1..segments {
        for j in 1..segments {
            let (s, t) = (f64::from(i) * h, f64::from(j) * h);
            let centre = composite(s, t);
            let along_u = second_difference(composite(s + h, t), centre, composite(s - h, t));
            let along_v = second_difference(composite(s, t + h), centre, composite(s, t - h));
            let diagonal =
                second_difference(composite(s + h, t + h), centre, composite(s - h, t - h));
            curvature = curvature.max(along_u + along_v + diagonal);
        }
    }
    2.0 * curvature / 8.0
}

/// A 1.2 m × 0.9 m sheet of 6 × 6 quads facing +z, seen from the front over a grey background.
fn front_sheet_scene() -> (SlabMesh, Camera, Background) {
    let mesh = SlabMesh::flat_sheet(
        Vec3::new(-0.6, -0.45, 0.0),
        Vec3::X * 1.2,
        Vec3::Y * 0.9,
        Vec3::Z,
        6,
        6,
    )
    .unwrap();
    (
        mesh,
        camera(Vec3::new(0.3, 0.2, 1.8)),
        Background::Uniform([0.3, 0.3, 0.3]),
    )
}

fn camera(eye: Vec3) -> Camera {
    Camera {
        eye,
        target: Vec3::ZERO,
        up: Vec3::Y,
        vertical_fov: 0.9,
        near: 0.05,
        far: 20.0,
    }
}

#[test]
fn per_fragment_matches_cpu_model_pixel_by_pixel() {
    let Some(mut renderer) = renderer(WIDTH, HEIGHT) else {
        return;
    };
    let epsilon = format_epsilon(&renderer);
    let sheet = Sheet {
        origin: DVec3::new(-0.6, -0.45, 0.0),
        u: DVec3::new(1.2, 0.0, 0.0),
        v: DVec3::new(0.0, 0.9, 0.0),
        normal: DVec3::Z,
    };
    let background = [0.21, 0.34, 0.55];
    let flux = 40.0;
    let eyes = [
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::new(1.3, 0.4, 1.1),
        Vec3::new(-0.2, -1.6, 0.7),
    ];
    let lights = [
        ("front-lit", DVec3::new(0.5, 0.7, 1.4)),
        ("back-lit", DVec3::new(-0.4, 0.3, -1.2)),
    ];
    let materials = [(0.2, 1.0), (1.0, 0.6), (3.0, 0.9)];
    let mut worst: f64 = 0.0;
    let mut worst_relative: f64 = 0.0;
    for (light_name, light) in lights {
        // "Already turned toward the light", as the renderer expects.
        let normal = if light.z > 0.0 { DVec3::Z } else { -DVec3::Z };
        let sheet = Sheet { normal, ..sheet };
        let mesh = sheet.mesh(1);
        for (case, eye) in eyes.iter().enumerate() {
            let camera = camera(*eye);
            for (material, &(tau, albedo)) in materials.iter().enumerate() {
                for convention in [
                    IrradianceConvention::NormalToBeam,
                    IrradianceConvention::PaperLiteral,
                ] {
                    if convention == IrradianceConvention::PaperLiteral && material != 1 {
                        continue; // one material suffices to exercise the switch
                    }
                    let mut shading = ShadingParams::uniform(
                        tau as f32,
                        albedo as f32,
                        light.as_vec3(),
                        flux as f32,
                    )
                    .unwrap();
                    shading.convention = convention;
                    let image = renderer
                        .render(
                            &mesh,
                            &camera,
                            &shading,
                            &Background::Uniform(background),
                            EvaluationPath::PerFragment,
                        )
                        .unwrap();
                    let eye = eye.as_dvec3();
                    let hit = |x: f64, y: f64| {
                        let (origin, direction) = camera.pixel_ray(x, y, WIDTH, HEIGHT).unwrap();
                        sheet.hit(origin, direction)
                    };
                    let (tau_f32, albedo_f32) = (f64::from(tau as f32), f64::from(albedo as f32));
                    let result = compare(
                        &image,
                        epsilon,
                        |x, y| match hit(x, y) {
                            Some(point) => {
                                let (source, alpha) = model_at(
                                    point,
                                    normal,
                                    eye,
                                    (light, flux),
                                    tau_f32,
                                    albedo_f32,
                                    convention,
                                );
                                (background.map(|b| f64::from(b) * alpha + source), alpha)
                            }
                            None => (background.map(f64::from), 1.0),
                        },
                        |x, y| u32::from(hit(x, y).is_some()),
                    );
                    assert!(
                        result.covered > 300,
                        "{light_name} view {case}: sheet covers only {} pixels",
                        result.covered
                    );
                    assert!(
                        result.compared > result.covered + 300,
                        "background barely compared"
                    );
                    worst = worst.max(result.worst_ratio);
                    worst_relative = worst_relative.max(result.worst_relative);
                }
            }
        }
    }
    println!(
        "per-fragment: worst error/tolerance {worst:.3}, worst relative error {worst_relative:e}"
    );
}

#[test]
fn background_image_is_composited_pixel_exactly() {
    let Some(mut renderer) = renderer(WIDTH, HEIGHT) else {
        return;
    };
    let epsilon = format_epsilon(&renderer);
    let sheet = Sheet {
        origin: DVec3::new(-0.5, -0.4, 0.0),
        u: DVec3::new(1.0, 0.0, 0.0),
        v: DVec3::new(0.0, 0.8, 0.0),
        normal: DVec3::Z,
    };
    let texel = |x: u32, y: u32| [0.01 * f64::from(x % 17), 0.02 * f64::from(y % 13), 0.5];
    let texels = (0..HEIGHT)
        .flat_map(|y| (0..WIDTH).map(move |x| texel(x, y).map(|c| c as f32)))
        .map(|[r, g, b]| [r, g, b, 1.0])
        .collect();
    let background = Background::Image(Texture2d::new(WIDTH, HEIGHT, texels).unwrap());
    let (light, flux, tau, albedo) = (DVec3::new(0.2, -0.3, 1.5), 25.0, 0.5, 0.8);
    let shading =
        ShadingParams::uniform(tau as f32, albedo as f32, light.as_vec3(), flux as f32).unwrap();
    let camera = camera(Vec3::new(0.3, 0.2, 1.8));
    let image = renderer
        .render(
            &sheet.mesh(1),
            &camera,
            &shading,
            &background,
            EvaluationPath::PerFragment,
        )
        .unwrap();
    let eye = camera.eye.as_dvec3();
    let hit = |x: f64, y: f64| {
        let (origin, direction) = camera.pixel_ray(x, y, WIDTH, HEIGHT).unwrap();
        sheet.hit(origin, direction)
    };
    // The background varies per pixel, so compare only the slab's own contribution through α: the
    // expected value uses this pixel's background texel (neighbour spread is taken on the model alone).
    let (tau, albedo) = (f64::from(tau as f32), f64::from(albedo as f32));
    let mut compared = 0;
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let (cx, cy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            let inside = hit(cx, cy).is_some();
            if [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
                .iter()
                .chain(&SAMPLE_OFFSETS)
                .any(|(dx, dy)| hit(cx + dx, cy + dy).is_some() != inside)
            {
                continue;
            }
            let bg = texel(x, y).map(|c| f64::from(c as f32));
            let got = image.pixel(x, y).unwrap();
            let (expected, tolerance) = match hit(cx, cy) {
                None => (bg, [0.0; 3]),
                Some(point) => {
                    let (source, alpha) = model_at(
                        point,
                        DVec3::Z,
                        eye,
                        (light, flux),
                        tau,
                        albedo,
                        IrradianceConvention::NormalToBeam,
                    );
                    let mut spread: f64 = 0.0;
                    for (dx, dy) in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)] {
                        let p = hit(cx + dx, cy + dy).unwrap();
                        let (s, a) = model_at(
                            p,
                            DVec3::Z,
                            eye,
                            (light, flux),
                            tau,
                            albedo,
                            IrradianceConvention::NormalToBeam,
                        );
                        spread = spread.max((s - source).abs()).max((a - alpha).abs());
                    }
                    // Tolerance as in `compare`: 1/8 of the neighbour spread + 64 format epsilons + 1e-7.
                    (
                        bg.map(|b| b * alpha + source),
                        bg.map(|b| {
                            spread / 8.0 * (1.0 + b) + 64.0 * epsilon * (b * alpha + source) + 1e-7
                        }),
                    )
                }
            };
            for c in 0..3 {
                let error = (f64::from(got[c]) - expected[c]).abs();
                // Outside the sheet the background is copied: exact up to the format's rounding.
                let tolerance = tolerance[c].max(epsilon * expected[c].abs());
                assert!(
                    error <= tolerance,
                    "({x},{y}) c{c}: {} vs {}",
                    got[c],
                    expected[c]
                );
            }
            compared += 1;
        }
    }
    assert!(compared > 4000);
}

#[test]
fn a_texture_beyond_the_device_limit_is_a_typed_error_and_keeps_the_last_good_one() {
    let Some(mut renderer) = renderer(WIDTH, HEIGHT) else {
        return;
    };
    let sheet = Sheet {
        origin: DVec3::new(-0.5, -0.4, 0.0),
        u: DVec3::new(1.0, 0.0, 0.0),
        v: DVec3::new(0.0, 0.8, 0.0),
        normal: DVec3::Z,
    };
    let camera = camera(Vec3::new(0.3, 0.2, 1.8));
    let background = Background::Uniform([0.2, 0.3, 0.4]);
    let good = ShadingParams::uniform(0.5, 0.8, Vec3::new(0.2, -0.3, 1.5), 25.0).unwrap();
    let render = |renderer: &mut HeadlessRenderer, shading: &ShadingParams| {
        renderer.render(
            &sheet.mesh(1),
            &camera,
            shading,
            &background,
            EvaluationPath::PerFragment,
        )
    };
    let before = render(&mut renderer, &good).unwrap();
    let max = renderer.max_texture_dimension();
    for texture in ["albedo", "thickness"] {
        let tall =
            Texture2d::new(1, max + 1, vec![[0.5, 0.5, 0.5, 1.0]; max as usize + 1]).unwrap();
        let mut shading = good.clone();
        match texture {
            "albedo" => shading.albedo_texture = tall,
            _ => shading.thickness_texture = Some(tall),
        }
        let error = render(&mut renderer, &shading).unwrap_err();
        assert!(
            matches!(error, RenderError::TextureTooLarge { texture: t, width: 1, height, max: m }
                if t == texture && height == max + 1 && m == max),
            "{error}"
        );
        assert!(error.to_string().contains(texture), "{error}");
    }
    let after = render(&mut renderer, &good).unwrap();
    assert_eq!(before.pixels, after.pixels);
}

#[test]
fn overlapping_sheets_composite_back_to_front() {
    let Some(mut renderer) = renderer(WIDTH, HEIGHT) else {
        return;
    };
    let epsilon = format_epsilon(&renderer);
    // Near sheet first in the mesh: drawn in mesh order the far sheet would wrongly cover it.
    let near = Sheet {
        origin: DVec3::new(-0.5, -0.35, 0.35),
        u: DVec3::new(0.8, 0.0, 0.0),
        v: DVec3::new(0.0, 0.6, 0.0),
        normal: DVec3::Z,
    };
    let far = Sheet {
        origin: DVec3::new(-0.3, -0.25, 0.0),
        u: DVec3::new(0.8, 0.0, 0.0),
        v: DVec3::new(0.0, 0.6, 0.0),
        normal: DVec3::Z,
    };
    let background = [0.3, 0.3, 0.3];
    let (tau, albedo, flux) = (0.7, 0.9, 30.0);
    for (name, light) in [
        ("front-lit", DVec3::new(0.3, 0.5, 1.6)),
        ("back-lit", DVec3::new(-0.2, 0.4, -1.3)),
    ] {
        let normal = if light.z > 0.0 { DVec3::Z } else { -DVec3::Z };
        let (near, far) = (Sheet { normal, ..near }, Sheet { normal, ..far });
        let mut mesh = near.mesh(2);
        mesh.append(&far.mesh(2));
        let camera = camera(Vec3::new(0.1, 0.1, 2.2));
        let shading =
            ShadingParams::uniform(tau as f32, albedo as f32, light.as_vec3(), flux as f32)
                .unwrap();
        let image = renderer
            .render(
                &mesh,
                &camera,
                &shading,
                &Background::Uniform(background),
                EvaluationPath::PerFragment,
            )
            .unwrap();
        let eye = camera.eye.as_dvec3();
        let (tau, albedo) = (f64::from(tau as f32), f64::from(albedo as f32));
        let hits = |x: f64, y: f64| {
            let (origin, direction) = camera.pixel_ray(x, y, WIDTH, HEIGHT).unwrap();
            (near.hit(origin, direction), far.hit(origin, direction))
        };
        let shade = |point: DVec3| {
            model_at(
                point,
                normal,
                eye,
                (light, flux),
                tau,
                albedo,
                IrradianceConvention::NormalToBeam,
            )
        };
        let mut order_matters: f64 = 0.0;
        let result = compare(
            &image,
            epsilon,
            |x, y| {
                let (near_hit, far_hit) = hits(x, y);
                let mut radiance = background.map(f64::from);
                let mut alpha = 1.0;
                // Eq. (9) applied far layer first, then near.
                for point in [far_hit, near_hit].into_iter().flatten() {
                    let (source, transmittance) = shade(point);
                    radiance = radiance.map(|r| r * transmittance + source);
                    alpha *= transmittance;
                }
                if let (Some(n), Some(f)) = (near_hit, far_hit) {
                    // What drawing in the wrong order would give, to show the test can fail.
                    let ((sn, an), (sf, af)) = (shade(n), shade(f));
                    let wrong = (f64::from(background[0]) * an + sn) * af + sf;
                    order_matters = order_matters.max((wrong - radiance[0]).abs() / radiance[0]);
                }
                (radiance, alpha)
            },
            |x, y| {
                let (n, f) = hits(x, y);
                u32::from(n.is_some()) + 2 * u32::from(f.is_some())
            },
        );
        assert!(result.covered > 400, "{name}: covered {}", result.covered);
        assert!(
            order_matters > 0.05,
            "{name}: scene does not distinguish draw orders ({order_matters})"
        );
        println!(
            "{name}: wrong order would differ by up to {:.1} %, worst error/tolerance {:.3}",
            100.0 * order_matters,
            result.worst_ratio
        );
    }
}

#[test]
fn per_vertex_and_cpu_paths_agree_with_per_fragment_on_a_fine_sheet() {
    let (width, height) = (128, 96);
    let Some(mut renderer) = renderer(width, height) else {
        return;
    };
    let epsilon = format_epsilon(&renderer);
    let segments = 48;
    let sheet = Sheet {
        origin: DVec3::new(-0.6, -0.45, 0.0),
        u: DVec3::new(1.2, 0.0, 0.1),
        v: DVec3::new(0.0, 0.9, -0.05),
        normal: DVec3::new(1.2, 0.0, 0.1)
            .cross(DVec3::new(0.0, 0.9, -0.05))
            .normalize(),
    };
    let camera = camera(Vec3::new(0.4, 0.3, 1.7));
    let background_radiance = [0.25, 0.2, 0.15];
    let background = Background::Uniform(background_radiance);
    for (name, light) in [
        ("front-lit", Vec3::new(0.5, 0.6, 1.2)),
        ("back-lit", Vec3::new(-0.3, 0.2, -1.1)),
    ] {
        let normal = if light.z > 0.0 {
            sheet.normal
        } else {
            -sheet.normal
        };
        let mesh = Sheet { normal, ..sheet }.mesh(segments);
        // Thickness texture: a smooth ramp in u (the weave/bump-map idea), exercised by all three paths.
        let thickness = Texture2d::new(
            8,
            1,
            (0..8)
                .map(|i| [0.5 + 0.125 * i as f32, 0.0, 0.0, 1.0])
                .collect(),
        )
        .unwrap();
        let mut shading = ShadingParams::uniform(1.2, 0.85, light, 30.0).unwrap();
        shading.thickness_texture = Some(thickness);
        let fragment = renderer
            .render(
                &mesh,
                &camera,
                &shading,
                &background,
                EvaluationPath::PerFragment,
            )
            .unwrap();
        let vertex = renderer
            .render(
                &mesh,
                &camera,
                &shading,
                &background,
                EvaluationPath::PerVertex,
            )
            .unwrap();
        let cpu = renderer
            .render(&mesh, &camera, &shading, &background, EvaluationPath::Cpu)
            .unwrap();

        // Interpolation-error bound for linear interpolation over a triangle of edge h: (h²/8)·|f''|
        // per direction. Second differences of the CPU model at the vertex spacing estimate h²·f''
        // along u, v and the diagonal; the bound used is their sum / 8, times 2 for safety, on the
        // composite (background·α + L) of each channel.
        let eye = camera.eye.as_dvec3();
        let composite = |s: f64, t: f64| {
            let point = sheet.origin + s * sheet.u + t * sheet.v;
            let uv = [s as f32, t as f32];
            let tau = sheer_slab::render::optical_thickness_at(&shading, uv);
            let (radiance, alpha) =
                slab_values_at(point, normal, tau, [1.0; 3], eye, &shading).unwrap();
            // Λ = 0.85 (f32) times L per unit albedo, over the background, per channel.
            let albedo = f64::from(0.85f32);
            [0, 1, 2].map(|c| f64::from(background_radiance[c]) * alpha[c] + albedo * radiance[c])
        };
        let interpolation_tolerance = interpolation_bound(segments, composite);
        let mut worst_vertex: f64 = 0.0;
        let mut worst_cpu_vs_vertex: f64 = 0.0;
        let mut compared = 0;
        for (index, ((f, v), c)) in fragment
            .pixels
            .iter()
            .zip(&vertex.pixels)
            .zip(&cpu.pixels)
            .enumerate()
        {
            for channel in 0..3 {
                let (f, v, c) = (
                    f64::from(f[channel]),
                    f64::from(v[channel]),
                    f64::from(c[channel]),
                );
                let difference = (v - f).abs();
                worst_vertex = worst_vertex.max(difference);
                assert!(
                    difference <= interpolation_tolerance + 64.0 * epsilon * f.abs() + 1e-7,
                    "{name} pixel {index}: per-vertex {v} vs per-fragment {f} (bound {interpolation_tolerance:e})"
                );
                // The CPU path interpolates the same per-vertex quantities computed in f64 instead of f32,
                // and samples the half-float thickness texture bilinearly in f64 where the GPU uses its
                // 8-bit sub-texel weights (lavapipe): the thickness differs by ≤ 2^-8 of a texel step
                // (0.125·1.2/256 ≈ 6e-4 in τ1), i.e. ≤ 6e-4·|∂L/∂τ1| ≤ 6e-4·L/τ1 relative. 1e-3 relative
                // plus 64 ε covers both.
                let cpu_difference = (c - v).abs();
                worst_cpu_vs_vertex = worst_cpu_vs_vertex.max(cpu_difference / v.abs().max(1e-7));
                assert!(
                    cpu_difference <= 1e-3 * v.abs() + 64.0 * epsilon * v.abs() + 1e-7,
                    "{name} pixel {index}: CPU path {c} vs per-vertex {v}"
                );
            }
            compared += 1;
        }
        assert_eq!(compared, (width * height) as usize);
        println!(
            "{name}: per-vertex vs per-fragment worst {worst_vertex:e} (bound {interpolation_tolerance:e}); \
             CPU vs per-vertex worst relative {worst_cpu_vs_vertex:e}"
        );
    }
}

#[test]
fn per_channel_optical_thickness_blends_per_channel() {
    let Some(mut renderer) = renderer(WIDTH, HEIGHT) else {
        return;
    };
    let epsilon = format_epsilon(&renderer);
    let sheet = Sheet {
        origin: DVec3::new(-0.6, -0.45, 0.0),
        u: DVec3::new(1.2, 0.0, 0.0),
        v: DVec3::new(0.0, 0.9, 0.0),
        normal: -DVec3::Z,
    };
    let (light, flux) = (DVec3::new(0.3, -0.2, -1.4), 35.0);
    let taus = [0.3f32, 1.0, 2.5];
    let albedos = [0.9f32, 0.6, 0.3];
    let mut shading = ShadingParams::uniform(1.0, 1.0, light.as_vec3(), flux as f32).unwrap();
    shading.optical_thickness = taus;
    shading.albedo_scale = albedos;
    let camera = camera(Vec3::new(0.2, 0.3, 1.9));
    let background = [0.4f32, 0.5, 0.6];
    let result = renderer.render(
        &sheet.mesh(1),
        &camera,
        &shading,
        &Background::Uniform(background),
        EvaluationPath::PerFragment,
    );
    if !renderer.supports_per_channel_optical_thickness() {
        assert!(matches!(
            result,
            Err(RenderError::PerChannelAlphaUnsupported)
        ));
        eprintln!("adapter has no dual-source blending: per-channel tau1 correctly refused");
        return;
    }
    let image = result.unwrap();
    let eye = camera.eye.as_dvec3();
    let hit = |x: f64, y: f64| {
        let (origin, direction) = camera.pixel_ray(x, y, WIDTH, HEIGHT).unwrap();
        sheet.hit(origin, direction)
    };
    let comparison = compare(
        &image,
        epsilon,
        |x, y| match hit(x, y) {
            Some(point) => {
                let mut rgb = [0.0; 3];
                let mut alpha_mean = 0.0;
                for c in 0..3 {
                    let (source, alpha) = model_at(
                        point,
                        sheet.normal,
                        eye,
                        (light, flux),
                        f64::from(taus[c]),
                        f64::from(albedos[c]),
                        IrradianceConvention::NormalToBeam,
                    );
                    rgb[c] = f64::from(background[c]) * alpha + source;
                    alpha_mean += alpha / 3.0;
                }
                (rgb, alpha_mean)
            }
            None => (background.map(f64::from), 1.0),
        },
        |x, y| u32::from(hit(x, y).is_some()),
    );
    assert!(comparison.covered > 300);
    println!(
        "per-channel tau1: worst relative error {:e}",
        comparison.worst_relative
    );
}

/// Relative error bound of the f32 all-orders lookup against the CPU sampler on the multiply-scattered
/// part (`tests/all_orders.rs::wgsl_lookup_matches_the_cpu_sampler` derives 8.7e-5 for the shipped
/// table and observes 3.7e-6).
const LOOKUP_RELATIVE_TOLERANCE: f64 = 8.7e-5;

fn all_orders() -> Scattering {
    Scattering::AllOrders(load_all_orders_table(default_table_path()).expect("the shipped table"))
}

#[test]
fn all_orders_per_fragment_matches_cpu_model_pixel_by_pixel() {
    let Some(mut renderer) = renderer(WIDTH, HEIGHT) else {
        return;
    };
    let epsilon = format_epsilon(&renderer);
    let scattering = all_orders();
    let sheet = Sheet {
        origin: DVec3::new(-0.6, -0.45, 0.0),
        u: DVec3::new(1.2, 0.0, 0.0),
        v: DVec3::new(0.0, 0.9, 0.0),
        normal: DVec3::Z,
    };
    let background = [0.21, 0.34, 0.55];
    let flux = 40.0;
    let eyes = [Vec3::new(0.0, 0.0, 2.0), Vec3::new(1.3, 0.4, 1.1)];
    let lights = [
        ("front-lit", DVec3::new(0.5, 0.7, 1.4)),
        ("back-lit", DVec3::new(-0.4, 0.3, -1.2)),
    ];
    // Thin, the paper's τ1 = 2, thick; Λ from conservative to strongly absorbing.
    let materials = [(0.05, 1.0), (2.0, 0.9), (6.0, 0.5)];
    let (mut worst, mut worst_relative, mut largest_multiple_share) = (0.0f64, 0.0f64, 0.0f64);
    for (light_name, light) in lights {
        let normal = if light.z > 0.0 { DVec3::Z } else { -DVec3::Z };
        let sheet = Sheet { normal, ..sheet };
        let mesh = sheet.mesh(1);
        for (case, eye) in eyes.iter().enumerate() {
            let camera = camera(*eye);
            for (material, &(tau, albedo)) in materials.iter().enumerate() {
                let convention = if material == 1 && case == 1 {
                    IrradianceConvention::PaperLiteral
                } else {
                    IrradianceConvention::NormalToBeam
                };
                let mut shading =
                    ShadingParams::uniform(tau as f32, albedo as f32, light.as_vec3(), flux as f32)
                        .unwrap();
                shading.convention = convention;
                shading.scattering = scattering.clone();
                shading.all_orders_sampling = AllOrdersSampling::PerFragment;
                let image = renderer
                    .render(
                        &mesh,
                        &camera,
                        &shading,
                        &Background::Uniform(background),
                        EvaluationPath::PerFragment,
                    )
                    .unwrap();
                let eye = eye.as_dvec3();
                let hit = |x: f64, y: f64| {
                    let (origin, direction) = camera.pixel_ray(x, y, WIDTH, HEIGHT).unwrap();
                    sheet.hit(origin, direction)
                };
                let (tau_f32, albedo_f32) = (f64::from(tau as f32), f64::from(albedo as f32));
                let result = compare_with_slack(
                    &image,
                    epsilon,
                    |x, y| match hit(x, y) {
                        Some(point) => {
                            let (source, alpha, multiple) = model_at_with(
                                &scattering,
                                point,
                                normal,
                                eye,
                                (light, flux),
                                tau_f32,
                                albedo_f32,
                                convention,
                            );
                            largest_multiple_share = largest_multiple_share.max(multiple / source);
                            (
                                background.map(|b| f64::from(b) * alpha + source),
                                alpha,
                                [LOOKUP_RELATIVE_TOLERANCE * multiple; 3],
                            )
                        }
                        None => (background.map(f64::from), 1.0, [0.0; 3]),
                    },
                    |x, y| u32::from(hit(x, y).is_some()),
                );
                assert!(
                    result.covered > 300,
                    "{light_name} view {case}: sheet covers only {} pixels",
                    result.covered
                );
                worst = worst.max(result.worst_ratio);
                worst_relative = worst_relative.max(result.worst_relative);
            }
        }
    }
    // The comparison has power: multiple scattering is a large part of what is compared.
    assert!(largest_multiple_share > 0.3, "{largest_multiple_share}");
    println!(
        "all-orders per-fragment: worst error/tolerance {worst:.3}, worst relative error \
         {worst_relative:e}; multiple scattering up to {:.0} % of the slab's radiance",
        100.0 * largest_multiple_share
    );
}

#[test]
fn all_orders_per_vertex_and_cpu_paths_agree_with_per_fragment_on_a_fine_sheet() {
    let (width, height) = (128, 96);
    let Some(mut renderer) = renderer(width, height) else {
        return;
    };
    let epsilon = format_epsilon(&renderer);
    let segments = 48;
    let sheet = Sheet {
        origin: DVec3::new(-0.6, -0.45, 0.0),
        u: DVec3::new(1.2, 0.0, 0.1),
        v: DVec3::new(0.0, 0.9, -0.05),
        normal: DVec3::new(1.2, 0.0, 0.1)
            .cross(DVec3::new(0.0, 0.9, -0.05))
            .normalize(),
    };
    let camera = camera(Vec3::new(0.4, 0.3, 1.7));
    let background_radiance = [0.25, 0.2, 0.15];
    let background = Background::Uniform(background_radiance);
    // Thickness ramp in u, albedo ramp in v with different channels: τ1 and Λ vary per vertex, and Λ
    // per channel, which the all-orders part needs at each vertex.
    let thickness = Texture2d::new(
        8,
        1,
        (0..8)
            .map(|i| [0.5 + 0.125 * i as f32, 0.0, 0.0, 1.0])
            .collect(),
    )
    .unwrap();
    let albedo_texture = Texture2d::new(
        1,
        8,
        (0..8)
            .map(|i| {
                let a = 0.55 + 0.06 * i as f32;
                [a, 0.9 * a, 0.7 * a, 1.0]
            })
            .collect(),
    )
    .unwrap();
    for (name, light) in [
        ("front-lit", Vec3::new(0.5, 0.6, 1.2)),
        ("back-lit", Vec3::new(-0.3, 0.2, -1.1)),
    ] {
        let normal = if light.z > 0.0 {
            sheet.normal
        } else {
            -sheet.normal
        };
        let mesh = Sheet { normal, ..sheet }.mesh(segments);
        let mut shading = ShadingParams::uniform(1.2, 1.0, light, 30.0).unwrap();
        shading.thickness_texture = Some(thickness.clone());
        shading.albedo_texture = albedo_texture.clone();
        shading.scattering = all_orders();
        shading.all_orders_sampling = AllOrdersSampling::PerFragment;
        let render = |renderer: &mut HeadlessRenderer, path| {
            renderer
                .render(&mesh, &camera, &shading, &background, path)
                .unwrap()
        };
        let fragment = render(&mut renderer, EvaluationPath::PerFragment);
        let vertex = render(&mut renderer, EvaluationPath::PerVertex);
        let cpu = render(&mut renderer, EvaluationPath::Cpu);
        let table_per_vertex = ShadingParams {
            all_orders_sampling: AllOrdersSampling::PerVertex,
            ..shading.clone()
        };
        let hybrid = renderer
            .render(
                &mesh,
                &camera,
                &table_per_vertex,
                &background,
                EvaluationPath::PerFragment,
            )
            .unwrap();
        let (worst_hybrid, hybrid_bound) = assert_table_per_vertex_interpolates(
            &fragment,
            &hybrid,
            &Sheet { normal, ..sheet },
            segments,
            &shading,
            camera.eye.as_dvec3(),
            epsilon,
        );

        // What the per-vertex paths interpolate: G = L/Λ (with the vertex's Λ) and α, from the CPU
        // model at (s, t); the fragment multiplies G by its own Λ ≤ Λ_max.
        let eye = camera.eye.as_dvec3();
        let values = |s: f64, t: f64, tau_scale: f64, albedo_shift: f64| {
            let point = sheet.origin + s * sheet.u + t * sheet.v;
            let uv = [s as f32, t as f32];
            let tau = sheer_slab::render::optical_thickness_at(&shading, uv).map(|v| v * tau_scale);
            let albedo = sheer_slab::render::albedo_at(&shading, uv).map(|v| v + albedo_shift);
            slab_values_at(point, normal, tau, albedo, eye, &shading).unwrap()
        };
        let albedo_max = f64::from(0.55f32 + 0.06 * 7.0);
        // Linear interpolation over a triangle of edge h errs by ≤ (h²/8)|f''| per direction; second
        // differences at the vertex spacing estimate h² f'' along u, v and the diagonal; ×2 for safety.
        let h = 1.0 / f64::from(segments);
        let second = |f: &dyn Fn(f64, f64) -> [f64; 3], s: f64, t: f64| {
            let centre = f(s, t);
            [(h, 0.0), (0.0, h), (h, h)]
                .iter()
                .map(|&(ds, dt)| {
                    let (plus, minus) = (f(s + ds, t + dt), f(s - ds, t - dt));
                    (0..3)
                        .map(|c| (plus[c] - 2.0 * centre[c] + minus[c]).abs())
                        .fold(0.0, f64::max)
                })
                .sum::<f64>()
        };
        let radiance = |s: f64, t: f64| values(s, t, 1.0, 0.0).0;
        let alpha = |s: f64, t: f64| values(s, t, 1.0, 0.0).1;
        let (mut curvature, mut sensitivity) = (0.0f64, 0.0f64);
        for i in 1..segments {
            for j in 1..segments {
                let (s, t) = (f64::from(i) * h, f64::from(j) * h);
                let background_max = background_radiance.iter().copied().fold(0.0f32, f32::max);
                curvature = curvature.max(
                    albedo_max * second(&radiance, s, t)
                        + f64::from(background_max) * second(&alpha, s, t),
                );
                // The GPU samples both textures with 8-bit sub-texel weights (lavapipe), the CPU path
                // exactly: τ1 may differ by 2^-8 of its texel step (0.125 of τ1), Λ by 2^-8 of 0.06.
                // Relative change of G over those differences, by central differences on the CPU.
                let base = radiance(s, t);
                let dtau = 0.125 / 256.0;
                let (up, down) = (
                    values(s, t, 1.0 + dtau, 0.0).0,
                    values(s, t, 1.0 - dtau, 0.0).0,
                );
                let dalbedo = 0.06 / 256.0;
                let (more, less) = (values(s, t, 1.0, dalbedo).0, values(s, t, 1.0, -dalbedo).0);
                for c in 0..3 {
                    let change = 0.5 * ((up[c] - down[c]).abs() + (more[c] - less[c]).abs());
                    sensitivity = sensitivity.max(change / base[c].max(1e-12));
                }
            }
        }
        let interpolation_tolerance = 2.0 * curvature / 8.0;
        // Both GPU paths look the table up in f32 (≤ LOOKUP_RELATIVE_TOLERANCE each); the CPU path in f64.
        let relative_vertex = 2.0 * LOOKUP_RELATIVE_TOLERANCE + 64.0 * epsilon;
        let relative_cpu = 2.0 * sensitivity + LOOKUP_RELATIVE_TOLERANCE + 64.0 * epsilon;
        let (mut worst_vertex, mut worst_cpu) = (0.0f64, 0.0f64);
        for (index, ((f, v), c)) in fragment
            .pixels
            .iter()
            .zip(&vertex.pixels)
            .zip(&cpu.pixels)
            .enumerate()
        {
            for channel in 0..3 {
                let (f, v, c) = (
                    f64::from(f[channel]),
                    f64::from(v[channel]),
                    f64::from(c[channel]),
                );
                let difference = (v - f).abs();
                worst_vertex = worst_vertex.max(difference);
                assert!(
                    difference <= interpolation_tolerance + relative_vertex * f.abs() + 1e-7,
                    "{name} pixel {index}: per-vertex {v} vs per-fragment {f} \
                     (bound {interpolation_tolerance:e})"
                );
                let cpu_difference = (c - v).abs();
                worst_cpu = worst_cpu.max(cpu_difference / v.abs().max(1e-7));
                assert!(
                    cpu_difference <= relative_cpu * v.abs() + 1e-7,
                    "{name} pixel {index}: CPU path {c} vs per-vertex {v} (bound {relative_cpu:e})"
                );
            }
        }
        println!(
            "all-orders {name}: per-vertex vs per-fragment worst {worst_vertex:e} (bound \
             {interpolation_tolerance:e}); CPU vs per-vertex worst relative {worst_cpu:e} (bound \
             {relative_cpu:e}); per fragment with the table per vertex vs per fragment worst \
             {worst_hybrid:e} (bound {hybrid_bound:e})"
        );
    }
}

/// The per-fragment path with the table looked up per vertex (`AllOrdersSampling::PerVertex`, image
/// `per_vertex`) against the same path with the table per fragment (`exact`), on a sheet of
/// `segments` × `segments` quads. They differ only in the table's reduced value f = L_m/(Λ²·μ0·E),
/// which the first interpolates linearly over each triangle and then multiplies by the fragment's
/// Λ²·μ0·E: so per pixel by at most max(Λ²·μ0·E) times the interpolation error of f, bounded as in the
/// per-vertex test by (h²/8)|f''| per direction from second differences at the vertex spacing, ×2, plus
/// both lookups' f32 tolerance. Returns (worst difference, bound).
fn assert_table_per_vertex_interpolates(
    exact: &LinearImage,
    per_vertex: &LinearImage,
    sheet: &Sheet,
    segments: u32,
    shading: &ShadingParams,
    eye: DVec3,
    epsilon: f64,
) -> (f64, f64) {
    let single = ShadingParams {
        scattering: Scattering::Single,
        ..shading.clone()
    };
    let light = shading.light_position.as_dvec3();
    // (f per channel, Λ²·μ0·E per channel) at sheet coordinates (s, t); slab_values_at gives L/Λ.
    let multiple = |s: f64, t: f64| {
        let point = sheet.origin + s * sheet.u + t * sheet.v;
        let uv = [s as f32, t as f32];
        let tau = sheer_slab::render::optical_thickness_at(shading, uv);
        let albedo = sheer_slab::render::albedo_at(shading, uv);
        let all = slab_values_at(point, sheet.normal, tau, albedo, eye, shading)
            .unwrap()
            .0;
        let one = slab_values_at(point, sheet.normal, tau, albedo, eye, &single)
            .unwrap()
            .0;
        let mu0 = sheer_normals::lit_side_cosines(sheet.normal, light - point, eye - point)
            .unwrap()
            .mu0;
        let irradiance = point_light_beam_normal_irradiance(
            f64::from(shading.light_flux),
            light.distance(point),
        )
        .unwrap();
        (
            std::array::from_fn::<f64, 3, _>(|c| {
                (all[c] - one[c]) / (albedo[c] * mu0 * irradiance)
            }),
            std::array::from_fn::<f64, 3, _>(|c| albedo[c] * albedo[c] * mu0 * irradiance),
        )
    };
    let h = 1.0 / f64::from(segments);
    let (mut curvature, mut largest_weight) = (0.0f64, 0.0f64);
    for i in 1..segments {
        for j in 1..segments {
            let (s, t) = (f64::from(i) * h, f64::from(j) * h);
            let (centre, weight) = multiple(s, t);
            for (ds, dt) in [(h, 0.0), (0.0, h), (h, h)] {
                let (plus, minus) = (multiple(s + ds, t + dt).0, multiple(s - ds, t - dt).0);
                for c in 0..3 {
                    curvature = curvature.max((plus[c] - 2.0 * centre[c] + minus[c]).abs() * 3.0);
                }
            }
            largest_weight = largest_weight.max(weight.into_iter().fold(0.0, f64::max));
        }
    }
    let bound = largest_weight * 2.0 * curvature / 8.0;
    let relative = 2.0 * LOOKUP_RELATIVE_TOLERANCE + 64.0 * epsilon;
    let mut worst = 0.0f64;
    for (index, (e, v)) in exact.pixels.iter().zip(&per_vertex.pixels).enumerate() {
        assert_eq!(e[3], v[3], "pixel {index}: α is per fragment on both");
        for channel in 0..3 {
            let (e, v) = (f64::from(e[channel]), f64::from(v[channel]));
            worst = worst.max((v - e).abs());
            assert!(
                (v - e).abs() <= bound + relative * e.abs() + 1e-7,
                "pixel {index}: table per vertex {v} vs per fragment {e} (bound {bound:e})"
            );
        }
    }
    // The two differ at all (the compute pass ran and the interpolation is visible), but only a little.
    assert!(
        worst > 0.0,
        "the table-per-vertex render equals the per-fragment one exactly"
    );
    (worst, bound)
}

#[test]
fn single_scattering_renders_the_same_after_all_orders_frames() {
    let Some(mut renderer) = renderer(WIDTH, HEIGHT) else {
        return;
    };
    let (mesh, camera, background) = front_sheet_scene();
    let single = ShadingParams::uniform(2.0, 0.9, Vec3::new(0.4, 0.5, 1.3), 40.0).unwrap();
    let all = ShadingParams {
        scattering: all_orders(),
        ..single.clone()
    };
    // Multiple scattering only adds light, by more than 5 % in every covered pixel.
    assert_adds_light_and_leaves_the_rest(
        &mut renderer,
        (&mesh, &camera, &background),
        &single,
        &all,
        1.05,
    );
    // The table is uploaded once and kept: the same Arc renders without re-uploading (no observable
    // difference other than speed), and a second, equal table also renders the same image.
    let again = ShadingParams {
        scattering: Scattering::AllOrders(Arc::new(
            load_all_orders_table(default_table_path())
                .unwrap()
                .as_ref()
                .clone(),
        )),
        ..single.clone()
    };
    let first = renderer
        .render(
            &mesh,
            &camera,
            &all,
            &background,
            EvaluationPath::PerFragment,
        )
        .unwrap();
    let second = renderer
        .render(
            &mesh,
            &camera,
            &again,
            &background,
            EvaluationPath::PerFragment,
        )
        .unwrap();
    assert_eq!(first, second);
}

#[test]
fn all_orders_per_channel_optical_thickness() {
    let Some(mut renderer) = renderer(WIDTH, HEIGHT) else {
        return;
    };
    if !renderer.supports_per_channel_optical_thickness() {
        eprintln!(
            "adapter has no dual-source blending: per-channel tau1 is refused (tested above)"
        );
        return;
    }
    let epsilon = format_epsilon(&renderer);
    let scattering = all_orders();
    let sheet = Sheet {
        origin: DVec3::new(-0.6, -0.45, 0.0),
        u: DVec3::new(1.2, 0.0, 0.0),
        v: DVec3::new(0.0, 0.9, 0.0),
        normal: -DVec3::Z,
    };
    let (light, flux) = (DVec3::new(0.3, -0.2, -1.4), 35.0);
    let taus = [0.3f32, 1.0, 2.5];
    let albedos = [0.9f32, 0.6, 0.99];
    let mut shading = ShadingParams::uniform(1.0, 1.0, light.as_vec3(), flux as f32).unwrap();
    shading.optical_thickness = taus;
    shading.albedo_scale = albedos;
    shading.scattering = scattering.clone();
    shading.all_orders_sampling = AllOrdersSampling::PerFragment;
    let camera = camera(Vec3::new(0.2, 0.3, 1.9));
    let background = [0.4f32, 0.5, 0.6];
    let image = renderer
        .render(
            &sheet.mesh(1),
            &camera,
            &shading,
            &Background::Uniform(background),
            EvaluationPath::PerFragment,
        )
        .unwrap();
    let eye = camera.eye.as_dvec3();
    let hit = |x: f64, y: f64| {
        let (origin, direction) = camera.pixel_ray(x, y, WIDTH, HEIGHT).unwrap();
        sheet.hit(origin, direction)
    };
    let comparison = compare_with_slack(
        &image,
        epsilon,
        |x, y| match hit(x, y) {
            Some(point) => {
                let (mut rgb, mut slack) = ([0.0; 3], [0.0; 3]);
                let mut alpha_mean = 0.0;
                for c in 0..3 {
                    let (source, alpha, multiple) = model_at_with(
                        &scattering,
                        point,
                        sheet.normal,
                        eye,
                        (light, flux),
                        f64::from(taus[c]),
                        f64::from(albedos[c]),
                        IrradianceConvention::NormalToBeam,
                    );
                    rgb[c] = f64::from(background[c]) * alpha + source;
                    slack[c] = LOOKUP_RELATIVE_TOLERANCE * multiple;
                    alpha_mean += alpha / 3.0;
                }
                (rgb, alpha_mean, slack)
            }
            None => (background.map(f64::from), 1.0, [0.0; 3]),
        },
        |x, y| u32::from(hit(x, y).is_some()),
    );
    assert!(comparison.covered > 300);
    // The same with the table per vertex (the compute pass's per-channel variant), on a mesh fine
    // enough for the interpolation to be accurate.
    let segments = 24;
    let fine = sheet.mesh(segments);
    let table_per_vertex = ShadingParams {
        all_orders_sampling: AllOrdersSampling::PerVertex,
        ..shading.clone()
    };
    let render = |renderer: &mut HeadlessRenderer, shading: &ShadingParams| {
        renderer
            .render(
                &fine,
                &camera,
                shading,
                &Background::Uniform(background),
                EvaluationPath::PerFragment,
            )
            .unwrap()
    };
    let exact = render(&mut renderer, &shading);
    let hybrid = render(&mut renderer, &table_per_vertex);
    let (worst, bound) = assert_table_per_vertex_interpolates(
        &exact, &hybrid, &sheet, segments, &shading, eye, epsilon,
    );
    println!(
        "all-orders per-channel tau1: worst relative error {:e}; table per vertex vs per fragment \
         worst {worst:e} (bound {bound:e})",
        comparison.worst_relative
    );
}

/// A light of enormous flux right at the sheet overflows the target's floats: that is a typed error
/// naming the pixel, not an image with infinite, NaN or saturated (`f32::MAX`, as NVIDIA's driver
/// writes an overflow) pixels; and a camera that defines no view is
/// refused before anything is drawn (it rendered only the background).
#[test]
fn overflowing_radiance_and_a_viewless_camera_are_typed_errors() {
    let Some(mut renderer) = renderer(16, 16) else {
        return;
    };
    let mesh =
        SlabMesh::flat_sheet(Vec3::new(-0.5, -0.5, 0.0), Vec3::X, Vec3::Y, Vec3::Z, 2, 2).unwrap();
    let view = camera(Vec3::new(0.0, 0.0, 2.0));
    for path in [
        EvaluationPath::PerFragment,
        EvaluationPath::PerVertex,
        EvaluationPath::Cpu,
    ] {
        let shading = ShadingParams::uniform(1.0, 0.9, Vec3::new(0.0, 0.0, 1e-3), 3e38).unwrap();
        match renderer.render(
            &mesh,
            &view,
            &shading,
            &Background::Uniform([0.1, 0.1, 0.1]),
            path,
        ) {
            Err(RenderError::OverflowedPixel {
                x,
                y,
                value,
                format,
            }) => {
                // Infinity on lavapipe, the format's largest finite value on NVIDIA's driver.
                assert!(
                    x < 16 && y < 16 && (value.is_nan() || value.abs() >= format.largest_finite()),
                    "{path:?}: {value}"
                );
            }
            other => panic!("{path:?}: expected an overflowed pixel error, got {other:?}"),
        }
        // The same scene with an ordinary light renders, finite everywhere.
        let shading = ShadingParams::uniform(1.0, 0.9, Vec3::new(0.0, 0.0, 1.0), 40.0).unwrap();
        let image = renderer
            .render(
                &mesh,
                &view,
                &shading,
                &Background::Uniform([0.1, 0.1, 0.1]),
                path,
            )
            .unwrap();
        assert!(image.pixels.iter().flatten().all(|c| c.is_finite()));
        let mut viewless = view;
        viewless.target = viewless.eye;
        assert!(matches!(
            renderer.render(
                &mesh,
                &viewless,
                &shading,
                &Background::Uniform([0.1, 0.1, 0.1]),
                path,
            ),
            Err(RenderError::Camera(
                sheer_slab::render::CameraError::EyeAtTarget(_)
            ))
        ));
    }
}

/// Sky light (sheer_slab::sky) from the shipped diffuse table: a blue sky and a green ground.
fn daylight() -> sheer_slab::SkyLight {
    sheer_slab::SkyLight {
        environment: sheer_slab::DiffuseEnvironment::sky_and_ground(
            [0.43, 0.54, 0.59],
            [0.2, 0.26, 0.31],
        )
        .unwrap(),
        table: sheer_slab::load_diffuse_table(sheer_slab::DiffuseTable::DEFAULT_PATH)
            .expect("the shipped diffuse table"),
    }
}

/// Sky light from an equirectangular image with light from every side: a sky brighter towards +x and
/// −z, a sun-like bright patch, a darker ground: every one of the nine coefficients non-zero.
fn structured_daylight() -> sheer_slab::SkyLight {
    let (width, height) = (32u32, 17u32);
    let texels = (0..height)
        .flat_map(|row| {
            (0..width).map(move |column| {
                let (u, v) = (
                    (column as f32 + 0.5) / width as f32,
                    (row as f32 + 0.5) / height as f32,
                );
                let sun = if (u - 0.3).abs() < 0.07 && (v - 0.25).abs() < 0.1 {
                    6.0
                } else {
                    0.0
                };
                let sky = if v < 0.5 {
                    0.4 + 0.5 * u
                } else {
                    0.1 + 0.1 * u
                };
                [sky + sun, 0.8 * sky + sun, 0.6 * sky + 0.5 * sun, 1.0]
            })
        })
        .collect();
    let image = Texture2d::new(width, height, texels).unwrap();
    sheer_slab::SkyLight {
        environment: sheer_slab::DiffuseEnvironment::from_equirectangular(&image, 1.0).unwrap(),
        table: sheer_slab::load_diffuse_table(sheer_slab::DiffuseTable::DEFAULT_PATH)
            .expect("the shipped diffuse table"),
    }
}

/// A sheet under sky light alone (no point light), and under sky light plus the point light, with
/// either scattering model: the per-fragment path against the CPU model (`slab_values_at`, f64)
/// pixel by pixel with the tolerances of the point-light tests, the diffuse lookup's f32 error
/// (the all-orders lookup's bound: the same axes and operations, one interpolation stage fewer) on the
/// sky's part; then the per-vertex and CPU paths against per-fragment on a fine sheet with the
/// interpolation bound of `per_vertex_and_cpu_paths_agree_with_per_fragment_on_a_fine_sheet`.
#[test]
fn sky_light_matches_the_cpu_model_on_every_path() {
    let (width, height) = (128, 96);
    let Some(mut renderer) = renderer(width, height) else {
        return;
    };
    let epsilon = format_epsilon(&renderer);
    let background = [0.21, 0.34, 0.55];
    // Tilted, so that the sky and the ground light the two faces differently.
    let sheet = Sheet {
        origin: DVec3::new(-0.6, -0.45, 0.1),
        u: DVec3::new(1.2, 0.0, 0.1),
        v: DVec3::new(0.0, 0.9, -0.35),
        normal: DVec3::new(1.2, 0.0, 0.1)
            .cross(DVec3::new(0.0, 0.9, -0.35))
            .normalize(),
    };
    let eyes = [Vec3::new(0.3, 0.2, 1.8), Vec3::new(-0.5, -0.6, -1.6)];
    let mut largest_sky_share = 0.0f64;
    // Grey and coloured Λ (each channel on its own albedo axis), sky and ground (bands 0–1) and an
    // environment image with light from every side (all nine coefficients).
    for (case, (flux, scattering, tau, albedo, environment)) in [
        (0.0, Scattering::Single, 2.0, [1.0; 3], daylight()),
        (40.0, all_orders(), 2.0, [0.9; 3], daylight()),
        (40.0, Scattering::Single, 0.3, [0.7; 3], daylight()),
        (
            0.0,
            all_orders(),
            1.5,
            [0.9, 0.45, 0.15],
            structured_daylight(),
        ),
        (
            40.0,
            Scattering::Single,
            2.0,
            [0.2, 0.6, 0.95],
            structured_daylight(),
        ),
    ]
    .into_iter()
    .enumerate()
    {
        for (view, eye) in eyes.iter().enumerate() {
            let camera = Camera {
                vertical_fov: 0.9,
                ..camera(*eye)
            };
            let light = Vec3::new(0.5, 0.7, 1.4);
            let mut shading = ShadingParams::uniform(tau, 1.0, light, flux).unwrap();
            shading.albedo_scale = albedo;
            shading.scattering = scattering.clone();
            shading.sky = Some(environment.clone());
            let no_sky = ShadingParams {
                sky: None,
                ..shading.clone()
            };
            let mesh = sheet.mesh(1);
            let image = renderer
                .render(
                    &mesh,
                    &camera,
                    &shading,
                    &Background::Uniform(background),
                    EvaluationPath::PerFragment,
                )
                .unwrap();
            let eye = eye.as_dvec3();
            let hit = |x: f64, y: f64| {
                let (origin, direction) = camera.pixel_ray(x, y, width, height).unwrap();
                sheet.hit(origin, direction)
            };
            let albedo = albedo.map(f64::from);
            let result = compare_with_slack(
                &image,
                epsilon,
                |x, y| match hit(x, y) {
                    Some(point) => {
                        let tau = [f64::from(tau); 3];
                        let (with, alpha) =
                            slab_values_at(point, sheet.normal, tau, albedo, eye, &shading)
                                .unwrap();
                        let (without, _) =
                            slab_values_at(point, sheet.normal, tau, albedo, eye, &no_sky).unwrap();
                        let sky = (with[0] - without[0]) * albedo[0];
                        largest_sky_share = largest_sky_share.max(sky / (with[0] * albedo[0]));
                        (
                            [0, 1, 2]
                                .map(|c| f64::from(background[c]) * alpha[c] + albedo[c] * with[c]),
                            alpha[0],
                            [0, 1, 2].map(|c| {
                                LOOKUP_RELATIVE_TOLERANCE * (with[c] - without[c]).abs() * albedo[c]
                            }),
                        )
                    }
                    None => (background.map(f64::from), 1.0, [0.0; 3]),
                },
                |x, y| u32::from(hit(x, y).is_some()),
            );
            assert!(
                result.covered > 300,
                "case {case} view {view}: {}",
                result.covered
            );
            println!(
                "sky case {case} view {view}: worst error/tolerance {:.3}, relative {:e}",
                result.worst_ratio, result.worst_relative
            );

            // The per-vertex and CPU paths on a fine sheet, against per-fragment.
            let segments = 32;
            let fine = sheet.mesh(segments);
            let render = |renderer: &mut HeadlessRenderer, path| {
                renderer
                    .render(
                        &fine,
                        &camera,
                        &shading,
                        &Background::Uniform(background),
                        path,
                    )
                    .unwrap()
            };
            let fragment = render(&mut renderer, EvaluationPath::PerFragment);
            let vertex = render(&mut renderer, EvaluationPath::PerVertex);
            let cpu = render(&mut renderer, EvaluationPath::Cpu);
            let composite = |s: f64, t: f64| {
                let point = sheet.origin + s * sheet.u + t * sheet.v;
                let (radiance, alpha) = slab_values_at(
                    point,
                    sheet.normal,
                    [f64::from(tau); 3],
                    albedo,
                    eye,
                    &shading,
                )
                .unwrap();
                [0, 1, 2].map(|c| f64::from(background[c]) * alpha[c] + albedo[c] * radiance[c])
            };
            let bound = interpolation_bound(segments, composite);
            for (index, ((f, v), c)) in fragment
                .pixels
                .iter()
                .zip(&vertex.pixels)
                .zip(&cpu.pixels)
                .enumerate()
            {
                for channel in 0..3 {
                    let (f, v, c) = (
                        f64::from(f[channel]),
                        f64::from(v[channel]),
                        f64::from(c[channel]),
                    );
                    let lookup = LOOKUP_RELATIVE_TOLERANCE * f.abs();
                    assert!(
                        (v - f).abs() <= bound + lookup + 64.0 * epsilon * f.abs() + 1e-7,
                        "case {case} view {view} pixel {index}: per-vertex {v} vs per-fragment {f} \
                         (bound {bound:e})"
                    );
                    assert!(
                        (c - v).abs() <= 2.0 * lookup + 64.0 * epsilon * v.abs() + 1e-7,
                        "case {case} view {view} pixel {index}: CPU path {c} vs per-vertex {v}"
                    );
                }
            }
        }
    }
    // The comparison has power: sky light is a large part of what is compared.
    assert!(largest_sky_share > 0.5, "{largest_sky_share}");
}

/// Sky light only adds light, and a scene without it renders exactly as before.
#[test]
fn sky_light_only_adds_light_and_off_changes_nothing() {
    let Some(mut renderer) = renderer(WIDTH, HEIGHT) else {
        return;
    };
    let (mesh, camera, background) = front_sheet_scene();
    let plain = ShadingParams::uniform(2.0, 0.9, Vec3::new(-0.4, 0.5, -1.3), 40.0).unwrap();
    let sky = ShadingParams {
        sky: Some(daylight()),
        ..plain.clone()
    };
    assert_adds_light_and_leaves_the_rest(
        &mut renderer,
        (&mesh, &camera, &background),
        &plain,
        &sky,
        1.0,
    );
}

/// On every path: rendering with `more` after `base` leaves `base`'s frames as they were (bit for
/// bit), keeps α (the direct transmission), and makes every covered pixel brighter than `factor` times
/// its `base` radiance in every channel.
fn assert_adds_light_and_leaves_the_rest(
    renderer: &mut HeadlessRenderer,
    (mesh, camera, background): (&SlabMesh, &Camera, &Background),
    base: &ShadingParams,
    more: &ShadingParams,
    factor: f32,
) {
    for path in [
        EvaluationPath::PerFragment,
        EvaluationPath::PerVertex,
        EvaluationPath::Cpu,
    ] {
        let mut render = |shading| {
            renderer
                .render(mesh, camera, shading, background, path)
                .unwrap()
        };
        let (before, with, after) = (render(base), render(more), render(base));
        assert_eq!(before, after, "{path:?}");
        let mut covered = 0;
        for (b, w) in before.pixels.iter().zip(&with.pixels) {
            assert_eq!(
                b[3], w[3],
                "{path:?}: α is the direct transmission either way"
            );
            if b[3] < 1.0 {
                covered += 1;
                for c in 0..3 {
                    assert!(w[c] > b[c] * factor, "{path:?}: {w:?} vs {b:?}");
                }
            }
        }
        assert!(covered > 300, "{path:?}: {covered}");
    }
}

/// Four samples per pixel: a pixel inside the sheet or inside the background is the one-sample
/// pixel (each sample is blended by eq. (9) alone, and the mean of equal samples is that value), while
/// pixels on the sheet's edge are blends: their transmittance α lies strictly between the sheet's and
/// the background's 1, which no one-sample pixel does.
#[test]
fn four_samples_blend_edges_and_leave_the_rest_as_it_was() {
    let Some(mut four) = renderer(WIDTH, HEIGHT) else {
        return;
    };
    let mut one = HeadlessRenderer::new(WIDTH, HEIGHT).expect("the same adapter, one sample");
    assert_eq!(four.samples(), 4);
    let sheet = Sheet {
        origin: DVec3::new(-0.6, -0.45, 0.0),
        u: DVec3::new(1.2, 0.0, 0.3),
        v: DVec3::new(0.1, 0.9, 0.0),
        normal: DVec3::new(1.2, 0.0, 0.3)
            .cross(DVec3::new(0.1, 0.9, 0.0))
            .normalize(),
    };
    let camera = camera(Vec3::new(0.3, 0.2, 1.8));
    let shading = ShadingParams::uniform(2.0, 0.9, Vec3::new(0.4, 0.5, 1.3), 40.0).unwrap();
    let background = Background::Uniform([0.3, 0.2, 0.1]);
    let mesh = sheet.mesh(4);
    let render = |renderer: &mut HeadlessRenderer| {
        renderer
            .render(
                &mesh,
                &camera,
                &shading,
                &background,
                EvaluationPath::PerFragment,
            )
            .unwrap()
    };
    let (single, multi) = (render(&mut one), render(&mut four));
    // Same format: equal but for the rasteriser's f32 interpolation of the fragment's inputs, which a
    // multisampled target computes by other operations (measured: 1 ulp; 16 ulps allowed); otherwise
    // within the coarser format's rounding.
    let tolerance = if one.target_format() == four.target_format() {
        16.0 * f32::EPSILON
    } else {
        2f32.powi(-10)
    };
    let covered = |x: f64, y: f64| {
        let (origin, direction) = camera.pixel_ray(x, y, WIDTH, HEIGHT).unwrap();
        sheet.hit(origin, direction).is_some()
    };
    let (mut interior, mut edges, mut blended) = (0, 0, 0);
    let sheet_alpha = single
        .pixels
        .iter()
        .filter(|p| p[3] < 1.0)
        .map(|p| p[3])
        .fold(0.0f32, f32::max);
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let (cx, cy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            let corners = [
                (-0.5, -0.5),
                (0.5, -0.5),
                (-0.5, 0.5),
                (0.5, 0.5),
                (0.0, 0.0),
            ]
            .map(|(dx, dy)| covered(cx + dx, cy + dy));
            let (s, m) = (single.pixel(x, y).unwrap(), multi.pixel(x, y).unwrap());
            assert!(
                s[3] == 1.0 || s[3] <= sheet_alpha,
                "one sample: pixel ({x}, {y}) is a blend, α = {}",
                s[3]
            );
            if corners.iter().all(|&c| c == corners[0]) {
                interior += 1;
                for c in 0..4 {
                    assert!(
                        (m[c] - s[c]).abs() <= tolerance * s[c].abs(),
                        "pixel ({x}, {y}) channel {c}: four samples {} vs one {}",
                        m[c],
                        s[c]
                    );
                }
            } else {
                edges += 1;
                blended += usize::from(m[3] > sheet_alpha * 1.01 && m[3] < 0.99);
            }
        }
    }
    assert!(
        interior > 3000 && edges > 100,
        "{interior} interior, {edges} edge pixels"
    );
    // Most edge pixels are partly covered by the sheet and partly by the background.
    assert!(
        blended * 2 > edges,
        "only {blended} of {edges} edge pixels are blends"
    );
    println!(
        "4× MSAA: {interior} interior pixels as before, {blended} of {edges} edge pixels blended"
    );
}
