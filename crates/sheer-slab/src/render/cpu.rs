//! CPU-side work of the renderer: the per-vertex "on the CPU" evaluation path (rayon, `f64` model of
//! [`crate::model`], and for the all-orders model the `f64` table sampler of [`crate::all_orders`];
//! the lit-side rule is `sheer-normals`' in `f64`, the shaders' is its WGSL twin), back-to-front
//! triangle sorting, and half-float texture quantisation shared by upload and CPU sampling.

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use sheer_normals::{LitSide, lit_side_cosines};

use super::scene::{ShadingParams, SlabMesh, Texture2d};
use super::shadow::{LightTransmission, ShadowCasters};
use super::slab_renderer::OpaqueMesh;
use crate::all_orders::{Scattering, multiple_scattered_radiance_per_albedo_rgb, table_tau_range};
use crate::model::{
    Albedo, Cosine, Face, OpticalThickness, SlabParameterError, direct_transmission,
    single_scattered_reflected_radiance, single_scattered_transmitted_radiance,
};
use crate::sky::{diffuse_response_per_albedo, sky_radiance_per_albedo};

/// Cosines below this are evaluated at this value, as in `shaders/thin_slab.wgsl` (grazing guard).
pub const COSINE_FLOOR: f64 = 1e-6;

/// Per-vertex output of the CPU path, uploaded as vertex attributes.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct VertexSlab {
    /// L±/Λ (W/(m²·sr)) per channel: single scattering for Λ = 1, plus for the all-orders model the
    /// multiple part per unit albedo evaluated with the vertex's Λ (the fragment multiplies by its Λ).
    pub radiance_per_albedo: [f32; 3],
    /// α = e^{−τ1/μ} per channel.
    pub transmittance: [f32; 3],
}

/// The model at one surface point: L/Λ (W/(m²·sr)) and α per channel, with the same geometric guards as
/// the shader (μ0 ≤ 0: no light; cosines floored at [`COSINE_FLOOR`] and capped at 1 against rounding).
/// `tau` per channel must be > 0 and finite (validated by [`ShadingParams::validate`]). `albedo` (Λ per
/// channel) is used only by the all-orders model, whose multiple part is not linear in Λ; single
/// scattering is returned for Λ = 1, as the GPU paths interpolate it.
#[cfg(any(test, feature = "test-support"))]
pub fn slab_values_at(
    position: DVec3,
    normal: DVec3,
    tau: [f64; 3],
    albedo: [f64; 3],
    eye: DVec3,
    params: &ShadingParams,
) -> Result<([f64; 3], [f64; 3]), SlabParameterError> {
    slab_values_lit_by(
        position,
        normal,
        tau,
        albedo,
        eye,
        params,
        &LightTransmission::UNSHADOWED,
    )
}

