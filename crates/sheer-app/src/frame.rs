//! The case study's frame pipeline, shared by the window and the command line:
//! simulator → normals turned toward the light → thin-slab shading → a linear radiance image.
//!
//! Data flows one way: [`FlagScene`] owns the simulation and the mesh, [`FrameRenderer`] owns the GPU.

use std::time::{Duration, Instant};

use glam::Vec3;
use sheer_cloth::Simulation;
use sheer_normals::{Light, NormalUpdater};
use std::sync::{Arc, OnceLock};

use sheer_slab::render::ShadingError;
use sheer_slab::render::{
    Background, Camera, EvaluationPath, HeadlessRenderer, LinearImage, ShadingParams, SlabMesh,
    Texture2d, srgb8_to_linear,
};
use sheer_slab::{
    AllOrdersTable, DiffuseEnvironment, DiffuseTable, IrradianceConvention, SkyLight,
};

use crate::CliError;
use crate::scene::{self, AllOrdersLookup, Convention, EvaluationPathName, Scene, ShadingModel};
use crate::simulate::{flag_simulation, grid_uvs};

/// Time spent in each stage of the last frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct StageTimes {
    pub simulation: Duration,
    pub normals: Duration,
    /// Shading: per-path evaluation, uploads, GPU work and waiting for it.
    pub shading: Duration,
    /// The part of `shading` from submitting the frame to the GPU until it has finished (uploads
    /// staged before are copied then); the rest of `shading` is CPU work.
    pub gpu: Duration,
    pub readback: Duration,
}

/// The simulated flag (or the static sheet) of a scene, with its normals turned toward the light.
pub struct FlagScene {
    pub scene: Scene,
    simulation: Option<Simulation>,
    updater: NormalUpdater,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    pub mesh: SlabMesh,
    /// Frames advanced since time 0: the scene's one clock (see [`FlagScene::time`]).
    frame: u64,
}

impl FlagScene {
    pub fn new(scene: Scene) -> Result<FlagScene, CliError> {
        let (simulation, mesh) = match &scene.static_sheet {
            Some(sheet) => {
                let tilt = sheet.tilt_degrees.to_radians();
                let rotation = glam::Quat::from_rotation_x(tilt);
                let centre = Vec3::from_array(sheet.centre);
                let u_edge = rotation * Vec3::new(sheet.size[0], 0.0, 0.0);
                let v_edge = rotation * Vec3::new(0.0, sheet.size[1], 0.0);
                let mesh = SlabMesh::flat_sheet(
                    centre - 0.5 * (u_edge + v_edge),
                    u_edge,
                    v_edge,
                    rotation * Vec3::Z,
                    sheet.segments,
                    sheet.segments,
                )
                .map_err(|e| CliError::new(format!("static sheet: {e}")))?;
                (None, mesh)
            }
            None => {
                let sim = flag_simulation(&scene)?;
                let mut mesh = SlabMesh {
                    positions: vec![[0.0; 3]; sim.particle_count()],
                    normals: vec![[0.0, 0.0, 1.0]; sim.particle_count()],
                    uvs: grid_uvs(scene.flag.columns, scene.flag.rows),
                    indices: sim.triangles().iter().flatten().copied().collect(),
                };
                for (p, q) in mesh.positions.iter_mut().zip(sim.positions()) {
                    *p = q.as_vec3().to_array();
                }
                (Some(sim), mesh)
            }
        };
        let updater = NormalUpdater::new(mesh.positions.len(), &mesh.indices)
            .map_err(|e| CliError::new(format!("normals: {e}")))?;
        let n = mesh.positions.len();
        let mut flag = FlagScene {
            scene,
            simulation,
            updater,
            positions: mesh
                .positions
                .iter()
                .map(|p| Vec3::from_array(*p))
                .collect(),
            normals: vec![Vec3::Z; n],
            mesh,
            frame: 0,
        };
        flag.update_normals()?;
        Ok(flag)
    }

