//! `sheer bench render`: frames per second of the whole case study per evaluation path, with single
//! scattering (the paper) and with all orders (the table), with and without sky light, with translucent
//! shadows, and for the baseline, at the scene's size (512 × 512 by default), with the time of each stage, in one run. The
//! cases are measured in interleaved rounds, so that drift of the machine's load affects them alike;
//! each case is compared with the paper's model on the fragment path round by round (median of the
//! per-round frame-time ratios), and its image with the most exact case (all orders and sky light,
//! the table looked up in every fragment, no shadows) on the same flag under four light directions: the
//! mean and 95th percentile of the relative error of the radiance seen in the cloth's pixels (for the
//! shadowed cases: what the shadows change). The cost and the error
//! of each case are what the default's choice rests on (docs/shading-model.md). The shading stage's time
//! is split as the window's panel splits it: the part from submitting the frame to the GPU until it
//! has finished (`gpu_ms`; on a software rasteriser the drawing itself) and the rest, CPU work
//! (evaluation, sorting, uploads, checks); of the GPU's part, the passes before the draw (the shadow
//! map from the light, uploads) are submitted and timed on their own (`shadow_ms`).

use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;

use sheer_slab::render::LinearImage;

use crate::frame::{FlagScene, FrameRenderer, StageTimes};
use crate::scene::ShadingModel;
use crate::{CliError, outln};
use sheer_slab::ScatteringOrders;
use sheer_slab::render::{AllOrdersSampling, EvaluationPath};

#[derive(Debug, Args)]
pub struct BenchRenderArgs {
    /// Scene file (TOML); default: the shipped default scene.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Minimum measuring time per case, seconds, in [0, 3600].
    #[arg(long, default_value_t = 3.0, allow_negative_numbers = true)]
    pub seconds: f64,
    /// Print CSV instead of a table.
    #[arg(long)]
    pub csv: bool,
}

struct Row {
    name: &'static str,
    frames: u32,
    total: Duration,
    stages: StageTimes,
    /// Mean frame time of each round, s.
    rounds: Vec<f64>,
}

/// Frames per case per round of the interleaved measurement.
const FRAMES_PER_ROUND: u32 = 3;

