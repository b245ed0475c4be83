//! `sheer bench render`: frames per second of the whole case study per evaluation path, with single
//! scattering (the paper) and with all orders (the table), and for the baseline, at the scene's size
//! (512 × 512 by default), with the time of each stage, in one run. The cases are measured in
//! interleaved rounds, so that drift of the machine's load affects them alike; each all-orders case is
//! also compared with single scattering on the same path round by round (median of the per-round
//! frame-time ratios). The shading stage's time is split as the window's panel splits it: the part
//! from submitting the frame to the GPU until it has finished (`gpu_ms`; on a software rasteriser the
//! drawing itself) and the rest, CPU work (evaluation, sorting, uploads, checks).

use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;

use crate::frame::{FlagScene, FrameRenderer, StageTimes};
use crate::scene::{AllOrdersLookup, EvaluationPathName, Scattering, ShadingModel};
use crate::{CliError, outln};

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
    path: EvaluationPathName,
    scattering: Scattering,
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
    use AllOrdersLookup::{Fragment as TablePerFragment, Vertex as TablePerVertex};
    use EvaluationPathName::{Cpu, Fragment, Vertex};
    use Scattering::{AllOrders, Single};
    use ShadingModel::{Baseline, ThinSlab};
    // (name, model, path, scattering, where the fragment path looks the all-orders table up).
    let cases = [
        ("fragment", ThinSlab, Fragment, Single, TablePerFragment),
        (
            "fragment/all-orders",
            ThinSlab,
            Fragment,
            AllOrders,
            TablePerFragment,
        ),
        // The per-fragment path with the table looked up once per vertex (`all_orders_lookup`).
        (
            "fragment/all-orders/table@vertex",
            ThinSlab,
            Fragment,
            AllOrders,
            TablePerVertex,
        ),
        ("vertex", ThinSlab, Vertex, Single, TablePerFragment),
        (
            "vertex/all-orders",
            ThinSlab,
            Vertex,
            AllOrders,
            TablePerFragment,
        ),
        ("cpu", ThinSlab, Cpu, Single, TablePerFragment),
        ("cpu/all-orders", ThinSlab, Cpu, AllOrders, TablePerFragment),
        ("baseline", Baseline, Fragment, Single, TablePerFragment),
    ];
    let mut rows: Vec<Row> = cases
        .iter()
        .map(|&(name, _, path, scattering, _)| Row {
            name,
            path,
            scattering,
            frames: 0,
            total: Duration::ZERO,
            stages: StageTimes::default(),
            rounds: Vec::new(),
        })
        .collect();
    let select =
        |renderer: &mut FrameRenderer, flag: &mut FlagScene, case: usize| -> Result<(), CliError> {
            let (_, model, path, scattering, lookup) = cases[case];
            flag.scene.shading.model = model;
            flag.scene.shading.path = path;
            let shading = &mut flag.scene.shading;
            if shading.scattering != scattering || shading.all_orders_lookup != lookup {
                shading.scattering = scattering;
                shading.all_orders_lookup = lookup;
                renderer.update_shading(&flag.scene)?;
            }
            Ok(())
        };
    // Warm-up: pipelines compile and the table uploads on first use.
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
                row.stages.readback += times.readback;
            }
            let elapsed = start.elapsed();
            row.total += elapsed;
            row.frames += FRAMES_PER_ROUND;
            row.rounds
                .push(elapsed.as_secs_f64() / f64::from(FRAMES_PER_ROUND));
        }
    }
    let (w, h) = (flag.scene.render.width, flag.scene.render.height);
    let per_frame = |d: Duration, n: u32| d.as_secs_f64() * 1e3 / f64::from(n);
    let baseline_fps = {
        let b = rows.last().expect("eight rows");
        f64::from(b.frames) / b.total.as_secs_f64()
    };
    // Median over rounds of this row's frame time over single scattering's on the same path.
    let against_single = |row: &Row| -> Option<f64> {
        let single = rows
            .iter()
            .find(|r| r.path == row.path && r.scattering == Single && r.name != "baseline")?;
        if row.scattering != AllOrders {
            return None;
        }
        let mut ratios: Vec<f64> = row
            .rounds
            .iter()
            .zip(&single.rounds)
            .map(|(a, s)| a / s)
            .collect();
        ratios.sort_by(f64::total_cmp);
        let n = ratios.len();
        Some(0.5 * (ratios[(n - 1) / 2] + ratios[n / 2]))
    };
    if args.csv {
        outln!(
            "path,width,height,fps,ratio_to_baseline,ratio_to_single,simulation_ms,normals_ms,shading_gpu_ms,gpu_ms,readback_ms"
        )?;
    } else {
        outln!("adapter: {}", renderer.adapter())?;
        outln!(
            "{:<30} {:>9} {:>8} {:>9} {:>7} {:>14} {:>11} {:>13} {:>12} {:>12}",
            "path",
            "size",
            "fps",
            "×baseline",
            "×single",
            "simulation ms",
            "normals ms",
            "shading+GPU ms",
            "of which GPU",
            "read-back ms"
        )?;
    }
    for row in &rows {
        let fps = f64::from(row.frames) / row.total.as_secs_f64();
        let values = (
            per_frame(row.stages.simulation, row.frames),
            per_frame(row.stages.normals, row.frames),
            per_frame(row.stages.shading, row.frames),
            per_frame(row.stages.gpu, row.frames),
            per_frame(row.stages.readback, row.frames),
        );
        let single = against_single(row);
        if args.csv {
            // CSV numbers in their shortest round-trip form.
            outln!(
                "{},{w},{h},{fps:?},{:?},{},{:?},{:?},{:?},{:?},{:?}",
                row.name,
                baseline_fps / fps,
                single.map_or(String::new(), |r| format!("{r:?}")),
                values.0,
                values.1,
                values.2,
                values.3,
                values.4
            )?;
        } else {
            outln!(
                "{:<30} {:>9} {:>8.1} {:>9.2} {:>7} {:>14.2} {:>11.2} {:>13.2} {:>12.2} {:>12.2}",
                row.name,
                format!("{w}x{h}"),
                fps,
                baseline_fps / fps,
                single.map_or("-".to_string(), |r| format!("{r:.2}")),
                values.0,
                values.1,
                values.2,
                values.3,
                values.4
            )?;
        }
    }
    if !args.csv {
        outln!(
            "×baseline: frame time relative to the baseline's (cost ratio; 1.00 = as fast). ×single: \
             all orders against single scattering on the same path, median of per-round ratios."
        )?;
    }
    Ok(())
}