/// [`slab_values_at`] with the point light's beam reaching the point through `light` (the layers in
/// front of it, `shadow.rs`): the beam's part times `light.direct`, plus with the all-orders model
/// the slab's diffuse response to the isotropic radiance `μ0·E⊥·light.diffuse` on its lit face.
pub fn slab_values_lit_by(
    position: DVec3,
    normal: DVec3,
    tau: [f64; 3],
    albedo: [f64; 3],
    eye: DVec3,
    params: &ShadingParams,
    light: &LightTransmission,
) -> Result<([f64; 3], [f64; 3]), SlabParameterError> {
    let to_light = params.light_position.as_dvec3() - position;
    let LitSide { mu0, mu, face } = lit_side_cosines(normal, to_light, eye - position)?;
    let unit = Albedo::new(1.0)?;
    let cos_mu = Cosine::new("mu", mu.clamp(COSINE_FLOOR, 1.0))?;
    let cos_mu0 = Cosine::new("mu0", mu0.clamp(COSINE_FLOOR, 1.0))?;
    let optical_thickness = [
        OpticalThickness::new(tau[0])?,
        OpticalThickness::new(tau[1])?,
        OpticalThickness::new(tau[2])?,
    ];
    let multiple_per_albedo = match &params.scattering {
        Scattering::AllOrders(table) if mu0 > 0.0 => {
            // Validation admits τ1 up to TABLE_RANGE_SLACK outside the table (its ends in f32) and Λ
            // up to half-float rounding above 1 (texel × scale ≤ 1 before quantisation): these guards
            // only absorb that rounding, as the shader's do.
            let (min, max) = table_tau_range(table);
            let clamp_tau = |c: usize| OpticalThickness::new(tau[c].clamp(min, max));
            let clamp_albedo = |c: usize| Albedo::new(albedo[c].clamp(0.0, 1.0));
            multiple_scattered_radiance_per_albedo_rgb(
                table,
                face,
                [clamp_tau(0)?, clamp_tau(1)?, clamp_tau(2)?],
                [clamp_albedo(0)?, clamp_albedo(1)?, clamp_albedo(2)?],
                cos_mu0,
                cos_mu,
            )?
        }
        _ => [0.0; 3],
    };
    // Sky light lights both faces whatever the point light does (crate::sky).
    let mut radiance = match &params.sky {
        Some(sky) => {
            let (min, max) = (sky.table.spec().tau_min, sky.table.spec().tau_max);
            sky_radiance_per_albedo(
                sky,
                normal,
                eye - position,
                tau.map(|t| t.clamp(min, max)),
                albedo.map(|a| a.clamp(0.0, 1.0)),
                cos_mu.get(),
            )?
        }
        None => [0.0; 3],
    };
    let mut transmittance = [0.0; 3];
    for channel in 0..3 {
        transmittance[channel] = direct_transmission(optical_thickness[channel], cos_mu);
        if mu0 <= 0.0 {
            continue;
        }
        let irradiance = params.convention.inserted_irradiance(
            f64::from(params.light_flux) / (4.0 * std::f64::consts::PI * to_light.length_squared()),
            cos_mu0,
        );
        let single = if face == Face::Lit {
            single_scattered_reflected_radiance(optical_thickness[channel], unit, cos_mu0, cos_mu)
        } else {
            single_scattered_transmitted_radiance(optical_thickness[channel], unit, cos_mu0, cos_mu)
        };
        radiance[channel] +=
            (single + multiple_per_albedo[channel]) * irradiance * light.direct[channel];
    }
    if let Some(table) = params.diffuse_through_table()
        && mu0 > 0.0
        && light.diffuse.iter().any(|d| *d > 0.0)
    {
        let spec = table.spec();
        let (reflected, transmitted) = diffuse_response_per_albedo(
            table,
            tau.map(|t| t.clamp(spec.tau_min, spec.tau_max)),
            albedo.map(|a| a.clamp(0.0, 1.0)),
            cos_mu.get(),
        )?;
        // E⊥ = Φ/(4πr²) whatever the convention: the layer in front already weighted its flux by μ0.
        let normal_irradiance =
            f64::from(params.light_flux) / (4.0 * std::f64::consts::PI * to_light.length_squared());
        for c in 0..3 {
            let response = if face == Face::Lit {
                reflected[c]
            } else {
                transmitted[c]
            };
            radiance[c] += response * light.diffuse[c] * (cos_mu0.get() * normal_irradiance);
        }
    }
    Ok((radiance, transmittance))
}

/// Λ per channel at texture coordinate `uv`: `params.albedo_scale` times the albedo texture, sampled
/// bilinearly with clamp-to-edge from its half-float quantisation (what the GPU samples).
pub fn albedo_at(params: &ShadingParams, uv: [f32; 2]) -> [f64; 3] {
    let texel = sample_bilinear(&params.albedo_texture, uv, 3);
    [0, 1, 2].map(|c| f64::from(params.albedo_scale[c]) * texel[c])
}

/// τ1 per channel at texture coordinate `uv`: `params.optical_thickness` times the thickness texture's red
/// channel, sampled bilinearly with clamp-to-edge from its half-float quantisation (what the GPU samples).
pub fn optical_thickness_at(params: &ShadingParams, uv: [f32; 2]) -> [f64; 3] {
    let scale = params
        .thickness_texture
        .as_ref()
        .map_or(1.0, |texture| sample_bilinear_red(texture, uv));
    params.optical_thickness.map(|t| f64::from(t) * scale)
}

