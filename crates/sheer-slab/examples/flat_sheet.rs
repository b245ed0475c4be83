//! Renders a front-lit and a back-lit flat sheet headless (per-fragment thin slab and the baseline) over a
//! gradient background, writes PNGs to the directory given as the first argument (default `target/`),
//! and prints the CPU model's values at the sheet's centre.
//!
//! `cargo run -p sheer-slab --release --example flat_sheet -- [output-dir]`

use std::path::PathBuf;

use glam::Vec3;
use sheer_slab::model::{
    Albedo, Cosine, Face, IrradianceConvention, OpticalThickness,
    point_light_beam_normal_irradiance, slab_shading,
};
use sheer_slab::render::{
    Background, Camera, EvaluationPath, HeadlessRenderer, ShadingParams, SlabMesh, Texture2d,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let output = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "target".into()));
    std::fs::create_dir_all(&output)?;
    let (width, height) = (512, 512);
    let mut renderer = HeadlessRenderer::new(width, height)?;
    println!("adapter: {}", renderer.adapter_description());

    let camera = Camera {
        eye: Vec3::new(0.0, -0.6, 2.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        vertical_fov: 0.9,
        near: 0.1,
        far: 10.0,
    };
    // A vertical gradient (linear radiance, W/(m²·sr)) so that transparency is visible.
    let texels = (0..height)
        .flat_map(|y| {
            let t = y as f32 / (height - 1) as f32;
            (0..width).map(move |x| {
                let s = x as f32 / (width - 1) as f32;
                [0.05 + 0.25 * (1.0 - t), 0.08 + 0.2 * s, 0.3 * t + 0.05, 1.0]
            })
        })
        .collect();
    let background = Background::Image(Texture2d::new(width, height, texels)?);

    // Paper, figure 2: Λ = 1, τ1 = 2; a flag-like albedo texture (blue stripe on white).
    let albedo = Texture2d::new(
        4,
        4,
        (0..16)
            .map(|i| {
                if i / 4 == 1 || i % 4 == 1 {
                    [0.1, 0.25, 0.9, 1.0]
                } else {
                    [0.95, 0.95, 0.95, 1.0]
                }
            })
            .collect(),
    )?;
    for (name, light, normal) in [
        ("front_lit", Vec3::new(0.6, 0.8, 1.5), Vec3::Z),
        ("back_lit", Vec3::new(0.4, 0.6, -1.5), -Vec3::Z),
    ] {
        let mesh = SlabMesh::flat_sheet(
            Vec3::new(-0.6, -0.4, 0.0),
            Vec3::X * 1.2,
            Vec3::Y * 0.8,
            normal,
            24,
            16,
        )?;
        let mut shading = ShadingParams::uniform(2.0, 1.0, light, 60.0)?;
        shading.albedo_texture = albedo.clone();
        shading.exposure = 3.0;
        for path in [EvaluationPath::PerFragment, EvaluationPath::Baseline] {
            let image = renderer.render(&mesh, &camera, &shading, &background, path)?;
            let file = output.join(format!("flat_sheet_{name}_{}.png", path.name()));
            image.save_png(&file, shading.exposure)?;
            println!("wrote {}", file.display());
        }

        // The CPU model at the sheet's centre (origin), for Λ = 1.
        let to_light = light;
        let to_eye = camera.eye;
        let mu0 = normal.dot(to_light.normalize()) as f64;
        let signed_mu = normal.dot(to_eye.normalize()) as f64;
        let side = if signed_mu >= 0.0 {
            Face::Lit
        } else {
            Face::Far
        };
        let irradiance = point_light_beam_normal_irradiance(60.0, to_light.length() as f64)?;
        for convention in [
            IrradianceConvention::NormalToBeam,
            IrradianceConvention::PaperLiteral,
        ] {
            let shading = slab_shading(
                OpticalThickness::new(2.0)?,
                Albedo::new(1.0)?,
                Cosine::new("mu0", mu0)?,
                Cosine::new("mu", signed_mu.abs())?,
                side,
                irradiance,
                convention,
            )?;
            println!(
                "{name} centre ({convention:?}): mu0 = {mu0:.4}, mu = {:.4}, side = {side:?}, E_normal = {irradiance:.4} W/m^2, \
                 alpha = {:.5}, L_source = {:.5} W/(m^2 sr)",
                signed_mu.abs(),
                shading.transmittance,
                shading.source_radiance
            );
        }
    }
    Ok(())
}
