//! Plain-data inputs of the renderer: the mesh, the camera, the shading parameters, the background, and
//! the linear image that comes back (with exposure and sRGB encoding for display).

use std::path::Path;
use std::sync::Arc;

use glam::{DMat4, DVec3, DVec4, Mat4, Vec3};
use thiserror::Error;

use super::shadow::Shadows;
use crate::all_orders::{Scattering, TABLE_RANGE_SLACK, table_tau_range};
use crate::model::IrradianceConvention;
use crate::sky::SkyLight;

/// Why a mesh was rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MeshError {
    /// Positions, normals and uvs must have one entry per vertex.
    #[error("mesh has {positions} positions, {normals} normals and {uvs} uvs; they must be equal")]
    LengthMismatch {
        /// Number of positions.
        positions: usize,
        /// Number of normals.
        normals: usize,
        /// Number of uvs.
        uvs: usize,
    },
    /// Triangle list needs a multiple of three indices, at least one triangle.
    #[error("mesh has {0} indices; need a positive multiple of 3")]
    IndexCount(usize),
    /// An index points past the vertices.
    #[error("index {index} at position {position} is out of range for {vertices} vertices")]
    IndexOutOfRange {
        /// The index value.
        index: u32,
        /// Where in the index list.
        position: usize,
        /// Vertex count.
        vertices: usize,
    },
    /// A NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite {attribute}")]
    NonFinite {
        /// "position", "normal" or "uv".
        attribute: &'static str,
        /// Vertex number.
        vertex: usize,
    },
    /// A flat sheet needs at least one segment each way and two independent edges.
    #[error("flat sheet needs segments >= 1 and non-parallel, non-zero edges")]
    DegenerateSheet,
}

/// A triangle mesh as plain data. Normals are per vertex and already turned toward the light (the renderer
/// turns the interpolated normal toward the light again per fragment, as `shaders/lit_side.wgsl` does).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SlabMesh {
    /// Vertex positions (m).
    pub positions: Vec<[f32; 3]>,
    /// Vertex normals (any length > 0).
    pub normals: Vec<[f32; 3]>,
    /// Texture coordinates in [0, 1]² (albedo and thickness textures).
    pub uvs: Vec<[f32; 2]>,
    /// Triangle list.
    pub indices: Vec<u32>,
}

impl SlabMesh {
    /// Checks lengths, index range and finiteness.
    pub fn validate(&self) -> Result<(), MeshError> {
        let vertices = self.positions.len();
        if self.normals.len() != vertices || self.uvs.len() != vertices {
            return Err(MeshError::LengthMismatch {
                positions: vertices,
                normals: self.normals.len(),
                uvs: self.uvs.len(),
            });
        }
        if self.indices.is_empty() || !self.indices.len().is_multiple_of(3) {
            return Err(MeshError::IndexCount(self.indices.len()));
        }
        if let Some((position, &index)) = self
            .indices
            .iter()
            .enumerate()
            .find(|&(_, &i)| i as usize >= vertices)
        {
            return Err(MeshError::IndexOutOfRange {
                index,
                position,
                vertices,
            });
        }
        for vertex in 0..vertices {
            let checks: [(&'static str, bool); 3] = [
                (
                    "position",
                    self.positions[vertex].iter().all(|c| c.is_finite()),
                ),
                ("normal", self.normals[vertex].iter().all(|c| c.is_finite())),
                ("uv", self.uvs[vertex].iter().all(|c| c.is_finite())),
            ];
            if let Some(&(attribute, _)) = checks.iter().find(|(_, ok)| !ok) {
                return Err(MeshError::NonFinite { attribute, vertex });
            }
        }
        Ok(())
    }

    /// A flat parallelogram `origin + s·u_edge + t·v_edge`, (s, t) in [0, 1]², split into
    /// `segments_u × segments_v` quads of two triangles, uv = (s, t), every normal = `normal`.
    pub fn flat_sheet(
        origin: Vec3,
        u_edge: Vec3,
        v_edge: Vec3,
        normal: Vec3,
        segments_u: u32,
        segments_v: u32,
    ) -> Result<Self, MeshError> {
        if segments_u == 0 || segments_v == 0 || u_edge.cross(v_edge).length_squared() <= 0.0 {
            return Err(MeshError::DegenerateSheet);
        }
        let mut mesh = Self::default();
        for j in 0..=segments_v {
            for i in 0..=segments_u {
                let s = i as f32 / segments_u as f32;
                let t = j as f32 / segments_v as f32;
                mesh.positions
                    .push((origin + s * u_edge + t * v_edge).to_array());
                mesh.normals.push(normal.to_array());
                mesh.uvs.push([s, t]);
            }
        }
        let row = segments_u + 1;
        for j in 0..segments_v {
            for i in 0..segments_u {
                let a = j * row + i;
                mesh.indices
                    .extend_from_slice(&[a, a + 1, a + row + 1, a, a + row + 1, a + row]);
            }
        }
        mesh.validate()?;
        Ok(mesh)
    }

    /// Appends another mesh (for scenes of several sheets).
    pub fn append(&mut self, other: &SlabMesh) {
        let offset = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.uvs.extend_from_slice(&other.uvs);
        self.indices
            .extend(other.indices.iter().map(|i| i + offset));
    }
}

/// A pinhole camera (right-handed, depth range 0..1 as wgpu expects).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position (m).
    pub eye: Vec3,
    /// Point looked at (m).
    pub target: Vec3,
    /// Up direction.
    pub up: Vec3,
    /// Vertical field of view (rad).
    pub vertical_fov: f32,
    /// Near plane distance (m).
    pub near: f32,
    /// Far plane distance (m).
    pub far: f32,
}

