//! The scene file (TOML): everything the window and the command line need to reproduce a run — the flag
//! and its simulation, the thin-slab shading, the circling light, the camera, the background and the
//! output size — or, instead of the flag, a static flat sheet whose render can be checked by hand.
//!
//! Unknown keys are errors (serde's `deny_unknown_fields`), and [`Scene::validate`] names the key of any
//! out-of-range value. The default scene is `assets/default.scene.toml`; every key is documented there.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sheer_cloth::{GridSpec, SimParams};

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

/// Where the thin-slab model is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EvaluationPathName {
    Fragment,
    Vertex,
    Cpu,
}

/// Which irradiance goes into eqs. (4)–(5) (see the sheer-slab README for the finding).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Convention {
    NormalToBeam,
    PaperLiteral,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShadingSection {
    pub model: ShadingModel,
    pub path: EvaluationPathName,
    /// τ1, the slab's optical thickness (dimensionless, > 0), per channel.
    pub optical_thickness: [f32; 3],
    /// Multiplies the albedo texture to give Λ per channel (Λ must stay in [0, 1]).
    pub albedo_scale: [f32; 3],
    /// Albedo texture, relative to the scene file (sRGB PNG; decoded to linear); `""` for white.
    pub albedo_texture: Option<String>,
    /// Optional thickness texture (red channel multiplies τ1), relative to the scene file.
    pub thickness_texture: Option<String>,
    pub convention: Convention,
    /// The baseline's constant α (0.2 in the paper).
    pub baseline_alpha: f32,
    /// Display exposure: linear radiance × exposure before sRGB encoding.
    pub exposure: f32,
}

impl Default for ShadingSection {
    /// The paper's figure 2: Λ = 1, τ1 = 2, baseline α = 0.2.
    fn default() -> Self {
        ShadingSection {
            model: ShadingModel::ThinSlab,
            path: EvaluationPathName::Fragment,
            optical_thickness: [2.0; 3],
            albedo_scale: [1.0; 3],
            albedo_texture: Some("faroe_flag.png".into()),
            thickness_texture: None,
            convention: Convention::NormalToBeam,
            baseline_alpha: 0.2,
            exposure: 0.5,
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
    /// Light position at time `time` (s).
    pub fn position(&self, time: f32) -> [f32; 3] {
        let angle = if self.period == 0.0 {
            self.phase
        } else {
            self.phase + std::f32::consts::TAU * time / self.period
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
}

impl Default for RenderSection {
    /// The paper's 512 × 512 at 60 Hz.
    fn default() -> Self {
        RenderSection {
            width: 512,
            height: 512,
            fps: 60.0,
            warmup: 1.5,
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

/// A whole scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Scene {
    pub flag: GridSpec,
    pub simulation: SimParams,
    pub shading: ShadingSection,
    pub light: LightSection,
    pub camera: CameraSection,
    pub background: BackgroundSection,
    pub render: RenderSection,
    /// When present, this sheet replaces the flag and nothing is simulated.
    pub static_sheet: Option<StaticSheet>,
    /// Directory relative paths are resolved against (the scene file's folder); not in the file.
    #[serde(skip)]
    pub base_dir: PathBuf,
}

impl Default for Scene {
    fn default() -> Self {
        let mut simulation = SimParams::default();
        // A fresh breeze across the flag at 27° from its plane, gusting and turbulent: enough to make it
        // wave rather than stream flat.
        simulation.wind.velocity = sheer_cloth::glam::DVec3::new(5.0, 0.0, 2.5);
        simulation.wind.gust_strength = 0.5;
        simulation.wind.turbulence = 0.4;
        Scene {
            flag: GridSpec::default(),
            simulation,
            shading: ShadingSection::default(),
            light: LightSection::default(),
            camera: CameraSection::default(),
            background: BackgroundSection::default(),
            render: RenderSection::default(),
            static_sheet: None,
            base_dir: PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets"),
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

fn finite3(key: &str, v: [f32; 3]) -> Result<(), CliError> {
    check(v.iter().all(|c| c.is_finite()), key, v, "must be finite")
}

impl Scene {
    /// Parses a scene from TOML text; relative paths resolve against `base_dir`.
    pub fn from_toml(text: &str, base_dir: &Path) -> Result<Scene, CliError> {
        let mut scene: Scene = toml::from_str(text).map_err(|e| {
            CliError::new(format!("scene: {}", e.message().trim())).with_span(text, e.span())
        })?;
        scene.base_dir = base_dir.to_path_buf();
        scene.validate()?;
        Ok(scene)
    }

    /// Reads and parses a scene file.
    pub fn load(path: &Path) -> Result<Scene, CliError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| CliError::new(format!("cannot read scene {}: {e}", path.display())))?;
        let base = path.parent().unwrap_or(Path::new("."));
        Scene::from_toml(&text, base).map_err(|e| CliError::new(format!("{}: {e}", path.display())))
    }

    /// The file's text for this scene (for writing the default scene out).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }

    /// Resolves a path written in the scene file.
    pub fn resolve(&self, relative: &str) -> PathBuf {
        self.base_dir.join(relative)
    }

    /// Checks every value's range; the error names the key.
    pub fn validate(&self) -> Result<(), CliError> {
        sheer_cloth::ClothModel::grid(&self.flag)
            .map_err(|e| CliError::new(format!("scene: [flag]: {e}")))?;
        self.simulation
            .validate()
            .map_err(|e| CliError::new(format!("scene: [simulation]: {e}")))?;
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
            s.exposure.is_finite() && s.exposure > 0.0,
            "shading.exposure",
            s.exposure,
            "must be finite and > 0",
        )?;
        let l = &self.light;
        check(
            l.flux.is_finite() && l.flux >= 0.0,
            "light.flux",
            l.flux,
            "must be finite and ≥ 0 W",
        )?;
        finite3("light.centre", l.centre)?;
        check(
            l.radius.is_finite() && l.radius > 0.0,
            "light.radius",
            l.radius,
            "must be finite and > 0 m",
        )?;
        check(
            l.period.is_finite(),
            "light.period",
            l.period,
            "must be finite",
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
        check(
            c.position != c.target,
            "camera.target",
            c.target,
            "must differ from camera.position",
        )?;
        check(
            c.vertical_fov_degrees > 1.0 && c.vertical_fov_degrees < 179.0,
            "camera.vertical_fov_degrees",
            c.vertical_fov_degrees,
            "must lie in (1, 179)",
        )?;
        let b = &self.background;
        check(
            b.colour.iter().all(|v| v.is_finite() && *v >= 0.0),
            "background.colour",
            b.colour,
            "must be finite and ≥ 0",
        )?;
        check(
            b.radiance_scale.is_finite() && b.radiance_scale >= 0.0,
            "background.radiance_scale",
            b.radiance_scale,
            "must be finite and ≥ 0",
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
            r.fps.is_finite() && r.fps > 0.0,
            "render.fps",
            r.fps,
            "must be finite and > 0",
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
                sheet.size.iter().all(|v| v.is_finite() && *v > 0.0),
                "static_sheet.size",
                sheet.size,
                "must be finite and > 0 m",
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

    #[test]
    fn an_empty_file_is_the_default_scene() {
        let default = Scene {
            base_dir: assets(),
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
        assert_eq!(scene.shading.path, EvaluationPathName::Cpu);
        assert_eq!(scene.shading.convention, Convention::PaperLiteral);
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
            ("[flag]\ncolumns = 1", "[flag]"),
            ("[flag]\nareal_density = -0.2", "[flag]"),
            ("[simulation.stretch]\nstiffness = 0.0", "stretch"),
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
}
