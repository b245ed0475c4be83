//! The study's files: every command of `sheer study` writes its CSV, PNG, Markdown and TOML files
//! through these functions into one folder (`docs/` for the published study).

use std::fmt::Write as _;
use std::path::Path;

use sheer_cloth::Method;

use crate::ablation::{AblationRow, FRAMES_PER_TURN, INTERSECTION_FRAMES, ablation};
use crate::chart::{stability_chart, work_precision_chart};
use crate::choose::{
    Budget, BudgetRecord, Choice, ChoiceFile, ChoiceRecord, REAL_TIME_CPU_MS_PER_SIMULATED_SECOND,
    ReferenceRecord, SceneRecord, choose,
};
use crate::coverage::coverage_difference;
use crate::reference::{Reference, reference};
use crate::seeds::{SeedRow, across_seeds, summarise};
use crate::stability::{
    StabilityMap, StabilitySetup, find_stability_boundary, map_methods, stability_map,
};
use crate::work_precision::{Row, StudyConfig, work_precision};
use crate::{Monitor, Scene, StudyError};

/// Checks the output folder `out` before any work: that it can be created and written (a study takes
/// minutes, and would find out only when it wrote its first file); and, for a quick run (`quick`)
/// unless `force`, refuses a folder whose `choice.toml` is not itself from a quick run: the quick study
/// would overwrite (or, when no setting meets the budget, delete) a full study's published results.
pub fn check_output_folder(out: &Path, quick: bool, force: bool) -> Result<(), StudyError> {
    if out.exists() && !out.is_dir() {
        // The system's "File exists" reads as if the folder were the problem.
        let error = std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            "it is a file, not a folder",
        );
        return Err(io_error(out, error));
    }
    std::fs::create_dir_all(out).map_err(|e| io_error(out, e))?;
    let probe = out.join(format!(".sheer-study-write-check-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(|e| io_error(out, e))?;
    std::fs::remove_file(&probe).map_err(|e| io_error(&probe, e))?;
    if !quick || force {
        return Ok(());
    }
    let path = out.join("choice.toml");
    let text = read_existing(&path)?;
    if text.is_empty() {
        return Ok(());
    }
    let path = path.display().to_string();
    let table =
        toml::from_str::<toml::Table>(&text).map_err(|e| StudyError::WouldReplaceUnknownFile {
            path: path.clone(),
            reason: format!("it is not TOML: {}", e.message().trim().replace('\n', "; ")),
        })?;
    match table.get("quick").and_then(toml::Value::as_bool) {
        Some(true) => Ok(()),
        Some(false) => Err(StudyError::WouldReplaceFullStudy { path }),
        None => Err(StudyError::WouldReplaceUnknownFile {
            path,
            reason: "it has no `quick` flag".into(),
        }),
    }
}

/// The text of `path`, or an empty string when it does not exist; any other read error is an error
/// (an unreadable file must not be treated as empty and then overwritten).
fn read_existing(path: &Path) -> Result<String, StudyError> {
    match std::fs::read_to_string(path) {
        Ok(text) => Ok(text),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(String::new()),
        Err(e) => Err(io_error(path, e)),
    }
}

/// Writes everything `docs/` publishes into `out`: work–precision, stability map, choice, ablation.
pub fn write_all(
    config: &StudyConfig,
    budget: &Budget,
    out: &Path,
    monitor: &Monitor,
) -> Result<(), StudyError> {
    let mut rows = write_work_precision(config, out, monitor)?;
    let measured = write_choice(config, budget, out, monitor)?;
    rows.extend(measured.rows.iter().cloned());
    work_precision_chart(&rows, &out.join("work-precision.png"))?;
    write_ablation(config, &measured, out, monitor)?;
    write_stability(config, out, monitor)?;
    Ok(())
}

fn io_error(path: &Path, source: std::io::Error) -> StudyError {
    StudyError::Io {
        path: path.display().to_string(),
        source,
    }
}

fn write_file(path: &Path, text: &str) -> Result<(), StudyError> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(|e| io_error(parent, e))?;
    }
    crate::whole_file::write(path, text)
}

/// A CSV number in its shortest round-trip form (`{:?}`), or empty.
fn optional(value: Option<f64>) -> String {
    value.map_or(String::new(), |v| format!("{v:?}"))
}

