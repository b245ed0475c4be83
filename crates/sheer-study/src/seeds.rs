//! The ablation's small differences across gusts: the same settings on several seeds of the wind.
//!
//! The waving flag is chaotic, so its time-averaged coverage ([`crate::coverage`]) differs between any
//! two runs that are not bit for bit the same, by about 0.02 (halving the reference's own step gives
//! 0.0201, docs/study.md), half the default budget. One run against one reference then cannot tell a
//! setting that changes the picture by 0.01 from one that changes nothing: the study's rows for the
//! wind's renewal interval and the springs' dashpots sit inside the budget but within that noise of the
//! full model, and a full run against another reference could move the choice the other way.
//!
//! Here each setting runs on `n` scenes that differ only in the seed of the wind's gusts and turbulence
//! ([`sheer_cloth::Wind::seed`]): `n` independent flutters, each against its own converged reference
//! (with its halving check, [`reference()`]). What a setting changes is then the mean, over the seeds, of
//! its coverage difference from the reference *less the full model's on the same seed* (a paired
//! difference, so what the seed does to both cancels), with its standard error `s/√n`.
//!
//! The reference is always the full model, renewing the wind at every one of its sub-steps: a held
//! wind is an approximation a run makes, not part of the model it approximates.

use rayon::prelude::*;
use sheer_cloth::{DEFAULT_FLAG_WIND_RENEWAL_INTERVAL, Method, SpringParams};

use crate::ablation::{WIND_RENEWAL_INTERVALS, wind_renewal_setting};
use crate::coverage::coverage_difference;
use crate::reference::reference;
use crate::run::{on_one_thread, simulate};
use crate::{Monitor, Scene, StudyError};

/// One setting on one seed.
#[derive(Clone, Debug, PartialEq)]
pub struct SeedRow {
    /// The wind's seed ([`sheer_cloth::Wind::seed`]).
    pub seed: u64,
    /// What differs from the full model (`full model` for the full model itself).
    pub setting: String,
    /// The integrator the setting was run with.
    pub method: Method,
    /// Time-averaged coverage difference from this seed's reference (`None` if the run diverged).
    pub coverage_vs_reference: Option<f64>,
    /// Time-averaged coverage difference from the full model on this seed, run by the base method.
    pub coverage_vs_full: Option<f64>,
    /// This seed's reference halving difference in coverage: differences below it are not resolved.
    pub reference_halving: Option<f64>,
}

/// One setting over every seed.
#[derive(Clone, Debug, PartialEq)]
pub struct SeedSummary {
    /// What differs from the full model (`full model` for the full model itself).
    pub setting: String,
    /// The integrator the setting was run with.
    pub method: Method,
    /// Seeds on which the run finished (did not diverge).
    pub seeds: usize,
    /// Mean over the seeds of the coverage difference from the reference.
    pub mean_vs_reference: f64,
    /// Sample standard deviation over the seeds of the coverage difference from the reference.
    pub spread_vs_reference: f64,
    /// Least coverage difference from the reference over the seeds.
    pub least_vs_reference: f64,
    /// Greatest coverage difference from the reference over the seeds.
    pub greatest_vs_reference: f64,
    /// Mean of `D(setting, reference) − D(full model, reference)`, seed by seed.
    pub mean_change: f64,
    /// Standard error of `mean_change` (`s/√n`; 0 with one seed).
    pub change_standard_error: f64,
}

/// A setting of the seed study: what differs from the full model.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Setting {
    FullModel,
    /// `wind.renewal_interval` = this, s.
    WindHeld(f64),
    /// `wind.per_substep` = false: the forces of the frame's start held for its sub-steps.
    WindOncePerFrame,
    NoDashpots,
    NoAirDamping,
    /// The parts the ablation keeps by a margin below the measure's resolution.
    NoBending,
    NoLift,
    NoAttachments,
    /// The base method with half its sub-steps (the choice's cheaper neighbour in the sweep).
    HalfTheSubsteps,
}

impl Setting {
    /// Every setting, the full model first.
    const ALL: [Setting; 11] = [
        Setting::FullModel,
        Setting::WindHeld(WIND_RENEWAL_INTERVALS[1]),
        Setting::WindHeld(WIND_RENEWAL_INTERVALS[2]),
        Setting::WindHeld(WIND_RENEWAL_INTERVALS[3]),
        Setting::WindOncePerFrame,
        Setting::NoDashpots,
        Setting::NoAirDamping,
        Setting::NoBending,
        Setting::NoLift,
        Setting::NoAttachments,
        Setting::HalfTheSubsteps,
    ];

