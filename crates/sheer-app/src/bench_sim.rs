//! `sheer bench sim`: milliseconds per 60 Hz frame and particle-substeps per second for each method, on
//! the default flag and on larger grids, measured in one run of one build.

use std::fmt::Write as _;
use std::time::{Duration, Instant};

use clap::Args;
use sheer_cloth::{ClothModel, GridSpec, Method, SimParams, Simulation};

use crate::scene::{MAX_GRID_SIDE, MAX_ITERATIONS, MAX_SUBSTEPS};
use crate::{CliError, outln};

const FRAME: f64 = 1.0 / 60.0;

#[derive(Debug, Args)]
pub struct BenchSimArgs {
    /// Methods to measure (comma-separated): explicit_euler, symplectic_euler, verlet, implicit_euler,
    /// pbd, xpbd, small_steps_xpbd. Default: all.
    #[arg(long, value_delimiter = ',')]
    pub method: Vec<String>,
    /// Grids as COLUMNSxROWS (comma-separated), each side in [2, 1024]. Default:
    /// 16x11,64x46,256x186,1024x745.
    #[arg(long, value_delimiter = ',')]
    pub grid: Vec<String>,
    /// Sub-steps per frame for every method (default: each method's stable setting on the flag,
    /// `Method::stable_flag_setting`).
    #[arg(long, allow_negative_numbers = true)]
    pub substeps: Option<u32>,
    /// Solver iterations per sub-step (PBD, XPBD) or the CG iteration cap (implicit Euler); the other
    /// methods have none (refused if no method measured has iterations).
    #[arg(long, allow_negative_numbers = true)]
    pub iterations: Option<u32>,
    /// rayon thread counts to measure (comma-separated), each at most the core count. Default: 1 and
    /// all cores.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    pub threads: Vec<usize>,
    /// Particle count from which passes run on rayon's pool (default: the library's measured threshold;
    /// 0 forces the parallel code paths on, for finding the crossover).
    #[arg(long, allow_negative_numbers = true)]
    pub parallel_min_particles: Option<usize>,
    /// The longest the wind's forces are held between renewals, s (`wind.renewal_interval`; 0 renews
    /// them at every sub-step). Default: the default flag's, 0.002.
    #[arg(long, allow_negative_numbers = true)]
    pub wind_renewal_interval: Option<f64>,
    /// The springs' dashpots (`damping` of stretch, shear and bending): `on` (the default flag's)
    /// or `off` (all three 0 N·s/m, which the position-based solvers skip on a grid).
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub spring_damping: Switch,
    /// Contacts: `none` (the default), `pole` (the default scene's pole capsule) or `self` (the pole
    /// and self-collision, as `assets/wrap.scene.toml`); position-based methods only.
    #[arg(long, value_enum, default_value_t = ContactCase::None)]
    pub contacts: ContactCase,
    /// The cloth's thickness with `--contacts pole|self`, m (`collisions.thickness`). Default: the
    /// default flag's, 0.004.
    #[arg(long, allow_negative_numbers = true)]
    pub thickness: Option<f64>,
    /// Minimum measuring time per case, seconds, in [0, 3600] (at least one frame is always timed).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub seconds: f64,
    /// Print CSV: method,width,height,substeps,iterations,threads,ms_per_frame,particle_substeps_per_s
    #[arg(long)]
    pub csv: bool,
}

/// A model part switched on or off.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Switch {
    On,
    Off,
}

/// The contacts a `sheer bench sim` case resolves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ContactCase {
    None,
    Pole,
    #[value(name = "self")]
    SelfAndPole,
}

/// What `sheer bench sim` changes in the default flag besides the method and the grid.
#[derive(Clone, Copy, Debug)]
pub struct FlagOverrides {
    /// `parallel_min_particles`; `None`: the library's.
    pub parallel_min_particles: Option<usize>,
    /// `wind.renewal_interval`, s; `None`: the default flag's.
    pub wind_renewal_interval: Option<f64>,
    pub spring_damping: Switch,
    pub contacts: ContactCase,
    /// `collisions.thickness`, m; `None`: the default flag's.
    pub thickness: Option<f64>,
}

/// Longest `--seconds` of the benchmarks: an hour per case, so that a typo does not hang the program.
pub const MAX_BENCH_SECONDS: f64 = 3600.0;

/// `--seconds` of `sheer bench sim` and `sheer bench render`: in [0, [`MAX_BENCH_SECONDS`]].
pub fn check_seconds(seconds: f64) -> Result<(), CliError> {
    if seconds.is_finite() && (0.0..=MAX_BENCH_SECONDS).contains(&seconds) {
        Ok(())
    } else {
        Err(CliError::new(format!(
            "--seconds must lie in [0, {MAX_BENCH_SECONDS}], got {seconds:?}"
        )))
    }
}