    /// Scene time, s: `frame / fps` in double precision, the one clock of `simulate`, `render`, the
    /// window and `bench` (summing a single-precision 1/60 drew the light 2.8 s late at 3600 s).
    pub fn time(&self) -> f64 {
        self.frame as f64 / f64::from(self.scene.render.fps)
    }

    /// Frames advanced since time 0.
    pub fn frame(&self) -> u64 {
        self.frame
    }

    /// The simulation step of one frame, s: `1/fps` in double precision, the same in every command, so
    /// that `simulate` and `render` of one scene give the same particles bit for bit.
    pub fn frame_duration(&self) -> f64 {
        1.0 / f64::from(self.scene.render.fps)
    }

    /// The simulation, when the scene has a flag (not a static sheet).
    pub fn simulation(&self) -> Option<&Simulation> {
        self.simulation.as_ref()
    }

    /// Light position now, m.
    pub fn light_position(&self) -> Vec3 {
        Vec3::from_array(self.scene.light.position(self.time()))
    }

    /// Back to time 0 and the flag at rest.
    pub fn reset(&mut self) -> Result<(), CliError> {
        if let Some(sim) = &mut self.simulation {
            sim.reset();
        }
        self.frame = 0;
        self.copy_positions();
        self.update_normals()
    }

    fn copy_positions(&mut self) {
        if let Some(sim) = &self.simulation {
            sim.write_positions_f32(&mut self.positions);
            for (p, q) in self.mesh.positions.iter_mut().zip(&self.positions) {
                *p = q.to_array();
            }
        }
    }

    pub fn update_normals(&mut self) -> Result<(), CliError> {
        if self.simulation.is_none() {
            return Ok(()); // the static sheet's normals are set once (the renderer re-orients them)
        }
        let light = Light::Point {
            position: self.light_position(),
        };
        self.updater
            .update(&self.positions, &light, &mut self.normals)
            .map_err(|e| CliError::new(format!("normals: {e}")))?;
        for (n, m) in self.mesh.normals.iter_mut().zip(&self.normals) {
            *n = m.to_array();
        }
        Ok(())
    }

    /// Advances the scene by one frame ([`Self::frame_duration`]): simulation step, then normals. A
    /// diverged step is reported ([`step_failure`]) and leaves the last good state.
    pub fn advance_frame(&mut self, times: &mut StageTimes) -> Result<(), CliError> {
        let start = Instant::now();
        let dt = self.frame_duration();
        if let Some(sim) = &mut self.simulation {
            sim.step(dt).map_err(|e| {
                CliError::new(format!(
                    "simulation: {}",
                    step_failure(&e, &self.scene.simulation)
                ))
            })?;
        }
        self.frame += 1;
        self.copy_positions();
        times.simulation = start.elapsed();
        let start = Instant::now();
        self.update_normals()?;
        times.normals = start.elapsed();
        Ok(())
    }

    /// Replaces the simulation parameters mid-run (the cloth carries on from where it is).
    pub fn set_simulation_params(
        &mut self,
        params: sheer_cloth::SimParams,
    ) -> Result<(), CliError> {
        if let Some(sim) = &mut self.simulation {
            sim.set_params(params.clone())
                .map_err(|e| CliError::new(e.to_string()))?;
        }
        self.scene.simulation = params;
        Ok(())
    }
}