/// `name ×substeps, iterations` in words.
pub fn describe(method: &Method) -> String {
    match *method {
        Method::ImplicitEuler {
            substeps,
            cg_max_iterations,
            cg_tolerance,
        } => format!(
            "implicit_euler ×{substeps} (CG ≤ {cg_max_iterations} it, tol {cg_tolerance:.0e})"
        ),
        Method::Pbd {
            substeps,
            iterations,
            stiffness,
        } => format!("pbd ×{substeps}, {iterations} it, k = {stiffness}"),
        Method::Xpbd {
            substeps,
            iterations,
        } => format!("xpbd ×{substeps}, {iterations} it"),
        _ => format!("{} ×{}", method.name(), method.substeps()),
    }
}

/// Header of `work-precision.csv`.
const WORK_PRECISION_HEADER: &str = "scene,particles,method,substeps,iterations,substep_s,time_s,rms_position_error_m,max_position_error_m,relative_energy_drift,reference_energy_drift,max_strain,diverged,cpu_ms_per_simulated_s,reference_halving_rms_m,coverage_difference,reference_coverage_halving";

/// The work–precision CSV (one row per method setting and sample time; the coverage columns are per
/// run, repeated on each of its rows, and empty for scenes without a coverage window).
pub fn work_precision_csv(rows: &[Row]) -> String {
    let mut csv = format!("{WORK_PRECISION_HEADER}\n");
    for r in rows {
        let (substeps, iterations) = r.knobs();
        let m = &r.metrics;
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{:?},{:?},{},{},{},{:?},{},{},{:?},{:?},{},{}",
            r.scene,
            r.particles,
            r.method.name(),
            substeps,
            iterations,
            r.substep,
            m.time,
            optional(m.rms_position_error),
            optional(m.max_position_error),
            optional(m.relative_energy_drift),
            m.reference_energy_drift,
            optional(m.max_strain),
            m.diverged,
            r.cpu_ms_per_simulated_second,
            r.reference_rms_halving,
            optional(r.coverage_difference),
            optional(r.reference_coverage_halving)
        );
    }
    csv
}

fn halving_lines(scene: &Scene, reference: &Reference, text: &mut String) {
    let _ = writeln!(
        text,
        "- `{}` ({}×{}): reference {} (sub-step {:.3e} s)",
        reference.scene,
        scene.grid.columns,
        scene.grid.rows,
        describe(&reference.method),
        reference.substep
    );
    for h in &reference.halving {
        let _ = writeln!(
            text,
            "  - t = {} s: halving the step changes the result by RMS {:.2e} m, max {:.2e} m",
            h.time, h.rms_difference, h.max_difference
        );
    }
    if let (Some(halving), Some(window)) = (reference.coverage_halving, scene.coverage) {
        let _ = writeln!(
            text,
            "  - time-averaged coverage over {}–{} s: halving the step changes it by {:.2e}",
            window.start, window.end, halving
        );
    }
}

/// The model parameters a run used, in one line (so two runs' outputs show whether they measured the
/// same flag).
fn parameter_line(scene: &Scene) -> String {
    let p = &scene.params;
    format!(
        "stretch {} N/m, shear {} N/m, bending {} N/m (enabled: {}/{}/{}), spring damping {}/{}/{} N·s/m, wind {:?} m/s, gusts {}, turbulence {}, lift {}, wind forces {}, long-range attachments {}, air damping {} 1/s, {} kg/m²",
        p.stretch.stiffness,
        p.shear.stiffness,
        p.bend.stiffness,
        p.stretch.enabled,
        p.shear.enabled,
        p.bend.enabled,
        p.stretch.damping,
        p.shear.damping,
        p.bend.damping,
        p.wind.velocity.to_array(),
        p.wind.gust_strength,
        p.wind.turbulence,
        p.wind.lift_coefficient,
        if !p.wind.per_substep {
            "held for the frame".to_string()
        } else if p.wind.renewal_interval == 0.0 {
            "renewed every sub-step".to_string()
        } else {
            format!(
                "held ≤ {} ms",
                crate::ablation::milliseconds(p.wind.renewal_interval)
            )
        },
        if p.long_range_attachments {
            "on"
        } else {
            "off"
        },
        p.air_damping,
        scene.grid.areal_density
    )
}