/// Why a camera was rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CameraError {
    /// Eye, target and up must be finite.
    #[error("camera {name} {value:?} is not finite")]
    NonFinite {
        /// `eye`, `target` or `up`.
        name: &'static str,
        /// The rejected vector.
        value: [f32; 3],
    },
    /// The eye must not sit on the point it looks at (no view direction).
    #[error("camera eye and target coincide at {0:?}")]
    EyeAtTarget([f32; 3]),
    /// `up` must be non-zero and not along the view direction (no roll would be defined).
    #[error("camera up {0:?} is zero or parallel to the view direction")]
    Up([f32; 3]),
    /// The vertical field of view must lie in (0, π) radians.
    #[error("camera vertical field of view {0} rad is outside (0, pi)")]
    FieldOfView(f32),
    /// The clip planes must satisfy 0 < near < far, both finite (m).
    #[error("camera clip planes near = {near} m, far = {far} m: need 0 < near < far, both finite")]
    ClipPlanes {
        /// Near plane distance.
        near: f32,
        /// Far plane distance.
        far: f32,
    },
    /// A pixel position must be finite.
    #[error("pixel position ({x}, {y}) is not finite")]
    PixelPosition {
        /// Column, in pixels.
        x: f64,
        /// Row, in pixels.
        y: f64,
    },
    /// An image needs at least one pixel each way.
    #[error("image size {width}x{height} has no pixels")]
    ImageSize {
        /// Width, pixels.
        width: u32,
        /// Height, pixels.
        height: u32,
    },
}

impl Camera {
    /// Checks that the camera defines a view: finite vectors, an eye apart from the target, an `up` not
    /// along the view, a field of view in (0, π) and clip planes 0 < near < far. Otherwise its
    /// view-projection holds NaN or infinities and a render would show only the background.
    pub fn validate(&self) -> Result<(), CameraError> {
        for (name, value) in [("eye", self.eye), ("target", self.target), ("up", self.up)] {
            if !value.is_finite() {
                return Err(CameraError::NonFinite {
                    name,
                    value: value.to_array(),
                });
            }
        }
        // In f64, as the view-projection is built.
        let view = self.target.as_dvec3() - self.eye.as_dvec3();
        if view == DVec3::ZERO {
            return Err(CameraError::EyeAtTarget(self.eye.to_array()));
        }
        let up = self.up.as_dvec3();
        let sine = up.cross(view).length() / (up.length() * view.length());
        if sine.is_nan() || sine <= 1e-6 {
            return Err(CameraError::Up(self.up.to_array()));
        }
        // The projection's focal term 1/tan(fov/2) must fit the f32 matrix the GPU gets.
        let focal = 1.0 / (0.5 * f64::from(self.vertical_fov)).tan();
        if !(self.vertical_fov > 0.0
            && f64::from(self.vertical_fov) < std::f64::consts::PI
            && (focal as f32).is_finite())
        {
            return Err(CameraError::FieldOfView(self.vertical_fov));
        }
        if !(self.near > 0.0 && self.near < self.far && self.far.is_finite()) {
            return Err(CameraError::ClipPlanes {
                near: self.near,
                far: self.far,
            });
        }
        Ok(())
    }

    /// World → clip transform for an image of `width × height` pixels.
    pub fn view_projection(&self, width: u32, height: u32) -> Mat4 {
        self.view_projection_f64(width, height).as_mat4()
    }

    fn view_projection_f64(&self, width: u32, height: u32) -> DMat4 {
        let aspect = f64::from(width) / f64::from(height);
        let view = glam::dcamera::rh::view::look_at_mat4(
            self.eye.as_dvec3(),
            self.target.as_dvec3(),
            self.up.as_dvec3(),
        );
        // WebGPU clip space: depth in [0, 1], y up.
        let projection = glam::dcamera::rh::proj::directx::perspective(
            f64::from(self.vertical_fov),
            aspect,
            f64::from(self.near),
            f64::from(self.far),
        );
        projection * view
    }

    /// The ray (origin, unit direction) through the point `(x, y)` of the image in pixel units, (0, 0)
    /// being the top-left corner of the image (pixel centres are at half-integers), in `f64`: for reference
    /// computations that must match the rasteriser's sample positions. The camera must be valid
    /// ([`validate`](Self::validate)) and the position finite.
    pub fn pixel_ray(
        &self,
        x: f64,
        y: f64,
        width: u32,
        height: u32,
    ) -> Result<(DVec3, DVec3), CameraError> {
        self.validate()?;
        if !(x.is_finite() && y.is_finite()) {
            return Err(CameraError::PixelPosition { x, y });
        }
        if width == 0 || height == 0 {
            return Err(CameraError::ImageSize { width, height });
        }
        let inverse = self.view_projection_f64(width, height).inverse();
        let ndc_x = 2.0 * x / f64::from(width) - 1.0;
        let ndc_y = 1.0 - 2.0 * y / f64::from(height);
        let near = inverse * DVec4::new(ndc_x, ndc_y, 0.0, 1.0);
        let far = inverse * DVec4::new(ndc_x, ndc_y, 1.0, 1.0);
        let near = near.truncate() / near.w;
        let far = far.truncate() / far.w;
        let origin = self.eye.as_dvec3();
        Ok((origin, (far - near).normalize()))
    }
}

/// An RGBA image of `f32` texels, row-major from the top (v = 0) row.
///
/// Cloning shares the texels (a reference count), and comparing two clones is a pointer comparison:
/// the renderer keeps a clone of each texture it uploaded and compares it with the one it is given
/// every frame, which for the 1100×800 flag texture had been a 14 MB pass a frame.
#[derive(Debug, Clone)]
pub struct Texture2d {
    width: u32,
    height: u32,
    texels: Arc<[[f32; 4]]>,
    /// Per channel, the least and the greatest texel, found once here so that the checks that run
    /// every frame ([`ShadingParams::validate`]) need not pass over every texel.
    channel_min: [f32; 4],
    channel_max: [f32; 4],
}

