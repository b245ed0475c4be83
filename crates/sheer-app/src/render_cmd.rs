//! `sheer render` (one frame or a sequence, PNG and linear OpenEXR) and `sheer figure2` (the paper's
//! figure 2: back-lit and front-lit, baseline and thin-slab, as one labelled 2×2 image).

use std::path::{Path, PathBuf};

use ab_glyph::{Font, FontRef, PxScale, ScaleFont};
use clap::{Args, ValueEnum};
use image::{Rgb, RgbImage};
use sheer_slab::render::{LinearImage, save_image_file};

use crate::CliError;
use crate::frame::{FlagScene, FrameRenderer, StageTimes};
use crate::output::FrameNames;
use crate::scene::{Scene, ShadingModel};
use crate::sequence::{Sequence, advance_to, run_sequence};
use sheer_slab::ScatteringOrders;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ImageFormat {
    /// 8-bit sRGB after exposure.
    Png,
    /// Linear radiance, 32-bit float (OpenEXR), before exposure; alpha = transmittance through the
    /// cloth.
    Exr,
    /// Both, side by side.
    Both,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Scene file (TOML); default: the shipped default scene.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Output image for a single frame (.png or .exr).
    #[arg(long, conflicts_with = "out_dir")]
    pub out: Option<PathBuf>,
    /// Render a sequence of this many frames (1/fps apart) into --out-dir.
    #[arg(
        long,
        requires = "out_dir",
        conflicts_with = "out",
        allow_negative_numbers = true
    )]
    pub frames: Option<u32>,
    /// Directory for frame_0000.png … of a sequence (numbers padded to the last frame's width). A
    /// folder that already holds frame_*.png or frame_*.exr files is refused unless --overwrite.
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
    /// Remove the frame_*.png and frame_*.exr files already in --out-dir first.
    #[arg(long, requires = "out_dir")]
    pub overwrite: bool,
    /// Image format of a sequence (a single --out frame takes its format from the extension).
    #[arg(long, value_enum, default_value_t = ImageFormat::Png, conflicts_with = "out")]
    pub format: ImageFormat,
    /// Scene time of a single frame, or of a sequence's first frame, s, in [0, 3600] (the flag is
    /// simulated up to it). Default: 2 for a single frame, 0 for a sequence.
    #[arg(long, allow_negative_numbers = true)]
    pub time: Option<f64>,
}

/// `--time` of a single `sheer render` frame when none is given, s.
pub const DEFAULT_FRAME_TIME_S: f64 = 2.0;

/// Latest scene time a frame may be rendered at, s: an hour of simulated flag (216 000 frames at
/// 60 Hz) is already minutes of computing.
pub const MAX_SCENE_TIME_S: f64 = 3600.0;

/// Checks a `--time` argument: finite and in [0, [`MAX_SCENE_TIME_S`]] s.
pub fn check_time(time: f64) -> Result<f64, CliError> {
    if time.is_finite() && (0.0..=MAX_SCENE_TIME_S).contains(&time) {
        Ok(time)
    } else {
        Err(CliError::new(format!(
            "--time must lie in [0, 3600] s, got {time:?}"
        )))
    }
}

/// The image types `save_image` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageKind {
    Png,
    Exr,
}

/// The type of image `path` names by its extension (any case), if it is one `save_image` writes.
fn extension_kind(path: &Path) -> Option<ImageKind> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("png") => Some(ImageKind::Png),
        Some("exr") => Some(ImageKind::Exr),
        _ => None,
    }
}

/// The type of image `path` names by its extension (any case): `.png` or `.exr`.
pub fn image_kind(path: &Path) -> Result<ImageKind, CliError> {
    extension_kind(path).ok_or_else(|| {
        CliError::new(format!(
            "{}: unknown image type (use .png or .exr)",
            path.display()
        ))
    })
}

/// Saves a linear image as PNG (exposure, sRGB) or OpenEXR (linear float), by extension.
pub fn save_image(image: &LinearImage, path: &Path, exposure: f32) -> Result<(), CliError> {
    match image_kind(path)? {
        ImageKind::Png => image
            .save_png(path, exposure)
            .map_err(|e| CliError::new(format!("cannot write {}: {e}", path.display()))),
        ImageKind::Exr => save_exr_rgba(image, path),
    }
}

