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
    Background, Camera, EvaluationPath, HeadlessRenderer, LightMarker, LinearImage, OpaqueMesh,
    ShadingParams, Shadows, SlabFrame, SlabMesh, Texture2d, srgb8_to_linear,
};
use sheer_slab::{AllOrdersTable, DiffuseEnvironment, DiffuseTable, SkyLight};

use crate::CliError;
use crate::scene::{self, Scene, ShadingModel};
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
    /// The part of `gpu` before the draw: the shadow map's passes from the light (with the uploads and
    /// the per-vertex table pass, when there is one), submitted on their own.
    pub shadow: Duration,
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
        let previous = std::mem::replace(&mut self.scene.simulation, params);
        if let Some(sim) = &mut self.simulation
            && let Err(e) = sim.set_params(self.scene.simulation_params())
        {
            self.scene.simulation = previous;
            return Err(CliError::new(e.to_string()));
        }
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

/// The scene's translucent shadows (`shading.shadows`, `shading.shadow_resolution`), with the built-in
/// diffuse table for the light scattered through a layer in front.
pub fn shadows(scene: &Scene) -> Result<Option<Shadows>, CliError> {
    if !scene.shading.shadows {
        return Ok(None);
    }
    Ok(Some(Shadows {
        resolution: scene.shading.shadow_resolution,
        diffuse_table: Some(builtin_diffuse_table()?),
    }))
}

/// The renderer's scattering model for the scene's `shading.scattering`, with the built-in table.
fn scattering(scene: &Scene) -> Result<sheer_slab::Scattering, CliError> {
    sheer_slab::Scattering::with_orders(scene.shading.scattering, builtin_all_orders_table)
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

/// The scene's inputs to the renderer, shared by the command line and the window: material, sky and
/// background, the camera, the flag pole and the light's marker.
pub struct FrameShading {
    shading: ShadingParams,
    background: Background,
    /// The scene section `shading.sky` was made from: an environment image is decoded and projected
    /// again only when the section changes.
    environment: scene::EnvironmentSection,
    size: (u32, u32),
    camera: Camera,
    pole: Vec<OpaqueMesh>,
}

impl FrameShading {
    /// Loads the scene's textures and tables.
    pub fn new(scene: &Scene) -> Result<FrameShading, CliError> {
        let (width, height) = (scene.render.width, scene.render.height);
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
            convention: scene.shading.convention,
            exposure: scene.shading.exposure,
            baseline_transmittance: scene.shading.baseline_alpha,
            scattering: scattering(scene)?,
            all_orders_sampling: scene.shading.all_orders_lookup,
            sky: sky_light(scene)?,
            shadows: shadows(scene)?,
        };
        validate_shading(&shading, scene)?;
        Ok(FrameShading {
            shading,
            background,
            environment: scene.environment.clone(),
            size: (width, height),
            camera: camera(scene),
            pole: Vec::new(),
        })
    }

    /// Updates the material parameters from the scene (τ1, Λ scale, flux, convention, scattering
    /// model, exposure, α, sky).
    pub fn update(&mut self, scene: &Scene) -> Result<(), CliError> {
        let mut shading = self.shading.clone();
        shading.optical_thickness = scene.shading.optical_thickness;
        shading.albedo_scale = scene.shading.albedo_scale;
        shading.light_flux = scene.light.flux;
        shading.exposure = scene.shading.exposure;
        shading.baseline_transmittance = scene.shading.baseline_alpha;
        shading.convention = scene.shading.convention;
        shading.scattering = scattering(scene)?;
        shading.all_orders_sampling = scene.shading.all_orders_lookup;
        if scene.environment != self.environment {
            shading.sky = sky_light(scene)?;
        }
        shading.shadows = shadows(scene)?;
        validate_shading(&shading, scene)?;
        self.shading = shading;
        self.environment = scene.environment.clone();
        Ok(())
    }

    pub fn exposure(&self) -> f32 {
        self.shading.exposure
    }

    /// The image size, pixels.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// What the renderer draws for the flag as it is now: one frame, or for the split view the thin
    /// slab with the baseline over its left half. The pole and the marker are geometry of each frame.
    pub fn frames<'a>(&'a mut self, flag: &'a FlagScene) -> Result<Vec<SlabFrame<'a>>, CliError> {
        let scene = &flag.scene;
        self.shading.light_position = flag.light_position();
        self.camera = camera(scene);
        self.pole.clear();
        if scene.static_sheet.is_none() {
            self.pole.push(pole(scene)?);
        }
        let (width, height) = self.size;
        let light_marker = scene.light.marker.then(|| LightMarker {
            radius_pixels: (width.min(height) as f32 / 100.0).max(3.0),
            radiance: MARKER_RADIANCE,
        });
        let thin_slab = scene.shading.path;
        let this = &*self;
        let frame = |path, scissor| SlabFrame {
            mesh: &flag.mesh,
            camera: &this.camera,
            shading: &this.shading,
            background: &this.background,
            path,
            opaque: &this.pole,
            light_marker,
            scissor,
        };
        Ok(match scene.shading.model {
            ShadingModel::ThinSlab => vec![frame(thin_slab, None)],
            ShadingModel::Baseline => vec![frame(EvaluationPath::Baseline, None)],
            ShadingModel::Split => vec![
                frame(thin_slab, None),
                frame(EvaluationPath::Baseline, Some([0, 0, width / 2, height])),
            ],
        })
    }
}

