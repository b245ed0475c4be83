//! Sky light: daylight from a whole environment on both faces of the cloth, with the slab's all-orders
//! response to diffuse illumination (an extension of Frisvad, Christensen & Falster 2005, whose slab is
//! lit by one point light only).
//!
//! # Incident light
//! The environment is described by its irradiance `E(m)` (W/m²) on a plane of outward normal `m`, in
//! the nine-coefficient spherical-harmonic form of Ramamoorthi & Hanrahan (2001), "An efficient
//! representation for irradiance environment maps": `E(m)/π = Σ c_lm Y_lm(m)` with `c_lm = (A_l/π) L_lm`,
//! `A_0 = π`, `A_1 = 2π/3`, `A_2 = π/4`, and `L_lm` the environment radiance's coefficients. Each face
//! of the slab is lit as if by the uniform radiance `L_in(m) = E(m)/π` (W/(m²·sr)) over the hemisphere
//! it looks at: the same irradiance, with its angular detail averaged away. For a sky of radiance `L_s`
//! above the horizon and a ground of radiance `L_g` below it this is exact in `E`:
//! `E(m)/π = (L_s + L_g)/2 + (L_s − L_g)/2 · m_y` (the view factors of a tilted plane; bands 0 and 1
//! carry it whole, since a step in `y` has no band-2 part and `A_l = 0` for odd `l > 1`). For an
//! environment image, three bands keep `E` to within a few per cent (Ramamoorthi & Hanrahan's figure).
//!
//! # Response (all orders)
//! Under uniform incident radiance `L_in` on one face, the slab sends `L_in·R_d(τ1, Λ, μ)` back out of
//! that face at cosine μ and `L_in·T_d(τ1, Λ, μ)` out of the other, diffusely scattered light only
//! (`sheer_transport::DiffuseTable`, computed by its all-orders solver and checked against its Monte
//! Carlo). The unscattered light that crosses the slab along the view ray is the background behind it,
//! which eq. (9) already adds as `α·L_dst`. So the eye, on the face of outward normal `m` at `μ = |n·e|`,
//! receives
//!
//! `L_sky = L_in(m)·R_d(μ) + L_in(−m)·T_d(μ)` (W/(m²·sr)),
//!
//! added to the point light's eqs. (4)–(5) on every evaluation path. The renderer carries it per unit
//! albedo, `R_d/Λ` and `T_d/Λ`, as it does the point light's radiance.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::DVec3;
use thiserror::Error;

pub use sheer_transport::DiffuseTable;

use crate::model::SlabParameterError;
use crate::render::Texture2d;

/// Why a sky cannot be used.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SkyError {
    /// A radiance must be finite and ≥ 0.
    #[error("{name} must be finite and ≥ 0 W/(m²·sr) in every channel, got {value:?}")]
    Radiance {
        /// Which radiance (`sky` or `ground`).
        name: &'static str,
        /// The value given.
        value: [f32; 3],
    },
    /// An environment image texel (times its scale) is negative or not finite.
    #[error("environment image texel {texel} has radiance {value:?}: must be finite and ≥ 0")]
    Texel {
        /// Index of the texel (row-major).
        texel: usize,
        /// Its radiance.
        value: [f32; 3],
    },
    /// The environment image's scale must be finite and ≥ 0.
    #[error("environment image scale must be finite and ≥ 0, got {0:?}")]
    Scale(f32),
}

/// Real spherical harmonics of bands 0–2 at the unit vector `m` (x, y, z), in the order
/// Y00, Y1−1 (y), Y10 (z), Y11 (x), Y2−2 (xy), Y2−1 (yz), Y20, Y21 (xz), Y22 (Ramamoorthi & Hanrahan
/// 2001, eq. 3).
pub(crate) fn spherical_harmonics(m: DVec3) -> [f64; 9] {
    let (x, y, z) = (m.x, m.y, m.z);
    [
        0.282_094_791_773_878_14,
        0.488_602_511_902_919_9 * y,
        0.488_602_511_902_919_9 * z,
        0.488_602_511_902_919_9 * x,
        1.092_548_430_592_079_2 * x * y,
        1.092_548_430_592_079_2 * y * z,
        0.315_391_565_252_520_05 * (3.0 * z * z - 1.0),
        1.092_548_430_592_079_2 * x * z,
        0.546_274_215_296_039_6 * (x * x - y * y),
    ]
}