impl PartialEq for Texture2d {
    fn eq(&self, other: &Self) -> bool {
        self.width == other.width
            && self.height == other.height
            && (Arc::ptr_eq(&self.texels, &other.texels) || self.texels == other.texels)
    }
}

impl Texture2d {
    /// An image; `texels.len()` must be `width·height`, all finite.
    pub fn new(width: u32, height: u32, texels: Vec<[f32; 4]>) -> Result<Self, ShadingError> {
        if width == 0 || height == 0 || texels.len() != width as usize * height as usize {
            return Err(ShadingError::TextureSize {
                width,
                height,
                texels: texels.len(),
            });
        }
        // One pass: the first non-finite texel, else each channel's extremes.
        let (mut channel_min, mut channel_max) = ([f32::INFINITY; 4], [f32::NEG_INFINITY; 4]);
        for (index, texel) in texels.iter().enumerate() {
            if texel.iter().any(|c| !c.is_finite()) {
                return Err(ShadingError::NonFiniteTexel { index });
            }
            for channel in 0..4 {
                channel_min[channel] = channel_min[channel].min(texel[channel]);
                channel_max[channel] = channel_max[channel].max(texel[channel]);
            }
        }
        Ok(Self {
            width,
            height,
            texels: texels.into(),
            channel_min,
            channel_max,
        })
    }

    /// A 1×1 image.
    pub fn uniform(value: [f32; 4]) -> Result<Self, ShadingError> {
        Self::new(1, 1, vec![value])
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Texels, row-major.
    pub fn texels(&self) -> &[[f32; 4]] {
        &self.texels
    }
}

/// Why shading parameters were rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ShadingError {
    /// The sky's diffuse table and the all-orders table must share their axes (the shader samples both
    /// on one set).
    #[error("the diffuse table and the all-orders table have different grids")]
    TableAxes,
    /// Texture dimensions and texel count disagree.
    #[error("texture of {width}x{height} has {texels} texels")]
    TextureSize {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// Texels given.
        texels: usize,
    },
    /// A NaN or infinite texel.
    #[error("texel {index} is not finite")]
    NonFiniteTexel {
        /// Texel number.
        index: usize,
    },
    /// τ1 per channel must be finite and > 0.
    #[error("optical thickness {0:?} must be finite and > 0 in every channel")]
    OpticalThickness([f32; 3]),
    /// Albedo scale times albedo texel must stay in [0, 1].
    #[error("albedo (scale {scale:?} times texel {texel}) leaves [0, 1]")]
    Albedo {
        /// The scale.
        scale: [f32; 3],
        /// First offending texel.
        texel: usize,
    },
    /// Thickness texels (red channel, multiplying τ1) must be in [2^-14, 65504] (normal half floats).
    #[error("thickness texel {texel} = {value:?} is outside [6.1e-5, 65504]")]
    Thickness {
        /// Texel number.
        texel: usize,
        /// Its red channel.
        value: f32,
    },
    /// Flux Φ must be finite and ≥ 0.
    #[error("light flux {0} W must be finite and >= 0")]
    Flux(f32),
    /// The light position must be finite.
    #[error("light position {0:?} is not finite")]
    LightPosition([f32; 3]),
    /// Exposure must be finite and > 0.
    #[error("exposure {0} must be finite and > 0")]
    Exposure(f32),
    /// The baseline's constant α must be in [0, 1].
    #[error("baseline transmittance {0} is outside [0, 1]")]
    BaselineTransmittance(f32),
    /// With the all-orders model, τ1 (times the thickness texture, as the GPU samples it) must lie in the
    /// table's range.
    #[error(
        "optical thickness {value:?} (channel {channel}, times the thickness texture) lies outside the \
         all-orders table's range [{min}, {max}]"
    )]
    OutsideTable {
        /// Colour channel (0 = red).
        channel: usize,
        /// The smallest or largest τ1 of that channel.
        value: f64,
        /// Smallest τ1 of the table.
        min: f64,
        /// Largest τ1 of the table.
        max: f64,
    },
    /// An opaque mesh (a flag pole) that cannot be drawn: what is wrong with it.
    #[error("opaque mesh: {0}")]
    OpaqueMesh(String),
    /// The shadow map needs at least 16 texels per side.
    #[error("shadow map resolution {0} must be at least 16 texels")]
    ShadowResolution(u32),
    /// Shadows with the all-orders model need a diffuse table (for the light scattered through a layer).
    #[error("shadows with the all-orders model need a diffuse table (shadows or sky light)")]
    ShadowDiffuseTable,
    /// The sky's and the shadows' diffuse tables must be the same table (the shader binds one).
    #[error("the sky light and the shadows have different diffuse tables")]
    DiffuseTables,
    /// The light marker's radius must be finite and > 0, its radiance finite and ≥ 0.
    #[error("light marker of radius {radius_pixels} px and radiance {radiance:?} W/(m²·sr)")]
    LightMarker {
        /// Radius, pixels.
        radius_pixels: f32,
        /// Radiance per channel.
        radiance: [f32; 3],
    },
}

