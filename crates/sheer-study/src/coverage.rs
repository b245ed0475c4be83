//! A phase-insensitive accuracy measure: the time-averaged coverage of the cloth seen by an
//! orthographic camera looking along −z.
//!
//! The waving flag is chaotic: after about half a second two runs that differ by rounding-sized
//! amounts flutter out of phase, and a pointwise position error then only says that they have
//! decorrelated (the reference itself moves by centimetres when its step is halved). What a viewer
//! sees of a waving flag over a few seconds is the region it sweeps and how often it is where. So each
//! run accumulates, per pixel of the [`Viewport`], the fraction of its frames inside a time window in
//! which the cloth covers the pixel's centre (the rasteriser of [`crate::silhouette`]), and two runs
//! are compared by the normalised L1 difference of these maps:
//!
//! `D = Σ_p |c_run(p) − c_ref(p)| / Σ_p c_ref(p)`,
//!
//! the pixel-time in which exactly one of the two covers a pixel, as a fraction of the reference's
//! mean covered area. `D` is 0 for identical runs, at most `1 + Σ c_run / Σ c_ref` otherwise, and for
//! a still sheet of width `w` moved sideways by `δ < w` it is `2δ/w` (see the tests).

use sheer_cloth::glam::DVec3;

use crate::StudyError;
use crate::silhouette::{Viewport, rasterise};

/// Which frames a time-averaged coverage averages over, and the camera window.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoverageWindow {
    /// First sampled simulated time, s (inclusive).
    pub start: f64,
    /// Last sampled simulated time, s (inclusive).
    pub end: f64,
    /// The window of the x–y plane the coverage is rasterised in.
    pub viewport: Viewport,
}

impl CoverageWindow {
    /// The published flag window: 0.5 s to 2.5 s (121 frames at 60 Hz; the flag has left its flat
    /// start and flutters; the window spans a full period of the 0.5 Hz gusts), 256 × 256 pixels of
    /// 7.8 mm over the 2 m × 2 m window around the flag.
    pub fn flag() -> CoverageWindow {
        CoverageWindow {
            start: 0.5,
            end: 2.5,
            viewport: Viewport::around_flag(256),
        }
    }

    /// Whether `time` (s) lies in the window, to within `tolerance` s.
    pub fn contains(&self, time: f64, tolerance: f64) -> bool {
        time >= self.start - tolerance && time <= self.end + tolerance
    }
}

/// Per-pixel fraction of the sampled frames in which the cloth covered the pixel's centre, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct MeanCoverage {
    /// The window it was rasterised in (`fractions` has its `resolution²` pixels).
    pub viewport: Viewport,
    /// `resolution²` fractions in [0, 1].
    pub fractions: Vec<f64>,
    /// How many frames were averaged.
    pub frames: u32,
}

impl MeanCoverage {
    /// Mean covered area, m²: the sum of the fractions times the pixel area.
    pub fn mean_area(&self) -> f64 {
        let pixel = self.viewport.size / self.viewport.resolution as f64;
        self.fractions.iter().sum::<f64>() * pixel * pixel
    }
}

/// Accumulates coverage frame by frame.
#[derive(Clone, Debug)]
pub struct CoverageAccumulator {
    viewport: Viewport,
    counts: Vec<u32>,
    /// The frame (1-based) in which each pixel was last counted, so a pixel under a fold counts once.
    last_frame: Vec<u32>,
    frames: u32,
}

impl CoverageAccumulator {
    /// An empty accumulator over a valid viewport ([`Viewport::validate`]).
    pub fn new(viewport: Viewport) -> Result<CoverageAccumulator, StudyError> {
        viewport.validate()?;
        let pixels = viewport.resolution * viewport.resolution;
        Ok(CoverageAccumulator {
            viewport,
            counts: vec![0; pixels],
            last_frame: vec![0; pixels],
            frames: 0,
        })
    }

    /// Adds one frame: the cloth at `positions` with `triangles` (which must name existing positions;
    /// a frame refused is not counted).
    pub fn add(&mut self, positions: &[DVec3], triangles: &[[u32; 3]]) -> Result<(), StudyError> {
        let frame = self.frames + 1;
        let (counts, last_frame) = (&mut self.counts, &mut self.last_frame);
        rasterise(positions, triangles, &self.viewport, |pixel| {
            if last_frame[pixel] != frame {
                last_frame[pixel] = frame;
                counts[pixel] += 1;
            }
        })?;
        self.frames = frame;
        Ok(())
    }

    /// Frames added so far.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// The average over the frames added; `None` if none was.
    pub fn finish(&self) -> Option<MeanCoverage> {
        if self.frames == 0 {
            return None;
        }
        let frames = self.frames as f64;
        Some(MeanCoverage {
            viewport: self.viewport,
            fractions: self.counts.iter().map(|&c| c as f64 / frames).collect(),
            frames: self.frames,
        })
    }
}

