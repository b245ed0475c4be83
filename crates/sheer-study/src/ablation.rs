//! Ablation: what each part of the model costs and what it changes.
//!
//! Every variant of the flag (one part switched off, another integrator, another resolution) runs
//! with the same sampling and the same base method (the automatic choice), except the integrator rows;
//! its positions are compared with the full model run by the base method (the part's own effect) and
//! with the full model's converged reference (effect plus integration error), its silhouette with the
//! full model's (see [`crate::silhouette`]) and, when the scene has a coverage window, its
//! time-averaged coverage with the full model's and the reference's ([`crate::coverage`]). Grids of
//! another resolution are compared at the full model's particles through bilinear interpolation in the
//! cloth's (u, v) parameters; coverage needs no resampling.
//!
//! What a part costs is timed apart from the accuracy runs ([`CostTiming`]): each variant beside the
//! full model, the two runs taking turns every few frames, for a few rounds, and the variant's time over
//! the full model's in the same round ([`CostRatio`]). One run each had not been enough: over the
//! minutes an ablation takes, the host's pace drifts by more than most parts cost (one such run had
//! the flag without bending 22 % *dearer* than with it), and even back to back, a simulated second
//! each, the rounds' ratios spread by ±15 %.

use sheer_cloth::glam::DVec3;
use sheer_cloth::{
    Collider, GridSpec, Method, SimParams, SpringParams, intersecting_triangle_pairs,
};

use crate::coverage::coverage_difference;
use crate::cpu::thread_cpu_seconds;
use crate::metrics::position_errors;
use crate::reference::Reference;
use crate::run::{Trajectory, on_one_thread, simulate};
use crate::silhouette::{Viewport, coverage, silhouette_difference};
use crate::{Monitor, Scene, StudyError};

/// One variant at one sample time.
#[derive(Clone, Debug, PartialEq)]
pub struct AblationRow {
    /// Which part is changed (`full`, `shear`, `bending`, …).
    pub part: String,
    /// What it is changed to.
    pub setting: String,
    /// The integrator the variant was run with.
    pub method: Method,
    /// The variant's grid, (columns, rows) particles.
    pub grid: (usize, usize),
    /// Simulated time, s.
    pub time: f64,
    /// CPU milliseconds per simulated second (one thread): the median of the variant's timed runs
    /// ([`CostTiming`]).
    pub cpu_ms_per_simulated_second: f64,
    /// The variant's CPU time over the full model's, the two run side by side ([`CostTiming`]; `None` on
    /// the full model's own rows and where every timed run diverged).
    pub cost_vs_full: Option<CostRatio>,
    /// RMS position difference from the full model run by the same method, m.
    pub rms_vs_full: Option<f64>,
    /// RMS position error against the full model's converged reference, m.
    pub rms_vs_reference: Option<f64>,
    /// `1 − IoU` of the orthographic coverage silhouettes of this variant and the full model.
    pub silhouette_difference: Option<f64>,
    /// Time-averaged coverage difference from the full model run by the base method (the same on each
    /// of the variant's rows; `None` without a coverage window or when either run diverged).
    pub coverage_vs_full: Option<f64>,
    /// Time-averaged coverage difference from the full model's reference.
    pub coverage_vs_reference: Option<f64>,
    /// Whether the variant's run diverged before `time` (its error columns are then `None`).
    pub diverged: bool,
    /// In how many of the first [`INTERSECTION_FRAMES`] frames the cloth passes through itself (some
    /// pair of triangles intersects: `sheer_cloth::intersecting_triangle_pairs`); the same on each of
    /// the variant's rows; `None` when the run diverged first.
    pub self_intersecting_frames: Option<usize>,
}

/// Frames over which [`AblationRow::self_intersecting_frames`] counts (10 s at 60 Hz: the coverage
/// window's 2.5 s is too short for the default flag to fold through itself).
pub const INTERSECTION_FRAMES: usize = 600;

/// In how many of the first [`INTERSECTION_FRAMES`] frames of `scene` run by `method` the cloth passes
/// through itself (`None` if the run diverges).
fn self_intersecting_frames(
    scene: &Scene,
    method: Method,
    monitor: &Monitor,
) -> Result<Option<usize>, StudyError> {
    on_one_thread(|| {
        let mut sim = scene.simulation(method)?;
        let triangles = sim.triangles().to_vec();
        let mut frames = 0;
        for frame in 0..INTERSECTION_FRAMES {
            if sim.step(scene.frame).is_err() {
                return Ok(None);
            }
            frames += usize::from(intersecting_triangle_pairs(sim.positions(), &triangles) > 0);
            if frame % 60 == 0 {
                monitor.check()?;
            }
        }
        Ok(Some(frames))
    })?
}

