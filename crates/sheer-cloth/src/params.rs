//! Simulation parameters: plain, serialisable data in SI units.
//!
//! Everything a run needs besides the mesh lives in [`SimParams`], so a scene file can describe any run.
//! Every field has a default (the waving-flag defaults), and [`SimParams::validate`] turns a bad value
//! into a [`ParamError`] naming the field instead of letting it reach the integrator.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::error::ParamError;

/// The time integrator, with its own knobs. All methods run behind the same
/// [`Simulation::step`](crate::Simulation::step); `substeps` splits each `step(dt)` into equal sub-steps.
///
/// Serialised as one table, `kind` and the knobs of that kind (`{ kind = "xpbd", substeps = 2,
/// iterations = 20 }`). It is read through a flat table (the private `MethodTable`), so that a
/// deserialiser that tracks positions (TOML's) can point at the offending key: serde's internally
/// tagged enums buffer the table first and lose them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", try_from = "MethodTable")]
pub enum Method {
    /// Forward Euler: `x' = x + h v`, `v' = v + h a(x, v)`. Unconditionally unstable without damping
    /// (its amplification factor is `sqrt(1 + (ωh)²) > 1`); shipped as the baseline that fails.
    ExplicitEuler {
        /// Sub-steps per [`step`](crate::Simulation::step)`(dt)`, each `dt / substeps` s long.
        substeps: u32,
    },
    /// Semi-implicit (symplectic) Euler: `v' = v + h a(x, v)`, `x' = x + h v'`. Stable for `h < 2/ω`.
    SymplecticEuler {
        /// Sub-steps per [`step`](crate::Simulation::step)`(dt)`, each `dt / substeps` s long.
        substeps: u32,
    },
    /// Velocity Verlet (Swope et al. 1982), second order, symplectic. Stable for `h < 2/ω`.
    Verlet {
        /// Sub-steps per [`step`](crate::Simulation::step)`(dt)`, each `dt / substeps` s long.
        substeps: u32,
    },
    /// Backward Euler linearised once per step and solved by preconditioned conjugate gradients
    /// (Baraff & Witkin 1998, "Large steps in cloth simulation", eqs. (15)–(18)).
    ImplicitEuler {
        /// Sub-steps per [`step`](crate::Simulation::step)`(dt)`, each `dt / substeps` s long.
        substeps: u32,
        /// Upper bound on CG iterations per solve.
        cg_max_iterations: u32,
        /// Relative residual `|b − A Δv| / |b|` at which CG stops, in (0, 1) (CG starts at 1).
        cg_tolerance: f64,
    },
    /// Position-based dynamics (Müller et al. 2007): dimensionless stiffness in (0, 1], corrected for
    /// the iteration count by `1 − (1 − k)^(1/n)` (their section 3.3).
    Pbd {
        /// Sub-steps per [`step`](crate::Simulation::step)`(dt)`, each `dt / substeps` s long.
        substeps: u32,
        /// Gauss–Seidel sweeps over all constraints per sub-step.
        iterations: u32,
        /// Dimensionless PBD stiffness in (0, 1]; the spring stiffnesses in N/m are not used.
        stiffness: f64,
    },
    /// Extended PBD (Macklin, Müller, Chentanez 2016): compliance `α = 1/k` in m/N taken from the
    /// springs, Lagrange multipliers reset every sub-step, `iterations` Gauss–Seidel sweeps per sub-step.
    Xpbd {
        /// Sub-steps per [`step`](crate::Simulation::step)`(dt)`, each `dt / substeps` s long.
        substeps: u32,
        /// Gauss–Seidel sweeps over all constraints per sub-step.
        iterations: u32,
    },
    /// "Small steps" XPBD (Macklin et al. 2019): `substeps` sub-steps of one XPBD iteration each.
    SmallStepsXpbd {
        /// Sub-steps per [`step`](crate::Simulation::step)`(dt)`, each `dt / substeps` s long.
        substeps: u32,
    },
}

/// The kinds of [`Method`], as a table's `kind` names them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
enum MethodKind {
    ExplicitEuler,
    SymplecticEuler,
    Verlet,
    ImplicitEuler,
    Pbd,
    Xpbd,
    SmallStepsXpbd,
}

/// A [`Method`] as written: its kind and every knob any kind has. Turned into a method by
/// `TryFrom`, which asks for exactly the knobs of that kind.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MethodTable {
    kind: MethodKind,
    substeps: Option<u32>,
    iterations: Option<u32>,
    stiffness: Option<f64>,
    cg_max_iterations: Option<u32>,
    cg_tolerance: Option<f64>,
}

impl TryFrom<MethodTable> for Method {
    type Error = String;