/// Runs the work–precision sweep of the three scenes and writes `work-precision.{csv,png,md}`.
pub fn write_work_precision(
    config: &StudyConfig,
    out: &Path,
    monitor: &Monitor,
) -> Result<Vec<Row>, StudyError> {
    let scenes = [
        Scene::flag(config.sweep_grid)?.with_coverage(Some(config.coverage_window)),
        Scene::hanging_sheet(config.sweep_grid)?,
        Scene::stiff(config.stiff_grid)?,
    ];
    let mut rows = Vec::new();
    let mut notes = String::from("# Work–precision: references\n\n");
    for scene in &scenes {
        let reference = reference(scene, &config.sample_times, monitor)?;
        halving_lines(scene, &reference, &mut notes);
        let _ = writeln!(notes, "  - parameters: {}", parameter_line(scene));
        monitor.println(&format!("reference of {} done", scene.name));
        rows.extend(work_precision(
            scene,
            &reference,
            &config.sweep(scene),
            monitor,
        )?);
    }
    write_file(&out.join("work-precision.csv"), &work_precision_csv(&rows))?;
    write_file(&out.join("work-precision.md"), &notes)?;
    work_precision_chart(&rows, &out.join("work-precision.png"))?;
    Ok(rows)
}

/// What [`write_choice`] measured on the default flag; the ablation reuses it.
#[derive(Clone, Debug)]
pub struct ChoiceMeasurement {
    /// The default flag at the choice grid, with the config's coverage window.
    pub scene: Scene,
    /// The converged reference run of that scene.
    pub reference: Reference,
    /// Coverage difference of the converged coarser flag (`StudyConfig::choice_coarse_grid`) from
    /// the reference.
    pub resolution_coverage_difference: Option<f64>,
    /// Every measured setting at every sample time (the choice's candidates).
    pub rows: Vec<Row>,
    /// The cheapest setting within the budget; `None` when none meets it.
    pub choice: Option<Choice>,
}

fn mm(value: Option<f64>) -> String {
    value.map_or("—".to_string(), |v| format!("{:.2}", v * 1e3))
}

fn fraction(value: Option<f64>) -> String {
    value.map_or("—".to_string(), |v| format!("{v:.4}"))
}

