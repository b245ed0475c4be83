//! Translucent shadows of the point light. Frisvad et al. (2005) light every point of the slab with the
//! full beam Φ/(4πr²); here the beam reaching a point is attenuated by every cloth layer it crosses on its
//! way from the light, by that layer's direct transmission `t = e^{−τ1/μ0}` per channel (α of eq. 9 with
//! the light's cosine), and stopped by opaque geometry. With the all-orders model, the light a layer
//! scatters through itself also reaches the layer behind: its scattered flux `μ0·T_d·E⊥` is taken to
//! leave isotropically toward a parallel receiver, as radiance `μ0·E⊥·D` with `D = T_d/π` (T_d at the
//! layer's own cosine, μ0 the receiver's), and the receiver answers with its diffuse response `R_d` or
//! `T_d` (the sky's tables, [`crate::sky`]). Its irradiance `(t + T_d)·μ0·E⊥` never exceeds the unshadowed
//! `μ0·E⊥`, since `t + T_d ≤ 1` in the layer. That approximation neglects the inter-reflection between
//! layers and the anisotropy of the transmitted light; it is measured against a Monte Carlo of two
//! parallel slabs in `sheer-transport` (tests/two_slabs.rs, docs/perf/two-slab-shadow.md).
//!
//! Two realisations of the same rule:
//! * on the GPU (the per-fragment and per-vertex paths), a transmittance shadow map: [`SHADOW_LAYERS`]
//!   depth-peeling passes from the light, each keeping the nearest surface behind the previous layer, with
//!   `t` and `D` per vertex of the caster; the lookup, per vertex of the receiver and interpolated, has a
//!   slope-scaled bias and 2×2 percentage-closer filtering (`shaders/shadow.wgsl`);
//! * on the CPU, [`ShadowCasters::light_transmission`]: the segment from the light to the point cast
//!   against every triangle (through a grid over the light's view), exact to `f64` — the reference of the
//!   GPU path's tests and the CPU evaluation path's shadows.
//!
//! Why these choices, measured on lavapipe with `sheer bench render` (docs/perf/shadows.md): one view
//! from the light, not a cube map (one pass per layer instead of six); the frustum around the cloth's
//! bounding sphere only (the pole is drawn into it where it lies between the light and the cloth); two
//! layers, not four (a third layer's beam is below e^{−2τ1}, and each pass costs about 4 ms at 512²); the
//! lookup per vertex (per fragment it cost as much again as the passes). A light inside the cloth's sphere
//! gets a cone of at most [`MAX_HALF_ANGLE_DEGREES`] around the sphere's centre; points outside it receive
//! the full beam on both realisations.

use std::sync::Arc;

use glam::{DVec3, Mat4, Vec3};

use super::cpu::{COSINE_FLOOR, albedo_at, optical_thickness_at};
use super::scene::{ShadingError, ShadingParams, SlabMesh};
use super::slab_renderer::OpaqueMesh;
use crate::sky::{DiffuseTable, diffuse_response_per_albedo};

/// Surfaces recorded per shadow-map texel: a point behind more layers than this is attenuated by the
/// nearest ones only (the GPU; the CPU ray caster counts every layer).
pub const SHADOW_LAYERS: usize = 2;

/// The shadow map's default resolution (texels per side).
pub const DEFAULT_SHADOW_RESOLUTION: u32 = 512;

/// The widest half-angle of the light's view (degrees), used when the light is inside the casters'
/// bounding sphere.
pub const MAX_HALF_ANGLE_DEGREES: f32 = 75.0;

/// Translucent shadows of the point light (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Shadows {
    /// The shadow map's texels per side (16 to the device's largest texture).
    pub resolution: u32,
    /// The diffuse table for the light scattered through a layer in front (the all-orders model needs
    /// one: this, or the sky's when there is sky light, which must then be the same table).
    pub diffuse_table: Option<Arc<DiffuseTable>>,
}

impl Default for Shadows {
    fn default() -> Self {
        Self {
            resolution: DEFAULT_SHADOW_RESOLUTION,
            diffuse_table: None,
        }
    }
}

impl Shadows {
    /// Checks the resolution's lower bound (the device's limit is checked when rendering).
    pub fn validate(&self) -> Result<(), ShadingError> {
        if self.resolution < 16 {
            return Err(ShadingError::ShadowResolution(self.resolution));
        }
        Ok(())
    }
}

