//! The window (eframe + egui on wgpu): the waving flag with a side panel of every knob, a live readout of
//! the time each stage takes, mouse orbit and zoom, screenshots, and a scripted mode
//! (`sheer --frames N --screenshot F`) that runs N frames, saves the whole window and exits.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use eframe::egui;
use eframe::wgpu;
use sheer_cloth::Method;

use crate::CliError;
use crate::frame::{FlagScene, FrameShading, StageTimes};
use crate::scene::{Scene, ShadingModel, ShadingSection};
use crate::window_image::{WindowImage, wanted_features};
use sheer_slab::ScatteringOrders;
use sheer_slab::render::{AllOrdersSampling, EvaluationPath};

/// Options of the window from the command line.
#[derive(Debug, Clone, Default)]
pub struct WindowOptions {
    pub scene: Option<PathBuf>,
    /// Run this many frames, then (with `screenshot`) save the window and exit.
    pub frames: Option<u32>,
    pub screenshot: Option<PathBuf>,
}

/// A number typed into the panel: kept as text while edited, applied only when it parses and passes
/// its check; otherwise refused with a message.
struct NumberField {
    label: &'static str,
    text: String,
    error: Option<String>,
}

impl NumberField {
    fn new(label: &'static str, value: f64) -> Self {
        NumberField {
            label,
            text: format!("{}", value as f32),
            error: None,
        }
    }

    /// Shows the field; returns the new value when one was entered and accepted.
    fn show(
        &mut self,
        ui: &mut egui::Ui,
        check: impl Fn(f64) -> Result<(), String>,
    ) -> Option<f64> {
        let mut accepted = None;
        ui.horizontal(|ui| {
            ui.label(self.label);
            let response = ui.add(egui::TextEdit::singleline(&mut self.text).desired_width(70.0));
            if response.lost_focus() {
                match self.text.trim().parse::<f64>() {
                    Ok(value) if value.is_finite() => match check(value) {
                        Ok(()) => {
                            self.error = None;
                            accepted = Some(value);
                        }
                        Err(message) => self.error = Some(message),
                    },
                    _ => self.error = Some(format!("`{}` is not a number", self.text.trim())),
                }
            }
        });
        if let Some(error) = &self.error {
            ui.colored_label(egui::Color32::from_rgb(255, 110, 110), error);
        }
        accepted
    }
}

fn in_range(low: f64, high: f64) -> impl Fn(f64) -> Result<(), String> {
    move |v| {
        if v >= low && v <= high {
            Ok(())
        } else {
            Err(format!("refused: must lie in [{low}, {high}]"))
        }
    }
}

/// A count: a whole number in [low, high] (2.7 is refused, not truncated to 2).
fn whole_in_range(low: f64, high: f64) -> impl Fn(f64) -> Result<(), String> {
    move |v| {
        if v.fract() == 0.0 && v >= low && v <= high {
            Ok(())
        } else {
            Err(format!(
                "refused: must be a whole number in [{low}, {high}]"
            ))
        }
    }
}

/// A knob of the simulation method, as edited in the panel.
#[derive(Clone, Copy, Debug)]
enum MethodKnob {
    Substeps(u32),
    /// Solver iterations (PBD, XPBD) or the CG iteration cap (implicit Euler).
    Iterations(u32),
    PbdStiffness(f64),
    CgTolerance(f64),
}

/// `method` with only `knob` changed: its other knobs (PBD stiffness, the CG cap and tolerance) keep
/// their values. A knob the method does not have leaves it unchanged.
fn with_knob(method: Method, knob: MethodKnob) -> Method {
    match (knob, method) {
        (MethodKnob::Substeps(n), _) => method.with_knobs(Some(n), None),
        (MethodKnob::Iterations(n), _) => method.with_knobs(None, Some(n)),
        (
            MethodKnob::PbdStiffness(stiffness),
            Method::Pbd {
                substeps,
                iterations,
                ..
            },
        ) => Method::Pbd {
            substeps,
            iterations,
            stiffness,
        },
        (
            MethodKnob::CgTolerance(cg_tolerance),
            Method::ImplicitEuler {
                substeps,
                cg_max_iterations,
                ..
            },
        ) => Method::ImplicitEuler {
            substeps,
            cg_max_iterations,
            cg_tolerance,
        },
        _ => method,
    }
}

/// Three radiances (W/(m²·sr)), typed as `r, g, b`: applied only when all three parse and lie in
/// [0, 1e6]; otherwise refused with a message.
struct RadianceField {
    label: &'static str,
    text: String,
    error: Option<String>,
}

impl RadianceField {
    fn new(label: &'static str, value: [f32; 3]) -> Self {
        RadianceField {
            label,
            text: format!("{}, {}, {}", value[0], value[1], value[2]),
            error: None,
        }
    }

    /// Shows the field; returns the new radiances when they were entered and accepted.
    fn show(&mut self, ui: &mut egui::Ui) -> Option<[f32; 3]> {
        let mut accepted = None;
        ui.horizontal(|ui| {
            ui.label(self.label);
            let response = ui.add(egui::TextEdit::singleline(&mut self.text).desired_width(110.0));
            if response.lost_focus() {
                let values: Vec<Option<f32>> = self
                    .text
                    .split(',')
                    .map(|v| v.trim().parse::<f32>().ok())
                    .collect();
                match values.as_slice() {
                    [Some(r), Some(g), Some(b)]
                        if [r, g, b].iter().all(|v| {
                            v.is_finite() && (0.0..=crate::scene::MAX_RADIANCE).contains(*v)
                        }) =>
                    {
                        self.error = None;
                        accepted = Some([*r, *g, *b]);
                    }
                    _ => {
                        self.error = Some(format!(
                            "refused: `{}` is not three radiances r, g, b in [0, 1e6]",
                            self.text.trim()
                        ))
                    }
                }
            }
        });
        if let Some(error) = &self.error {
            ui.colored_label(egui::Color32::from_rgb(255, 110, 110), error);
        }
        accepted
    }
}

