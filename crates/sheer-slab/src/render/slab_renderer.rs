//! [`SlabRenderer`]: the thin-slab renderer as a component of the caller's wgpu frame, in the shape of
//! egui-wgpu's renderer. Create it once from the caller's `Device`, `Queue`, target format, sample count
//! and depth format; each frame, [`prepare`](SlabRenderer::prepare) uploads the mesh, the material and the
//! tables (and encodes the per-vertex all-orders compute pass into the caller's encoder), and
//! [`paint`](SlabRenderer::paint) records the background, the opaque geometry, the light marker and the
//! back-to-front sorted cloth, blended by eq. (9) `L_dst·α_src + L_src`, into the caller's render pass. It
//! never creates a device, never waits for the GPU and never reads back; errors are values.
//!
//! Draw order inside the pass: background (no depth), opaque meshes and the light marker (depth test and
//! write), cloth (depth test, no write). With a depth attachment an opaque pole hides the cloth behind it
//! and is seen through the cloth in front of it.
//!
//! With [`ShadingParams::shadows`], `prepare` first encodes the shadow map's depth-peeling passes from the
//! light into the caller's encoder (render passes into the renderer's own textures; [`super::shadow`]).

use std::collections::HashMap;
use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::cpu::{VertexSlab, f32_to_f16_bits, per_vertex_slab_values, sort_back_to_front};
use super::shadow::{LightView, SHADOW_DISTANCE_BIAS, SHADOW_LAYERS, SHADOW_SLOPE_TEXELS};
use super::{
    AllOrdersSampling, Background, Camera, EvaluationPath, LIT_SIDE, MULTIPLE_AT_VERTEX,
    OUTPUT_DUAL, OUTPUT_SINGLE, RenderError, SHADER_BODY, SHADOW, ShadingError, ShadingParams,
    SlabMesh, Texture2d, validated,
};
use crate::all_orders::{AllOrdersTable, Scattering, TableFace};
use crate::model::IrradianceConvention;
use crate::sky::DiffuseTable;
use sheer_transport::TableSpec;

/// What a [`SlabRenderer`] writes into its target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TargetOutput {
    /// Linear radiance, W/(m²·sr), for a float target the caller reads or tone-maps itself.
    Radiance,
    /// Radiance times [`ShadingParams::exposure`], for a display target: use an `…Srgb` format, which
    /// blends in linear light and encodes on store (it clamps at 1 after every layer).
    Exposed,
}

/// How the caller's render pass is set up; fixed for the renderer's life.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlabRendererOptions {
    /// The colour attachment's format. It must be blendable (`Rgba32Float` needs
    /// `Features::FLOAT32_BLENDABLE`).
    pub target_format: wgpu::TextureFormat,
    /// Samples per pixel of the colour attachment: 1, or 4 for anti-aliased edges.
    pub samples: u32,
    /// The depth attachment's format, if the pass has one (then opaque geometry hides the cloth behind
    /// it); the caller clears it to 1.0.
    pub depth_format: Option<wgpu::TextureFormat>,
    /// Radiance or exposed radiance.
    pub output: TargetOutput,
}

/// An opaque, diffuse (Lambertian) mesh lit by the point light and the sky: a flag pole, say.
#[derive(Debug, Clone, PartialEq)]
pub struct OpaqueMesh {
    /// Vertex positions, m.
    pub positions: Vec<[f32; 3]>,
    /// Outward unit normals, one per vertex.
    pub normals: Vec<[f32; 3]>,
    /// Triangles, three vertex indices each.
    pub indices: Vec<u32>,
    /// Diffuse albedo ρ per channel, in [0, 1].
    pub albedo: [f32; 3],
}

impl OpaqueMesh {
    /// A closed cylinder from `bottom` to `top` of `radius` (m) with `segments` sides (≥ 3) and flat
    /// caps. Errors if the axis or the radius is not positive and finite.
    pub fn cylinder(
        bottom: Vec3,
        top: Vec3,
        radius: f32,
        segments: u32,
        albedo: [f32; 3],
    ) -> Result<OpaqueMesh, ShadingError> {
        let axis = top - bottom;
        let length = axis.length();
        if !(length.is_finite() && length > 0.0 && radius.is_finite() && radius > 0.0)
            || segments < 3
        {
            return Err(ShadingError::OpaqueMesh(format!(
                "cylinder of length {length} m, radius {radius} m, {segments} segments"
            )));
        }
        let along = axis / length;
        let (u, v) = along.any_orthonormal_pair();
        let mut mesh = OpaqueMesh {
            positions: Vec::new(),
            normals: Vec::new(),
            indices: Vec::new(),
            albedo,
        };
        // The side: one ring at each end, normals pointing out.
        for k in 0..segments {
            let angle = k as f32 / segments as f32 * std::f32::consts::TAU;
            let normal = u * angle.cos() + v * angle.sin();
            for end in [bottom, top] {
                mesh.positions.push((end + radius * normal).to_array());
                mesh.normals.push(normal.to_array());
            }
        }
        for k in 0..segments {
            let (a, b) = (2 * k, 2 * ((k + 1) % segments));
            mesh.indices
                .extend_from_slice(&[a, b, a + 1, b, b + 1, a + 1]);
        }
        // The caps: a fan around each end's centre.
        for (end, normal) in [(bottom, -along), (top, along)] {
            let centre = mesh.positions.len() as u32;
            mesh.positions.push(end.to_array());
            mesh.normals.push(normal.to_array());
            for k in 0..segments {
                let angle = k as f32 / segments as f32 * std::f32::consts::TAU;
                mesh.positions
                    .push((end + radius * (u * angle.cos() + v * angle.sin())).to_array());
                mesh.normals.push(normal.to_array());
            }
            for k in 0..segments {
                mesh.indices.extend_from_slice(&[
                    centre,
                    centre + 1 + k,
                    centre + 1 + (k + 1) % segments,
                ]);
            }
        }
        Ok(mesh)
    }

    /// Checks lengths, indices, finiteness, normals (of about unit length) and the albedo range.
    pub fn validate(&self) -> Result<(), ShadingError> {
        let fail = |what: String| Err(ShadingError::OpaqueMesh(what));
        if self.normals.len() != self.positions.len() {
            return fail(format!(
                "{} normals for {} positions",
                self.normals.len(),
                self.positions.len()
            ));
        }
        if !self.indices.len().is_multiple_of(3) {
            return fail(format!(
                "{} indices, not whole triangles",
                self.indices.len()
            ));
        }
        if let Some(&index) = self
            .indices
            .iter()
            .find(|&&i| i as usize >= self.positions.len())
        {
            return fail(format!(
                "index {index} beyond {} vertices",
                self.positions.len()
            ));
        }
        let finite = |v: &[f32; 3]| v.iter().all(|c| c.is_finite());
        if !self.positions.iter().all(finite) || !self.normals.iter().all(finite) {
            return fail("a position or normal is not finite".into());
        }
        // The shader normalises them: a zero normal would give a NaN pixel.
        if let Some(normal) = self
            .normals
            .iter()
            .find(|n| Vec3::from_array(**n).length() < 0.5)
        {
            return fail(format!("normal {normal:?} is not a unit vector"));
        }
        if !self.albedo.iter().all(|a| (0.0..=1.0).contains(a)) {
            return fail(format!("albedo {:?} outside [0, 1]", self.albedo));
        }
        Ok(())
    }
}

/// A marker where the point light is: a disc of constant radiance with a black rim, drawn at the light's
/// depth, so the cloth in front of the light is seen over it. It marks the light; it does not model it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightMarker {
    /// Radius of the disc, pixels (> 0).
    pub radius_pixels: f32,
    /// Radiance of the disc, W/(m²·sr) (finite, ≥ 0).
    pub radiance: [f32; 3],
}