/// The sweep on the app's default flag ([`Scene::default_flag`] at the choice grid), the automatic
/// choice, a section of `work-precision.md` stating the budget, the choice and why, `choice.toml`, and
/// the rows merged into `work-precision.csv`.
pub fn write_choice(
    config: &StudyConfig,
    budget: &Budget,
    out: &Path,
    monitor: &Monitor,
) -> Result<ChoiceMeasurement, StudyError> {
    let (columns, rows) = config.choice_grid;
    let scene = Scene::default_flag()?
        .with_resolution(columns, rows)?
        .with_coverage(Some(config.coverage_window));
    let window = config.coverage_window;
    let reference = reference(&scene, &config.choice_times, monitor)?;
    let coarse_scene =
        scene.with_resolution(config.choice_coarse_grid.0, config.choice_coarse_grid.1)?;
    let coarse = crate::reference::reference(&coarse_scene, &config.choice_times, monitor)?;
    let resolution_coverage_difference = coarse
        .trajectory
        .coverage
        .as_ref()
        .zip(reference.trajectory.coverage.as_ref())
        .and_then(|(c, f)| coverage_difference(c, f));
    let sweep = config.sweep(&scene);
    let rows = work_precision(&scene, &reference, &sweep, monitor)?;
    let choice = choose(budget, &rows);
    let pointwise_budget = Budget::RmsPosition {
        time: config.choice_times[0],
        max_error: 5e-3,
    };
    let pointwise = choose(&pointwise_budget, &rows);

    let mut text = String::from("\n# Automatic choice for the default flag\n\n");
    let _ = writeln!(
        text,
        "The app's default flag (`assets/default.scene.toml`, here {}×{} particles): {}. Every method of the sweep runs it{}.\n",
        scene.grid.columns,
        scene.grid.rows,
        parameter_line(&scene),
        if config.quick {
            " (**--quick: small grid and short window, not a choice for the app**)"
        } else {
            ""
        }
    );
    halving_lines(&scene, &reference, &mut text);
    let _ = writeln!(
        text,
        "- resolution: the converged {}×{} flag's time-averaged coverage differs from the {}×{} reference's by {}\n",
        coarse_scene.grid.columns,
        coarse_scene.grid.rows,
        scene.grid.columns,
        scene.grid.rows,
        fraction(resolution_coverage_difference)
    );
    text.push_str("## Budget, choice and why\n\n");
    let _ = writeln!(text, "Budget: {}.\n", budget.describe());
    if let Budget::Coverage { max_difference } = *budget {
        let _ = writeln!(
            text,
            "The measure: per pixel of an orthographic view along −z ({}×{} pixels over {} m × {} m), the \
             fraction of the frames from {} s to {} s in which the flag covers it; two runs differ by \
             `Σ|c_run − c_ref| / Σ c_ref`. Unlike a position error it does not grow with the flutter's \
             phase, which the chaotic flag loses within half a second.\n",
            window.viewport.resolution,
            window.viewport.resolution,
            window.viewport.size,
            window.viewport.size,
            window.start,
            window.end
        );
        let ratio = |yardstick: Option<f64>| {
            yardstick
                .filter(|y| *y > 0.0)
                .map_or("—".to_string(), |y| format!("{:.2}", max_difference / y))
        };
        let _ = writeln!(
            text,
            "Why this size: halving the cloth's resolution ({}×{} → {}×{}, both converged) changes the \
             coverage by {}; the budget is {}× that, so an integrator within it changes the picture \
             no more than a coarser model would, and CPU spent below it buys nothing the viewer can \
             tell from the model's own discretisation. The reference resolves it: halving the \
             reference's step changes its coverage by {} (the budget is {}× that).\n",
            scene.grid.columns,
            scene.grid.rows,
            coarse_scene.grid.columns,
            coarse_scene.grid.rows,
            fraction(resolution_coverage_difference),
            ratio(resolution_coverage_difference),
            fraction(reference.coverage_halving),
            ratio(reference.coverage_halving)
        );
    }
    match &choice {
        Some(c) => {
            let _ = writeln!(
                text,
                "Choice: **{}** — {}, {:.1} CPU ms per simulated s (one thread; {} real time: the \
                 limit is {} ms/s), the cheapest of {} settings that meet the budget.\n",
                describe(&c.method),
                match c.budget {
                    Budget::Coverage { .. } => format!("coverage difference {:.4}", c.error),
                    Budget::RmsPosition { .. } => format!("RMS error {:.2} mm", c.error * 1e3),
                },
                c.cpu_ms_per_simulated_second,
                if c.cpu_ms_per_simulated_second <= REAL_TIME_CPU_MS_PER_SIMULATED_SECOND {
                    "within"
                } else {
                    "**not** within"
                },
                REAL_TIME_CPU_MS_PER_SIMULATED_SECOND,
                c.candidates
            );
        }
        None => text.push_str("No measured setting meets the budget.\n\n"),
    }
    if !matches!(budget, Budget::RmsPosition { .. }) {
        let halving = reference
            .halving_at(config.choice_times[0])
            .map_or(0.0, |h| h.rms_difference);
        let _ = writeln!(
            text,
            "For comparison, the pointwise budget {} (reference halving difference there: {:.2} mm) \
             picks {}\n",
            pointwise_budget.describe(),
            halving * 1e3,
            pointwise
                .as_ref()
                .map_or("no measured setting.".to_string(), |c| format!(
                    "{}, {:.2} mm, at {:.1} CPU ms per simulated s.",
                    describe(&c.method),
                    c.error * 1e3,
                    c.cpu_ms_per_simulated_second
                ))
        );
    }
    text.push_str("| method |");
    for time in &config.choice_times {
        let _ = write!(text, " RMS at {time} s (mm) |");
    }
    text.push_str(" coverage difference | CPU ms / simulated s | diverged |\n|---|");
    for _ in &config.choice_times {
        text.push_str("---|");
    }
    text.push_str("---|---|---|\n");
    let mut seen: Vec<Method> = Vec::new();
    for r in &rows {
        if seen.contains(&r.method) {
            continue;
        }
        seen.push(r.method);
        let _ = write!(text, "| {} |", describe(&r.method));
        for &time in &config.choice_times {
            let rms = rows
                .iter()
                .find(|x| x.method == r.method && (x.metrics.time - time).abs() < 1e-9)
                .and_then(|x| x.metrics.rms_position_error);
            let _ = write!(text, " {} |", mm(rms));
        }
        let diverged = rows
            .iter()
            .any(|x| x.method == r.method && x.metrics.diverged);
        let _ = writeln!(
            text,
            " {} | {:.1} | {} |",
            fraction(r.coverage_difference),
            r.cpu_ms_per_simulated_second,
            diverged
        );
    }
    let path = out.join("work-precision.md");
    let mut existing = read_existing(&path)?;
    if let Some(at) = existing.find("\n# Automatic choice") {
        existing.truncate(at);
    }
    existing.push_str(&text);
    write_file(&path, &existing)?;
    // Merge into work-precision.csv: replace earlier default-flag rows, keep the other scenes' (only
    // from a file with the same columns).
    let csv_path = out.join("work-precision.csv");
    let mut csv: String = match read_existing(&csv_path)? {
        existing if existing.lines().next() == Some(WORK_PRECISION_HEADER) => existing
            .lines()
            .filter(|line| !line.starts_with("default_flag,"))
            .map(|line| format!("{line}\n"))
            .collect(),
        _ => work_precision_csv(&[]),
    };
    for line in work_precision_csv(&rows).lines().skip(1) {
        csv.push_str(line);
        csv.push('\n');
    }
    write_file(&csv_path, &csv)?;
    let choice_path = out.join("choice.toml");
    match &choice {
        Some(c) => {
            let file = choice_file(
                config,
                &scene,
                &reference,
                resolution_coverage_difference,
                c,
                &rows,
            );
            let body = toml::to_string(&file).map_err(|e| StudyError::Encode {
                path: choice_path.display().to_string(),
                message: e.to_string(),
            })?;
            let header = format!(
                "# The automatic choice for the app's default flag, written by `sheer study {}` (see\n\
                 # work-precision.md). The app's default scene must use this method on this flag (test\n\
                 # `scene::tests::the_default_flag_uses_the_studys_choice` in sheer-app).\n\n",
                if config.quick {
                    "… --quick"
                } else {
                    "choose|all"
                }
            );
            write_file(&choice_path, &format!("{header}{body}"))?;
        }
        None => {
            // A choice file from an earlier run would claim a choice this budget does not make.
            if choice_path.exists() {
                std::fs::remove_file(&choice_path).map_err(|e| io_error(&choice_path, e))?;
            }
        }
    }
    monitor.println(&text);
    Ok(ChoiceMeasurement {
        scene,
        reference,
        resolution_coverage_difference,
        rows,
        choice,
    })
}

