//! Charts (plotters, PNG): the work–precision chart and the stability map.
//!
//! Text is drawn by ab_glyph from a TrueType font read at run time: DejaVu Sans (Bitstream Vera
//! licence, permissive; Debian package `fonts-dejavu-core`) unless `SHEER_FONT` names another file. No
//! font file is committed.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};
use sheer_cloth::Method;

use crate::StudyError;
use crate::stability::{StabilityClass, StabilityMap};
use crate::work_precision::Row;

/// Where the chart font is looked for when `SHEER_FONT` is not set.
pub const DEFAULT_FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

/// Registers the chart font once per process as plotters' "sans-serif".
pub fn register_chart_font() -> Result<(), StudyError> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    let path = std::env::var("SHEER_FONT").unwrap_or_else(|_| DEFAULT_FONT.to_string());
    REGISTERED
        .get_or_init(|| {
            let bytes = std::fs::read(&path).map_err(|e| e.to_string())?;
            // plotters keeps fonts for the life of the process; registered once, so leaked once.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            register_font("sans-serif", FontStyle::Normal, bytes)
                .map_err(|_| "not a TrueType font".to_string())
        })
        .clone()
        .map_err(|message| StudyError::Font { path, message })
}

fn chart_error(path: &Path, error: impl std::fmt::Display) -> StudyError {
    StudyError::Chart {
        path: path.display().to_string(),
        message: error.to_string(),
    }
}

fn method_colour(name: &str) -> RGBColor {
    match name {
        "explicit_euler" => RGBColor(150, 150, 150),
        "symplectic_euler" => RGBColor(31, 119, 180),
        "verlet" => RGBColor(23, 190, 207),
        "implicit_euler" => RGBColor(214, 39, 40),
        "pbd" => RGBColor(255, 127, 14),
        "xpbd" => RGBColor(44, 160, 44),
        _ => RGBColor(148, 103, 189),
    }
}