/// Position of grid `spec` at parameters `(u, v)` ∈ [0, 1]² by bilinear interpolation of `positions`.
fn sample_grid(positions: &[DVec3], spec: &GridSpec, u: f64, v: f64) -> DVec3 {
    let x = u * (spec.columns - 1) as f64;
    let y = v * (spec.rows - 1) as f64;
    let (c0, r0) = (
        (x.floor() as usize).min(spec.columns - 2),
        (y.floor() as usize).min(spec.rows - 2),
    );
    let (fx, fy) = (x - c0 as f64, y - r0 as f64);
    let at = |r: usize, c: usize| positions[r * spec.columns + c];
    let top = at(r0, c0).lerp(at(r0, c0 + 1), fx);
    let bottom = at(r0 + 1, c0).lerp(at(r0 + 1, c0 + 1), fx);
    top.lerp(bottom, fy)
}

/// `positions` of grid `from` resampled at the particles of grid `to`.
pub(crate) fn resample(positions: &[DVec3], from: &GridSpec, to: &GridSpec) -> Vec<DVec3> {
    if from.columns == to.columns && from.rows == to.rows {
        return positions.to_vec();
    }
    let mut out = Vec::with_capacity(to.columns * to.rows);
    for r in 0..to.rows {
        for c in 0..to.columns {
            let u = c as f64 / (to.columns - 1) as f64;
            let v = r as f64 / (to.rows - 1) as f64;
            out.push(sample_grid(positions, from, u, v));
        }
    }
    out
}

/// How the ablation times its variants: `rounds` rounds, each running every variant beside the full
/// model over the first `window` simulated seconds (s), the two taking turns every six frames (the
/// first turn alternating between them from variant to variant and round to round), without snapshots
/// or coverage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostTiming {
    /// Rounds of timed runs per variant (each a ratio; the median is reported).
    pub rounds: usize,
    /// Simulated time each timed run covers, s.
    pub window: f64,
}

/// A variant's cost as a multiple of the full model's: the median of its rounds' ratios, and the least
/// and greatest of them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostRatio {
    /// The median of the rounds' ratios.
    pub median: f64,
    /// The least of them.
    pub low: f64,
    /// The greatest of them.
    pub high: f64,
}

impl CostRatio {
    /// The median, least and greatest of `ratios` (`None` when there are none).
    pub fn of(ratios: &[f64]) -> Option<CostRatio> {
        let mut sorted = ratios.to_vec();
        sorted.sort_by(f64::total_cmp);
        Some(CostRatio {
            median: median_of_sorted(&sorted)?,
            low: *sorted.first()?,
            high: *sorted.last()?,
        })
    }
}

/// The median of sorted `values` (the mean of the middle two for an even count).
fn median_of_sorted(values: &[f64]) -> Option<f64> {
    let n = values.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(values[n / 2]),
        _ => Some(0.5 * (values[n / 2 - 1] + values[n / 2])),
    }
}

/// Frames each run advances before the other takes its turn in [`paired_costs`].
pub(crate) const FRAMES_PER_TURN: u64 = 6;

/// CPU milliseconds per simulated second of the full model and of `variant` over the first `window` s,
/// the two runs taking turns every [`FRAMES_PER_TURN`] frames (the first turn `full_first`'s, then
/// alternately which goes first), so that a change in the host's pace falls on both alike (`None` if
/// either diverged).
fn paired_costs(
    full: &Variant,
    variant: &Variant,
    window: f64,
    full_first: bool,
    monitor: &Monitor,
) -> Result<Option<[f64; 2]>, StudyError> {
    on_one_thread(|| {
        let mut sims = Vec::with_capacity(2);
        for v in [full, variant] {
            sims.push((v.scene.simulation(v.method)?, v.scene.frame));
        }
        let frames: Vec<u64> = sims
            .iter()
            .map(|(_, frame)| (window / frame).round().max(1.0) as u64)
            .collect();
        let mut cpu = [0.0; 2];
        let mut done = [0u64; 2];
        let mut turn = 0u64;
        while done[0] < frames[0] || done[1] < frames[1] {
            let order = if full_first == turn.is_multiple_of(2) {
                [0, 1]
            } else {
                [1, 0]
            };
            for i in order {
                let (sim, frame) = &mut sims[i];
                let steps = FRAMES_PER_TURN.min(frames[i] - done[i]);
                let started = thread_cpu_seconds();
                for _ in 0..steps {
                    if sim.step(*frame).is_err() {
                        return Ok(None);
                    }
                }
                cpu[i] += thread_cpu_seconds() - started;
                done[i] += steps;
            }
            turn += 1;
            monitor.check()?;
        }
        Ok(Some(std::array::from_fn(|i| {
            1e3 * cpu[i] / (frames[i] as f64 * sims[i].1)
        })))
    })?
}