/// What reaches a point from the light through the layers in front of it, per channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightTransmission {
    /// The fraction of the direct beam, Π t over the layers in front.
    pub direct: [f64; 3],
    /// `D = T_d/π` of the nearest layer in front times the direct fraction reaching that layer (sr⁻¹):
    /// the receiver's lit face gets isotropic radiance `μ0·E⊥·diffuse`.
    pub diffuse: [f64; 3],
}

impl LightTransmission {
    /// Nothing in the way: the whole beam, no scattered light.
    pub const UNSHADOWED: Self = Self {
        direct: [1.0; 3],
        diffuse: [0.0; 3],
    };
}

/// The light's view of the shadow casters: a square perspective frustum around their bounding sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightView {
    /// World to clip space of the shadow map (wgpu's depth range 0 to 1).
    pub view_projection: Mat4,
    /// One texel's width per metre of distance from the light, at the frustum's centre (the widest).
    pub texel_per_metre: f32,
}

impl LightView {
    /// The frustum from `light` around the bounding sphere of `points` at `resolution` texels per side;
    /// `None` without points.
    pub fn covering(
        light: Vec3,
        points: impl IntoIterator<Item = [f32; 3]>,
        resolution: u32,
    ) -> Option<LightView> {
        let (mut low, mut high) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for p in points {
            low = low.min(Vec3::from(p));
            high = high.max(Vec3::from(p));
        }
        if !low.is_finite() {
            return None;
        }
        let centre = 0.5 * (low + high);
        // 1 % margin (and a floor for a single point) so the sphere's rim is not on the frustum's edge.
        let radius = (0.5 * (high - low).length()).max(1e-3) * 1.01;
        let axis = centre - light;
        let distance = axis.length();
        let max_half = MAX_HALF_ANGLE_DEGREES.to_radians();
        let half_angle = if distance > radius {
            (radius / distance).asin().min(max_half)
        } else {
            max_half
        };
        let forward = if distance > 0.0 {
            axis / distance
        } else {
            Vec3::NEG_Z
        };
        let up = if forward.y.abs() < 0.9 {
            Vec3::Y
        } else {
            Vec3::X
        };
        // Near the light: an opaque caster between the light and the cloth's sphere is not clipped (the
        // depth buffer only orders surfaces; distances are stored exactly in the layers).
        let near = 1e-3 * distance.max(radius);
        let far = distance + radius;
        // As the camera's (`Camera::view_projection`): f64, WebGPU clip space (depth in [0, 1]).
        let view = glam::dcamera::rh::view::look_at_mat4(
            light.as_dvec3(),
            (light + forward).as_dvec3(),
            up.as_dvec3(),
        );
        let projection = glam::dcamera::rh::proj::directx::perspective(
            2.0 * f64::from(half_angle),
            1.0,
            f64::from(near),
            f64::from(far),
        );
        Some(LightView {
            view_projection: (projection * view).as_mat4(),
            texel_per_metre: 2.0 * half_angle.tan() / resolution as f32,
        })
    }

    /// Whether `point` projects inside the map (the GPU lookup's test, in the same `f32` arithmetic).
    pub fn contains(&self, point: Vec3) -> bool {
        let clip = self.view_projection * point.extend(1.0);
        clip.w > 0.0 && clip.x.abs() <= clip.w && clip.y.abs() <= clip.w
    }

    /// Normalised device x, y of `point` (only meaningful in front of the light).
    fn ndc(&self, point: Vec3) -> Option<[f32; 2]> {
        let clip = self.view_projection * point.extend(1.0);
        (clip.w > 0.0).then(|| [clip.x / clip.w, clip.y / clip.w])
    }
}

/// The bias of the GPU lookup, per metre of distance from the light: a receiver is shadowed by the
/// layers nearer than `d·(1 − slope·tanθ0 − SHADOW_DISTANCE_BIAS)`. `slope` is this many texel widths:
/// with 2×2 filtering the stored distance comes from a texel centre up to √2 texels from the receiver, on
/// a surface whose distance from the light changes by tan θ0 per metre across the beam.
pub const SHADOW_SLOPE_TEXELS: f32 = 2.0;

/// The distance-proportional part of the GPU lookup's bias: f32 rounding of distances (≈ 1e-7) and the
/// curvature of the cloth between a texel centre and the receiver, with margin.
pub const SHADOW_DISTANCE_BIAS: f32 = 2e-4;