/// Whether `path` ends in `.png` (any case): the images written only as PNG check it before any work.
pub fn has_png_extension(path: &Path) -> bool {
    extension_kind(path) == Some(ImageKind::Png)
}

pub fn run_render(args: &RenderArgs) -> Result<(), CliError> {
    let time = args.time.map(check_time).transpose()?;
    // An image type `save_image` cannot write is refused before the scene is simulated and drawn.
    if let Some(out) = &args.out {
        image_kind(out)?;
        crate::output::check_output_file(out)?;
    }
    let scene = crate::load_scene(args.scene.as_deref())?;
    crate::output::interrupt::install();
    let mut renderer = FrameRenderer::new(&scene)?;
    let mut flag = FlagScene::new(scene)?;
    let exposure = renderer.exposure();
    let mut times = StageTimes::default();
    match (&args.out, &args.out_dir) {
        (Some(out), None) => {
            advance_to(&mut flag, time.unwrap_or(DEFAULT_FRAME_TIME_S))?;
            let image = renderer.render(&flag, &mut times)?;
            save_image(&image, out, exposure)?;
            eprintln!("wrote {} ({})", out.display(), renderer.adapter());
        }
        (None, Some(dir)) => {
            let frames = args.frames.unwrap_or(1);
            if frames == 0 {
                return Err(CliError::new("--frames must be ≥ 1"));
            }
            let names = FrameNames::new(frames, &["png", "exr"]);
            crate::output::prepare_sequence_folder(dir, &names, args.overwrite)?;
            let (png, exr) = (
                matches!(args.format, ImageFormat::Png | ImageFormat::Both),
                matches!(args.format, ImageFormat::Exr | ImageFormat::Both),
            );
            let sequence = Sequence {
                dir,
                names: &names,
                extension: if png { "png" } else { "exr" },
                frames,
                start: time.unwrap_or(0.0),
                verb: "rendering",
            };
            run_sequence(&mut flag, &sequence, &mut times, |flag, frame, times| {
                let image = renderer.render(flag, times)?;
                if png {
                    save_image(&image, &dir.join(names.name(frame, "png")), exposure)?;
                }
                if exr {
                    save_image(&image, &dir.join(names.name(frame, "exr")), exposure)?;
                }
                Ok(())
            })?;
            eprintln!(
                "wrote {frames} frames to {} ({})",
                dir.display(),
                renderer.adapter()
            );
        }
        _ => {
            return Err(CliError::new(
                "give --out FILE, or --frames N --out-dir DIR",
            ));
        }
    }
    Ok(())
}

#[derive(Debug, Args)]
pub struct Figure2Args {
    /// Output PNG.
    #[arg(long)]
    pub out: PathBuf,
    /// Scene file (TOML); default: the shipped default scene. The thin-slab panels always use the
    /// paper's single-scattering model with Λ = 1, τ1 = 2 (the scene's `shading.scattering`,
    /// `optical_thickness` and `albedo_scale` are not used for them).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Scene time at which the flag is captured, s, in [0, 3600].
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    pub time: f64,
    /// Also write the four panels as linear OpenEXR (RGBA, alpha = transmittance through the flag):
    /// baseline_back.exr, baseline_front.exr, thin_slab_back.exr, thin_slab_front.exr.
    #[arg(long)]
    pub linear_dir: Option<PathBuf>,
}

/// File stems of the panels, in [`figure2_panels`] order.
pub const PANEL_NAMES: [&str; 4] = [
    "baseline_back",
    "baseline_front",
    "thin_slab_back",
    "thin_slab_front",
];

/// Saves a linear image with its alpha (the transmittance) as RGBA OpenEXR.
pub fn save_exr_rgba(image: &LinearImage, path: &Path) -> Result<(), CliError> {
    let data: Vec<f32> = image.pixels.iter().flatten().copied().collect();
    let exr = image::Rgba32FImage::from_raw(image.width, image.height, data)
        .ok_or_else(|| CliError::new("internal: image size mismatch"))?;
    save_image_file(&exr, path, image::ImageFormat::OpenExr)
        .map_err(|e| CliError::new(format!("cannot write {}: {e}", path.display())))
}

