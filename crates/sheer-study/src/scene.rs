//! The scenes of the study: a waving flag, a hanging sheet settling under gravity, and a stiff sheet
//! on which the explicit integrators fail.
//!
//! A scene is a grid, which edge is pinned, the full [`SimParams`] (the method is filled in per run),
//! the frame time at which `Simulation::step` is called and, for the flags, the window of the
//! time-averaged coverage ([`crate::coverage`]). The flags start from the app's default flag
//! ([`SimParams::waving_flag`]), so the study measures the flag the app shows. Long-range attachments
//! are off in the sweep scenes: they are an extra constraint that only the position-based methods know,
//! so with them on the methods would not integrate the same model; and the sweep's flag renews the wind
//! at every sub-step: the default flag's held wind (`Wind::renewal_interval`) is an approximation whose
//! error, a few millimetres at 0.25 s, would hide the fine explicit settings' own. The automatic choice runs on
//! [`Scene::default_flag`], the app's default exactly, attachments on (the ablation measures what they
//! change).

use sheer_cloth::glam::DVec3;
use sheer_cloth::{ClothModel, GridSpec, Method, SimParams, Simulation, SpringParams};

use crate::StudyError;
use crate::coverage::CoverageWindow;

/// Which particles are pinned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pinning {
    /// Column 0, the flag's pole side.
    Hoist,
    /// Row 0, a sheet hung from its top edge.
    TopEdge,
    /// Nothing pinned (a free cloth).
    Free,
}

/// A cloth, its pins, its parameters and the frame time of the study's runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Short snake_case name (CSV column `scene`).
    pub name: String,
    /// The particle grid: counts, size (m), areal density (kg/m²) and placement.
    pub grid: GridSpec,
    /// Which particles are pinned.
    pub pinning: Pinning,
    /// Parameters of the model; `method` is replaced by each run's method.
    pub params: SimParams,
    /// Time per `Simulation::step` call, s (the app's 60 Hz frame).
    pub frame: f64,
    /// Frames over which runs of this scene accumulate their time-averaged coverage (`None`: not
    /// measured). Runs last at least until the window's end.
    pub coverage: Option<CoverageWindow>,
}

/// The app's frame time, s.
pub const FRAME: f64 = 1.0 / 60.0;

impl Scene {
    /// The app's default waving flag ([`SimParams::waving_flag`]: 1.1 m × 0.8 m, 0.2 kg/m², hoist
    /// pinned, 5 m/s wind along +x with 2.5 m/s across, gusts and turbulence on) at `columns × rows`
    /// particles, long-range attachments off, the wind renewed at every sub-step, coverage over
    /// [`CoverageWindow::flag`].
    pub fn flag((columns, rows): (usize, usize)) -> Result<Scene, StudyError> {
        let grid = GridSpec {
            columns,
            rows,
            ..GridSpec::default()
        };
        let mut params = SimParams {
            long_range_attachments: false,
            ..SimParams::waving_flag()
        };
        params.wind.renew_at_every_evaluation();
        Scene::checked(Scene {
            name: "flag".into(),
            grid,
            pinning: Pinning::Hoist,
            params,
            frame: FRAME,
            coverage: Some(CoverageWindow::flag()),
        })
    }

    /// Exactly the app's default flag: [`GridSpec::default`] (64 × 46) and [`SimParams::waving_flag`]
    /// (long-range attachments on, as the app runs it), coverage over [`CoverageWindow::flag`]. The
    /// automatic choice and the ablation run on it.
    pub fn default_flag() -> Result<Scene, StudyError> {
        Scene::checked(Scene {
            name: "default_flag".into(),
            grid: GridSpec::default(),
            pinning: Pinning::Hoist,
            params: SimParams::waving_flag(),
            frame: FRAME,
            coverage: Some(CoverageWindow::flag()),
        })
    }

    /// The same scene with another coverage window (`None`: no coverage).
    pub fn with_coverage(self, coverage: Option<CoverageWindow>) -> Scene {
        Scene { coverage, ..self }
    }

