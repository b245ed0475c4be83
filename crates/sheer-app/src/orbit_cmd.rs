//! `sheer orbit`: the flag over one revolution of the light, in the paper's model (single scattering,
//! the point light alone) and in the scene's own shading (by default all orders and sky light): a strip
//! of frames, the paper's on top, and per frame the share of cloth pixels that render near-black.
//!
//! "Near-black": a cloth pixel (one the flag covers, transmittance 0 < α < 1: not the opaque pole)
//! whose brightness — its largest channel of linear radiance, background seen through the cloth
//! included — is below 5 % of the median cloth brightness over the whole orbit, each model against its
//! own median. The largest channel, not the luminance: the flag's saturated blue stripes have 4 % of
//! the white's luminance in full daylight (Rec. 709 weighs blue by 0.07) without being black.

use std::path::PathBuf;

use clap::Args;
use image::{Rgb, RgbImage};
use sheer_slab::render::LinearImage;

use crate::frame::{FlagScene, FrameRenderer, StageTimes};
use crate::render_cmd::draw_label;
use crate::scene::Scene;
use crate::{CliError, outln};
use sheer_slab::ScatteringOrders;

#[derive(Debug, Args)]
pub struct OrbitArgs {
    /// Scene file (TOML); default: the shipped default scene. Its light must orbit (`light.period` ≠ 0).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// The strip (PNG): the paper's model on top, the scene's shading below.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Frames in the strip, evenly over the orbit.
    #[arg(long, default_value_t = 6, allow_negative_numbers = true)]
    pub frames: u32,
    /// Frames measured, evenly over the orbit (the strip's frames among them when this is a multiple).
    #[arg(long, default_value_t = 48, allow_negative_numbers = true)]
    pub samples: u32,
    /// Scene time at which the orbit starts, s, in [0, 3600] (the flag is simulated up to it).
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    pub time: f64,
}

/// A cloth pixel below this fraction of the orbit's median cloth brightness counts as near-black.
pub const DARK_FRACTION: f64 = 0.05;

/// A pixel's brightness: its largest channel of linear radiance, W/(m²·sr).
fn brightness(pixel: &[f32; 4]) -> f64 {
    f64::from(pixel[0].max(pixel[1]).max(pixel[2]))
}

/// Whether a pixel shows cloth: the layers' transmittance α lies in (0, 1); the opaque pole is drawn
/// with α = 0, the background alone has α = 1.
fn is_cloth(pixel: &[f32; 4]) -> bool {
    pixel[3] > 0.0 && pixel[3] < 1.0
}

/// Per frame, the share of cloth pixels darker than [`DARK_FRACTION`] of the median cloth brightness
/// over all `frames`; with that median.
pub fn near_black_shares(frames: &[LinearImage]) -> (Vec<f64>, f64) {
    let mut all: Vec<f64> = frames
        .iter()
        .flat_map(|f| f.pixels.iter().filter(|p| is_cloth(p)).map(brightness))
        .collect();
    if all.is_empty() {
        return (vec![0.0; frames.len()], 0.0);
    }
    all.sort_by(f64::total_cmp);
    let median = all[all.len() / 2];
    let shares = frames
        .iter()
        .map(|f| {
            let cloth: Vec<f64> = f
                .pixels
                .iter()
                .filter(|p| is_cloth(p))
                .map(brightness)
                .collect();
            let dark = cloth
                .iter()
                .filter(|&&l| l < DARK_FRACTION * median)
                .count();
            dark as f64 / cloth.len().max(1) as f64
        })
        .collect();
    (shares, median)
}

/// The paper's shading of `scene`: single scattering and the point light alone.
pub fn paper_model(scene: &Scene) -> Scene {
    let mut paper = scene.clone();
    paper.shading.scattering = ScatteringOrders::Single;
    paper.environment.sky_light = false;
    paper
}

/// Frames over one orbit of the light, the same flag in both models.
pub struct Orbit {
    /// The paper's model.
    pub paper: Vec<LinearImage>,
    /// The scene's own shading.
    pub scene: Vec<LinearImage>,
    /// Scene time of each frame, s.
    pub times: Vec<f64>,
}

/// Renders `samples` frames over one orbit of the light from `time`, in the paper's model and in the
/// scene's shading.
pub fn render_orbit(scene: &Scene, time: f64, samples: u32) -> Result<Orbit, CliError> {
    let period = f64::from(scene.light.period).abs();
    if period == 0.0 {
        return Err(CliError::new(
            "scene: `light.period` is 0: the light does not orbit",
        ));
    }
    let mut flag = FlagScene::new(scene.clone())?;
    crate::sequence::advance_to(&mut flag, time)?;
    let paper_scene = paper_model(scene);
    let mut paper_renderer = FrameRenderer::new(&paper_scene)?;
    let mut renderer = FrameRenderer::new(scene)?;
    let (mut paper, mut own, mut times) = (Vec::new(), Vec::new(), Vec::new());
    let mut stages = StageTimes::default();
    for k in 0..samples {
        let target = time + period * f64::from(k) / f64::from(samples);
        crate::sequence::advance_to(&mut flag, target)?;
        own.push(renderer.render(&flag, &mut stages)?);
        // The same flag, seen in the paper's model (the renderer holds the shading; the scene's path,
        // camera and light are the same).
        paper.push(paper_renderer.render(&flag, &mut stages)?);
        times.push(flag.time());
    }
    Ok(Orbit {
        paper,
        scene: own,
        times,
    })
}

