//! Charts how wrong the paper's single-scattering model (eqs. (4)–(5)) is against all orders of
//! scattering, over τ1 ∈ [0.01, 10] for Λ = 0.5, 0.9, 1 and three (μ0, μ) pairs, both faces. Writes
//! `docs/single-vs-all-orders.csv` and `docs/single-vs-all-orders.png` and prints where each curve
//! crosses 1 % (the paper claims < 1 % for τ1 ≤ 0.2).
//!
//! `cargo run -p sheer-transport --release --example chart_single_vs_all`
//!
//! Text is drawn with ab_glyph from a TrueType file: DejaVu Sans from the usual Debian path, or the
//! file named by `SHEER_CHART_FONT`.

use plotters::prelude::*;
use sheer_transport::{
    SlabSolver, single_scattered_reflected_radiance, single_scattered_transmitted_radiance,
};
use std::fmt::Write as _;

const ALBEDOS: [f64; 3] = [0.5, 0.9, 1.0];
/// (μ0, μ): normal incidence and viewing; oblique light seen more grazing; grazing light seen near
/// normal.
const GEOMETRIES: [(f64, f64); 3] = [(1.0, 1.0), (0.7, 0.4), (0.3, 0.9)];
const SAMPLES: usize = 61;

struct Curve {
    reflected: bool,
    albedo: f64,
    mu0: f64,
    mu: f64,
    /// (τ1, single, all orders, relative error (all − single)/all).
    points: Vec<(f64, f64, f64, f64)>,
}

/// Relative error (all − single)/all of single scattering for one configuration.
fn relative_error(
    tau1: f64,
    albedo: f64,
    mu0: f64,
    mu: f64,
    reflected: bool,
) -> Result<f64, sheer_transport::TransportError> {
    let solution = SlabSolver::new(tau1, albedo)?.solve(mu0)?;
    let (single, all) = if reflected {
        (
            single_scattered_reflected_radiance(tau1, albedo, mu0, mu)?,
            solution.reflected_radiance(mu)?,
        )
    } else {
        (
            single_scattered_transmitted_radiance(tau1, albedo, mu0, mu)?,
            solution.transmitted_radiance(mu)?,
        )
    };
    Ok((all - single) / all)
}