/// A triangle of a shadow caster, in `f64`, with what the light needs at each corner.
#[derive(Debug, Clone)]
struct CasterTriangle {
    corners: [DVec3; 3],
    /// Cloth: per-corner normals and uvs; opaque: none.
    cloth: Option<([DVec3; 3], [[f32; 2]; 3])>,
}

/// The scene's shadow casters on the CPU: the cloth and the opaque meshes, bucketed by where they fall
/// in the light's view.
#[derive(Debug, Clone)]
pub struct ShadowCasters {
    light: DVec3,
    view: Option<LightView>,
    triangles: Vec<CasterTriangle>,
    /// `GRID × GRID` cells over the light's view, each listing the triangles whose projection may cover it.
    cells: Vec<Vec<u32>>,
}

const GRID: usize = 64;

impl ShadowCasters {
    /// Collects the casters for a light at `light`, with the view the GPU would use at `resolution`
    /// (around the cloth: only points of the cloth receive shadows there).
    pub fn new(mesh: &SlabMesh, opaque: &[OpaqueMesh], light: Vec3, resolution: u32) -> Self {
        let view = LightView::covering(light, mesh.positions.iter().copied(), resolution);
        let at = |positions: &[[f32; 3]], i: u32| Vec3::from(positions[i as usize]).as_dvec3();
        let mut triangles = Vec::new();
        for corners in mesh.indices.chunks_exact(3) {
            triangles.push(CasterTriangle {
                corners: [0, 1, 2].map(|c| at(&mesh.positions, corners[c])),
                cloth: Some((
                    [0, 1, 2].map(|c| at(&mesh.normals, corners[c])),
                    [0, 1, 2].map(|c| mesh.uvs[corners[c] as usize]),
                )),
            });
        }
        for o in opaque {
            for corners in o.indices.chunks_exact(3) {
                triangles.push(CasterTriangle {
                    corners: [0, 1, 2].map(|c| at(&o.positions, corners[c])),
                    cloth: None,
                });
            }
        }
        let mut cells = vec![Vec::new(); GRID * GRID];
        if let Some(view) = &view {
            for (index, triangle) in triangles.iter().enumerate() {
                let projected: Option<Vec<[f32; 2]>> = triangle
                    .corners
                    .iter()
                    .map(|c| view.ndc(c.as_vec3()))
                    .collect();
                // A triangle reaching behind the light could project anywhere: every cell.
                let (low, high) = match projected {
                    Some(p) => (
                        [0, 1].map(|a| p.iter().map(|q| q[a]).fold(f32::INFINITY, f32::min)),
                        [0, 1].map(|a| p.iter().map(|q| q[a]).fold(f32::NEG_INFINITY, f32::max)),
                    ),
                    None => ([-1.0; 2], [1.0; 2]),
                };
                let [x0, y0] = low.map(cell_of);
                let [x1, y1] = high.map(cell_of);
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        cells[y * GRID + x].push(index as u32);
                    }
                }
            }
        }
        Self {
            light: light.as_dvec3(),
            view,
            triangles,
            cells,
        }
    }

    /// The light reaching `position` (m) through the casters: every triangle the segment from the light
    /// crosses before `position` (less a relative 1e-6 for the receiver's own surface), nearest first.
    /// Opaque triangles stop the beam; a cloth triangle passes `t = e^{−τ1/μ0}` of it and scatters
    /// `D = T_d(μ0)/π` through itself (all-orders model only, with `diffuse_table`), with τ1, Λ and the
    /// normal interpolated at the crossing as the GPU samples them.
    pub fn light_transmission(
        &self,
        position: DVec3,
        params: &ShadingParams,
        diffuse_table: Option<&DiffuseTable>,
    ) -> LightTransmission {
        let Some(view) = &self.view else {
            return LightTransmission::UNSHADOWED;
        };
        let Some([x, y]) = view.ndc(position.as_vec3()) else {
            return LightTransmission::UNSHADOWED;
        };
        if !view.contains(position.as_vec3()) {
            return LightTransmission::UNSHADOWED;
        }
        let segment = position - self.light;
        let length = segment.length();
        if length == 0.0 {
            return LightTransmission::UNSHADOWED;
        }
        let direction = segment / length;
        let limit = length * (1.0 - 1e-6);
        let mut hits: Vec<(f64, &CasterTriangle, [f64; 3])> = self.cells
            [cell_of(y) * GRID + cell_of(x)]
        .iter()
        .filter_map(|&i| {
            let triangle = &self.triangles[i as usize];
            ray_triangle(self.light, direction, &triangle.corners)
                .filter(|(t, _)| *t > 0.0 && *t < limit)
                .map(|(t, weights)| (t, triangle, weights))
        })
        .collect();
        hits.sort_by(|a, b| a.0.total_cmp(&b.0));
        // A segment through a shared edge or vertex crosses every triangle there at one point: one layer.
        hits.dedup_by(|later, earlier| later.0 - earlier.0 <= 1e-9 * length);
        let mut light = LightTransmission::UNSHADOWED;
        for (_, triangle, w) in hits {
            let Some((normals, uvs)) = &triangle.cloth else {
                // Opaque: nothing passes, nothing is scattered through.
                return LightTransmission {
                    direct: [0.0; 3],
                    diffuse: [0.0; 3],
                };
            };
            let normal =
                (normals[0] * w[0] + normals[1] * w[1] + normals[2] * w[2]).normalize_or_zero();
            let mu0 = normal.dot(direction).abs().clamp(COSINE_FLOOR, 1.0);
            let uv = [0, 1].map(|a| {
                (f64::from(uvs[0][a]) * w[0]
                    + f64::from(uvs[1][a]) * w[1]
                    + f64::from(uvs[2][a]) * w[2]) as f32
            });
            let tau = optical_thickness_at(params, uv);
            let scattered = match diffuse_table {
                Some(table) => {
                    let spec = table.spec();
                    let albedo = albedo_at(params, uv).map(|a| a.clamp(0.0, 1.0));
                    let tau = tau.map(|t| t.clamp(spec.tau_min, spec.tau_max));
                    // T_d = Λ·(T_d/Λ); a query outside the table (refused by validation) scatters nothing.
                    diffuse_response_per_albedo(table, tau, albedo, mu0)
                        .map(|(_, transmitted)| {
                            [0, 1, 2].map(|c| albedo[c] * transmitted[c] / std::f64::consts::PI)
                        })
                        .unwrap_or([0.0; 3])
                }
                None => [0.0; 3],
            };
            for c in 0..3 {
                light.diffuse[c] = light.direct[c] * scattered[c];
                light.direct[c] *= (-tau[c] / mu0).exp();
            }
        }
        light
    }
}

