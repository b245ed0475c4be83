//! The scene file (TOML): everything the window and the command line need to reproduce a run — the flag
//! and its simulation, the thin-slab shading, the circling light, the camera, the background and the
//! output size — or, instead of the flag, a static flat sheet whose render can be checked by hand.
//!
//! Unknown keys are errors (serde's `deny_unknown_fields`), so are arrays of the wrong length, and
//! [`Scene::validate`] names the key of any out-of-range value. The default scene is
//! `assets/default.scene.toml`, built into the binary with its images; every key is documented there.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sheer_cloth::{GridSpec, SimParams};
use sheer_slab::render::{AllOrdersSampling, EvaluationPath};
use sheer_slab::{IrradianceConvention, ScatteringOrders};

use crate::CliError;

/// Which shading the flag gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShadingModel {
    /// The paper's thin-slab model, eqs. (4)–(9).
    ThinSlab,
    /// Diffuse BRDF and constant α; back-lit side black (the paper's figure 2, top row).
    Baseline,
    /// Left half baseline, right half thin-slab.
    Split,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShadingSection {
    pub model: ShadingModel,
    /// Single scattering (the paper) or all orders (eqs. (4)–(5) + the table's multiple part).
    pub scattering: ScatteringOrders,
    /// With all orders on the fragment path: the table per vertex (interpolated) or per fragment.
    pub all_orders_lookup: AllOrdersSampling,
    /// Where the thin-slab model is evaluated: `fragment`, `vertex` or `cpu` (never `Baseline`, a model).
    pub path: EvaluationPath,
    /// τ1, the slab's optical thickness (dimensionless, > 0), per channel.
    pub optical_thickness: [f32; 3],
    /// Multiplies the albedo texture to give Λ per channel (Λ must stay in [0, 1]).
    pub albedo_scale: [f32; 3],
    /// Albedo texture, relative to the scene file (sRGB PNG; decoded to linear); `""` for white.
    pub albedo_texture: Option<String>,
    /// Optional thickness texture (red channel multiplies τ1), relative to the scene file.
    pub thickness_texture: Option<String>,
    pub convention: IrradianceConvention,
    /// The baseline's constant α (0.2 in the paper).
    pub baseline_alpha: f32,
    /// Display exposure: linear radiance × exposure before sRGB encoding.
    pub exposure: f32,
    /// Translucent shadows: the light's beam attenuated by the cloth layers in front (and stopped by the
    /// pole) on its way to each point.
    pub shadows: bool,
    /// The shadow map's texels per side (16–8192).
    pub shadow_resolution: u32,
}

impl Default for ShadingSection {
    /// The paper's figure 2 (Λ = 1, τ1 = 2, baseline α = 0.2), with all orders of scattering.
    fn default() -> Self {
        ShadingSection {
            model: ShadingModel::ThinSlab,
            // Single scattering misses 49–87 % of the light at τ1 = 2 (docs/shading-model.md).
            scattering: ScatteringOrders::All,
            all_orders_lookup: AllOrdersSampling::PerFragment,
            path: EvaluationPath::PerFragment,
            optical_thickness: [2.0; 3],
            albedo_scale: [1.0; 3],
            albedo_texture: Some("faroe_flag.png".into()),
            thickness_texture: None,
            convention: IrradianceConvention::NormalToBeam,
            baseline_alpha: 0.2,
            exposure: 0.5,
            shadows: true,
            shadow_resolution: sheer_slab::render::DEFAULT_SHADOW_RESOLUTION,
        }
    }
}

/// A point light circling the flag in a horizontal plane.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LightSection {
    /// Radiant flux Φ, W (isotropic point light).
    pub flux: f32,
    /// Centre of the orbit, m.
    pub centre: [f32; 3],
    /// Orbit radius, m.
    pub radius: f32,
    /// Time for one revolution, s (negative: clockwise seen from above; 0: the light stands still).
    pub period: f32,
    /// Angle at t = 0, rad; 0 puts the light in front of the flag (+z, the camera's side).
    pub phase: f32,
    /// Draw a small marker where the light is.
    pub marker: bool,
}

impl Default for LightSection {
    fn default() -> Self {
        LightSection {
            flux: 250.0,
            centre: [0.55, 0.4, 0.0],
            radius: 1.6,
            period: 12.0,
            phase: 0.6,
            marker: true,
        }
    }
}

impl LightSection {
    /// Light position at scene time `time` (s). The angle is reduced to one turn in double precision
    /// first, so that an hour into the scene the light is where the hour puts it.
    pub fn position(&self, time: f64) -> [f32; 3] {
        let angle = if self.period == 0.0 {
            self.phase
        } else {
            let turns = (time / f64::from(self.period)).rem_euclid(1.0);
            self.phase + (std::f64::consts::TAU * turns) as f32
        };
        [
            self.centre[0] + self.radius * angle.sin(),
            self.centre[1],
            self.centre[2] + self.radius * angle.cos(),
        ]
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraSection {
    /// Eye position, m.
    pub position: [f32; 3],
    /// Point looked at, m.
    pub target: [f32; 3],
    /// Vertical field of view, degrees.
    pub vertical_fov_degrees: f32,
}

impl Default for CameraSection {
    fn default() -> Self {
        CameraSection {
            position: [0.75, 0.25, 2.4],
            target: [0.6, 0.3, 0.0],
            vertical_fov_degrees: 40.0,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BackgroundSection {
    /// Painting behind the flag, relative to the scene file (sRGB PNG), stretched over the frame;
    /// `""` for none (the uniform colour). A static sheet always uses the uniform colour.
    pub image: Option<String>,
    /// Uniform linear radiance, W/(m²·sr), used when there is no image.
    pub colour: [f32; 3],
    /// Linear radiance of the painting's white, W/(m²·sr).
    pub radiance_scale: f32,
}

impl Default for BackgroundSection {
    fn default() -> Self {
        BackgroundSection {
            image: Some("faroe_landscape.png".into()),
            colour: [0.2, 0.2, 0.2],
            radiance_scale: 1.2,
        }
    }
}

/// Daylight on both faces of the cloth (sheer-slab's `sky` module): a sky above the horizon and a ground
/// below it, or an environment image, with the slab's all-orders response to diffuse light.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnvironmentSection {
    /// Light the cloth with the environment; false: the point light alone (the paper's scene).
    pub sky_light: bool,
    /// Radiance of the sky above the horizon (+y), W/(m²·sr) per channel.
    pub sky_radiance: [f32; 3],
    /// Radiance of the ground below the horizon, W/(m²·sr) per channel.
    pub ground_radiance: [f32; 3],
    /// Optional equirectangular environment image (sRGB PNG, row 0 straight up), relative to the scene
    /// file; when given it replaces the sky and ground radiances. `""` or left out: none.
    pub image: Option<String>,
    /// Radiance of the environment image's white, W/(m²·sr).
    pub image_radiance_scale: f32,
}

impl Default for EnvironmentSection {
    /// The painting's daylight: the mean linear radiance of the painting's upper third (its sky) and
    /// lower third (its sea and cliffs), times `background.radiance_scale` (a test recomputes them).
    fn default() -> Self {
        EnvironmentSection {
            sky_light: true,
            sky_radiance: DEFAULT_SKY_RADIANCE,
            ground_radiance: DEFAULT_GROUND_RADIANCE,
            image: None,
            image_radiance_scale: 1.0,
        }
    }
}

/// The default sky radiance, W/(m²·sr): the painting's upper third (see [`EnvironmentSection`]).
pub const DEFAULT_SKY_RADIANCE: [f32; 3] = [0.43, 0.54, 0.59];
/// The default ground radiance, W/(m²·sr): the painting's lower third.
pub const DEFAULT_GROUND_RADIANCE: [f32; 3] = [0.2, 0.26, 0.31];

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderSection {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Frames per simulated second (the simulation steps 1/fps per frame).
    pub fps: f32,
    /// Simulated seconds before the window shows its first frame (the flag starts at rest, flat).
    pub warmup: f32,
    /// Samples per pixel: 4 for anti-aliased edges, 1 for none.
    pub samples: u32,
}

impl Default for RenderSection {
    /// The paper's 512 × 512 at 60 Hz.
    fn default() -> Self {
        RenderSection {
            width: 512,
            height: 512,
            fps: 60.0,
            warmup: 1.5,
            samples: 4,
        }
    }
}

/// A static flat sheet instead of the simulated flag: uniform albedo, no texture, no simulation, so a
/// render can be checked against the model by hand.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StaticSheet {
    /// Centre of the sheet, m.
    pub centre: [f32; 3],
    /// Size along x and y before the tilt, m.
    pub size: [f32; 2],
    /// Rotation about the x axis, degrees (0: facing +z).
    pub tilt_degrees: f32,
    /// Uniform single-scattering albedo Λ per channel, in [0, 1].
    pub albedo: [f32; 3],
    /// Quads along each side.
    pub segments: u32,
}

impl Default for StaticSheet {
    fn default() -> Self {
        StaticSheet {
            centre: [0.0, 0.0, 0.0],
            size: [1.0, 1.0],
            tilt_degrees: 0.0,
            albedo: [1.0; 3],
            segments: 1,
        }
    }
}

/// The flag pole along the hoist: drawn, and (position-based methods) a collider.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PoleSection {
    /// Whether the flag collides with the pole (a capsule; position-based methods only).
    pub collider: bool,
}

impl Default for PoleSection {
    /// Off: in the default wind the flag never reaches its pole (60 s checked), so the contact would
    /// cost 1.3× the frame for nothing (docs/perf/collisions.md).
    fn default() -> Self {
        PoleSection { collider: false }
    }
}

/// A whole scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Scene {
    pub flag: GridSpec,
    pub simulation: SimParams,
    pub pole: PoleSection,
    pub shading: ShadingSection,
    pub light: LightSection,
    pub camera: CameraSection,
    pub background: BackgroundSection,
    pub environment: EnvironmentSection,
    pub render: RenderSection,
    /// When present, this sheet replaces the flag and nothing is simulated.
    pub static_sheet: Option<StaticSheet>,
    /// Directory relative paths are resolved against (the scene file's folder); not in the file.
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// Relative paths name the images built into the binary ([`BUILTIN_ASSETS`]) instead of files
    /// in `base_dir`: the default scene, so that an installed `sheer` needs no source tree. Not in
    /// the file.
    #[serde(skip)]
    pub builtin_assets: bool,
    /// Image keys the scene file left out ([`DEFAULT_IMAGE_KEYS`]): their default images are read from
    /// those built into the binary, wherever the file lies. Not in the file.
    #[serde(skip)]
    pub builtin_images: Vec<&'static str>,
}

/// The keys whose default value names one of the default scene's images ([`BUILTIN_ASSETS`]).
pub const DEFAULT_IMAGE_KEYS: [&str; 2] = ["shading.albedo_texture", "background.image"];

/// The shipped default scene, built into the binary (every key is documented there).
pub const DEFAULT_SCENE_TOML: &str = include_str!("../../../assets/default.scene.toml");

/// The default scene's images, built into the binary under the names its file uses.
pub const BUILTIN_ASSETS: [(&str, &[u8]); 2] = [
    (
        "faroe_flag.png",
        include_bytes!("../../../assets/faroe_flag.png"),
    ),
    (
        "faroe_landscape.png",
        include_bytes!("../../../assets/faroe_landscape.png"),
    ),
];

impl Scene {
    /// The flag pole (`sheer_cloth::Collider::flag_pole`): drawn always, a collider where
    /// `pole.collider` asks for it.
    pub fn pole(&self) -> sheer_cloth::Collider {
        sheer_cloth::Collider::flag_pole(&self.flag, self.simulation.collisions.thickness)
    }

