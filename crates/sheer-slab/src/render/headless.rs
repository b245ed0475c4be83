//! [`HeadlessRenderer`]: a thin owner of a wgpu device around [`SlabRenderer`], for images without a
//! window (`sheer render`, figures, benchmarks, tests). It picks an adapter, renders into a linear float
//! target (multisampled and resolved when asked) with a depth buffer, and reads the target back.
//!
//! Adapter choice: `WGPU_BACKEND` if set (every name in it must be a backend, else
//! [`RenderError::UnknownBackend`]), else Vulkan (Mesa lavapipe on a machine without a GPU) and then
//! GL (llvmpipe over EGL); the first adapter of the preferred backend wins, hardware before software.

use std::sync::{Arc, Mutex};

use super::slab_renderer::{
    SlabDraw, SlabFrame, SlabRenderer, SlabRendererOptions, SlabTarget, TargetOutput,
};
use super::{
    Background, Camera, EvaluationPath, LinearImage, RenderError, ShadingParams, SlabMesh,
    TargetFormat, extend_with_f16_texels, extend_with_f32_texels, first_overflowed_channel,
    target_wgpu_format,
};
// The shader checks' (`test-support`).
#[cfg(any(test, feature = "test-support"))]
use super::{LIT_SIDE, OUTPUT_SINGLE, SHADER_BODY, SHADOW, validated};
#[cfg(any(test, feature = "test-support"))]
use crate::all_orders::AllOrdersTable;

/// The depth attachment's format: every adapter renders and multisamples it.
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// GPU time of one frame, from submitting each part until the GPU has finished it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuTimes {
    /// The passes [`SlabRenderer::prepare`] records before the draw: the uploads staged with them, the
    /// shadow map's peel passes, the per-vertex table pass.
    pub before_draw: std::time::Duration,
    /// The frame's draw: background, opaque geometry, marker, cloth.
    pub draw: std::time::Duration,
}

impl GpuTimes {
    /// Both parts.
    pub fn total(&self) -> std::time::Duration {
        self.before_draw + self.draw
    }
}

/// A renderer without a window: renders into a linear float texture and reads it back.
pub struct HeadlessRenderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter_description: String,
    width: u32,
    height: u32,
    target_format: TargetFormat,
    target: SlabTarget,
    readback: wgpu::Buffer,
    padded_row_bytes: u32,
    renderer: SlabRenderer,
    uncaptured: Arc<Mutex<Vec<String>>>,
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
        let options = SlabRendererOptions {
            target_format: target_wgpu_format(target_format),
            samples,
            depth_format: Some(DEPTH_FORMAT),
            output: TargetOutput::Radiance,
        };
        let renderer = SlabRenderer::new(&device, &queue, options)?;
        let target = SlabTarget::new(
            &device,
            options,
            (width, height),
            wgpu::TextureUsages::COPY_SRC,
        )?;
        Ok(HeadlessRenderer {
            device,
            queue,
            adapter_description,
            width,
            height,
            target_format,
            target,
            readback,
            padded_row_bytes,
            renderer,
            uncaptured,
        })
    }

    /// Samples per pixel: 1, or 4 with anti-aliased edges.
    pub fn samples(&self) -> u32 {
        self.renderer.options().samples
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
        self.renderer.max_texture_dimension()
    }

    /// Whether per-channel τ1 (dual-source blending) is available.
    pub fn supports_per_channel_optical_thickness(&self) -> bool {
        self.renderer.supports_per_channel_optical_thickness()
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
        self.render_frames_timed(&[SlabFrame {
            mesh,
            camera,
            shading,
            background,
            path,
            opaque: &[],
            light_marker: None,
            scissor: None,
        }])
    }

    /// Renders `frames` one after the other into one pass over the target (each in its scissor
    /// rectangle; see [`SlabRenderer::prepare`]) and waits until the GPU has finished, returning the GPU
    /// time as [`render_frame_timed`](Self::render_frame_timed) does.
    pub fn render_frames_timed(
        &mut self,
        frames: &[SlabFrame<'_>],
    ) -> Result<std::time::Duration, RenderError> {
        self.render_frames_staged(frames).map(|times| times.total())
    }

    /// [`render_frames_timed`](Self::render_frames_timed) with the GPU time split in two: the passes
    /// [`SlabRenderer::prepare`] records (uploads, the shadow map, the per-vertex table pass), submitted
    /// and waited for on their own, then the frame's draw.
    pub fn render_frames_staged(
        &mut self,
        frames: &[SlabFrame<'_>],
    ) -> Result<GpuTimes, RenderError> {
        let mut prepare = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("prepare"),
            });
        let draws = frames
            .iter()
            .map(|frame| {
                self.renderer
                    .prepare(&mut prepare, (self.width, self.height), frame)
            })
            .collect::<Result<Vec<SlabDraw>, RenderError>>()?;
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        {
            let mut pass = self.target.begin_pass(&mut encoder);
            for draw in &draws {
                self.renderer.paint(&mut pass, draw);
            }
        }
        let wait = |commands: wgpu::CommandBuffer| {
            let submitted = std::time::Instant::now();
            self.queue.submit([commands]);
            self.device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|error| RenderError::Gpu(error.to_string()))?;
            Ok::<_, RenderError>(submitted.elapsed())
        };
        let before_draw = wait(prepare.finish())?;
        let draw = wait(encoder.finish())?;
        self.take_uncaptured()?;
        Ok(GpuTimes { before_draw, draw })
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
                texture: self.target.texture(),
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
}

impl std::fmt::Debug for HeadlessRenderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HeadlessRenderer")
            .field("adapter", &self.adapter_description)
            .field("size", &(self.width, self.height))
            .field("target_format", &self.target_format)
            .field("renderer", &self.renderer)
            .finish_non_exhaustive()
    }
}

/// The shader checks: the WGSL model evaluated on the GPU for samples, for the tests that compare it
/// with the `f64` model (behind the `test-support` feature).
#[cfg(any(test, feature = "test-support"))]
impl HeadlessRenderer {
    /// Evaluates the shader's model function (`slab_shapes` in `shaders/thin_slab.wgsl`) on the GPU for
    /// samples `(τ1, μ0, μ)` and returns `(eq. 4, eq. 5, α)` per sample, the radiances per unit
    /// irradiance and without the factor Λ/(4π): for checking the WGSL model against [`crate::model`].
    /// The renderer only calls it with cosines ≥ [`COSINE_FLOOR`](crate::render::cpu::COSINE_FLOOR).
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
        self.renderer.update_table(table)?;
        let bind_group = self.renderer.bind_group();
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
        let source = format!(
            "{OUTPUT_SINGLE}\n{LIT_SIDE}\n{SHADER_BODY}\n{SHADOW}\n{}",
            super::MODEL_CHECK
        );
        // With the frame's group 0: the same layout as the per-vertex all-orders pass (group 1 one
        // storage buffer in, one out); without: derived from the entry point.
        let layout = frame_bindings.map(|_| &self.renderer.compute_io_pipeline_layout);
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
            &self.renderer.compute_io_layout
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
}
