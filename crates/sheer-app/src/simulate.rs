//! `sheer simulate`: runs a scene's flag simulation and writes the mesh of every frame as Wavefront OBJ
//! (positions in metres, texture coordinates of the flag, triangles), for use in other tools.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::Args;
use sheer_cloth::{ClothModel, Simulation};

use crate::CliError;
use crate::scene::Scene;

#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Scene file (TOML); default: the shipped default scene.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Number of frames to simulate and write (1/fps seconds each).
    #[arg(long, default_value_t = 60, allow_negative_numbers = true)]
    pub frames: u32,
    /// Directory for frame_0000.obj, frame_0001.obj, … (created if missing).
    #[arg(long)]
    pub out_dir: PathBuf,
}

/// The flag of a scene, hoist edge pinned.
pub fn flag_simulation(scene: &Scene) -> Result<Simulation, CliError> {
    let model = ClothModel::grid(&scene.flag).and_then(|m| m.with_hoist_pinned())?;
    Ok(Simulation::new(model, scene.simulation.clone())?)
}

/// Texture coordinates of grid particles: u along the flag from the hoist, v down from the top.
pub fn grid_uvs(columns: usize, rows: usize) -> Vec<[f32; 2]> {
    (0..rows)
        .flat_map(|row| {
            (0..columns).map(move |column| {
                [
                    column as f32 / (columns - 1) as f32,
                    row as f32 / (rows - 1) as f32,
                ]
            })
        })
        .collect()
}

/// One frame as OBJ text.
pub fn obj_text(sim: &Simulation, uvs: &[[f32; 2]], frame: u32) -> String {
    let mut text = String::with_capacity(64 * sim.particle_count());
    let _ = writeln!(
        text,
        "# sheer frame {frame}, t = {:.6} s, {} particles",
        sim.time(),
        sim.particle_count()
    );
    for p in sim.positions() {
        let _ = writeln!(text, "v {:.7} {:.7} {:.7}", p.x, p.y, p.z);
    }
    for uv in uvs {
        // OBJ's v runs upward.
        let _ = writeln!(text, "vt {:.7} {:.7}", uv[0], 1.0 - uv[1]);
    }
    for tri in sim.triangles() {
        let [a, b, c] = tri.map(|i| i + 1);
        let _ = writeln!(text, "f {a}/{a} {b}/{b} {c}/{c}");
    }
    text
}

fn write(path: &Path, text: &str) -> Result<(), CliError> {
    std::fs::write(path, text)
        .map_err(|e| CliError::new(format!("cannot write {}: {e}", path.display())))
}

pub fn run(args: &SimulateArgs) -> Result<(), CliError> {
    let scene = crate::load_scene(args.scene.as_deref())?;
    if scene.static_sheet.is_some() {
        return Err(CliError::new(
            "the scene describes a static sheet: there is nothing to simulate",
        ));
    }
    if args.frames == 0 {
        return Err(CliError::new("--frames must be ≥ 1"));
    }
    crate::create_output_dir(&args.out_dir)?;
    let mut sim = flag_simulation(&scene)?;
    let uvs = grid_uvs(scene.flag.columns, scene.flag.rows);
    let dt = 1.0 / f64::from(scene.render.fps);
    let progress = crate::progress_bar(u64::from(args.frames), "simulating");
    for frame in 0..args.frames {
        sim.step(dt).map_err(|e| {
            CliError::new(format!("frame {frame}: {}", crate::frame::step_failure(&e)))
        })?;
        write(
            &args.out_dir.join(format!("frame_{frame:04}.obj")),
            &obj_text(&sim, &uvs, frame),
        )?;
        progress.inc(1);
    }
    progress.finish_and_clear();
    eprintln!(
        "wrote {} frames of {} particles to {}",
        args.frames,
        sim.particle_count(),
        args.out_dir.display()
    );
    Ok(())
}