/// The CPU evaluation path: every vertex in parallel (each vertex independent, so the result does not
/// depend on the thread count). Errors only for parameters [`ShadingParams::validate`] refuses.
pub fn per_vertex_slab_values(
    mesh: &SlabMesh,
    opaque: &[OpaqueMesh],
    eye: Vec3,
    params: &ShadingParams,
) -> Result<Vec<VertexSlab>, SlabParameterError> {
    let eye = eye.as_dvec3();
    // With shadows, the light reaching each vertex by ray casting (the GPU paths' reference).
    let casters = params
        .shadows
        .as_ref()
        .map(|shadows| ShadowCasters::new(mesh, opaque, params.light_position, shadows.resolution));
    let diffuse_through = params.diffuse_through_table().map(|table| table.as_ref());
    // The all-orders multiple part and the sky's response are not linear in Λ: they need the vertex's Λ.
    let all_orders = matches!(params.scattering, Scattering::AllOrders(_)) || params.sky.is_some();
    (0..mesh.positions.len())
        .into_par_iter()
        .map(|vertex| {
            let uv = mesh.uvs[vertex];
            let tau = optical_thickness_at(params, uv);
            // Single scattering is linear in Λ, applied per fragment: no need to sample Λ here.
            let albedo = if all_orders || diffuse_through.is_some() {
                albedo_at(params, uv)
            } else {
                [1.0; 3]
            };
            let position = Vec3::from(mesh.positions[vertex]).as_dvec3();
            let light = casters
                .as_ref()
                .map_or(LightTransmission::UNSHADOWED, |casters| {
                    casters.light_transmission(position, params, diffuse_through)
                });
            let (radiance, transmittance) = slab_values_lit_by(
                position,
                Vec3::from(mesh.normals[vertex]).as_dvec3(),
                tau,
                albedo,
                eye,
                params,
                &light,
            )?;
            Ok(VertexSlab {
                radiance_per_albedo: radiance.map(|v| v as f32),
                transmittance: transmittance.map(|v| v as f32),
            })
        })
        .collect()
}

/// Triangle indices reordered so that triangles farther from the eye (by centroid) come first; ties keep
/// mesh order, so the order is deterministic. Needed because eq. (9) blending is order dependent.
pub fn sort_back_to_front(mesh: &SlabMesh, eye: Vec3, sorted: &mut Vec<u32>) {
    let eye = eye.as_dvec3();
    let mut keyed: Vec<(f64, usize)> = mesh
        .indices
        .chunks_exact(3)
        .enumerate()
        .map(|(triangle, corners)| {
            let centroid = corners
                .iter()
                .map(|&i| Vec3::from(mesh.positions[i as usize]).as_dvec3())
                .sum::<DVec3>()
                / 3.0;
            (centroid.distance_squared(eye), triangle)
        })
        .collect();
    keyed.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    sorted.clear();
    sorted.extend(
        keyed.iter().flat_map(|&(_, triangle)| {
            mesh.indices[3 * triangle..3 * triangle + 3].iter().copied()
        }),
    );
}

/// Bilinear sample (clamp to edge, texel centres at (i + ½)/w) of the red channel after half-float
/// quantisation, matching a wgpu `Rgba16Float` texture with a linear, clamp-to-edge sampler up to the
/// GPU's sub-texel weight precision.
pub fn sample_bilinear_red(texture: &Texture2d, uv: [f32; 2]) -> f64 {
    sample_bilinear(texture, uv, 1)[0]
}

/// As [`sample_bilinear_red`] for the first `channels` channels (the rest are 0).
pub fn sample_bilinear(texture: &Texture2d, uv: [f32; 2], channels: usize) -> [f64; 4] {
    let (width, height) = (texture.width() as usize, texture.height() as usize);
    let fetch = |x: isize, y: isize, channel: usize| {
        let x = x.clamp(0, width as isize - 1) as usize;
        let y = y.clamp(0, height as isize - 1) as usize;
        f64::from(quantize_to_half(texture.texels()[y * width + x][channel]))
    };
    let x = f64::from(uv[0]) * width as f64 - 0.5;
    let y = f64::from(uv[1]) * height as f64 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    // Far outside [0, 1] the casts saturate; the neighbours must not overflow (clamped to the edge
    // anyway). A debug build panicked there; a release build wrapped to the other edge, with weight 0
    // (a saturated coordinate has no fraction), so no test under `--release` can tell the two apart.
    let (x0, y0) = (x0 as isize, y0 as isize);
    let (x1, y1) = (x0.saturating_add(1), y0.saturating_add(1));
    let mut result = [0.0; 4];
    for (channel, value) in result.iter_mut().enumerate().take(channels.min(4)) {
        let top = fetch(x0, y0, channel) * (1.0 - fx) + fetch(x1, y0, channel) * fx;
        let bottom = fetch(x0, y1, channel) * (1.0 - fx) + fetch(x1, y1, channel) * fx;
        *value = top * (1.0 - fy) + bottom * fy;
    }
    result
}