struct Variant {
    part: &'static str,
    setting: String,
    scene: Scene,
    method: Method,
}

fn with_params(scene: &Scene, change: impl FnOnce(&mut SimParams)) -> Scene {
    let mut changed = scene.clone();
    change(&mut changed.params);
    changed
}

/// How long the wind's forces are held between renewals (`wind.renewal_interval`): renewed at every
/// sub-step the default flag costs 1.150× its frame with the 2 ms hold (docs/ablation.md); held longer it
/// costs less. Every interval of 0 (every sub-step), 1, 2 and 4 ms but the scene's own, and once per
/// frame.
fn wind_interval_variants(scene: &Scene, method: Method) -> Vec<Variant> {
    let wind = scene.params.wind;
    let mut variants = Vec::new();
    for interval in WIND_RENEWAL_INTERVALS {
        if wind.per_substep && wind.renewal_interval == interval {
            continue;
        }
        variants.push(Variant {
            part: "wind renewal",
            setting: wind_renewal_setting(interval, scene.frame, method),
            scene: with_params(scene, |p| {
                p.wind.per_substep = true;
                p.wind.renewal_interval = interval;
            }),
            method,
        });
    }
    if wind.per_substep {
        variants.push(Variant {
            part: "wind renewal",
            setting: "once per frame".into(),
            scene: with_params(scene, |p| p.wind.hold_for_each_step()),
            method,
        });
    }
    variants
}

/// The wind renewal intervals of the ablation and the seed study, s.
pub(crate) const WIND_RENEWAL_INTERVALS: [f64; 4] = [0.0, 0.001, 0.002, 0.004];

/// An interval in words, with the sub-steps of `method` it holds the forces for at steps of `frame` s.
pub(crate) fn wind_renewal_setting(interval: f64, frame: f64, method: Method) -> String {
    if interval == 0.0 {
        return "every sub-step".into();
    }
    let h = frame / f64::from(method.substeps());
    let wind = sheer_cloth::Wind {
        renewal_interval: interval,
        ..sheer_cloth::Wind::default()
    };
    format!(
        "held ≤ {} ms (every {} sub-steps)",
        milliseconds(interval),
        wind.substeps_per_renewal(h)
    )
}

/// `seconds` in milliseconds, rounded to the microsecond for printing (0.007 s prints as 7, not
/// 7.000000000000001).
pub(crate) fn milliseconds(seconds: f64) -> f64 {
    (seconds * 1e6).round() / 1e3
}

