//! Headless wgpu renderer of the thin-slab model (Frisvad, Christensen & Falster 2005, §4): the three
//! evaluation paths the paper measures (per fragment, per vertex in the vertex shader, per vertex on the
//! CPU) and the traditional baseline (diffuse BRDF, constant α = 0.2), blended as eq. (9)
//! (`L_dst·α_src + L_src`) over a background, triangles sorted back to front every frame, into a linear
//! float target that is read back. Each thin-slab path evaluates either scattering model of
//! [`crate::all_orders::Scattering`].
//!
//! The all-orders table on the GPU: one `Rgba32Float` 2-D texture in which texel
//! `(a·C + j, (face·T + t)·C + k)` (C = cosine cells, T = τ1 nodes) holds the four stored values
//! `ln f` at `(μ0, μ)` nodes `(k, j), (k, j+1), (k+1, j), (k+1, j+1)` of τ1 node `t` and albedo node `a`,
//! so one `textureLoad` returns a whole (μ0, μ) cell and a quadrilinear lookup takes four loads; a second
//! texture holds per τ1 cell the albedo warps `(e^β − 1, 1/β)` of its two nodes, and a uniform the axes. Interpolation
//! weights are computed in the shader exactly as the CPU sampler does (multilinear in `ln f`), so the
//! paths agree to `f32` rounding; rgba32float is not filterable on every adapter, and hardware filtering
//! would quantise weights (8 bits on lavapipe).
//!
//! With [`AllOrdersSampling::PerVertex`] the per-fragment path instead runs a compute pass
//! (`shaders/multiple_at_vertex.wgsl`) that looks the table up once per mesh vertex for both faces and
//! feeds the result to the draw as vertex attributes (`vs_multiple_at_vertex`/`fs_multiple_at_vertex`).
//!
//! Adapter choice: `WGPU_BACKEND` if set (every name in it must be a backend, else
//! [`RenderError::UnknownBackend`]), else Vulkan (Mesa lavapipe on a machine without a GPU) and then
//! GL (llvmpipe over EGL); the first adapter of the preferred backend wins, hardware before software.

mod cpu;
mod scene;

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use bytemuck::{Pod, Zeroable};
use thiserror::Error;

pub use cpu::{
    COSINE_FLOOR, VertexSlab, albedo_at, f16_bits_to_f32, f32_to_f16_bits, lit_side_cosines,
    optical_thickness_at, per_vertex_slab_values, quantize_to_half, sample_bilinear,
    sample_bilinear_red, slab_values_at, sort_back_to_front,
};
pub use scene::{
    AllOrdersSampling, Background, Camera, CameraError, LinearImage, MeshError, ShadingError,
    ShadingParams, SlabMesh, Texture2d, linear_to_srgb, linear_to_srgb8, save_image_file,
    srgb8_to_linear, write_file_atomically,
};

use crate::all_orders::{AllOrdersTable, Scattering, TableFace};
use crate::model::{IrradianceConvention, SlabParameterError};
use crate::sky::DiffuseTable;
use sheer_transport::TableSpec;

const SHADER_BODY: &str = include_str!("../../../../shaders/thin_slab.wgsl");
const LIT_SIDE: &str = include_str!("../../../../shaders/lit_side.wgsl");
const OUTPUT_SINGLE: &str = include_str!("../../../../shaders/slab_output_single.wgsl");
const OUTPUT_DUAL: &str = include_str!("../../../../shaders/slab_output_dual.wgsl");
const MODEL_CHECK: &str = include_str!("../../../../shaders/slab_model_check.wgsl");
const MULTIPLE_AT_VERTEX: &str = include_str!("../../../../shaders/multiple_at_vertex.wgsl");

/// Runs `create` inside a validation error scope, so that a shader or pipeline wgpu rejects becomes
/// `RenderError::Gpu("{what}: {error}")` instead of an uncaptured error.
fn validated<T>(
    device: &wgpu::Device,
    what: &str,
    create: impl FnOnce() -> T,
) -> Result<T, RenderError> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let created = create();
    match pollster::block_on(scope.pop()) {
        Some(error) => Err(RenderError::Gpu(format!("{what}: {error}"))),
        None => Ok(created),
    }
}

/// Where the model is evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EvaluationPath {
    /// Eqs. (4)–(9) in the fragment shader (the paper's 300 fps path).
    PerFragment,
    /// In the vertex shader, interpolated (480 fps in the paper).
    PerVertex,
    /// Per vertex on the CPU with rayon, uploaded every frame (190 fps in the paper).
    Cpu,
    /// Traditional: diffuse BRDF, constant α, back-lit side black.
    Baseline,
}

impl EvaluationPath {
    /// All paths, baseline last.
    pub const ALL: [Self; 4] = [
        Self::PerFragment,
        Self::PerVertex,
        Self::Cpu,
        Self::Baseline,
    ];

    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            Self::PerFragment => "per-fragment",
            Self::PerVertex => "per-vertex",
            Self::Cpu => "cpu",
            Self::Baseline => "baseline",
        }
    }

    fn entry_points(self) -> (&'static str, &'static str) {
        match self {
            Self::PerFragment => ("vs_per_fragment", "fs_per_fragment"),
            Self::PerVertex => ("vs_per_vertex", "fs_interpolated"),
            Self::Cpu => ("vs_cpu", "fs_interpolated"),
            Self::Baseline => ("vs_per_fragment", "fs_baseline"),
        }
    }
}