/// `Σ |run − reference| / Σ reference` over the pixels (dimensionless, see the module doc). `None`
/// when the maps were taken through different viewports or the reference covers nothing.
pub fn coverage_difference(run: &MeanCoverage, reference: &MeanCoverage) -> Option<f64> {
    if run.viewport != reference.viewport || run.fractions.len() != reference.fractions.len() {
        return None;
    }
    let covered: f64 = reference.fractions.iter().sum();
    if covered <= 0.0 {
        return None;
    }
    let difference: f64 = run
        .fractions
        .iter()
        .zip(&reference.fractions)
        .map(|(a, b)| (a - b).abs())
        .sum();
    Some(difference / covered)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat `width × height` sheet in the x–y plane with its lower-left corner at (x, y), two triangles.
    fn sheet(x: f64, y: f64, width: f64, height: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        (
            vec![
                DVec3::new(x, y, 0.0),
                DVec3::new(x + width, y, 0.0),
                DVec3::new(x + width, y + height, 0.0),
                DVec3::new(x, y + height, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    /// 1 cm pixels from (−1, −1), 400 × 400: pixel centres at −0.995, −0.985, …, so sheet edges on
    /// whole centimetres never fall on a centre and coverage counts are exact.
    fn viewport() -> Viewport {
        Viewport {
            min_x: -1.0,
            min_y: -1.0,
            size: 4.0,
            resolution: 400,
        }
    }

    #[test]
    fn a_folded_sheet_counts_each_pixel_once_per_frame() {
        let (mut p, mut t) = sheet(0.0, 0.0, 0.5, 0.5);
        // The same square again on top (a fold lying flat): still covered in one frame, fraction 1.
        let (q, _) = sheet(0.0, 0.0, 0.5, 0.5);
        p.extend(q);
        t.extend([[4, 5, 6], [4, 6, 7]]);
        let mut accumulator = CoverageAccumulator::new(viewport()).unwrap();
        accumulator.add(&p, &t).unwrap();
        let mean = accumulator.finish().unwrap();
        assert!(mean.fractions.iter().all(|&f| f == 0.0 || f == 1.0));
        assert!(
            (mean.mean_area() - 0.25).abs() < 1e-12,
            "{}",
            mean.mean_area()
        );
    }

    #[test]
    fn two_positions_half_the_time_each() {
        // Frame 1: a 1 m × 0.5 m sheet at x ∈ [0, 1]; frame 2: moved by 0.25 m to x ∈ [0.25, 1.25].
        // Pixels in [0.25, 1] are covered in both frames (fraction 1), those in [0, 0.25] and
        // [1, 1.25] in one (fraction ½): mean area = 0.5·(0.75 + ½·0.5) = 0.5 m², as every frame covers.
        let (a, t) = sheet(0.0, 0.0, 1.0, 0.5);
        let (b, _) = sheet(0.25, 0.0, 1.0, 0.5);
        let mut accumulator = CoverageAccumulator::new(viewport()).unwrap();
        accumulator.add(&a, &t).unwrap();
        accumulator.add(&b, &t).unwrap();
        let mean = accumulator.finish().unwrap();
        assert_eq!(mean.frames, 2);
        assert!(
            (mean.mean_area() - 0.5).abs() < 1e-12,
            "{}",
            mean.mean_area()
        );
        let half = mean.fractions.iter().filter(|&&f| f == 0.5).count();
        // 2 × 0.25 m × 0.5 m = 0.25 m² at fraction ½: 2500 pixels of 1 cm².
        assert_eq!(half, 2500);
    }

    #[test]
    fn difference_of_shifted_still_sheets_is_twice_the_shift_over_the_width() {
        let (a, t) = sheet(0.0, 0.0, 1.0, 0.5);
        let mean = |p: &[DVec3]| {
            let mut accumulator = CoverageAccumulator::new(viewport()).unwrap();
            for _ in 0..3 {
                accumulator.add(p, &t).unwrap();
            }
            accumulator.finish().unwrap()
        };
        let reference = mean(&a);
        assert_eq!(coverage_difference(&reference, &reference), Some(0.0));
        // Shifted by δ = 0.1 m: the XOR area is 2 · 0.1 · 0.5 = 0.1 m² over 0.5 m², D = 2δ/w = 0.2.
        let (b, _) = sheet(0.1, 0.0, 1.0, 0.5);
        let d = coverage_difference(&mean(&b), &reference).unwrap();
        assert!((d - 0.2).abs() < 1e-12, "{d}");
        // Disjoint: every covered pixel-time differs, D = (0.5 + 0.5)/0.5 = 2.
        let (c, _) = sheet(-0.9, 1.5, 1.0, 0.5);
        let d = coverage_difference(&mean(&c), &reference).unwrap();
        assert!((d - 2.0).abs() < 1e-12, "{d}");
        // Nothing to normalise by, or another camera: no value rather than NaN.
        let empty = CoverageAccumulator::new(viewport()).unwrap();
        assert!(empty.finish().is_none());
        let mut other = viewport();
        other.resolution = 200;
        let mut elsewhere = CoverageAccumulator::new(other).unwrap();
        elsewhere.add(&a, &t).unwrap();
        assert_eq!(
            coverage_difference(&elsewhere.finish().unwrap(), &reference),
            None
        );
    }
}