    /// The setting in words, for runs of `method` at steps of `frame` s.
    fn name(self, frame: f64, method: Method) -> String {
        match self {
            Setting::FullModel => "full model".into(),
            Setting::WindHeld(interval) => format!(
                "wind {}{}",
                wind_renewal_setting(interval, frame, method),
                if interval == DEFAULT_FLAG_WIND_RENEWAL_INTERVAL {
                    ", the default flag"
                } else {
                    ""
                }
            ),
            Setting::WindOncePerFrame => "wind once per frame".into(),
            Setting::NoDashpots => "springs' dashpots off".into(),
            Setting::NoAirDamping => "air damping off".into(),
            Setting::NoBending => "bending springs off".into(),
            Setting::NoLift => "wind lift off".into(),
            Setting::NoAttachments => "long-range attachments off".into(),
            Setting::HalfTheSubsteps => "half the sub-steps".into(),
        }
    }

    /// The scene and method of this setting's run.
    fn apply(self, scene: &Scene, method: Method) -> (Scene, Method) {
        let mut changed = scene.clone();
        let p = &mut changed.params;
        match self {
            Setting::FullModel | Setting::HalfTheSubsteps => {}
            Setting::WindHeld(interval) => p.wind.renewal_interval = interval,
            Setting::WindOncePerFrame => p.wind.hold_for_each_step(),
            Setting::NoDashpots => p.remove_spring_damping(),
            Setting::NoAirDamping => p.air_damping = 0.0,
            Setting::NoBending => p.bend = SpringParams::disabled(),
            Setting::NoLift => p.wind.lift_coefficient = 0.0,
            Setting::NoAttachments => p.long_range_attachments = false,
        }
        let method = if self == Setting::HalfTheSubsteps {
            halved(method)
        } else {
            method
        };
        (changed, method)
    }
}

/// `method` with half its sub-steps (at least one).
fn halved(method: Method) -> Method {
    method.with_knobs(Some((method.substeps() / 2).max(1)), None)
}

/// Runs every setting on `scene` with the wind's seed set to each of `seeds` (the full model's
/// reference on each, at `sample_times`), base method `method`. The scene must have a coverage window
/// and renew its wind at every sub-step (the full model). Seeds run in parallel on rayon's pool, each
/// run on one thread of its own, so the rows do not depend on the thread count; they come seed by seed,
/// setting by setting.
pub fn across_seeds(
    scene: &Scene,
    method: Method,
    seeds: &[u64],
    sample_times: &[f64],
    monitor: &Monitor,
) -> Result<Vec<SeedRow>, StudyError> {
    if seeds.is_empty() {
        return Err(StudyError::InvalidInput {
            name: "seeds",
            value: 0.0,
            reason: "needs at least one seed",
        });
    }
    let mut sorted = seeds.to_vec();
    sorted.sort_unstable();
    if let Some(pair) = sorted.windows(2).find(|pair| pair[0] == pair[1]) {
        return Err(StudyError::InvalidInput {
            name: "seeds",
            value: pair[0] as f64,
            reason: "a seed given twice would count one flutter twice",
        });
    }
    if scene.coverage.is_none() {
        return Err(StudyError::InvalidInput {
            name: "coverage window",
            value: 0.0,
            reason: "the seed study compares time-averaged coverage; the scene has no window",
        });
    }
    if !scene.params.wind.updated_every_substep() {
        return Err(StudyError::InvalidInput {
            name: "wind.renewal_interval",
            value: scene.params.wind.renewal_interval,
            reason: "the full model renews the wind at every sub-step",
        });
    }
    // Every setting per seed (each seed's reference adds its own two runs).
    monitor.add_work((seeds.len() * Setting::ALL.len()) as u64);
    let per_seed: Vec<Result<Vec<SeedRow>, StudyError>> = seeds
        .par_iter()
        .map(|&seed| one_seed(scene, method, seed, sample_times, monitor))
        .collect();
    let mut rows = Vec::new();
    for seed_rows in per_seed {
        rows.extend(seed_rows?);
    }
    Ok(rows)
}