/// One panel of the work–precision chart: (method name, error, cost) points and the reference's own
/// halving difference in the same measure.
struct Panel {
    title: String,
    x_desc: &'static str,
    halving: f64,
    points: Vec<(&'static str, f64, f64)>,
}

/// The panels of `rows`: one per (scene, time) with the RMS position error, then one per scene with a
/// coverage window with the time-averaged coverage difference (one point per run).
fn panels(rows: &[Row]) -> Vec<Panel> {
    let mut keys: Vec<(String, f64)> = Vec::new();
    for row in rows {
        let key = (row.scene.clone(), row.metrics.time);
        if !keys.contains(&key) {
            keys.push(key);
        }
    }
    let particles_of = |scene: &str| {
        rows.iter()
            .find(|r| r.scene == scene)
            .map_or(0, |r| r.particles)
    };
    let mut panels = Vec::new();
    for (scene, time) in &keys {
        let panel: Vec<&Row> = rows
            .iter()
            .filter(|r| &r.scene == scene && r.metrics.time == *time)
            .collect();
        panels.push(Panel {
            title: format!("{scene} ({} particles), t = {time} s", particles_of(scene)),
            x_desc: "RMS position error (m)",
            halving: panel
                .iter()
                .map(|r| r.reference_rms_halving)
                .fold(0.0, f64::max),
            points: panel
                .iter()
                .filter_map(|r| {
                    Some((
                        r.method.name(),
                        r.metrics.rms_position_error?,
                        r.cpu_ms_per_simulated_second,
                    ))
                })
                .collect(),
        });
    }
    let mut scenes: Vec<&str> = Vec::new();
    for row in rows {
        if row.coverage_difference.is_some() && !scenes.contains(&row.scene.as_str()) {
            scenes.push(&row.scene);
        }
    }
    for scene in scenes {
        let mut seen: Vec<Method> = Vec::new();
        let mut points = Vec::new();
        let mut halving = 0.0f64;
        for r in rows.iter().filter(|r| r.scene == scene) {
            if seen.contains(&r.method) {
                continue;
            }
            seen.push(r.method);
            halving = halving.max(r.reference_coverage_halving.unwrap_or(0.0));
            if let Some(d) = r.coverage_difference {
                points.push((r.method.name(), d, r.cpu_ms_per_simulated_second));
            }
        }
        panels.push(Panel {
            title: format!(
                "{scene} ({} particles), time-averaged coverage",
                particles_of(scene)
            ),
            x_desc: "coverage difference (fraction of covered area)",
            halving,
            points,
        });
    }
    panels
}

/// Work–precision chart: one panel per (scene, time), RMS position error (m) against CPU ms per
/// simulated second, log–log, one line per method through its knob settings (sorted by cost), plus one
/// panel per flag scene with the time-averaged coverage difference on the error axis. Diverged runs are
/// left out (the CSV lists them). A dashed vertical line marks the reference's halving difference:
/// errors left of it are not resolved.
pub fn work_precision_chart(rows: &[Row], path: &Path) -> Result<(), StudyError> {
    register_chart_font()?;
    let panels = panels(rows);
    let columns = panels.len().clamp(1, 3);
    let panel_rows = panels.len().div_ceil(columns).max(1);
    // Drawn under a hidden name and renamed into place when complete.
    let partial = crate::whole_file::partial_path(path);
    let root = BitMapBackend::new(
        &partial,
        (560 * columns as u32, 460 * panel_rows as u32 + 40),
    )
    .into_drawing_area();
    root.fill(&WHITE).map_err(|e| chart_error(path, e))?;
    let (title, body) = root.split_vertically(40);
    title
        .titled(
            "Work–precision: error against the reference vs CPU cost (one thread)",
            ("sans-serif", 22),
        )
        .map_err(|e| chart_error(path, e))?;
    let areas = body.split_evenly((panel_rows, columns));
    for (panel, area) in panels.iter().zip(areas) {
        let points: Vec<(f64, f64)> = panel
            .points
            .iter()
            .map(|&(_, e, c)| (e, c))
            .filter(|(e, c)| *e > 0.0 && *c > 0.0)
            .collect();
        if points.is_empty() {
            continue;
        }
        let halving = panel.halving;
        let (mut x0, mut x1, mut y0, mut y1) = points.iter().fold(
            (f64::MAX, f64::MIN, f64::MAX, f64::MIN),
            |(a, b, c, d), (x, y)| (a.min(*x), b.max(*x), c.min(*y), d.max(*y)),
        );
        if halving > 0.0 {
            x0 = x0.min(halving);
        }
        x0 /= 2.0;
        x1 *= 2.0;
        y0 /= 2.0;
        y1 *= 2.0;
        let mut chart = ChartBuilder::on(&area)
            .caption(&panel.title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(62)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|e| chart_error(path, e))?;
        chart
            .configure_mesh()
            .x_desc(panel.x_desc)
            .y_desc("CPU ms per simulated s")
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(|e| chart_error(path, e))?;
        if halving > 0.0 {
            chart
                .draw_series(DashedLineSeries::new(
                    [(halving, y0), (halving, y1)],
                    6,
                    4,
                    BLACK.stroke_width(1),
                ))
                .map_err(|e| chart_error(path, e))?
                .label("reference halving difference")
                .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BLACK));
        }
        for name in Method::NAMES {
            let mut line: Vec<(f64, f64)> = panel
                .points
                .iter()
                .filter(|(n, _, _)| *n == name)
                .map(|&(_, e, c)| (e, c))
                .filter(|(e, c)| *e > 0.0 && *c > 0.0)
                .collect();
            if line.is_empty() {
                continue;
            }
            line.sort_by(|a, b| a.1.total_cmp(&b.1));
            let colour = method_colour(name);
            chart
                .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))
                .map_err(|e| chart_error(path, e))?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 16, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(line.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                .map_err(|e| chart_error(path, e))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 12))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| chart_error(path, e))?;
    }
    root.present().map_err(|e| chart_error(path, e))?;
    crate::whole_file::rename_into_place(&partial, path)
}

/// Geometric cell edges around sorted log-spaced values.
fn log_edges(values: &[f64]) -> Vec<f64> {
    let mut edges = Vec::with_capacity(values.len() + 1);
    for i in 0..=values.len() {
        let edge = match i {
            0 if values.len() > 1 => values[0] * (values[0] / values[1]).sqrt(),
            0 => values[0] / 2.0,
            i if i == values.len() && values.len() > 1 => {
                values[i - 1] * (values[i - 1] / values[i - 2]).sqrt()
            }
            i if i == values.len() => values[i - 1] * 2.0,
            i => (values[i - 1] * values[i]).sqrt(),
        };
        edges.push(edge);
    }
    edges
}