/// What the chosen scattering model costs in accuracy at the panel's τ1 and Λ: the table's own
/// interpolation error (sheer-transport's README) for all orders, and single scattering's missing share
/// of the lit and the far face's diffuse radiance against the all-orders table at μ0 = μ = 0.7.
fn model_error_text(shading: &ShadingSection, sky_light: bool) -> String {
    let (tau, albedo) = (
        f64::from(shading.optical_thickness[0]),
        f64::from(shading.albedo_scale[0]),
    );
    let missing = || -> Option<(f64, f64)> {
        let table = crate::frame::builtin_all_orders_table().ok()?;
        let (t, a, c) = (
            sheer_slab::OpticalThickness::new(tau).ok()?,
            sheer_slab::Albedo::new(albedo).ok()?,
            sheer_slab::Cosine::new("mu", 0.7).ok()?,
        );
        let single_lit = sheer_slab::single_scattered_reflected_radiance(t, a, c, c);
        let single_far = sheer_slab::single_scattered_transmitted_radiance(t, a, c, c);
        let all_lit = table.reflected_radiance(tau, albedo, 0.7, 0.7).ok()?;
        let all_far = table.transmitted_radiance(tau, albedo, 0.7, 0.7).ok()?;
        (all_lit > 0.0 && all_far > 0.0)
            .then(|| (1.0 - single_lit / all_lit, 1.0 - single_far / all_far))
    };
    let single = match missing() {
        Some((lit, far)) => format!(
            "single scattering misses {:.0} % (lit side) and {:.0} % (far side) of the light here",
            100.0 * lit,
            100.0 * far
        ),
        None => "single scattering: τ1 outside the all-orders table, error not measured".into(),
    };
    match shading.scattering {
        // The table's interpolation error against the solver (sheer-transport's README).
        ScatteringOrders::All => format!(
            "all orders: within 0.5 % (lit side) and 3.2 % (far side) of the exact slab{}; {single}",
            // The diffuse table's interpolation error for μ ≥ 0.05 (sheer-transport's README).
            if sky_light {
                ", sky light within 1.4 % and 3.4 %"
            } else {
                ""
            }
        ),
        ScatteringOrders::Single => single,
    }
}

struct Fields {
    sky_radiance: RadianceField,
    ground_radiance: RadianceField,
    optical_thickness: NumberField,
    albedo_scale: NumberField,
    flux: NumberField,
    radius: NumberField,
    period: NumberField,
    wind_speed: NumberField,
    wind_direction: NumberField,
    gusts: NumberField,
    substeps: NumberField,
    iterations: NumberField,
    pbd_stiffness: NumberField,
    cg_tolerance: NumberField,
    columns: NumberField,
}

impl Fields {
    /// Shows the shading section's numbers in their fields (after an edit was undone).
    fn show_shading(&mut self, shading: &ShadingSection) {
        self.optical_thickness.text = format!("{}", shading.optical_thickness[0]);
        self.albedo_scale.text = format!("{}", shading.albedo_scale[0]);
    }

    /// Shows `method`'s knobs in their fields (after a change of method, or of one knob).
    fn show_method(&mut self, method: Method) {
        self.substeps.text = method.substeps().to_string();
        self.iterations.text = method.iterations().to_string();
        self.iterations.label = match method {
            Method::ImplicitEuler { .. } => "CG max iterations",
            _ => "iterations",
        };
        match method {
            Method::Pbd { stiffness, .. } => self.pbd_stiffness.text = stiffness.to_string(),
            Method::ImplicitEuler { cg_tolerance, .. } => {
                self.cg_tolerance.text = cg_tolerance.to_string()
            }
            _ => {}
        }
        for field in [
            &mut self.substeps,
            &mut self.iterations,
            &mut self.pbd_stiffness,
            &mut self.cg_tolerance,
        ] {
            field.error = None;
        }
    }
}

pub struct SheerApp {
    flag: FlagScene,
    renderer: WindowImage,
    fields: Fields,
    paused: bool,
    step_once: bool,
    notice: Option<String>,
    times: StageTimes,
    frame_history: VecDeque<f32>,
    last_frame: Instant,
    frames_run: u32,
    options: WindowOptions,
    screenshot_requested: bool,
    screenshot_done: Arc<Mutex<Option<Result<PathBuf, String>>>>,
    /// Scripted mode (`--frames`): every frame's time, for the line [`run`] prints at exit.
    frame_times: Arc<Mutex<FrameTimes>>,
    /// Scripted mode (`--frames`): the first error, which closes the window and fails [`run`].
    script_failure: Arc<Mutex<Option<String>>>,
    // Camera orbit about its target: azimuth and elevation (rad) and distance (m).
    orbit: (f32, f32, f32),
    /// The space left for the image beside the panel in the last frame, points.
    image_area: egui::Vec2,
}

