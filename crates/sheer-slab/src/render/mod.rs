//! The wgpu renderer of the thin-slab model (Frisvad, Christensen & Falster 2005, §4): the three
//! evaluation paths the paper measures (per fragment, per vertex in the vertex shader, per vertex on the
//! CPU) and the traditional baseline (diffuse BRDF, constant α = 0.2), blended as eq. (9)
//! (`L_dst·α_src + L_src`) over a background, triangles sorted back to front every frame, into a linear
//! target. Each thin-slab path evaluates either scattering model of
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
//! Two ways in: [`SlabRenderer`] records into a render pass on the caller's device (a window, an
//! engine), and [`HeadlessRenderer`] owns a device around it and reads images back.

mod cpu;
mod headless;
mod scene;
mod shadow;
mod slab_renderer;

use thiserror::Error;

pub use headless::{GpuTimes, HeadlessRenderer};
pub use scene::{
    AllOrdersSampling, Background, Camera, CameraError, LinearImage, MeshError, ShadingError,
    ShadingParams, SlabMesh, Texture2d, linear_to_srgb, linear_to_srgb8, save_image_file,
    srgb8_to_linear, write_file_atomically,
};
pub use shadow::{DEFAULT_SHADOW_RESOLUTION, Shadows};

pub use slab_renderer::{
    LightMarker, OpaqueMesh, SlabDraw, SlabFrame, SlabRenderer, SlabRendererOptions, SlabTarget,
    TargetOutput,
};
/// The CPU references the tests check the GPU against (the `f64` model at a point, with and without
/// the light's transmission through the layers in front; the texture samplers the shaders mirror; the
/// shadow ray caster) and the GPU-test switch: for tests, behind the `test-support` feature.
#[cfg(feature = "test-support")]
pub use {
    cpu::{albedo_at, f16_bits_to_f32, optical_thickness_at, slab_values_at, slab_values_lit_by},
    shadow::{LightTransmission, ShadowCasters},
};

use crate::model::SlabParameterError;

const SHADER_BODY: &str = include_str!("../../../../shaders/thin_slab.wgsl");
const LIT_SIDE: &str = include_str!("../../../../shaders/lit_side.wgsl");
const OUTPUT_SINGLE: &str = include_str!("../../../../shaders/slab_output_single.wgsl");
const OUTPUT_DUAL: &str = include_str!("../../../../shaders/slab_output_dual.wgsl");
#[cfg(any(test, feature = "test-support"))]
const MODEL_CHECK: &str = include_str!("../../../../shaders/slab_model_check.wgsl");
const MULTIPLE_AT_VERTEX: &str = include_str!("../../../../shaders/multiple_at_vertex.wgsl");
const SHADOW: &str = include_str!("../../../../shaders/shadow.wgsl");

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
/// With the `serde` feature the thin-slab paths are named `fragment`, `vertex` and `cpu`; the baseline
/// is a different model, not a path, so a file cannot name it here.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum EvaluationPath {
    /// Eqs. (4)–(9) in the fragment shader (the paper's 300 fps path).
    #[cfg_attr(feature = "serde", serde(rename = "fragment"))]
    PerFragment,
    /// In the vertex shader, interpolated (480 fps in the paper).
    #[cfg_attr(feature = "serde", serde(rename = "vertex"))]
    PerVertex,
    /// Per vertex on the CPU with rayon, uploaded every frame (190 fps in the paper).
    Cpu,
    /// Traditional: diffuse BRDF, constant α, back-lit side black.
    #[cfg_attr(feature = "serde", serde(skip))]
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

/// The wgpu format of a linear target.
fn target_wgpu_format(format: TargetFormat) -> wgpu::TextureFormat {
    match format {
        TargetFormat::Rgba32Float => wgpu::TextureFormat::Rgba32Float,
        TargetFormat::Rgba16Float => wgpu::TextureFormat::Rgba16Float,
    }
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
            cpu::f16_bits_to_f32(u16::from_le_bytes([texel[at], texel[at + 1]]))
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

/// Whether GPU tests may be skipped: `SHEER_SKIP_GPU_TESTS=1`. Without it, a missing adapter fails them.
#[cfg(any(test, feature = "test-support"))]
pub fn gpu_tests_may_be_skipped() -> bool {
    std::env::var("SHEER_SKIP_GPU_TESTS").is_ok_and(|v| v == "1")
}

#[cfg(test)]
mod tests {
    use super::cpu::{f32_to_f16_bits, quantize_to_half};
    use super::*;

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
