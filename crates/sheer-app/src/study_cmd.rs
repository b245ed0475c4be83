//! `sheer study work-precision|stability|ablation|choose|seeds|all [--out DIR] [--quick]`: the command
//! line over the `sheer-study` library. Every command writes its CSV, PNG, Markdown and TOML files into
//! `--out` through `sheer_study::outputs`.

use std::path::PathBuf;

use clap::{Args, Subcommand, ValueEnum};
use sheer_study::outputs::{
    check_output_folder, write_ablation, write_all, write_choice, write_seeds, write_stability,
    write_work_precision,
};
use sheer_study::{Budget, DEFAULT_COVERAGE_BUDGET, Monitor, StudyConfig, StudyError};

use crate::output::interrupt;

/// `sheer study …`
#[derive(Args, Clone, Debug)]
pub struct StudyArgs {
    /// Which study to run.
    #[command(subcommand)]
    pub command: StudyCommand,
}

/// Options shared by every study command.
#[derive(Args, Clone, Debug)]
pub struct OutputArgs {
    /// Folder the CSV, PNG and Markdown files are written into.
    #[arg(long, default_value = "docs")]
    pub out: PathBuf,
    /// Small grids and short runs (seconds instead of minutes): a smoke test, not the published study.
    /// Refused when `--out` holds a full study (a `choice.toml` without `quick = true`, as the committed
    /// `docs/` does), unless `--force` is given: a smoke test must not replace published results.
    #[arg(long)]
    pub quick: bool,
    /// With `--quick`: write even into a folder that holds a full study's results.
    #[arg(long, requires = "quick")]
    pub force: bool,
}

/// Which error a budget bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BudgetKind {
    /// Time-averaged coverage over the flag's coverage window (0.5–2.5 s): insensitive to the phase
    /// of the flutter, so meaningful however long the flag waves.
    Coverage,
    /// Pointwise RMS position error at `--at` seconds: meaningful for the chaotic flag only within
    /// ~0.25 s.
    Rms,
}

/// Options of `choose` (and of the choice inside `ablation` and `all`).
#[derive(Args, Clone, Debug)]
pub struct BudgetArgs {
    /// Which error the budget bounds.
    #[arg(long, value_enum, default_value_t = BudgetKind::Coverage)]
    pub budget: BudgetKind,
    /// Coverage budget (`--budget coverage` only): the largest time-averaged coverage difference from
    /// the reference, as a fraction of the reference's mean covered area [default: 0.04].
    #[arg(long, allow_negative_numbers = true)]
    pub max_coverage_difference: Option<f64>,
    /// RMS budget (`--budget rms` only): the largest RMS position error, mm [default: 5].
    #[arg(long, allow_negative_numbers = true)]
    pub budget_mm: Option<f64>,
    /// RMS budget (`--budget rms` only): the simulated time at which it applies, s (one of the choice
    /// sweep's sample times: 0.25 or 1; with `--quick`, 0.25 only). Default 0.25 s, or with `--quick`
    /// the quick sweep's first sample time: the waving flag is chaotic, and at 1 s even its reference
    /// changes by centimetres when its step is halved.
    #[arg(long, allow_negative_numbers = true)]
    pub at: Option<f64>,
}

/// RMS budget when `--budget-mm` is not given, mm.
const DEFAULT_BUDGET_MM: f64 = 5.0;
/// RMS budget time when `--at` is not given (full study), s.
const DEFAULT_BUDGET_TIME: f64 = 0.25;

/// Options of `seeds`.
#[derive(Args, Clone, Debug)]
pub struct SeedArgs {
    /// Where and how much to run.
    #[command(flatten)]
    pub output: OutputArgs,
    /// How many seeds of the wind's gusts (1, 2, … n), each a flutter of its own with its own reference
    /// [default: 8; with `--quick`, 2].
    #[arg(long)]
    pub seeds: Option<u64>,
}

/// Output plus budget options.
#[derive(Args, Clone, Debug)]
pub struct ChoiceArgs {
    /// Where and how much to run.
    #[command(flatten)]
    pub output: OutputArgs,
    /// The error budget the choice must meet.
    #[command(flatten)]
    pub budget: BudgetArgs,
}

/// The study commands, one per figure or table of `docs/` (and `all` of them).
#[derive(Subcommand, Clone, Debug)]
pub enum StudyCommand {
    /// Work–precision sweep of every method on the flag, the hanging sheet and the stiff sheet.
    WorkPrecision(OutputArgs),
    /// Stability map (time step × stiffness) and the explicit methods' boundary against 2/ω_max.
    Stability(OutputArgs),
    /// Cost and effect of each model part on the default flag.
    Ablation(ChoiceArgs),
    /// Cheapest method and settings for the default flag within an error budget.
    Choose(ChoiceArgs),
    /// The ablation's closest rows (the wind's renewal interval, the dampings, bending, lift, the
    /// long-range attachments, half the sub-steps) on several seeds of the wind's gusts, each against its
    /// own reference (not part of `all`).
    Seeds(SeedArgs),
    /// Everything `docs/` publishes.
    All(ChoiceArgs),
}