pub fn run(args: &OrbitArgs) -> Result<(), CliError> {
    let time = crate::render_cmd::check_time(args.time)?;
    if args.frames == 0 || args.samples == 0 {
        return Err(CliError::new("--frames and --samples must be ≥ 1"));
    }
    if let Some(out) = &args.out {
        if !crate::render_cmd::has_png_extension(out) {
            return Err(CliError::new(format!(
                "--out {}: the strip is a PNG, so the file name must end in .png",
                out.display()
            )));
        }
        crate::output::check_output_file(out)?;
    }
    crate::output::interrupt::install();
    let scene = crate::load_scene(args.scene.as_deref())?;
    let Orbit {
        paper,
        scene: own,
        times,
    } = render_orbit(&scene, time, args.samples)?;
    let (paper_shares, paper_median) = near_black_shares(&paper);
    let (own_shares, own_median) = near_black_shares(&own);
    outln!(
        "near-black cloth pixels (brightest channel < {} % of the orbit's median), per frame over one orbit",
        100.0 * DARK_FRACTION
    )?;
    outln!("time_s,paper_model,scene_shading")?;
    for ((t, p), o) in times.iter().zip(&paper_shares).zip(&own_shares) {
        outln!("{t:?},{p:?},{o:?}")?;
    }
    let worst = |shares: &[f64]| shares.iter().copied().fold(0.0, f64::max);
    outln!(
        "worst frame: paper's model {:.2} % (median brightness {paper_median:.4}), scene's shading \
         {:.2} % (median {own_median:.4})",
        100.0 * worst(&paper_shares),
        100.0 * worst(&own_shares)
    )?;
    if let Some(out) = &args.out {
        let step = args.samples as f64 / f64::from(args.frames);
        let picks: Vec<usize> = (0..args.frames)
            .map(|k| ((f64::from(k) * step).round() as usize).min(own.len() - 1))
            .collect();
        let label = format!(
            "this scene: {}{}",
            match scene.shading.scattering {
                ScatteringOrders::All => "all orders",
                ScatteringOrders::Single => "single scattering",
            },
            if scene.environment.sky_light {
                " + sky"
            } else {
                ""
            }
        );
        let strip = strip_image(&paper, &own, &picks, &times, scene.shading.exposure, &label);
        sheer_slab::render::save_image_file(&strip, out, image::ImageFormat::Png)
            .map_err(|e| CliError::new(format!("cannot write {}: {e}", out.display())))?;
        eprintln!("wrote {}", out.display());
    }
    Ok(())
}

/// Frames `picks` of both rows side by side at half size, the paper's model on top, labelled.
fn strip_image(
    paper: &[LinearImage],
    own: &[LinearImage],
    picks: &[usize],
    times: &[f64],
    exposure: f32,
    own_label: &str,
) -> RgbImage {
    let (w, h) = (paper[0].width / 2, paper[0].height / 2);
    let mut strip = RgbImage::new(w * picks.len() as u32, 2 * h);
    for (column, &k) in picks.iter().enumerate() {
        for (row, frame) in [&paper[k], &own[k]].into_iter().enumerate() {
            let bytes = frame.to_srgb8(exposure);
            let full = frame.width;
            for y in 0..h {
                for x in 0..w {
                    // A 2 × 2 box filter of the sRGB bytes.
                    let mut sum = [0u32; 3];
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let i = 4 * ((2 * y + dy) * full + 2 * x + dx) as usize;
                        for c in 0..3 {
                            sum[c] += u32::from(bytes[i + c]);
                        }
                    }
                    let pixel = Rgb(sum.map(|s| ((s + 2) / 4) as u8));
                    strip.put_pixel(column as u32 * w + x, row as u32 * h + y, pixel);
                }
            }
        }
        let label = format!("t = {:.1} s", times[k]);
        draw_label(
            &mut strip,
            &label,
            column as f32 * w as f32 + 6.0,
            4.0,
            14.0,
        );
    }
    draw_label(&mut strip, "paper's model", 6.0, h as f32 - 20.0, 14.0);
    draw_label(&mut strip, own_label, 6.0, 2.0 * h as f32 - 20.0, 14.0);
    strip
}