fn parse_grid(text: &str) -> Result<(usize, usize), CliError> {
    let bad = || {
        CliError::new(format!(
            "--grid `{text}`: expected COLUMNSxROWS, e.g. 64x46"
        ))
    };
    // The scene file's limit: beyond it a grid runs out of memory (or time) before it shows anything.
    let out_of_range = || {
        CliError::new(format!(
            "--grid `{text}`: each side must lie in [2, {MAX_GRID_SIDE}] particles"
        ))
    };
    let side = |digits: &str| {
        let digits = digits.trim();
        match digits.parse::<usize>() {
            Ok(side) if (2..=MAX_GRID_SIDE).contains(&side) => Ok(side),
            Ok(_) => Err(out_of_range()),
            // All digits, yet no usize: a number beyond the range, not a malformed grid.
            Err(_) if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) => {
                Err(out_of_range())
            }
            Err(_) => Err(bad()),
        }
    };
    let (columns, rows) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    Ok((side(columns)?, side(rows)?))
}

/// One measured case.
pub struct Measurement {
    pub method: Method,
    pub columns: usize,
    pub rows: usize,
    /// `None` when the run diverged.
    pub ms_per_frame: Option<f64>,
}

impl Measurement {
    pub fn particle_substeps_per_s(&self) -> Option<f64> {
        self.ms_per_frame.map(|ms| {
            (self.columns * self.rows) as f64 * self.method.substeps() as f64 / (ms * 1e-3)
        })
    }
}

/// The app's default flag ([`SimParams::waving_flag`], hoist pinned) at another resolution, integrated
/// by `method`. (Before 2026-12-03 this was the default flag's geometry in a steady-mean 6 m/s wind with
/// the library's gusts: the same work per sub-step, and the wind renewed at every sub-step.)
pub fn flag_simulation(
    columns: usize,
    rows: usize,
    method: Method,
    overrides: FlagOverrides,
) -> Result<Simulation, CliError> {
    let spec = GridSpec {
        columns,
        rows,
        ..GridSpec::default()
    };
    let model = ClothModel::grid(&spec).and_then(|m| m.with_hoist_pinned())?;
    let mut params = SimParams {
        method,
        ..SimParams::waving_flag()
    };
    if let Some(interval) = overrides.wind_renewal_interval {
        params.wind.renewal_interval = interval;
    }
    if let Some(threshold) = overrides.parallel_min_particles {
        params.parallel_min_particles = threshold;
    }
    if overrides.spring_damping == Switch::Off {
        params.remove_spring_damping();
    }
    if let Some(thickness) = overrides.thickness {
        params.collisions.thickness = thickness;
    }
    if overrides.contacts != ContactCase::None {
        params
            .collisions
            .colliders
            .push(sheer_cloth::Collider::flag_pole(
                &spec,
                params.collisions.thickness,
            ));
        params.collisions.self_collision = overrides.contacts == ContactCase::SelfAndPole;
    }
    Ok(Simulation::new(model, params)?)
}

fn measure(
    method: Method,
    columns: usize,
    rows: usize,
    threads: usize,
    minimum: Duration,
    overrides: FlagOverrides,
) -> Result<Measurement, CliError> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| CliError::new(format!("cannot start {threads} threads: {e}")))?;
    pool.install(|| {
        let mut sim = flag_simulation(columns, rows, method, overrides)?;
        let mut result = Measurement {
            method,
            columns,
            rows,
            ms_per_frame: None,
        };
        // Warm up (caches, the flag starts to wave), then time whole frames.
        for _ in 0..3 {
            if sim.step(FRAME).is_err() {
                return Ok(result);
            }
        }
        let start = Instant::now();
        let mut frames = 0u32;
        while frames == 0 || start.elapsed() < minimum {
            if sim.step(FRAME).is_err() {
                return Ok(result);
            }
            frames += 1;
        }
        result.ms_per_frame = Some(start.elapsed().as_secs_f64() * 1e3 / frames as f64);
        Ok(result)
    })
}