/// One frame of cloth for [`SlabRenderer::prepare`].
#[derive(Debug, Clone, Copy)]
pub struct SlabFrame<'a> {
    /// The cloth.
    pub mesh: &'a SlabMesh,
    /// The view.
    pub camera: &'a Camera,
    /// Material, light and model.
    pub shading: &'a ShadingParams,
    /// What is behind everything (an image must have the target's size).
    pub background: &'a Background,
    /// Which evaluation path shades the cloth.
    pub path: EvaluationPath,
    /// Opaque geometry in the scene (none, or a flag pole).
    pub opaque: &'a [OpaqueMesh],
    /// The light's marker, if it is shown.
    pub light_marker: Option<LightMarker>,
    /// Only this rectangle of the target (x, y, width, height in pixels), or all of it.
    pub scissor: Option<[u32; 4]>,
}

/// A prepared frame: what [`SlabRenderer::paint`] records. Cheap to hold (shared GPU handles).
#[derive(Debug, Clone)]
pub struct SlabDraw {
    bind_group: wgpu::BindGroup,
    pipeline: wgpu::RenderPipeline,
    vertices: Option<wgpu::Buffer>,
    /// The CPU path's values or the multiple part per vertex (vertex buffer 1).
    per_vertex: Option<wgpu::Buffer>,
    indices: Option<wgpu::Buffer>,
    index_count: u32,
    opaque: Option<(wgpu::Buffer, wgpu::Buffer, u32)>,
    marker: bool,
    scissor: [u32; 4],
}

/// Attachments for a [`SlabRenderer`] when the caller has none of its own: a colour texture of the
/// renderer's format (drawn multisampled and resolved into it when the options ask for samples) and a
/// depth texture if the options name a depth format.
#[derive(Debug)]
pub struct SlabTarget {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    multisampled: Option<wgpu::TextureView>,
    depth: Option<wgpu::TextureView>,
}

impl SlabTarget {
    /// Textures of `width × height` for `options`; the colour texture also gets `usage` (`COPY_SRC` to
    /// read it back, `TEXTURE_BINDING` to sample it).
    pub fn new(
        device: &wgpu::Device,
        options: SlabRendererOptions,
        (width, height): (u32, u32),
        usage: wgpu::TextureUsages,
    ) -> Result<SlabTarget, RenderError> {
        let max = device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::Size { width, height, max });
        }
        // An sRGB colour texture may also be viewed without the sRGB encoding (egui samples textures
        // as gamma-encoded values).
        let plain = options.target_format.remove_srgb_suffix();
        let texture = |label, format: wgpu::TextureFormat, samples, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: if format.is_srgb() && samples == 1 {
                    std::slice::from_ref(&plain)
                } else {
                    &[]
                },
            })
        };
        let view = |texture: &wgpu::Texture| texture.create_view(&Default::default());
        let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let colour = texture("slab target", options.target_format, 1, attachment | usage);
        // The samples, resolved into `colour` at the end of each pass.
        let multisampled = (options.samples > 1).then(|| {
            view(&texture(
                "slab samples",
                options.target_format,
                options.samples,
                attachment,
            ))
        });
        let depth = options
            .depth_format
            .map(|format| view(&texture("slab depth", format, options.samples, attachment)));
        Ok(SlabTarget {
            view: view(&colour),
            texture: colour,
            multisampled,
            depth,
        })
    }

    /// The (resolved) colour texture. An sRGB one can also be viewed in its format without the sRGB
    /// encoding (`TextureFormat::remove_srgb_suffix`).
    pub fn texture(&self) -> &wgpu::Texture {
        &self.texture
    }

    /// A view of the (resolved) colour texture.
    pub fn view(&self) -> &wgpu::TextureView {
        &self.view
    }

    /// Begins a pass that clears colour to transparent black and depth to 1, ready for
    /// [`SlabRenderer::paint`].
    pub fn begin_pass<'e>(&self, encoder: &'e mut wgpu::CommandEncoder) -> wgpu::RenderPass<'e> {
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("slab pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: self.multisampled.as_ref().unwrap_or(&self.view),
                depth_slice: None,
                resolve_target: self.multisampled.as_ref().map(|_| &self.view),
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: self.depth.as_ref().map(|view| {
                wgpu::RenderPassDepthStencilAttachment {
                    view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }
}

/// A pipeline variant: path, dual-source output (per-channel τ1), thickness texture, all-orders model,
/// and for the per-fragment path with all orders whether the table is looked up per vertex.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct PipelineKey {
    path: EvaluationPath,
    dual: bool,
    thickness: bool,
    all_orders: bool,
    multiple_at_vertex: bool,
    sky: bool,
    shadows: bool,
}

impl PipelineKey {
    /// The shader's override constants for this variant. They specialise the shader at pipeline
    /// creation: per-channel τ1 evaluates the model three times, grey τ1 once; the thickness texture is
    /// sampled only when there is one (a software rasteriser would otherwise pay for the masked-off
    /// sample); the all-orders lookup exists only in all-orders pipelines, so single scattering runs
    /// exactly the code it ran before.
    fn override_constants(self) -> [(&'static str, f64); 5] {
        [
            ("per_channel_thickness", flag(self.dual)),
            ("has_thickness_texture", flag(self.thickness)),
            ("all_orders", flag(self.all_orders)),
            ("sky_light", flag(self.sky)),
            ("shadows", flag(self.shadows)),
        ]
    }
}

/// An override constant's value for a flag.
fn flag(on: bool) -> f64 {
    if on { 1.0 } else { 0.0 }
}

/// A shadow-map peeling pipeline: first layer or not, cloth or opaque, and for the cloth what its
/// fragments sample (per-channel τ1, thickness texture, the diffuse part).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct PeelKey {
    first: bool,
    opaque: bool,
    per_channel: bool,
    thickness: bool,
    diffuse: bool,
}

/// The shadow map: one `Rgba32Uint` texture per layer (`shaders/shadow.wgsl` gives the packing) and the
/// depth buffer its passes share.
struct ShadowMaps {
    resolution: u32,
    layers: Vec<wgpu::TextureView>,
    depth: wgpu::TextureView,
    /// Group 1 of peel pass k: layer k − 1 (pass 0: the empty stand-in).
    previous: Vec<wgpu::BindGroup>,
}

/// An empty shadow-map texel: no surface (distance 3e38 m, as f32 bits).
const EMPTY_SHADOW_TEXEL: [u32; 4] = [0x7f61_b1e6, 0, 0, 0];

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct FrameUniform {
    view_projection: [[f32; 4]; 4],
    eye: [f32; 4],
    light: [f32; 4],
    optical_thickness: [f32; 4],
    albedo_scale: [f32; 4],
    background: [f32; 4],
    baseline: [f32; 4],
    /// Sky light: the nine coefficients of E/π (`DiffuseEnvironment::shader_coefficients`).
    sky: [[f32; 4]; 9],
    /// Target width and height (pixels), output scale, light marker radius (pixels).
    output: [f32; 4],
    /// The light marker's radiance.
    marker: [f32; 4],
    /// The shadow map's view and projection from the light.
    shadow_view_projection: [[f32; 4]; 4],
    /// Resolution (texels), slope bias per metre of distance, distance bias per metre, unused.
    shadow: [f32; 4],
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct Vertex {
    position: [f32; 3],
    normal: [f32; 3],
    uv: [f32; 2],
}

/// A vertex of an opaque mesh (`OpaqueInput` in `thin_slab.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct OpaqueVertex {
    position: [f32; 3],
    normal: [f32; 3],
    albedo: [f32; 3],
}

struct GpuTexture {
    // Held so the texture outlives every bind group made from `view`.
    _texture: wgpu::Texture,
    view: wgpu::TextureView,
    source: Option<Texture2d>,
}

/// Axes of the all-orders table as the shader reads them (`AllOrdersAxes` in `thin_slab.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(crate) struct AllOrdersAxes {
    /// x: `c0 = ln τmin + τmin`; y: `1/(c1 − c0)`; z: τ1 cells; w: albedo cells.
    tau: [f32; 4],
    /// x: cosine cells C; y: texture rows per face (τ1 nodes × C).
    cosine: [f32; 4],
}