    fn try_from(table: MethodTable) -> Result<Method, String> {
        let MethodTable {
            kind,
            substeps,
            iterations,
            stiffness,
            cg_max_iterations,
            cg_tolerance,
        } = table;
        let given = [
            ("substeps", substeps.is_some()),
            ("iterations", iterations.is_some()),
            ("stiffness", stiffness.is_some()),
            ("cg_max_iterations", cg_max_iterations.is_some()),
            ("cg_tolerance", cg_tolerance.is_some()),
        ];
        let (name, knobs): (&str, &[&str]) = match kind {
            MethodKind::ExplicitEuler => ("explicit_euler", &["substeps"]),
            MethodKind::SymplecticEuler => ("symplectic_euler", &["substeps"]),
            MethodKind::Verlet => ("verlet", &["substeps"]),
            MethodKind::ImplicitEuler => (
                "implicit_euler",
                &["substeps", "cg_max_iterations", "cg_tolerance"],
            ),
            MethodKind::Pbd => ("pbd", &["substeps", "iterations", "stiffness"]),
            MethodKind::Xpbd => ("xpbd", &["substeps", "iterations"]),
            MethodKind::SmallStepsXpbd => ("small_steps_xpbd", &["substeps"]),
        };
        for (knob, present) in given {
            if present && !knobs.contains(&knob) {
                return Err(format!(
                    "`{knob}` is not a knob of {name} (its knobs: {})",
                    knobs.join(", ")
                ));
            }
            if !present && knobs.contains(&knob) {
                return Err(format!(
                    "missing `{knob}`: {name} needs {}",
                    knobs.join(", ")
                ));
            }
        }
        // Every knob of the kind is present (checked above).
        let missing = || format!("{name}: a knob is missing");
        let substeps = substeps.ok_or_else(missing)?;
        Ok(match kind {
            MethodKind::ExplicitEuler => Method::ExplicitEuler { substeps },
            MethodKind::SymplecticEuler => Method::SymplecticEuler { substeps },
            MethodKind::Verlet => Method::Verlet { substeps },
            MethodKind::ImplicitEuler => Method::ImplicitEuler {
                substeps,
                cg_max_iterations: cg_max_iterations.ok_or_else(missing)?,
                cg_tolerance: cg_tolerance.ok_or_else(missing)?,
            },
            MethodKind::Pbd => Method::Pbd {
                substeps,
                iterations: iterations.ok_or_else(missing)?,
                stiffness: stiffness.ok_or_else(missing)?,
            },
            MethodKind::Xpbd => Method::Xpbd {
                substeps,
                iterations: iterations.ok_or_else(missing)?,
            },
            MethodKind::SmallStepsXpbd => Method::SmallStepsXpbd { substeps },
        })
    }
}

impl Method {
    /// Sub-steps per call of `step(dt)`.
    pub fn substeps(&self) -> u32 {
        match *self {
            Method::ExplicitEuler { substeps }
            | Method::SymplecticEuler { substeps }
            | Method::Verlet { substeps }
            | Method::ImplicitEuler { substeps, .. }
            | Method::Pbd { substeps, .. }
            | Method::Xpbd { substeps, .. }
            | Method::SmallStepsXpbd { substeps } => substeps,
        }
    }

    /// Whether the method is position-based (PBD, XPBD, small-steps XPBD).
    pub fn is_position_based(&self) -> bool {
        matches!(
            self,
            Method::Pbd { .. } | Method::Xpbd { .. } | Method::SmallStepsXpbd { .. }
        )
    }

    /// Constraint-solver iterations per sub-step (1 for the force-based integrators).
    pub fn iterations(&self) -> u32 {
        match *self {
            Method::Pbd { iterations, .. } | Method::Xpbd { iterations, .. } => iterations,
            Method::ImplicitEuler {
                cg_max_iterations, ..
            } => cg_max_iterations,
            _ => 1,
        }
    }

    /// Whether the method has an iteration knob: solver iterations (PBD, XPBD) or the CG cap
    /// (implicit Euler). The others report 1 from [`Method::iterations`].
    pub fn has_iterations(&self) -> bool {
        matches!(
            self,
            Method::Pbd { .. } | Method::Xpbd { .. } | Method::ImplicitEuler { .. }
        )
    }

    /// This method with the given sub-steps and iterations (PBD, XPBD; the CG cap of implicit Euler),
    /// its other knobs unchanged (`None`: that knob unchanged too; a method without iterations ignores
    /// them).
    pub fn with_knobs(self, substeps: Option<u32>, iterations: Option<u32>) -> Method {
        let s = |x: u32| substeps.unwrap_or(x);
        let i = |x: u32| iterations.unwrap_or(x);
        match self {
            Method::ExplicitEuler { substeps } => Method::ExplicitEuler {
                substeps: s(substeps),
            },
            Method::SymplecticEuler { substeps } => Method::SymplecticEuler {
                substeps: s(substeps),
            },
            Method::Verlet { substeps } => Method::Verlet {
                substeps: s(substeps),
            },
            Method::ImplicitEuler {
                substeps,
                cg_max_iterations,
                cg_tolerance,
            } => Method::ImplicitEuler {
                substeps: s(substeps),
                cg_max_iterations: i(cg_max_iterations),
                cg_tolerance,
            },
            Method::Pbd {
                substeps,
                iterations,
                stiffness,
            } => Method::Pbd {
                substeps: s(substeps),
                iterations: i(iterations),
                stiffness,
            },
            Method::Xpbd {
                substeps,
                iterations,
            } => Method::Xpbd {
                substeps: s(substeps),
                iterations: i(iterations),
            },
            Method::SmallStepsXpbd { substeps } => Method::SmallStepsXpbd {
                substeps: s(substeps),
            },
        }
    }