fn choice_file(
    config: &StudyConfig,
    scene: &Scene,
    reference: &Reference,
    resolution_coverage_difference: Option<f64>,
    choice: &Choice,
    rows: &[Row],
) -> ChoiceFile {
    let of_method: Vec<&Row> = rows.iter().filter(|r| r.method == choice.method).collect();
    ChoiceFile {
        quick: config.quick,
        choice: ChoiceRecord {
            method: choice.method.name().to_string(),
            substeps: choice.method.substeps(),
            iterations: choice.method.iterations(),
            error: choice.error,
            coverage_difference: of_method.first().and_then(|r| r.coverage_difference),
            rms_position_error_m: of_method
                .iter()
                .filter_map(|r| Some([r.metrics.time, r.metrics.rms_position_error?]))
                .collect(),
            cpu_ms_per_simulated_second: choice.cpu_ms_per_simulated_second,
            real_time: choice.cpu_ms_per_simulated_second <= REAL_TIME_CPU_MS_PER_SIMULATED_SECOND,
            candidates: choice.candidates,
        },
        budget: BudgetRecord::of(
            &choice.budget,
            [config.coverage_window.start, config.coverage_window.end],
        ),
        reference: ReferenceRecord {
            method: reference.method.name().to_string(),
            substeps: reference.method.substeps(),
            coverage_halving: reference.coverage_halving,
            rms_halving_m: reference
                .halving
                .iter()
                .map(|h| [h.time, h.rms_difference])
                .collect(),
            coarse_grid: [config.choice_coarse_grid.0, config.choice_coarse_grid.1],
            resolution_coverage_difference,
        },
        scene: SceneRecord {
            flag: scene.grid,
            simulation: scene.params_with(choice.method),
        },
    }
}