/// What went wrong in a step, for a person: which limit tripped, its scene key, and only the remedies
/// that address that cause (`params`: the simulation that failed, for the numbers the advice names).
/// The command that reports it stops, so the message does not promise a kept state.
pub fn step_failure(error: &sheer_cloth::StepError, params: &sheer_cloth::SimParams) -> String {
    use sheer_cloth::DivergenceReason;
    let sheer_cloth::StepError::Diverged { step, reason } = error else {
        return error.to_string();
    };
    let substeps = params.method.substeps();
    let wind = params.wind.velocity.length();
    let peak_wind = wind * (1.0 + params.wind.gust_strength);
    match reason {
        DivergenceReason::Speed {
            particle,
            speed,
            limit,
        } => format!(
            "step {step} diverged: particle {particle} moved at {speed:.3e} m/s, above \
             `simulation.divergence.max_speed` = {limit} m/s. The wind peaks near {peak_wind:.3} m/s \
             (`simulation.wind.velocity`, `gust_strength`): if the cloth may really move that fast, \
             raise `simulation.divergence.max_speed`; otherwise lower the wind"
        ),
        DivergenceReason::Strain {
            spring,
            strain,
            limit,
        } => format!(
            "step {step} diverged: spring {spring} stretched by {strain:.3e}, above \
             `simulation.divergence.max_strain` = {limit}: the solver did not hold the cloth together \
             at this step size. More sub-steps (`simulation.method.substeps`, now {substeps}), fewer \
             `flag.columns` or less wind (now {wind:.3} m/s) keep it away"
        ),
        DivergenceReason::NonFinite { particle } => format!(
            "step {step} diverged: particle {particle} reached a non-finite position or velocity (the \
             integration blew up). More sub-steps (`simulation.method.substeps`, now {substeps}), fewer \
             `flag.columns` or less wind (`simulation.wind.velocity`, now {wind:.3} m/s) keep it away"
        ),
    }
}

/// Decodes the sRGB image that the scene's `key` names (`relative`) into linear [0, 1] texels,
/// resized to `size` when given; errors name the key.
pub fn load_linear_texture(
    scene: &Scene,
    key: &str,
    relative: &str,
    size: Option<(u32, u32)>,
) -> Result<Texture2d, CliError> {
    let bytes = scene.read_asset(key, relative)?;
    let image = image::load_from_memory(&bytes)
        .map_err(|e| {
            CliError::new(format!(
                "scene: `{key}` = {relative:?}: cannot decode the image: {e}"
            ))
        })?
        .to_rgb8();
    let image = match size {
        Some((w, h)) if image.dimensions() != (w, h) => {
            image::imageops::resize(&image, w, h, image::imageops::FilterType::Triangle)
        }
        _ => image,
    };
    let texels = image
        .pixels()
        .map(|p| {
            let [r, g, b] = p.0.map(srgb8_to_linear);
            [r, g, b, 1.0]
        })
        .collect();
    Texture2d::new(image.width(), image.height(), texels)
        .map_err(|e| CliError::new(format!("scene: `{key}` = {relative:?}: {e}")))
}

/// The all-orders table built into the binary (`assets/all_orders_table.bin`, regenerated by
/// `cargo run -p sheer-transport --release --example make_table`), checked and parsed once.
pub fn builtin_all_orders_table() -> Result<Arc<AllOrdersTable>, CliError> {
    static TABLE: OnceLock<Result<Arc<AllOrdersTable>, String>> = OnceLock::new();
    TABLE
        .get_or_init(|| {
            AllOrdersTable::from_bytes(include_bytes!("../../../assets/all_orders_table.bin"))
                .map(Arc::new)
                .map_err(|e| e.to_string())
        })
        .clone()
        .map_err(|e| CliError::new(format!("the built-in all-orders table: {e}")))
}

/// The diffuse (sky light) table built into the binary (`assets/diffuse_table.bin`, regenerated by
/// `cargo run -p sheer-transport --release --example make_diffuse_table`), checked and parsed once.
pub fn builtin_diffuse_table() -> Result<Arc<DiffuseTable>, CliError> {
    static TABLE: OnceLock<Result<Arc<DiffuseTable>, String>> = OnceLock::new();
    TABLE
        .get_or_init(|| {
            DiffuseTable::from_bytes(include_bytes!("../../../assets/diffuse_table.bin"))
                .map(Arc::new)
                .map_err(|e| e.to_string())
        })
        .clone()
        .map_err(|e| CliError::new(format!("the built-in diffuse table: {e}")))
}