pub fn run(args: &BenchRenderArgs) -> Result<(), CliError> {
    crate::bench_sim::check_seconds(args.seconds)?;
    let scene = crate::load_scene(args.scene.as_deref())?;
    let mut renderer = FrameRenderer::new(&scene)?;
    let mut flag = FlagScene::new(scene)?;
    use AllOrdersSampling::{PerFragment as TablePerFragment, PerVertex as TablePerVertex};
    use EvaluationPath::{Cpu, PerFragment as Fragment, PerVertex as Vertex};
    use ScatteringOrders::{All as AllOrders, Single};
    use ShadingModel::{Baseline, ThinSlab};
    // (name, model, path, scattering, where the fragment path looks the all-orders table up, sky light,
    // shadows).
    let cases = [
        // The paper's model: the cost every other case is compared with.
        (
            "fragment",
            ThinSlab,
            Fragment,
            Single,
            TablePerFragment,
            false,
            false,
        ),
        (
            "fragment/all-orders",
            ThinSlab,
            Fragment,
            AllOrders,
            TablePerFragment,
            false,
            false,
        ),
        (
            "fragment/single+sky",
            ThinSlab,
            Fragment,
            Single,
            TablePerFragment,
            true,
            false,
        ),
        // The most exact case: the images of the others are compared with its.
        (
            "fragment/all-orders+sky",
            ThinSlab,
            Fragment,
            AllOrders,
            TablePerFragment,
            true,
            false,
        ),
        // The table looked up once per vertex (`all_orders_lookup`).
        (
            "fragment/all-orders/table@vertex+sky",
            ThinSlab,
            Fragment,
            AllOrders,
            TablePerVertex,
            true,
            false,
        ),
        (
            "vertex",
            ThinSlab,
            Vertex,
            Single,
            TablePerFragment,
            false,
            false,
        ),
        (
            "vertex/all-orders+sky",
            ThinSlab,
            Vertex,
            AllOrders,
            TablePerFragment,
            true,
            false,
        ),
        ("cpu", ThinSlab, Cpu, Single, TablePerFragment, false, false),
        (
            "cpu/all-orders+sky",
            ThinSlab,
            Cpu,
            AllOrders,
            TablePerFragment,
            true,
            false,
        ),
        // Translucent shadows (the default): their cost against the same case without, and in
        // `error` what they change in the picture.
        (
            "fragment/all-orders+sky+shadows",
            ThinSlab,
            Fragment,
            AllOrders,
            TablePerFragment,
            true,
            true,
        ),
        (
            "vertex/all-orders+sky+shadows",
            ThinSlab,
            Vertex,
            AllOrders,
            TablePerFragment,
            true,
            true,
        ),
        (
            "cpu/all-orders+sky+shadows",
            ThinSlab,
            Cpu,
            AllOrders,
            TablePerFragment,
            true,
            true,
        ),
        (
            "baseline",
            Baseline,
            Fragment,
            Single,
            TablePerFragment,
            false,
            false,
        ),
    ];
    const PAPER: usize = 0;
    const EXACT: usize = 3;
    const VERTEX_SHADOWS: usize = 10;
    const CPU_SHADOWS: usize = 11;
    let mut rows: Vec<Row> = cases
        .iter()
        .map(|&(name, ..)| Row {
            name,
            frames: 0,
            total: Duration::ZERO,
            stages: StageTimes::default(),
            rounds: Vec::new(),
        })
        .collect();
    let select =
        |renderer: &mut FrameRenderer, flag: &mut FlagScene, case: usize| -> Result<(), CliError> {
            let (_, model, path, scattering, lookup, sky, shadows) = cases[case];
            flag.scene.shading.model = model;
            flag.scene.shading.path = path;
            let scene = &mut flag.scene;
            if scene.shading.scattering != scattering
                || scene.shading.all_orders_lookup != lookup
                || scene.environment.sky_light != sky
                || scene.shading.shadows != shadows
            {
                scene.shading.scattering = scattering;
                scene.shading.all_orders_lookup = lookup;
                scene.environment.sky_light = sky;
                scene.shading.shadows = shadows;
                renderer.update_shading(&flag.scene)?;
            }
            Ok(())
        };
    // Warm-up: pipelines compile and the tables upload on first use.
    for case in 0..cases.len() {
        select(&mut renderer, &mut flag, case)?;
        for _ in 0..3 {
            flag.advance_frame(&mut StageTimes::default())?;
            renderer.render(&flag, &mut StageTimes::default())?;
        }
    }
    while rows
        .iter()
        .any(|row| row.frames < 5 || row.total.as_secs_f64() < args.seconds)
    {
        for (case, row) in rows.iter_mut().enumerate() {
            select(&mut renderer, &mut flag, case)?;
            let start = Instant::now();
            for _ in 0..FRAMES_PER_ROUND {
                let mut times = StageTimes::default();
                flag.advance_frame(&mut times)?;
                renderer.render(&flag, &mut times)?;
                row.stages.simulation += times.simulation;
                row.stages.normals += times.normals;
                row.stages.shading += times.shading;
                row.stages.gpu += times.gpu;
                row.stages.shadow += times.shadow;
                row.stages.readback += times.readback;
            }
            let elapsed = start.elapsed();
            row.total += elapsed;
            row.frames += FRAMES_PER_ROUND;
            row.rounds
                .push(elapsed.as_secs_f64() / f64::from(FRAMES_PER_ROUND));
        }
    }
    // Each case's image against the most exact one's, on the same flag, the light turned by quarter
    // turns.
    let mut errors = vec![Vec::new(); cases.len()];
    // The shadow map's own error: the vertex path against the CPU path (ray casting), shadows on both;
    // without shadows the two agree to rounding, so what differs is the map.
    let mut map_errors = Vec::new();
    let phase = flag.scene.light.phase;
    for quarter in 0..4 {
        flag.scene.light.phase = phase + std::f32::consts::FRAC_PI_2 * quarter as f32;
        flag.update_normals()?;
        select(&mut renderer, &mut flag, EXACT)?;
        let exact = renderer.render(&flag, &mut StageTimes::default())?;
        let mut images = Vec::new();
        for (case, error) in errors.iter_mut().enumerate() {
            select(&mut renderer, &mut flag, case)?;
            let image = renderer.render(&flag, &mut StageTimes::default())?;
            error.extend(relative_errors(&image, &exact));
            images.push(image);
        }
        map_errors.extend(relative_errors(
            &images[VERTEX_SHADOWS],
            &images[CPU_SHADOWS],
        ));
    }
    let p95: Vec<f64> = errors.iter_mut().map(|e| percentile(e, 0.95)).collect();
    let means: Vec<f64> = errors
        .iter()
        .map(|e| e.iter().sum::<f64>() / e.len().max(1) as f64)
        .collect();
    let (w, h) = (flag.scene.render.width, flag.scene.render.height);
    let per_frame = |d: Duration, n: u32| d.as_secs_f64() * 1e3 / f64::from(n);
    let baseline_fps = {
        let b = rows.last().expect("the baseline row");
        f64::from(b.frames) / b.total.as_secs_f64()
    };
    // Median over rounds of this row's frame time over the paper's model's.
    let against_paper = |row: &Row| -> f64 {
        let mut ratios: Vec<f64> = row
            .rounds
            .iter()
            .zip(&rows[PAPER].rounds)
            .map(|(a, s)| a / s)
            .collect();
        percentile(&mut ratios, 0.5)
    };
    if args.csv {
        outln!(
            "path,width,height,fps,ratio_to_baseline,ratio_to_paper,error_mean,error_p95,simulation_ms,normals_ms,shading_gpu_ms,gpu_ms,shadow_ms,readback_ms"
        )?;
    } else {
        outln!("adapter: {}", renderer.adapter())?;
        outln!(
            "{:<38} {:>9} {:>7} {:>9} {:>7} {:>8} {:>9} {:>8} {:>8} {:>10} {:>10} {:>8} {:>10}",
            "path",
            "size",
            "fps",
            "×baseline",
            "×paper",
            "err mean",
            "error p95",
            "sim. ms",
            "normals",
            "shade+GPU",
            "of it GPU",
            "shadow",
            "read-back"
        )?;
    }
    for ((row, error), mean) in rows.iter().zip(&p95).zip(&means) {
        let fps = f64::from(row.frames) / row.total.as_secs_f64();
        let values = (
            per_frame(row.stages.simulation, row.frames),
            per_frame(row.stages.normals, row.frames),
            per_frame(row.stages.shading, row.frames),
            per_frame(row.stages.gpu, row.frames),
            per_frame(row.stages.shadow, row.frames),
            per_frame(row.stages.readback, row.frames),
        );
        let paper = against_paper(row);
        if args.csv {
            // CSV numbers in their shortest round-trip form.
            outln!(
                "{},{w},{h},{fps:?},{:?},{paper:?},{mean:?},{error:?},{:?},{:?},{:?},{:?},{:?},{:?}",
                row.name,
                baseline_fps / fps,
                values.0,
                values.1,
                values.2,
                values.3,
                values.4,
                values.5
            )?;
        } else {
            outln!(
                "{:<38} {:>9} {:>7.1} {:>9.2} {:>7.2} {:>7.1}% {:>8.1}% {:>8.2} {:>8.2} {:>10.2} {:>10.2} {:>8.2} {:>10.2}",
                row.name,
                format!("{w}x{h}"),
                fps,
                baseline_fps / fps,
                paper,
                100.0 * mean,
                100.0 * error,
                values.0,
                values.1,
                values.2,
                values.3,
                values.4,
                values.5
            )?;
        }
    }
    if !args.csv {
        outln!(
            "×baseline: frame time relative to the baseline's (1.00 = as fast). ×paper: relative to the \
             paper's model on the fragment path, median of per-round ratios. err mean, error p95: mean \
             and 95th percentile over the cloth's pixels of the relative error of the radiance seen, \
             against fragment/all-orders+sky (no shadows), four light directions. shadow: the GPU's \
             time for the passes before the draw (the shadow map; uploads)."
        )?;
        // The median, not the mean: a pixel the ray caster finds almost black makes any relative error
        // huge.
        outln!(
            "shadow map against ray casting (vertex vs cpu, shadows on, four light directions): median \
             {:.2}%, p95 {:.2}% of the cloth's pixels",
            100.0 * percentile(&mut map_errors, 0.5),
            100.0 * percentile(&mut map_errors, 0.95)
        )?;
    }
    Ok(())
}

/// Per cloth pixel (covered in either image: α < 1), the relative difference of the linear radiance
/// seen (luminance, Rec. 709) from `exact`'s.
fn relative_errors(image: &LinearImage, exact: &LinearImage) -> Vec<f64> {
    let luminance = |p: &[f32; 4]| {
        0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
    };
    image
        .pixels
        .iter()
        .zip(&exact.pixels)
        .filter(|(a, b)| a[3] < 1.0 || b[3] < 1.0)
        .map(|(a, b)| {
            let reference = luminance(b);
            (luminance(a) - reference).abs() / reference.max(1e-6)
        })
        .collect()
}

/// The `fraction` quantile of `values` (nearest rank); 0 for none.
fn percentile(values: &mut [f64], fraction: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let rank = ((fraction * values.len() as f64).ceil() as usize).clamp(1, values.len());
    values[rank - 1]
}