    /// Short snake_case name, as used in scene files, CSV output and charts.
    pub fn name(&self) -> &'static str {
        match self {
            Method::ExplicitEuler { .. } => "explicit_euler",
            Method::SymplecticEuler { .. } => "symplectic_euler",
            Method::Verlet { .. } => "verlet",
            Method::ImplicitEuler { .. } => "implicit_euler",
            Method::Pbd { .. } => "pbd",
            Method::Xpbd { .. } => "xpbd",
            Method::SmallStepsXpbd { .. } => "small_steps_xpbd",
        }
    }

    /// Every method with the given sub-step count and otherwise default knobs (for sweeps and benches).
    pub fn all_with_substeps(substeps: u32, iterations: u32) -> [Method; 7] {
        [
            Method::ExplicitEuler { substeps },
            Method::SymplecticEuler { substeps },
            Method::Verlet { substeps },
            Method::ImplicitEuler {
                substeps,
                // Ten per iteration; a cap beyond u32 is no cap at all, so it saturates.
                cg_max_iterations: iterations.max(1).saturating_mul(10),
                cg_tolerance: 1e-6,
            },
            Method::Pbd {
                substeps,
                iterations,
                stiffness: 1.0,
            },
            Method::Xpbd {
                substeps,
                iterations,
            },
            Method::SmallStepsXpbd { substeps },
        ]
    }

    /// Parses a method name as printed by [`Method::name`], with the given knobs.
    pub fn from_name(name: &str, substeps: u32, iterations: u32) -> Option<Method> {
        Method::all_with_substeps(substeps, iterations)
            .into_iter()
            .find(|m| m.name() == name)
    }

    fn validate(&self) -> Result<(), ParamError> {
        if self.substeps() == 0 {
            return Err(ParamError::new(
                "method.substeps",
                0.0,
                "must be at least 1",
            ));
        }
        match *self {
            Method::ImplicitEuler {
                cg_max_iterations,
                cg_tolerance,
                ..
            } => {
                if cg_max_iterations == 0 {
                    return Err(ParamError::new(
                        "method.cg_max_iterations",
                        0.0,
                        "must be at least 1",
                    ));
                }
                // CG starts from Δv = 0, a relative residual of 1: a tolerance of 1 or more stops it
                // before its first iteration and leaves the cloth's velocities unchanged.
                if !(cg_tolerance > 0.0 && cg_tolerance < 1.0) {
                    return Err(ParamError::new(
                        "method.cg_tolerance",
                        cg_tolerance,
                        "must lie in (0, 1): CG starts at a relative residual of 1",
                    ));
                }
            }
            Method::Pbd {
                iterations,
                stiffness,
                ..
            } => {
                if iterations == 0 {
                    return Err(ParamError::new(
                        "method.iterations",
                        0.0,
                        "must be at least 1",
                    ));
                }
                if !(stiffness > 0.0 && stiffness <= 1.0) {
                    return Err(ParamError::new(
                        "method.stiffness",
                        stiffness,
                        "PBD stiffness must lie in (0, 1]",
                    ));
                }
            }
            Method::Xpbd { iterations: 0, .. } => {
                return Err(ParamError::new(
                    "method.iterations",
                    0.0,
                    "must be at least 1",
                ));
            }
            _ => {}
        }
        Ok(())
    }
}

impl Default for Method {
    /// Small-steps XPBD with 40 sub-steps: the study's automatic choice for the default flag
    /// (`docs/choice.toml`, `docs/study.md`; the app tests that its default scene matches it).
    fn default() -> Self {
        Method::SmallStepsXpbd { substeps: 40 }
    }
}

/// One family of springs (stretch, shear or bending): switchable, with its own stiffness and damping.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpringParams {
    /// Whether this family of springs exists in the model at all.
    pub enabled: bool,
    /// Hooke stiffness per spring, N/m. XPBD uses the compliance `1/stiffness` (m/N).
    pub stiffness: f64,
    /// Dashpot coefficient along the spring, N·s/m (XPBD: Macklin et al. 2016 eq. (26), `β = damping`).
    pub damping: f64,
}

impl SpringParams {
    /// An enabled family with the given stiffness (N/m) and damping (N·s/m).
    pub fn new(stiffness: f64, damping: f64) -> Self {
        SpringParams {
            enabled: true,
            stiffness,
            damping,
        }
    }

    /// A switched-off family.
    pub fn disabled() -> Self {
        SpringParams {
            enabled: false,
            ..SpringParams::default()
        }
    }