fn orbit_of(scene: &Scene) -> (f32, f32, f32) {
    let eye = glam::Vec3::from_array(scene.camera.position);
    let target = glam::Vec3::from_array(scene.camera.target);
    let d = eye - target;
    let distance = d.length();
    (d.x.atan2(d.z), (d.y / distance).asin(), distance)
}

impl SheerApp {
    pub fn new(scene: Scene, options: WindowOptions) -> Result<SheerApp, CliError> {
        let renderer = WindowImage::new(FrameShading::new(&scene)?);
        let mut flag = FlagScene::new(scene.clone())?;
        crate::sequence::advance_to(&mut flag, f64::from(scene.render.warmup))?;
        let orbit = orbit_of(&scene);
        let wind = scene.simulation.wind;
        let speed = wind.velocity.length();
        let mut fields = Fields {
            sky_radiance: RadianceField::new("sky (W/m²sr)", scene.environment.sky_radiance),
            ground_radiance: RadianceField::new(
                "ground (W/m²sr)",
                scene.environment.ground_radiance,
            ),
            optical_thickness: NumberField::new(
                "τ₁",
                f64::from(scene.shading.optical_thickness[0]),
            ),
            albedo_scale: NumberField::new("Λ scale", f64::from(scene.shading.albedo_scale[0])),
            flux: NumberField::new("flux Φ (W)", f64::from(scene.light.flux)),
            radius: NumberField::new("orbit radius (m)", f64::from(scene.light.radius)),
            period: NumberField::new("orbit period (s)", f64::from(scene.light.period)),
            wind_speed: NumberField::new("wind speed (m/s)", speed),
            wind_direction: NumberField::new(
                "direction (°)",
                wind.velocity.z.atan2(wind.velocity.x).to_degrees(),
            ),
            gusts: NumberField::new("gusts", wind.gust_strength),
            substeps: NumberField::new("sub-steps", f64::from(scene.simulation.method.substeps())),
            iterations: NumberField::new(
                "iterations",
                f64::from(scene.simulation.method.iterations()),
            ),
            pbd_stiffness: NumberField::new("PBD stiffness", 1.0),
            cg_tolerance: NumberField::new("CG tolerance", 1e-4),
            columns: NumberField::new("grid columns", scene.flag.columns as f64),
        };
        fields.show_method(scene.simulation.method);
        Ok(SheerApp {
            flag,
            renderer,
            fields,
            paused: false,
            step_once: false,
            notice: None,
            times: StageTimes::default(),
            frame_history: VecDeque::with_capacity(240),
            last_frame: Instant::now(),
            frames_run: 0,
            options,
            screenshot_requested: false,
            screenshot_done: Arc::new(Mutex::new(None)),
            frame_times: Arc::new(Mutex::new(FrameTimes::default())),
            script_failure: Arc::new(Mutex::new(None)),
            orbit,
            image_area: egui::Vec2::ZERO,
        })
    }

    fn apply_orbit(&mut self) {
        let (azimuth, elevation, distance) = self.orbit;
        let target = glam::Vec3::from_array(self.flag.scene.camera.target);
        let offset = distance
            * glam::Vec3::new(
                azimuth.sin() * elevation.cos(),
                elevation.sin(),
                azimuth.cos() * elevation.cos(),
            );
        self.flag.scene.camera.position = (target + offset).to_array();
    }

    /// Rebuilds the flag for `scene` (a new grid); a scene that fails validation is refused and the
    /// running flag kept.
    fn rebuild(&mut self, scene: Scene) {
        match scene.validate().and_then(|()| FlagScene::new(scene)) {
            Ok(flag) => self.flag = flag,
            Err(e) => self.notice = Some(format!("rebuild refused: {e}")),
        }
    }