/// IEEE binary16 bits of `value`, rounded to nearest even (overflow → ∞).
pub fn f32_to_f16_bits(value: f32) -> u16 {
    let bits = value.to_bits();
    let sign = ((bits >> 16) & 0x8000) as u16;
    let exponent = ((bits >> 23) & 0xff) as i32;
    let mantissa = bits & 0x7f_ffff;
    if exponent == 0xff {
        return sign | 0x7c00 | if mantissa != 0 { 0x200 } else { 0 };
    }
    let half_exponent = exponent - 127 + 15;
    if half_exponent >= 0x1f {
        return sign | 0x7c00;
    }
    if half_exponent <= 0 {
        // Subnormal half: value = m·2^−24 with m = significand·2^(e − 14).
        if half_exponent < -10 {
            return sign;
        }
        let significand = mantissa | 0x80_0000;
        let shift = (14 - half_exponent) as u32;
        let halfway = 1u32 << (shift - 1);
        let rounded = (significand + halfway - 1 + ((significand >> shift) & 1)) >> shift;
        return sign | rounded as u16;
    }
    let rounded = mantissa + 0xfff + ((mantissa >> 13) & 1);
    // A carry out of the mantissa correctly bumps the exponent.
    let out = ((half_exponent as u32) << 10) + (rounded >> 13);
    sign | out.min(0x7c00) as u16
}

/// The `f32` value of IEEE binary16 bits.
pub fn f16_bits_to_f32(bits: u16) -> f32 {
    let sign = u32::from(bits & 0x8000) << 16;
    let exponent = u32::from((bits >> 10) & 0x1f);
    let mantissa = u32::from(bits & 0x3ff);
    let magnitude = match exponent {
        0 => (mantissa as f32 * 2f32.powi(-24)).to_bits(),
        0x1f => 0x7f80_0000 | (mantissa << 13),
        _ => ((exponent + 112) << 23) | (mantissa << 13),
    };
    f32::from_bits(sign | magnitude)
}

/// `value` rounded to the nearest half float.
pub fn quantize_to_half(value: f32) -> f32 {
    f16_bits_to_f32(f32_to_f16_bits(value))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_float_round_trip() {
        // Exactly representable values survive; 1 + 2^-11 is a tie and rounds to even (1.0).
        for v in [
            0.0f32,
            1.0,
            0.5,
            0.75,
            65504.0,
            2f32.powi(-14),
            2f32.powi(-24),
            -3.25,
        ] {
            assert_eq!(quantize_to_half(v), v, "{v}");
        }
        assert_eq!(quantize_to_half(1.0 + 2f32.powi(-11)), 1.0);
        assert_eq!(
            quantize_to_half(1.0 + 3.0 * 2f32.powi(-11)),
            1.0 + 2f32.powi(-9)
        );
        assert_eq!(f32_to_f16_bits(1e6), 0x7c00);
        // Relative error of rounding to 11 significant bits is ≤ 2^-11.
        for v in [0.1f32, 0.3, 0.7, 3.7, 1234.5] {
            assert!((quantize_to_half(v) - v).abs() <= v * 2f32.powi(-11));
        }
    }

    #[test]
    fn lit_side_rule() {
        // Normal pointing away from the light is flipped; eye behind → far side.
        let side = lit_side_cosines(-DVec3::Z, DVec3::Z, -DVec3::Z * 2.0).unwrap();
        assert_eq!((side.mu0, side.mu, side.face), (1.0, 1.0, Face::Far));
        let zero_normal = lit_side_cosines(DVec3::ZERO, DVec3::Z, DVec3::Z).unwrap();
        assert_eq!(
            (zero_normal.mu0, zero_normal.mu, zero_normal.face),
            (0.0, 0.0, Face::Lit)
        );
    }

    #[test]
    fn cpu_path_is_independent_of_thread_count() {
        let mut mesh = SlabMesh::flat_sheet(Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, 40, 30).unwrap();
        for (i, position) in mesh.positions.iter_mut().enumerate() {
            position[2] = 0.05 * (i as f32 * 0.37).sin();
        }
        let params = ShadingParams::uniform(1.5, 0.8, Vec3::new(0.3, 0.2, 1.0), 20.0).unwrap();
        let eye = Vec3::new(0.5, -0.4, -1.5);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| per_vertex_slab_values(&mesh, &[], eye, &params).unwrap())
        };
        let single = run(1);
        assert_eq!(single, run(4));
        assert_eq!(single, run(7));
        assert!(single.iter().any(|v| v.radiance_per_albedo[0] > 0.0));
    }

    #[test]
    fn sort_puts_far_triangles_first() {
        let near = SlabMesh::flat_sheet(Vec3::new(0.0, 0.0, 1.0), Vec3::X, Vec3::Y, Vec3::Z, 1, 1)
            .unwrap();
        let far = SlabMesh::flat_sheet(Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, 1, 1).unwrap();
        let mut mesh = near.clone();
        mesh.append(&far);
        let mut sorted = Vec::new();
        sort_back_to_front(&mesh, Vec3::new(0.5, 0.5, 5.0), &mut sorted);
        // The far sheet's vertices are 4..8.
        assert!(sorted[..6].iter().all(|&i| i >= 4));
        assert!(sorted[6..].iter().all(|&i| i < 4));
    }
}