/// Light angles (rad, 0 = on the camera's side) of the figure's two columns.
pub const BACK_LIT_PHASE: f32 = std::f32::consts::PI + 0.5;
pub const FRONT_LIT_PHASE: f32 = 0.6;

/// The four panels of figure 2, in reading order: (baseline, back-lit), (baseline, front-lit),
/// (thin-slab, back-lit), (thin-slab, front-lit), as linear images of the scene's size. The thin-slab
/// panels reproduce the paper: single scattering, Λ = 1, τ1 = 2, and no sky light, whatever the scene's
/// shading and environment say.
pub fn figure2_panels(scene: &Scene, time: f64) -> Result<[LinearImage; 4], CliError> {
    let mut scene = scene.clone();
    scene.light.period = 0.0; // the light holds still at each panel's angle
    scene.environment.sky_light = false; // the paper's scene: the point light alone
    let mut flag = FlagScene::new(scene.clone())?;
    advance_to(&mut flag, time)?;
    let mut panels = Vec::with_capacity(4);
    let mut renderer = FrameRenderer::new(&scene)?;
    for model in [ShadingModel::Baseline, ShadingModel::ThinSlab] {
        for phase in [BACK_LIT_PHASE, FRONT_LIT_PHASE] {
            flag.scene.shading.model = model;
            if model == ShadingModel::ThinSlab {
                // The paper's figure: its single-scattering model (eqs. (4)–(5)), Λ = 1, τ1 = 2.
                flag.scene.shading.scattering = ScatteringOrders::Single;
                flag.scene.shading.optical_thickness = [2.0; 3];
                flag.scene.shading.albedo_scale = [1.0; 3];
            }
            flag.scene.light.phase = phase;
            // Turn the normals toward this panel's light without moving the cloth.
            flag.update_normals()?;
            renderer.update_shading(&flag.scene)?;
            panels.push(renderer.render(&flag, &mut StageTimes::default())?);
        }
    }
    panels
        .try_into()
        .map_err(|_| CliError::new("internal: expected four panels"))
}

/// Draws `text` in white with a dark outline at (x, y) (top-left of the line), `size` pixels high.
pub fn draw_label(image: &mut RgbImage, text: &str, x: f32, y: f32, size: f32) {
    let Ok(font) = FontRef::try_from_slice(epaint_default_fonts::UBUNTU_LIGHT) else {
        return;
    };
    let scaled = font.as_scaled(PxScale::from(size));
    for (offset, colour) in [
        ((1.0, 1.0), Rgb::<u8>([0, 0, 0])),
        ((0.0, 0.0), Rgb::<u8>([255, 255, 255])),
    ] {
        let mut caret = x + offset.0;
        let baseline = y + offset.1 + scaled.ascent();
        let mut previous = None;
        for ch in text.chars() {
            let id = font.glyph_id(ch);
            if let Some(p) = previous {
                caret += scaled.kern(p, id);
            }
            let glyph = id.with_scale_and_position(size, ab_glyph::point(caret, baseline));
            caret += scaled.h_advance(id);
            previous = Some(id);
            if let Some(outlined) = font.outline_glyph(glyph) {
                let bounds = outlined.px_bounds();
                outlined.draw(|gx, gy, coverage| {
                    let px = bounds.min.x as i64 + i64::from(gx);
                    let py = bounds.min.y as i64 + i64::from(gy);
                    if px >= 0
                        && py >= 0
                        && (px as u32) < image.width()
                        && (py as u32) < image.height()
                    {
                        let pixel = image.get_pixel_mut(px as u32, py as u32);
                        for c in 0..3 {
                            let blended = f32::from(pixel[c]) * (1.0 - coverage)
                                + f32::from(colour[c]) * coverage;
                            pixel[c] = blended.round() as u8;
                        }
                    }
                });
            }
        }
    }
}

/// The panels' labels, in [`figure2_panels`] order: the baseline's α is the scene's
/// (`shading.baseline_alpha`); the thin-slab panels are always rendered with Λ = 1, τ1 = 2.
pub fn figure2_labels(baseline_alpha: f32) -> [String; 4] {
    [
        format!("baseline, α = {baseline_alpha} — back-lit"),
        format!("baseline, α = {baseline_alpha} — front-lit"),
        "thin slab, Λ = 1, τ₁ = 2 — back-lit".to_string(),
        "thin slab, Λ = 1, τ₁ = 2 — front-lit".to_string(),
    ]
}