/// The all-orders table on the GPU (see the module docs of `render`), with the table it was made from.
struct GpuTable {
    _cells: wgpu::Texture,
    cells_view: wgpu::TextureView,
    _warp: wgpu::Texture,
    warp_view: wgpu::TextureView,
    axes: wgpu::Buffer,
    source: Option<Arc<AllOrdersTable>>,
    /// The grid whose axes (`warp_view`, `axes`) are uploaded: the all-orders table's, or the diffuse
    /// table's when only the sky needs them.
    spec: Option<TableSpec>,
}

/// The diffuse (sky light) table on the GPU, with the table it was made from.
struct GpuDiffuse {
    _cells: wgpu::Texture,
    view: wgpu::TextureView,
    source: Option<Arc<DiffuseTable>>,
}

/// The thin-slab renderer on the caller's device (see the module docs).
pub struct SlabRenderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    options: SlabRendererOptions,
    dual_source: bool,
    uniform: wgpu::Buffer,
    sampler: wgpu::Sampler,
    bind_group_layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    /// Group 1 of the renderer's compute passes: one storage buffer in (binding 0), one out (binding 1)
    /// — the per-vertex all-orders pass (mesh vertices in, multiple part out) and the model checks.
    pub(crate) compute_io_layout: wgpu::BindGroupLayout,
    /// Group 0 (the frame's bindings) and group 1 [`compute_io_layout`](Self::compute_io_layout).
    pub(crate) compute_io_pipeline_layout: wgpu::PipelineLayout,
    modules: HashMap<bool, wgpu::ShaderModule>,
    pipelines: HashMap<PipelineKey, wgpu::RenderPipeline>,
    /// The per-vertex all-orders pass per (per-channel τ1, thickness texture).
    multiple_pipelines: HashMap<(bool, bool), wgpu::ComputePipeline>,
    background_pipeline: wgpu::RenderPipeline,
    opaque_pipeline: wgpu::RenderPipeline,
    marker_pipeline: wgpu::RenderPipeline,
    /// Group 1 of the shadow map's peel passes (the previous layer) and their layout.
    peel_layout: wgpu::BindGroupLayout,
    peel_pipeline_layout: wgpu::PipelineLayout,
    peel_pipelines: HashMap<PeelKey, wgpu::RenderPipeline>,
    /// A 1×1 empty shadow-map layer, bound wherever no shadow map is (no shadows, the peel passes).
    empty_shadow: wgpu::TextureView,
    shadow_maps: Option<ShadowMaps>,
    albedo: GpuTexture,
    thickness: GpuTexture,
    background: GpuTexture,
    table: GpuTable,
    diffuse: GpuDiffuse,
    vertex_buffer: Option<(wgpu::Buffer, usize)>,
    cpu_buffer: Option<(wgpu::Buffer, usize)>,
    /// The multiple part per vertex, both faces (6 floats per vertex), written by the compute pass.
    multiple_buffer: Option<(wgpu::Buffer, usize)>,
    index_buffer: Option<(wgpu::Buffer, usize)>,
    opaque_vertex_buffer: Option<(wgpu::Buffer, usize)>,
    opaque_index_buffer: Option<(wgpu::Buffer, usize)>,
    sorted_indices: Vec<u32>,
    vertex_scratch: Vec<Vertex>,
}