    /// Checks the family's knobs; the error names the field, `{family}.stiffness` or `{family}.damping`.
    /// A switched-off family is checked too, for what it keeps until it is switched back on: a
    /// stiffness of 0 there says "none", a NaN or a negative value is an error.
    fn validate(&self, keys: [&'static str; 2]) -> Result<(), ParamError> {
        if self.enabled {
            positive(keys[0], self.stiffness)?;
        } else {
            non_negative(keys[0], self.stiffness)?;
        }
        non_negative(keys[1], self.damping)?;
        Ok(())
    }
}

impl Default for SpringParams {
    fn default() -> Self {
        SpringParams::new(100.0, 0.0)
    }
}

/// Wind: a uniform air velocity with deterministic gusts, acting on every triangle through a flat-plate
/// drag and lift model (Ling, Damodaran & Gay 1996, "Aerodynamic force models for animating cloth
/// motion in air flow").
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Wind {
    /// Mean air velocity, m/s.
    pub velocity: DVec3,
    /// Air density, kg/m³ (1.225 at sea level, 15 °C).
    pub air_density: f64,
    /// Drag coefficient of a flat plate normal to the flow (dimensionless; about 1.2 for a square plate).
    pub drag_coefficient: f64,
    /// Lift coefficient (dimensionless); 0 switches lift off.
    pub lift_coefficient: f64,
    /// Gust amplitude as a fraction of the mean speed along the wind; 0 switches gusts off.
    pub gust_strength: f64,
    /// Lateral turbulence amplitude as a fraction of the mean speed; 0 switches it off.
    pub turbulence: f64,
    /// Typical gust frequency, Hz.
    pub gust_frequency: f64,
    /// Seed of the gust signal: the same seed gives the same gusts, bit for bit.
    pub seed: u64,
    /// Re-evaluate the aerodynamic forces every sub-step (default) instead of once per `step`, held over
    /// its sub-steps. Held forces cost a twentieth but treat drag explicitly over the whole frame: its
    /// rate `ρ C_D |u| / (2 × areal density)` times the frame time must stay well below 2, which fails
    /// for light fabric in strong wind (0.1 kg/m² at 10–12 m/s diverges at 60 Hz; tested).
    pub per_substep: bool,
    /// With `per_substep`: the longest the aerodynamic forces are held, s. They are renewed at the
    /// first sub-step of each `step` and then every `⌊renewal_interval / h⌋` sub-steps of length `h`
    /// (every sub-step where that is below 2), at the first force evaluation of that sub-step; 0 (the
    /// library's default) renews them at every force evaluation. A time rather than a count of
    /// sub-steps, so that the same value holds the forces equally long whatever the method's sub-step.
    /// On the default flag, holding them for up to 1, 2 or 4 ms changed nothing the study resolves
    /// across eight seeds of the gusts (`sheer study seeds`), and renewing them at every sub-step costs
    /// 1.150× the frame of the 2 ms hold (`sheer study ablation`; docs/study.md).
    pub renewal_interval: f64,
}

impl Default for Wind {
    fn default() -> Self {
        Wind {
            velocity: DVec3::new(0.0, 0.0, 0.0),
            air_density: 1.225,
            drag_coefficient: 1.2,
            lift_coefficient: 0.4,
            gust_strength: 0.3,
            turbulence: 0.15,
            gust_frequency: 0.5,
            seed: 1,
            per_substep: true,
            renewal_interval: 0.0,
        }
    }
}

impl Wind {
    /// Whether the wind can exert any force (a zero mean velocity with no gusts does nothing).
    pub fn is_active(&self) -> bool {
        self.velocity != DVec3::ZERO
            && (self.drag_coefficient != 0.0 || self.lift_coefficient != 0.0)
    }

    /// Whether the aerodynamic forces are re-evaluated at every force evaluation (the library's
    /// default): `per_substep` with `renewal_interval` = 0.
    pub fn updated_every_substep(&self) -> bool {
        self.per_substep && self.renewal_interval == 0.0
    }

    /// Re-evaluates the aerodynamic forces at every force evaluation (the library's default):
    /// `per_substep` with `renewal_interval` = 0.
    pub fn renew_at_every_evaluation(&mut self) {
        self.per_substep = true;
        self.renewal_interval = 0.0;
    }

    /// Holds the forces of each step's start over all its sub-steps: `per_substep` off, and with it
    /// `renewal_interval` 0, the only value allowed then (a held frame has no interval to renew at).
    pub fn hold_for_each_step(&mut self) {
        self.per_substep = false;
        self.renewal_interval = 0.0;
    }

    /// With a `renewal_interval` > 0 and sub-steps of `h` s: the forces are renewed every this many
    /// sub-steps, `⌊renewal_interval / h⌋`, at least 1. An interval of exactly `k·h` gives `k` (a
    /// relative 10⁻⁹ allows for its rounding).
    pub fn substeps_per_renewal(&self, h: f64) -> u32 {
        let substeps = (self.renewal_interval / h * (1.0 + 1e-9)).floor();
        if substeps.is_nan() || substeps < 1.0 {
            1
        } else {
            substeps.min(f64::from(u32::MAX)) as u32
        }
    }

