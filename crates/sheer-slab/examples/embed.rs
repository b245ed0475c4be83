//! Thin cloth in your own wgpu frame: a plain winit + wgpu window (no egui) showing a wavy sheet under a
//! light that circles it, shaded by [`SlabRenderer`] inside the window's own render pass, with normals
//! turned toward the light by `sheer-normals`. This is the code path to copy into an engine: your
//! device, your surface, your pass; sheer-slab only uploads and records.
//!
//! `cargo run -p sheer-slab --release --example embed` (under `xvfb-run -a` without a display);
//! `-- --frames N` closes the window after N frames and prints the mean frame time.

use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use sheer_normals::{Light, NormalUpdater};
use sheer_slab::render::{
    Background, Camera, EvaluationPath, LightMarker, ShadingParams, SlabFrame, SlabMesh,
    SlabRenderer, SlabRendererOptions, TargetOutput, Texture2d,
};
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

/// Samples per pixel (anti-aliased edges).
const SAMPLES: u32 = 4;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The sheet: a 1.2 m × 0.8 m grid, rows along y, waving along x.
struct Sheet {
    mesh: SlabMesh,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    updater: NormalUpdater,
}

impl Sheet {
    fn new() -> Result<Sheet, Box<dyn std::error::Error>> {
        let mesh = SlabMesh::flat_sheet(
            Vec3::new(-0.6, -0.4, 0.0),
            Vec3::X * 1.2,
            Vec3::Y * 0.8,
            Vec3::Z,
            48,
            32,
        )?;
        let updater = NormalUpdater::new(mesh.positions.len(), &mesh.indices)?;
        let positions = mesh.positions.iter().map(|&p| Vec3::from(p)).collect();
        let normals = vec![Vec3::Z; mesh.positions.len()];
        Ok(Sheet {
            mesh,
            positions,
            normals,
            updater,
        })
    }

    /// Moves the sheet to time `t` (s) and turns its normals toward the light (μ0 > 0).
    fn update(&mut self, t: f32, light: Vec3) -> Result<(), Box<dyn std::error::Error>> {
        for (position, vertex) in self.positions.iter_mut().zip(&mut self.mesh.positions) {
            let x = position.x;
            position.z = 0.08 * (6.0 * x - 3.0 * t).sin() * (x + 0.6);
            *vertex = position.to_array();
        }
        let light = Light::Point { position: light };
        self.updater
            .update(&self.positions, &light, &mut self.normals)?;
        for (vertex, normal) in self.mesh.normals.iter_mut().zip(&self.normals) {
            *vertex = normal.to_array();
        }
        Ok(())
    }
}

/// The window's GPU state: everything an engine would already have, plus one `SlabRenderer`.
struct Gpu {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    device: wgpu::Device,
    queue: wgpu::Queue,
    config: wgpu::SurfaceConfiguration,
    multisampled: wgpu::TextureView,
    depth: wgpu::TextureView,
    slab: SlabRenderer,
}

impl Gpu {
    fn new(window: Arc<Window>) -> Result<Gpu, Box<dyn std::error::Error>> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
        let surface = instance.create_surface(Arc::clone(&window))?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            compatible_surface: Some(&surface),
            ..Default::default()
        }))?;
        let (device, queue) =
            pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
                // Per-channel τ1 needs dual-source blending; this sheet is grey, so nothing is required.
                required_features: adapter.features() & wgpu::Features::DUAL_SOURCE_BLENDING,
                ..Default::default()
            }))?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .ok_or("the adapter cannot present to this window")?;
        // An sRGB surface blends eq. (9) in linear light.
        let capabilities = surface.get_capabilities(&adapter);
        if let Some(&srgb) = capabilities.formats.iter().find(|f| f.is_srgb()) {
            config.format = srgb;
        }
        surface.configure(&device, &config);
        let slab = SlabRenderer::new(
            &device,
            &queue,
            SlabRendererOptions {
                target_format: config.format,
                samples: SAMPLES,
                depth_format: Some(DEPTH_FORMAT),
                output: TargetOutput::Exposed,
            },
        )?;
        let (multisampled, depth) = attachments(&device, &config);
        println!("adapter: {}", adapter.get_info().name);
        Ok(Gpu {
            window,
            surface,
            device,
            queue,
            config,
            multisampled,
            depth,
            slab,
        })
    }

    fn resize(&mut self, width: u32, height: u32) {
        self.config.width = width.max(1);
        self.config.height = height.max(1);
        self.surface.configure(&self.device, &self.config);
        (self.multisampled, self.depth) = attachments(&self.device, &self.config);
    }

    /// One frame: prepare the slab (uploads, sort), then record it into the window's pass.
    fn draw(
        &mut self,
        sheet: &Sheet,
        shading: &ShadingParams,
    ) -> Result<(), Box<dyn std::error::Error>> {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(frame)
            | wgpu::CurrentSurfaceTexture::Suboptimal(frame) => frame,
            // Resized or hidden: configure again and skip this frame.
            _ => {
                self.surface.configure(&self.device, &self.config);
                return Ok(());
            }
        };
        let view = frame.texture.create_view(&Default::default());
        let size = (self.config.width, self.config.height);
        let camera = Camera {
            eye: Vec3::new(0.0, 0.1, 2.2),
            target: Vec3::ZERO,
            up: Vec3::Y,
            vertical_fov: 0.7,
            near: 0.1,
            far: 20.0,
        };
        let background = Background::Uniform([0.25, 0.35, 0.45]);
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let draw = self.slab.prepare(
            &mut encoder,
            size,
            &SlabFrame {
                mesh: &sheet.mesh,
                camera: &camera,
                shading,
                background: &background,
                path: EvaluationPath::PerFragment,
                opaque: &[],
                light_marker: Some(LightMarker {
                    radius_pixels: 6.0,
                    radiance: [4.0, 3.6, 2.4],
                }),
                scissor: None,
            },
        )?;
        {
            // Your pass: any colour attachment of the renderer's format and samples, depth cleared to 1.
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("window pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.multisampled,
                    depth_slice: None,
                    resolve_target: Some(&view),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth,
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
            self.slab.paint(&mut pass, &draw);
        }
        self.queue.submit([encoder.finish()]);
        self.window.pre_present_notify();
        self.queue.present(frame);
        Ok(())
    }
}