/// The band of each of the nine coefficients.
const BANDS: [usize; 9] = [0, 1, 1, 1, 2, 2, 2, 2, 2];
/// `A_l/π`: the clamped-cosine convolution per band (Ramamoorthi & Hanrahan 2001, eq. 8), divided by π.
const COSINE_LOBE_OVER_PI: [f64; 3] = [1.0, 2.0 / 3.0, 0.25];

/// Diffuse light from every direction: the irradiance of any plane, as nine spherical-harmonic
/// coefficients per channel of `E/π` (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct DiffuseEnvironment {
    coefficients: [[f64; 3]; 9],
}

impl DiffuseEnvironment {
    /// A uniform sky of radiance `sky` above the horizon (y > 0) and a uniform ground of radiance
    /// `ground` below it, W/(m²·sr) per channel.
    pub fn sky_and_ground(sky: [f32; 3], ground: [f32; 3]) -> Result<Self, SkyError> {
        for (name, value) in [("sky", sky), ("ground", ground)] {
            if value.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
                return Err(SkyError::Radiance { name, value });
            }
        }
        // L00 = 2π·Y00·(L_s + L_g); L1−1 = 0.4886·π·(L_s − L_g) (∫ y dω over y > 0 is π); the rest 0.
        let mut coefficients = [[0.0; 3]; 9];
        let y00 = spherical_harmonics(DVec3::Y)[0];
        for c in 0..3 {
            let (s, g) = (f64::from(sky[c]), f64::from(ground[c]));
            coefficients[0][c] = 2.0 * std::f64::consts::PI * y00 * (s + g);
            coefficients[1][c] =
                COSINE_LOBE_OVER_PI[1] * 0.488_602_511_902_919_9 * std::f64::consts::PI * (s - g);
        }
        Ok(DiffuseEnvironment { coefficients })
    }

    /// The environment of an equirectangular (latitude–longitude) image of linear radiance, times
    /// `scale` (W/(m²·sr) per unit texel): row 0 looks straight up (+y), the last row straight down;
    /// column u ∈ [0, 1) looks at azimuth φ = 2πu from −z towards +x, `(sin θ sin φ, cos θ, −sin θ cos φ)`.
    /// Each texel counts with its solid angle `(2π/W)(π/H) sin θ`.
    pub fn from_equirectangular(image: &Texture2d, scale: f32) -> Result<Self, SkyError> {
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(SkyError::Scale(scale));
        }
        let (width, height) = (image.width() as usize, image.height() as usize);
        let mut radiance_coefficients = [[0.0f64; 3]; 9];
        let pi = std::f64::consts::PI;
        for row in 0..height {
            let theta = pi * (row as f64 + 0.5) / height as f64;
            let solid_angle = (2.0 * pi / width as f64) * (pi / height as f64) * theta.sin();
            for column in 0..width {
                let index = row * width + column;
                let texel = image.texels()[index];
                let value = [0, 1, 2].map(|c| texel[c] * scale);
                if value.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
                    return Err(SkyError::Texel {
                        texel: index,
                        value,
                    });
                }
                let phi = 2.0 * pi * (column as f64 + 0.5) / width as f64;
                let direction = DVec3::new(
                    theta.sin() * phi.sin(),
                    theta.cos(),
                    -theta.sin() * phi.cos(),
                );
                for (k, y) in spherical_harmonics(direction).into_iter().enumerate() {
                    for c in 0..3 {
                        radiance_coefficients[k][c] += f64::from(value[c]) * y * solid_angle;
                    }
                }
            }
        }
        let mut coefficients = radiance_coefficients;
        for (k, coefficient) in coefficients.iter_mut().enumerate() {
            for value in coefficient.iter_mut() {
                *value *= COSINE_LOBE_OVER_PI[BANDS[k]];
            }
        }
        Ok(DiffuseEnvironment { coefficients })
    }

    /// The uniform radiance `L_in(m) = E(m)/π` (W/(m²·sr)) that lights a face of outward unit normal
    /// `m`, per channel. Three bands of an image can dip below zero where the image is dark beside a
    /// bright sun; no light is negative, so such a value is 0.
    pub(crate) fn radiance_on_face(&self, m: DVec3) -> [f64; 3] {
        let basis = spherical_harmonics(m);
        [0, 1, 2].map(|c| {
            let sum: f64 = (0..9).map(|k| self.coefficients[k][c] * basis[k]).sum();
            sum.max(0.0)
        })
    }

    /// The coefficients of `E/π` as the shader reads them: nine `vec4`s, rgb per coefficient.
    pub(crate) fn shader_coefficients(&self) -> [[f32; 4]; 9] {
        self.coefficients
            .map(|[r, g, b]| [r as f32, g as f32, b as f32, 0.0])
    }
}