/// Runs a study command with a progress bar; Ctrl-C stops it with [`StudyError::Interrupted`] (a
/// second Ctrl-C ends the process).
pub fn run(args: &StudyArgs) -> Result<(), StudyError> {
    interrupt::install();
    let monitor = Monitor::with_progress_bar(interrupt::flag());
    let result = match &args.command {
        StudyCommand::WorkPrecision(out) => {
            let config = config(out);
            check_output(out)
                .and_then(|()| write_work_precision(&config, &out.out, &monitor).map(|_| ()))
        }
        StudyCommand::Stability(out) => {
            check_output(out).and_then(|()| write_stability(&config(out), &out.out, &monitor))
        }
        StudyCommand::Choose(ChoiceArgs {
            output: out,
            budget,
        }) => {
            let config = config(out);
            budget_of(budget, &config).and_then(|budget| {
                check_output(out)?;
                write_choice(&config, &budget, &out.out, &monitor).map(|_| ())
            })
        }
        StudyCommand::Ablation(ChoiceArgs {
            output: out,
            budget,
        }) => {
            let config = config(out);
            budget_of(budget, &config).and_then(|budget| {
                check_output(out)?;
                let measured = write_choice(&config, &budget, &out.out, &monitor)?;
                write_ablation(&config, &measured, &out.out, &monitor)
            })
        }
        StudyCommand::Seeds(SeedArgs { output: out, seeds }) => {
            let config = config(out);
            let count = seeds.unwrap_or(if out.quick { 2 } else { 8 });
            check_output(out).and_then(|()| write_seeds(&config, count, &out.out, &monitor))
        }
        StudyCommand::All(ChoiceArgs {
            output: out,
            budget,
        }) => {
            let config = config(out);
            budget_of(budget, &config).and_then(|budget| {
                check_output(out)?;
                write_all(&config, &budget, &out.out, &monitor)
            })
        }
    };
    monitor.finish();
    result
}

fn config(out: &OutputArgs) -> StudyConfig {
    if out.quick {
        StudyConfig::quick()
    } else {
        StudyConfig::full()
    }
}

/// An option that the chosen `--budget` kind does not use: given, it would be silently ignored.
fn unused_option(name: &'static str, value: f64, reason: &'static str) -> StudyError {
    StudyError::InvalidInput {
        name,
        value,
        reason,
    }
}

fn budget_of(args: &BudgetArgs, config: &StudyConfig) -> Result<Budget, StudyError> {
    if args.budget == BudgetKind::Coverage {
        if let Some(value) = args.budget_mm {
            return Err(unused_option(
                "--budget-mm",
                value,
                "only applies with `--budget rms`",
            ));
        }
        if let Some(value) = args.at {
            return Err(unused_option(
                "--at",
                value,
                "only applies with `--budget rms`",
            ));
        }
        let max_difference = args
            .max_coverage_difference
            .unwrap_or(DEFAULT_COVERAGE_BUDGET);
        if !(max_difference.is_finite() && max_difference > 0.0) {
            return Err(StudyError::InvalidInput {
                name: "--max-coverage-difference",
                value: max_difference,
                reason: "must be finite and > 0",
            });
        }
        return Ok(Budget::Coverage { max_difference });
    }
    if let Some(value) = args.max_coverage_difference {
        return Err(unused_option(
            "--max-coverage-difference",
            value,
            "only applies with `--budget coverage`",
        ));
    }
    let budget_mm = args.budget_mm.unwrap_or(DEFAULT_BUDGET_MM);
    if !(budget_mm.is_finite() && budget_mm > 0.0) {
        return Err(StudyError::InvalidInput {
            name: "--budget-mm",
            value: budget_mm,
            reason: "must be finite and > 0",
        });
    }
    // Quick runs are shorter than 1 s: without `--at` the budget applies at their first sample time;
    // a given `--at` must be one of the run's sample times (never silently replaced; NaN matches none).
    let at = match args.at {
        Some(at) => at,
        None if config.quick => config.choice_times[0],
        None => DEFAULT_BUDGET_TIME,
    };
    if !config.choice_times.iter().any(|t| (t - at).abs() < 1e-9) {
        return Err(StudyError::InvalidInput {
            name: "--at",
            value: at,
            reason: if config.quick {
                "must be one of the quick sweep's sample times (0.25 s only)"
            } else {
                "must be one of the choice sweep's sample times (0.25 or 1 s)"
            },
        });
    }
    Ok(Budget::RmsPosition {
        time: at,
        max_error: budget_mm * 1e-3,
    })
}

/// [`check_output_folder`] for the command's `--out`, `--quick` and `--force`.
fn check_output(out: &OutputArgs) -> Result<(), StudyError> {
    check_output_folder(&out.out, out.quick, out.force)
}