/// The 2×2 figure with labels, as an sRGB image; `baseline_alpha` is the baseline panels' α.
pub fn figure2_image(panels: &[LinearImage; 4], exposure: f32, baseline_alpha: f32) -> RgbImage {
    let (w, h) = (panels[0].width, panels[0].height);
    let mut figure = RgbImage::new(2 * w, 2 * h);
    let labels = figure2_labels(baseline_alpha);
    for (k, panel) in panels.iter().enumerate() {
        let (ox, oy) = ((k as u32 % 2) * w, (k as u32 / 2) * h);
        let bytes = panel.to_srgb8(exposure);
        for y in 0..h {
            for x in 0..w {
                let i = 4 * (y * w + x) as usize;
                figure.put_pixel(ox + x, oy + y, Rgb([bytes[i], bytes[i + 1], bytes[i + 2]]));
            }
        }
        draw_label(
            &mut figure,
            &labels[k],
            ox as f32 + 10.0,
            oy as f32 + 8.0,
            (h as f32 / 20.0).max(12.0),
        );
    }
    figure
}

pub fn run_figure2(args: &Figure2Args) -> Result<(), CliError> {
    let time = check_time(args.time)?;
    // Checked before the four renders: the figure is an 8-bit labelled image.
    if !has_png_extension(&args.out) {
        return Err(CliError::new(format!(
            "--out {}: the figure is a PNG, so the file name must end in .png (linear panels: \
             --linear-dir)",
            args.out.display()
        )));
    }
    crate::output::check_output_file(&args.out)?;
    if let Some(dir) = &args.linear_dir {
        crate::output::create_output_dir(dir)?;
    }
    let scene = crate::load_scene(args.scene.as_deref())?;
    let panels = figure2_panels(&scene, time)?;
    if let Some(dir) = &args.linear_dir {
        for (panel, name) in panels.iter().zip(PANEL_NAMES) {
            save_exr_rgba(panel, &dir.join(format!("{name}.exr")))?;
        }
    }
    let figure = figure2_image(
        &panels,
        scene.shading.exposure,
        scene.shading.baseline_alpha,
    );
    save_image_file(&figure, &args.out, image::ImageFormat::Png)
        .map_err(|e| CliError::new(format!("cannot write {}: {e}", args.out.display())))?;
    eprintln!("wrote {}", args.out.display());
    Ok(())
}

#[cfg(test)]
mod label_tests {
    use super::*;

    #[test]
    fn the_baseline_labels_give_the_scenes_alpha() {
        let labels = figure2_labels(0.35);
        assert!(labels[0].contains("α = 0.35") && labels[1].contains("α = 0.35"));
        assert!(labels.iter().all(|l| !l.contains("α = 0.2")));
        assert_eq!(figure2_labels(0.2)[0], "baseline, α = 0.2 — back-lit");
    }

    #[test]
    fn figure2_thin_slab_panels_are_single_scattering_whatever_the_scene_says() {
        // The captions name the paper's model; an all-orders scene must not change the panels.
        let mut scene = Scene::builtin_default().unwrap();
        scene.render.width = 64;
        scene.render.height = 48;
        scene.shading.scattering = ScatteringOrders::Single;
        let single = figure2_panels(&scene, 0.1).unwrap();
        scene.shading.scattering = ScatteringOrders::All;
        let all_orders = figure2_panels(&scene, 0.1).unwrap();
        assert_eq!(single, all_orders);
    }

    #[test]
    fn scene_times_outside_an_hour_are_refused() {
        for time in [0.0, 2.0, 3600.0] {
            assert!(check_time(time).is_ok(), "{time}");
        }
        for time in [-5.0, -0.0001, 3600.5, 1e9, 1e300, f64::NAN, f64::INFINITY] {
            let error = check_time(time).unwrap_err().to_string();
            assert!(error.contains("--time"), "{error}");
        }
        // Past f32's range, echoed as written rather than as `inf`.
        let error = check_time(1e300).unwrap_err().to_string();
        assert!(error.ends_with("got 1e300"), "{error}");
    }
}