    /// The flag's fabric hung from its top edge in still air, settling under gravity from rest.
    pub fn hanging_sheet((columns, rows): (usize, usize)) -> Result<Scene, StudyError> {
        let grid = GridSpec {
            columns,
            rows,
            ..GridSpec::default()
        };
        let mut params = SimParams {
            long_range_attachments: false,
            ..SimParams::waving_flag()
        };
        params.wind.velocity = DVec3::ZERO;
        Scene::checked(Scene {
            name: "hanging_sheet".into(),
            grid,
            pinning: Pinning::TopEdge,
            params,
            frame: FRAME,
            coverage: None,
        })
    }

    /// A hanging sheet of stiff fabric (stretch 10⁵ N/m, shear 10⁴ N/m, bending 500 N/m: the default
    /// ratios scaled by 100), pushed by the flag's wind: its highest spring frequency puts the explicit
    /// integrators' stability limit below 10⁻⁴ s, so they fail at any practical sub-step count.
    pub fn stiff((columns, rows): (usize, usize)) -> Result<Scene, StudyError> {
        let grid = GridSpec {
            columns,
            rows,
            ..GridSpec::default()
        };
        let mut params = SimParams {
            long_range_attachments: false,
            stretch: SpringParams::new(1.0e5, 1.0),
            shear: SpringParams::new(1.0e4, 0.2),
            bend: SpringParams::new(500.0, 0.05),
            ..SimParams::default()
        };
        params.wind.velocity = DVec3::new(3.0, 0.0, 3.0);
        Scene::checked(Scene {
            name: "stiff".into(),
            grid,
            pinning: Pinning::TopEdge,
            params,
            frame: FRAME,
            coverage: None,
        })
    }

    /// Undamped springs only plus gravity, hung from the top edge: the scene of the stability map, on
    /// which linear stability analysis applies exactly (no dashpots, drag or air damping to shift the
    /// boundary). Stretch stiffness `stretch` N/m, shear a tenth and bending a two-hundredth of it
    /// (the default flag's ratios).
    pub fn undamped_sheet(
        (columns, rows): (usize, usize),
        stretch: f64,
    ) -> Result<Scene, StudyError> {
        if !(stretch.is_finite() && stretch > 0.0) {
            return Err(StudyError::InvalidInput {
                name: "stretch stiffness",
                value: stretch,
                reason: "must be finite and > 0 N/m",
            });
        }
        let grid = GridSpec {
            columns,
            rows,
            ..GridSpec::default()
        };
        let mut params = SimParams {
            long_range_attachments: false,
            stretch: SpringParams::new(stretch, 0.0),
            shear: SpringParams::new(stretch / 10.0, 0.0),
            bend: SpringParams::new(stretch / 200.0, 0.0),
            air_damping: 0.0,
            ..SimParams::default()
        };
        params.wind.velocity = DVec3::ZERO;
        Scene::checked(Scene {
            name: "undamped_sheet".into(),
            grid,
            pinning: Pinning::TopEdge,
            params,
            frame: FRAME,
            coverage: None,
        })
    }

    fn checked(scene: Scene) -> Result<Scene, StudyError> {
        scene.model()?;
        Ok(scene)
    }

    /// The pinned cloth model of this scene.
    pub fn model(&self) -> Result<ClothModel, StudyError> {
        let model = ClothModel::grid(&self.grid)?;
        Ok(match self.pinning {
            Pinning::Hoist => model.with_hoist_pinned()?,
            Pinning::TopEdge => model.with_top_edge_pinned()?,
            Pinning::Free => model,
        })
    }

    /// The scene's parameters with `method`.
    pub fn params_with(&self, method: Method) -> SimParams {
        SimParams {
            method,
            ..self.params.clone()
        }
    }

    /// A simulation of this scene at rest, integrated by `method`.
    pub fn simulation(&self, method: Method) -> Result<Simulation, StudyError> {
        Ok(Simulation::new(self.model()?, self.params_with(method))?)
    }

    /// The same scene at another resolution (same size, fabric and forces).
    pub fn with_resolution(&self, columns: usize, rows: usize) -> Result<Scene, StudyError> {
        Scene::checked(Scene {
            grid: GridSpec {
                columns,
                rows,
                ..self.grid
            },
            ..self.clone()
        })
    }

    /// Particles of the scene's grid.
    pub fn particle_count(&self) -> usize {
        self.grid.columns * self.grid.rows
    }
}