    /// Shows an error in the panel; in scripted mode it also ends the run with that error (a screenshot
    /// of a failed frame, or none at all, must not exit as a success).
    fn report_error(&mut self, ctx: &egui::Context, message: String) {
        if self.options.frames.is_some() {
            if let Ok(mut failure) = self.script_failure.lock()
                && failure.is_none()
            {
                *failure = Some(message.clone());
            }
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
        self.notice = Some(message);
    }

    fn advance_and_render(&mut self, ctx: &egui::Context) {
        let mut times = StageTimes::default();
        if !self.paused || self.step_once {
            self.step_once = false;
            if let Err(error) = self.flag.advance_frame(&mut times) {
                // Never show a diverged mesh: back to rest, and say so.
                self.report_error(ctx, format!("{error} — the flag was reset"));
                if let Err(e) = self.flag.reset() {
                    self.report_error(ctx, e.to_string());
                }
            }
        }
        if let Err(error) = self.renderer.render(&self.flag, &mut times) {
            self.report_error(ctx, error.to_string());
        }
        self.times = times;
        let now = Instant::now();
        let frame_ms = (now - self.last_frame).as_secs_f32() * 1e3;
        self.last_frame = now;
        if self.frame_history.len() == 240 {
            self.frame_history.pop_front();
        }
        self.frame_history.push_back(frame_ms);
        // The first interval runs from the app's creation, not from a frame.
        if self.options.frames.is_some()
            && self.frames_run > 0
            && let Ok(mut frame_times) = self.frame_times.lock()
        {
            frame_times.milliseconds.push(f64::from(frame_ms));
            frame_times.adapter = self.renderer.adapter().to_owned();
        }
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("sheer");
        ui.label("Thin cloth as a thin slab (Frisvad et al. 2005)");
        ui.separator();
        let mut shading_changed = false;
        let shading_before = self.flag.scene.shading.clone();
        egui::CollapsingHeader::new("Shading")
            .default_open(true)
            .show(ui, |ui| {
                let s = &mut self.flag.scene.shading;
                ui.horizontal(|ui| {
                    ui.selectable_value(&mut s.model, ShadingModel::ThinSlab, "thin slab");
                    ui.selectable_value(&mut s.model, ShadingModel::Baseline, "baseline");
                    ui.selectable_value(&mut s.model, ShadingModel::Split, "split");
                });
                ui.horizontal(|ui| {
                    ui.label("path");
                    ui.selectable_value(&mut s.path, EvaluationPath::PerFragment, "fragment");
                    ui.selectable_value(&mut s.path, EvaluationPath::PerVertex, "vertex");
                    ui.selectable_value(&mut s.path, EvaluationPath::Cpu, "CPU");
                });
                ui.horizontal(|ui| {
                    ui.label("scattering");
                    let before = s.scattering;
                    ui.selectable_value(&mut s.scattering, ScatteringOrders::Single, "single");
                    ui.selectable_value(&mut s.scattering, ScatteringOrders::All, "all orders");
                    shading_changed |= s.scattering != before;
                });
                if s.scattering == ScatteringOrders::All && s.path == EvaluationPath::PerFragment {
                    ui.horizontal(|ui| {
                        ui.label("table lookup");
                        let before = s.all_orders_lookup;
                        ui.selectable_value(
                            &mut s.all_orders_lookup,
                            AllOrdersSampling::PerVertex,
                            "per vertex",
                        )
                        .on_hover_text(
                            "once per vertex, interpolated: about the cost of single scattering",
                        );
                        ui.selectable_value(
                            &mut s.all_orders_lookup,
                            AllOrdersSampling::PerFragment,
                            "per fragment",
                        )
                        .on_hover_text("exact to the table in every pixel, slower");
                        shading_changed |= s.all_orders_lookup != before;
                    });
                }
                shading_changed |= ui
                    .checkbox(&mut s.shadows, "translucent shadows")
                    .on_hover_text(
                        "the light reaching each point through the cloth layers in front of it \
                         and past the pole",
                    )
                    .changed();
                if let Some(v) = self.fields.optical_thickness.show(ui, in_range(1e-3, 50.0)) {
                    s.optical_thickness = [v as f32; 3];
                    shading_changed = true;
                }
                ui.small(model_error_text(s, self.flag.scene.environment.sky_light));
                if let Some(v) = self.fields.albedo_scale.show(ui, in_range(0.0, 1.0)) {
                    s.albedo_scale = [v as f32; 3];
                    shading_changed = true;
                }
            });
        egui::CollapsingHeader::new("Light")
            .default_open(true)
            .show(ui, |ui| {
                let t = self.flag.time();
                let l = &mut self.flag.scene.light;
                if let Some(v) = self.fields.flux.show(ui, in_range(0.0, 1e4)) {
                    l.flux = v as f32;
                    shading_changed = true;
                }
                if let Some(v) = self.fields.radius.show(ui, in_range(0.05, 20.0)) {
                    l.radius = v as f32;
                }
                if let Some(v) = self.fields.period.show(ui, in_range(-600.0, 600.0)) {
                    // Keep the light where it is when the speed changes (angles in whole turns
                    // dropped, in double precision: the scene's clock may be far from 0).
                    let angle = |period: f64| {
                        if period == 0.0 {
                            0.0
                        } else {
                            std::f64::consts::TAU * (t / period).rem_euclid(1.0)
                        }
                    };
                    l.phase = (f64::from(l.phase) + angle(f64::from(l.period)) - angle(v))
                        .rem_euclid(std::f64::consts::TAU) as f32;
                    l.period = v as f32;
                }
            });
        let environment_before = self.flag.scene.environment.clone();
        egui::CollapsingHeader::new("Sky")
            .default_open(true)
            .show(ui, |ui| {
                let e = &mut self.flag.scene.environment;
                ui.checkbox(&mut e.sky_light, "sky light on both faces")
                    .on_hover_text("daylight from the sky above and the ground below (all orders)");
                if let Some(v) = self.fields.sky_radiance.show(ui) {
                    e.sky_radiance = v;
                }
                if let Some(v) = self.fields.ground_radiance.show(ui) {
                    e.ground_radiance = v;
                }
                if e.image.as_deref().is_some_and(|i| !i.is_empty()) {
                    ui.small("an environment image replaces these (environment.image)");
                }
            });
        if self.flag.scene.environment != environment_before
            && let Err(e) = self.renderer.update_shading(&self.flag.scene)
        {
            self.flag.scene.environment = environment_before;
            self.notice = Some(e.to_string());
        }
        ui.collapsing("Wind", |ui| {
            let mut params = self.flag.scene.simulation.clone();
            let mut changed = false;
            let speed = params.wind.velocity.length();
            let direction = params.wind.velocity.z.atan2(params.wind.velocity.x);
            let set = |speed: f64, direction: f64| {
                sheer_cloth::glam::DVec3::new(speed * direction.cos(), 0.0, speed * direction.sin())
            };
            if let Some(v) = self.fields.wind_speed.show(ui, in_range(0.0, 40.0)) {
                params.wind.velocity = set(v, direction);
                changed = true;
            }
            if let Some(v) = self.fields.wind_direction.show(ui, in_range(-360.0, 360.0)) {
                params.wind.velocity = set(speed, v.to_radians());
                changed = true;
            }
            if let Some(v) = self.fields.gusts.show(ui, in_range(0.0, 2.0)) {
                params.wind.gust_strength = v;
                changed = true;
            }
            if changed && let Err(e) = self.flag.set_simulation_params(params) {
                self.notice = Some(e.to_string());
            }
        });
        ui.collapsing("Simulation", |ui| {
            let mut params = self.flag.scene.simulation.clone();
            let current = params.method.name();
            let mut chosen = current;
            egui::ComboBox::from_label("method")
                .selected_text(current)
                .show_ui(ui, |ui| {
                    for name in Method::NAMES {
                        ui.selectable_value(&mut chosen, name, name);
                    }
                });
            let mut method = params.method;
            if chosen != current
                && let Some(setting) = Method::stable_flag_setting(chosen)
            {
                method = setting;
            }
            // Each field changes only its own knob of the method.
            if let Some(v) = self.fields.substeps.show(ui, whole_in_range(1.0, 2000.0)) {
                method = with_knob(method, MethodKnob::Substeps(v as u32));
            }
            if matches!(
                method,
                Method::Pbd { .. } | Method::Xpbd { .. } | Method::ImplicitEuler { .. }
            ) && let Some(v) = self.fields.iterations.show(ui, whole_in_range(1.0, 1000.0))
            {
                method = with_knob(method, MethodKnob::Iterations(v as u32));
            }
            if matches!(method, Method::Pbd { .. })
                && let Some(v) = self.fields.pbd_stiffness.show(ui, |v| {
                    if v > 0.0 && v <= 1.0 {
                        Ok(())
                    } else {
                        Err("refused: must lie in (0, 1]".to_string())
                    }
                })
            {
                method = with_knob(method, MethodKnob::PbdStiffness(v));
            }
            if matches!(method, Method::ImplicitEuler { .. })
                && let Some(v) = self.fields.cg_tolerance.show(ui, |v: f64| {
                    // CG starts at a relative residual of 1: 1 or more would stop it at once.
                    if (1e-12..1.0).contains(&v) {
                        Ok(())
                    } else {
                        Err("refused: must lie in [1e-12, 1)".to_string())
                    }
                })
            {
                method = with_knob(method, MethodKnob::CgTolerance(v));
            }
            if method != params.method {
                params.method = method;
                self.fields.show_method(method);
                // Force-based methods have no contacts: the switch goes off with them, said aloud.
                if !method.is_position_based() && params.collisions.self_collision {
                    params.collisions.self_collision = false;
                    self.notice = Some(format!(
                        "self-collision switched off: {} has no contacts",
                        method.name()
                    ));
                }
                if let Err(e) = self.flag.set_simulation_params(params) {
                    self.notice = Some(e.to_string());
                }
            }
            if self.flag.scene.simulation.method.is_position_based() {
                let mut params = self.flag.scene.simulation.clone();
                if ui
                    .checkbox(&mut params.collisions.self_collision, "self-collision")
                    .on_hover_text(
                        "no layer of the flag passes through another; costs many times the \
                         simulation (docs/perf/collisions.md)",
                    )
                    .changed()
                    && let Err(e) = self.flag.set_simulation_params(params)
                {
                    self.notice = Some(e.to_string());
                }
            }
            if let Some(v) = self.fields.columns.show(ui, whole_in_range(2.0, 512.0)) {
                let mut scene = self.flag.scene.clone();
                // Keep the flag's cells square (the Faroe flag's 8:11 at the default size).
                let flag = &mut scene.flag;
                flag.columns = v as usize;
                flag.rows = ((v - 1.0) * flag.height / flag.width).round().max(1.0) as usize + 1;
                self.rebuild(scene);
            }
            ui.horizontal(|ui| {
                if ui
                    .button(if self.paused { "run" } else { "pause" })
                    .clicked()
                {
                    self.paused = !self.paused;
                }
                if ui.button("step").clicked() {
                    self.paused = true;
                    self.step_once = true;
                }
                if ui.button("reset").clicked()
                    && let Err(e) = self.flag.reset()
                {
                    self.notice = Some(e.to_string());
                }
            });
        });
        if shading_changed
            && let Err(e) =
                apply_shading_or_restore(&mut self.flag.scene, shading_before, |scene| {
                    self.renderer.update_shading(scene)
                })
        {
            self.fields.show_shading(&self.flag.scene.shading);
            self.notice = Some(e.to_string());
        }
        ui.separator();
        if ui.button("screenshot").clicked() {
            let path = PathBuf::from(format!("sheer-{}.png", self.frames_run));
            self.request_screenshot(ui.ctx(), path);
        }
        if let Some(notice) = &self.notice {
            ui.colored_label(egui::Color32::from_rgb(255, 200, 90), notice);
        }
        ui.separator();
        self.readout(ui);
    }

    fn readout(&self, ui: &mut egui::Ui) {
        let mean = if self.frame_history.is_empty() {
            0.0
        } else {
            self.frame_history.iter().sum::<f32>() / self.frame_history.len() as f32
        };
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        ui.label(format!(
            "{:.1} frames/s ({mean:.1} ms)",
            1e3 / mean.max(1e-3)
        ));
        // Shading's CPU side (sort, per-path evaluation, staging the uploads, encoding); the GPU's work
        // runs beside the next frame's and shows in the frame time.
        ui.monospace(format!(
            "simulation   {:6.2} ms\nnormals      {:6.2} ms\nshading, CPU {:6.2} ms",
            ms(self.times.simulation),
            ms(self.times.normals),
            ms(self.times.shading),
        ));
        ui.small(format!("adapter: {}", self.renderer.adapter()));
        // Frame-time history, 0 to the largest recent frame time.
        let (rect, _) =
            ui.allocate_exact_size(egui::vec2(ui.available_width(), 60.0), egui::Sense::hover());
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 2.0, egui::Color32::from_gray(30));
        let top = self.frame_history.iter().cloned().fold(1.0f32, f32::max);
        let n = self.frame_history.len().max(2) as f32;
        let points: Vec<egui::Pos2> = self
            .frame_history
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                egui::pos2(
                    rect.left() + rect.width() * i as f32 / (n - 1.0),
                    rect.bottom() - rect.height() * v / top,
                )
            })
            .collect();
        painter.add(egui::Shape::line(
            points,
            egui::Stroke::new(1.5, egui::Color32::from_rgb(120, 200, 255)),
        ));
        painter.text(
            rect.left_top() + egui::vec2(4.0, 2.0),
            egui::Align2::LEFT_TOP,
            format!("frame time, max {top:.0} ms"),
            egui::FontId::proportional(11.0),
            egui::Color32::from_gray(200),
        );
    }

    fn request_screenshot(&mut self, ctx: &egui::Context, path: PathBuf) {
        let done = self.screenshot_done.clone();
        ctx.request_screenshot(move |image| {
            let [w, h] = image.size;
            let bytes: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
            let result = image::RgbaImage::from_raw(w as u32, h as u32, bytes)
                .ok_or_else(|| "screenshot has the wrong size".to_string())
                .and_then(|img| {
                    let rgb = image::DynamicImage::ImageRgba8(img).to_rgb8();
                    image::ImageFormat::from_path(&path)
                        .and_then(|format| sheer_slab::render::save_image_file(&rgb, &path, format))
                        .map_err(|e| format!("cannot write {}: {e}", path.display()))
                })
                .map(|()| path);
            if let Ok(mut slot) = done.lock() {
                *slot = Some(result);
            }
        });
        self.screenshot_requested = true;
    }
}