/// Sky light on the cloth: the environment and the slab's diffuse response table.
#[derive(Debug, Clone, PartialEq)]
pub struct SkyLight {
    /// The light arriving from every direction.
    pub environment: DiffuseEnvironment,
    /// `R_d`, `T_d` over (τ1, Λ, μ), from `sheer-transport`'s all-orders solver.
    pub table: Arc<DiffuseTable>,
}

/// The smallest Λ at which `R_d/Λ`, `T_d/Λ` are evaluated: below it they equal their Λ → 0 limit to
/// about 1e-8 relative (the response is Λ times a smooth function of Λ).
const ALBEDO_FLOOR: f64 = 1e-8;

/// `(R_d/Λ, T_d/Λ)` per channel at cosine `mu` (sr⁰: dimensionless per unit albedo), the table's
/// interpolated all-orders response to uniform diffuse incidence. `tau` and `albedo` per channel must
/// lie in the table's range (validated by the renderer's `ShadingParams::validate`).
pub(crate) fn diffuse_response_per_albedo(
    table: &DiffuseTable,
    tau: [f64; 3],
    albedo: [f64; 3],
    mu: f64,
) -> Result<([f64; 3], [f64; 3]), SlabParameterError> {
    let mut reflected = [0.0; 3];
    let mut transmitted = [0.0; 3];
    for c in 0..3 {
        let a = albedo[c].clamp(ALBEDO_FLOOR, 1.0);
        let refused = |_| SlabParameterError::DiffuseTableQuery {
            tau1: tau[c],
            albedo: a,
            mu,
        };
        reflected[c] = table.reflectance(tau[c], a, mu).map_err(refused)? / a;
        transmitted[c] = table.transmittance(tau[c], a, mu).map_err(refused)? / a;
    }
    Ok((reflected, transmitted))
}

/// The sky's radiance toward the eye per unit albedo (W/(m²·sr)), per channel: `L_in(m)·R_d/Λ +
/// L_in(−m)·T_d/Λ`, with `m` the normal of the face the eye looks at and `mu` = |n·e| (floored and capped
/// by the caller as the point light's cosines are). A zero normal gives no sky light.
pub(crate) fn sky_radiance_per_albedo(
    sky: &SkyLight,
    normal: DVec3,
    to_eye: DVec3,
    tau: [f64; 3],
    albedo: [f64; 3],
    mu: f64,
) -> Result<[f64; 3], SlabParameterError> {
    let n = normal.normalize_or_zero();
    if n == DVec3::ZERO {
        return Ok([0.0; 3]);
    }
    let face = if n.dot(to_eye) >= 0.0 { n } else { -n };
    let (reflected, transmitted) = diffuse_response_per_albedo(&sky.table, tau, albedo, mu)?;
    let (near, far) = (
        sky.environment.radiance_on_face(face),
        sky.environment.radiance_on_face(-face),
    );
    Ok([0, 1, 2].map(|c| near[c] * reflected[c] + far[c] * transmitted[c]))
}