/// The scene's sky light (`[environment]`): none when `environment.sky_light` is off; an environment
/// image when one is named, else the sky and ground radiances.
pub fn sky_light(scene: &Scene) -> Result<Option<SkyLight>, CliError> {
    let environment = &scene.environment;
    if !environment.sky_light {
        return Ok(None);
    }
    let light = match environment.image.as_deref() {
        Some(path) if !path.is_empty() => {
            let image = load_linear_texture(scene, "environment.image", path, None)?;
            DiffuseEnvironment::from_equirectangular(&image, environment.image_radiance_scale)
        }
        _ => DiffuseEnvironment::sky_and_ground(
            environment.sky_radiance,
            environment.ground_radiance,
        ),
    }
    .map_err(|e| CliError::new(format!("scene: [environment]: {e}")))?;
    Ok(Some(SkyLight {
        environment: light,
        table: builtin_diffuse_table()?,
    }))
}

/// Where the renderer's per-fragment path looks the all-orders table up (`shading.all_orders_lookup`).
fn all_orders_sampling(scene: &Scene) -> sheer_slab::render::AllOrdersSampling {
    match scene.shading.all_orders_lookup {
        AllOrdersLookup::Vertex => sheer_slab::render::AllOrdersSampling::PerVertex,
        AllOrdersLookup::Fragment => sheer_slab::render::AllOrdersSampling::PerFragment,
    }
}

/// The renderer's scattering model for the scene's `shading.scattering`.
fn scattering(scene: &Scene) -> Result<sheer_slab::Scattering, CliError> {
    Ok(match scene.shading.scattering {
        scene::Scattering::Single => sheer_slab::Scattering::Single,
        scene::Scattering::AllOrders => {
            sheer_slab::Scattering::AllOrders(builtin_all_orders_table()?)
        }
    })
}

/// Validates the shading parameters; τ1 outside the all-orders table names the scene keys.
fn validate_shading(shading: &ShadingParams, scene: &Scene) -> Result<(), CliError> {
    shading.validate().map_err(|e| match e {
        ShadingError::OutsideTable {
            channel,
            value,
            min,
            max,
        } => CliError::new(format!(
            "scene: `shading.optical_thickness` = {:?}: with `shading.scattering = \"all-orders\"` \
             or `environment.sky_light` τ1 (times the thickness texture) must lie in the range of \
             their precomputed tables, [{min}, {max}]; channel {channel} reaches {value}",
            scene.shading.optical_thickness
        )),
        // Names the file and the pixel, so that the texture can be mended: from an 8-bit image only a
        // red of 0 fails. (An albedo texel cannot leave [0, 1] from a scene: 8-bit texels times a
        // scale the scene holds to [0, 1].)
        ShadingError::Thickness { texel, value } => {
            let path = scene
                .shading
                .thickness_texture
                .as_deref()
                .unwrap_or_default();
            let width = shading
                .thickness_texture
                .as_ref()
                .map_or(1, |t| t.width().max(1));
            let (column, row) = (texel % width as usize, texel / width as usize);
            CliError::new(format!(
                "scene: `shading.thickness_texture` = {path:?}: the pixel at column {column}, row \
                 {row} has red {value:?} (linear), outside [6.1e-5, 65504]: only the red channel is \
                 read, it multiplies τ1, and 0 would be a hole"
            ))
        }
        other => CliError::new(format!("shading: {other}")),
    })
}

/// The GPU side: renderer, textures and the scene's shading parameters.
pub struct FrameRenderer {
    renderer: HeadlessRenderer,
    shading: ShadingParams,
    background: Background,
    /// The scene section `shading.sky` was made from: an environment image is decoded and projected
    /// again only when the section changes.
    environment: scene::EnvironmentSection,
}