impl SlabRenderer {
    /// Creates the renderer's layouts, buffers and fixed pipelines on `device`. Errors: samples other
    /// than 1 or 4, or a target format the device cannot render and blend with those samples.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        options: SlabRendererOptions,
    ) -> Result<SlabRenderer, RenderError> {
        if !matches!(options.samples, 1 | 4) {
            return Err(RenderError::Samples(options.samples));
        }
        let (device, queue) = (device.clone(), queue.clone());
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame uniform"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("linear clamp"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        // Every binding is also visible to compute: the per-vertex all-orders pass reads the frame, the
        // textures and the table.
        let all_stages = wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let texture_entry = |binding: u32, filterable: bool| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: all_stages,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let table_entry = |binding: u32| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        // A shadow-map layer (shadow.wgsl), read with textureLoad.
        let shadow_entry = |binding: u32| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: all_stages,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Uint,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let bind_group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("slab bindings"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: all_stages,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                texture_entry(1, true),
                texture_entry(2, true),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: all_stages,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
                texture_entry(4, false),
                // The all-orders table: also read by the compute check of the lookup.
                table_entry(5),
                table_entry(6),
                table_entry(8),
                shadow_entry(9),
                shadow_entry(10),
                wgpu::BindGroupLayoutEntry {
                    binding: 7,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("slab layout"),
            bind_group_layouts: &[Some(&bind_group_layout)],
            immediate_size: 0,
        });
        let storage_entry = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let compute_io_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("compute io"),
            entries: &[storage_entry(0, true), storage_entry(1, false)],
        });
        let compute_io_pipeline_layout =
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("compute io"),
                bind_group_layouts: &[Some(&bind_group_layout), Some(&compute_io_layout)],
                immediate_size: 0,
            });
        let peel_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow peel previous layer"),
            entries: &[wgpu::BindGroupLayoutEntry {
                visibility: wgpu::ShaderStages::FRAGMENT,
                ..shadow_entry(2)
            }],
        });
        let peel_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadow peel"),
            bind_group_layouts: &[Some(&bind_group_layout), Some(&peel_layout)],
            immediate_size: 0,
        });
        let empty_shadow = shadow_layer_texture(&device, 1, "empty shadow layer");
        queue.write_texture(
            empty_shadow.as_image_copy(),
            bytemuck::cast_slice(&EMPTY_SHADOW_TEXEL),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(16),
                rows_per_image: Some(1),
            },
            wgpu::Extent3d {
                width: 1,
                height: 1,
                depth_or_array_layers: 1,
            },
        );
        let empty_shadow = empty_shadow.create_view(&Default::default());
        let white = Texture2d::uniform([1.0; 4])?;
        let albedo =
            Self::upload_texture(&device, &queue, &white, wgpu::TextureFormat::Rgba16Float);
        let thickness =
            Self::upload_texture(&device, &queue, &white, wgpu::TextureFormat::Rgba16Float);
        let background =
            Self::upload_texture(&device, &queue, &white, wgpu::TextureFormat::Rgba32Float);
        // Single scattering binds a 1×1 stand-in for the table (the layout needs one).
        let table = Self::upload_table_textures(
            &device,
            &queue,
            (1, 1, &[0.0; 4]),
            (1, &[0.0; 4]),
            AllOrdersAxes::zeroed(),
            None,
            None,
        );
        // Without sky light a 1×1 stand-in for the diffuse table, as for the all-orders table.
        let diffuse = Self::upload_diffuse_texture(&device, &queue, (1, 1, &[0.0; 4]), None);
        let dual_source = device
            .features()
            .contains(wgpu::Features::DUAL_SOURCE_BLENDING);
        let module = shader_module(&device, false)?;
        let fixed = FixedPipelines::new(&device, &pipeline_layout, &module, options)?;
        Ok(SlabRenderer {
            device,
            queue,
            options,
            dual_source,
            uniform,
            sampler,
            bind_group_layout,
            pipeline_layout,
            compute_io_layout,
            compute_io_pipeline_layout,
            modules: HashMap::from([(false, module)]),
            pipelines: HashMap::new(),
            multiple_pipelines: HashMap::new(),
            background_pipeline: fixed.background,
            opaque_pipeline: fixed.opaque,
            marker_pipeline: fixed.marker,
            peel_layout,
            peel_pipeline_layout,
            peel_pipelines: HashMap::new(),
            empty_shadow,
            shadow_maps: None,
            albedo,
            thickness,
            background,
            table,
            diffuse,
            vertex_buffer: None,
            cpu_buffer: None,
            multiple_buffer: None,
            index_buffer: None,
            opaque_vertex_buffer: None,
            opaque_index_buffer: None,
            sorted_indices: Vec::new(),
            vertex_scratch: Vec::new(),
        })
    }

    /// The options the renderer was made with.
    pub fn options(&self) -> SlabRendererOptions {
        self.options
    }

    /// Whether per-channel τ1 (dual-source blending, `Features::DUAL_SOURCE_BLENDING`) is available.
    pub fn supports_per_channel_optical_thickness(&self) -> bool {
        self.dual_source
    }

    /// The largest width or height of a texture on this device (the albedo and thickness textures of
    /// [`ShadingParams`] must fit; [`RenderError::TextureTooLarge`] otherwise).
    pub fn max_texture_dimension(&self) -> u32 {
        self.device.limits().max_texture_dimension_2d
    }

    /// Checks `frame`, uploads what changed (mesh, sorted indices, textures, tables, uniform) through
    /// the queue, and encodes the per-vertex all-orders compute pass into `encoder` when the frame needs
    /// it. `target_size` is the render pass's size in pixels. The returned draw is recorded by
    /// [`paint`](Self::paint) into a pass submitted after the uploads (the queue orders them).
    ///
    /// Several frames may be prepared for one pass (a split view: each with its own scissor and path)
    /// as long as they share the mesh, camera and shading; the last uniform written is the one used.
    pub fn prepare(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        target_size: (u32, u32),
        frame: &SlabFrame<'_>,
    ) -> Result<SlabDraw, RenderError> {
        let SlabFrame {
            mesh,
            camera,
            shading,
            background,
            path,
            ..
        } = *frame;
        let (width, height) = target_size;
        let max = self.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::Size { width, height, max });
        }
        mesh.validate()?;
        camera.validate()?;
        shading.validate()?;
        for opaque in frame.opaque {
            opaque.validate()?;
        }
        if let Some(marker) = frame.light_marker
            && !(marker.radius_pixels.is_finite()
                && marker.radius_pixels > 0.0
                && marker.radiance.iter().all(|c| c.is_finite() && *c >= 0.0))
        {
            return Err(ShadingError::LightMarker {
                radius_pixels: marker.radius_pixels,
                radiance: marker.radiance,
            }
            .into());
        }
        let dual = !shading.grey_optical_thickness();
        if dual && !self.dual_source {
            return Err(RenderError::PerChannelAlphaUnsupported);
        }
        self.update_textures(shading, background, target_size)?;
        match (&shading.scattering, &shading.sky) {
            (Scattering::AllOrders(table), _) => self.update_table(table)?,
            // The sky samples its table on the all-orders table's axes: upload the axes alone.
            (Scattering::Single, Some(sky)) => self.update_axes(&sky.table)?,
            (Scattering::Single, None) => {}
        }
        if let Some(table) = shading.diffuse_table() {
            self.update_diffuse(table)?;
        }
        // The baseline is the paper's comparison as published: no shadows; the CPU path casts rays.
        let shadow_view = match &shading.shadows {
            Some(shadows)
                if matches!(
                    path,
                    EvaluationPath::PerFragment | EvaluationPath::PerVertex
                ) =>
            {
                if shadows.resolution > max {
                    return Err(RenderError::TextureTooLarge {
                        texture: "shadow map",
                        width: shadows.resolution,
                        height: shadows.resolution,
                        max,
                    });
                }
                LightView::covering(
                    shading.light_position,
                    mesh.positions.iter().copied(),
                    shadows.resolution,
                )
                .map(|view| (view, shadows.resolution))
            }
            _ => None,
        };
        let uniform = self.frame_uniform(frame, target_size, shadow_view);
        self.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        self.upload_mesh(mesh, frame.opaque, camera, shading, path)?;
        let opaque_index_count = self.upload_opaque(frame.opaque);
        if let Some((_, resolution)) = shadow_view {
            let peel = PeelKey {
                first: true,
                opaque: false,
                per_channel: dual,
                thickness: shading.thickness_texture.is_some(),
                diffuse: shading.diffuse_through_table().is_some(),
            };
            let counts = (mesh.indices.len() as u32, opaque_index_count);
            self.encode_shadow_passes(encoder, peel, resolution, counts)?;
        }
        let key = PipelineKey {
            path,
            dual,
            thickness: shading.thickness_texture.is_some(),
            // The baseline ignores the scattering model.
            all_orders: path != EvaluationPath::Baseline
                && matches!(shading.scattering, Scattering::AllOrders(_)),
            multiple_at_vertex: path == EvaluationPath::PerFragment
                && matches!(shading.scattering, Scattering::AllOrders(_))
                && shading.all_orders_sampling == AllOrdersSampling::PerVertex,
            // The CPU path evaluates the sky per vertex itself; the baseline has none.
            sky: shading.sky.is_some()
                && matches!(
                    path,
                    EvaluationPath::PerFragment | EvaluationPath::PerVertex
                ),
            shadows: shadow_view.is_some(),
        };
        self.pipeline(key)?;
        let bind_group = self.bind_group_with_shadows(key.shadows);
        if key.multiple_at_vertex {
            self.encode_multiple_at_vertex(encoder, &bind_group, key, mesh.positions.len())?;
        }
        let per_vertex = if key.multiple_at_vertex {
            self.multiple_buffer.as_ref()
        } else if path == EvaluationPath::Cpu {
            self.cpu_buffer.as_ref()
        } else {
            None
        };
        // The marker is drawn only in front of the camera.
        let light = shading.light_position;
        let marker = frame.light_marker.is_some()
            && (camera.view_projection(width, height) * light.extend(1.0)).w > 0.0;
        let opaque = match (
            &self.opaque_vertex_buffer,
            &self.opaque_index_buffer,
            opaque_index_count,
        ) {
            (Some((vertices, _)), Some((indices, _)), count) if count > 0 => {
                Some((vertices.clone(), indices.clone(), count))
            }
            _ => None,
        };
        Ok(SlabDraw {
            bind_group,
            pipeline: self.pipelines[&key].clone(),
            vertices: self.vertex_buffer.as_ref().map(|(b, _)| b.clone()),
            per_vertex: per_vertex.map(|(b, _)| b.clone()),
            indices: self.index_buffer.as_ref().map(|(b, _)| b.clone()),
            index_count: mesh.indices.len() as u32,
            opaque,
            marker,
            scissor: frame.scissor.unwrap_or([0, 0, width, height]),
        })
    }

    /// Records `draw` into `pass` (whose attachments match the renderer's options): background, opaque
    /// meshes, light marker, then the sorted cloth blended by eq. (9).
    pub fn paint(&self, pass: &mut wgpu::RenderPass<'_>, draw: &SlabDraw) {
        let [x, y, width, height] = draw.scissor;
        pass.set_scissor_rect(x, y, width, height);
        pass.set_bind_group(0, &draw.bind_group, &[]);
        pass.set_pipeline(&self.background_pipeline);
        pass.draw(0..3, 0..1);
        if let Some((vertices, indices, count)) = &draw.opaque {
            pass.set_pipeline(&self.opaque_pipeline);
            pass.set_vertex_buffer(0, vertices.slice(..));
            pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..*count, 0, 0..1);
        }
        if draw.marker {
            pass.set_pipeline(&self.marker_pipeline);
            pass.draw(0..4, 0..1);
        }
        let (Some(vertices), Some(indices)) = (&draw.vertices, &draw.indices) else {
            return; // an empty mesh: nothing to draw
        };
        pass.set_pipeline(&draw.pipeline);
        pass.set_vertex_buffer(0, vertices.slice(..));
        if let Some(per_vertex) = &draw.per_vertex {
            pass.set_vertex_buffer(1, per_vertex.slice(..));
        }
        pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..draw.index_count, 0, 0..1);
    }

    /// Encodes the shadow map's [`SHADOW_LAYERS`] peeling passes from the light (`shaders/shadow.wgsl`):
    /// pass k draws the cloth and the opaque meshes and keeps, per texel, the nearest surface behind
    /// layer k − 1. `peel` gives the cloth's variant (its `first` and `opaque` are set here).
    fn encode_shadow_passes(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        peel: PeelKey,
        resolution: u32,
        (cloth_index_count, opaque_index_count): (u32, u32),
    ) -> Result<(), RenderError> {
        if self.shadow_maps.as_ref().map(|m| m.resolution) != Some(resolution) {
            let layers: Vec<wgpu::TextureView> = (0..SHADOW_LAYERS)
                .map(|_| {
                    shadow_layer_texture(&self.device, resolution, "shadow map layer")
                        .create_view(&Default::default())
                })
                .collect();
            let depth = self
                .device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some("shadow map depth"),
                    size: wgpu::Extent3d {
                        width: resolution,
                        height: resolution,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wgpu::TextureFormat::Depth32Float,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                    view_formats: &[],
                })
                .create_view(&Default::default());
            let previous = std::iter::once(&self.empty_shadow)
                .chain(layers.iter().take(SHADOW_LAYERS - 1))
                .map(|view| {
                    self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("shadow peel previous layer"),
                        layout: &self.peel_layout,
                        entries: &[wgpu::BindGroupEntry {
                            binding: 2,
                            resource: wgpu::BindingResource::TextureView(view),
                        }],
                    })
                })
                .collect();
            self.shadow_maps = Some(ShadowMaps {
                resolution,
                layers,
                depth,
                previous,
            });
        }
        let variants = [false, true].map(|first| {
            [false, true].map(|opaque| PeelKey {
                first,
                opaque,
                ..peel
            })
        });
        for key in variants.iter().flatten() {
            self.peel_pipeline(*key)?;
        }
        // The peel passes' group 0 binds the empty stand-in where the layers go: they are the targets.
        let frame_bindings = self.bind_group_with_shadows(false);
        let Some(maps) = &self.shadow_maps else {
            return Ok(());
        };
        let [empty, a, b, c] = EMPTY_SHADOW_TEXEL.map(f64::from);
        for (k, layer) in maps.layers.iter().enumerate() {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow map layer"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: layer,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: empty,
                            g: a,
                            b,
                            a: c,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &maps.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &frame_bindings, &[]);
            pass.set_bind_group(1, &maps.previous[k], &[]);
            let first = k == 0;
            if let (Some((vertices, _)), Some((indices, _))) =
                (&self.vertex_buffer, &self.index_buffer)
                && cloth_index_count > 0
            {
                pass.set_pipeline(&self.peel_pipelines[&variants[usize::from(first)][0]]);
                pass.set_vertex_buffer(0, vertices.slice(..));
                pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..cloth_index_count, 0, 0..1);
            }
            if let (Some((vertices, _)), Some((indices, _))) =
                (&self.opaque_vertex_buffer, &self.opaque_index_buffer)
                && opaque_index_count > 0
            {
                pass.set_pipeline(&self.peel_pipelines[&variants[usize::from(first)][1]]);
                pass.set_vertex_buffer(0, vertices.slice(..));
                pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..opaque_index_count, 0, 0..1);
            }
        }
        Ok(())
    }

    /// Creates the peel pipeline `key` unless it exists.
    fn peel_pipeline(&mut self, key: PeelKey) -> Result<(), RenderError> {
        if self.peel_pipelines.contains_key(&key) {
            return Ok(());
        }
        let module = self.module(false)?;
        let cloth_attributes =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2];
        let opaque_attributes =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3];
        let (entry_points, stride, attributes) = if key.opaque {
            (
                ("vs_peel_opaque", "fs_peel_opaque"),
                std::mem::size_of::<OpaqueVertex>(),
                &opaque_attributes[..],
            )
        } else {
            (
                ("vs_peel_cloth", "fs_peel_cloth"),
                std::mem::size_of::<Vertex>(),
                &cloth_attributes[..],
            )
        };
        let constants = [
            ("first_layer", flag(key.first)),
            ("per_channel_thickness", flag(key.per_channel)),
            ("has_thickness_texture", flag(key.thickness)),
            ("diffuse_through", flag(key.diffuse)),
            // Λ is sampled at the vertex level only where the all-orders switch says so.
            ("all_orders", flag(key.diffuse)),
        ];
        let options = wgpu::PipelineCompilationOptions {
            constants: &constants,
            ..Default::default()
        };
        let pipeline = validated(&self.device, "shadow peel pipeline", || {
            self.device
                .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("shadow peel"),
                    layout: Some(&self.peel_pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(entry_points.0),
                        compilation_options: options.clone(),
                        buffers: &[Some(wgpu::VertexBufferLayout {
                            array_stride: stride as u64,
                            step_mode: wgpu::VertexStepMode::Vertex,
                            attributes,
                        })],
                    },
                    // Both faces cast shadows.
                    primitive: wgpu::PrimitiveState {
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: depth_state(Some(wgpu::TextureFormat::Depth32Float), true),
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(entry_points.1),
                        compilation_options: options.clone(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format: wgpu::TextureFormat::Rgba32Uint,
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
        })?;
        self.peel_pipelines.insert(key, pipeline);
        Ok(())
    }

    fn encode_multiple_at_vertex(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        frame_bindings: &wgpu::BindGroup,
        key: PipelineKey,
        vertex_count: usize,
    ) -> Result<(), RenderError> {
        let size = vertex_count * std::mem::size_of::<VertexSlab>();
        if !matches!(&self.multiple_buffer, Some((_, capacity)) if *capacity == size) {
            let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("multiple at vertex"),
                size: size as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX,
                mapped_at_creation: false,
            });
            self.multiple_buffer = Some((buffer, size));
        }
        let variant = (key.dual, key.thickness);
        if !self.multiple_pipelines.contains_key(&variant) {
            let module = self.module(key.dual)?;
            let constants = key.override_constants();
            let pipeline = validated(&self.device, "multiple-at-vertex pipeline", || {
                self.device
                    .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some("multiple at vertex"),
                        layout: Some(&self.compute_io_pipeline_layout),
                        module: &module,
                        entry_point: Some("cs_multiple_at_vertex"),
                        compilation_options: wgpu::PipelineCompilationOptions {
                            constants: &constants,
                            ..Default::default()
                        },
                        cache: None,
                    })
            })?;
            self.multiple_pipelines.insert(variant, pipeline);
        }
        let (Some((vertices, _)), Some((multiple, _))) =
            (&self.vertex_buffer, &self.multiple_buffer)
        else {
            return Ok(()); // no vertices: nothing to draw either
        };
        let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("multiple at vertex"),
            layout: &self.compute_io_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: vertices.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: multiple.as_entire_binding(),
                },
            ],
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("multiple at vertex"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.multiple_pipelines[&variant]);
        pass.set_bind_group(0, frame_bindings, &[]);
        pass.set_bind_group(1, &bind_group, &[]);
        pass.dispatch_workgroups((vertex_count as u32).div_ceil(64), 1, 1);
        Ok(())
    }

    fn frame_uniform(
        &self,
        frame: &SlabFrame<'_>,
        (width, height): (u32, u32),
        shadow_view: Option<(LightView, u32)>,
    ) -> FrameUniform {
        let SlabFrame {
            camera,
            shading,
            background,
            ..
        } = *frame;
        let [t0, t1, t2] = shading.optical_thickness;
        let [a0, a1, a2] = shading.albedo_scale;
        let eye = camera.eye;
        let light = shading.light_position;
        let marker = frame.light_marker.unwrap_or(LightMarker {
            radius_pixels: 0.0,
            radiance: [0.0; 3],
        });
        let [m0, m1, m2] = marker.radiance;
        FrameUniform {
            view_projection: camera.view_projection(width, height).to_cols_array_2d(),
            eye: [eye.x, eye.y, eye.z, 1.0],
            light: [light.x, light.y, light.z, shading.light_flux],
            optical_thickness: [
                t0,
                t1,
                t2,
                if shading.thickness_texture.is_some() {
                    1.0
                } else {
                    0.0
                },
            ],
            albedo_scale: [
                a0,
                a1,
                a2,
                match shading.convention {
                    IrradianceConvention::NormalToBeam => 0.0,
                    IrradianceConvention::PaperLiteral => 1.0,
                },
            ],
            background: match background {
                Background::Uniform([r, g, b]) => [*r, *g, *b, 0.0],
                Background::Image(_) => [0.0, 0.0, 0.0, 1.0],
            },
            baseline: [shading.baseline_transmittance, 0.0, 0.0, 0.0],
            sky: shading
                .sky
                .as_ref()
                .map_or([[0.0; 4]; 9], |sky| sky.environment.shader_coefficients()),
            output: [
                width as f32,
                height as f32,
                match self.options.output {
                    TargetOutput::Radiance => 1.0,
                    TargetOutput::Exposed => shading.exposure,
                },
                marker.radius_pixels,
            ],
            marker: [m0, m1, m2, 0.0],
            shadow_view_projection: shadow_view
                .map_or(glam::Mat4::IDENTITY, |(view, _)| view.view_projection)
                .to_cols_array_2d(),
            shadow: shadow_view.map_or([0.0; 4], |(view, resolution)| {
                [
                    resolution as f32,
                    SHADOW_SLOPE_TEXELS * view.texel_per_metre,
                    SHADOW_DISTANCE_BIAS,
                    0.0,
                ]
            }),
        }
    }

    fn update_textures(
        &mut self,
        shading: &ShadingParams,
        background: &Background,
        (width, height): (u32, u32),
    ) -> Result<(), RenderError> {
        // Checked before anything is uploaded, so that a refused texture leaves the last good ones.
        let max = self.device.limits().max_texture_dimension_2d;
        let textures = [
            ("albedo", Some(&shading.albedo_texture)),
            ("thickness", shading.thickness_texture.as_ref()),
        ];
        for (texture, source) in textures {
            if let Some(source) = source
                && (source.width() > max || source.height() > max)
            {
                return Err(RenderError::TextureTooLarge {
                    texture,
                    width: source.width(),
                    height: source.height(),
                    max,
                });
            }
        }
        if self.albedo.source.as_ref() != Some(&shading.albedo_texture) {
            self.albedo = Self::upload_texture(
                &self.device,
                &self.queue,
                &shading.albedo_texture,
                wgpu::TextureFormat::Rgba16Float,
            );
        }
        if let Some(thickness) = &shading.thickness_texture
            && self.thickness.source.as_ref() != Some(thickness)
        {
            self.thickness = Self::upload_texture(
                &self.device,
                &self.queue,
                thickness,
                wgpu::TextureFormat::Rgba16Float,
            );
        }
        match background {
            Background::Uniform(colour) => {
                if !colour.iter().all(|c| c.is_finite()) {
                    return Err(ShadingError::NonFiniteTexel { index: 0 }.into());
                }
            }
            Background::Image(image) => {
                if image.width() != width || image.height() != height {
                    return Err(RenderError::BackgroundSize {
                        got_width: image.width(),
                        got_height: image.height(),
                        width,
                        height,
                    });
                }
                if self.background.source.as_ref() != Some(image) {
                    self.background = Self::upload_texture(
                        &self.device,
                        &self.queue,
                        image,
                        wgpu::TextureFormat::Rgba32Float,
                    );
                }
            }
        }
        Ok(())
    }

    /// Group 0 without a shadow map (the empty stand-in in its place), for the shader checks.
    #[cfg(any(test, feature = "test-support"))]
    pub(crate) fn bind_group(&self) -> wgpu::BindGroup {
        self.bind_group_with_shadows(false)
    }

    /// Group 0, with the shadow map's layers if `shadows` (and one exists).
    fn bind_group_with_shadows(&self, shadows: bool) -> wgpu::BindGroup {
        fn texture(binding: u32, view: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: wgpu::BindingResource::TextureView(view),
            }
        }
        let layer = |k: usize| match &self.shadow_maps {
            Some(maps) if shadows => &maps.layers[k],
            _ => &self.empty_shadow,
        };
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("slab bind group"),
            layout: &self.bind_group_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.uniform.as_entire_binding(),
                },
                texture(1, &self.albedo.view),
                texture(2, &self.thickness.view),
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
                texture(4, &self.background.view),
                texture(5, &self.table.cells_view),
                texture(6, &self.table.warp_view),
                texture(8, &self.diffuse.view),
                texture(9, layer(0)),
                texture(10, layer(1)),
                wgpu::BindGroupEntry {
                    binding: 7,
                    resource: self.table.axes.as_entire_binding(),
                },
            ],
        })
    }

    /// A table texture of `width × height` texels fits the device, or the typed error.
    fn check_table_size(&self, width: usize, height: usize) -> Result<(), RenderError> {
        let max = self.device.limits().max_texture_dimension_2d;
        if width > max as usize || height > max as usize {
            return Err(RenderError::TableTooLarge {
                width: width.min(u32::MAX as usize) as u32,
                height: height.min(u32::MAX as usize) as u32,
                max,
            });
        }
        Ok(())
    }

    /// Uploads the all-orders table unless it is the one already on the GPU.
    pub(crate) fn update_table(&mut self, table: &Arc<AllOrdersTable>) -> Result<(), RenderError> {
        if is_uploaded(self.table.source.as_ref(), table) {
            return Ok(());
        }
        let spec = table.spec();
        let (taus, albedos, cosines) = (spec.tau_count, spec.albedo_count, spec.cosine_count);
        let cells = cosines - 1;
        let (width, height) = (albedos * cells, 2 * taus * cells);
        self.check_table_size(width, height)?;
        // Texel (a·C + j, (face·T + t)·C + k) = ln f at (μ0, μ) nodes (k, j), (k, j+1), (k+1, j),
        // (k+1, j+1); the stored layout is [face][tau][albedo][mu0][mu].
        let values = table.log_values();
        let mut texels = vec![0.0f32; 4 * width * height];
        for face in [TableFace::Reflected, TableFace::Transmitted] {
            let face = face as usize;
            for t in 0..taus {
                for a in 0..albedos {
                    let block = ((face * taus + t) * albedos + a) * cosines * cosines;
                    let value = |k: usize, j: usize| values[block + k * cosines + j];
                    for k in 0..cells {
                        for j in 0..cells {
                            let (x, y) = (a * cells + j, (face * taus + t) * cells + k);
                            let texel = 4 * (y * width + x);
                            texels[texel..texel + 4].copy_from_slice(&[
                                value(k, j),
                                value(k, j + 1),
                                value(k + 1, j),
                                value(k + 1, j + 1),
                            ]);
                        }
                    }
                }
            }
        }
        let (warp, axes) = table_axes(
            spec,
            table.albedo_warp_strengths(),
            table.tau_coordinate_range(),
        );
        self.table = Self::upload_table_textures(
            &self.device,
            &self.queue,
            (width as u32, height as u32, &texels),
            ((taus - 1) as u32, &warp),
            axes,
            Some(Arc::clone(table)),
            Some(spec),
        );
        Ok(())
    }

    /// Uploads the axes of the diffuse table's grid (with a 1×1 stand-in for the all-orders cells)
    /// unless that grid's axes are already on the GPU.
    fn update_axes(&mut self, diffuse: &DiffuseTable) -> Result<(), RenderError> {
        let spec = diffuse.spec();
        if self.table.spec == Some(spec) {
            return Ok(());
        }
        let (warp, axes) = table_axes(
            spec,
            diffuse.albedo_warp_strengths(),
            diffuse.tau_coordinate_range(),
        );
        self.table = Self::upload_table_textures(
            &self.device,
            &self.queue,
            (1, 1, &[0.0; 4]),
            ((spec.tau_count - 1) as u32, &warp),
            axes,
            None,
            Some(spec),
        );
        Ok(())
    }

    /// Uploads the diffuse table unless it is the one already on the GPU. Texel (a·C + j, t) holds
    /// (ln(R_d/Λ) at μ nodes j and j + 1, ln(T_d/Λ) at the same nodes) of τ1 node t, albedo node a; the
    /// stored layout is [face][tau][albedo][mu].
    fn update_diffuse(&mut self, table: &Arc<DiffuseTable>) -> Result<(), RenderError> {
        if is_uploaded(self.diffuse.source.as_ref(), table) {
            return Ok(());
        }
        let spec = table.spec();
        let (taus, albedos, cosines) = (spec.tau_count, spec.albedo_count, spec.cosine_count);
        let cells = cosines - 1;
        let (width, height) = (albedos * cells, taus);
        self.check_table_size(width, height)?;
        let values = table.log_values();
        let value = |face: usize, t: usize, a: usize, j: usize| {
            values[((face * taus + t) * albedos + a) * cosines + j]
        };
        let mut texels = vec![0.0f32; 4 * width * height];
        for t in 0..taus {
            for a in 0..albedos {
                for j in 0..cells {
                    let texel = 4 * (t * width + a * cells + j);
                    texels[texel..texel + 4].copy_from_slice(&[
                        value(0, t, a, j),
                        value(0, t, a, j + 1),
                        value(1, t, a, j),
                        value(1, t, a, j + 1),
                    ]);
                }
            }
        }
        self.diffuse = Self::upload_diffuse_texture(
            &self.device,
            &self.queue,
            (width as u32, height as u32, &texels),
            Some(Arc::clone(table)),
        );
        Ok(())
    }

    fn upload_diffuse_texture(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (width, height, texels): (u32, u32, &[f32]),
        source: Option<Arc<DiffuseTable>>,
    ) -> GpuDiffuse {
        let (texture, view) = float_texture(device, queue, "diffuse table", width, height, texels);
        GpuDiffuse {
            _cells: texture,
            view,
            source,
        }
    }

    fn upload_table_textures(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (width, height, cells): (u32, u32, &[f32]),
        (warp_width, warp): (u32, &[f32]),
        axes: AllOrdersAxes,
        source: Option<Arc<AllOrdersTable>>,
        spec: Option<TableSpec>,
    ) -> GpuTable {
        let (cells_texture, cells_view) =
            float_texture(device, queue, "all-orders table", width, height, cells);
        let (warp_texture, warp_view) =
            float_texture(device, queue, "all-orders warp", warp_width, 1, warp);
        let axes_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("all-orders axes"),
            size: std::mem::size_of::<AllOrdersAxes>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        queue.write_buffer(&axes_buffer, 0, bytemuck::bytes_of(&axes));
        GpuTable {
            _cells: cells_texture,
            cells_view,
            _warp: warp_texture,
            warp_view,
            axes: axes_buffer,
            source,
            spec,
        }
    }

    fn upload_texture(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        source: &Texture2d,
        format: wgpu::TextureFormat,
    ) -> GpuTexture {
        let size = wgpu::Extent3d {
            width: source.width(),
            height: source.height(),
            depth_or_array_layers: 1,
        };
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("slab texture"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let (bytes, bytes_per_texel): (Vec<u8>, u32) = match format {
            wgpu::TextureFormat::Rgba16Float => (
                source
                    .texels()
                    .iter()
                    .flat_map(|texel| texel.map(f32_to_f16_bits))
                    .flat_map(u16::to_le_bytes)
                    .collect(),
                8,
            ),
            _ => (bytemuck::cast_slice(source.texels()).to_vec(), 16),
        };
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(source.width() * bytes_per_texel),
                rows_per_image: Some(source.height()),
            },
            size,
        );
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        GpuTexture {
            _texture: texture,
            view,
            source: Some(source.clone()),
        }
    }

    fn upload_mesh(
        &mut self,
        mesh: &SlabMesh,
        opaque: &[OpaqueMesh],
        camera: &Camera,
        shading: &ShadingParams,
        path: EvaluationPath,
    ) -> Result<(), RenderError> {
        self.vertex_scratch.clear();
        self.vertex_scratch
            .extend((0..mesh.positions.len()).map(|i| Vertex {
                position: mesh.positions[i],
                normal: mesh.normals[i],
                uv: mesh.uvs[i],
            }));
        let vertices = std::mem::take(&mut self.vertex_scratch);
        Self::write_buffer(
            &self.device,
            &self.queue,
            &mut self.vertex_buffer,
            bytemuck::cast_slice(&vertices),
            // Storage: the per-vertex all-orders pass reads it.
            wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE,
        );
        self.vertex_scratch = vertices;
        sort_back_to_front(mesh, camera.eye, &mut self.sorted_indices);
        let indices = std::mem::take(&mut self.sorted_indices);
        Self::write_buffer(
            &self.device,
            &self.queue,
            &mut self.index_buffer,
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        );
        self.sorted_indices = indices;
        if path == EvaluationPath::Cpu {
            let values = per_vertex_slab_values(mesh, opaque, camera.eye, shading)?;
            Self::write_buffer(
                &self.device,
                &self.queue,
                &mut self.cpu_buffer,
                bytemuck::cast_slice(&values),
                wgpu::BufferUsages::VERTEX,
            );
        }
        Ok(())
    }

    fn write_buffer(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        slot: &mut Option<(wgpu::Buffer, usize)>,
        bytes: &[u8],
        usage: wgpu::BufferUsages,
    ) {
        let fits = matches!(slot, Some((_, capacity)) if *capacity == bytes.len());
        if !fits {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("mesh data"),
                size: bytes.len() as u64,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            *slot = Some((buffer, bytes.len()));
        }
        if let Some((buffer, _)) = slot {
            queue.write_buffer(buffer, 0, bytes);
        }
    }

    fn module(&mut self, dual: bool) -> Result<wgpu::ShaderModule, RenderError> {
        if let Some(module) = self.modules.get(&dual) {
            return Ok(module.clone());
        }
        let module = shader_module(&self.device, dual)?;
        self.modules.insert(dual, module.clone());
        Ok(module)
    }

    fn pipeline(&mut self, key: PipelineKey) -> Result<(), RenderError> {
        if self.pipelines.contains_key(&key) {
            return Ok(());
        }
        let PipelineKey {
            path,
            dual,
            multiple_at_vertex,
            ..
        } = key;
        let module = self.module(dual)?;
        let (vertex_entry, fragment_entry) = if multiple_at_vertex {
            ("vs_multiple_at_vertex", "fs_multiple_at_vertex")
        } else {
            path.entry_points()
        };
        let mesh_attributes =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2];
        let cpu_attributes = wgpu::vertex_attr_array![3 => Float32x3, 4 => Float32x3];
        let mut buffers = vec![Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<Vertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &mesh_attributes,
        })];
        // Buffer 1: the CPU path's per-vertex values, or the multiple part per vertex (both 2 × vec3).
        if path == EvaluationPath::Cpu || multiple_at_vertex {
            buffers.push(Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<VertexSlab>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &cpu_attributes,
            }));
        }
        // Eq. (9): L_dst·α_src + L_src. The alpha channel keeps the product of the α drawn over the
        // background (which writes alpha 1).
        let (colour_factor, alpha_factor) = if dual {
            (wgpu::BlendFactor::Src1, wgpu::BlendFactor::Src1Alpha)
        } else {
            (wgpu::BlendFactor::SrcAlpha, wgpu::BlendFactor::SrcAlpha)
        };
        let blend = wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: colour_factor,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: alpha_factor,
                operation: wgpu::BlendOperation::Add,
            },
        };
        let constants = key.override_constants();
        let pipeline = validated(&self.device, &format!("{} pipeline", path.name()), || {
            self.device
                .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(path.name()),
                    layout: Some(&self.pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(vertex_entry),
                        compilation_options: wgpu::PipelineCompilationOptions {
                            constants: &constants,
                            ..Default::default()
                        },
                        buffers: &buffers,
                    },
                    // Both faces: the slab is seen from either side.
                    primitive: wgpu::PrimitiveState {
                        cull_mode: None,
                        ..Default::default()
                    },
                    // The cloth is hidden by opaque geometry in front of it and hides nothing itself.
                    depth_stencil: depth_state(self.options.depth_format, false),
                    multisample: wgpu::MultisampleState {
                        count: self.options.samples,
                        ..Default::default()
                    },
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(fragment_entry),
                        compilation_options: wgpu::PipelineCompilationOptions {
                            constants: &constants,
                            ..Default::default()
                        },
                        targets: &[Some(wgpu::ColorTargetState {
                            format: self.options.target_format,
                            blend: Some(blend),
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
        })?;
        self.pipelines.insert(key, pipeline);
        Ok(())
    }

    /// Uploads the opaque meshes as one vertex and one index buffer; returns the index count.
    fn upload_opaque(&mut self, meshes: &[OpaqueMesh]) -> u32 {
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        for mesh in meshes {
            let base = vertices.len() as u32;
            vertices.extend(mesh.positions.iter().zip(&mesh.normals).map(
                |(&position, &normal)| OpaqueVertex {
                    position,
                    normal,
                    albedo: mesh.albedo,
                },
            ));
            indices.extend(mesh.indices.iter().map(|i| base + i));
        }
        if indices.is_empty() {
            return 0;
        }
        Self::write_buffer(
            &self.device,
            &self.queue,
            &mut self.opaque_vertex_buffer,
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX,
        );
        Self::write_buffer(
            &self.device,
            &self.queue,
            &mut self.opaque_index_buffer,
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        );
        indices.len() as u32
    }
}

impl std::fmt::Debug for SlabRenderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SlabRenderer")
            .field("options", &self.options)
            .field("dual_source", &self.dual_source)
            .finish_non_exhaustive()
    }
}

