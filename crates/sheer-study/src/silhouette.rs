//! The screen-space silhouette of the cloth: an orthographic camera looking along −z rasterises the
//! triangles onto a coverage grid (a pixel is covered when its centre lies in a triangle), and two
//! silhouettes differ by `1 − IoU` (the XOR area over the union area).
//!
//! This is the coverage silhouette seen by an orthographic camera, not the output of the GPU renderer
//! (which another crate provides); it measures how much of the picture's outline a model change moves.

use sheer_cloth::ModelError;
use sheer_cloth::glam::DVec3;

use crate::StudyError;

/// The most pixels a side: 16 384² coverage entries (256 Mi) is far beyond any study's need.
pub const MAX_RESOLUTION: usize = 16_384;

/// A square window of the x–y plane, m, rasterised at `resolution × resolution` pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewport {
    /// Left edge of the window, m.
    pub min_x: f64,
    /// Bottom edge of the window, m.
    pub min_y: f64,
    /// Side of the square window, m.
    pub size: f64,
    /// Pixels along each side (at most [`MAX_RESOLUTION`]).
    pub resolution: usize,
}

impl Viewport {
    /// A window around the default flag and everywhere it can wave (1.1 m × 0.8 m cloth whose top-left
    /// corner is at (0, 0.8)): x from −0.4 to 1.6 m, y from −0.7 to 1.3 m.
    pub fn around_flag(resolution: usize) -> Viewport {
        Viewport {
            min_x: -0.4,
            min_y: -0.7,
            size: 2.0,
            resolution,
        }
    }

    /// Checks that the window is a finite square of positive size, at 1 to [`MAX_RESOLUTION`] pixels a
    /// side.
    pub fn validate(&self) -> Result<(), StudyError> {
        let invalid = |name, value, reason| StudyError::InvalidInput {
            name,
            value,
            reason,
        };
        for (name, value) in [
            ("viewport.min_x", self.min_x),
            ("viewport.min_y", self.min_y),
        ] {
            if !value.is_finite() {
                return Err(invalid(name, value, "must be finite (m)"));
            }
        }
        if !(self.size.is_finite() && self.size > 0.0) {
            return Err(invalid(
                "viewport.size",
                self.size,
                "must be finite and > 0 (m)",
            ));
        }
        if !(1..=MAX_RESOLUTION).contains(&self.resolution) {
            return Err(invalid(
                "viewport.resolution",
                self.resolution as f64,
                "must be 1 to 16384 pixels a side",
            ));
        }
        Ok(())
    }
}