impl FrameRenderer {
    /// Finds an adapter (Mesa lavapipe or llvmpipe without a GPU) and loads the scene's textures.
    pub fn new(scene: &Scene) -> Result<FrameRenderer, CliError> {
        let (width, height) = (scene.render.width, scene.render.height);
        let renderer = HeadlessRenderer::with_samples(width, height, scene.render.samples)
            .map_err(|e| CliError::new(format!("renderer: {e}")))?;
        let albedo_texture = match (&scene.static_sheet, &scene.shading.albedo_texture) {
            (Some(sheet), _) => {
                let [r, g, b] = sheet.albedo;
                Texture2d::uniform([r, g, b, 1.0]).map_err(|e| CliError::new(e.to_string()))?
            }
            (None, Some(path)) if !path.is_empty() => {
                load_linear_texture(scene, "shading.albedo_texture", path, None)?
            }
            (None, _) => Texture2d::uniform([1.0; 4]).map_err(|e| CliError::new(e.to_string()))?,
        };
        let thickness_texture = match &scene.shading.thickness_texture {
            Some(path) if !path.is_empty() => Some(load_linear_texture(
                scene,
                "shading.thickness_texture",
                path,
                None,
            )?),
            _ => None,
        };
        let background = match (&scene.static_sheet, &scene.background.image) {
            (None, Some(path)) if !path.is_empty() => {
                let mut texture =
                    load_linear_texture(scene, "background.image", path, Some((width, height)))?;
                let scale = scene.background.radiance_scale;
                let texels: Vec<[f32; 4]> = texture
                    .texels()
                    .iter()
                    .map(|t| [t[0] * scale, t[1] * scale, t[2] * scale, 1.0])
                    .collect();
                texture = Texture2d::new(width, height, texels)
                    .map_err(|e| CliError::new(e.to_string()))?;
                Background::Image(texture)
            }
            _ => Background::Uniform(scene.background.colour),
        };
        let shading = ShadingParams {
            optical_thickness: scene.shading.optical_thickness,
            albedo_scale: scene.shading.albedo_scale,
            albedo_texture,
            thickness_texture,
            light_position: Vec3::from_array(scene.light.position(0.0)),
            light_flux: scene.light.flux,
            convention: match scene.shading.convention {
                Convention::NormalToBeam => IrradianceConvention::NormalToBeam,
                Convention::PaperLiteral => IrradianceConvention::PaperLiteral,
            },
            exposure: scene.shading.exposure,
            baseline_transmittance: scene.shading.baseline_alpha,
            scattering: scattering(scene)?,
            all_orders_sampling: all_orders_sampling(scene),
            sky: sky_light(scene)?,
        };
        validate_shading(&shading, scene)?;
        Ok(FrameRenderer {
            renderer,
            shading,
            background,
            environment: scene.environment.clone(),
        })
    }

    /// Which GPU adapter renders.
    pub fn adapter(&self) -> &str {
        self.renderer.adapter_description()
    }

    /// Updates the material parameters from the scene (τ1, Λ scale, flux, convention, scattering
    /// model, exposure, α).
    pub fn update_shading(&mut self, scene: &Scene) -> Result<(), CliError> {
        let mut shading = self.shading.clone();
        shading.optical_thickness = scene.shading.optical_thickness;
        shading.albedo_scale = scene.shading.albedo_scale;
        shading.light_flux = scene.light.flux;
        shading.exposure = scene.shading.exposure;
        shading.baseline_transmittance = scene.shading.baseline_alpha;
        shading.convention = match scene.shading.convention {
            Convention::NormalToBeam => IrradianceConvention::NormalToBeam,
            Convention::PaperLiteral => IrradianceConvention::PaperLiteral,
        };
        shading.scattering = scattering(scene)?;
        shading.all_orders_sampling = all_orders_sampling(scene);
        if scene.environment != self.environment {
            shading.sky = sky_light(scene)?;
        }
        validate_shading(&shading, scene)?;
        self.shading = shading;
        self.environment = scene.environment.clone();
        Ok(())
    }

    pub fn exposure(&self) -> f32 {
        self.shading.exposure
    }