/// The thin-slab shader module: the output declaration (single or dual-source), the lit-side rule, the
/// model and the per-vertex all-orders pass.
fn shader_module(device: &wgpu::Device, dual: bool) -> Result<wgpu::ShaderModule, RenderError> {
    let source = format!(
        "{}\n{}\n{}\n{}\n{}",
        if dual { OUTPUT_DUAL } else { OUTPUT_SINGLE },
        LIT_SIDE,
        SHADER_BODY,
        SHADOW,
        MULTIPLE_AT_VERTEX
    );
    validated(device, "shader", || {
        device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(if dual {
                "thin_slab (dual source)"
            } else {
                "thin_slab"
            }),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        })
    })
}

/// A shadow-map layer texture (`Rgba32Uint`, square): a render target of the peel passes, read by the
/// lookup.
fn shadow_layer_texture(device: &wgpu::Device, resolution: u32, label: &str) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: resolution,
            height: resolution,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Uint,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    })
}

/// Depth testing for a pass with a depth attachment: less-than, writing depth if `write`.
fn depth_state(
    format: Option<wgpu::TextureFormat>,
    write: bool,
) -> Option<wgpu::DepthStencilState> {
    format.map(|format| wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(write),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    })
}

/// The pipelines that do not depend on the material: background, opaque meshes, light marker.
struct FixedPipelines {
    background: wgpu::RenderPipeline,
    opaque: wgpu::RenderPipeline,
    marker: wgpu::RenderPipeline,
}