impl eframe::App for SheerApp {
    /// The window is cleared to the panel's colour, so that the panel needs no fill of its own: on a
    /// software rasteriser a panel-sized quad costs milliseconds a frame.
    fn clear_color(&self, visuals: &egui::Visuals) -> [f32; 4] {
        visuals.panel_fill.to_normalized_gamma_f32()
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        // A finished screenshot: report it, and in scripted mode leave.
        let finished = self.screenshot_done.lock().ok().and_then(|mut s| s.take());
        if let Some(result) = finished {
            self.screenshot_requested = false;
            match result {
                Ok(path) => self.notice = Some(format!("saved {}", path.display())),
                Err(e) => self.report_error(&ctx, e),
            }
            if self.options.frames.is_some() {
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
        }
        self.advance_and_render(&ctx);
        self.frames_run += 1;
        // No fill: the window's clear colour is the panel's (`clear_color`).
        let panel =
            egui::Frame::side_top_panel(&ctx.global_style()).fill(egui::Color32::TRANSPARENT);
        egui::Panel::left("controls")
            .resizable(false)
            .frame(panel)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.side_panel(ui));
            });
        // No fill behind the image: on a software rasteriser a panel-sized quad costs as much as the
        // image itself, and eframe has cleared the window already.
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| {
                let available = ui.available_size();
                self.image_area = available;
                if !image_fits(available) {
                    ui.colored_label(
                        egui::Color32::from_rgb(255, 110, 110),
                        too_small_message(available),
                    );
                } else if let Some(texture) = self.renderer.texture_id() {
                    // Pixel for pixel, smaller only where the window is: an enlarged image is only
                    // blurred, and costs a larger quad on a software rasteriser.
                    let (width, height) = self.renderer.size();
                    let size = egui::vec2(width as f32, height as f32) / ctx.pixels_per_point();
                    let scale = (available.x / size.x).min(available.y / size.y).min(1.0);
                    let shown = egui::Rect::from_center_size(ui.max_rect().center(), size * scale);
                    let response = ui.put(
                        shown,
                        egui::Image::new((texture, size))
                            .fit_to_exact_size(size * scale)
                            .sense(egui::Sense::drag()),
                    );
                    if response.dragged() {
                        let delta = response.drag_delta();
                        self.orbit.0 -= delta.x * 0.01;
                        self.orbit.1 = (self.orbit.1 + delta.y * 0.01).clamp(-1.4, 1.4);
                        self.apply_orbit();
                    }
                    if response.hovered() {
                        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
                        if scroll != 0.0 {
                            self.orbit.2 = (self.orbit.2 * (1.0 - scroll * 0.002)).clamp(0.3, 20.0);
                            self.apply_orbit();
                        }
                    }
                }
            });
        if let Some(limit) = self.options.frames
            && self.frames_run >= limit
            && !self.screenshot_requested
        {
            match self.options.screenshot.clone() {
                // A screenshot without the flag in it is no screenshot of the scene.
                Some(_) if self.frames_run == limit && !image_fits(self.image_area) => {
                    let message = format!("--screenshot: {}", too_small_message(self.image_area));
                    self.report_error(&ctx, message);
                }
                Some(path) if self.frames_run == limit => self.request_screenshot(&ctx, path),
                Some(_) => {}
                None => ctx.send_viewport_cmd(egui::ViewportCommand::Close),
            }
        }
        ctx.request_repaint();
    }
}