/// Why the diffuse table could not be loaded.
#[derive(Debug, Error)]
pub enum DiffuseTableLoadError {
    /// The file is missing or unreadable.
    #[error("cannot read the diffuse table {path}: {source}")]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// The file is not a diffuse table (bad magic, version, size, values or checksum).
    #[error("{path} is not a valid diffuse table: {reason}")]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
}

/// Reads and checks a diffuse table file (`assets/diffuse_table.bin` at the workspace root is shipped;
/// regenerate it with `cargo run -p sheer-transport --release --example make_diffuse_table`).
pub fn load_diffuse_table(
    path: impl AsRef<Path>,
) -> Result<Arc<DiffuseTable>, DiffuseTableLoadError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| DiffuseTableLoadError::Unreadable {
        path: path.to_path_buf(),
        source,
    })?;
    DiffuseTable::from_bytes(&bytes)
        .map(Arc::new)
        .map_err(|error| DiffuseTableLoadError::Corrupt {
            path: path.to_path_buf(),
            reason: error.to_string(),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sky_and_ground_light_a_tilted_face_by_its_view_factors() {
        let environment =
            DiffuseEnvironment::sky_and_ground([1.0, 0.5, 0.0], [0.2, 0.1, 0.0]).unwrap();
        for m in [
            DVec3::Y,
            -DVec3::Y,
            DVec3::X,
            DVec3::new(0.6, 0.8, 0.0),
            DVec3::new(0.0, -0.28, 0.96),
        ] {
            let got = environment.radiance_on_face(m);
            for (c, (s, g)) in [(1.0f32, 0.2f32), (0.5, 0.1), (0.0, 0.0)]
                .into_iter()
                .enumerate()
            {
                let (s, g) = (f64::from(s), f64::from(g));
                let expected = (s + g) / 2.0 + (s - g) / 2.0 * m.y;
                assert!(
                    (got[c] - expected).abs() < 1e-12,
                    "{m} {c}: {} vs {expected}",
                    got[c]
                );
            }
        }
        assert!(DiffuseEnvironment::sky_and_ground([f32::NAN, 0.0, 0.0], [0.0; 3]).is_err());
        assert!(DiffuseEnvironment::sky_and_ground([0.0; 3], [-1.0, 0.0, 0.0]).is_err());
    }

    /// An image of the same sky and ground gives the same light, to its discretisation: the midpoint
    /// rule in θ on H rows errs by O(1/H²) on the smooth parts and O(1/H) at the horizon's row, whose
    /// texels straddle it; with an odd H = 257 the middle row straddles the horizon, and 2/H bounds both.
    #[test]
    fn an_image_of_a_sky_and_a_ground_is_that_sky_and_ground() {
        let (width, height) = (64u32, 257u32);
        let texels: Vec<[f32; 4]> = (0..height)
            .flat_map(|row| {
                let value = if row < height / 2 {
                    [0.8, 0.9, 1.0, 1.0]
                } else {
                    [0.2, 0.3, 0.1, 1.0]
                };
                std::iter::repeat_n(value, width as usize)
            })
            .collect();
        let image = Texture2d::new(width, height, texels).unwrap();
        let from_image = DiffuseEnvironment::from_equirectangular(&image, 2.0).unwrap();
        let exact = DiffuseEnvironment::sky_and_ground([1.6, 1.8, 2.0], [0.4, 0.6, 0.2]).unwrap();
        for m in [
            DVec3::Y,
            DVec3::Z,
            DVec3::new(0.6, -0.8, 0.0),
            DVec3::new(-0.48, 0.6, 0.64),
        ] {
            let (a, b) = (from_image.radiance_on_face(m), exact.radiance_on_face(m));
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() < 2.0 / f64::from(height),
                    "{m} {c}: {} vs {}",
                    a[c],
                    b[c]
                );
            }
        }
        let bad = Texture2d::new(1, 1, vec![[-1.0, 0.0, 0.0, 1.0]]).unwrap();
        assert!(DiffuseEnvironment::from_equirectangular(&bad, 1.0).is_err());
        assert!(DiffuseEnvironment::from_equirectangular(&image, f32::INFINITY).is_err());
    }
}