/// Stability map: one panel per method, time step (s) across, stretch stiffness (N/m) up, cells
/// green (stable), orange (inaccurate) or red (diverged); the mass–spring panels carry the linear
/// prediction `dt = 2/ω_max` (power iteration) as a black line.
pub fn stability_chart(map: &StabilityMap, path: &Path) -> Result<(), StudyError> {
    register_chart_font()?;
    let mut steps: Vec<f64> = map.cells.iter().map(|c| c.dt).collect();
    steps.sort_by(f64::total_cmp);
    steps.dedup();
    let stiffnesses = map.setup.stiffnesses.clone();
    if steps.is_empty() || stiffnesses.is_empty() {
        return Err(chart_error(path, "empty stability map"));
    }
    let step_edges = log_edges(&steps);
    let stiffness_edges = log_edges(&stiffnesses);
    let names: Vec<&str> = Method::NAMES
        .iter()
        .copied()
        .filter(|n| map.cells.iter().any(|c| c.method.name() == *n))
        .collect();
    let columns = 4usize;
    let panel_rows = names.len().div_ceil(columns).max(1);
    // Drawn under a hidden name and renamed into place when complete.
    let partial = crate::whole_file::partial_path(path);
    let root = BitMapBackend::new(
        &partial,
        (420 * columns as u32, 380 * panel_rows as u32 + 70),
    )
    .into_drawing_area();
    root.fill(&WHITE).map_err(|e| chart_error(path, e))?;
    let (title, body) = root.split_vertically(70);
    title
        .titled(
            &format!(
                "Stability map, undamped {}×{} sheet, {} s: green stable, orange RMS error > {} mm, red diverged; line: 2/ω_max",
                map.setup.grid.0,
                map.setup.grid.1,
                map.setup.duration,
                map.setup.error_bound * 1e3
            ),
            ("sans-serif", 20),
        )
        .map_err(|e| chart_error(path, e))?;
    let (x0, x1) = (step_edges[0], step_edges[steps.len()]);
    let (y0, y1) = (stiffness_edges[0], stiffness_edges[stiffnesses.len()]);
    for (name, area) in names.iter().zip(body.split_evenly((panel_rows, columns))) {
        let mut chart = ChartBuilder::on(&area)
            .caption(*name, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(56)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|e| chart_error(path, e))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("time step (s)")
            .y_desc("stretch stiffness (N/m)")
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(|e| chart_error(path, e))?;
        let cells = map.cells.iter().filter(|c| c.method.name() == *name);
        chart
            .draw_series(cells.filter_map(|cell| {
                let i = steps.iter().position(|&s| s == cell.dt)?;
                let j = stiffnesses.iter().position(|&k| k == cell.stiffness)?;
                let colour = match cell.class {
                    StabilityClass::Stable => RGBColor(120, 200, 120),
                    StabilityClass::Inaccurate => RGBColor(250, 180, 80),
                    StabilityClass::Diverged => RGBColor(220, 70, 60),
                };
                Some(Rectangle::new(
                    [
                        (step_edges[i], stiffness_edges[j]),
                        (step_edges[i + 1], stiffness_edges[j + 1]),
                    ],
                    colour.filled(),
                ))
            }))
            .map_err(|e| chart_error(path, e))?;
        if matches!(*name, "symplectic_euler" | "verlet" | "explicit_euler") {
            let line: Vec<(f64, f64)> = map
                .predictions
                .iter()
                .map(|p| (p.dt_power_iteration, p.stiffness))
                .filter(|(dt, _)| *dt > x0 && *dt < x1)
                .collect();
            chart
                .draw_series(LineSeries::new(line, BLACK.stroke_width(2)))
                .map_err(|e| chart_error(path, e))?;
        }
    }
    root.present().map_err(|e| chart_error(path, e))?;
    crate::whole_file::rename_into_place(&partial, path)
}