/// The ablation of `scene` (the full model) run by `method` (the base: every row but the integrator
/// rows uses it), at the reference's sample times and over the scene's coverage window. Every row is
/// compared with the full model run by `method`; its cost is timed as `timing` says.
pub fn ablation(
    scene: &Scene,
    method: Method,
    reference: &Reference,
    grids: &[(usize, usize)],
    timing: CostTiming,
    monitor: &Monitor,
) -> Result<Vec<AblationRow>, StudyError> {
    if timing.rounds == 0 || !(timing.window.is_finite() && timing.window > 0.0) {
        return Err(StudyError::InvalidInput {
            name: "ablation cost timing window",
            value: if timing.rounds == 0 {
                0.0
            } else {
                timing.window
            },
            reason: "needs at least one round and a finite window > 0 s",
        });
    }
    let times = reference.trajectory.snapshot_times();
    let attachments = scene.params.long_range_attachments;
    let mut variants = vec![
        Variant {
            part: "full",
            setting: "all parts".into(),
            scene: scene.clone(),
            method,
        },
        Variant {
            part: "shear",
            setting: "off".into(),
            scene: with_params(scene, |p| p.shear = SpringParams::disabled()),
            method,
        },
        Variant {
            part: "bending",
            setting: "off".into(),
            scene: with_params(scene, |p| p.bend = SpringParams::disabled()),
            method,
        },
        Variant {
            part: "spring damping",
            setting: "off (all three families)".into(),
            scene: with_params(scene, SimParams::remove_spring_damping),
            method,
        },
        Variant {
            part: "air damping",
            setting: "off".into(),
            scene: with_params(scene, |p| p.air_damping = 0.0),
            method,
        },
        Variant {
            part: "wind lift",
            setting: "off (C_L = 0)".into(),
            scene: with_params(scene, |p| p.wind.lift_coefficient = 0.0),
            method,
        },
        Variant {
            part: "gusts",
            setting: "off (steady wind)".into(),
            scene: with_params(scene, |p| {
                p.wind.gust_strength = 0.0;
                p.wind.turbulence = 0.0;
            }),
            method,
        },
        Variant {
            part: "long-range attachments",
            setting: if attachments { "off" } else { "on" }.into(),
            scene: with_params(scene, |p| p.long_range_attachments = !attachments),
            method,
        },
        Variant {
            part: "pole collider",
            setting: "on (capsule, 15 mm)".into(),
            scene: with_params(scene, |p| {
                p.collisions.colliders =
                    vec![Collider::flag_pole(&scene.grid, p.collisions.thickness)];
            }),
            method,
        },
        Variant {
            part: "self-collision",
            setting: format!("on ({} mm)", scene.params.collisions.thickness * 1e3),
            scene: with_params(scene, |p| p.collisions.self_collision = true),
            method,
        },
        Variant {
            part: "integrator",
            setting: "implicit Euler ×1, CG 10⁻⁴".into(),
            scene: scene.clone(),
            method: Method::ImplicitEuler {
                substeps: 1,
                cg_max_iterations: 100,
                cg_tolerance: 1e-4,
            },
        },
        Variant {
            part: "integrator",
            setting: "symplectic Euler ×200 (explicit)".into(),
            scene: scene.clone(),
            method: Method::SymplecticEuler { substeps: 200 },
        },
    ];
    variants.extend(wind_interval_variants(scene, method));
    for &(columns, rows) in grids {
        if (columns, rows) == (scene.grid.columns, scene.grid.rows) {
            continue;
        }
        variants.push(Variant {
            part: "resolution",
            setting: format!("{columns}×{rows}"),
            scene: scene.with_resolution(columns, rows)?,
            method,
        });
    }
    monitor.add_work((variants.len() + timing.rounds) as u64);
    // The silhouette is taken through the coverage camera when the scene has one.
    let viewport = scene
        .coverage
        .map_or(Viewport::around_flag(256), |w| w.viewport);
    let triangles_of =
        |s: &Scene| -> Result<Vec<[u32; 3]>, StudyError> { Ok(s.model()?.triangles) };
    let full_triangles = triangles_of(scene)?;
    let mut full_run: Option<Trajectory> = None;
    let mut rows = Vec::new();
    for variant in &variants {
        let trajectory = on_one_thread(|| {
            simulate(
                &variant.scene,
                variant.method,
                variant.scene.frame,
                &times,
                monitor,
            )
        })??;
        // The first variant is the full model run by the base method.
        let full_run = &*full_run.get_or_insert_with(|| trajectory.clone());
        let coverage_against = |other: Option<&crate::coverage::MeanCoverage>| {
            trajectory
                .coverage
                .as_ref()
                .zip(other)
                .and_then(|(own, other)| coverage_difference(own, other))
        };
        let coverage_vs_full = coverage_against(full_run.coverage.as_ref());
        let coverage_vs_reference = coverage_against(reference.trajectory.coverage.as_ref());
        let triangles = triangles_of(&variant.scene)?;
        let self_intersecting = self_intersecting_frames(&variant.scene, variant.method, monitor)?;
        for &time in &times {
            let own = trajectory.at(time);
            let expected_full = full_run.at(time);
            let expected_reference = reference.trajectory.at(time);
            let resampled = own.map(|s| resample(&s.positions, &variant.scene.grid, &scene.grid));
            let rms_against = |other: Option<&crate::Snapshot>| -> Option<f64> {
                let positions = resampled.as_ref()?;
                position_errors(positions, &other?.positions).map(|(rms, _)| rms)
            };
            let silhouette = match (own, expected_full) {
                (Some(own), Some(full_snapshot)) => Some(silhouette_difference(
                    &coverage(&own.positions, &triangles, &viewport)?,
                    &coverage(&full_snapshot.positions, &full_triangles, &viewport)?,
                )),
                _ => None,
            };
            rows.push(AblationRow {
                part: variant.part.to_string(),
                setting: variant.setting.clone(),
                method: variant.method,
                grid: (variant.scene.grid.columns, variant.scene.grid.rows),
                time,
                cpu_ms_per_simulated_second: trajectory.cpu_ms_per_simulated_second(),
                cost_vs_full: None,
                rms_vs_full: rms_against(expected_full),
                rms_vs_reference: rms_against(expected_reference),
                silhouette_difference: silhouette,
                coverage_vs_full,
                coverage_vs_reference,
                diverged: own.is_none(),
                self_intersecting_frames: self_intersecting,
            });
        }
        monitor.finish_run(&format!("ablation {} {}", variant.part, variant.setting));
    }
    // The costs: every variant beside the full model (variant 0), round by round.
    let mut costs = vec![Vec::new(); variants.len()];
    let mut ratios = vec![Vec::new(); variants.len()];
    for round in 0..timing.rounds {
        for v in 1..variants.len() {
            let full_first = (round + v).is_multiple_of(2);
            let pair = paired_costs(
                &variants[0],
                &variants[v],
                timing.window,
                full_first,
                monitor,
            )?;
            if let Some([full, own]) = pair {
                costs[0].push(full);
                costs[v].push(own);
                ratios[v].push(own / full);
            }
        }
        monitor.finish_run(&format!(
            "ablation costs, round {} of {}",
            round + 1,
            timing.rounds
        ));
    }
    for (v, variant_rows) in rows.chunks_mut(times.len().max(1)).enumerate() {
        costs[v].sort_by(f64::total_cmp);
        let cost = median_of_sorted(&costs[v]);
        let ratio = CostRatio::of(&ratios[v]);
        for row in variant_rows {
            // A variant that diverged in every timed run keeps its accuracy run's cost.
            row.cpu_ms_per_simulated_second = cost.unwrap_or(row.cpu_ms_per_simulated_second);
            row.cost_vs_full = ratio;
        }
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resampling_a_planar_grid_is_exact() {
        // A flat grid maps (u, v) affinely to space, which bilinear interpolation reproduces exactly
        // (to rounding, 1e-15 m on a 1 m cloth).
        let from = GridSpec {
            columns: 5,
            rows: 4,
            ..GridSpec::default()
        };
        let to = GridSpec {
            columns: 9,
            rows: 7,
            ..GridSpec::default()
        };
        let positions = sheer_cloth::ClothModel::grid(&from).unwrap().positions;
        let expected = sheer_cloth::ClothModel::grid(&to).unwrap().positions;
        let (rms, max) = position_errors(&resample(&positions, &from, &to), &expected).unwrap();
        assert!(max < 1e-14 && rms < 1e-14, "{rms} {max}");
    }

    #[test]
    fn the_wind_rows_leave_out_the_scenes_own_interval() {
        let scene = Scene::default_flag().unwrap();
        let settings = |scene: &Scene| -> Vec<(String, bool, f64)> {
            wind_interval_variants(scene, Method::default())
                .into_iter()
                .map(|v| {
                    let wind = v.scene.params.wind;
                    (v.setting, wind.per_substep, wind.renewal_interval)
                })
                .collect()
        };
        assert_eq!(scene.params.wind.renewal_interval, 0.002);
        assert_eq!(
            settings(&scene),
            [
                ("every sub-step".to_string(), true, 0.0),
                ("held ≤ 1 ms (every 2 sub-steps)".to_string(), true, 0.001),
                ("held ≤ 4 ms (every 9 sub-steps)".to_string(), true, 0.004),
                ("once per frame".to_string(), false, 0.0),
            ]
        );
        let every = with_params(&scene, |p| p.wind.renewal_interval = 0.0);
        assert_eq!(
            settings(&every),
            [
                ("held ≤ 1 ms (every 2 sub-steps)".to_string(), true, 0.001),
                ("held ≤ 2 ms (every 4 sub-steps)".to_string(), true, 0.002),
                ("held ≤ 4 ms (every 9 sub-steps)".to_string(), true, 0.004),
                ("once per frame".to_string(), false, 0.0),
            ]
        );
        let held = with_params(&scene, |p| p.wind.hold_for_each_step());
        assert_eq!(settings(&held).len(), 4);
        assert!(settings(&held).iter().all(|(_, every, _)| *every));
    }
}