    /// The simulation's parameters with the pole's capsule among the colliders where `pole.collider`
    /// asks for it and the method has contacts (position-based).
    pub fn simulation_params(&self) -> SimParams {
        let mut params = self.simulation.clone();
        if self.pole.collider && params.method.is_position_based() {
            params.collisions.colliders.push(self.pole());
        }
        params
    }
}

impl Default for Scene {
    fn default() -> Self {
        // A fresh breeze across the flag at 27° from its plane, gusting and turbulent: enough to make it
        // wave rather than stream flat; integrated by the study's automatic choice (docs/choice.toml).
        let simulation = SimParams::waving_flag();
        Scene {
            flag: GridSpec::default(),
            simulation,
            pole: PoleSection::default(),
            shading: ShadingSection::default(),
            light: LightSection::default(),
            camera: CameraSection::default(),
            background: BackgroundSection::default(),
            environment: EnvironmentSection::default(),
            render: RenderSection::default(),
            static_sheet: None,
            base_dir: PathBuf::new(),
            builtin_assets: true,
            builtin_images: Vec::new(),
        }
    }
}

fn check(ok: bool, key: &str, value: impl std::fmt::Debug, rule: &str) -> Result<(), CliError> {
    if ok {
        Ok(())
    } else {
        Err(CliError::new(format!("scene: `{key}` = {value:?}: {rule}")))
    }
}

/// Largest particle grid side: `sheer bench sim`'s largest grid is 1024 × 745; a larger one runs
/// out of memory (or time) before it shows anything.
pub const MAX_GRID_SIDE: usize = 1024;
/// Most sub-steps per frame a scene may ask for: far above any stable setting (forward Euler on the
/// default flag needs 1600), low enough that a typo does not hang the program.
pub const MAX_SUBSTEPS: u32 = 100_000;
/// Most solver iterations (PBD, XPBD) or conjugate-gradient iterations (implicit Euler) per sub-step.
pub const MAX_ITERATIONS: u32 = 10_000;
/// Frames per simulated second: the simulation steps 1/fps per frame.
pub const FPS_RANGE: (f32, f32) = (1.0, 1000.0);
/// Largest light flux, W. Far above any lamp (the irradiance at 1 m is 8·10⁴ W/m², about 60 suns)
/// and far enough below f32's 3.4·10³⁸ that no radiance overflows an f32 render target. A half-float
/// target (some GL drivers) holds at most 65 504 W/(m²·sr), which such a light near the cloth exceeds:
/// that frame is then an error naming the pixel (`RenderError::OverflowedPixel`), not an image of
/// infinities or saturated values.
pub const MAX_FLUX_W: f32 = 1e6;
/// Largest background radiance (colour, painting white), W/(m²·sr), and largest display exposure:
/// the same margin against overflow of an f32 target (a half-float one: as for the flux above).
pub const MAX_RADIANCE: f32 = 1e6;
/// Positions (m) must lie within this distance of the origin along every axis: f32 coordinates
/// further out lose the millimetres the cloth is made of.
pub const MAX_COORDINATE_M: f32 = 1e4;
/// Largest flag side, m.
pub const MAX_FLAG_SIZE_M: f64 = 100.0;

/// What serde does to a scene file without a word, found by comparing the file with the scene read
/// from it: toml fills a fixed-size array (and a glam vector) from the first elements of a longer array
/// and drops the rest; and a number read into an `f32` field becomes infinite beyond 3.4·10³⁸, and 0 or
/// a subnormal (which loses its digits) below 1.2·10⁻³⁸. Both are refused, naming the key.
fn check_silent_conversions(text: &str, scene: &Scene) -> Result<(), CliError> {
    match (toml::de::DeTable::parse(text), toml::Value::try_from(scene)) {
        (Ok(file), Ok(toml::Value::Table(read))) => compare_tables(text, file.get_ref(), &read, ""),
        // The text parsed already, and a scene always serialises.
        _ => Ok(()),
    }
}

fn compare_tables(
    text: &str,
    file: &toml::de::DeTable<'_>,
    read: &toml::Table,
    prefix: &str,
) -> Result<(), CliError> {
    for (key, value) in file {
        let key: &str = key.get_ref();
        let path = format!("{prefix}{key}");
        compare_value(text, &path, value, read.get(key))?;
    }
    Ok(())
}

fn compare_value(
    text: &str,
    path: &str,
    value: &toml::Spanned<toml::de::DeValue<'_>>,
    read: Option<&toml::Value>,
) -> Result<(), CliError> {
    match (value.get_ref(), read) {
        (toml::de::DeValue::Table(inner), Some(toml::Value::Table(read))) => {
            compare_tables(text, inner, read, &format!("{path}."))
        }
        (toml::de::DeValue::Array(values), Some(toml::Value::Array(read))) => {
            if values.len() != read.len() {
                return Err(CliError::new(format!(
                    "scene: `{path}` has {} values: it takes {}",
                    values.len(),
                    read.len()
                ))
                .with_span(text, Some(value.span())));
            }
            for (element, read) in values.iter().zip(read) {
                compare_value(text, path, element, Some(read))?;
            }
            Ok(())
        }
        (toml::de::DeValue::Float(written), Some(toml::Value::Float(read))) => {
            let Ok(written) = written.as_str().parse::<f64>() else {
                return Ok(());
            };
            // An f64 field reads the value exactly, an f32 field to within its rounding (6·10⁻⁸).
            let narrowed = written.is_finite()
                && written != *read
                && !(read.is_finite()
                    && read.abs() >= f64::from(f32::MIN_POSITIVE)
                    && (read - written).abs() <= 1e-7 * written.abs());
            if narrowed {
                return Err(CliError::new(format!(
                    "scene: `{path}` = {written:e} is beyond single precision (it would read as \
                     {read:e}): give 0 or a magnitude in [1.2e-38, 3.4e38]"
                ))
                .with_span(text, Some(value.span())));
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

/// A position in metres: finite and within [`MAX_COORDINATE_M`] of the origin.
fn finite3(key: &str, v: [f32; 3]) -> Result<(), CliError> {
    check(
        v.iter()
            .all(|c| c.is_finite() && c.abs() <= MAX_COORDINATE_M),
        key,
        v,
        "must be finite and within 10 km of the origin",
    )
}

/// The scene `text` describes, every key it leaves out taking the default scene's value, as the default
/// scene file promises. Serde alone fills a key left out of a table the file does write from that
/// table's own type: a file with a `[simulation]` table got `SimParams::default()`'s wind, which is
/// still air, not the waving flag's (`SimParams::waving_flag`). One exception: with
/// `wind.per_substep = false` a left-out `wind.renewal_interval` is 0, the only value that goes with it.
/// `text` has been read as a scene already, so its keys and values are known to be valid.
///
/// A left-out image key ([`DEFAULT_IMAGE_KEYS`]) names an image built into the binary
/// ([`Scene::builtin_images`]), so that a scene file of a few keys in any folder shows the flag and the
/// painting.
fn with_default_scene_values(text: &str) -> Result<Scene, CliError> {
    let unexpected = |e: &dyn std::fmt::Display| CliError::new(format!("scene: {e}"));
    let given: toml::Table = text.parse().map_err(|e| unexpected(&e))?;
    let mut values = match toml::Value::try_from(Scene::default()) {
        Ok(toml::Value::Table(values)) => values,
        Ok(other) => return Err(unexpected(&format!("the default scene wrote {other}"))),
        Err(e) => return Err(unexpected(&e)),
    };
    let builtin_images: Vec<&'static str> = DEFAULT_IMAGE_KEYS
        .into_iter()
        .filter(|key| value_at(&given, key).is_none())
        .collect();
    // Holding the wind for the whole frame goes with no renewal interval: left out, it is 0 there.
    let per_frame = value_at(&given, "simulation.wind.per_substep")
        == Some(&toml::Value::Boolean(false))
        && value_at(&given, "simulation.wind.renewal_interval").is_none();
    lay_over(&mut values, given, "");
    if per_frame
        && let Some(interval) = value_at_mut(&mut values, "simulation.wind.renewal_interval")
    {
        *interval = toml::Value::Float(0.0);
    }
    let mut scene: Scene = toml::Value::Table(values)
        .try_into()
        .map_err(|e| unexpected(&e))?;
    scene.builtin_images = builtin_images;
    Ok(scene)
}

/// The value at a dotted `path` (`simulation.wind.seed`) of a TOML table.
fn value_at<'a>(table: &'a toml::Table, path: &str) -> Option<&'a toml::Value> {
    let (head, rest) = path.split_once('.').unwrap_or((path, ""));
    let value = table.get(head)?;
    if rest.is_empty() {
        Some(value)
    } else {
        value_at(value.as_table()?, rest)
    }
}

/// As [`value_at`], mutably: the value for the caller to replace.
fn value_at_mut<'a>(table: &'a mut toml::Table, path: &str) -> Option<&'a mut toml::Value> {
    let (head, rest) = path.split_once('.').unwrap_or((path, ""));
    let value = table.get_mut(head)?;
    if rest.is_empty() {
        Some(value)
    } else {
        value_at_mut(value.as_table_mut()?, rest)
    }
}

/// Lays `given` over `values` key by key and into sub-tables, except a given `simulation.method`, which
/// replaces the default's whole (a method names its kind and every knob of that kind).
fn lay_over(values: &mut toml::Table, given: toml::Table, prefix: &str) {
    for (key, value) in given {
        let path = format!("{prefix}{key}");
        match (values.get_mut(&key), value) {
            (Some(toml::Value::Table(inner)), toml::Value::Table(value))
                if path != "simulation.method" =>
            {
                lay_over(inner, value, &format!("{path}."));
            }
            (_, value) => {
                values.insert(key, value);
            }
        }
    }
}

impl Scene {
    /// Parses a scene from TOML text; relative paths resolve against `base_dir`. A key the text leaves
    /// out takes the default scene's value (`assets/default.scene.toml`, [`Scene::default`]).
    pub fn from_toml(text: &str, base_dir: &Path) -> Result<Scene, CliError> {
        // Read as written first, so that a bad key, type or value is reported with its line.
        let as_written: Scene = toml::from_str(text).map_err(|e| {
            let message = e.message().trim();
            // A key earlier versions wrote: say what replaced it, not only that it is unknown.
            let hint = if message.starts_with("unknown field `substeps_per_update`") {
                "; `wind.substeps_per_update` (a count of sub-steps) became `wind.renewal_interval`, \
                 the longest time the wind's forces are held, in seconds (4 of 40 sub-steps at 60 Hz: \
                 4/2400 s, about 0.00167; it is rounded down to whole sub-steps)"
            } else {
                ""
            };
            CliError::new(format!("scene: {message}{hint}")).with_span(text, e.span())
        })?;
        check_silent_conversions(text, &as_written)?;
        let mut scene = with_default_scene_values(text)?;
        scene.base_dir = base_dir.to_path_buf();
        scene.builtin_assets = false;
        scene.validate()?;
        Ok(scene)
    }