/// Why rendering failed.
#[derive(Debug, Error)]
pub enum RenderError {
    /// No GPU or software adapter (Vulkan or GL) could be found.
    #[error(
        "no graphics adapter found for backends {backends}: install Mesa's software drivers \
         (lavapipe: mesa-vulkan-drivers; llvmpipe: libegl-mesa0) or a GPU driver, or choose backends \
         with WGPU_BACKEND=vulkan|gl"
    )]
    NoAdapter {
        /// The backends that were searched.
        backends: String,
    },
    /// `WGPU_BACKEND` holds a name that is no graphics backend, or none at all (`name` is then empty);
    /// wgpu itself would skip the name with a log line and, if nothing is left, search no backend.
    #[error(
        "WGPU_BACKEND = {value:?}: {name:?} is no graphics backend (this build has vulkan and gl, \
         comma-separated)"
    )]
    UnknownBackend {
        /// The variable's whole value.
        value: String,
        /// The first name in it that is not a backend.
        name: String,
    },
    /// The adapter refused to create a device.
    #[error("could not create a device on {adapter}: {message}")]
    RequestDevice {
        /// The adapter's name and backend.
        adapter: String,
        /// wgpu's reason.
        message: String,
    },
    /// A wgpu validation or out-of-memory error.
    #[error("GPU error: {0}")]
    Gpu(String),
    /// Multisampling takes 1 (none) or 4 samples per pixel.
    #[error("{0} samples per pixel: multisampling takes 1 (off) or 4")]
    Samples(u32),
    /// The adapter cannot multisample a float render target.
    #[error("the adapter {adapter} cannot render a float target with {samples} samples per pixel")]
    MultisampleUnsupported {
        /// The adapter.
        adapter: String,
        /// Samples asked for.
        samples: u32,
    },
    /// Width or height is zero or beyond the device's limit.
    #[error("render size {width}x{height} is not supported (1..={max} per side)")]
    Size {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// The device's maximum 2-D texture dimension.
        max: u32,
    },
    /// Bad mesh.
    #[error("invalid mesh: {0}")]
    Mesh(#[from] MeshError),
    /// A camera that defines no view.
    #[error("invalid camera: {0}")]
    Camera(#[from] CameraError),
    /// A pixel read back is NaN, infinite, or saturated at the largest finite value of the target's
    /// float format ([`TargetFormat::largest_finite`]): the radiance overflowed the target (a light of
    /// enormous flux, or one almost touching the cloth). GPUs differ in how they store an overflow:
    /// Mesa's lavapipe writes infinity, NVIDIA's Vulkan driver (H200, 580.159) writes `f32::MAX`; both
    /// are reported rather than handed on as an image.
    #[error(
        "pixel ({x}, {y}) came out {value} (the radiance overflows the {format:?} target): lower \
         the light's flux or move it away from the cloth"
    )]
    OverflowedPixel {
        /// Column.
        x: u32,
        /// Row from the top.
        y: u32,
        /// The first overflowed channel's value: NaN, ±infinity or ±[`TargetFormat::largest_finite`].
        value: f32,
        /// The render target's format.
        format: TargetFormat,
    },
    /// Bad shading parameters.
    #[error("invalid shading parameters: {0}")]
    Shading(#[from] ShadingError),
    /// A background image must have the render target's size.
    #[error("background image is {got_width}x{got_height}, the target is {width}x{height}")]
    BackgroundSize {
        /// Image width.
        got_width: u32,
        /// Image height.
        got_height: u32,
        /// Target width.
        width: u32,
        /// Target height.
        height: u32,
    },
    /// Per-channel τ1 needs per-channel α, i.e. dual-source blending, which this adapter lacks.
    #[error(
        "optical thickness differs between channels but the adapter has no dual-source blending"
    )]
    PerChannelAlphaUnsupported,
    /// A model parameter the CPU path refused (only for parameters that validation lets through).
    #[error("model: {0}")]
    Model(#[from] SlabParameterError),
    /// A texture of the shading parameters is larger than this device's textures may be.
    #[error("the {texture} texture is {width}x{height} texels; the device allows {max} per side")]
    TextureTooLarge {
        /// Which texture: `albedo` or `thickness`.
        texture: &'static str,
        /// Texture width.
        width: u32,
        /// Texture height.
        height: u32,
        /// The device's maximum 2-D texture dimension.
        max: u32,
    },
    /// The all-orders table does not fit in one texture of this device.
    #[error(
        "the all-orders table needs a {width}x{height} texture; the device allows {max} per side"
    )]
    TableTooLarge {
        /// Texture width.
        width: u32,
        /// Texture height.
        height: u32,
        /// The device's maximum 2-D texture dimension.
        max: u32,
    },
}

/// The linear render target's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TargetFormat {
    /// 32-bit float per channel (adapter supports blending it).
    Rgba32Float,
    /// 16-bit float per channel (relative precision 2^-11).
    Rgba16Float,
}