/// The ablation CSV.
pub fn ablation_csv(rows: &[AblationRow]) -> String {
    let mut csv = String::from(
        "part,setting,method,substeps,iterations,columns,rows,time_s,cpu_ms_per_simulated_s,cost_vs_full,cost_vs_full_low,cost_vs_full_high,rms_vs_full_m,rms_vs_reference_m,silhouette_1_minus_iou,coverage_vs_full,coverage_vs_reference,diverged,self_intersecting_frames\n",
    );
    for r in rows {
        let _ = writeln!(
            csv,
            "{},\"{}\",{},{},{},{},{},{:?},{:?},{},{},{},{},{},{},{},{},{},{}",
            r.part,
            r.setting,
            r.method.name(),
            r.method.substeps(),
            r.method.iterations(),
            r.grid.0,
            r.grid.1,
            r.time,
            r.cpu_ms_per_simulated_second,
            optional(r.cost_vs_full.map(|c| c.median)),
            optional(r.cost_vs_full.map(|c| c.low)),
            optional(r.cost_vs_full.map(|c| c.high)),
            optional(r.rms_vs_full),
            optional(r.rms_vs_reference),
            optional(r.silhouette_difference),
            optional(r.coverage_vs_full),
            optional(r.coverage_vs_reference),
            r.diverged,
            r.self_intersecting_frames
                .map_or(String::new(), |f| f.to_string())
        );
    }
    csv
}

/// Runs the ablation of the default flag with the chosen method as its base ([`Method::default`], the
/// app's default, when nothing met the budget) and writes `ablation.{csv,md}`.
pub fn write_ablation(
    config: &StudyConfig,
    measured: &ChoiceMeasurement,
    out: &Path,
    monitor: &Monitor,
) -> Result<(), StudyError> {
    let scene = &measured.scene;
    let method = measured
        .choice
        .as_ref()
        .map_or(Method::default(), |c| c.method);
    let rows = ablation(
        scene,
        method,
        &measured.reference,
        &config.ablation_grids,
        config.ablation_timing,
        monitor,
    )?;
    write_file(&out.join("ablation.csv"), &ablation_csv(&rows))?;
    let window = config.coverage_window;
    let mut text = format!(
        "# Ablation of the default flag ({}×{}, base method {}{})\n\n\
         Every row runs the base method except the integrator rows. \
         `vs full`: RMS position difference from the full model run by the base method (the part's own effect). \
         `vs reference`: RMS error against the full model's converged reference. \
         Silhouette: 1 − IoU of the coverage silhouettes seen by an orthographic camera looking along −z \
         ({}×{} pixels over a {} m × {} m window) at that time, against the full model run by the base method. \
         Coverage: the time-averaged coverage difference over {}–{} s (per run, so the same at both times) \
         against the full model run by the base method and against the reference. \
         Cost: CPU time on one thread, timed apart from the accuracy runs over the first {} s of a run, \
         {}, each variant beside the full model, the two runs taking turns every {} frames; \
         `CPU ms / simulated s` is the median of the variant's timed runs, `× full` the median of its \
         rounds' ratios to the full model's time (least–greatest in brackets). \
         Through itself: in how many of the first {} frames ({} s) some pair of the cloth's triangles \
         intersects.\n\n\
         Parameters of the full model: {}.\n\n\
         | part | setting | method | t (s) | CPU ms / simulated s | × full | vs full (mm) | vs reference (mm) | silhouette 1 − IoU | coverage vs full | coverage vs reference | through itself |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        scene.grid.columns,
        scene.grid.rows,
        describe(&method),
        if measured.choice.is_some() {
            ", the automatic choice"
        } else {
            ", the app's default: no setting met the budget"
        },
        window.viewport.resolution,
        window.viewport.resolution,
        window.viewport.size,
        window.viewport.size,
        window.start,
        window.end,
        config.ablation_timing.window,
        match config.ablation_timing.rounds {
            1 => "in one round".to_string(),
            rounds => format!("in {rounds} rounds"),
        },
        FRAMES_PER_TURN,
        INTERSECTION_FRAMES,
        INTERSECTION_FRAMES as f64 * scene.frame,
        parameter_line(scene)
    );
    let mm_or_diverged =
        |v: Option<f64>| v.map_or("diverged".to_string(), |v| format!("{:.2}", v * 1e3));
    for r in &rows {
        let _ = writeln!(
            text,
            "| {} | {} | {} | {} | {:.1} | {} | {} | {} | {} | {} | {} | {} |",
            r.part,
            r.setting,
            describe(&r.method),
            r.time,
            r.cpu_ms_per_simulated_second,
            r.cost_vs_full.map_or("—".to_string(), |c| format!(
                "{:.3} ({:.3}–{:.3})",
                c.median, c.low, c.high
            )),
            mm_or_diverged(r.rms_vs_full),
            mm_or_diverged(r.rms_vs_reference),
            fraction(r.silhouette_difference),
            fraction(r.coverage_vs_full),
            fraction(r.coverage_vs_reference),
            r.self_intersecting_frames
                .map_or("diverged".to_string(), |f| f.to_string())
        );
    }
    write_file(&out.join("ablation.md"), &text)
}