/// The grid cell of a normalised device coordinate in [−1, 1] (clamped).
fn cell_of(ndc: f32) -> usize {
    (((ndc + 1.0) * 0.5 * GRID as f32).floor().max(0.0) as usize).min(GRID - 1)
}

/// Möller & Trumbore (1997): the ray `origin + t·direction` against a triangle; `(t, barycentric
/// weights of the corners)` where it crosses the triangle's interior or edge.
fn ray_triangle(origin: DVec3, direction: DVec3, corners: &[DVec3; 3]) -> Option<(f64, [f64; 3])> {
    let edge1 = corners[1] - corners[0];
    let edge2 = corners[2] - corners[0];
    let p = direction.cross(edge2);
    let determinant = edge1.dot(p);
    // A degenerate triangle, or the ray in its plane: no crossing.
    if determinant.abs() < 1e-300 {
        return None;
    }
    let inverse = 1.0 / determinant;
    let s = origin - corners[0];
    let u = s.dot(p) * inverse;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(edge1);
    let v = direction.dot(q) * inverse;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some((edge2.dot(q) * inverse, [1.0 - u - v, u, v]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_through_a_triangle_gives_its_distance_and_weights() {
        let corners = [
            DVec3::new(-1.0, -1.0, 2.0),
            DVec3::new(1.0, -1.0, 2.0),
            DVec3::new(0.0, 1.0, 2.0),
        ];
        let (t, w) = ray_triangle(DVec3::ZERO, DVec3::Z, &corners).unwrap();
        assert!((t - 2.0).abs() < 1e-12);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(ray_triangle(DVec3::ZERO, DVec3::X, &corners).is_none());
        assert!(ray_triangle(DVec3::new(5.0, 0.0, 0.0), DVec3::Z, &corners).is_none());
    }

    #[test]
    fn the_light_view_covers_every_caster() {
        let light = Vec3::new(3.0, 1.0, 2.0);
        let points = [[0.0, 0.0, 0.0], [1.0, 0.5, 0.0], [0.5, -0.5, 0.3]];
        let view = LightView::covering(light, points, 512).unwrap();
        for p in points {
            assert!(view.contains(Vec3::from(p)));
        }
        // Behind the light, away from the casters.
        assert!(!view.contains(light * 2.0));
        assert!(LightView::covering(light, [], 512).is_none());
    }
}
