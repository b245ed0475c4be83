//! `SlabRenderer` on a device the test owns gives the headless renderer's pixels bit for bit; opaque
//! geometry and the light marker are composited by eq. (9) like the background: an opaque pole behind
//! the cloth is seen through it, one in front hides it, and the marker behind the cloth takes the
//! background's place under the cloth's α.
//!
//! Without any adapter these tests fail, unless `SHEER_SKIP_GPU_TESTS=1`.

use std::sync::{Arc, Mutex};

use glam::Vec3;
use sheer_slab::render::{
    Background, Camera, EvaluationPath, HeadlessRenderer, LightMarker, OpaqueMesh, RenderError,
    ShadingParams, SlabFrame, SlabMesh, SlabRenderer, SlabRendererOptions, SlabTarget,
    TargetFormat, TargetOutput, gpu_tests_may_be_skipped,
};

const WIDTH: u32 = 80;
const HEIGHT: u32 = 64;

fn renderer() -> Option<HeadlessRenderer> {
    match HeadlessRenderer::with_samples(WIDTH, HEIGHT, 4) {
        Ok(renderer) => Some(renderer),
        Err(error @ RenderError::NoAdapter { .. }) if gpu_tests_may_be_skipped() => {
            eprintln!("skipping GPU test (SHEER_SKIP_GPU_TESTS=1): {error}");
            None
        }
        Err(error) => panic!("GPU tests need an adapter: {error}"),
    }
}

fn camera() -> Camera {
    Camera {
        eye: Vec3::new(0.0, 0.0, 3.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        vertical_fov: 0.6,
        near: 0.05,
        far: 20.0,
    }
}

/// A 1.2 m × 0.9 m sheet in the plane z = 0 facing the camera.
fn sheet() -> SlabMesh {
    SlabMesh::flat_sheet(
        Vec3::new(-0.6, -0.45, 0.0),
        Vec3::X * 1.2,
        Vec3::Y * 0.9,
        Vec3::Z,
        8,
        6,
    )
    .unwrap()
}

/// A vertical pole through (0, ·, z), 6 cm thick.
fn pole(z: f32) -> OpaqueMesh {
    OpaqueMesh::cylinder(
        Vec3::new(0.0, -1.0, z),
        Vec3::new(0.0, 1.0, z),
        0.03,
        16,
        [0.6, 0.5, 0.4],
    )
    .unwrap()
}

fn frame<'a>(
    mesh: &'a SlabMesh,
    camera: &'a Camera,
    shading: &'a ShadingParams,
    background: &'a Background,
    opaque: &'a [OpaqueMesh],
    light_marker: Option<LightMarker>,
) -> SlabFrame<'a> {
    SlabFrame {
        mesh,
        camera,
        shading,
        background,
        path: EvaluationPath::PerFragment,
        opaque,
        light_marker,
        scissor: None,
    }
}