    /// Renders the flag as the scene's shading model says, and draws the light marker.
    pub fn render(
        &mut self,
        flag: &FlagScene,
        times: &mut StageTimes,
    ) -> Result<LinearImage, CliError> {
        let scene = &flag.scene;
        let thin_slab = match scene.shading.path {
            EvaluationPathName::Fragment => EvaluationPath::PerFragment,
            EvaluationPathName::Vertex => EvaluationPath::PerVertex,
            EvaluationPathName::Cpu => EvaluationPath::Cpu,
        };
        let mut image = match scene.shading.model {
            ShadingModel::ThinSlab => self.render_path(flag, thin_slab, times)?,
            ShadingModel::Baseline => self.render_path(flag, EvaluationPath::Baseline, times)?,
            ShadingModel::Split => {
                let left = self.render_path(flag, EvaluationPath::Baseline, times)?;
                let mut right = self.render_path(flag, thin_slab, times)?;
                let half = right.width / 2;
                for y in 0..right.height {
                    for x in 0..half {
                        let i = (y * right.width + x) as usize;
                        right.pixels[i] = left.pixels[i];
                    }
                }
                right
            }
        };
        if scene.static_sheet.is_none() {
            draw_pole(&mut image, scene, flag.light_position());
        }
        if scene.light.marker {
            let camera = camera(scene);
            let light = flag.light_position();
            // Behind the cloth the marker is seen through it, as the background is (eq. 9).
            let seen_through =
                segment_crosses_mesh(camera.eye, light, &flag.mesh).then_some(&self.background);
            draw_light_marker(&mut image, &camera, light, seen_through);
        }
        Ok(image)
    }

    fn render_path(
        &mut self,
        flag: &FlagScene,
        path: EvaluationPath,
        times: &mut StageTimes,
    ) -> Result<LinearImage, CliError> {
        self.shading.light_position = flag.light_position();
        let start = Instant::now();
        let gpu = self
            .renderer
            .render_frame_timed(
                &flag.mesh,
                &camera(&flag.scene),
                &self.shading,
                &self.background,
                path,
            )
            .map_err(|e| CliError::new(format!("render: {e}")))?;
        times.shading += start.elapsed();
        times.gpu += gpu;
        let start = Instant::now();
        let image = self
            .renderer
            .read_target()
            .map_err(|e| CliError::new(format!("render: {e}")))?;
        times.readback += start.elapsed();
        Ok(image)
    }
}

/// The scene's camera as the renderer takes it.
pub fn camera(scene: &Scene) -> Camera {
    Camera {
        eye: Vec3::from_array(scene.camera.position),
        target: Vec3::from_array(scene.camera.target),
        up: Vec3::Y,
        vertical_fov: scene.camera.vertical_fov_degrees.to_radians(),
        near: 0.05,
        far: 100.0,
    }
}

/// Radius of the flag pole, m.
const POLE_RADIUS: f32 = 0.015;