    /// Whether the held forces are due for renewal at sub-step `substep` (from 0) of a step of sub-steps
    /// of `h` s: only with `per_substep` and a `renewal_interval` > 0 (otherwise they are renewed at every
    /// evaluation, or held for the whole step).
    pub fn renewal_due(&self, substep: u32, h: f64) -> bool {
        self.per_substep
            && self.renewal_interval > 0.0
            && substep.is_multiple_of(self.substeps_per_renewal(h))
    }

    pub(crate) fn validate(&self) -> Result<(), ParamError> {
        finite_vec("wind.velocity", self.velocity)?;
        non_negative("wind.air_density", self.air_density)?;
        non_negative("wind.drag_coefficient", self.drag_coefficient)?;
        non_negative("wind.lift_coefficient", self.lift_coefficient)?;
        non_negative("wind.gust_strength", self.gust_strength)?;
        non_negative("wind.turbulence", self.turbulence)?;
        positive("wind.gust_frequency", self.gust_frequency)?;
        non_negative("wind.renewal_interval", self.renewal_interval)?;
        // Held for the whole frame, the forces have no interval to renew at; a value here would be
        // ignored without a word.
        if !self.per_substep && self.renewal_interval != 0.0 {
            return Err(ParamError::new(
                "wind.renewal_interval",
                self.renewal_interval,
                "applies only with wind.per_substep = true (false holds the forces for the whole frame)",
            ));
        }
        Ok(())
    }
}

/// When a step counts as diverged. A diverged step is undone and reported as
/// [`StepError::Diverged`](crate::StepError::Diverged).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DivergenceLimits {
    /// Largest particle speed still believed, m/s.
    pub max_speed: f64,
    /// Largest spring strain `length/rest − 1` still believed (dimensionless).
    pub max_strain: f64,
}

impl Default for DivergenceLimits {
    fn default() -> Self {
        // A flag in a 30 m/s gale whips its fly end at a few tens of m/s; real fabric breaks long before
        // it stretches to 11 times its length. Anything beyond is numerical runaway.
        DivergenceLimits {
            max_speed: 200.0,
            max_strain: 10.0,
        }
    }
}

/// All parameters of a run besides the mesh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimParams {
    /// The integrator and its sub-step and iteration counts.
    pub method: Method,
    /// Springs along the mesh edges (grid rows and columns).
    pub stretch: SpringParams,
    /// Springs across grid cell diagonals (grids only; a triangle mesh's edges already resist shear).
    pub shear: SpringParams,
    /// Springs skipping one particle (grids) or joining the far corners of adjacent triangles (meshes).
    pub bend: SpringParams,
    /// Gravitational acceleration, m/s².
    pub gravity: DVec3,
    /// Linear air damping of absolute velocity, 1/s (`f = −m c v`).
    pub air_damping: f64,
    /// The wind on the cloth's triangles (a grid or mesh; springs-only models feel none).
    pub wind: Wind,
    /// Position-based methods only: long-range attachments (Kim, Chentanez & Müller 2012, "Long Range
    /// Attachments — A Method to Simulate Inextensible Clothing in Computer Games"). Each free particle
    /// may not move further from its nearest pinned particle than at rest. Gauss–Seidel needs about as many
    /// sweeps as the cloth is particles long to carry a load from the pole to the fly end; the tethers
    /// carry it in one, so a hanging flag does not stretch like rubber at 20 sweeps per frame (the
    /// default flag released in still air: a 99th-percentile stretch strain of at most 0.021 with them,
    /// 0.119 without; `examples/hanging_stretch.rs`).
    pub long_range_attachments: bool,
    /// When a step counts as diverged and is undone ([`StepError::Diverged`](crate::StepError::Diverged)).
    pub divergence: DivergenceLimits,
    /// Below this many particles every pass runs on one thread. From it, the mass–spring methods' passes
    /// run on rayon's pool (the position-based methods on a general mesh stay on one thread), and the
    /// position-based methods on a grid on a team of as many threads as rayon's
    /// pool has (but at most a fifth of the grid's rows, and at least two), which spin between
    /// passes and stay with the simulation (parked while it is not stepping). Results are
    /// bit-identical either way. The team pays from about 400 particles when the machine has a free
    /// core for each of its threads; the default leaves cloths below 16 384 particles (where
    /// rayon's pool starts to pay) on one thread, so that a small cloth does not take a second core
    /// unasked, e.g. from the app's renderer.
    pub parallel_min_particles: usize,
    /// Position-based methods only: contacts of the cloth with itself and with colliders. Off by
    /// default (no self-collision, no colliders); a force-based method with either on is refused.
    pub collisions: Collisions,
}