/// The multisampled colour and the depth attachment for the surface's size.
fn attachments(
    device: &wgpu::Device,
    config: &wgpu::SurfaceConfiguration,
) -> (wgpu::TextureView, wgpu::TextureView) {
    let texture = |format| {
        device
            .create_texture(&wgpu::TextureDescriptor {
                label: None,
                size: wgpu::Extent3d {
                    width: config.width,
                    height: config.height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: SAMPLES,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            })
            .create_view(&Default::default())
    };
    (texture(config.format), texture(DEPTH_FORMAT))
}

struct App {
    gpu: Option<Gpu>,
    sheet: Sheet,
    shading: ShadingParams,
    start: Instant,
    frames: u32,
    frame_limit: Option<u32>,
    error: Option<Box<dyn std::error::Error>>,
}

impl App {
    fn frame(&mut self) -> Result<(), Box<dyn std::error::Error>> {
        let t = self.start.elapsed().as_secs_f32();
        // The light circles the sheet once every 8 s, so each face is lit in turn.
        let angle = t * std::f32::consts::TAU / 8.0;
        self.shading.light_position = Vec3::new(1.5 * angle.sin(), 0.5, 1.5 * angle.cos());
        self.sheet.update(t, self.shading.light_position)?;
        if let Some(gpu) = &mut self.gpu {
            gpu.draw(&self.sheet, &self.shading)?;
            gpu.window.request_redraw();
        }
        self.frames += 1;
        Ok(())
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_some() {
            return;
        }
        let attributes = Window::default_attributes().with_title("sheer-slab: embed");
        let gpu = event_loop
            .create_window(attributes)
            .map_err(Into::into)
            .and_then(|window| Gpu::new(Arc::new(window)));
        match gpu {
            Ok(gpu) => {
                gpu.window.request_redraw();
                self.gpu = Some(gpu);
            }
            Err(error) => {
                self.error = Some(error);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(gpu) = &mut self.gpu {
                    gpu.resize(size.width, size.height);
                }
            }
            WindowEvent::RedrawRequested => {
                if let Err(error) = self.frame() {
                    self.error = Some(error);
                    event_loop.exit();
                }
                if self.frame_limit.is_some_and(|limit| self.frames >= limit) {
                    let seconds = self.start.elapsed().as_secs_f64();
                    println!(
                        "{} frames, {:.1} ms a frame",
                        self.frames,
                        seconds * 1e3 / f64::from(self.frames)
                    );
                    event_loop.exit();
                }
            }
            _ => {}
        }
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let frame_limit = match args.iter().position(|a| a == "--frames") {
        Some(i) => Some(args.get(i + 1).ok_or("--frames needs a number")?.parse()?),
        None => None,
    };
    // The paper's figure 2 material: τ1 = 2, Λ = 1, a 60 W point light, with a blue stripe.
    let mut shading = ShadingParams::uniform(2.0, 1.0, Vec3::new(0.0, 0.5, 1.5), 60.0)?;
    shading.albedo_texture =
        Texture2d::new(3, 1, vec![[0.95; 4], [0.1, 0.25, 0.9, 1.0], [0.95; 4]])?;
    shading.exposure = 3.0;
    let mut app = App {
        gpu: None,
        sheet: Sheet::new()?,
        shading,
        start: Instant::now(),
        frames: 0,
        frame_limit,
        error: None,
    };
    EventLoop::new()?.run_app(&mut app)?;
    match app.error {
        Some(error) => Err(error),
        None => Ok(()),
    }
}