/// The seed study's CSV, one row per seed and setting.
pub fn seeds_csv(rows: &[SeedRow]) -> String {
    let mut csv = String::from(
        "seed,setting,method,substeps,coverage_vs_reference,coverage_vs_full,reference_coverage_halving\n",
    );
    for r in rows {
        let _ = writeln!(
            csv,
            "{},\"{}\",{},{},{},{},{}",
            r.seed,
            r.setting,
            r.method.name(),
            r.method.substeps(),
            optional(r.coverage_vs_reference),
            optional(r.coverage_vs_full),
            optional(r.reference_halving)
        );
    }
    csv
}

/// Runs the seed study ([`crate::seeds`]) on the default flag at the choice grid, base method the app's
/// default ([`Method::default`], the committed choice), seeds `1..=count`; writes `seeds.{csv,md}`.
pub fn write_seeds(
    config: &StudyConfig,
    count: u64,
    out: &Path,
    monitor: &Monitor,
) -> Result<(), StudyError> {
    if !(1..=64).contains(&count) {
        return Err(StudyError::InvalidInput {
            name: "--seeds",
            value: count as f64,
            reason: "must be 1 to 64",
        });
    }
    let (columns, rows) = config.choice_grid;
    // The full model renews the wind at every sub-step; the default flag's hold is one of the settings.
    let mut scene = Scene::default_flag()?
        .with_resolution(columns, rows)?
        .with_coverage(Some(config.coverage_window));
    scene.params.wind.renew_at_every_evaluation();
    let method = Method::default();
    let seeds: Vec<u64> = (1..=count).collect();
    let rows = across_seeds(&scene, method, &seeds, &config.choice_times, monitor)?;
    write_file(&out.join("seeds.csv"), &seeds_csv(&rows))?;
    let window = config.coverage_window;
    let halvings: Vec<f64> = seeds
        .iter()
        .filter_map(|&seed| {
            rows.iter()
                .find(|r| r.seed == seed)
                .and_then(|r| r.reference_halving)
        })
        .collect();
    let mut text = format!(
        "# The ablation's closest rows across gust seeds ({}×{}, base method {}{})\n\n\
         Each setting runs on {} flags that differ only in the seed of the wind's gusts and turbulence \
         (`wind.seed` = 1 … {}), each against its own reference (velocity Verlet, the full model, the wind \
         renewed every sub-step). `D`: the time-averaged coverage difference over {}–{} s from that \
         seed's reference. `change`: the mean over the seeds of `D(setting) − D(full model)` on the same \
         seed, ± its standard error. The references' own halving differences: {}.\n\n\
         Parameters of the full model: {}.\n\n\
         | setting | method | seeds | mean D | spread (s) | least–greatest | change vs full model |\n\
         |---|---|---|---|---|---|---|\n",
        scene.grid.columns,
        scene.grid.rows,
        describe(&method),
        if config.quick {
            "; **--quick: a small grid and a short window, not a result**"
        } else {
            ""
        },
        count,
        count,
        window.start,
        window.end,
        halvings
            .iter()
            .map(|h| format!("{h:.4}"))
            .collect::<Vec<_>>()
            .join(", "),
        parameter_line(&scene)
    );
    for (setting, summary) in summarise(&rows) {
        match summary {
            Some(s) => {
                let _ = writeln!(
                    text,
                    "| {} | {} | {} | {:.4} | {:.4} | {:.4}–{:.4} | {:+.4} ± {:.4} |",
                    setting,
                    describe(&s.method),
                    s.seeds,
                    s.mean_vs_reference,
                    s.spread_vs_reference,
                    s.least_vs_reference,
                    s.greatest_vs_reference,
                    s.mean_change,
                    s.change_standard_error
                );
            }
            None => {
                let _ = writeln!(
                    text,
                    "| {setting} | — | 0 (diverged on every seed) | | | | |"
                );
            }
        }
    }
    write_file(&out.join("seeds.md"), &text)
}

