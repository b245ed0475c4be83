//! The window's image of the flag: sheer-slab's [`SlabRenderer`] records into a pass on eframe's own wgpu
//! device, into a texture egui shows as an image. No read-back, no colour conversion on the CPU, no
//! upload of pixels from the CPU: the frame's commands are submitted before egui's, and the queue
//! orders them.
//!
//! The texture is `Rgba8UnormSrgb` holding exposed radiance: eq. (9) blends in linear light (an sRGB
//! attachment blends linear values and encodes on store), multisampled as the scene asks and resolved.

use std::time::Instant;

use eframe::egui;
use eframe::egui_wgpu::{self, wgpu};
use sheer_slab::render::{SlabRenderer, SlabRendererOptions, SlabTarget, TargetOutput};

use crate::CliError;
use crate::frame::{FlagScene, FrameShading, StageTimes};
use crate::scene::Scene;

/// The displayed texture's format: 8-bit sRGB, which every adapter renders, blends and multisamples.
const DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The features the window's device asks for when the adapter has them: dual-source blending gives
/// per-channel τ1.
pub fn wanted_features(adapter: &wgpu::Adapter) -> wgpu::Features {
    adapter.features() & wgpu::Features::DUAL_SOURCE_BLENDING
}

/// The flag's image on eframe's device, and egui's handle to it.
pub struct WindowImage {
    shading: FrameShading,
    /// Made once eframe's device exists ([`attach`](Self::attach)).
    gpu: Option<Gpu>,
}

struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
    renderer: SlabRenderer,
    target: SlabTarget,
    texture_id: egui::TextureId,
    adapter: String,
}

impl WindowImage {
    /// The image of `shading`'s scene, not yet on a device.
    pub fn new(shading: FrameShading) -> WindowImage {
        WindowImage { shading, gpu: None }
    }

    /// Creates the renderer and the image's textures on eframe's device and registers the image with
    /// egui.
    pub fn attach(
        &mut self,
        render_state: &egui_wgpu::RenderState,
        samples: u32,
    ) -> Result<(), CliError> {
        let device = render_state.device.clone();
        let queue = render_state.queue.clone();
        let options = SlabRendererOptions {
            target_format: DISPLAY_FORMAT,
            samples,
            depth_format: Some(DEPTH_FORMAT),
            output: TargetOutput::Exposed,
        };
        let renderer = SlabRenderer::new(&device, &queue, options)
            .map_err(|e| CliError::new(format!("renderer: {e}")))?;
        let target = SlabTarget::new(
            &device,
            options,
            self.shading.size(),
            wgpu::TextureUsages::TEXTURE_BINDING,
        )
        .map_err(|e| CliError::new(format!("renderer: {e}")))?;
        // egui samples textures as sRGB-encoded values: it gets the image's bytes without decoding.
        let encoded = target.texture().create_view(&wgpu::TextureViewDescriptor {
            format: Some(DISPLAY_FORMAT.remove_srgb_suffix()),
            ..Default::default()
        });
        let texture_id = render_state.renderer.write().register_native_texture(
            &device,
            &encoded,
            wgpu::FilterMode::Linear,
        );
        let info = render_state.adapter.get_info();
        self.gpu = Some(Gpu {
            device,
            queue,
            renderer,
            target,
            texture_id,
            adapter: format!("{} ({:?}, {})", info.name, info.backend, info.driver_info),
        });
        Ok(())
    }

    /// egui's handle to the image.
    pub fn texture_id(&self) -> Option<egui::TextureId> {
        self.gpu.as_ref().map(|gpu| gpu.texture_id)
    }

    /// The image size, pixels.
    pub fn size(&self) -> (u32, u32) {
        self.shading.size()
    }

    /// The adapter that renders: name, backend and driver.
    pub fn adapter(&self) -> &str {
        self.gpu
            .as_ref()
            .map_or("none yet", |gpu| gpu.adapter.as_str())
    }

    /// See [`FrameShading::update`].
    pub fn update_shading(&mut self, scene: &Scene) -> Result<(), CliError> {
        self.shading.update(scene)
    }

    /// Records the flag's frame into the image and submits it, without waiting for the GPU. wgpu
    /// errors inside are caught in an error scope and returned.
    pub fn render(&mut self, flag: &FlagScene, times: &mut StageTimes) -> Result<(), CliError> {
        let Some(gpu) = &mut self.gpu else {
            return Err(CliError::new("render: the window has no GPU device yet"));
        };
        let start = Instant::now();
        let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("flag frame"),
            });
        let size = self.shading.size();
        let frames = self.shading.frames(flag)?;
        let draws = frames
            .iter()
            .map(|frame| gpu.renderer.prepare(&mut encoder, size, frame))
            .collect::<Result<Vec<_>, _>>();
        if let Ok(draws) = &draws {
            let mut pass = gpu.target.begin_pass(&mut encoder);
            for draw in draws {
                gpu.renderer.paint(&mut pass, draw);
            }
        }
        gpu.queue.submit([encoder.finish()]);
        // Validation is synchronous in wgpu on native, so the scope is resolved at once.
        let error = pollster::block_on(scope.pop());
        times.shading += start.elapsed();
        draws.map_err(|e| CliError::new(format!("render: {e}")))?;
        match error {
            Some(error) => Err(CliError::new(format!("render: GPU error: {error}"))),
            None => Ok(()),
        }
    }
}