fn one_seed(
    scene: &Scene,
    method: Method,
    seed: u64,
    sample_times: &[f64],
    monitor: &Monitor,
) -> Result<Vec<SeedRow>, StudyError> {
    let mut seeded = scene.clone();
    seeded.params.wind.seed = seed;
    seeded.name = format!("{} (seed {seed})", scene.name);
    let reference = reference(&seeded, sample_times, monitor)?;
    let mut rows: Vec<SeedRow> = Vec::with_capacity(Setting::ALL.len());
    let mut full_coverage = None;
    for setting in Setting::ALL {
        let (changed, run_method) = setting.apply(&seeded, method);
        let trajectory = on_one_thread(|| {
            simulate(&changed, run_method, changed.frame, sample_times, monitor)
        })??;
        let coverage = trajectory.coverage;
        let against = |other: Option<&crate::MeanCoverage>| {
            coverage
                .as_ref()
                .zip(other)
                .and_then(|(own, other)| coverage_difference(own, other))
        };
        let coverage_vs_reference = against(reference.trajectory.coverage.as_ref());
        // The first setting is the full model.
        let full = full_coverage.get_or_insert_with(|| coverage.clone());
        let coverage_vs_full = against(full.as_ref());
        rows.push(SeedRow {
            seed,
            setting: setting.name(seeded.frame, method),
            method: run_method,
            coverage_vs_reference,
            coverage_vs_full,
            reference_halving: reference.coverage_halving,
        });
        monitor.finish_run(&format!(
            "seeds: seed {seed}, {}",
            setting.name(seeded.frame, method)
        ));
    }
    Ok(rows)
}