impl TargetFormat {
    /// The largest finite value a channel of this format holds (IEEE 754 binary32: `f32::MAX`;
    /// binary16: 65 504). A channel at this value has no headroom left: a GPU that saturates an
    /// overflowing result instead of writing infinity leaves exactly this value behind.
    pub fn largest_finite(self) -> f32 {
        match self {
            TargetFormat::Rgba32Float => f32::MAX,
            TargetFormat::Rgba16Float => 65_504.0,
        }
    }
}

/// Appends the texels of `bytes`, little-endian RGBA f32 as the GPU wrote them: on a little-endian
/// host whose bytes are 4-byte aligned (wgpu aligns a mapping to 8, and rows to 256) a cast of the
/// whole row, else texel by texel.
fn extend_with_f32_texels(pixels: &mut Vec<[f32; 4]>, bytes: &[u8]) {
    match bytemuck::try_cast_slice::<u8, [f32; 4]>(bytes) {
        Ok(texels) if cfg!(target_endian = "little") => pixels.extend_from_slice(texels),
        _ => pixels.extend(bytes.chunks_exact(16).map(|texel| {
            std::array::from_fn(|channel| {
                let at = 4 * channel;
                f32::from_le_bytes([texel[at], texel[at + 1], texel[at + 2], texel[at + 3]])
            })
        })),
    }
}

/// Appends the texels of `bytes`, little-endian RGBA IEEE half floats, as f32.
fn extend_with_f16_texels(pixels: &mut Vec<[f32; 4]>, bytes: &[u8]) {
    pixels.extend(bytes.chunks_exact(8).map(|texel| {
        std::array::from_fn(|channel| {
            let at = 2 * channel;
            f16_bits_to_f32(u16::from_le_bytes([texel[at], texel[at + 1]]))
        })
    }));
}

/// The first channel of `pixels` that overflowed a target of `format` — NaN, infinite, or at the
/// format's largest finite magnitude — as (pixel index, value).
fn first_overflowed_channel(pixels: &[[f32; 4]], format: TargetFormat) -> Option<(usize, f32)> {
    let largest = format.largest_finite();
    pixels.iter().enumerate().find_map(|(index, pixel)| {
        pixel
            .iter()
            .find(|channel| !channel.is_finite() || channel.abs() >= largest)
            .map(|&value| (index, value))
    })
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
}

impl PipelineKey {
    /// The shader's override constants for this variant. They specialise the shader at pipeline
    /// creation: per-channel τ1 evaluates the model three times, grey τ1 once; the thickness texture is
    /// sampled only when there is one (a software rasteriser would otherwise pay for the masked-off
    /// sample); the all-orders lookup exists only in all-orders pipelines, so single scattering runs
    /// exactly the code it ran before.
    fn override_constants(self) -> [(&'static str, f64); 4] {
        let flag = |on: bool| if on { 1.0 } else { 0.0 };
        [
            ("per_channel_thickness", flag(self.dual)),
            ("has_thickness_texture", flag(self.thickness)),
            ("all_orders", flag(self.all_orders)),
            ("sky_light", flag(self.sky)),
        ]
    }
}

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
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct Vertex {
    position: [f32; 3],
    normal: [f32; 3],
    uv: [f32; 2],
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
struct AllOrdersAxes {
    /// x: `c0 = ln τmin + τmin`; y: `1/(c1 − c0)`; z: τ1 cells; w: albedo cells.
    tau: [f32; 4],
    /// x: cosine cells C; y: texture rows per face (τ1 nodes × C).
    cosine: [f32; 4],
}

/// The all-orders table on the GPU (see the module docs), with the table it was made from.
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

/// A renderer without a window: renders into a linear float texture and reads it back.
pub struct HeadlessRenderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter_description: String,
    width: u32,
    height: u32,
    target_format: TargetFormat,
    dual_source: bool,
    target: wgpu::Texture,
    target_view: wgpu::TextureView,
    /// Samples per pixel (1 or 4).
    samples: u32,
    /// With more than one sample: the multisampled attachment, resolved into `target`.
    multisampled: Option<(wgpu::Texture, wgpu::TextureView)>,
    readback: wgpu::Buffer,
    padded_row_bytes: u32,
    uniform: wgpu::Buffer,
    sampler: wgpu::Sampler,
    bind_group_layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    /// Group 1 of the renderer's compute passes: one storage buffer in (binding 0), one out (binding 1)
    /// — the per-vertex all-orders pass (mesh vertices in, multiple part out) and the model checks.
    compute_io_layout: wgpu::BindGroupLayout,
    /// Group 0 (the frame's bindings) and group 1 [`compute_io_layout`](Self::compute_io_layout).
    compute_io_pipeline_layout: wgpu::PipelineLayout,
    modules: HashMap<bool, wgpu::ShaderModule>,
    pipelines: HashMap<PipelineKey, wgpu::RenderPipeline>,
    /// The per-vertex all-orders pass per (per-channel τ1, thickness texture).
    multiple_pipelines: HashMap<(bool, bool), wgpu::ComputePipeline>,
    background_pipeline: Option<wgpu::RenderPipeline>,
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
    sorted_indices: Vec<u32>,
    vertex_scratch: Vec<Vertex>,
    uncaptured: Arc<Mutex<Vec<String>>>,
}

fn target_wgpu_format(format: TargetFormat) -> wgpu::TextureFormat {
    match format {
        TargetFormat::Rgba32Float => wgpu::TextureFormat::Rgba32Float,
        TargetFormat::Rgba16Float => wgpu::TextureFormat::Rgba16Float,
    }
}

fn backend_rank(backend: wgpu::Backend) -> u8 {
    match backend {
        wgpu::Backend::Vulkan => 0,
        wgpu::Backend::Gl => 1,
        _ => 2,
    }
}

fn device_rank(device_type: wgpu::DeviceType) -> u8 {
    match device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    }
}