/// τ1 at which the relative error reaches `threshold`, by bisection in `ln τ1` on [1e-6, 10] (the error
/// increases with τ1); 40 halvings resolve it to 1e-9 relative.
fn threshold_crossing(
    curve: &Curve,
    threshold: f64,
) -> Result<Option<f64>, sheer_transport::TransportError> {
    let (mut low, mut high) = (1e-6f64.ln(), 10f64.ln());
    let error_at = |log_tau: f64| {
        relative_error(
            log_tau.exp(),
            curve.albedo,
            curve.mu0,
            curve.mu,
            curve.reflected,
        )
    };
    if error_at(high)? < threshold || error_at(low)? > threshold {
        return Ok(None);
    }
    for _ in 0..40 {
        let middle = 0.5 * (low + high);
        if error_at(middle)? < threshold {
            low = middle;
        } else {
            high = middle;
        }
    }
    Ok(Some((0.5 * (low + high)).exp()))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let taus: Vec<f64> = (0..SAMPLES)
        .map(|i| 10f64.powf(-2.0 + 3.0 * i as f64 / (SAMPLES - 1) as f64))
        .collect();
    let mut curves = Vec::new();
    for &albedo in &ALBEDOS {
        let mut reflected: Vec<Curve> = Vec::new();
        let mut transmitted: Vec<Curve> = Vec::new();
        for &(mu0, mu) in &GEOMETRIES {
            for (list, side) in [(&mut reflected, true), (&mut transmitted, false)] {
                list.push(Curve {
                    reflected: side,
                    albedo,
                    mu0,
                    mu,
                    points: Vec::new(),
                });
            }
        }
        for &tau1 in &taus {
            let solver = SlabSolver::new(tau1, albedo)?;
            for (g, &(mu0, mu)) in GEOMETRIES.iter().enumerate() {
                let solution = solver.solve(mu0)?;
                let single = single_scattered_reflected_radiance(tau1, albedo, mu0, mu)?;
                let all = solution.reflected_radiance(mu)?;
                reflected[g]
                    .points
                    .push((tau1, single, all, (all - single) / all));
                let single = single_scattered_transmitted_radiance(tau1, albedo, mu0, mu)?;
                let all = solution.transmitted_radiance(mu)?;
                transmitted[g]
                    .points
                    .push((tau1, single, all, (all - single) / all));
            }
        }
        curves.extend(reflected);
        curves.extend(transmitted);
    }

    let docs = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs");
    let mut csv = String::from(
        "side,albedo,mu0,mu,tau1,single_scattering_radiance,all_orders_radiance,relative_error\n",
    );
    for curve in &curves {
        let side = if curve.reflected {
            "reflected"
        } else {
            "transmitted"
        };
        for &(tau1, single, all, error) in &curve.points {
            writeln!(
                csv,
                "{side},{},{},{},{tau1:.6e},{single:.10e},{all:.10e},{error:.6e}",
                curve.albedo, curve.mu0, curve.mu
            )?;
        }
    }
    let csv_path = format!("{docs}/single-vs-all-orders.csv");
    // Each file is written under a hidden name and renamed into place when complete.
    let partial_csv = format!("{docs}/.single-vs-all-orders.part.csv");
    std::fs::write(&partial_csv, csv)?;
    std::fs::rename(&partial_csv, &csv_path)?;

    println!("side        albedo  mu0  mu   err@0.01   err@0.2    err@2      tau1 where err = 1%");
    for curve in &curves {
        let at = |tau: f64| {
            curve
                .points
                .iter()
                .min_by(|a, b| {
                    (a.0.ln() - tau.ln())
                        .abs()
                        .total_cmp(&(b.0.ln() - tau.ln()).abs())
                })
                .map_or(f64::NAN, |p| p.3)
        };
        let crossing = threshold_crossing(curve, 0.01)?
            .map_or("outside [1e-6, 10]".to_string(), |t| format!("{t:.5}"));
        println!(
            "{:<11} {:<6}  {:<4} {:<4} {:<10.3e} {:<10.3e} {:<10.3e} {crossing}",
            if curve.reflected {
                "reflected"
            } else {
                "transmitted"
            },
            curve.albedo,
            curve.mu0,
            curve.mu,
            at(0.01),
            at(0.2),
            at(2.0)
        );
    }

    let font_path = std::env::var("SHEER_CHART_FONT")
        .unwrap_or_else(|_| "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf".to_string());
    let font: &'static [u8] = Box::leak(
        std::fs::read(&font_path)
            .map_err(|e| format!("cannot read font {font_path} ({e}); set SHEER_CHART_FONT"))?
            .into_boxed_slice(),
    );
    plotters::style::register_font("sans-serif", FontStyle::Normal, font)
        .map_err(|_| format!("{font_path} is not a usable TrueType font"))?;

    let png_path = format!("{docs}/single-vs-all-orders.png");
    let partial_png = format!("{docs}/.single-vs-all-orders.part.png");
    let root = BitMapBackend::new(&partial_png, (1600, 760)).into_drawing_area();
    root.fill(&WHITE)?;
    let (title, body) = root.split_vertically(50);
    title.draw(&Text::new(
        "Single scattering (Frisvad et al. 2005, eqs. 4-5) vs all orders: relative error (all - single) / all",
        (20, 14),
        ("sans-serif", 24).into_font(),
    ))?;
    let colours = [
        RGBColor(0, 114, 178),
        RGBColor(230, 159, 0),
        RGBColor(204, 51, 17),
    ];
    for (panel, reflected) in body.split_evenly((1, 2)).iter().zip([true, false]) {
        let caption = if reflected {
            "Reflected (lit face), eq. (4)"
        } else {
            "Transmitted (unlit face), eq. (5)"
        };
        let mut chart = ChartBuilder::on(panel)
            .caption(caption, ("sans-serif", 22))
            .margin(18)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d((0.01f64..10.0).log_scale(), (5e-3f64..1.0).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("optical thickness tau1")
            .y_desc("relative error of single scattering")
            .label_style(("sans-serif", 16))
            .axis_desc_style(("sans-serif", 18))
            .draw()?;
        // The paper's claim: below 1 % for tau1 <= 0.2.
        chart.draw_series(LineSeries::new(
            vec![(0.01, 0.01), (10.0, 0.01)],
            BLACK.stroke_width(1),
        ))?;
        chart.draw_series(LineSeries::new(
            vec![(0.2, 5e-3), (0.2, 1.0)],
            BLACK.stroke_width(1),
        ))?;
        for curve in curves.iter().filter(|c| c.reflected == reflected) {
            let a = ALBEDOS.iter().position(|&x| x == curve.albedo).unwrap_or(0);
            let g = GEOMETRIES
                .iter()
                .position(|&x| x == (curve.mu0, curve.mu))
                .unwrap_or(0);
            let colour = colours[a];
            let data: Vec<(f64, f64)> = curve.points.iter().map(|p| (p.0, p.3.max(5e-3))).collect();
            let label = format!(
                "albedo {}  mu0 {}  mu {}",
                curve.albedo, curve.mu0, curve.mu
            );
            let width = [3, 1, 2][g];
            chart
                .draw_series(LineSeries::new(data.clone(), colour.stroke_width(width)))?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 24, y)], colour.stroke_width(width))
                });
            if g == 2 {
                chart.draw_series(
                    data.iter()
                        .step_by(4)
                        .map(|&p| Circle::new(p, 3, colour.filled())),
                )?;
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .label_font(("sans-serif", 15))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
    }
    root.present()?;
    std::fs::rename(&partial_png, &png_path)?;
    println!("wrote {csv_path} and {png_path}");
    Ok(())
}