/// The flag pole along the hoist edge: an opaque, diffuse (albedo 0.5) vertical cylinder lit by the
/// point light, drawn over the frame like the light marker — the flag is attached to it, so it is
/// never far behind the cloth it would hide.
fn draw_pole(image: &mut LinearImage, scene: &Scene, light: Vec3) {
    let cam = camera(scene);
    let view_projection = cam.view_projection(image.width, image.height);
    let origin = Vec3::new(
        scene.flag.origin.x as f32,
        scene.flag.origin.y as f32,
        scene.flag.origin.z as f32,
    );
    let top = origin + Vec3::new(0.0, 0.06, 0.0);
    let bottom = origin - Vec3::new(0.0, scene.flag.height as f32 + 1.5, 0.0);
    let to_pixels = |p: Vec3| {
        let clip = view_projection * p.extend(1.0);
        (clip.w > 0.0).then(|| {
            let ndc = clip.truncate() / clip.w;
            glam::Vec2::new(
                (ndc.x + 1.0) * 0.5 * image.width as f32,
                (1.0 - ndc.y) * 0.5 * image.height as f32,
            )
        })
    };
    let (Some(a), Some(b)) = (to_pixels(top), to_pixels(bottom)) else {
        return;
    };
    // Pixel half-width from the radius seen at the pole's distance (the top's, a fine approximation).
    let side = (top - cam.eye).cross(Vec3::Y).normalize_or_zero() * POLE_RADIUS;
    let half_width = to_pixels(top + side)
        .map_or(1.0, |p| p.distance(a))
        .max(1.0);
    let axis = b - a;
    let length_squared = axis.length_squared().max(1e-6);
    let across = (top - cam.eye).cross(Vec3::Y).normalize_or_zero();
    // Horizontal, from the pole toward the camera: `across` × up (up × `across` would face away,
    // lighting the pole from behind).
    let towards_eye = across.cross(Vec3::Y);
    let irradiance = |point: Vec3, normal: Vec3| {
        let d = light - point;
        let r2 = d.length_squared().max(1e-6);
        scene.light.flux / (4.0 * std::f32::consts::PI * r2) * normal.dot(d / r2.sqrt()).max(0.0)
    };
    let (x0, x1) = (
        a.x.min(b.x) - half_width - 1.0,
        a.x.max(b.x) + half_width + 1.0,
    );
    let (y0, y1) = (a.y.min(b.y).max(0.0), a.y.max(b.y));
    for y in (y0 as u32)..(y1.min(image.height as f32) as u32) {
        for x in (x0.max(0.0) as u32)..(x1.min(image.width as f32) as u32) {
            let p = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let t = ((p - a).dot(axis) / length_squared).clamp(0.0, 1.0);
            let offset = (p - (a + t * axis)).perp_dot(axis.normalize_or_zero());
            let u = offset / half_width; // −1 … 1 across the pole
            if u.abs() > 1.0 {
                continue;
            }
            let normal = (u * across + (1.0 - u * u).sqrt() * towards_eye).normalize_or_zero();
            let point = top.lerp(bottom, t) + POLE_RADIUS * normal;
            // Lambertian, albedo 0.5: L = ρ E / π, plus a little sky so its shadow side is not void.
            let radiance = 0.5 * irradiance(point, normal) / std::f32::consts::PI + 0.02;
            let i = (y * image.width + x) as usize;
            image.pixels[i] = [radiance * 0.9, radiance * 0.8, radiance * 0.65, 0.0];
        }
    }
}

/// The marker's disc, linear W/(m²·sr): a warm white well above the flag's radiance.
const MARKER_RADIANCE: [f32; 3] = [4.0, 3.6, 2.4];

/// Whether the segment from `from` to `to` passes through a triangle of `mesh` (Möller & Trumbore
/// 1997, "Fast, minimum storage ray–triangle intersection"); degenerate triangles are missed.
fn segment_crosses_mesh(from: Vec3, to: Vec3, mesh: &SlabMesh) -> bool {
    let direction = to - from;
    mesh.indices.chunks_exact(3).any(|triangle| {
        let [a, b, c] = [0, 1, 2].map(|k| Vec3::from_array(mesh.positions[triangle[k] as usize]));
        let (edge1, edge2) = (b - a, c - a);
        let p = direction.cross(edge2);
        let determinant = edge1.dot(p);
        if determinant.abs() < 1e-12 {
            return false; // parallel to the triangle's plane, or a degenerate triangle
        }
        let inverse = 1.0 / determinant;
        let offset = from - a;
        let u = offset.dot(p) * inverse;
        let q = offset.cross(edge1);
        let v = direction.dot(q) * inverse;
        let t = edge2.dot(q) * inverse;
        u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < 1.0
    })
}