/// Material, light and display parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadingParams {
    /// τ1 per channel (dimensionless, > 0). Equal channels render with blend factor SrcAlpha; different
    /// channels need dual-source blending.
    pub optical_thickness: [f32; 3],
    /// Multiplies the albedo texture to give Λ per channel.
    pub albedo_scale: [f32; 3],
    /// Albedo texture (the flag's colours), linear, rgb used.
    pub albedo_texture: Texture2d,
    /// Optional thickness texture: its red channel multiplies τ1 (the paper's weave/bump-map suggestion).
    pub thickness_texture: Option<Texture2d>,
    /// Point-light position (m).
    pub light_position: Vec3,
    /// Point-light flux Φ (W), isotropic.
    pub light_flux: f32,
    /// Irradiance convention for eqs. (4)–(5).
    pub convention: IrradianceConvention,
    /// Display exposure: linear radiance (W/(m²·sr)) times this is the display value before sRGB encoding.
    pub exposure: f32,
    /// The baseline's constant α (0.2 in the paper's figure 2).
    pub baseline_transmittance: f32,
    /// Single scattering (the paper) or all orders (eqs. 4–5 plus the table's multiple part).
    pub scattering: Scattering,
    /// Where the per-fragment path looks the all-orders table up (the other paths evaluate everything
    /// per vertex anyway).
    pub all_orders_sampling: AllOrdersSampling,
    /// Daylight on both faces ([`crate::sky`]), or none (the paper's scene: the point light alone).
    pub sky: Option<SkyLight>,
    /// Translucent shadows of the point light (`shadow.rs`), or none (the paper: every point gets
    /// the whole beam).
    pub shadows: Option<Shadows>,
}

/// Where [`EvaluationPath::PerFragment`](super::EvaluationPath::PerFragment) looks the all-orders table
/// up. Single scattering (eqs. 4–5), α, the irradiance, μ0 and Λ are per fragment either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum AllOrdersSampling {
    /// In every fragment (twelve texel loads): exact to the table everywhere; on lavapipe about 1.8×
    /// the frame time of single scattering.
    #[default]
    #[cfg_attr(feature = "serde", serde(rename = "fragment"))]
    PerFragment,
    /// Once per mesh vertex per frame (a compute pass), for both faces; the table's reduced value
    /// f = L_m/(Λ²μ0) is interpolated and each fragment picks its face and multiplies by its own
    /// Λ²·μ0·E. About 1.1× single scattering; errs where f is not linear over a triangle: at Λ edges of
    /// the albedo texture and along folds where μ or μ0 → 0 (measured in the workspace's
    /// tests/render.rs and the README).
    #[cfg_attr(feature = "serde", serde(rename = "vertex"))]
    PerVertex,
}

impl AllOrdersSampling {
    /// Both, the default first.
    pub const ALL: [Self; 2] = [Self::PerFragment, Self::PerVertex];

    /// The user-facing name: `per-vertex` or `per-fragment`.
    pub fn name(self) -> &'static str {
        match self {
            Self::PerVertex => "per-vertex",
            Self::PerFragment => "per-fragment",
        }
    }
}

impl ShadingParams {
    /// Uniform τ1 and Λ, white albedo texture, no thickness texture, baseline α = 0.2, exposure 1.
    pub fn uniform(
        optical_thickness: f32,
        albedo: f32,
        light_position: Vec3,
        light_flux: f32,
    ) -> Result<Self, ShadingError> {
        let params = Self {
            optical_thickness: [optical_thickness; 3],
            albedo_scale: [albedo; 3],
            albedo_texture: Texture2d::uniform([1.0; 4])?,
            thickness_texture: None,
            light_position,
            light_flux,
            convention: IrradianceConvention::default(),
            exposure: 1.0,
            baseline_transmittance: 0.2,
            scattering: Scattering::Single,
            all_orders_sampling: AllOrdersSampling::default(),
            sky: None,
            shadows: None,
        };
        params.validate()?;
        Ok(params)
    }

    /// Checks every parameter's domain.
    pub fn validate(&self) -> Result<(), ShadingError> {
        if !self
            .optical_thickness
            .iter()
            .all(|t| t.is_finite() && *t > 0.0)
        {
            return Err(ShadingError::OpticalThickness(self.optical_thickness));
        }
        // Each check below holds for every texel when it holds for each channel's least and greatest
        // texel: multiplying by a scale ≥ 0 is monotone in f32 (the exact product is, and rounding
        // keeps order), so the texels that pass form an interval. Only a failure looks for the first
        // texel that fails, to name it. Checked against a pass over every texel in
        // the unit test `texture_checks_by_extremes_equal_a_pass_over_every_texel`.
        let albedo_in_range = |value: &[f32; 4]| {
            (0..3).all(|c| {
                let albedo = self.albedo_scale[c] * value[c];
                albedo.is_finite() && (0.0..=1.0).contains(&albedo) && self.albedo_scale[c] >= 0.0
            })
        };
        let albedo = &self.albedo_texture;
        if !(albedo_in_range(&albedo.channel_min) && albedo_in_range(&albedo.channel_max))
            && let Some(texel) = albedo.texels.iter().position(|v| !albedo_in_range(v))
        {
            return Err(ShadingError::Albedo {
                scale: self.albedo_scale,
                texel,
            });
        }
        if let Some(thickness) = &self.thickness_texture {
            let in_range = |value: f32| (6.103_515_6e-5..=65504.0).contains(&value);
            if !(in_range(thickness.channel_min[0]) && in_range(thickness.channel_max[0]))
                && let Some(texel) = thickness.texels.iter().position(|v| !in_range(v[0]))
            {
                return Err(ShadingError::Thickness {
                    texel,
                    value: thickness.texels[texel][0],
                });
            }
        }
        if !(self.light_flux.is_finite() && self.light_flux >= 0.0) {
            return Err(ShadingError::Flux(self.light_flux));
        }
        if !self.light_position.is_finite() {
            return Err(ShadingError::LightPosition(self.light_position.to_array()));
        }
        if !(self.exposure.is_finite() && self.exposure > 0.0) {
            return Err(ShadingError::Exposure(self.exposure));
        }
        if !(0.0..=1.0).contains(&self.baseline_transmittance) {
            return Err(ShadingError::BaselineTransmittance(
                self.baseline_transmittance,
            ));
        }
        if let Scattering::AllOrders(table) = &self.scattering {
            self.validate_table_range(table_tau_range(table))?;
        }
        if let Some(sky) = &self.sky {
            let spec = sky.table.spec();
            self.validate_table_range((spec.tau_min, spec.tau_max))?;
            // The shader samples both tables on one set of axes.
            if let Scattering::AllOrders(table) = &self.scattering
                && table.spec() != spec
            {
                return Err(ShadingError::TableAxes);
            }
        }
        if let Some(shadows) = &self.shadows {
            shadows.validate()?;
            if let (Some(sky), Some(table)) = (&self.sky, &shadows.diffuse_table)
                && !(Arc::ptr_eq(&sky.table, table) || sky.table == *table)
            {
                return Err(ShadingError::DiffuseTables);
            }
            if let Some(table) = &shadows.diffuse_table {
                let spec = table.spec();
                self.validate_table_range((spec.tau_min, spec.tau_max))?;
                if let Scattering::AllOrders(all_orders) = &self.scattering
                    && all_orders.spec() != spec
                {
                    return Err(ShadingError::TableAxes);
                }
            }
            if matches!(self.scattering, Scattering::AllOrders(_)) && self.diffuse_table().is_none()
            {
                return Err(ShadingError::ShadowDiffuseTable);
            }
        }
        Ok(())
    }

