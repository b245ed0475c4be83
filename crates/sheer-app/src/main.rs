//! `sheer`: the thin-cloth engine's command line.
//!
//! Every failure prints one line, `error: …`, and exits with status 1 (usage errors: clap's status 2,
//! also on one line).

mod assets;
mod bench_render;
mod bench_sim;
mod frame;
mod orbit_cmd;
mod output;
mod render_cmd;
mod scene;
mod sequence;
mod simulate;
mod slab_cmd;
mod study_cmd;
mod window;
mod window_image;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// `println!` that gives a [`CliError`] instead of panicking when standard output is closed or full
/// (`sheer bench sim | head -1`, `> /dev/full`).
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*).map_err(|e| {
            $crate::CliError::new(format!("cannot write to standard output: {e}"))
        })
    }};
}
pub(crate) use outln;

/// A one-line, user-facing error.
#[derive(Debug)]
pub struct CliError(String);

impl CliError {
    /// An error the program reports as `error: {message}`, on one line (newlines become spaces).
    pub fn new(message: impl Into<String>) -> Self {
        CliError(message.into())
    }

    /// Appends the line number of `span` in `text`, when there is one.
    pub fn with_span(self, text: &str, span: Option<std::ops::Range<usize>>) -> Self {
        match span {
            Some(span) => {
                let start = span.start.min(text.len());
                let line = text[..start].matches('\n').count() + 1;
                let source = text.lines().nth(line - 1).unwrap_or("").trim();
                CliError(format!("{} (line {line}: `{source}`)", self.0))
            }
            None => self,
        }
    }
}

impl std::error::Error for CliError {}

impl std::fmt::Display for CliError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // One line, whatever the source said.
        f.write_str(&self.0.replace('\n', " "))
    }
}

impl From<sheer_cloth::ModelError> for CliError {
    fn from(e: sheer_cloth::ModelError) -> Self {
        CliError(e.to_string())
    }
}

impl From<sheer_cloth::SetupError> for CliError {
    fn from(e: sheer_cloth::SetupError) -> Self {
        CliError(e.to_string())
    }
}

/// The scene at `path`, or the default scene (built into the binary) when `None`.
pub fn load_scene(path: Option<&std::path::Path>) -> Result<scene::Scene, CliError> {
    match path {
        Some(path) => scene::Scene::load(path),
        None => scene::Scene::builtin_default(),
    }
}

/// Clap's usage error on one line: its message and tip, without the usage block and the pointer to
/// `--help`.
fn one_line_usage_error(error: &clap::Error) -> String {
    let text = error.to_string();
    let body = text.split("\nUsage:").next().unwrap_or(&text);
    let mut line = String::new();
    for part in body
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("For more information"))
    {
        if !line.is_empty() {
            line.push_str(if line.ends_with(':') { " " } else { "; " });
        }
        line.push_str(part);
    }
    line
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
pub fn progress_bar(length: u64, message: &'static str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(length);
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(message);
    bar
}

#[derive(Debug, Parser)]
#[command(
    name = "sheer",
    version,
    about = "Thin cloth, simulated and rendered as thin slabs (Frisvad et al. 2005)"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Window: scene file (TOML); default: the shipped default scene.
    #[arg(long)]
    scene: Option<std::path::PathBuf>,
    /// Window: run this many frames (≥ 1), then exit (after the screenshot, with --screenshot).
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..))]
    frames: Option<u32>,
    /// Window: save a screenshot of the whole window as PNG after --frames frames.
    #[arg(long, requires = "frames")]
    screenshot: Option<std::path::PathBuf>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render a scene headless: one frame, or a sequence (PNG and linear OpenEXR).
    Render(render_cmd::RenderArgs),
    /// The paper's figure 2: baseline and thin-slab, back-lit and front-lit, as one 2×2 image.
    Figure2(render_cmd::Figure2Args),
    /// The flag over one orbit of the light: the paper's model against the scene's shading, the
    /// share of near-black cloth pixels per frame, and a strip of frames (--out).
    Orbit(orbit_cmd::OrbitArgs),
    /// Simulate a scene's flag and write every frame's mesh as OBJ.
    Simulate(simulate::SimulateArgs),
    /// Evaluate the thin-slab model for CSV rows `tau1,albedo,mu0,mu`.
    Slab(slab_cmd::SlabArgs),
    /// Regenerate the procedural assets: the Faroe flag texture and the watercolour painting.
    Assets(AssetsArgs),
    /// Speed against accuracy of the simulator: work–precision, stability map, ablation and the
    /// automatic choice of the default flag's method (docs/study.md).
    Study(study_cmd::StudyArgs),
    /// Benchmarks.
    #[command(subcommand)]
    Bench(BenchCommand),
}

#[derive(Debug, clap::Args)]
struct AssetsArgs {
    /// Directory to write faroe_flag.png and faroe_landscape.png into.
    #[arg(long, default_value = "assets")]
    out: std::path::PathBuf,
}

#[derive(Debug, Subcommand)]
enum BenchCommand {
    /// Simulation cost per 60 Hz frame for each method and grid.
    Sim(bench_sim::BenchSimArgs),
    /// Frames per second of the case study per evaluation path and baseline, with per-stage times.
    Render(bench_render::BenchRenderArgs),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(error) => {
            use clap::error::ErrorKind;
            if matches!(
                error.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                error.exit();
            }
            eprintln!("{}", one_line_usage_error(&error));
            return ExitCode::from(2);
        }
    };
    let result = match &cli.command {
        None => window::run(window::WindowOptions {
            scene: cli.scene.clone(),
            frames: cli.frames,
            screenshot: cli.screenshot.clone(),
        }),
        Some(_) if cli.frames.is_some() || cli.screenshot.is_some() || cli.scene.is_some() => {
            Err(CliError::new(
                "--scene/--frames/--screenshot before a subcommand are window options; put --scene after the subcommand",
            ))
        }
        Some(Command::Render(args)) => render_cmd::run_render(args),
        Some(Command::Figure2(args)) => render_cmd::run_figure2(args),
        Some(Command::Slab(args)) => slab_cmd::run(args),
        Some(Command::Assets(args)) => output::create_output_dir(&args.out).and_then(|()| {
            assets::write_assets(&args.out).map_err(|e| CliError::new(e.to_string()))
        }),
        Some(Command::Simulate(args)) => simulate::run(args),
        Some(Command::Orbit(args)) => orbit_cmd::run(args),
        Some(Command::Study(args)) => {
            study_cmd::run(args).map_err(|e| CliError::new(e.to_string()))
        }
        Some(Command::Bench(BenchCommand::Sim(args))) => bench_sim::run(args),
        Some(Command::Bench(BenchCommand::Render(args))) => bench_render::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::FAILURE
        }
    }
}