/// A small bright disc with a black rim where the light is (it marks the light, it does not model
/// it). Drawn over the frame, or, when `seen_through` gives the background because the cloth lies
/// between the eye and the light, behind the cloth: in each pixel the marker takes the background's
/// place under the layers' transmittance α (alpha channel), `L = L_cloth + α·L_marker` with
/// `L_cloth = L − α·L_background` (eq. 9), so the light shows through thin fabric as it should.
fn draw_light_marker(
    image: &mut LinearImage,
    camera: &Camera,
    light: Vec3,
    seen_through: Option<&Background>,
) {
    let clip = camera.view_projection(image.width, image.height) * light.extend(1.0);
    if clip.w <= 0.0 {
        return; // behind the camera
    }
    let ndc = clip.truncate() / clip.w;
    let cx = (ndc.x + 1.0) * 0.5 * image.width as f32;
    let cy = (1.0 - ndc.y) * 0.5 * image.height as f32;
    let radius = (image.width.min(image.height) as f32 / 100.0).max(3.0);
    let (x0, x1) = ((cx - radius).floor().max(0.0), (cx + radius).ceil());
    let (y0, y1) = ((cy - radius).floor().max(0.0), (cy + radius).ceil());
    for y in (y0 as u32)..(y1.min(image.height as f32) as u32) {
        for x in (x0 as u32)..(x1.min(image.width as f32) as u32) {
            let d = ((x as f32 + 0.5 - cx).powi(2) + (y as f32 + 0.5 - cy).powi(2)).sqrt();
            let i = (y * image.width + x) as usize;
            let marker = if d <= radius {
                MARKER_RADIANCE
            } else if d <= radius + 1.5 {
                [0.0; 3]
            } else {
                continue;
            };
            let pixel = &mut image.pixels[i];
            let alpha = pixel[3];
            for channel in 0..3 {
                pixel[channel] = match seen_through {
                    None => marker[channel],
                    Some(background) => {
                        let behind = match background {
                            Background::Uniform(colour) => colour[channel],
                            Background::Image(texture) => texture.texels()[i][channel],
                        };
                        // max(): L − α·L_background is the cloth's own radiance, ≥ 0 but for rounding.
                        (pixel[channel] - alpha * behind).max(0.0) + alpha * marker[channel]
                    }
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1 m sheet in the plane z = 0 around the origin, 4 × 4 cells.
    fn sheet() -> SlabMesh {
        SlabMesh::flat_sheet(Vec3::new(-0.5, -0.5, 0.0), Vec3::X, Vec3::Y, Vec3::Z, 4, 4).unwrap()
    }

    #[test]
    fn a_segment_through_the_sheet_crosses_it_and_one_that_stops_short_does_not() {
        let mesh = sheet();
        let eye = Vec3::new(0.1, 0.2, 3.0);
        assert!(segment_crosses_mesh(eye, Vec3::new(0.1, 0.2, -1.0), &mesh));
        assert!(!segment_crosses_mesh(eye, Vec3::new(0.1, 0.2, 0.5), &mesh));
        // Beside the sheet, and parallel to it.
        assert!(!segment_crosses_mesh(eye, Vec3::new(2.0, 0.2, -1.0), &mesh));
        assert!(!segment_crosses_mesh(
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            &mesh
        ));
    }

    /// The marker's centre pixel after drawing it over a uniform image of cloth radiance 0.3 with
    /// transmittance α = 0.25 over a background of 0.2, light straight ahead of the camera.
    fn marker_centre(seen_through: Option<&Background>) -> [f32; 4] {
        let (width, height) = (64, 48);
        let mut image = LinearImage {
            width,
            height,
            pixels: vec![[0.3, 0.3, 0.3, 0.25]; (width * height) as usize],
        };
        let camera = Camera {
            eye: Vec3::new(0.0, 0.0, 3.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            vertical_fov: 0.5,
            near: 0.05,
            far: 100.0,
        };
        draw_light_marker(&mut image, &camera, Vec3::ZERO, seen_through);
        image.pixels[(height / 2 * width + width / 2) as usize]
    }

    #[test]
    fn the_marker_is_drawn_over_the_frame_or_seen_through_the_cloth() {
        // In front: the marker replaces the pixel's radiance; α is kept.
        let front = marker_centre(None);
        assert_eq!(front, [4.0, 3.6, 2.4, 0.25]);
        // Behind: it takes the background's place under α (eq. 9): (0.3 − 0.25·0.2) + 0.25·L_marker.
        let behind = marker_centre(Some(&Background::Uniform([0.2; 3])));
        for (channel, marker) in MARKER_RADIANCE.iter().enumerate() {
            let expected = (0.3 - 0.25 * 0.2) + 0.25 * marker;
            assert!(
                (behind[channel] - expected).abs() < 1e-6,
                "channel {channel}: {} vs {expected}",
                behind[channel]
            );
        }
        assert_eq!(behind[3], 0.25);
    }
}