    /// The diffuse table the renderer binds: the sky's, else the shadows' (validation makes them one).
    pub fn diffuse_table(&self) -> Option<&Arc<crate::sky::DiffuseTable>> {
        self.sky.as_ref().map(|sky| &sky.table).or(self
            .shadows
            .as_ref()
            .and_then(|shadows| shadows.diffuse_table.as_ref()))
    }

    /// The diffuse table the light scattered through a layer uses: with shadows and the all-orders model.
    pub fn diffuse_through_table(&self) -> Option<&Arc<crate::sky::DiffuseTable>> {
        match (&self.shadows, &self.scattering) {
            (Some(_), Scattering::AllOrders(_)) => self.diffuse_table(),
            _ => None,
        }
    }

    /// Every τ1 the renderer can meet (τ1 per channel times the half-float thickness texels, which
    /// bilinear filtering only mixes) must lie in `[min, max]`, up to [`TABLE_RANGE_SLACK`].
    fn validate_table_range(&self, (min, max): (f64, f64)) -> Result<(), ShadingError> {
        // Rounding to half floats keeps order, so the extreme texels give the extreme half floats.
        let (low, high) = match &self.thickness_texture {
            Some(texture) => (
                f64::from(super::cpu::quantize_to_half(texture.channel_min[0])),
                f64::from(super::cpu::quantize_to_half(texture.channel_max[0])),
            ),
            None => (1.0, 1.0),
        };
        for (channel, &tau) in self.optical_thickness.iter().enumerate() {
            let (smallest, largest) = (f64::from(tau) * low, f64::from(tau) * high);
            for value in [smallest, largest] {
                if value < min * (1.0 - TABLE_RANGE_SLACK)
                    || value > max * (1.0 + TABLE_RANGE_SLACK)
                {
                    return Err(ShadingError::OutsideTable {
                        channel,
                        value,
                        min,
                        max,
                    });
                }
            }
        }
        Ok(())
    }

    /// Whether τ1 is the same in all channels (then α is grey and blend factor SrcAlpha suffices).
    pub fn grey_optical_thickness(&self) -> bool {
        let [r, g, b] = self.optical_thickness;
        r == g && g == b
    }
}

/// What is drawn first, behind the slab.
#[derive(Debug, Clone, PartialEq)]
pub enum Background {
    /// Uniform linear radiance (W/(m²·sr)) per channel.
    Uniform([f32; 3]),
    /// A linear radiance image of exactly the render target's size (pixel-exact, no filtering).
    Image(Texture2d),
}

/// A linear radiance image read back from the render target: rgb in W/(m²·sr), alpha = product of the
/// transmittances α of the layers covering the pixel (1 where only background is seen).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major from the top row.
    pub pixels: Vec<[f32; 4]>,
}

impl LinearImage {
    /// The pixel at column `x`, row `y` (from the top); `None` outside the image.
    pub fn pixel(&self, x: u32, y: u32) -> Option<[f32; 4]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        self.pixels
            .get(y as usize * self.width as usize + x as usize)
            .copied()
    }

    /// 8-bit sRGB RGBA (alpha 255) of `radiance × exposure`, clamped to [0, 1] for display only.
    pub fn to_srgb8(&self, exposure: f32) -> Vec<u8> {
        let mut bytes = Vec::with_capacity(self.pixels.len() * 4);
        for pixel in &self.pixels {
            for &channel in &pixel[..3] {
                bytes.push(linear_to_srgb8(channel * exposure));
            }
            bytes.push(255);
        }
        bytes
    }

    /// Writes the sRGB rendering (see [`Self::to_srgb8`]) as a PNG ([`save_image_file`]).
    pub fn save_png(&self, path: &Path, exposure: f32) -> Result<(), image::ImageError> {
        let image = image::RgbaImage::from_raw(self.width, self.height, self.to_srgb8(exposure))
            .ok_or_else(|| {
                image::ImageError::Parameter(image::error::ParameterError::from_kind(
                    image::error::ParameterErrorKind::DimensionMismatch,
                ))
            })?;
        save_image_file(&image, path, image::ImageFormat::Png)
    }
}

/// Writes `image` to `path` in `format`, so that every write error reaches the caller: it is encoded
/// in memory and written with one [`std::fs::write`]. `image`'s own `save` writes through a buffer
/// whose last flush error is lost when the buffer is dropped: a PNG of a few KiB "written" to a full
/// disk (`/dev/full`) returned `Ok`.
pub fn save_image_file<P, Container>(
    image: &image::ImageBuffer<P, Container>,
    path: &Path,
    format: image::ImageFormat,
) -> Result<(), image::ImageError>
where
    P: image::Pixel + image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
    Container: std::ops::Deref<Target = [P::Subpixel]>,
{
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, format)?;
    write_file_atomically(path, &bytes.into_inner()).map_err(image::ImageError::IoError)
}