/// The frame times of a scripted run.
#[derive(Debug, Default)]
struct FrameTimes {
    milliseconds: Vec<f64>,
    adapter: String,
}

impl FrameTimes {
    /// `window: N frames, median M ms, p95 P ms, F frames/s, adapter A`, or nothing before two frames.
    fn line(&self) -> Option<String> {
        let mut sorted = self.milliseconds.clone();
        if sorted.is_empty() {
            return None;
        }
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        // Nearest rank: the smallest time that at least p of the frames do not exceed.
        let rank = |p: f64| sorted[((p * n as f64).ceil() as usize).clamp(1, n) - 1];
        let mean = sorted.iter().sum::<f64>() / n as f64;
        Some(format!(
            "window: {n} frames, median {:.1} ms, p95 {:.1} ms, {:.1} frames/s, adapter {}",
            rank(0.5),
            rank(0.95),
            1e3 / mean,
            self.adapter
        ))
    }
}

/// The smallest image area, in points each way, in which the window still shows the frame.
const MIN_IMAGE_SIDE: f32 = 128.0;

/// Whether an image area of `available` points shows the frame.
fn image_fits(available: egui::Vec2) -> bool {
    available.x >= MIN_IMAGE_SIDE && available.y >= MIN_IMAGE_SIDE
}