/// The command line's renderer: a headless device around the shared frame description.
pub struct FrameRenderer {
    renderer: HeadlessRenderer,
    shading: FrameShading,
}

impl FrameRenderer {
    /// Finds an adapter (Mesa lavapipe or llvmpipe without a GPU) and loads the scene's textures.
    pub fn new(scene: &Scene) -> Result<FrameRenderer, CliError> {
        let shading = FrameShading::new(scene)?;
        let (width, height) = shading.size();
        let renderer = HeadlessRenderer::with_samples(width, height, scene.render.samples)
            .map_err(|e| CliError::new(format!("renderer: {e}")))?;
        Ok(FrameRenderer { renderer, shading })
    }

    /// Which GPU adapter renders.
    pub fn adapter(&self) -> &str {
        self.renderer.adapter_description()
    }

    /// See [`FrameShading::update`].
    pub fn update_shading(&mut self, scene: &Scene) -> Result<(), CliError> {
        self.shading.update(scene)
    }

    pub fn exposure(&self) -> f32 {
        self.shading.exposure()
    }

    /// Renders the flag as the scene's shading model says, with the pole and the light marker, and
    /// reads the image back.
    pub fn render(
        &mut self,
        flag: &FlagScene,
        times: &mut StageTimes,
    ) -> Result<LinearImage, CliError> {
        let start = Instant::now();
        let frames = self.shading.frames(flag)?;
        let gpu = self
            .renderer
            .render_frames_staged(&frames)
            .map_err(|e| CliError::new(format!("render: {e}")))?;
        times.shading += start.elapsed();
        times.gpu += gpu.total();
        times.shadow += gpu.before_draw;
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

/// The pole's diffuse albedo: a pale wood.
const POLE_ALBEDO: [f32; 3] = [0.45, 0.4, 0.325];

/// The flag pole along the hoist edge (`Scene::pole`): an opaque, diffuse cylinder lit by the point
/// light and the sky like everything else, drawn out to where contacts keep the cloth's mid-surface
/// (half its thickness beyond the capsule), so that it touches the hoist.
fn pole(scene: &Scene) -> Result<OpaqueMesh, CliError> {
    let sheer_cloth::Collider::Capsule { start, end, radius } = scene.pole() else {
        return Err(CliError::new("flag pole: not a capsule"));
    };
    let drawn_radius = radius + scene.simulation.collisions.thickness / 2.0;
    let to_f32 = |v: sheer_cloth::glam::DVec3| Vec3::new(v.x as f32, v.y as f32, v.z as f32);
    OpaqueMesh::cylinder(
        to_f32(start),
        to_f32(end),
        drawn_radius as f32,
        24,
        POLE_ALBEDO,
    )
    .map_err(|e| CliError::new(format!("flag pole: {e}")))
}

/// The marker's disc, linear W/(m²·sr): a warm white well above the flag's radiance.
const MARKER_RADIANCE: [f32; 3] = [4.0, 3.6, 2.4];