/// Calls `visit(pixel)` for every pixel (row-major index) whose centre lies in a triangle of the
/// cloth; a pixel covered by several triangles (a fold, a shared edge) is visited once per triangle.
/// The viewport must be valid ([`Viewport::validate`]) and every triangle must name existing positions.
pub fn rasterise(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    viewport: &Viewport,
    mut visit: impl FnMut(usize),
) -> Result<(), StudyError> {
    viewport.validate()?;
    let vertex_count = positions.len();
    for (triangle, corners) in triangles.iter().enumerate() {
        if let Some(&index) = corners.iter().find(|&&i| i as usize >= vertex_count) {
            return Err(ModelError::IndexOutOfRange {
                triangle,
                index,
                vertex_count,
            }
            .into());
        }
    }
    let n = viewport.resolution;
    let pixel = viewport.size / n as f64;
    for tri in triangles {
        let [a, b, c] = tri.map(|i| positions[i as usize]);
        let edge =
            |p: DVec3, q: DVec3, x: f64, y: f64| (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
        let area = edge(a, b, c.x, c.y);
        if area == 0.0 || !area.is_finite() {
            continue; // seen edge-on (covers no pixel centre), or not a triangle at all
        }
        let to_pixel = |v: f64, min: f64| ((v - min) / pixel - 0.5).floor();
        // Triangles wholly outside the window cover nothing (and must not be clamped onto its edge).
        let (x_lo, x_hi) = (
            to_pixel(a.x.min(b.x).min(c.x), viewport.min_x),
            to_pixel(a.x.max(b.x).max(c.x), viewport.min_x) + 1.0,
        );
        let (y_lo, y_hi) = (
            to_pixel(a.y.min(b.y).min(c.y), viewport.min_y),
            to_pixel(a.y.max(b.y).max(c.y), viewport.min_y) + 1.0,
        );
        if x_hi < 0.0 || y_hi < 0.0 || x_lo > n as f64 - 1.0 || y_lo > n as f64 - 1.0 {
            continue;
        }
        let clamp = |v: f64| v.clamp(0.0, n as f64 - 1.0) as usize;
        let (x0, x1, y0, y1) = (clamp(x_lo), clamp(x_hi), clamp(y_lo), clamp(y_hi));
        for py in y0..=y1 {
            let y = viewport.min_y + (py as f64 + 0.5) * pixel;
            for px in x0..=x1 {
                let x = viewport.min_x + (px as f64 + 0.5) * pixel;
                // Inside when all three edge functions have the sign of the triangle's area (either
                // winding: a folded flag shows its back).
                let (e0, e1, e2) = (edge(a, b, x, y), edge(b, c, x, y), edge(c, a, x, y));
                let inside = if area > 0.0 {
                    e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0
                } else {
                    e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0
                };
                if inside {
                    visit(py * n + px);
                }
            }
        }
    }
    Ok(())
}

/// Coverage mask, row-major, `resolution²` entries (inputs as for [`rasterise`]).
pub fn coverage(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    viewport: &Viewport,
) -> Result<Vec<bool>, StudyError> {
    viewport.validate()?;
    let n = viewport.resolution;
    let mut mask = vec![false; n * n];
    rasterise(positions, triangles, viewport, |pixel| mask[pixel] = true)?;
    Ok(mask)
}

/// `1 − IoU` of two coverage masks: 0 for identical silhouettes, 1 for disjoint ones, 0 when both
/// are empty.
pub fn silhouette_difference(a: &[bool], b: &[bool]) -> f64 {
    let (mut union, mut intersection) = (0usize, 0usize);
    for (&x, &y) in a.iter().zip(b) {
        union += (x || y) as usize;
        intersection += (x && y) as usize;
    }
    if union == 0 {
        0.0
    } else {
        1.0 - intersection as f64 / union as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(offset_x: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let p = vec![
            DVec3::new(offset_x, 0.0, 0.0),
            DVec3::new(offset_x + 1.0, 0.0, 0.0),
            DVec3::new(offset_x + 1.0, 1.0, 0.0),
            DVec3::new(offset_x, 1.0, 0.0),
        ];
        (p, vec![[0, 1, 2], [0, 2, 3]])
    }

    #[test]
    fn shifted_square_differs_by_the_expected_fraction() {
        let viewport = Viewport {
            min_x: -1.0,
            min_y: -1.0,
            size: 4.0,
            resolution: 200,
        };
        let (p, t) = square(0.0);
        let (q, _) = square(0.5);
        let a = coverage(&p, &t, &viewport).unwrap();
        assert_eq!(silhouette_difference(&a, &a), 0.0);
        // Unit square covers 1 m² = 2500 pixels of 2 cm; shifted by half: intersection 0.5, union 1.5,
        // 1 − IoU = 2/3. Pixel-centre sampling on a grid aligned with the square's edges is exact up
        // to edges that fall on pixel centres: one column of 50 pixels, 2 % of the union.
        let expected = 2.0 / 3.0;
        let measured = silhouette_difference(&a, &coverage(&q, &t, &viewport).unwrap());
        assert!((measured - expected).abs() < 0.02, "{measured}");
        let covered = a.iter().filter(|&&c| c).count();
        assert!((covered as f64 - 2500.0).abs() <= 100.0, "{covered}");
    }

    /// A viewport of no size or of more pixels than memory holds, and a triangle naming a vertex that
    /// is not there, are typed errors (they gave an empty coverage, overflowed `n²`, or panicked).
    #[test]
    fn bad_viewports_and_triangles_are_typed_errors() {
        let (p, t) = square(0.0);
        let good = Viewport {
            min_x: -1.0,
            min_y: -1.0,
            size: 3.0,
            resolution: 8,
        };
        assert!(coverage(&p, &t, &good).is_ok());
        let refused = |viewport: Viewport| match coverage(&p, &t, &viewport) {
            Err(StudyError::InvalidInput { name, .. }) => name,
            other => panic!("expected an invalid input, got {other:?}"),
        };
        for size in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(refused(Viewport { size, ..good }), "viewport.size");
        }
        for resolution in [0, MAX_RESOLUTION + 1, 1 << 32] {
            assert_eq!(
                refused(Viewport { resolution, ..good }),
                "viewport.resolution"
            );
        }
        assert_eq!(
            refused(Viewport {
                min_x: f64::NAN,
                ..good
            }),
            "viewport.min_x"
        );
        let mut bad_triangles = t.clone();
        bad_triangles[1][2] = 4;
        assert!(matches!(
            coverage(&p, &bad_triangles, &good),
            Err(StudyError::Model(ModelError::IndexOutOfRange {
                triangle: 1,
                index: 4,
                vertex_count: 4
            }))
        ));
    }
}