/// Writes `bytes` to `path` so that `path` never holds a partial file: they go to a hidden name beside
/// it (`.NAME.part-PID`) and are renamed into place when complete (a rename within one folder is
/// atomic on POSIX file systems). An interrupted or failed write leaves the old file, or none; the
/// partial file is removed on error (a killed process can leave one, hidden). Through a symbolic link
/// the file it names is replaced, not the link; a device or pipe (`/dev/stdout`, `/dev/full`) is
/// written directly, since no partial file can be left there.
pub fn write_file_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
        return std::fs::write(path, bytes);
    }
    let target = if path.is_symlink() {
        std::fs::canonicalize(path)?
    } else {
        path.to_path_buf()
    };
    let name = target.file_name().ok_or_else(|| {
        std::io::Error::new(std::io::ErrorKind::InvalidInput, "the path names no file")
    })?;
    let mut partial_name = std::ffi::OsString::from(".");
    partial_name.push(name);
    partial_name.push(format!(".part-{}", std::process::id()));
    let partial = target.with_file_name(partial_name);
    let result = std::fs::write(&partial, bytes).and_then(|()| std::fs::rename(&partial, &target));
    if result.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    result
}

/// The inverse sRGB transfer function (IEC 61966-2-1): an 8-bit sRGB value to linear [0, 1], e.g. for
/// texture data read from PNG files.
pub fn srgb8_to_linear(value: u8) -> f32 {
    let c = f32::from(value) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB transfer function (IEC 61966-2-1) of a display value, clamped to [0, 1] (NaN → 0): the
/// encoded value in [0, 1], unquantised (for measuring display differences finer than a level).
pub fn linear_to_srgb(value: f32) -> f32 {
    let v = if value.is_nan() {
        0.0
    } else {
        value.clamp(0.0, 1.0)
    };
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// [`linear_to_srgb`] to 8 bits: `round(255·linear_to_srgb(value))`, looked up rather than evaluated
/// with a `powf` per channel (three per pixel per frame, 10 % of `perf record`'s samples of the window;
/// a 512 × 512 frame 8.66 → 1.61 ms, `cargo bench -p sheer-slab --bench srgb`). The same codes for
/// every `f32` (unit test
/// `srgb8_by_table_equals_the_formula_for_every_f32_in_the_unit_interval`).
pub fn linear_to_srgb8(value: f32) -> u8 {
    // Clamped as the formula clamps (NaN → 0), without branches: a frame's values are in no order.
    let clamped = if value > 0.0 { value.min(1.0) } else { 0.0 };
    let table = srgb8_table();
    let code = table.code_at_bucket_start[(clamped.to_bits() >> SRGB8_BUCKET_BITS) as usize];
    code + u8::from(clamped >= table.thresholds[usize::from(code)])
}

/// `round(255·linear_to_srgb(value))`, evaluated.
fn linear_to_srgb8_by_formula(value: f32) -> u8 {
    (linear_to_srgb(value) * 255.0).round() as u8
}

/// The low bits of an `f32` that one bucket of [`Srgb8Table`] spans: 2¹⁶ neighbouring floats, in which
/// the code steps up at most once (the steepest, the one starting at 0.5, spans about 0.66 codes; the
/// exhaustive unit test would fail on a bucket that spanned two steps).
const SRGB8_BUCKET_BITS: u32 = 16;

/// The tables of [`linear_to_srgb8`].
struct Srgb8Table {
    /// At index `k` (0…254), the least `f32` that the formula maps to code `k + 1` or more: found by
    /// bisection over the bit patterns of [0, 1], which order as the values do. Index 255: infinity.
    thresholds: [f32; 256],
    /// For each bucket of floats in [0, 1] (the bit pattern without its low [`SRGB8_BUCKET_BITS`]), the
    /// code of its first float.
    code_at_bucket_start: Vec<u8>,
}

fn srgb8_table() -> &'static Srgb8Table {
    static TABLE: std::sync::OnceLock<Srgb8Table> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let one = 1.0f32.to_bits();
        let thresholds = std::array::from_fn(|index| {
            let Ok(code) = u8::try_from(index + 1) else {
                return f32::INFINITY;
            };
            let (mut below, mut at) = (0.0f32.to_bits(), one);
            while at - below > 1 {
                let middle = below + (at - below) / 2;
                if linear_to_srgb8_by_formula(f32::from_bits(middle)) >= code {
                    at = middle;
                } else {
                    below = middle;
                }
            }
            f32::from_bits(at)
        });
        let code_at_bucket_start = (0..=one >> SRGB8_BUCKET_BITS)
            .map(|bucket| linear_to_srgb8_by_formula(f32::from_bits(bucket << SRGB8_BUCKET_BITS)))
            .collect();
        Srgb8Table {
            thresholds,
            code_at_bucket_start,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A texel value: ordinary, at or beyond the albedo and half-float thickness bounds, or negative.
    fn texel_value() -> impl Strategy<Value = f32> {
        prop_oneof![
            0.0f32..=1.0,
            Just(0.0f32),
            Just(-0.0f32),
            Just(1.0f32),
            Just(f32::from_bits(1.0f32.to_bits() + 1)),
            Just(6.103_515_6e-5f32),
            Just(6.1e-5f32),
            Just(65504.0f32),
            Just(65520.0f32),
            -2.0f32..0.0,
            0.0f32..70_000.0,
            Just(3e38f32),
        ]
    }

    fn scale() -> impl Strategy<Value = f32> {
        prop_oneof![
            0.0f32..=2.0,
            Just(0.0f32),
            Just(-0.0f32),
            Just(1.0f32),
            Just(f32::from_bits(1.0f32.to_bits() - 1)),
            Just(-0.5f32),
            Just(f32::INFINITY),
            Just(f32::NAN),
            Just(1e-39f32),
        ]
    }

    fn texture() -> impl Strategy<Value = Texture2d> {
        (1u32..5, 1u32..5).prop_flat_map(|(width, height)| {
            prop::collection::vec(
                prop::array::uniform4(texel_value()),
                (width * height) as usize,
            )
            .prop_map(move |texels| Texture2d::new(width, height, texels).unwrap())
        })
    }

    /// The texture checks of `ShadingParams::validate` as a pass over every texel (what it did
    /// before it used each channel's extremes).
    fn texture_checks_texel_by_texel(params: &ShadingParams) -> Result<(), ShadingError> {
        for (texel, value) in params.albedo_texture.texels.iter().enumerate() {
            let in_range = (0..3).all(|c| {
                let albedo = params.albedo_scale[c] * value[c];
                albedo.is_finite() && (0.0..=1.0).contains(&albedo) && params.albedo_scale[c] >= 0.0
            });
            if !in_range {
                return Err(ShadingError::Albedo {
                    scale: params.albedo_scale,
                    texel,
                });
            }
        }
        if let Some(thickness) = &params.thickness_texture {
            for (texel, value) in thickness.texels.iter().enumerate() {
                if !(6.103_515_6e-5..=65504.0).contains(&value[0]) {
                    return Err(ShadingError::Thickness {
                        texel,
                        value: value[0],
                    });
                }
            }
        }
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// The per-frame checks that use each channel's least and greatest texel accept and refuse
        /// exactly what a pass over every texel does, and name the same first texel.
        #[test]
        fn texture_checks_by_extremes_equal_a_pass_over_every_texel(
            albedo_texture in texture(),
            thickness_texture in proptest::option::of(texture()),
            albedo_scale in prop::array::uniform3(scale()),
            table_min in 0.001f64..1.0,
            table_span in 1.0f64..1000.0,
        ) {
            let mut params = ShadingParams::uniform(1.0, 1.0, Vec3::ONE, 1.0).unwrap();
            params.albedo_texture = albedo_texture;
            params.thickness_texture = thickness_texture;
            params.albedo_scale = albedo_scale;
            let texture_error = |result: Result<(), ShadingError>| match result {
                Err(e @ (ShadingError::Albedo { .. } | ShadingError::Thickness { .. })) => Err(e),
                _ => Ok(()),
            };
            prop_assert_eq!(
                format!("{:?}", texture_error(params.validate())),
                format!("{:?}", texture_checks_texel_by_texel(&params))
            );
            // The table's τ1 range against the half floats of every texel.
            let range = (table_min, table_min * table_span);
            let (low, high) = match &params.thickness_texture {
                Some(texture) => texture.texels.iter().fold((f64::MAX, f64::MIN), |(lo, hi), t| {
                    let v = f64::from(crate::render::cpu::quantize_to_half(t[0]));
                    (lo.min(v), hi.max(v))
                }),
                None => (1.0, 1.0),
            };
            let outside = params.optical_thickness.iter().any(|&tau| {
                [f64::from(tau) * low, f64::from(tau) * high].iter().any(|&value| {
                    value < range.0 * (1.0 - TABLE_RANGE_SLACK)
                        || value > range.1 * (1.0 + TABLE_RANGE_SLACK)
                })
            });
            prop_assert_eq!(params.validate_table_range(range).is_err(), outside);
        }
    }

    /// The table gives the formula's code for every `f32` from 0 to 1 (all 1 065 353 217 of them, on
    /// rayon's threads), so the formula never steps down between two thresholds; and for values
    /// outside: negatives, above 1, infinities, NaN.
    #[test]
    fn srgb8_by_table_equals_the_formula_for_every_f32_in_the_unit_interval() {
        use rayon::prelude::*;
        let mismatches: usize = (0..=1.0f32.to_bits() >> 16)
            .into_par_iter()
            .map(|chunk| {
                let bits = chunk << 16..=(chunk << 16 | 0xffff).min(1.0f32.to_bits());
                bits.filter(|&bits| {
                    let value = f32::from_bits(bits);
                    linear_to_srgb8(value) != linear_to_srgb8_by_formula(value)
                })
                .count()
            })
            .sum();
        assert_eq!(mismatches, 0);
        for value in [
            -0.0,
            -1e-30,
            -1.0,
            f32::NEG_INFINITY,
            f32::from_bits(1.0f32.to_bits() + 1),
            2.0,
            f32::MAX,
            f32::INFINITY,
            f32::NAN,
            -f32::NAN,
        ] {
            assert_eq!(
                linear_to_srgb8(value),
                linear_to_srgb8_by_formula(value),
                "{value}"
            );
        }
        let thresholds = &srgb8_table().thresholds;
        assert!(thresholds.windows(2).all(|pair| pair[0] < pair[1]));
    }

    #[test]
    fn a_clone_of_a_texture_shares_its_texels_and_equals_it() {
        let texture = Texture2d::new(2, 1, vec![[0.25, 0.5, 0.75, 1.0], [1.0; 4]]).unwrap();
        let clone = texture.clone();
        assert!(Arc::ptr_eq(&texture.texels, &clone.texels));
        assert_eq!(texture, clone);
        let same_values = Texture2d::new(2, 1, texture.texels().to_vec()).unwrap();
        assert!(!Arc::ptr_eq(&texture.texels, &same_values.texels));
        assert_eq!(texture, same_values);
        let other = Texture2d::new(2, 1, vec![[0.25, 0.5, 0.75, 1.0], [0.5; 4]]).unwrap();
        assert_ne!(texture, other);
        assert_ne!(
            texture,
            Texture2d::new(1, 2, texture.texels().to_vec()).unwrap()
        );
    }

    #[test]
    fn srgb_endpoints_and_midpoint() {
        assert_eq!(linear_to_srgb8(0.0), 0);
        assert_eq!(linear_to_srgb8(1.0), 255);
        assert_eq!(linear_to_srgb8(2.0), 255);
        assert_eq!(linear_to_srgb8(f32::NAN), 0);
        // sRGB(0.5) = 0.7354 → 187.5 → 188.
        assert_eq!(linear_to_srgb8(0.5), 188);
    }

    #[test]
    fn srgb_decoding_inverts_the_encoding_at_every_8_bit_value() {
        assert_eq!(srgb8_to_linear(0), 0.0);
        assert_eq!(srgb8_to_linear(255), 1.0);
        for value in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(value)), value, "{value}");
        }
    }

    #[test]
    fn mesh_validation_names_the_problem() {
        let mut mesh = SlabMesh::flat_sheet(Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, 2, 2).unwrap();
        assert_eq!(mesh.positions.len(), 9);
        assert_eq!(mesh.indices.len(), 24);
        mesh.indices[5] = 9;
        assert_eq!(
            mesh.validate(),
            Err(MeshError::IndexOutOfRange {
                index: 9,
                position: 5,
                vertices: 9
            })
        );
        mesh.indices[5] = 0;
        mesh.normals[3][1] = f32::NAN;
        assert_eq!(
            mesh.validate(),
            Err(MeshError::NonFinite {
                attribute: "normal",
                vertex: 3
            })
        );
        assert!(SlabMesh::flat_sheet(Vec3::ZERO, Vec3::X, Vec3::X, Vec3::Z, 1, 1).is_err());
    }

    #[test]
    fn shading_validation() {
        let mut params = ShadingParams::uniform(1.0, 0.5, Vec3::Z, 10.0).unwrap();
        params.albedo_scale = [1.5, 0.5, 0.5];
        assert!(matches!(
            params.validate(),
            Err(ShadingError::Albedo { .. })
        ));
        assert!(ShadingParams::uniform(0.0, 0.5, Vec3::Z, 10.0).is_err());
        assert!(ShadingParams::uniform(1.0, 0.5, Vec3::Z, -1.0).is_err());
    }

    /// A camera 3 m up the z axis looking at the origin.
    fn camera_on_the_z_axis() -> Camera {
        Camera {
            eye: Vec3::new(0.0, 0.0, 3.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            vertical_fov: 0.8,
            near: 0.1,
            far: 10.0,
        }
    }

    /// Outside the image there is no pixel (a row past the end panicked, a column past it gave the
    /// next row's pixel).
    #[test]
    fn a_pixel_outside_the_image_is_none() {
        let image = LinearImage {
            width: 3,
            height: 2,
            pixels: (0..6).map(|i| [i as f32; 4]).collect(),
        };
        assert_eq!(image.pixel(2, 1), Some([5.0; 4]));
        assert_eq!(image.pixel(0, 1), Some([3.0; 4]));
        assert_eq!(image.pixel(3, 0), None);
        assert_eq!(image.pixel(0, 2), None);
        assert_eq!(image.pixel(u32::MAX, u32::MAX), None);
    }

    #[test]
    fn pixel_ray_hits_the_target_at_the_centre() {
        let camera = camera_on_the_z_axis();
        let (origin, direction) = camera.pixel_ray(32.0, 16.0, 64, 32).unwrap();
        assert!((origin - DVec3::new(0.0, 0.0, 3.0)).length() < 1e-12);
        // Round trip through an f64 4×4 inverse: ~1e-15 relative per entry.
        assert!((direction - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-12);
    }

    /// Each of these made a view-projection of NaN or infinities: a render of only the background and
    /// NaN rays.
    #[test]
    fn cameras_that_define_no_view_are_typed_errors() {
        let good = camera_on_the_z_axis();
        assert_eq!(good.validate(), Ok(()));
        let bad = |f: &dyn Fn(&mut Camera)| {
            let mut camera = good;
            f(&mut camera);
            let error = camera.validate().unwrap_err();
            // By their text: NaN fields make equal errors compare unequal.
            assert_eq!(
                format!("{:?}", camera.pixel_ray(1.0, 1.0, 4, 4).unwrap_err()),
                format!("{error:?}")
            );
            error
        };
        assert!(matches!(
            bad(&|c| c.eye.x = f32::NAN),
            CameraError::NonFinite { name: "eye", .. }
        ));
        assert!(matches!(
            bad(&|c| c.up = Vec3::splat(f32::INFINITY)),
            CameraError::NonFinite { name: "up", .. }
        ));
        assert!(matches!(
            bad(&|c| c.target = c.eye),
            CameraError::EyeAtTarget(_)
        ));
        assert!(matches!(bad(&|c| c.up = Vec3::ZERO), CameraError::Up(_)));
        assert!(matches!(bad(&|c| c.up = -Vec3::Z), CameraError::Up(_)));
        // 1e-39 rad: 1/tan(fov/2) beyond f32.
        for fov in [0.0, -0.5, 3.2, f32::NAN, 1e-39] {
            assert!(matches!(
                bad(&|c| c.vertical_fov = fov),
                CameraError::FieldOfView(_)
            ));
        }
        for (near, far) in [(0.0, 10.0), (-1.0, 10.0), (5.0, 5.0), (1.0, f32::INFINITY)] {
            assert!(matches!(
                bad(&|c| (c.near, c.far) = (near, far)),
                CameraError::ClipPlanes { .. }
            ));
        }
        assert!(matches!(
            good.pixel_ray(f64::NAN, 1.0, 4, 4),
            Err(CameraError::PixelPosition { .. })
        ));
        assert!(matches!(
            good.pixel_ray(1.0, 1.0, 0, 4),
            Err(CameraError::ImageSize {
                width: 0,
                height: 4
            })
        ));
    }
}