impl FixedPipelines {
    fn new(
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        module: &wgpu::ShaderModule,
        options: SlabRendererOptions,
    ) -> Result<FixedPipelines, RenderError> {
        let opaque_attributes =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3];
        let opaque_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<OpaqueVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &opaque_attributes,
        })];
        // (label, vertex and fragment entry points, vertex buffers, topology, writes depth)
        let make = |label: &str,
                    (vertex, fragment): (&str, &str),
                    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
                    topology: wgpu::PrimitiveTopology,
                    depth: Option<wgpu::DepthStencilState>| {
            validated(device, &format!("{label} pipeline"), || {
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(layout),
                    vertex: wgpu::VertexState {
                        module,
                        entry_point: Some(vertex),
                        compilation_options: Default::default(),
                        buffers,
                    },
                    primitive: wgpu::PrimitiveState {
                        topology,
                        ..Default::default()
                    },
                    depth_stencil: depth,
                    multisample: wgpu::MultisampleState {
                        count: options.samples,
                        ..Default::default()
                    },
                    fragment: Some(wgpu::FragmentState {
                        module,
                        entry_point: Some(fragment),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format: options.target_format,
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
        };
        let triangles = wgpu::PrimitiveTopology::TriangleList;
        // The background lies behind everything: it passes any depth test and writes none.
        let behind_everything = options.depth_format.map(|format| wgpu::DepthStencilState {
            format,
            depth_write_enabled: Some(false),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        });
        Ok(FixedPipelines {
            background: make(
                "background",
                ("vs_background", "fs_background"),
                &[],
                triangles,
                behind_everything,
            )?,
            opaque: make(
                "opaque",
                ("vs_opaque", "fs_opaque"),
                &opaque_buffers,
                triangles,
                depth_state(options.depth_format, true),
            )?,
            marker: make(
                "light marker",
                ("vs_marker", "fs_marker"),
                &[],
                wgpu::PrimitiveTopology::TriangleStrip,
                depth_state(options.depth_format, true),
            )?,
        })
    }
}

/// Whether `table` is the one `uploaded` to the GPU: the same `Arc`, or an equal table.
fn is_uploaded<T: PartialEq>(uploaded: Option<&Arc<T>>, table: &Arc<T>) -> bool {
    uploaded.is_some_and(|uploaded| Arc::ptr_eq(uploaded, table) || uploaded == table)
}

/// An `Rgba32Float` texture of `width × height` texels holding `data` (four floats a texel), and its view.
fn float_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    label: &'static str,
    width: u32,
    height: u32,
    data: &[f32],
) -> (wgpu::Texture, wgpu::TextureView) {
    let size = wgpu::Extent3d {
        width,
        height,
        depth_or_array_layers: 1,
    };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        bytemuck::cast_slice(data),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(width * 16),
            rows_per_image: Some(height),
        },
        size,
    );
    let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    (texture, view)
}

/// The albedo warps (texel t: (e^β − 1, 1/β) of τ1 nodes t and t + 1, one load per τ1 cell) and the
/// axes uniform of a table grid, shared by the all-orders and the diffuse table.
fn table_axes(
    spec: TableSpec,
    warp_strengths: &[f64],
    (c0, c1): (f64, f64),
) -> (Vec<f32>, AllOrdersAxes) {
    let warps: Vec<[f32; 2]> = warp_strengths
        .iter()
        .map(|&beta| [beta.exp_m1() as f32, (1.0 / beta) as f32])
        .collect();
    let warp: Vec<f32> = warps
        .windows(2)
        .flat_map(|pair| [pair[0][0], pair[0][1], pair[1][0], pair[1][1]])
        .collect();
    let (taus, albedos, cells) = (spec.tau_count, spec.albedo_count, spec.cosine_count - 1);
    let axes = AllOrdersAxes {
        tau: [
            c0 as f32,
            (1.0 / (c1 - c0)) as f32,
            (taus - 1) as f32,
            (albedos - 1) as f32,
        ],
        cosine: [cells as f32, (taus * cells) as f32, 0.0, 0.0],
    };
    (warp, axes)
}