/// Contacts of the cloth with itself and with rigid colliders, resolved as position constraints
/// every sub-step of a position-based method (`collision.rs`). A force-based method with any contact
/// switched on is refused by [`SimParams::validate`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Collisions {
    /// Whether the cloth collides with itself: every particle keeps `thickness` from every triangle,
    /// and every edge from every edge, that it does not touch at rest.
    pub self_collision: bool,
    /// The cloth's thickness, m: the gap self-contacts keep between layers, and twice the gap kept
    /// from a collider's surface. Light flag fabric is a fraction of a millimetre thick; the default
    /// 4 mm is a cushion that the default flag's particles cannot cross in one sub-step.
    pub thickness: f64,
    /// Coulomb friction coefficient of the cloth on colliders (dimensionless, ≥ 0): a particle in
    /// contact stops sliding while its tangential motion over a sub-step is at most `friction` times
    /// the depth it was pushed out by (Macklin et al. 2014, "Unified particle physics", §6.1).
    pub friction: f64,
    /// Rigid obstacles, fixed in space (move them between steps with
    /// [`Simulation::set_params`](crate::Simulation::set_params)).
    pub colliders: Vec<Collider>,
}

impl Default for Collisions {
    fn default() -> Self {
        Collisions {
            self_collision: false,
            thickness: 0.004,
            friction: 0.3,
            colliders: Vec::new(),
        }
    }
}

impl Collisions {
    /// Whether any contact is switched on.
    pub fn any(&self) -> bool {
        self.self_collision || !self.colliders.is_empty()
    }

    /// Checks every field; the error names the first bad one (a collider's key without its index:
    /// [`Collider::validate`] checks one collider).
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("collisions.thickness", self.thickness)?;
        non_negative("collisions.friction", self.friction)?;
        self.colliders.iter().try_for_each(Collider::validate)
    }
}

/// A rigid obstacle the cloth cannot enter: its particles keep half the cloth's thickness from its
/// surface. Serialised as a table with `kind` (`{ kind = "sphere", center = [0, 0, 0], radius = 0.2 }`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Collider {
    /// A ball: centre (m) and radius (m).
    Sphere {
        /// Centre, m.
        center: DVec3,
        /// Radius, m (> 0).
        radius: f64,
    },
    /// A capsule (a segment swept by a ball), such as a flag pole: the segment's ends (m) and radius (m).
    Capsule {
        /// One end of the axis, m.
        start: DVec3,
        /// The other end of the axis, m.
        end: DVec3,
        /// Radius, m (> 0).
        radius: f64,
    },
    /// A half-space, such as the ground: a point on its surface (m) and the normal pointing out of it
    /// (any length > 0; normalised when used).
    Plane {
        /// A point on the surface, m.
        point: DVec3,
        /// The outward normal (towards where the cloth may be).
        normal: DVec3,
    },
}

/// Radius of the flag pole of [`Collider::flag_pole`], m.
pub const FLAG_POLE_RADIUS: f64 = 0.015;

impl Collider {
    /// The pole of a flag hung as [`GridSpec`](crate::GridSpec) says (hoist pinned at `x =
    /// origin.x`): a vertical capsule of radius [`FLAG_POLE_RADIUS`] from 1.5 m below the flag's foot
    /// to 6 cm above its top, its axis behind the hoist by the radius and half of `thickness` (m), the
    /// distance contacts keep, so that the flag at rest touches it nowhere however fine its grid.
    pub fn flag_pole(flag: &crate::GridSpec, thickness: f64) -> Collider {
        let axis_top = flag.origin + DVec3::new(-(FLAG_POLE_RADIUS + thickness / 2.0), 0.06, 0.0);
        Collider::Capsule {
            start: axis_top - DVec3::new(0.0, flag.height + 1.56, 0.0),
            end: axis_top,
            radius: FLAG_POLE_RADIUS,
        }
    }

    /// Checks this collider's fields; the error names the key within the collider's table, e.g.
    /// `"collisions.colliders.radius"`.
    pub fn validate(&self) -> Result<(), ParamError> {
        match *self {
            Collider::Sphere { center, radius } => {
                finite_vec("collisions.colliders.center", center)?;
                positive("collisions.colliders.radius", radius)
            }
            Collider::Capsule { start, end, radius } => {
                finite_vec("collisions.colliders.start", start)?;
                finite_vec("collisions.colliders.end", end)?;
                positive("collisions.colliders.radius", radius)
            }
            Collider::Plane { point, normal } => {
                finite_vec("collisions.colliders.point", point)?;
                finite_vec("collisions.colliders.normal", normal)?;
                let length = normal.length();
                if length > 0.0 && length.is_finite() {
                    Ok(())
                } else {
                    Err(ParamError::new(
                        "collisions.colliders.normal",
                        length,
                        "must have a finite length > 0",
                    ))
                }
            }
        }
    }
}