/// The centre pixel of a headless render of `frames`: radiance and α.
fn centre(renderer: &mut HeadlessRenderer, frames: &[SlabFrame<'_>]) -> [f32; 4] {
    renderer.render_frames_timed(frames).unwrap();
    let image = renderer.read_target().unwrap();
    image.pixel(WIDTH / 2, HEIGHT / 2).unwrap()
}

#[test]
fn a_renderer_on_the_callers_device_gives_the_headless_pixels() {
    let Some(mut headless) = renderer() else {
        return;
    };
    let (mesh, camera) = (sheet(), camera());
    let shading = ShadingParams::uniform(2.0, 0.9, Vec3::new(0.5, 0.8, 2.0), 40.0).unwrap();
    let background = Background::Uniform([0.2, 0.3, 0.4]);
    let poles = [pole(-0.3)];
    let marker = Some(LightMarker {
        radius_pixels: 4.0,
        radiance: [4.0, 3.6, 2.4],
    });
    let frames = [frame(&mesh, &camera, &shading, &background, &poles, marker)];
    headless.render_frames_timed(&frames).unwrap();
    let expected = headless.read_target().unwrap();

    // The caller's own device, on the adapter the headless renderer chose.
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
    let adapter = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
        .into_iter()
        .find(|adapter| {
            let info = adapter.get_info();
            let description = format!("{} ({:?}, {})", info.name, info.backend, info.driver_info);
            description == headless.adapter_description()
        })
        .expect("the headless renderer's adapter");
    let format = match headless.target_format() {
        TargetFormat::Rgba32Float => wgpu::TextureFormat::Rgba32Float,
        TargetFormat::Rgba16Float => wgpu::TextureFormat::Rgba16Float,
    };
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_features: adapter.features()
            & (wgpu::Features::FLOAT32_BLENDABLE
                | wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES
                | wgpu::Features::DUAL_SOURCE_BLENDING),
        required_limits: adapter.limits(),
        ..Default::default()
    }))
    .unwrap();
    let options = SlabRendererOptions {
        target_format: format,
        samples: 4,
        depth_format: Some(wgpu::TextureFormat::Depth32Float),
        output: TargetOutput::Radiance,
    };
    let mut slab = SlabRenderer::new(&device, &queue, options).unwrap();
    let target = SlabTarget::new(
        &device,
        options,
        (WIDTH, HEIGHT),
        wgpu::TextureUsages::COPY_SRC,
    )
    .unwrap();
    let mut encoder = device.create_command_encoder(&Default::default());
    let draw = slab
        .prepare(&mut encoder, (WIDTH, HEIGHT), &frames[0])
        .unwrap();
    {
        let mut pass = target.begin_pass(&mut encoder);
        slab.paint(&mut pass, &draw);
    }
    // Read back as a user would: copy to a mappable buffer (rows padded to 256 bytes).
    let texel = format.block_copy_size(None).unwrap();
    let row = (WIDTH * texel).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
        * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: u64::from(row * HEIGHT),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        target.texture().as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(HEIGHT),
            },
        },
        wgpu::Extent3d {
            width: WIDTH,
            height: HEIGHT,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);
    let mapped = Arc::new(Mutex::new(None));
    let sink = Arc::clone(&mapped);
    buffer
        .slice(..)
        .map_async(wgpu::MapMode::Read, move |result| {
            *sink.lock().unwrap() = Some(result);
        });
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    mapped.lock().unwrap().take().unwrap().unwrap();
    let bytes = buffer.slice(..).get_mapped_range().unwrap().to_vec();
    let mut differing = 0;
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let start = (y * row + x * texel) as usize;
            let texel_bytes = &bytes[start..start + texel as usize];
            let own: Vec<u32> = match format {
                wgpu::TextureFormat::Rgba32Float => texel_bytes
                    .chunks_exact(4)
                    .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect(),
                _ => texel_bytes
                    .chunks_exact(2)
                    .map(|b| {
                        sheer_slab::render::f16_bits_to_f32(u16::from_le_bytes([b[0], b[1]]))
                            .to_bits()
                    })
                    .collect(),
            };
            let headless_bits: Vec<u32> = expected
                .pixel(x, y)
                .unwrap()
                .iter()
                .map(|v| v.to_bits())
                .collect();
            differing += usize::from(own != headless_bits);
        }
    }
    assert_eq!(differing, 0, "pixels that differ from the headless render");
}

#[test]
fn an_opaque_pole_is_seen_through_the_cloth_in_front_and_hides_the_cloth_behind() {
    let Some(mut renderer) = renderer() else {
        return;
    };
    let (mesh, camera) = (sheet(), camera());
    let empty = SlabMesh::flat_sheet(
        Vec3::new(5.0, 5.0, -10.0),
        Vec3::X * 0.01,
        Vec3::Y * 0.01,
        Vec3::Z,
        1,
        1,
    )
    .unwrap();
    let shading = ShadingParams::uniform(2.0, 0.9, Vec3::new(0.4, 0.6, 2.0), 40.0).unwrap();
    let background = Background::Uniform([0.2, 0.3, 0.4]);
    for z in [-0.3, 0.3] {
        let poles = [pole(z)];
        let cloth = centre(
            &mut renderer,
            &[frame(&mesh, &camera, &shading, &background, &[], None)],
        );
        let pole_alone = centre(
            &mut renderer,
            &[frame(&empty, &camera, &shading, &background, &poles, None)],
        );
        let both = centre(
            &mut renderer,
            &[frame(&mesh, &camera, &shading, &background, &poles, None)],
        );
        // The pole is lit, opaque (α = 0 behind it), and not the background.
        assert_eq!(pole_alone[3], 0.0);
        assert!(
            pole_alone[..3]
                .iter()
                .zip(&background_colour(&background))
                .any(|(p, b)| p != b)
        );
        if z > 0.0 {
            assert_eq!(both, pole_alone, "a pole in front hides the cloth");
        } else {
            // Eq. (9): the cloth's own radiance L − α·L_background, over the pole instead.
            let alpha = cloth[3];
            assert!(alpha > 0.01 && alpha < 0.99, "α = {alpha}");
            for c in 0..3 {
                let expected =
                    cloth[c] - alpha * background_colour(&background)[c] + alpha * pole_alone[c];
                // Two f32 blends on each side: a few ulps of the largest term.
                let tolerance = 8.0 * f32::EPSILON * cloth[c].max(pole_alone[c]).max(1.0);
                assert!(
                    (both[c] - expected).abs() <= tolerance,
                    "channel {c}: {} against {expected}",
                    both[c]
                );
            }
            assert_eq!(both[3], 0.0, "nothing behind the pole is seen");
        }
    }
}