/// The backends to search: those `WGPU_BACKEND` names, else Vulkan and GL.
fn backends_from_env() -> Result<wgpu::Backends, RenderError> {
    match std::env::var_os("WGPU_BACKEND") {
        None => Ok(wgpu::Backends::VULKAN | wgpu::Backends::GL),
        Some(value) => backends_from_list(&value.to_string_lossy()),
    }
}

/// The backends a comma-separated list names, as wgpu reads it (case-insensitive, spaces and empty
/// names skipped), except that every name must be a backend and at least one must be given.
fn backends_from_list(value: &str) -> Result<wgpu::Backends, RenderError> {
    let unknown = |name: &str| RenderError::UnknownBackend {
        value: value.to_owned(),
        name: name.to_owned(),
    };
    let mut backends = wgpu::Backends::empty();
    for name in value.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        let backend = wgpu::Backends::from_comma_list(name);
        if backend.is_empty() {
            return Err(unknown(name));
        }
        backends |= backend;
    }
    if backends.is_empty() {
        return Err(unknown(""));
    }
    Ok(backends)
}

impl HeadlessRenderer {
    /// Finds an adapter (see the module docs), creates a device and a `width × height` linear target.
    pub fn new(width: u32, height: u32) -> Result<Self, RenderError> {
        Self::with_samples(width, height, 1)
    }