impl Default for SimParams {
    fn default() -> Self {
        SimParams {
            method: Method::default(),
            stretch: SpringParams::new(1000.0, 0.01),
            shear: SpringParams::new(100.0, 0.002),
            bend: SpringParams::new(15.0, 0.001),
            gravity: DVec3::new(0.0, -9.81, 0.0),
            air_damping: 0.05,
            wind: Wind::default(),
            long_range_attachments: true,
            divergence: DivergenceLimits::default(),
            parallel_min_particles: 16_384,
            collisions: Collisions::default(),
        }
    }
}

impl SimParams {
    /// Parameters with every force switched off except the springs (for tests of internal dynamics).
    pub fn springs_only(method: Method, stretch: SpringParams) -> Self {
        SimParams {
            method,
            stretch,
            shear: SpringParams::disabled(),
            bend: SpringParams::disabled(),
            gravity: DVec3::ZERO,
            air_damping: 0.0,
            wind: Wind {
                velocity: DVec3::ZERO,
                ..Wind::default()
            },
            ..SimParams::default()
        }
    }

    /// Removes the dashpots of all three spring families (`damping` 0 N·s/m; the position-based solvers
    /// on a grid then skip the damping term), stiffnesses unchanged.
    pub fn remove_spring_damping(&mut self) {
        for springs in [&mut self.stretch, &mut self.shear, &mut self.bend] {
            springs.damping = 0.0;
        }
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.method.validate()?;
        self.stretch
            .validate(["stretch.stiffness", "stretch.damping"])?;
        self.shear.validate(["shear.stiffness", "shear.damping"])?;
        self.bend.validate(["bend.stiffness", "bend.damping"])?;
        finite_vec("gravity", self.gravity)?;
        non_negative("air_damping", self.air_damping)?;
        self.wind.validate()?;
        positive("divergence.max_speed", self.divergence.max_speed)?;
        positive("divergence.max_strain", self.divergence.max_strain)?;
        self.collisions.validate()?;
        if self.collisions.any() && !self.method.is_position_based() {
            return Err(ParamError::new(
                "collisions.self_collision",
                1.0,
                "contacts need a position-based method (pbd, xpbd, small_steps_xpbd): switch \
                 collisions off (self_collision = false, no colliders) for a force-based one",
            ));
        }
        Ok(())
    }
}

fn positive(name: &'static str, value: f64) -> Result<(), ParamError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ParamError::new(name, value, "must be finite and > 0"))
    }
}

fn non_negative(name: &'static str, value: f64) -> Result<(), ParamError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(ParamError::new(name, value, "must be finite and ≥ 0"))
    }
}

fn finite_vec(name: &'static str, value: DVec3) -> Result<(), ParamError> {
    for component in value.to_array() {
        if !component.is_finite() {
            return Err(ParamError::new(name, component, "must be finite"));
        }
    }
    Ok(())
}

impl Method {
    /// Every method's name as [`Method::name`] prints it, in the order tables, charts and menus list
    /// them (the force-based integrators from least to most stable, then the position-based ones).
    pub const NAMES: [&'static str; 7] = [
        "explicit_euler",
        "symplectic_euler",
        "verlet",
        "implicit_euler",
        "pbd",
        "xpbd",
        "small_steps_xpbd",
    ];

    /// The setting at which method `name` runs the default flag (64 × 46 particles, 60 Hz frames)
    /// without diverging, measured by the study (`docs/study.md`, `docs/work-precision.csv`): the
    /// explicit mass–spring methods need their sub-step below `2/ω_max` of the stiffest spring
    /// (symplectic Euler and Verlet: 200 sub-steps; forward Euler, which only its damping keeps
    /// bounded, 1600 — it diverges at 400); implicit Euler and the position-based methods are stable
    /// at any step, so they get the cheapest settings the benches compare. `None` for an unknown name.
    /// On finer grids the explicit methods need proportionally more sub-steps.
    pub fn stable_flag_setting(name: &str) -> Option<Method> {
        Some(match name {
            "explicit_euler" => Method::ExplicitEuler { substeps: 1600 },
            "symplectic_euler" => Method::SymplecticEuler { substeps: 200 },
            "verlet" => Method::Verlet { substeps: 200 },
            "implicit_euler" => Method::ImplicitEuler {
                substeps: 1,
                cg_max_iterations: 100,
                cg_tolerance: 1e-4,
            },
            "pbd" => Method::Pbd {
                substeps: 4,
                iterations: 10,
                stiffness: 1.0,
            },
            "xpbd" => Method::Xpbd {
                substeps: 2,
                iterations: 20,
            },
            "small_steps_xpbd" => Method::SmallStepsXpbd { substeps: 20 },
            _ => return None,
        })
    }
}

/// How long the default flag holds the wind's forces at most, s ([`Wind::renewal_interval`]): every
/// 4 of its 40 sub-steps a frame. Across eight seeds of the gusts, holding them for up to 1, 2 or 4 ms
/// changed the flag's time-averaged coverage by +0.0011, +0.0011 and −0.0004 (standard errors
/// 0.0008–0.0010) against a budget of 0.04, and once per frame by +0.0086 ± 0.0032 (`sheer study
/// seeds`, docs/seeds.md).
pub const DEFAULT_FLAG_WIND_RENEWAL_INTERVAL: f64 = 0.002;