#[test]
fn the_light_marker_behind_the_cloth_is_seen_through_it() {
    let Some(mut renderer) = renderer() else {
        return;
    };
    let (mesh, camera) = (sheet(), camera());
    // The light straight behind the sheet's centre, on the camera's axis: the sheet is back-lit.
    let shading = ShadingParams::uniform(2.0, 0.9, Vec3::new(0.0, 0.0, -1.5), 40.0).unwrap();
    let background = Background::Uniform([0.2, 0.3, 0.4]);
    let marker = LightMarker {
        radius_pixels: 3.0,
        radiance: [4.0, 3.6, 2.4],
    };
    let without = centre(
        &mut renderer,
        &[frame(&mesh, &camera, &shading, &background, &[], None)],
    );
    let with = centre(
        &mut renderer,
        &[frame(
            &mesh,
            &camera,
            &shading,
            &background,
            &[],
            Some(marker),
        )],
    );
    let alpha = without[3];
    assert!(alpha > 0.01, "α = {alpha}");
    for c in 0..3 {
        let expected =
            without[c] - alpha * background_colour(&background)[c] + alpha * marker.radiance[c];
        let tolerance = 8.0 * f32::EPSILON * marker.radiance[c];
        assert!(
            (with[c] - expected).abs() <= tolerance,
            "channel {c}: {} against {expected}",
            with[c]
        );
    }
    // In front of the cloth (light between camera and sheet) the marker is drawn as it is.
    let shading = ShadingParams::uniform(2.0, 0.9, Vec3::new(0.0, 0.0, 1.5), 40.0).unwrap();
    let front = centre(
        &mut renderer,
        &[frame(
            &mesh,
            &camera,
            &shading,
            &background,
            &[],
            Some(marker),
        )],
    );
    assert_eq!(front, [4.0, 3.6, 2.4, 0.0]);
}

fn background_colour(background: &Background) -> [f32; 3] {
    match background {
        Background::Uniform(colour) => *colour,
        Background::Image(_) => unreachable!("the tests use a uniform background"),
    }
}

#[test]
fn bad_opaque_meshes_and_markers_are_typed_errors() {
    assert!(OpaqueMesh::cylinder(Vec3::ZERO, Vec3::ZERO, 0.1, 8, [0.5; 3]).is_err());
    assert!(OpaqueMesh::cylinder(Vec3::ZERO, Vec3::Y, f32::NAN, 8, [0.5; 3]).is_err());
    let mut mesh = pole(0.0);
    mesh.indices.push(10_000);
    assert!(mesh.validate().is_err());
    let mut mesh = pole(0.0);
    mesh.albedo = [1.5, 0.5, 0.5];
    assert!(mesh.validate().is_err());
    let mut mesh = pole(0.0);
    mesh.normals[3] = [0.0; 3];
    assert!(mesh.validate().is_err());
    assert!(pole(0.0).validate().is_ok());
    let Some(mut renderer) = renderer() else {
        return;
    };
    let (sheet, camera) = (sheet(), camera());
    let shading = ShadingParams::uniform(2.0, 0.9, Vec3::new(0.0, 0.0, 1.5), 40.0).unwrap();
    let background = Background::Uniform([0.2; 3]);
    for radius_pixels in [0.0, -1.0, f32::NAN] {
        let marker = LightMarker {
            radius_pixels,
            radiance: [1.0; 3],
        };
        let result = renderer.render_frames_timed(&[frame(
            &sheet,
            &camera,
            &shading,
            &background,
            &[],
            Some(marker),
        )]);
        assert!(matches!(result, Err(RenderError::Shading(_))), "{result:?}");
    }
}