/// Says that the window is too small for the image, with the sizes.
fn too_small_message(available: egui::Vec2) -> String {
    format!(
        "the window leaves {:.0}×{:.0} points beside the panel, too small to show the image (it needs \
         {MIN_IMAGE_SIDE:.0}×{MIN_IMAGE_SIDE:.0}): make the window or the screen larger",
        available.x.max(0.0),
        available.y.max(0.0)
    )
}

/// Opens the window; returns when it closes. A scripted run (`--frames N`) then prints one line: frames,
/// median and 95th-percentile frame time, frames per second and the adapter.
pub fn run(options: WindowOptions) -> Result<(), CliError> {
    if let Some(path) = &options.screenshot {
        check_screenshot_path(path)?;
    }
    let scene = crate::load_scene(options.scene.as_deref())?;
    let samples = scene.render.samples;
    let mut app = SheerApp::new(scene, options)?;
    let failure = Arc::clone(&app.script_failure);
    let summary = Arc::clone(&app.frame_times);
    let mut wgpu_options = eframe::egui_wgpu::WgpuConfiguration::default().with_surface_config(
        eframe::egui_wgpu::SurfaceConfig {
            present_mode: wgpu::PresentMode::AutoNoVsync,
            desired_maximum_frame_latency: Some(1),
        },
    );
    if let eframe::egui_wgpu::WgpuSetup::CreateNew(setup) = &mut wgpu_options.wgpu_setup {
        // eframe's device, with the features the flag's renderer can use and the adapter's texture
        // size (the all-orders table is one texture).
        let base = Arc::clone(&setup.device_descriptor);
        setup.device_descriptor = Arc::new(move |adapter| {
            let mut descriptor = base(adapter);
            descriptor.required_features |= wanted_features(adapter);
            descriptor.required_limits.max_texture_dimension_2d =
                adapter.limits().max_texture_dimension_2d;
            descriptor
        });
    }
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size([1000.0, 620.0])
            .with_title("sheer — thin cloth"),
        renderer: eframe::Renderer::Wgpu,
        wgpu_options,
        // Dithering costs a hash per pixel on a software rasteriser and the image is already 8-bit sRGB.
        dithering: false,
        ..Default::default()
    };
    eframe::run_native(
        "sheer",
        native,
        Box::new(move |creation| {
            let render_state = creation
                .wgpu_render_state
                .as_ref()
                .ok_or_else(|| CliError::new("the window has no wgpu device"))?;
            app.renderer.attach(render_state, samples)?;
            Ok(Box::new(app))
        }),
    )
    .map_err(|e| CliError::new(format!("window: {}", window_error_reason(&e.to_string()))))?;
    if let Some(message) = failure.lock().ok().and_then(|mut f| f.take()) {
        return Err(CliError::new(message));
    }
    if let Some(line) = summary.lock().ok().and_then(|s| s.line()) {
        crate::outln!("{line}")?;
    }
    Ok(())
}

/// `--screenshot`: a `.png` in an existing directory, checked before the window opens (the window
/// writes it only after its frames have run).
fn check_screenshot_path(path: &std::path::Path) -> Result<(), CliError> {
    if !crate::render_cmd::has_png_extension(path) {
        return Err(CliError::new(format!(
            "--screenshot {}: the screenshot is a PNG, so the file name must end in .png",
            path.display()
        )));
    }
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(parent) = parent
        && !parent.is_dir()
    {
        return Err(CliError::new(format!(
            "--screenshot {}: the directory {} does not exist",
            path.display(),
            parent.display()
        )));
    }
    Ok(())
}

/// Applies the panel's shading edits through `apply` (the renderer's update). On failure the renderer
/// keeps its last good parameters, so the whole shading section goes back to `before`: the panel
/// must not show a τ1 (or anything else) that the image does not use.
fn apply_shading_or_restore(
    scene: &mut Scene,
    before: ShadingSection,
    apply: impl FnOnce(&Scene) -> Result<(), CliError>,
) -> Result<(), CliError> {
    let result = apply(scene);
    if result.is_err() {
        scene.shading = before;
    }
    result
}