impl SimParams {
    /// The app's default waving flag (`assets/default.scene.toml`): the default fabric in a fresh
    /// breeze of 5 m/s along the flag with 2.5 m/s across it (27° from its plane), gusting by half the
    /// mean speed with lateral turbulence of 0.4 of it, long-range attachments on, integrated by
    /// [`Method::default`] (the study's automatic choice, `docs/choice.toml`). The app's scene
    /// defaults and the study's `default_flag` scene both start from this, so the choice is measured
    /// on exactly the flag the app shows.
    pub fn waving_flag() -> SimParams {
        let mut params = SimParams::default();
        params.wind.velocity = DVec3::new(5.0, 0.0, 2.5);
        params.wind.gust_strength = 0.5;
        params.wind.turbulence = 0.4;
        params.wind.renewal_interval = DEFAULT_FLAG_WIND_RENEWAL_INTERVAL;
        params
    }
}

#[cfg(test)]
mod wind_renewal_tests {
    use super::*;

    #[test]
    fn an_interval_of_whole_sub_steps_renews_after_exactly_that_many() {
        let held = |interval: f64| Wind {
            renewal_interval: interval,
            ..Wind::default()
        };
        // k sub-steps of a 60 Hz frame cut into n, however the products round.
        for n in [3, 7, 20, 40, 41, 200, 1200] {
            let h = 1.0 / 60.0 / f64::from(n);
            for k in [1, 2, 3, 4, 9, 10] {
                let interval = f64::from(k) * h;
                assert_eq!(held(interval).substeps_per_renewal(h), k, "{k} of {n}");
                // A hair less than k sub-steps holds the forces for one sub-step fewer.
                assert_eq!(
                    held(interval * (1.0 - 1e-6)).substeps_per_renewal(h),
                    (k - 1).max(1),
                    "just under {k} of {n}"
                );
            }
        }
        // The default flag: 2 ms of ×40 is 4 sub-steps, of ×20 two, of ×10 one.
        for (n, k) in [(40, 4), (20, 2), (10, 1)] {
            let h = 1.0 / 60.0 / f64::from(n);
            assert_eq!(
                held(DEFAULT_FLAG_WIND_RENEWAL_INTERVAL).substeps_per_renewal(h),
                k
            );
        }
        // No interval, an absurd one, or an absurd sub-step: never 0 (a modulus), never a panic.
        assert_eq!(held(0.0).substeps_per_renewal(1e-3), 1);
        assert_eq!(held(1e300).substeps_per_renewal(1e-3), u32::MAX);
        assert_eq!(held(2e-3).substeps_per_renewal(0.0), u32::MAX);
        assert_eq!(held(2e-3).substeps_per_renewal(f64::NAN), 1);
        // Due at the step's first sub-step and every k-th after; never without an interval or with
        // the forces held for the whole step.
        let h = 1.0 / 2400.0;
        let due: Vec<u32> = (0..12).filter(|&s| held(2e-3).renewal_due(s, h)).collect();
        assert_eq!(due, [0, 4, 8]);
        assert!((0..12).all(|s| !held(0.0).renewal_due(s, h)));
        let frame = Wind {
            per_substep: false,
            ..Wind::default()
        };
        assert!((0..12).all(|s| !frame.renewal_due(s, h)));
    }

    /// The two settings without an interval, from any wind: each valid, and each what it says.
    #[test]
    fn holding_for_each_step_and_renewing_every_evaluation_are_valid_settings() {
        for start in [Wind::default(), SimParams::waving_flag().wind] {
            let mut held = start;
            held.hold_for_each_step();
            assert!(held.validate().is_ok() && !held.per_substep && !held.updated_every_substep());
            let mut renewed = held;
            renewed.renew_at_every_evaluation();
            assert!(renewed.validate().is_ok() && renewed.updated_every_substep());
        }
    }
}

#[cfg(test)]
mod method_name_tests {
    use super::*;

    #[test]
    fn every_name_has_a_stable_flag_setting_of_that_method() {
        for name in Method::NAMES {
            let method = Method::stable_flag_setting(name).unwrap();
            assert_eq!(method.name(), name);
            assert!(method.validate().is_ok(), "{name}");
            assert_eq!(Method::from_name(name, 1, 1).map(|m| m.name()), Some(name));
        }
        assert_eq!(Method::stable_flag_setting("rk4"), None);
        // NAMES lists every variant once.
        let mut sorted = Method::NAMES.to_vec();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), Method::all_with_substeps(1, 1).len());
        // The iteration knob: exactly the methods whose iteration count follows the one asked for.
        for method in Method::all_with_substeps(1, 7) {
            assert_eq!(
                method.has_iterations(),
                method.iterations() != 1,
                "{method:?}"
            );
        }
    }
}