    /// The shipped default scene ([`DEFAULT_SCENE_TOML`]) with its images, as built into the binary.
    pub fn builtin_default() -> Result<Scene, CliError> {
        let mut scene = Scene::from_toml(DEFAULT_SCENE_TOML, Path::new(""))
            .map_err(|e| CliError::new(format!("the built-in default scene: {e}")))?;
        scene.builtin_assets = true;
        Ok(scene)
    }

    /// Reads and parses a scene file.
    pub fn load(path: &Path) -> Result<Scene, CliError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| CliError::new(format!("cannot read scene {}: {e}", path.display())))?;
        let base = path.parent().unwrap_or(Path::new("."));
        Scene::from_toml(&text, base).map_err(|e| CliError::new(format!("{}: {e}", path.display())))
    }

    /// The file's text for this scene (tests only: round trips); a serialisation error fails the test
    /// instead of yielding an empty text.
    #[cfg(test)]
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("a scene serialises to TOML")
    }

    /// Resolves a path written in the scene file.
    pub fn resolve(&self, relative: &str) -> PathBuf {
        self.base_dir.join(relative)
    }

    /// The bytes of the file that `key` names (relative to the scene file, or built in); the error
    /// names the key.
    pub fn read_asset(
        &self,
        key: &str,
        relative: &str,
    ) -> Result<std::borrow::Cow<'static, [u8]>, CliError> {
        let built_in = |name: &str| BUILTIN_ASSETS.iter().any(|(n, _)| *n == name);
        if self.builtin_assets || (self.builtin_images.contains(&key) && built_in(relative)) {
            return BUILTIN_ASSETS
                .iter()
                .find(|(name, _)| *name == relative)
                .map(|(_, bytes)| std::borrow::Cow::Borrowed(*bytes))
                .ok_or_else(|| {
                    let names: Vec<&str> = BUILTIN_ASSETS.iter().map(|(name, _)| *name).collect();
                    CliError::new(format!(
                        "scene: `{key}` = {relative:?}: the built-in default scene has only {}",
                        names.join(" and ")
                    ))
                });
        }
        let path = self.resolve(relative);
        std::fs::read(&path)
            .map(std::borrow::Cow::Owned)
            .map_err(|e| {
                CliError::new(format!(
                    "scene: `{key}` = {relative:?}: cannot read {}: {e}",
                    path.display()
                ))
            })
    }

    /// Checks every value's range; the error names the key.
    pub fn validate(&self) -> Result<(), CliError> {
        let f = &self.flag;
        for (key, side) in [("flag.columns", f.columns), ("flag.rows", f.rows)] {
            check(
                (2..=MAX_GRID_SIDE).contains(&side),
                key,
                side,
                "must lie in [2, 1024] particles",
            )?;
        }
        for (key, size) in [("flag.width", f.width), ("flag.height", f.height)] {
            check(
                size.is_finite() && size > 0.0 && size <= MAX_FLAG_SIZE_M,
                key,
                size,
                "must lie in (0, 100] m",
            )?;
        }
        check(
            f.areal_density.is_finite() && f.areal_density > 0.0,
            "flag.areal_density",
            f.areal_density,
            "must be finite and > 0 kg/m²",
        )?;
        // A file cannot name it (the enum's serde skips it); code that sets it gets the model instead.
        check(
            self.shading.path != EvaluationPath::Baseline,
            "shading.path",
            "baseline",
            "is a shading model: set `shading.model = \"baseline\"`",
        )?;
        // Checked in f64, as the simulator holds it (narrowed first, 1e308 was reported as inf).
        let origin = f.origin.to_array();
        check(
            origin
                .iter()
                .all(|c| c.is_finite() && c.abs() <= f64::from(MAX_COORDINATE_M)),
            "flag.origin",
            origin,
            "must be finite and within 10 km of the origin",
        )?;
        // The model's own checks (cells with no area, …), in its words.
        sheer_cloth::ClothModel::grid(&self.flag)
            .map_err(|e| CliError::new(format!("scene: [flag]: {e}")))?;
        for (i, collider) in self.simulation.collisions.colliders.iter().enumerate() {
            collider.validate().map_err(|e| {
                let key = e.name.trim_start_matches("collisions.colliders.");
                CliError::new(format!(
                    "scene: `simulation.collisions.colliders[{i}].{key}` = {}: {}",
                    e.value, e.reason
                ))
            })?;
        }
        self.simulation.validate().map_err(|e| {
            CliError::new(format!(
                "scene: `simulation.{}` = {}: {}",
                e.name, e.value, e.reason
            ))
        })?;
        let method = &self.simulation.method;
        check(
            method.substeps() <= MAX_SUBSTEPS,
            "simulation.method.substeps",
            method.substeps(),
            "must lie in [1, 100000]",
        )?;
        let iterations_key = match method {
            sheer_cloth::Method::ImplicitEuler { .. } => "simulation.method.cg_max_iterations",
            _ => "simulation.method.iterations",
        };
        check(
            method.iterations() <= MAX_ITERATIONS,
            iterations_key,
            method.iterations(),
            "must lie in [1, 10000]",
        )?;
        let s = &self.shading;
        check(
            s.optical_thickness
                .iter()
                .all(|t| t.is_finite() && *t > 0.0),
            "shading.optical_thickness",
            s.optical_thickness,
            "must be finite and > 0",
        )?;
        check(
            s.albedo_scale
                .iter()
                .all(|a| a.is_finite() && (0.0..=1.0).contains(a)),
            "shading.albedo_scale",
            s.albedo_scale,
            "must lie in [0, 1]",
        )?;
        check(
            (0.0..=1.0).contains(&s.baseline_alpha),
            "shading.baseline_alpha",
            s.baseline_alpha,
            "must lie in [0, 1]",
        )?;
        check(
            s.exposure.is_finite() && s.exposure > 0.0 && s.exposure <= MAX_RADIANCE,
            "shading.exposure",
            s.exposure,
            "must lie in (0, 1e6]",
        )?;
        check(
            (16..=8192).contains(&s.shadow_resolution),
            "shading.shadow_resolution",
            s.shadow_resolution,
            "must lie in [16, 8192] texels",
        )?;
        let l = &self.light;
        check(
            l.flux.is_finite() && (0.0..=MAX_FLUX_W).contains(&l.flux),
            "light.flux",
            l.flux,
            "must lie in [0, 1e6] W",
        )?;
        finite3("light.centre", l.centre)?;
        check(
            l.radius.is_finite() && l.radius > 0.0 && l.radius <= MAX_COORDINATE_M,
            "light.radius",
            l.radius,
            "must lie in (0, 10000] m",
        )?;
        // The orbit's angle is 2π t / period in f32: below about 1e-34 s it overflows within the hour
        // that t may run, and under a millisecond (a thousand turns a second, far beyond any frame
        // rate) the angle's f32 steps are radians wide, so its position is noise.
        check(
            l.period.is_finite() && (l.period == 0.0 || l.period.abs() >= 1e-3),
            "light.period",
            l.period,
            "must be 0 (the light stands still) or at least 0.001 s in magnitude",
        )?;
        check(
            l.phase.is_finite(),
            "light.phase",
            l.phase,
            "must be finite",
        )?;
        let c = &self.camera;
        finite3("camera.position", c.position)?;
        finite3("camera.target", c.target)?;
        // The view direction is their difference, normalised in f32: at coordinates of metres a
        // millimetre still fixes it to about 1e-4 rad, where 1e-30 m leaves no direction at all.
        // 1 % below 1 mm, so that a millimetre as written passes after f32 has rounded coordinates
        // of up to about 100 m (half an ulp there is 3.8e-6 m).
        let distance = glam::DVec3::from_array(c.target.map(f64::from))
            .distance(glam::DVec3::from_array(c.position.map(f64::from)));
        check(
            distance >= 0.99e-3,
            "camera.target",
            c.target,
            "must lie at least 1 mm from camera.position",
        )?;
        // The camera's up is +y: looking along it leaves no direction for "up" in the image (the
        // view matrix degenerates and nothing is drawn). 0.01 rad ≈ 0.6°.
        let view = (glam::Vec3::from_array(c.target) - glam::Vec3::from_array(c.position))
            .normalize_or_zero();
        check(
            view.cross(glam::Vec3::Y).length() >= 0.01,
            "camera.target",
            c.target,
            "the view direction from camera.position must not lie within 0.6° of the up axis (±y)",
        )?;
        check(
            c.vertical_fov_degrees > 1.0 && c.vertical_fov_degrees < 179.0,
            "camera.vertical_fov_degrees",
            c.vertical_fov_degrees,
            "must lie in (1, 179)",
        )?;
        let b = &self.background;
        check(
            b.colour
                .iter()
                .all(|v| v.is_finite() && (0.0..=MAX_RADIANCE).contains(v)),
            "background.colour",
            b.colour,
            "must lie in [0, 1e6] W/(m²·sr)",
        )?;
        check(
            b.radiance_scale.is_finite() && (0.0..=MAX_RADIANCE).contains(&b.radiance_scale),
            "background.radiance_scale",
            b.radiance_scale,
            "must lie in [0, 1e6] W/(m²·sr)",
        )?;
        let e = &self.environment;
        for (key, value) in [
            ("environment.sky_radiance", e.sky_radiance),
            ("environment.ground_radiance", e.ground_radiance),
        ] {
            check(
                value
                    .iter()
                    .all(|v| v.is_finite() && (0.0..=MAX_RADIANCE).contains(v)),
                key,
                value,
                "must lie in [0, 1e6] W/(m²·sr)",
            )?;
        }
        check(
            e.image_radiance_scale.is_finite()
                && (0.0..=MAX_RADIANCE).contains(&e.image_radiance_scale),
            "environment.image_radiance_scale",
            e.image_radiance_scale,
            "must lie in [0, 1e6] W/(m²·sr)",
        )?;
        let r = &self.render;
        check(
            (16..=8192).contains(&r.width),
            "render.width",
            r.width,
            "must lie in [16, 8192] pixels",
        )?;
        check(
            (16..=8192).contains(&r.height),
            "render.height",
            r.height,
            "must lie in [16, 8192] pixels",
        )?;
        check(
            matches!(r.samples, 1 | 4),
            "render.samples",
            r.samples,
            "must be 4 (anti-aliased edges) or 1 (none)",
        )?;
        check(
            r.fps.is_finite() && (FPS_RANGE.0..=FPS_RANGE.1).contains(&r.fps),
            "render.fps",
            r.fps,
            "must lie in [1, 1000] frames per simulated second",
        )?;
        check(
            r.warmup.is_finite() && (0.0..=600.0).contains(&r.warmup),
            "render.warmup",
            r.warmup,
            "must lie in [0, 600] s",
        )?;
        if let Some(sheet) = &self.static_sheet {
            finite3("static_sheet.centre", sheet.centre)?;
            check(
                sheet
                    .size
                    .iter()
                    .all(|v| v.is_finite() && *v > 0.0 && *v <= MAX_COORDINATE_M),
                "static_sheet.size",
                sheet.size,
                "must lie in (0, 10000] m",
            )?;
            check(
                sheet.tilt_degrees.is_finite(),
                "static_sheet.tilt_degrees",
                sheet.tilt_degrees,
                "must be finite",
            )?;
            check(
                sheet
                    .albedo
                    .iter()
                    .all(|a| a.is_finite() && (0.0..=1.0).contains(a)),
                "static_sheet.albedo",
                sheet.albedo,
                "must lie in [0, 1]",
            )?;
            check(
                (1..=1024).contains(&sheet.segments),
                "static_sheet.segments",
                sheet.segments,
                "must lie in [1, 1024]",
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assets() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets")
    }

    fn parse(text: &str) -> Result<Scene, String> {
        Scene::from_toml(text, &assets()).map_err(|e| e.to_string())
    }

    #[test]
    fn the_shipped_default_scene_documents_exactly_the_defaults() {
        let path = assets().join("default.scene.toml");
        let scene = Scene::load(&path).unwrap();
        let default = Scene {
            base_dir: scene.base_dir.clone(),
            builtin_assets: false,
            // The template leaves its image keys out, so that a copy works from any folder.
            builtin_images: DEFAULT_IMAGE_KEYS.to_vec(),
            ..Scene::default()
        };
        assert_eq!(scene, default);
        // And every key of the defaults appears in the file (the file documents them all).
        let text = std::fs::read_to_string(&path).unwrap();
        let round_trip = Scene::default().to_toml();
        for line in round_trip.lines() {
            if let Some((key, _)) = line.split_once(" = ") {
                assert!(
                    text.contains(&format!("{} =", key.trim())),
                    "undocumented key {key}"
                );
            }
        }
    }

    /// The default sky and ground are the painting's daylight: the mean linear radiance of its upper
    /// and lower thirds, times the painting's white, rounded to the two decimals the file gives.
    #[test]
    fn the_default_sky_and_ground_are_the_paintings_daylight() {
        let painting =
            image::load_from_memory(include_bytes!("../../../assets/faroe_landscape.png"))
                .unwrap()
                .to_rgb8();
        let (width, height) = painting.dimensions();
        let mean = |rows: std::ops::Range<u32>| {
            let mut sum = [0.0f64; 3];
            for y in rows.clone() {
                for x in 0..width {
                    let p = painting.get_pixel(x, y).0;
                    for c in 0..3 {
                        sum[c] += f64::from(sheer_slab::render::srgb8_to_linear(p[c]));
                    }
                }
            }
            let count = f64::from(width) * f64::from(rows.end - rows.start);
            sum.map(|v| v / count * f64::from(BackgroundSection::default().radiance_scale))
        };
        let third = height / 3;
        for (default, measured) in [
            (DEFAULT_SKY_RADIANCE, mean(0..third)),
            (DEFAULT_GROUND_RADIANCE, mean(height - third..height)),
        ] {
            for c in 0..3 {
                assert!(
                    (f64::from(default[c]) - measured[c]).abs() <= 0.005 + 1e-6,
                    "{default:?} vs {measured:?}"
                );
            }
        }
    }

    #[test]
    fn a_copy_of_the_default_scene_works_from_any_folder() {
        let folder = std::env::temp_dir().join(format!("sheer-template-{}", std::process::id()));
        std::fs::create_dir_all(&folder).unwrap();
        let copy = folder.join("my.scene.toml");
        std::fs::copy(assets().join("default.scene.toml"), &copy).unwrap();
        let scene = Scene::load(&copy).unwrap();
        let flag = scene
            .read_asset(
                "shading.albedo_texture",
                scene.shading.albedo_texture.as_deref().unwrap(),
            )
            .unwrap();
        let painting = scene
            .read_asset(
                "background.image",
                scene.background.image.as_deref().unwrap(),
            )
            .unwrap();
        assert_eq!(
            &*flag,
            &include_bytes!("../../../assets/faroe_flag.png")[..]
        );
        assert_eq!(
            &*painting,
            &include_bytes!("../../../assets/faroe_landscape.png")[..]
        );
        std::fs::remove_dir_all(&folder).unwrap();
    }

    #[test]
    fn the_default_flag_uses_the_studys_choice() {
        // docs/choice.toml is written by `sheer study choose|all`: the cheapest method within the
        // flag's error budget, measured on the flag recorded with it. The default scene must run that
        // method, and on that flag: a changed default (fabric, wind, grid) needs a new choice.
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../docs/choice.toml");
        let text = std::fs::read_to_string(&path).unwrap();
        let file: sheer_study::ChoiceFile = toml::from_str(&text).unwrap();
        assert!(!file.quick, "docs/choice.toml comes from a --quick run");
        let scene = Scene::load(&assets().join("default.scene.toml")).unwrap();
        let method = scene.simulation.method;
        assert_eq!(
            (method.name(), method.substeps(), method.iterations()),
            (
                file.choice.method.as_str(),
                file.choice.substeps,
                file.choice.iterations
            ),
            "the default scene's method differs from docs/choice.toml"
        );
        assert_eq!(
            (scene.flag, &scene.simulation),
            (file.scene.flag, &file.scene.simulation),
            "docs/choice.toml was measured on another flag: rerun `cargo run --release -- study choose --out docs`"
        );
    }

    #[test]
    fn an_empty_file_is_the_default_scene() {
        let default = Scene {
            base_dir: assets(),
            builtin_assets: false,
            builtin_images: DEFAULT_IMAGE_KEYS.to_vec(),
            ..Scene::default()
        };
        assert_eq!(parse("").unwrap(), default);
    }

    #[test]
    fn every_section_accepts_its_keys() {
        let scene = parse(
            r#"
            [flag]
            columns = 16
            rows = 11
            [simulation.method]
            kind = "pbd"
            substeps = 2
            iterations = 8
            stiffness = 0.9
            [shading]
            model = "split"
            path = "cpu"
            convention = "paper_literal"
            optical_thickness = [1.0, 2.0, 3.0]
            [light]
            period = 0.0
            [static_sheet]
            albedo = [0.5, 0.5, 0.5]
            segments = 8
            "#,
        )
        .unwrap();
        assert_eq!(scene.flag.columns, 16);
        assert_eq!(
            scene.simulation.method,
            sheer_cloth::Method::Pbd {
                substeps: 2,
                iterations: 8,
                stiffness: 0.9
            }
        );
        assert_eq!(scene.shading.model, ShadingModel::Split);
        assert_eq!(scene.shading.path, EvaluationPath::Cpu);
        assert_eq!(scene.shading.convention, IrradianceConvention::PaperLiteral);
        assert_eq!(scene.light.position(5.0), scene.light.position(0.0));
        assert_eq!(scene.static_sheet.unwrap().segments, 8);
    }

    #[test]
    fn unknown_keys_are_errors_naming_the_key() {
        for (text, key) in [
            ("colour = 1", "colour"),
            ("[flag]\ncolumn = 3", "column"),
            ("[simulation.wind]\nspeed = 3.0", "speed"),
            ("[shading]\ntau = 2.0", "tau"),
            ("[light]\npower = 2.0", "power"),
            ("[camera]\nfov = 2.0", "fov"),
            ("[render]\nsize = 2", "size"),
            ("[static_sheet]\nthickness = 2", "thickness"),
        ] {
            let error = parse(text).unwrap_err();
            assert!(
                error.contains(key) && error.contains("line"),
                "{text}: {error}"
            );
        }
    }

    #[test]
    fn out_of_range_values_are_errors_naming_the_key() {
        for (text, key) in [
            ("[flag]\ncolumns = 1", "flag.columns"),
            ("[flag]\nareal_density = -0.2", "flag.areal_density"),
            (
                "[simulation.stretch]\nstiffness = 0.0",
                "simulation.stretch.stiffness",
            ),
            (
                "[simulation.method]\nkind = \"xpbd\"\nsubsteps = 0\niterations = 3",
                "method.substeps",
            ),
            ("[simulation]\nair_damping = -1.0", "air_damping"),
            (
                "[shading]\noptical_thickness = [0.0, 1.0, 1.0]",
                "shading.optical_thickness",
            ),
            (
                "[shading]\nalbedo_scale = [1.5, 1.0, 1.0]",
                "shading.albedo_scale",
            ),
            ("[shading]\nbaseline_alpha = 2.0", "shading.baseline_alpha"),
            ("[shading]\nexposure = 0.0", "shading.exposure"),
            (
                "[shading]\nshadow_resolution = 8",
                "shading.shadow_resolution",
            ),
            ("[light]\nflux = -1.0", "light.flux"),
            ("[light]\nradius = 0.0", "light.radius"),
            ("[camera]\ntarget = [0.75, 0.25, 2.4]", "camera.target"),
            (
                "[camera]\nvertical_fov_degrees = 180.0",
                "camera.vertical_fov_degrees",
            ),
            (
                "[background]\nradiance_scale = -1.0",
                "background.radiance_scale",
            ),
            ("[render]\nwidth = 4", "render.width"),
            ("[render]\nfps = 0.0", "render.fps"),
            ("[static_sheet]\nsize = [0.0, 1.0]", "static_sheet.size"),
            (
                "[static_sheet]\nalbedo = [1.0, -1.0, 1.0]",
                "static_sheet.albedo",
            ),
            ("[static_sheet]\nsegments = 0", "static_sheet.segments"),
            ("[shading]\nmodel = \"phong\"", "model"),
            ("[render]\nwidth = \"big\"", "width"),
        ] {
            let error = parse(text).unwrap_err();
            assert!(error.contains(key), "{text}: {error}");
            assert_eq!(error.lines().count(), 1, "{error}");
        }
    }

    #[test]
    fn the_scattering_key_takes_single_or_all_orders_and_names_itself_when_wrong() {
        assert_eq!(parse("").unwrap().shading.scattering, ScatteringOrders::All);
        let single = parse("[shading]\nscattering = \"single\"").unwrap();
        assert_eq!(single.shading.scattering, ScatteringOrders::Single);
        for wrong in ["double", "all_orders", "Single"] {
            let error = parse(&format!("[shading]\nscattering = \"{wrong}\"")).unwrap_err();
            assert!(
                error.contains("scattering")
                    && error.contains(wrong)
                    && error.contains("all-orders"),
                "{error}"
            );
            assert_eq!(error.lines().count(), 1, "{error}");
        }
    }
}

/// Scene-file parsing, key by key: every key is accepted and lands where it should, and every kind of
/// bad value is a one-line error naming its key.
#[cfg(test)]
mod key_tests {
    use super::*;

    fn assets() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets")
    }

    fn parse(text: &str) -> Result<Scene, String> {
        Scene::from_toml(text, &assets()).map_err(|e| e.to_string())
    }

    use super::{value_at, value_at_mut};

    /// Every leaf key of a TOML table, dotted.
    fn leaf_keys(table: &toml::Table, prefix: &str, keys: &mut Vec<String>) {
        for (key, value) in table {
            let path = format!("{prefix}{key}");
            match value.as_table() {
                Some(inner) => leaf_keys(inner, &format!("{path}."), keys),
                None => keys.push(path),
            }
        }
    }

    /// Every key but the method's knobs (see `every_method_kind_takes_its_knobs`), with a valid
    /// value other than its default; f32 values are exact in binary so they print back unchanged.
    const EVERY_KEY: &[(&str, &str)] = &[
        ("flag.columns", "32"),
        ("flag.rows", "23"),
        ("flag.width", "1.5"),
        ("flag.height", "1.25"),
        ("flag.areal_density", "0.25"),
        ("flag.origin", "[0.5, 1.5, -0.5]"),
        ("simulation.gravity", "[0.0, -9.5, 0.0]"),
        ("simulation.air_damping", "0.25"),
        ("simulation.long_range_attachments", "false"),
        ("simulation.parallel_min_particles", "1024"),
        ("simulation.stretch.enabled", "false"),
        ("simulation.stretch.stiffness", "500.0"),
        ("simulation.stretch.damping", "0.5"),
        ("simulation.shear.enabled", "false"),
        ("simulation.shear.stiffness", "50.0"),
        ("simulation.shear.damping", "0.25"),
        ("simulation.bend.enabled", "false"),
        ("simulation.bend.stiffness", "7.5"),
        ("simulation.bend.damping", "0.125"),
        ("simulation.wind.velocity", "[3.0, 0.0, 1.5]"),
        ("simulation.wind.air_density", "1.25"),
        ("simulation.wind.drag_coefficient", "1.5"),
        ("simulation.wind.lift_coefficient", "0.25"),
        ("simulation.wind.gust_strength", "0.25"),
        ("simulation.wind.turbulence", "0.5"),
        ("simulation.wind.gust_frequency", "0.75"),
        ("simulation.wind.seed", "7"),
        ("simulation.wind.per_substep", "false"),
        // The default flag's is 0.002 s; held for the frame, the forces take none.
        ("simulation.wind.renewal_interval", "0.0"),
        ("simulation.divergence.max_speed", "150.0"),
        ("simulation.divergence.max_strain", "5.0"),
        ("simulation.collisions.self_collision", "true"),
        ("simulation.collisions.thickness", "0.005"),
        ("simulation.collisions.friction", "0.5"),
        (
            "simulation.collisions.colliders",
            "[{ kind = \"sphere\", center = [0.5, 0.0, 0.5], radius = 0.25 }]",
        ),
        ("pole.collider", "true"),
        ("shading.model", "\"split\""),
        ("shading.path", "\"vertex\""),
        ("shading.optical_thickness", "[1.5, 2.5, 3.0]"),
        ("shading.albedo_scale", "[0.5, 0.75, 1.0]"),
        ("shading.albedo_texture", "\"\""),
        ("shading.thickness_texture", "\"faroe_flag.png\""),
        ("shading.convention", "\"paper_literal\""),
        ("shading.scattering", "\"single\""),
        ("shading.all_orders_lookup", "\"vertex\""),
        ("shading.baseline_alpha", "0.5"),
        ("shading.exposure", "1.5"),
        ("shading.shadows", "false"),
        ("shading.shadow_resolution", "1024"),
        ("light.flux", "125.0"),
        ("light.centre", "[0.5, 0.5, 0.25]"),
        ("light.radius", "2.5"),
        ("light.period", "-6.0"),
        ("light.phase", "1.5"),
        ("light.marker", "false"),
        ("camera.position", "[1.0, 0.5, 3.0]"),
        ("camera.target", "[0.5, 0.25, 0.0]"),
        ("camera.vertical_fov_degrees", "30.0"),
        ("background.image", "\"\""),
        ("background.colour", "[0.25, 0.5, 0.75]"),
        ("background.radiance_scale", "2.0"),
        ("environment.sky_light", "false"),
        ("environment.sky_radiance", "[1.0, 1.5, 2.0]"),
        ("environment.ground_radiance", "[0.5, 0.25, 0.125]"),
        ("environment.image", "\"faroe_landscape.png\""),
        ("environment.image_radiance_scale", "3.0"),
        ("render.width", "640"),
        ("render.height", "480"),
        ("render.fps", "30.0"),
        ("render.samples", "1"),
        ("render.warmup", "0.5"),
        ("static_sheet.centre", "[0.5, 0.25, 0.0]"),
        ("static_sheet.size", "[2.0, 0.5]"),
        ("static_sheet.tilt_degrees", "30.0"),
        ("static_sheet.albedo", "[0.5, 0.25, 1.0]"),
        ("static_sheet.segments", "4"),
    ];

    /// `[section]\nkey = value` for a dotted key.
    fn one_key(path: &str, value: &str) -> String {
        let (section, key) = path.rsplit_once('.').unwrap();
        format!("[{section}]\n{key} = {value}\n")
    }

    #[test]
    fn every_key_is_accepted_and_lands_in_the_scene() {
        for (path, value) in EVERY_KEY {
            let text = one_key(path, value);
            let scene = parse(&text).unwrap_or_else(|e| panic!("{text}: {e}"));
            let mut written: toml::Table = toml::from_str(&scene.to_toml()).unwrap();
            let expected: toml::Table = toml::from_str(&format!("v = {value}")).unwrap();
            assert_eq!(value_at(&written, path), Some(&expected["v"]), "{text}");
            let default: toml::Table = toml::from_str(
                &Scene {
                    static_sheet: path.starts_with("static_sheet.").then(StaticSheet::default),
                    ..Scene::default()
                }
                .to_toml(),
            )
            .unwrap();
            assert_ne!(value_at(&default, path), Some(&expected["v"]), "{path}");
            // Every other key is the default scene's, as `assets/default.scene.toml` promises: not
            // the default of the key's own table, which for the wind is the library's still air.
            match value_at(&default, path) {
                Some(value) => *value_at_mut(&mut written, path).unwrap() = value.clone(),
                // A key the default leaves out (an optional texture).
                None => {
                    let (table, key) = path.rsplit_once('.').unwrap();
                    let table = value_at_mut(&mut written, table).unwrap();
                    table.as_table_mut().unwrap().remove(key);
                }
            }
            if *path == "simulation.wind.per_substep" {
                // Held for the whole frame, the wind has no renewal interval.
                let interval =
                    value_at_mut(&mut written, "simulation.wind.renewal_interval").unwrap();
                assert_eq!(*interval, toml::Value::Float(0.0));
                *interval = value_at(&default, "simulation.wind.renewal_interval")
                    .unwrap()
                    .clone();
            }
            assert_eq!(written, default, "{text}");
        }
    }

    #[test]
    fn a_table_given_in_part_keeps_the_default_scene_values_of_the_rest() {
        let flag = Scene::default().simulation;
        // A `[simulation]` table of one key leaves the waving flag's wind alone.
        let scene = parse("[simulation]\nair_damping = 0.1").unwrap();
        assert_eq!(scene.simulation.air_damping, 0.1);
        assert_eq!(scene.simulation.wind, flag.wind);
        // A `[simulation.wind]` table of one key leaves its gusts and its hold alone.
        let scene = parse("[simulation.wind]\nseed = 7").unwrap();
        assert_eq!(scene.simulation.wind.seed, 7);
        assert_eq!(scene.simulation.wind.gust_strength, flag.wind.gust_strength);
        assert_eq!(
            scene.simulation.wind.renewal_interval,
            flag.wind.renewal_interval
        );
        assert!(flag.wind.renewal_interval > 0.0 && flag.wind.gust_strength != 0.3);
        // A method replaces the default's whole, knobs and all.
        let scene = parse("[simulation.method]\nkind = \"verlet\"\nsubsteps = 100").unwrap();
        assert_eq!(
            scene.simulation.method,
            sheer_cloth::Method::Verlet { substeps: 100 }
        );
    }

    #[test]
    fn the_key_table_covers_every_key_of_the_scene() {
        // A scene with every optional part present, so that every key is written out.
        let full = Scene {
            static_sheet: Some(StaticSheet::default()),
            shading: ShadingSection {
                thickness_texture: Some("weave.png".into()),
                ..ShadingSection::default()
            },
            environment: EnvironmentSection {
                image: Some("sky.png".into()),
                ..EnvironmentSection::default()
            },
            ..Scene::default()
        };
        let table: toml::Table = toml::from_str(&full.to_toml()).unwrap();
        let mut keys = Vec::new();
        leaf_keys(&table, "", &mut keys);
        let tested: Vec<&str> = EVERY_KEY.iter().map(|(path, _)| *path).collect();
        for key in &keys {
            if !key.starts_with("simulation.method.") {
                assert!(tested.contains(&key.as_str()), "key `{key}` is not tested");
            }
        }
        for path in tested {
            assert!(keys.iter().any(|k| k == path), "`{path}` is not a key");
        }
    }

    #[test]
    fn every_method_kind_takes_its_knobs() {
        use sheer_cloth::Method;
        for (text, expected) in [
            (
                "kind = \"explicit_euler\"\nsubsteps = 1600",
                Method::ExplicitEuler { substeps: 1600 },
            ),
            (
                "kind = \"symplectic_euler\"\nsubsteps = 200",
                Method::SymplecticEuler { substeps: 200 },
            ),
            (
                "kind = \"verlet\"\nsubsteps = 150",
                Method::Verlet { substeps: 150 },
            ),
            (
                "kind = \"implicit_euler\"\nsubsteps = 2\ncg_max_iterations = 50\ncg_tolerance = 1e-5",
                Method::ImplicitEuler {
                    substeps: 2,
                    cg_max_iterations: 50,
                    cg_tolerance: 1e-5,
                },
            ),
            (
                "kind = \"pbd\"\nsubsteps = 4\niterations = 12\nstiffness = 0.5",
                Method::Pbd {
                    substeps: 4,
                    iterations: 12,
                    stiffness: 0.5,
                },
            ),
            (
                "kind = \"xpbd\"\nsubsteps = 3\niterations = 15",
                Method::Xpbd {
                    substeps: 3,
                    iterations: 15,
                },
            ),
            (
                "kind = \"small_steps_xpbd\"\nsubsteps = 30",
                Method::SmallStepsXpbd { substeps: 30 },
            ),
        ] {
            let scene = parse(&format!("[simulation.method]\n{text}")).unwrap();
            assert_eq!(scene.simulation.method, expected, "{text}");
        }
        // Every kind as the scene writes it reads back the same: the flat table that reads a method
        // (`MethodTable` in sheer-cloth) is kept by hand beside the derived writer.
        let stable = Method::NAMES.map(|name| Method::stable_flag_setting(name).unwrap());
        for method in Method::all_with_substeps(3, 7).into_iter().chain(stable) {
            let mut scene = parse("").unwrap();
            scene.simulation.method = method;
            let text = scene.to_toml();
            assert_eq!(parse(&text).unwrap().simulation.method, method, "{text}");
        }
    }

    /// Asserts that `text` is refused with one line that contains every needle.
    fn assert_refused(text: &str, needles: &[&str]) {
        let error = match parse(text) {
            Ok(_) => panic!("accepted: {text}"),
            Err(error) => error,
        };
        assert_eq!(error.lines().count(), 1, "{text}: {error}");
        for needle in needles {
            assert!(error.contains(needle), "{text}: `{error}` lacks `{needle}`");
        }
    }

    #[test]
    fn numbers_that_single_precision_cannot_hold_are_errors_naming_the_key() {
        // Found by an audit: 1e308 was reported as "got inf", 1e-300 silently became 0 (a still light)
        // and 1e-44 a subnormal that made the light's position infinite mid-run.
        for (text, key) in [
            ("[light]\nperiod = 1e-44", "light.period"),
            ("[light]\nperiod = -1e-40", "light.period"),
            ("[light]\nperiod = 1e-300", "light.period"),
            ("[light]\nradius = 1e308", "light.radius"),
            ("[light]\ncentre = [0.0, 1e39, 0.0]", "light.centre"),
            (
                "[shading]\noptical_thickness = [2.0, 2.0, 1e308]",
                "shading.optical_thickness",
            ),
        ] {
            assert_refused(text, &[key, "beyond single precision"]);
        }
        // An f64 field holds such values exactly, and its own range check speaks.
        assert_refused(
            "[flag]\norigin = [1e308, 0.0, 0.0]",
            &["flag.origin", "1e308"],
        );
        // Ordinary values round to f32 and pass; the light's period has its own floor.
        parse("[light]\nperiod = 0.1\nradius = 1.3").unwrap();
        parse("[light]\nperiod = 0.0").unwrap();
        assert_refused("[light]\nperiod = 1e-30", &["light.period", "0.001"]);
    }

    #[test]
    fn nan_and_infinite_values_are_errors_naming_the_key() {
        // X stands for nan, inf and -inf in turn.
        for (template, key) in [
            ("[flag]\nwidth = X", "flag.width"),
            ("[flag]\nheight = X", "flag.height"),
            ("[flag]\nareal_density = X", "flag.areal_density"),
            ("[flag]\norigin = [0.0, X, 0.0]", "flag.origin"),
            (
                "[simulation]\ngravity = [0.0, X, 0.0]",
                "simulation.gravity",
            ),
            ("[simulation]\nair_damping = X", "simulation.air_damping"),
            (
                "[simulation.method]\nkind = \"implicit_euler\"\nsubsteps = 1\ncg_max_iterations = 9\ncg_tolerance = X",
                "simulation.method.cg_tolerance",
            ),
            (
                "[simulation.method]\nkind = \"pbd\"\nsubsteps = 1\niterations = 9\nstiffness = X",
                "simulation.method.stiffness",
            ),
            (
                "[simulation.stretch]\nstiffness = X",
                "simulation.stretch.stiffness",
            ),
            (
                "[simulation.stretch]\ndamping = X",
                "simulation.stretch.damping",
            ),
            (
                "[simulation.shear]\nstiffness = X",
                "simulation.shear.stiffness",
            ),
            (
                "[simulation.shear]\ndamping = X",
                "simulation.shear.damping",
            ),
            (
                "[simulation.bend]\nstiffness = X",
                "simulation.bend.stiffness",
            ),
            ("[simulation.bend]\ndamping = X", "simulation.bend.damping"),
            (
                "[simulation.wind]\nvelocity = [X, 0.0, 0.0]",
                "simulation.wind.velocity",
            ),
            (
                "[simulation.wind]\nair_density = X",
                "simulation.wind.air_density",
            ),
            (
                "[simulation.wind]\ndrag_coefficient = X",
                "simulation.wind.drag_coefficient",
            ),
            (
                "[simulation.wind]\nlift_coefficient = X",
                "simulation.wind.lift_coefficient",
            ),
            (
                "[simulation.wind]\ngust_strength = X",
                "simulation.wind.gust_strength",
            ),
            (
                "[simulation.wind]\nturbulence = X",
                "simulation.wind.turbulence",
            ),
            (
                "[simulation.wind]\ngust_frequency = X",
                "simulation.wind.gust_frequency",
            ),
            (
                "[simulation.divergence]\nmax_speed = X",
                "simulation.divergence.max_speed",
            ),
            (
                "[simulation.divergence]\nmax_strain = X",
                "simulation.divergence.max_strain",
            ),
            (
                "[shading]\noptical_thickness = [2.0, X, 2.0]",
                "shading.optical_thickness",
            ),
            (
                "[shading]\nalbedo_scale = [X, 1.0, 1.0]",
                "shading.albedo_scale",
            ),
            ("[shading]\nbaseline_alpha = X", "shading.baseline_alpha"),
            ("[shading]\nexposure = X", "shading.exposure"),
            ("[light]\nflux = X", "light.flux"),
            ("[light]\ncentre = [0.0, 0.0, X]", "light.centre"),
            ("[light]\nradius = X", "light.radius"),
            ("[light]\nperiod = X", "light.period"),
            ("[light]\nphase = X", "light.phase"),
            ("[camera]\nposition = [X, 0.0, 2.0]", "camera.position"),
            ("[camera]\ntarget = [0.0, X, 0.0]", "camera.target"),
            (
                "[camera]\nvertical_fov_degrees = X",
                "camera.vertical_fov_degrees",
            ),
            ("[background]\ncolour = [0.2, 0.2, X]", "background.colour"),
            (
                "[background]\nradiance_scale = X",
                "background.radiance_scale",
            ),
            (
                "[environment]\nsky_radiance = [X, 1.0, 1.0]",
                "environment.sky_radiance",
            ),
            (
                "[environment]\nground_radiance = [0.1, X, 0.1]",
                "environment.ground_radiance",
            ),
            (
                "[environment]\nimage_radiance_scale = X",
                "environment.image_radiance_scale",
            ),
            ("[render]\nfps = X", "render.fps"),
            ("[render]\nwarmup = X", "render.warmup"),
            (
                "[static_sheet]\ncentre = [X, 0.0, 0.0]",
                "static_sheet.centre",
            ),
            ("[static_sheet]\nsize = [1.0, X]", "static_sheet.size"),
            (
                "[static_sheet]\ntilt_degrees = X",
                "static_sheet.tilt_degrees",
            ),
            (
                "[static_sheet]\nalbedo = [X, 0.5, 0.5]",
                "static_sheet.albedo",
            ),
        ] {
            for special in ["nan", "inf", "-inf"] {
                assert_refused(&template.replace('X', special), &[key]);
            }
        }
    }

    #[test]
    fn out_of_range_values_are_errors_naming_the_key() {
        let implicit = "[simulation.method]\nkind = \"implicit_euler\"\nsubsteps = 1\n";
        let pbd = "[simulation.method]\nkind = \"pbd\"\nsubsteps = 1\n";
        for (text, key) in [
            ("[flag]\ncolumns = 1".to_string(), "flag.columns"),
            ("[flag]\ncolumns = 1025".into(), "flag.columns"),
            // Found by the audit: this grid aborted the program on allocation failure.
            (
                "[flag]\ncolumns = 100000\nrows = 100000".into(),
                "flag.columns",
            ),
            ("[flag]\nrows = 1".into(), "flag.rows"),
            ("[flag]\nrows = 5000".into(), "flag.rows"),
            ("[flag]\nwidth = 0.0".into(), "flag.width"),
            ("[flag]\nwidth = 101.0".into(), "flag.width"),
            ("[flag]\nheight = -1.0".into(), "flag.height"),
            ("[flag]\nareal_density = 0.0".into(), "flag.areal_density"),
            ("[flag]\norigin = [2e4, 0.0, 0.0]".into(), "flag.origin"),
            (
                "[simulation]\nair_damping = -1.0".into(),
                "simulation.air_damping",
            ),
            (
                "[simulation.method]\nkind = \"verlet\"\nsubsteps = 0".into(),
                "simulation.method.substeps",
            ),
            (
                "[simulation.method]\nkind = \"verlet\"\nsubsteps = 100001".into(),
                "simulation.method.substeps",
            ),
            (
                format!("{implicit}cg_max_iterations = 0\ncg_tolerance = 1e-6"),
                "simulation.method.cg_max_iterations",
            ),
            (
                format!("{implicit}cg_max_iterations = 10001\ncg_tolerance = 1e-6"),
                "simulation.method.cg_max_iterations",
            ),
            (
                format!("{implicit}cg_max_iterations = 10\ncg_tolerance = 0.0"),
                "simulation.method.cg_tolerance",
            ),
            (
                format!("{pbd}iterations = 0\nstiffness = 1.0"),
                "simulation.method.iterations",
            ),
            (
                format!("{pbd}iterations = 10001\nstiffness = 1.0"),
                "simulation.method.iterations",
            ),
            (
                format!("{pbd}iterations = 4\nstiffness = 1.5"),
                "simulation.method.stiffness",
            ),
            (
                format!("{pbd}iterations = 4\nstiffness = 0.0"),
                "simulation.method.stiffness",
            ),
            (
                "[simulation.method]\nkind = \"xpbd\"\nsubsteps = 1\niterations = 0".into(),
                "simulation.method.iterations",
            ),
            (
                "[simulation.stretch]\nstiffness = 0.0".into(),
                "simulation.stretch.stiffness",
            ),
            (
                "[simulation.stretch]\ndamping = -1.0".into(),
                "simulation.stretch.damping",
            ),
            (
                "[simulation.shear]\nstiffness = -5.0".into(),
                "simulation.shear.stiffness",
            ),
            (
                "[simulation.shear]\ndamping = -1.0".into(),
                "simulation.shear.damping",
            ),
            (
                "[simulation.bend]\nstiffness = 0.0".into(),
                "simulation.bend.stiffness",
            ),
            (
                "[simulation.bend]\ndamping = -0.5".into(),
                "simulation.bend.damping",
            ),
            (
                "[simulation.wind]\nair_density = -1.0".into(),
                "simulation.wind.air_density",
            ),
            (
                "[simulation.wind]\ndrag_coefficient = -1.0".into(),
                "simulation.wind.drag_coefficient",
            ),
            (
                "[simulation.wind]\nlift_coefficient = -1.0".into(),
                "simulation.wind.lift_coefficient",
            ),
            (
                "[simulation.wind]\ngust_strength = -1.0".into(),
                "simulation.wind.gust_strength",
            ),
            (
                "[simulation.wind]\nturbulence = -1.0".into(),
                "simulation.wind.turbulence",
            ),
            (
                "[simulation.wind]\ngust_frequency = 0.0".into(),
                "simulation.wind.gust_frequency",
            ),
            (
                "[simulation.wind]\nrenewal_interval = -0.002".into(),
                "simulation.wind.renewal_interval",
            ),
            (
                "[simulation.divergence]\nmax_speed = 0.0".into(),
                "simulation.divergence.max_speed",
            ),
            (
                "[simulation.divergence]\nmax_strain = -1.0".into(),
                "simulation.divergence.max_strain",
            ),
            (
                "[shading]\noptical_thickness = [0.0, 1.0, 1.0]".into(),
                "shading.optical_thickness",
            ),
            (
                "[shading]\nalbedo_scale = [1.5, 1.0, 1.0]".into(),
                "shading.albedo_scale",
            ),
            (
                "[shading]\nalbedo_scale = [1.0, -0.5, 1.0]".into(),
                "shading.albedo_scale",
            ),
            (
                "[shading]\nbaseline_alpha = 2.0".into(),
                "shading.baseline_alpha",
            ),
            (
                "[shading]\nbaseline_alpha = -0.1".into(),
                "shading.baseline_alpha",
            ),
            ("[shading]\nexposure = 0.0".into(), "shading.exposure"),
            ("[shading]\nexposure = 2e6".into(), "shading.exposure"),
            ("[light]\nflux = -1.0".into(), "light.flux"),
            // Found by the audit: this flux wrote infinite pixels into the EXR.
            ("[light]\nflux = 3e38".into(), "light.flux"),
            ("[light]\nflux = 2e6".into(), "light.flux"),
            ("[light]\ncentre = [0.0, -2e4, 0.0]".into(), "light.centre"),
            ("[light]\nradius = 0.0".into(), "light.radius"),
            ("[light]\nradius = 2e4".into(), "light.radius"),
            (
                "[camera]\nposition = [0.0, 0.0, 2e4]".into(),
                "camera.position",
            ),
            (
                "[camera]\ntarget = [0.75, 0.25, 2.4]".into(),
                "camera.target",
            ),
            (
                "[camera]\nvertical_fov_degrees = 1.0".into(),
                "camera.vertical_fov_degrees",
            ),
            (
                "[camera]\nvertical_fov_degrees = 180.0".into(),
                "camera.vertical_fov_degrees",
            ),
            (
                "[background]\ncolour = [-1.0, 0.0, 0.0]".into(),
                "background.colour",
            ),
            (
                "[background]\ncolour = [2e6, 0.0, 0.0]".into(),
                "background.colour",
            ),
            (
                "[background]\nradiance_scale = -1.0".into(),
                "background.radiance_scale",
            ),
            (
                "[background]\nradiance_scale = 2e6".into(),
                "background.radiance_scale",
            ),
            ("[render]\nwidth = 4".into(), "render.width"),
            ("[render]\nwidth = 9000".into(), "render.width"),
            ("[render]\nheight = 8".into(), "render.height"),
            ("[render]\nheight = 10000".into(), "render.height"),
            ("[render]\nsamples = 2".into(), "render.samples"),
            ("[render]\nsamples = 0".into(), "render.samples"),
            ("[render]\nfps = 0.0".into(), "render.fps"),
            ("[render]\nfps = 0.5".into(), "render.fps"),
            ("[render]\nfps = 2000.0".into(), "render.fps"),
            // Found by the audit: 1e30 frames per second looped for billions of steps.
            ("[render]\nfps = 1e30".into(), "render.fps"),
            ("[render]\nwarmup = -1.0".into(), "render.warmup"),
            ("[render]\nwarmup = 601.0".into(), "render.warmup"),
            (
                "[static_sheet]\ncentre = [2e4, 0.0, 0.0]".into(),
                "static_sheet.centre",
            ),
            (
                "[static_sheet]\nsize = [0.0, 1.0]".into(),
                "static_sheet.size",
            ),
            (
                "[static_sheet]\nsize = [2e4, 1.0]".into(),
                "static_sheet.size",
            ),
            (
                "[static_sheet]\nalbedo = [1.0, -1.0, 1.0]".into(),
                "static_sheet.albedo",
            ),
            (
                "[static_sheet]\nalbedo = [1.5, 1.0, 1.0]".into(),
                "static_sheet.albedo",
            ),
            (
                "[static_sheet]\nsegments = 0".into(),
                "static_sheet.segments",
            ),
            (
                "[static_sheet]\nsegments = 1025".into(),
                "static_sheet.segments",
            ),
        ] {
            assert_refused(&text, &[key]);
        }
    }

    #[test]
    fn a_camera_looking_along_the_up_axis_is_refused() {
        // Straight up, straight down, and 0.1° off vertical: the view has no "up" and nothing is drawn.
        for (position, target) in [
            ("[0.0, 0.0, 0.0]", "[0.0, 5.0, 0.0]"),
            ("[0.5, 3.0, 0.5]", "[0.5, 0.0, 0.5]"),
            ("[0.0, 0.0, 0.0]", "[0.00873, 5.0, 0.0]"),
        ] {
            assert_refused(
                &format!("[camera]\nposition = {position}\ntarget = {target}"),
                &["camera.target", "up axis"],
            );
        }
        // On top of the camera, under a millimetre from it, or so close that the direction is lost
        // in f32: refused for that. A millimetre as written, or more, is fine.
        let camera =
            |target: &str| format!("[camera]\nposition = [0.0, 0.0, 2.0]\ntarget = {target}");
        for target in ["[0.0, 0.0, 2.0]", "[0.0005, 0.0, 2.0]", "[1e-30, 0.0, 2.0]"] {
            assert_refused(&camera(target), &["camera.target", "at least 1 mm"]);
        }
        for target in [
            "[0.0, 0.0, 2.001]",
            "[0.001, 0.0, 2.0]",
            "[0.002, 0.0, 2.0]",
        ] {
            assert!(parse(&camera(target)).is_ok(), "{target}");
        }
        // Steep but not vertical is fine (the window's orbit stops at 80°).
        assert!(parse("[camera]\nposition = [0.0, 5.0, 0.9]\ntarget = [0.0, 0.0, 0.0]").is_ok());
    }

    #[test]
    fn malformed_values_are_errors_naming_the_key_and_line() {
        for (text, needles) in [
            // Wrong array lengths.
            ("[flag]\norigin = [0.0, 0.8]", &["origin", "line 2"][..]),
            (
                "[simulation]\ngravity = [0.0, -9.81]",
                &["gravity", "line 2"],
            ),
            (
                "[simulation.wind]\nvelocity = [1.0, 2.0, 3.0, 4.0]",
                &["velocity", "line 2"],
            ),
            (
                "[shading]\noptical_thickness = [2.0, 2.0]",
                &["optical_thickness", "line 2"],
            ),
            (
                "[shading]\nalbedo_scale = [1.0, 1.0, 1.0, 1.0]",
                &["albedo_scale", "line 2"],
            ),
            ("[light]\ncentre = [0.0]", &["centre", "line 2"]),
            ("[camera]\nposition = []", &["position", "line 2"]),
            ("[background]\ncolour = [0.2, 0.2]", &["colour", "line 2"]),
            ("[static_sheet]\nsize = [1.0]", &["size", "line 2"]),
            ("[static_sheet]\nalbedo = [1.0, 1.0]", &["albedo", "line 2"]),
            // Wrong types.
            ("[flag]\ncolumns = \"big\"", &["columns", "line 2"]),
            ("[flag]\ncolumns = 2.5", &["columns", "line 2"]),
            ("[flag]\ncolumns = -3", &["columns", "line 2"]),
            (
                "[simulation]\nlong_range_attachments = \"yes\"",
                &["long_range_attachments", "line 2"],
            ),
            (
                "[simulation]\nparallel_min_particles = -1",
                &["parallel_min_particles", "line 2"],
            ),
            ("[simulation.wind]\nseed = -1", &["seed", "line 2"]),
            (
                "[simulation.wind]\nsubsteps_per_update = 4",
                &[
                    "substeps_per_update",
                    "became `wind.renewal_interval`",
                    "0.00167",
                    "line 2",
                ],
            ),
            (
                "[simulation.wind]\nper_substep = 1",
                &["per_substep", "line 2"],
            ),
            (
                "[simulation.stretch]\nenabled = \"no\"",
                &["enabled", "line 2"],
            ),
            (
                "[shading]\nalbedo_texture = 3",
                &["albedo_texture", "line 2"],
            ),
            ("[light]\nmarker = 1", &["marker", "line 2"]),
            ("[render]\nwidth = \"big\"", &["width", "line 2"]),
            ("[render]\nheight = -512", &["height", "line 2"]),
            ("[static_sheet]\nsegments = 1.5", &["segments", "line 2"]),
            ("flag = 3", &["flag", "line 1"]),
            // Bad enum strings.
            (
                "[shading]\nmodel = \"phong\"",
                &["phong", "model", "line 2"],
            ),
            ("[shading]\npath = \"gpu\"", &["gpu", "path", "line 2"]),
            (
                "[shading]\nconvention = \"literal\"",
                &["literal", "convention", "line 2"],
            ),
            (
                "[shading]\nscattering = \"double\"",
                &["double", "scattering", "line 2"],
            ),
            (
                "[shading]\nall_orders_lookup = \"pixel\"",
                &["pixel", "all_orders_lookup", "line 2"],
            ),
            (
                "[simulation.method]\nkind = \"rk4\"\nsubsteps = 1",
                &["rk4", "kind", "line 2"],
            ),
            // Inside the method's table the line is the key's, not the table header's.
            (
                "[simulation.method]\nkind = \"pbd\"\nsubsteps = 4\niterations = -10\nstiffness = 1.0",
                &["-10", "line 4"],
            ),
            (
                "[simulation.method]\nkind = \"xpbd\"\nsubsteps = 4\niterations = 10\nstiffnes = 1.0",
                &["stiffnes", "line 5"],
            ),
            (
                "[simulation.method]\nkind = \"verlet\"\nsubsteps = 2.5",
                &["2.5", "line 3"],
            ),
            // Missing method knobs, and a knob the method does not have.
            (
                "[simulation.method]\nkind = \"pbd\"\nsubsteps = 2\niterations = 4",
                &["stiffness"],
            ),
            (
                "[simulation.method]\nkind = \"implicit_euler\"\nsubsteps = 1\ncg_tolerance = 1e-6",
                &["cg_max_iterations"],
            ),
            ("[simulation.method]\nkind = \"verlet\"", &["substeps"]),
            ("[simulation.method]\nsubsteps = 3", &["kind"]),
            (
                "[simulation.method]\nkind = \"verlet\"\nsubsteps = 3\niterations = 4",
                &["`iterations` is not a knob of verlet", "line 1"],
            ),
            (
                "[simulation.method]\nkind = \"xpbd\"\nsubsteps = 3\niterations = 4\nstiffness = 0.5",
                &["`stiffness` is not a knob of xpbd (its knobs: substeps, iterations)"],
            ),
            // Duplicate keys and tables.
            ("[light]\nflux = 1.0\nflux = 2.0", &["flux", "line 3"]),
            (
                "[render]\nwidth = 64\n[render]\nheight = 64",
                &["render", "line 3"],
            ),
            // Not TOML at all.
            ("this is not toml", &["line 1"]),
        ] {
            assert_refused(text, needles);
        }
    }

    #[test]
    fn unknown_keys_in_every_section_are_errors_naming_the_key() {
        for section in [
            "",
            "[flag]",
            "[simulation]",
            "[simulation.method]\nkind = \"verlet\"\nsubsteps = 3",
            "[simulation.stretch]",
            "[simulation.shear]",
            "[simulation.bend]",
            "[simulation.wind]",
            "[simulation.divergence]",
            "[shading]",
            "[light]",
            "[camera]",
            "[background]",
            "[render]",
            "[static_sheet]",
        ] {
            let text = format!("{section}\nbogus_key = 1");
            assert_refused(&text, &["bogus_key"]);
        }
    }

    #[test]
    fn images_a_scene_file_leaves_out_are_the_built_in_ones_wherever_it_lies() {
        // A scene file in a folder without the default images.
        let folder =
            std::env::temp_dir().join(format!("sheer-builtin-images-{}", std::process::id()));
        std::fs::create_dir_all(&folder).unwrap();
        let scene = Scene::from_toml("[simulation]\nair_damping = 0.1", &folder).unwrap();
        for key in DEFAULT_IMAGE_KEYS {
            let name = match key {
                "shading.albedo_texture" => scene.shading.albedo_texture.clone().unwrap(),
                _ => scene.background.image.clone().unwrap(),
            };
            let bytes = scene.read_asset(key, &name).unwrap();
            assert_eq!(
                &*bytes,
                std::fs::read(assets().join(&name)).unwrap(),
                "{key}"
            );
        }
        // An image the file names is read from the file's folder, even the default's name.
        let scene =
            Scene::from_toml("[shading]\nalbedo_texture = \"faroe_flag.png\"", &folder).unwrap();
        let error = scene
            .read_asset("shading.albedo_texture", "faroe_flag.png")
            .unwrap_err()
            .to_string();
        assert!(error.contains("cannot read"), "{error}");
        assert!(
            scene
                .read_asset("background.image", "faroe_landscape.png")
                .is_ok()
        );
        std::fs::remove_dir_all(&folder).ok();
    }

    #[test]
    fn the_built_in_default_scene_is_the_shipped_file_with_its_images() {
        let scene = Scene::builtin_default().unwrap();
        // The file leaves its image keys out: the built-in images.
        let default = Scene {
            builtin_images: DEFAULT_IMAGE_KEYS.to_vec(),
            ..Scene::default()
        };
        assert_eq!(scene, default);
        // The images it names are built in, identical to the files in assets/.
        for key_and_name in [
            ("shading.albedo_texture", &scene.shading.albedo_texture),
            ("background.image", &scene.background.image),
        ] {
            let (key, Some(name)) = key_and_name else {
                panic!("{key_and_name:?}")
            };
            let bytes = scene.read_asset(key, name).unwrap();
            assert_eq!(&*bytes, std::fs::read(assets().join(name)).unwrap());
        }
        // Whatever the current directory: it reads no file.
        let error = scene
            .read_asset("shading.thickness_texture", "weave.png")
            .unwrap_err();
        assert!(
            error.to_string().contains("shading.thickness_texture"),
            "{error}"
        );
    }

    #[test]
    fn missing_and_corrupt_images_are_errors_naming_the_key() {
        let dir = std::env::temp_dir().join(format!("sheer-key-tests-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("corrupt.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
        let scene = Scene::from_toml("", &dir).unwrap();
        for key in [
            "shading.albedo_texture",
            "shading.thickness_texture",
            "background.image",
        ] {
            for (name, why) in [
                ("missing.png", "cannot read"),
                ("corrupt.png", "cannot decode"),
            ] {
                let error = crate::frame::load_linear_texture(&scene, key, name, None)
                    .err()
                    .unwrap_or_else(|| panic!("{key} = {name} accepted"))
                    .to_string();
                assert!(
                    error.contains(key) && error.contains(name) && error.contains(why),
                    "{error}"
                );
                assert_eq!(error.lines().count(), 1, "{error}");
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
