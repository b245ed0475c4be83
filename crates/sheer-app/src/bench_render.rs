//! `sheer bench render`: frames per second of the whole case study per evaluation path and for the
//! baseline, at the scene's size (512 × 512 by default), with the time of each stage, in one run.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;

use crate::CliError;
use crate::frame::{FlagScene, FrameRenderer, StageTimes};
use crate::scene::{EvaluationPathName, ShadingModel};

#[derive(Debug, Args)]
pub struct BenchRenderArgs {
    /// Scene file (TOML); default: the shipped default scene.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Minimum measuring time per path, seconds.
    #[arg(long, default_value_t = 3.0)]
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
}

pub fn run(args: &BenchRenderArgs) -> Result<(), CliError> {
    if !(args.seconds.is_finite() && args.seconds >= 0.0) {
        return Err(CliError::new(format!(
            "--seconds must be ≥ 0, got {}",
            args.seconds
        )));
    }
    let scene = crate::load_scene(args.scene.as_deref())?;
    let mut renderer = FrameRenderer::new(&scene)?;
    let mut flag = FlagScene::new(scene)?;
    let dt = 1.0 / flag.scene.render.fps;
    let cases = [
        (
            "fragment",
            ShadingModel::ThinSlab,
            EvaluationPathName::Fragment,
        ),
        ("vertex", ShadingModel::ThinSlab, EvaluationPathName::Vertex),
        ("cpu", ShadingModel::ThinSlab, EvaluationPathName::Cpu),
        (
            "baseline",
            ShadingModel::Baseline,
            EvaluationPathName::Fragment,
        ),
    ];
    let mut rows = Vec::new();
    for (name, model, path) in cases {
        flag.scene.shading.model = model;
        flag.scene.shading.path = path;
        let mut stages = StageTimes::default();
        // Warm-up: pipelines compile on first use.
        for _ in 0..3 {
            flag.advance(dt, &mut StageTimes::default())?;
            renderer.render(&flag, &mut StageTimes::default())?;
        }
        let start = Instant::now();
        let mut frames = 0;
        while frames < 5 || start.elapsed().as_secs_f64() < args.seconds {
            let mut times = StageTimes::default();
            flag.advance(dt, &mut times)?;
            renderer.render(&flag, &mut times)?;
            stages.simulation += times.simulation;
            stages.normals += times.normals;
            stages.shading += times.shading;
            stages.readback += times.readback;
            frames += 1;
        }
        rows.push(Row {
            name,
            frames,
            total: start.elapsed(),
            stages,
        });
    }
    let (w, h) = (flag.scene.render.width, flag.scene.render.height);
    let per_frame = |d: Duration, n: u32| d.as_secs_f64() * 1e3 / f64::from(n);
    let baseline_fps = {
        let b = rows.last().expect("four rows");
        f64::from(b.frames) / b.total.as_secs_f64()
    };
    if args.csv {
        println!(
            "path,width,height,fps,ratio_to_baseline,simulation_ms,normals_ms,shading_gpu_ms,readback_ms"
        );
    } else {
        println!("adapter: {}", renderer.adapter());
        println!(
            "{:<9} {:>9} {:>8} {:>9} {:>14} {:>11} {:>13} {:>12}",
            "path",
            "size",
            "fps",
            "×baseline",
            "simulation ms",
            "normals ms",
            "shading+GPU ms",
            "read-back ms"
        );
    }
    for row in &rows {
        let fps = f64::from(row.frames) / row.total.as_secs_f64();
        let values = (
            per_frame(row.stages.simulation, row.frames),
            per_frame(row.stages.normals, row.frames),
            per_frame(row.stages.shading, row.frames),
            per_frame(row.stages.readback, row.frames),
        );
        if args.csv {
            println!(
                "{},{w},{h},{fps:.2},{:.3},{:.3},{:.3},{:.3},{:.3}",
                row.name,
                baseline_fps / fps,
                values.0,
                values.1,
                values.2,
                values.3
            );
        } else {
            println!(
                "{:<9} {:>9} {:>8.1} {:>9.2} {:>14.2} {:>11.2} {:>13.2} {:>12.2}",
                row.name,
                format!("{w}x{h}"),
                fps,
                baseline_fps / fps,
                values.0,
                values.1,
                values.2,
                values.3
            );
        }
    }
    if !args.csv {
        println!("×baseline: frame time relative to the baseline's (cost ratio; 1.00 = as fast).");
    }
    Ok(())
}