#[cfg(test)]
mod panel_tests {
    use super::*;

    #[test]
    fn a_refused_shading_edit_restores_the_whole_shading_section() {
        // The τ1 field accepts [1e-3, 50] but the all-orders table covers [0.01, 10]: the renderer
        // refuses τ1 = 20, and the panel must go back to the τ1 the image still uses.
        let mut scene = Scene::builtin_default().unwrap();
        scene.shading.scattering = ScatteringOrders::Single;
        let before = scene.shading.clone();
        scene.shading.scattering = ScatteringOrders::All;
        scene.shading.optical_thickness = [20.0; 3];
        let outside_table = |scene: &Scene| {
            if scene.shading.scattering == ScatteringOrders::All
                && scene.shading.optical_thickness.iter().any(|&t| t > 10.0)
            {
                Err(CliError::new("τ1 outside the table".to_string()))
            } else {
                Ok(())
            }
        };
        let result = apply_shading_or_restore(&mut scene, before.clone(), outside_table);
        assert!(result.is_err());
        assert_eq!(scene.shading, before);

        // An accepted edit stays.
        scene.shading.optical_thickness = [5.0; 3];
        apply_shading_or_restore(&mut scene, before, outside_table).unwrap();
        assert_eq!(scene.shading.optical_thickness, [5.0; 3]);
    }

    #[test]
    fn counts_typed_into_the_panel_must_be_whole_numbers() {
        let check = whole_in_range(1.0, 2000.0);
        assert!(check(3.0).is_ok());
        for refused in [2.7, 0.0, 2001.0, -4.0] {
            let message = check(refused).unwrap_err();
            assert!(message.starts_with("refused:"), "{refused}: {message}");
        }
    }

    #[test]
    fn editing_one_method_knob_keeps_the_others() {
        let pbd = Method::Pbd {
            substeps: 4,
            iterations: 10,
            stiffness: 0.7,
        };
        assert_eq!(
            with_knob(pbd, MethodKnob::Substeps(8)),
            Method::Pbd {
                substeps: 8,
                iterations: 10,
                stiffness: 0.7
            }
        );
        assert_eq!(
            with_knob(pbd, MethodKnob::PbdStiffness(0.25)),
            Method::Pbd {
                substeps: 4,
                iterations: 10,
                stiffness: 0.25
            }
        );
        let implicit = Method::ImplicitEuler {
            substeps: 1,
            cg_max_iterations: 100,
            cg_tolerance: 1e-5,
        };
        // Twice the sub-steps, then back: the CG cap and tolerance are untouched by either edit.
        let edited = with_knob(
            with_knob(implicit, MethodKnob::Substeps(2)),
            MethodKnob::Substeps(1),
        );
        assert_eq!(edited, implicit);
        assert_eq!(
            with_knob(implicit, MethodKnob::Iterations(40)),
            Method::ImplicitEuler {
                substeps: 1,
                cg_max_iterations: 40,
                cg_tolerance: 1e-5
            }
        );
        assert_eq!(
            with_knob(implicit, MethodKnob::CgTolerance(1e-8)),
            Method::ImplicitEuler {
                substeps: 1,
                cg_max_iterations: 100,
                cg_tolerance: 1e-8
            }
        );
        // A knob the method does not have changes nothing.
        let xpbd = Method::Xpbd {
            substeps: 2,
            iterations: 20,
        };
        assert_eq!(with_knob(xpbd, MethodKnob::PbdStiffness(0.5)), xpbd);
        assert_eq!(with_knob(xpbd, MethodKnob::CgTolerance(1e-3)), xpbd);
    }
}

/// The reason in a window error, without the place in winit's source that winit's OS errors name
/// (`os error at /root/.cargo/registry/…/platform_impl/linux/mod.rs:765: neither WAYLAND_DISPLAY nor
/// WAYLAND_SOCKET nor DISPLAY is set`), and with the remedy when there is no display.
fn window_error_reason(message: &str) -> String {
    const MARK: &str = "os error at ";
    let mut reason = message.to_string();
    if let Some(start) = message.find(MARK) {
        let rest = &message[start + MARK.len()..];
        if let Some(end) = rest.find(".rs:") {
            let after = &rest[end + ".rs:".len()..];
            let digits = after.chars().take_while(char::is_ascii_digit).count();
            if let Some(tail) = after[digits..].strip_prefix(": ") {
                reason = format!("{}{tail}", &message[..start]);
            }
        }
    }
    if reason.contains("DISPLAY") {
        reason.push_str(" (no display: run it under `xvfb-run -a`)");
    }
    reason
}

#[cfg(test)]
mod window_error_tests {
    use super::window_error_reason;

    #[test]
    fn a_window_error_gives_the_reason_without_winits_source_path() {
        assert_eq!(
            window_error_reason(
                "winit EventLoopError: os error at /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/\
                 winit-0.30.13/src/platform_impl/linux/mod.rs:765: neither WAYLAND_DISPLAY nor \
                 WAYLAND_SOCKET nor DISPLAY is set."
            ),
            "winit EventLoopError: neither WAYLAND_DISPLAY nor WAYLAND_SOCKET nor DISPLAY is set. \
             (no display: run it under `xvfb-run -a`)"
        );
        assert_eq!(window_error_reason("wgpu: no adapter"), "wgpu: no adapter");
    }
}
