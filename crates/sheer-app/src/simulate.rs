//! `sheer simulate`: runs a scene's flag simulation and writes the mesh of every frame as Wavefront OBJ
//! (positions in metres, texture coordinates of the flag, triangles), for use in other tools.

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use sheer_cloth::{ClothModel, Simulation};

use crate::CliError;
use crate::frame::{FlagScene, StageTimes};
use crate::output::FrameNames;
use crate::scene::Scene;
use crate::sequence::{Sequence, run_sequence};

#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Scene file (TOML); default: the shipped default scene.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Number of frames to write (1/fps seconds apart; frame 0 is the scene at the frame nearest --time).
    #[arg(long, default_value_t = 60, allow_negative_numbers = true)]
    pub frames: u32,
    /// Scene time of frame 0, s, in [0, 3600] (the flag is simulated up to it), as in `render`.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub time: f64,
    /// Directory for frame_0000.obj, frame_0001.obj, … (created if missing; numbers padded to the last
    /// frame's width). A folder that already holds frame_*.obj files is refused unless --overwrite.
    #[arg(long)]
    pub out_dir: PathBuf,
    /// Remove the frame_*.obj files already in --out-dir first.
    #[arg(long)]
    pub overwrite: bool,
}

/// The flag of a scene, hoist edge pinned.
pub fn flag_simulation(scene: &Scene) -> Result<Simulation, CliError> {
    let model = ClothModel::grid(&scene.flag).and_then(|m| m.with_hoist_pinned())?;
    Ok(Simulation::new(model, scene.simulation_params())?)
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

/// One frame as OBJ text, positions in the shortest form that reads back to the simulation's f64
/// exactly.
pub fn obj_text(sim: &Simulation, uvs: &[[f32; 2]], frame: u32, time: f64) -> String {
    let mut text = String::with_capacity(64 * sim.particle_count());
    let _ = writeln!(
        text,
        "# sheer frame {frame}, t = {time:?} s, {} particles",
        sim.particle_count()
    );
    for p in sim.positions() {
        let _ = writeln!(text, "v {:?} {:?} {:?}", p.x, p.y, p.z);
    }
    for uv in uvs {
        // OBJ's v runs upward.
        let _ = writeln!(text, "vt {:?} {:?}", uv[0], 1.0 - uv[1]);
    }
    for tri in sim.triangles() {
        let [a, b, c] = tri.map(|i| i + 1);
        let _ = writeln!(text, "f {a}/{a} {b}/{b} {c}/{c}");
    }
    text
}

pub fn run(args: &SimulateArgs) -> Result<(), CliError> {
    let start = crate::render_cmd::check_time(args.time)?;
    let scene = crate::load_scene(args.scene.as_deref())?;
    if scene.static_sheet.is_some() {
        return Err(CliError::new(
            "the scene describes a static sheet: there is nothing to simulate",
        ));
    }
    if args.frames == 0 {
        return Err(CliError::new("--frames must be ≥ 1"));
    }
    let names = FrameNames::new(args.frames, &["obj"]);
    crate::output::prepare_sequence_folder(&args.out_dir, &names, args.overwrite)?;
    crate::output::interrupt::install();
    let mut flag = FlagScene::new(scene)?;
    let uvs = grid_uvs(flag.scene.flag.columns, flag.scene.flag.rows);
    let sequence = Sequence {
        dir: &args.out_dir,
        names: &names,
        extension: "obj",
        frames: args.frames,
        start,
        verb: "simulating",
    };
    run_sequence(
        &mut flag,
        &sequence,
        &mut StageTimes::default(),
        |flag, frame, _| {
            let sim = flag
                .simulation()
                .ok_or_else(|| CliError::new("internal: a flag scene without a simulation"))?;
            crate::output::write_file(
                &args.out_dir.join(names.name(frame, "obj")),
                obj_text(sim, &uvs, frame, flag.time()).as_bytes(),
            )
        },
    )?;
    eprintln!(
        "wrote {} frames of {} particles to {}",
        args.frames,
        flag.mesh.positions.len(),
        args.out_dir.display()
    );
    Ok(())
}