/// Mean and sample standard deviation (0 for one value; `None` for none).
fn mean_and_spread(values: &[f64]) -> Option<(f64, f64)> {
    let n = values.len();
    if n == 0 {
        return None;
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    let spread = if n > 1 {
        (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
    } else {
        0.0
    };
    Some((mean, spread))
}

/// Each setting's figures over the seeds, in the order of the rows (`None` for a setting that
/// diverged on every seed). The first setting of the rows is the baseline, as [`across_seeds`] writes
/// them (the full model). The paired change, and its standard error, count only seeds on which both
/// the setting and the baseline finished; `seeds` counts those on which the setting finished.
pub fn summarise(rows: &[SeedRow]) -> Vec<(String, Option<SeedSummary>)> {
    let mut names: Vec<&str> = Vec::new();
    for row in rows {
        if !names.contains(&row.setting.as_str()) {
            names.push(&row.setting);
        }
    }
    let full_of = |seed: u64| {
        rows.iter()
            .find(|r| r.seed == seed && r.setting == names[0])
            .and_then(|r| r.coverage_vs_reference)
    };
    names
        .iter()
        .map(|&name| {
            let of_setting: Vec<&SeedRow> = rows.iter().filter(|r| r.setting == name).collect();
            let values: Vec<f64> = of_setting
                .iter()
                .filter_map(|r| r.coverage_vs_reference)
                .collect();
            let changes: Vec<f64> = of_setting
                .iter()
                .filter_map(|r| Some(r.coverage_vs_reference? - full_of(r.seed)?))
                .collect();
            let summary = mean_and_spread(&values).zip(mean_and_spread(&changes)).map(
                |((mean, spread), (mean_change, change_spread))| SeedSummary {
                    setting: name.to_string(),
                    method: of_setting[0].method,
                    seeds: values.len(),
                    mean_vs_reference: mean,
                    spread_vs_reference: spread,
                    least_vs_reference: values.iter().copied().fold(f64::INFINITY, f64::min),
                    greatest_vs_reference: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                    mean_change,
                    change_standard_error: change_spread / (changes.len() as f64).sqrt(),
                },
            );
            (name.to_string(), summary)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(seed: u64, setting: &str, d: Option<f64>) -> SeedRow {
        SeedRow {
            seed,
            setting: setting.into(),
            method: Method::default(),
            coverage_vs_reference: d,
            coverage_vs_full: None,
            reference_halving: None,
        }
    }

    #[test]
    fn the_change_is_paired_seed_by_seed() {
        // Seed 2's flutter is far from its reference for both settings; the paired change cancels it.
        let rows = [
            row(1, "full model", Some(0.02)),
            row(1, "held", Some(0.03)),
            row(2, "full model", Some(0.06)),
            row(2, "held", Some(0.07)),
            row(3, "full model", Some(0.03)),
            row(3, "held", None),
        ];
        let summary = summarise(&rows);
        assert_eq!(summary.len(), 2);
        let full = summary[0].1.as_ref().unwrap();
        assert_eq!(full.seeds, 3);
        assert!((full.mean_vs_reference - 0.11 / 3.0).abs() < 1e-15);
        assert!(full.mean_change.abs() < 1e-15 && full.change_standard_error == 0.0);
        let held = summary[1].1.as_ref().unwrap();
        // Seed 3 diverged: two seeds, both 0.01 above the full model.
        assert_eq!(held.seeds, 2);
        assert!((held.mean_vs_reference - 0.05).abs() < 1e-15);
        assert!((held.spread_vs_reference - 0.02f64.sqrt() * 0.2).abs() < 1e-12);
        assert_eq!(
            (held.least_vs_reference, held.greatest_vs_reference),
            (0.03, 0.07)
        );
        assert!((held.mean_change - 0.01).abs() < 1e-12);
        assert!(held.change_standard_error < 1e-12);
        // A setting that diverged everywhere has no summary.
        let summary = summarise(&[row(1, "full model", Some(0.02)), row(1, "gone", None)]);
        assert!(summary[1].1.is_none());
    }

    #[test]
    fn halving_keeps_the_method_and_its_knobs() {
        assert_eq!(
            halved(Method::SmallStepsXpbd { substeps: 40 }),
            Method::SmallStepsXpbd { substeps: 20 }
        );
        assert_eq!(
            halved(Method::Xpbd {
                substeps: 1,
                iterations: 10
            }),
            Method::Xpbd {
                substeps: 1,
                iterations: 10
            }
        );
    }

    #[test]
    fn bad_seed_lists_and_scenes_are_refused() {
        let mut scene = Scene::default_flag().unwrap();
        scene.params.wind.renewal_interval = 0.0;
        let monitor = Monitor::hidden();
        let method = Method::default();
        let refused = |scene: &Scene, seeds: &[u64]| {
            matches!(
                across_seeds(scene, method, seeds, &[0.25], &monitor),
                Err(StudyError::InvalidInput { .. })
            )
        };
        assert!(refused(&scene, &[]));
        assert!(refused(&scene, &[3, 1, 3]));
        assert!(refused(&scene.clone().with_coverage(None), &[1]));
        // The default flag holds its wind: not the full model.
        assert!(refused(&Scene::default_flag().unwrap(), &[1]));
    }

    #[test]
    fn every_setting_runs_on_every_seed_and_the_full_model_is_its_own_baseline() {
        let config = crate::StudyConfig::quick();
        let mut scene = Scene::default_flag()
            .unwrap()
            .with_resolution(config.choice_grid.0, config.choice_grid.1)
            .unwrap()
            .with_coverage(Some(config.coverage_window));
        scene.params.wind.renewal_interval = 0.0;
        let rows = across_seeds(
            &scene,
            // ×40, so that every hold renews less often than every sub-step.
            Method::SmallStepsXpbd { substeps: 40 },
            &[1, 2],
            &config.choice_times,
            &Monitor::hidden(),
        )
        .unwrap();
        let settings = Setting::ALL.len();
        assert_eq!(rows.len(), 2 * settings);
        for (i, r) in rows.iter().enumerate() {
            assert_eq!(r.seed, [1, 2][i / settings]);
            assert!(
                r.reference_halving
                    .is_some_and(|h| h.is_finite() && h >= 0.0)
            );
            let d = r.coverage_vs_reference.unwrap();
            assert!(d.is_finite() && d > 0.0, "{r:?}");
        }
        let full: Vec<&SeedRow> = rows.iter().filter(|r| r.setting == "full model").collect();
        assert_eq!(full.len(), 2);
        assert!(full.iter().all(|r| r.coverage_vs_full == Some(0.0)));
        // The two seeds are two flutters: their full models differ from their references differently.
        assert_ne!(full[0].coverage_vs_reference, full[1].coverage_vs_reference);
        // The halved run is the base method with half the sub-steps.
        let halved_rows: Vec<&SeedRow> = rows
            .iter()
            .filter(|r| r.setting == "half the sub-steps")
            .collect();
        assert!(
            halved_rows
                .iter()
                .all(|r| r.method == Method::SmallStepsXpbd { substeps: 20 })
        );
        // Every other setting changes the run.
        for r in rows.iter().filter(|r| r.setting != "full model") {
            assert!(r.coverage_vs_full.unwrap() > 0.0, "{r:?}");
        }
    }
}