/// The stability CSV.
pub fn stability_csv(map: &StabilityMap) -> String {
    let mut csv = String::from("method,stiffness_n_per_m,dt_s,class,rms_position_error_m\n");
    for c in &map.cells {
        let _ = writeln!(
            csv,
            "{},{:?},{:?},{},{}",
            c.method.name(),
            c.stiffness,
            c.dt,
            c.class.name(),
            optional(c.rms_position_error)
        );
    }
    csv
}

/// Runs the stability map and the bisection for the explicit symplectic methods' boundary; writes
/// `stability-map.{csv,png,md}`.
pub fn write_stability(
    config: &StudyConfig,
    out: &Path,
    monitor: &Monitor,
) -> Result<(), StudyError> {
    let setup = StabilitySetup {
        grid: config.stability_grid,
        stiffnesses: config.stability_stiffnesses.clone(),
        steps: config.stability_steps.clone(),
        duration: config.stability_duration,
        error_bound: 5e-3,
        methods: map_methods(),
    };
    let map = stability_map(&setup, monitor)?;
    write_file(&out.join("stability-map.csv"), &stability_csv(&map))?;
    stability_chart(&map, &out.join("stability-map.png"))?;
    let mut text = format!(
        "# Stability boundary of the explicit symplectic methods\n\n\
         Undamped {}×{} sheet hung from its top edge under gravity. Predicted limit `2/ω_max` with `ω_max` \
         from power iteration on `M^(-1/2) K M^(-1/2)` (3000 iterations) and from the Gershgorin bound (a \
         guaranteed lower bound on the limit); found: the largest step that survives {} s, bisected to 2^-10 \
         in log dt.\n\n| method | stretch k (N/m) | 2/ω_max power (s) | 2/ω_max Gershgorin (s) | found (s) | found / predicted |\n|---|---|---|---|---|---|\n",
        setup.grid.0, setup.grid.1, setup.duration
    );
    monitor.add_work(0);
    for prediction in &map.predictions {
        let scene = Scene::undamped_sheet(setup.grid, prediction.stiffness)?;
        for method in [
            Method::SymplecticEuler { substeps: 1 },
            Method::Verlet { substeps: 1 },
        ] {
            monitor.check()?;
            let found = find_stability_boundary(
                &scene,
                method,
                0.5 * prediction.dt_power_iteration,
                1.5 * prediction.dt_power_iteration,
                setup.duration,
                10,
                monitor,
            )?;
            let _ = writeln!(
                text,
                "| {} | {} | {:.4e} | {:.4e} | {:.4e} | {:.4} |",
                method.name(),
                prediction.stiffness,
                prediction.dt_power_iteration,
                prediction.dt_gershgorin,
                found,
                found / prediction.dt_power_iteration
            );
        }
    }
    write_file(&out.join("stability-map.md"), &text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_missing_file_reads_as_empty() {
        let dir = std::env::temp_dir().join(format!("sheer-study-read-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert_eq!(read_existing(&dir.join("missing.md")).unwrap(), "");
        // Not UTF-8: reading fails, and the file must not be treated as empty (then overwritten).
        let garbled = dir.join("work-precision.md");
        std::fs::write(&garbled, [0xff, 0xfe, b'#']).unwrap();
        assert!(matches!(
            read_existing(&garbled),
            Err(StudyError::Io { .. })
        ));
        std::fs::write(&garbled, "# kept\n").unwrap();
        assert_eq!(read_existing(&garbled).unwrap(), "# kept\n");
        std::fs::remove_dir_all(&dir).ok();
    }
}