pub fn run(args: &BenchSimArgs) -> Result<(), CliError> {
    check_seconds(args.seconds)?;
    let names: Vec<String> = if args.method.is_empty() {
        Method::NAMES.iter().map(|s| s.to_string()).collect()
    } else {
        args.method.clone()
    };
    if args
        .substeps
        .is_some_and(|n| !(1..=MAX_SUBSTEPS).contains(&n))
    {
        return Err(CliError::new(format!(
            "--substeps must lie in [1, {MAX_SUBSTEPS}]"
        )));
    }
    if args
        .iterations
        .is_some_and(|n| !(1..=MAX_ITERATIONS).contains(&n))
    {
        return Err(CliError::new(format!(
            "--iterations must lie in [1, {MAX_ITERATIONS}]"
        )));
    }
    let mut methods = Vec::new();
    for name in &names {
        let method = Method::stable_flag_setting(name).ok_or_else(|| {
            CliError::new(format!(
                "unknown method `{name}` (expected one of {})",
                Method::NAMES.join(", ")
            ))
        })?;
        methods.push(method.with_knobs(args.substeps, args.iterations));
    }
    // Applied to those methods that have iterations; a list without any would measure nothing it asks.
    if args.iterations.is_some() && !methods.iter().any(Method::has_iterations) {
        return Err(CliError::new(format!(
            "--iterations: none of the methods measured ({}) has iterations (pbd, xpbd: solver \
             iterations; implicit_euler: the CG cap)",
            names.join(", ")
        )));
    }
    let grids: Vec<(usize, usize)> = if args.grid.is_empty() {
        vec![(16, 11), (64, 46), (256, 186), (1024, 745)]
    } else {
        args.grid
            .iter()
            .map(|g| parse_grid(g))
            .collect::<Result<_, _>>()?
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut threads = if args.threads.is_empty() {
        vec![1, cores]
    } else {
        args.threads.clone()
    };
    threads.dedup();
    // More threads than cores would time their contention (a team's threads spin while they wait),
    // not the solver; and a pool of 10⁵ threads took minutes to start.
    if let Some(&bad) = threads.iter().find(|&&t| t == 0 || t > cores) {
        return Err(CliError::new(format!(
            "--threads must lie in [1, {cores}] (the cores), got {bad}"
        )));
    }
    if let Some(interval) = args.wind_renewal_interval
        && !(interval.is_finite() && interval >= 0.0)
    {
        return Err(CliError::new(format!(
            "--wind-renewal-interval must be finite and ≥ 0 s, got {interval}"
        )));
    }
    if let Some(thickness) = args.thickness {
        if !(thickness.is_finite() && thickness > 0.0) {
            return Err(CliError::new(format!(
                "--thickness must be finite and > 0 m, got {thickness}"
            )));
        }
        if args.contacts == ContactCase::None {
            return Err(CliError::new(
                "--thickness needs --contacts pole or self".to_string(),
            ));
        }
    }
    let minimum = Duration::from_secs_f64(args.seconds);
    let overrides = FlagOverrides {
        parallel_min_particles: args.parallel_min_particles,
        wind_renewal_interval: args.wind_renewal_interval,
        spring_damping: args.spring_damping,
        contacts: args.contacts,
        thickness: args.thickness,
    };
    if args.csv {
        outln!(
            "method,width,height,substeps,iterations,threads,ms_per_frame,particle_substeps_per_s"
        )?;
    } else {
        outln!(
            "{:<18} {:>11} {:>8} {:>10} {:>7} {:>12} {:>22}",
            "method",
            "grid",
            "substeps",
            "iterations",
            "threads",
            "ms/frame",
            "particle-substeps/s"
        )?;
    }
    for &(columns, rows) in &grids {
        for &method in &methods {
            for &t in &threads {
                let m = measure(method, columns, rows, t, minimum, overrides)?;
                let mut line = String::new();
                if args.csv {
                    let _ = write!(
                        line,
                        "{},{},{},{},{},{},{},{}",
                        method.name(),
                        columns,
                        rows,
                        method.substeps(),
                        method.iterations(),
                        t,
                        // CSV numbers in their shortest round-trip form.
                        m.ms_per_frame
                            .map_or("diverged".into(), |v| format!("{v:?}")),
                        m.particle_substeps_per_s()
                            .map_or("diverged".into(), |v| format!("{v:?}"))
                    );
                } else {
                    let _ = write!(
                        line,
                        "{:<18} {:>11} {:>8} {:>10} {:>7} {:>12} {:>22}",
                        method.name(),
                        format!("{columns}x{rows}"),
                        method.substeps(),
                        method.iterations(),
                        t,
                        m.ms_per_frame
                            .map_or("diverged".into(), |v| format!("{v:.3}")),
                        m.particle_substeps_per_s()
                            .map_or("diverged".into(), |v| format!("{v:.3e}"))
                    );
                }
                outln!("{line}")?;
            }
        }
    }
    // A grid below the threshold steps on one thread whatever the pool: say so, or its two-thread row
    // reads as a two-thread time.
    let threshold = overrides
        .parallel_min_particles
        .unwrap_or(SimParams::waving_flag().parallel_min_particles);
    let several: Vec<String> = threads
        .iter()
        .filter(|&&t| t > 1)
        .map(|t| t.to_string())
        .collect();
    if !several.is_empty() {
        for &(columns, rows) in grids.iter().filter(|(c, r)| c * r < threshold) {
            eprintln!(
                "note: {columns}x{rows} ({} particles) ran on one thread at --threads {}: below \
                 parallel_min_particles, {threshold} (--parallel-min-particles 0 runs it on the team)",
                columns * rows,
                several.join(",")
            );
        }
    }
    Ok(())
}