    /// A renderer of `width × height` pixels that takes `samples` samples per pixel (1, or 4 for
    /// anti-aliased edges): each sample is blended by eq. (9) on its own and the pixel is their mean, so a
    /// pixel inside one surface is exactly the one-sample value and a pixel on an edge a blend.
    pub fn with_samples(width: u32, height: u32, samples: u32) -> Result<Self, RenderError> {
        if !matches!(samples, 1 | 4) {
            return Err(RenderError::Samples(samples));
        }
        let backends = backends_from_env()?;
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle();
        descriptor.backends = backends;
        descriptor.flags = wgpu::InstanceFlags::from_build_config().with_env();
        let instance = wgpu::Instance::new(descriptor);
        let mut adapters = pollster::block_on(instance.enumerate_adapters(backends));
        adapters.sort_by_key(|adapter| {
            let info = adapter.get_info();
            (backend_rank(info.backend), device_rank(info.device_type))
        });
        let Some(adapter) = adapters.into_iter().next() else {
            return Err(RenderError::NoAdapter {
                backends: format!("{backends:?}"),
            });
        };
        let info = adapter.get_info();
        let adapter_description =
            format!("{} ({:?}, {})", info.name, info.backend, info.driver_info);

        let available = adapter.features();
        let mut required_features = wgpu::Features::empty();
        // A format multisamples and resolves if the adapter says so (beyond WebGPU's guarantees only
        // with adapter-specific format features).
        let multisamples = |format: wgpu::TextureFormat| {
            samples == 1
                || (available.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES)
                    && {
                        let flags = adapter.get_texture_format_features(format).flags;
                        flags.sample_count_supported(samples)
                            && flags.contains(wgpu::TextureFormatFeatureFlags::MULTISAMPLE_RESOLVE)
                    })
        };
        let target_format = if available.contains(wgpu::Features::FLOAT32_BLENDABLE)
            && multisamples(wgpu::TextureFormat::Rgba32Float)
        {
            required_features |= wgpu::Features::FLOAT32_BLENDABLE;
            TargetFormat::Rgba32Float
        } else if multisamples(wgpu::TextureFormat::Rgba16Float) {
            TargetFormat::Rgba16Float
        } else {
            return Err(RenderError::MultisampleUnsupported {
                adapter: adapter_description,
                samples,
            });
        };
        if samples > 1 {
            required_features |= wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
        }
        let dual_source = available.contains(wgpu::Features::DUAL_SOURCE_BLENDING);
        if dual_source {
            required_features |= wgpu::Features::DUAL_SOURCE_BLENDING;
        }
        let limits = adapter.limits();
        let max = limits.max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::Size { width, height, max });
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("sheer-slab"),
            required_features,
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|error| RenderError::RequestDevice {
            adapter: adapter_description.clone(),
            message: error.to_string(),
        })?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&uncaptured);
        device.on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
            if let Ok(mut errors) = sink.lock() {
                errors.push(error.to_string());
            }
        }));

        let target = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("linear radiance target"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: target_wgpu_format(target_format),
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let target_view = target.create_view(&wgpu::TextureViewDescriptor::default());
        // The samples, resolved into `target` at the end of each frame's pass.
        let multisampled = (samples > 1).then(|| {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("multisampled radiance"),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format: target_wgpu_format(target_format),
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            });
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            (texture, view)
        });
        let bytes_per_pixel = match target_format {
            TargetFormat::Rgba32Float => 16,
            TargetFormat::Rgba16Float => 8,
        };
        let padded_row_bytes = (width * bytes_per_pixel)
            .div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: u64::from(padded_row_bytes) * u64::from(height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
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
        let mut renderer = Self {
            device,
            queue,
            adapter_description,
            width,
            height,
            target_format,
            dual_source,
            target,
            target_view,
            samples,
            multisampled,
            readback,
            padded_row_bytes,
            uniform,
            sampler,
            bind_group_layout,
            pipeline_layout,
            compute_io_layout,
            compute_io_pipeline_layout,
            modules: HashMap::new(),
            pipelines: HashMap::new(),
            multiple_pipelines: HashMap::new(),
            background_pipeline: None,
            albedo,
            thickness,
            background,
            table,
            diffuse,
            vertex_buffer: None,
            cpu_buffer: None,
            multiple_buffer: None,
            index_buffer: None,
            sorted_indices: Vec::new(),
            vertex_scratch: Vec::new(),
            uncaptured,
        };
        renderer.background_pipeline = Some(renderer.create_background_pipeline()?);
        Ok(renderer)
    }

    /// Samples per pixel: 1, or 4 with anti-aliased edges.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The adapter in use: name, backend and driver.
    pub fn adapter_description(&self) -> &str {
        &self.adapter_description
    }

    /// The linear target's format.
    pub fn target_format(&self) -> TargetFormat {
        self.target_format
    }

    /// The largest width or height of a texture on this device (the albedo and thickness textures of
    /// [`ShadingParams`] must fit; [`RenderError::TextureTooLarge`] otherwise).
    pub fn max_texture_dimension(&self) -> u32 {
        self.device.limits().max_texture_dimension_2d
    }

    /// Whether per-channel τ1 (dual-source blending) is available.
    pub fn supports_per_channel_optical_thickness(&self) -> bool {
        self.dual_source
    }

    /// Target size (width, height).
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Renders one frame and reads the linear radiance image back.
    pub fn render(
        &mut self,
        mesh: &SlabMesh,
        camera: &Camera,
        shading: &ShadingParams,
        background: &Background,
        path: EvaluationPath,
    ) -> Result<LinearImage, RenderError> {
        self.render_frame(mesh, camera, shading, background, path)?;
        self.read_target()
    }

    /// Renders one frame (sort, per-path evaluation and uploads, background, slab) and waits until the GPU
    /// has finished it, without reading it back (for benchmarks).
    pub fn render_frame(
        &mut self,
        mesh: &SlabMesh,
        camera: &Camera,
        shading: &ShadingParams,
        background: &Background,
        path: EvaluationPath,
    ) -> Result<(), RenderError> {
        self.render_frame_timed(mesh, camera, shading, background, path)
            .map(|_| ())
    }

    /// [`render_frame`](Self::render_frame), returning how long the GPU took: from submitting the
    /// frame's commands until it has finished them. Everything before (sort, per-path evaluation,
    /// staging the uploads, encoding) is CPU work; wgpu copies staged uploads at submit, so the
    /// transfers count as GPU time.
    pub fn render_frame_timed(
        &mut self,
        mesh: &SlabMesh,
        camera: &Camera,
        shading: &ShadingParams,
        background: &Background,
        path: EvaluationPath,
    ) -> Result<std::time::Duration, RenderError> {
        mesh.validate()?;
        camera.validate()?;
        shading.validate()?;
        let dual = !shading.grey_optical_thickness();
        if dual && !self.dual_source {
            return Err(RenderError::PerChannelAlphaUnsupported);
        }
        self.update_textures(shading, background)?;
        match (&shading.scattering, &shading.sky) {
            (Scattering::AllOrders(table), _) => self.update_table(table)?,
            // The sky samples its table on the all-orders table's axes: upload the axes alone.
            (Scattering::Single, Some(sky)) => self.update_axes(&sky.table)?,
            (Scattering::Single, None) => {}
        }
        if let Some(sky) = &shading.sky {
            self.update_diffuse(&sky.table)?;
        }
        let uniform = self.frame_uniform(camera, shading, background);
        self.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        self.upload_mesh(mesh, camera, shading, path)?;
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
        };
        self.pipeline(key)?;
        let bind_group = self.bind_group();
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        if key.multiple_at_vertex {
            self.encode_multiple_at_vertex(&mut encoder, &bind_group, key, mesh.positions.len())?;
        }
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("slab pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: self
                        .multisampled
                        .as_ref()
                        .map_or(&self.target_view, |(_, view)| view),
                    depth_slice: None,
                    resolve_target: self.multisampled.as_ref().map(|_| &self.target_view),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &bind_group, &[]);
            if let Some(background_pipeline) = &self.background_pipeline {
                pass.set_pipeline(background_pipeline);
                pass.draw(0..3, 0..1);
            }
            let pipeline = &self.pipelines[&key];
            pass.set_pipeline(pipeline);
            if let Some((buffer, _)) = &self.vertex_buffer {
                pass.set_vertex_buffer(0, buffer.slice(..));
            }
            if path == EvaluationPath::Cpu
                && let Some((buffer, _)) = &self.cpu_buffer
            {
                pass.set_vertex_buffer(1, buffer.slice(..));
            }
            if key.multiple_at_vertex
                && let Some((buffer, _)) = &self.multiple_buffer
            {
                pass.set_vertex_buffer(1, buffer.slice(..));
            }
            if let Some((buffer, _)) = &self.index_buffer {
                pass.set_index_buffer(buffer.slice(..), wgpu::IndexFormat::Uint32);
            }
            pass.draw_indexed(0..mesh.indices.len() as u32, 0, 0..1);
        }
        let submitted = std::time::Instant::now();
        self.queue.submit([encoder.finish()]);
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|error| RenderError::Gpu(error.to_string()))?;
        let gpu = submitted.elapsed();
        self.take_uncaptured()?;
        Ok(gpu)
    }

    /// Encodes the per-vertex all-orders pass (`cs_multiple_at_vertex`): the table's multiple part for
    /// both faces at each of the mesh's `vertex_count` vertices, into `multiple_buffer`.
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

    /// Reads the last rendered frame back as linear radiance.
    pub fn read_target(&mut self) -> Result<LinearImage, RenderError> {
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.target,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row_bytes),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
        self.queue.submit([encoder.finish()]);
        let (width, height) = (self.width as usize, self.height as usize);
        let (format, row_stride) = (self.target_format, self.padded_row_bytes as usize);
        let pixels = self.map_and_read(&self.readback, |data| {
            let mut pixels = Vec::with_capacity(width * height);
            for row in 0..height {
                let start = row * row_stride;
                match format {
                    TargetFormat::Rgba32Float => {
                        extend_with_f32_texels(&mut pixels, &data[start..start + width * 16]);
                    }
                    TargetFormat::Rgba16Float => {
                        extend_with_f16_texels(&mut pixels, &data[start..start + width * 8]);
                    }
                }
            }
            pixels
        })?;
        if let Some((index, value)) = first_overflowed_channel(&pixels, self.target_format) {
            return Err(RenderError::OverflowedPixel {
                x: index as u32 % self.width,
                y: index as u32 / self.width,
                value,
                format: self.target_format,
            });
        }
        Ok(LinearImage {
            width: self.width,
            height: self.height,
            pixels,
        })
    }

    /// Evaluates the shader's model function (`slab_shapes` in `shaders/thin_slab.wgsl`) on the GPU for
    /// samples `(τ1, μ0, μ)` and returns `(eq. 4, eq. 5, α)` per sample, the radiances per unit
    /// irradiance and without the factor Λ/(4π): for checking the WGSL model against [`crate::model`].
    /// The renderer only calls it with cosines ≥ [`COSINE_FLOOR`].
    pub fn evaluate_shader_model(
        &mut self,
        samples: &[[f32; 3]],
    ) -> Result<Vec<[f32; 3]>, RenderError> {
        let inputs: Vec<[f32; 4]> = samples.iter().map(|&[t, m0, m]| [t, m0, m, 0.0]).collect();
        let outputs = self.run_model_check("cs_model_check", None, &inputs)?;
        Ok(outputs.iter().map(|v| [v[0], v[1], v[2]]).collect())
    }

    /// Evaluates the shader's all-orders lookup (`all_orders_log_value` in `shaders/thin_slab.wgsl`) on
    /// the GPU with `table` uploaded as the renderer uploads it, for samples `(τ1, Λ, μ0, μ)` (τ1 in the
    /// table's range, Λ, μ0, μ in [0, 1]). Returns per sample `(L_m reflected, L_m transmitted,
    /// ln f reflected, ln f transmitted)`: the multiply-scattered radiance per unit irradiance normal to
    /// the beam, `L_m = Λ² μ0 e^{ln f}` (sr⁻¹), and the interpolated logarithm, for checking against the
    /// CPU sampler.
    pub fn evaluate_shader_all_orders(
        &mut self,
        table: &Arc<AllOrdersTable>,
        samples: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, RenderError> {
        self.update_table(table)?;
        let bind_group = self.bind_group();
        self.run_model_check("cs_all_orders_check", Some(&bind_group), samples)
    }

    /// Runs a compute entry point of `shaders/slab_model_check.wgsl` over `inputs` (one `vec4` in, one
    /// out); `frame_bindings` binds the renderer's group 0 (with its explicit layout) when the entry point
    /// reads it.
    fn run_model_check(
        &mut self,
        entry_point: &str,
        frame_bindings: Option<&wgpu::BindGroup>,
        inputs: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, RenderError> {
        if inputs.is_empty() {
            return Ok(Vec::new());
        }
        let source = format!("{OUTPUT_SINGLE}\n{LIT_SIDE}\n{SHADER_BODY}\n{MODEL_CHECK}");
        // With the frame's group 0: the same layout as the per-vertex all-orders pass (group 1 one
        // storage buffer in, one out); without: derived from the entry point.
        let layout = frame_bindings.map(|_| &self.compute_io_pipeline_layout);
        let pipeline = validated(&self.device, "model check shader", || {
            let module = self
                .device
                .create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("slab model check"),
                    source: wgpu::ShaderSource::Wgsl(source.into()),
                });
            self.device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some("slab model check"),
                    layout,
                    module: &module,
                    entry_point: Some(entry_point),
                    compilation_options: Default::default(),
                    cache: None,
                })
        })?;
        let size = std::mem::size_of_val(inputs) as u64;
        let input_buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("model inputs"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.queue
            .write_buffer(&input_buffer, 0, bytemuck::cast_slice(inputs));
        let output_buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("model outputs"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("model readback"),
            size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let check_bindings = [
            wgpu::BindGroupEntry {
                binding: 0,
                resource: input_buffer.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: output_buffer.as_entire_binding(),
            },
        ];
        let derived_layout;
        let check_group_layout = if frame_bindings.is_some() {
            &self.compute_io_layout
        } else {
            derived_layout = pipeline.get_bind_group_layout(1);
            &derived_layout
        };
        let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("model check"),
            layout: check_group_layout,
            entries: &check_bindings,
        });
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("model check"),
            });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("model check"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&pipeline);
            if let Some(frame) = frame_bindings {
                pass.set_bind_group(0, frame, &[]);
            }
            pass.set_bind_group(1, &bind_group, &[]);
            pass.dispatch_workgroups((inputs.len() as u32).div_ceil(64), 1, 1);
        }
        encoder.copy_buffer_to_buffer(&output_buffer, 0, &readback, 0, size);
        self.queue.submit([encoder.finish()]);
        self.map_and_read(&readback, bytemuck::pod_collect_to_vec::<u8, [f32; 4]>)
    }

    /// Maps `buffer`, hands its bytes to `read` in place (no copy of the whole buffer first) and unmaps
    /// it.
    fn map_and_read<T>(
        &self,
        buffer: &wgpu::Buffer,
        read: impl FnOnce(&[u8]) -> T,
    ) -> Result<T, RenderError> {
        let slice = buffer.slice(..);
        let status = Arc::new(Mutex::new(None));
        let status_sink = Arc::clone(&status);
        slice.map_async(wgpu::MapMode::Read, move |result| {
            if let Ok(mut slot) = status_sink.lock() {
                *slot = Some(result);
            }
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|error| RenderError::Gpu(error.to_string()))?;
        let mapped = status.lock().ok().and_then(|mut slot| slot.take());
        match mapped {
            Some(Ok(())) => {}
            Some(Err(error)) => return Err(RenderError::Gpu(format!("mapping a buffer: {error}"))),
            None => return Err(RenderError::Gpu("buffer never mapped".into())),
        }
        let value = {
            let bytes = slice
                .get_mapped_range()
                .map_err(|error| RenderError::Gpu(format!("mapped range: {error}")))?;
            read(&bytes)
        };
        buffer.unmap();
        self.take_uncaptured()?;
        Ok(value)
    }

    fn take_uncaptured(&self) -> Result<(), RenderError> {
        let mut errors = self
            .uncaptured
            .lock()
            .map_err(|_| RenderError::Gpu("error log poisoned".into()))?;
        if errors.is_empty() {
            Ok(())
        } else {
            let message = errors.join("; ");
            errors.clear();
            Err(RenderError::Gpu(message))
        }
    }

    fn frame_uniform(
        &self,
        camera: &Camera,
        shading: &ShadingParams,
        background: &Background,
    ) -> FrameUniform {
        let [t0, t1, t2] = shading.optical_thickness;
        let [a0, a1, a2] = shading.albedo_scale;
        let eye = camera.eye;
        let light = shading.light_position;
        FrameUniform {
            view_projection: camera
                .view_projection(self.width, self.height)
                .to_cols_array_2d(),
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
        }
    }

    fn update_textures(
        &mut self,
        shading: &ShadingParams,
        background: &Background,
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
                if image.width() != self.width || image.height() != self.height {
                    return Err(RenderError::BackgroundSize {
                        got_width: image.width(),
                        got_height: image.height(),
                        width: self.width,
                        height: self.height,
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

    fn bind_group(&self) -> wgpu::BindGroup {
        fn texture(binding: u32, view: &wgpu::TextureView) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: wgpu::BindingResource::TextureView(view),
            }
        }
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
    fn update_table(&mut self, table: &Arc<AllOrdersTable>) -> Result<(), RenderError> {
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
            let values = per_vertex_slab_values(mesh, camera.eye, shading)?;
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
        let source = format!(
            "{}\n{}\n{}\n{}",
            if dual { OUTPUT_DUAL } else { OUTPUT_SINGLE },
            LIT_SIDE,
            SHADER_BODY,
            MULTIPLE_AT_VERTEX
        );
        let module = validated(&self.device, "shader", || {
            self.device
                .create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(if dual {
                        "thin_slab (dual source)"
                    } else {
                        "thin_slab"
                    }),
                    source: wgpu::ShaderSource::Wgsl(source.into()),
                })
        })?;
        self.modules.insert(dual, module.clone());
        Ok(module)
    }

    fn create_background_pipeline(&mut self) -> Result<wgpu::RenderPipeline, RenderError> {
        let module = self.module(false)?;
        validated(&self.device, "background pipeline", || {
            self.device
                .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("background"),
                    layout: Some(&self.pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_background"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: None,
                    multisample: wgpu::MultisampleState {
                        count: self.samples,
                        ..Default::default()
                    },
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_background"),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format: target_wgpu_format(self.target_format),
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
        })
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
                    depth_stencil: None,
                    multisample: wgpu::MultisampleState {
                        count: self.samples,
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
                            format: target_wgpu_format(self.target_format),
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
}

impl std::fmt::Debug for HeadlessRenderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HeadlessRenderer")
            .field("adapter", &self.adapter_description)
            .field("size", &(self.width, self.height))
            .field("target_format", &self.target_format)
            .field("dual_source", &self.dual_source)
            .finish_non_exhaustive()
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

/// Whether GPU tests may be skipped: `SHEER_SKIP_GPU_TESTS=1`. Without it, a missing adapter fails them.
pub fn gpu_tests_may_be_skipped() -> bool {
    std::env::var("SHEER_SKIP_GPU_TESTS").is_ok_and(|v| v == "1")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backend_lists_read_as_wgpu_reads_them_but_refuse_unknown_names() {
        let (vulkan, gl) = (wgpu::Backends::VULKAN, wgpu::Backends::GL);
        for (list, backends) in [
            ("vulkan", vulkan),
            ("Vulkan, GL", vulkan | gl),
            ("vk", vulkan),
            ("gles", gl),
            ("opengl,vulkan", vulkan | gl),
            // A stray comma is skipped, as wgpu skips it.
            ("vulkan,", vulkan),
            (" gl , ", gl),
        ] {
            assert_eq!(backends_from_list(list).ok(), Some(backends), "{list:?}");
        }
        for (list, unknown) in [
            ("garbage", "garbage"),
            ("vulkan, vulcan", "vulcan"),
            ("gl,,dx13", "dx13"),
            ("", ""),
            (" , ", ""),
        ] {
            match backends_from_list(list) {
                Err(RenderError::UnknownBackend { value, name }) => {
                    assert_eq!((value.as_str(), name.as_str()), (list, unknown));
                }
                other => panic!("{list:?}: expected UnknownBackend, got {other:?}"),
            }
        }
    }

    /// A row read back as a cast and texel by texel (the fallback for an unaligned mapping) gives the
    /// same texels, bit for bit, NaN and infinities included; half floats likewise.
    #[test]
    fn read_back_rows_give_the_texels_aligned_or_not() {
        let texels: Vec<[f32; 4]> = vec![
            [0.0, -0.0, 1.5, -2.25],
            [f32::MAX, f32::MIN_POSITIVE, 1e-45, f32::INFINITY],
            [f32::NAN, 3.0e38, -7.0, 0.1],
        ];
        let bytes: Vec<u8> = texels
            .iter()
            .flatten()
            .flat_map(|value| value.to_le_bytes())
            .collect();
        let bits = |pixels: &[[f32; 4]]| -> Vec<u32> {
            pixels.iter().flatten().map(|v| v.to_bits()).collect()
        };
        // One byte in, so that at least one of the two slices is not 4-byte aligned.
        let mut shifted = vec![0u8];
        shifted.extend_from_slice(&bytes);
        for slice in [&bytes[..], &shifted[1..]] {
            let mut pixels = Vec::new();
            extend_with_f32_texels(&mut pixels, slice);
            assert_eq!(bits(&pixels), bits(&texels));
        }
        let halves: Vec<u8> = texels
            .iter()
            .flatten()
            .flat_map(|&value| f32_to_f16_bits(value).to_le_bytes())
            .collect();
        let mut pixels = Vec::new();
        extend_with_f16_texels(&mut pixels, &halves);
        let expected: Vec<[f32; 4]> = texels
            .iter()
            .map(|texel| texel.map(quantize_to_half))
            .collect();
        assert_eq!(bits(&pixels), bits(&expected));
    }

    /// An overflow reads back as infinity on lavapipe but as `f32::MAX` on NVIDIA's Vulkan driver
    /// (seen on an H200 with driver 580.159: the gpu_vs_cpu overflow test got an image of 3.4·10³⁸
    /// pixels); both, NaN, and the half-float ceiling are overflow. The next value below each ceiling
    /// is not, nor is 10³⁴ (what that test's 3·10³⁸ W light gives a few pixels from it, finite there).
    #[test]
    fn overflow_is_infinity_nan_or_the_format_ceiling() {
        let background = [0.1, 0.1, 0.1, 1.0];
        let with = |channel: usize, value: f32| {
            let mut pixels = vec![background; 6];
            pixels[4][channel] = value;
            pixels
        };
        for format in [TargetFormat::Rgba32Float, TargetFormat::Rgba16Float] {
            let ceiling = format.largest_finite();
            for value in [
                f32::INFINITY,
                f32::NEG_INFINITY,
                f32::NAN,
                ceiling,
                -ceiling,
            ] {
                let found = first_overflowed_channel(&with(1, value), format);
                assert!(
                    matches!(found, Some((4, v)) if v.to_bits() == value.to_bits()),
                    "{format:?} {value}: {found:?}"
                );
            }
            let just_below = f32::from_bits(ceiling.to_bits() - 1);
            assert_eq!(first_overflowed_channel(&with(2, just_below), format), None);
            assert_eq!(first_overflowed_channel(&with(0, 1.0e4), format), None);
        }
        assert_eq!(
            first_overflowed_channel(&with(0, 1.0e34), TargetFormat::Rgba32Float),
            None
        );
        // The half-float ceiling is a legitimate radiance in an f32 target.
        assert_eq!(
            first_overflowed_channel(&with(3, 65_504.0), TargetFormat::Rgba32Float),
            None
        );
        // f16's next value below 65 504 is 65 472.
        assert_eq!(
            first_overflowed_channel(&with(3, 65_472.0), TargetFormat::Rgba16Float),
            None
        );
    }
}
