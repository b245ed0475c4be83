// shadow.wgsl — translucent shadows of the point light (crates/sheer-slab/src/render/shadow.rs): a
// transmittance shadow map built by depth peeling from the light, and its lookup by every evaluation path.
//
// The Rust side appends this file to thin_slab.wgsl, whose `Frame`, textures and table lookups it uses.
//
// Layer k of the map (k = 0, 1: `SHADOW_LAYERS` in shadow.rs; `shadow_layer_k`) holds, per texel (one ray from the light), the k-th
// nearest surface the ray crosses, packed into four u32:
//   x: its distance from the light (m, f32 bits); 3e38 where there is none;
//   y, z, w: pack2x16float of (t.r, t.g), (t.b, D.r), (D.g, D.b), where
//     t = e^{−τ1/μ0} per channel, the layer's direct transmission of the beam (Frisvad et al. 2005, α of
//         eq. 9 with the light's cosine μ0 for the eye's μ); 0 for an opaque surface;
//     D = T_d(μ0)/π per channel (sr⁻¹), T_d the layer's directional-hemispherical scattered transmittance
//         (by reciprocity the diffuse table's T_d(μ0)). Zero without the all-orders model, and for an
//         opaque surface.
// A point at distance d from the light receives the beam times Π t over the layers nearer than d, and
// from the nearest of them (times the t of the layers before it) isotropic radiance μ0·E⊥·D on its lit
// face: the layer's scattered flux μ0·T_d·E⊥ leaving isotropically, with the receiver's own μ0 (the two
// layers taken as parallel, as in the two-slab model this approximates). So the receiver's irradiance from
// the beam, t·μ0·E⊥ + T_d·μ0·E⊥, never exceeds μ0·E⊥: t + T_d ≤ 1 by energy conservation in the layer.

@group(0) @binding(9) var shadow_layer_0: texture_2d<u32>;
@group(0) @binding(10) var shadow_layer_1: texture_2d<u32>;

// Set per pipeline: true when the point light's beam is attenuated by the shadow map.
override shadows: bool = false;

// What reaches a point from the light through the layers in front of it.
struct LightTransmission {
    // Π t: the fraction of the direct beam, per channel.
    direct: vec3<f32>,
    // D of the nearest layer in front times the beam reaching it (sr⁻¹), per channel: the receiver's lit
    // face gets isotropic radiance μ0·E⊥·diffuse.
    diffuse: vec3<f32>,
}

// One stored layer: the accumulated transmission so far, updated when the layer lies before `limit`.
fn shadow_layer_step(packed: vec4<u32>, limit: f32, before: LightTransmission) -> LightTransmission {
    let rg = unpack2x16float(packed.y);
    let b_d = unpack2x16float(packed.z);
    let d_gb = unpack2x16float(packed.w);
    let t = vec3<f32>(rg, b_d.x);
    let d = vec3<f32>(b_d.y, d_gb);
    let in_front = bitcast<f32>(packed.x) < limit;
    let after = LightTransmission(before.direct * t, before.direct * d);
    return LightTransmission(select(before.direct, after.direct, in_front),
        select(before.diffuse, after.diffuse, in_front));
}

// All layers along the ray through one texel (clamped to the map).
fn shadow_texel(texel: vec2<i32>, limit: f32) -> LightTransmission {
    let size = vec2<i32>(textureDimensions(shadow_layer_0));
    let at = clamp(texel, vec2<i32>(0), size - 1);
    var result = LightTransmission(vec3<f32>(1.0), vec3<f32>(0.0));
    result = shadow_layer_step(textureLoad(shadow_layer_0, at, 0), limit, result);
    result = shadow_layer_step(textureLoad(shadow_layer_1, at, 0), limit, result);
    return result;
}

// a + (b − a)·f: exact when a = b (a single sheet gets exactly 1 and 0, so shadows change no pixel).
fn shadow_lerp(a: LightTransmission, b: LightTransmission, f: f32) -> LightTransmission {
    return LightTransmission(a.direct + (b.direct - a.direct) * f, a.diffuse + (b.diffuse - a.diffuse) * f);
}

// The light's transmission to `position` (m), whose own surface has cosine `mu0` to the light: the four
// texels around its projection, each compared with its distance less a slope-scaled bias, bilinearly
// weighted (percentage-closer filtering). Outside the map's frustum: the full beam.
fn light_transmission(position: vec3<f32>, mu0: f32) -> LightTransmission {
    let unshadowed = LightTransmission(vec3<f32>(1.0), vec3<f32>(0.0));
    if !shadows {
        return unshadowed;
    }
    let clip = frame.shadow_view_projection * vec4<f32>(position, 1.0);
    let ndc = clip.xy / clip.w;
    if clip.w <= 0.0 || any(abs(ndc) > vec2<f32>(1.0)) {
        return unshadowed;
    }
    let distance = length(position - frame.light.xyz);
    // A texel spans frame.shadow.y·d metres at distance d; the stored distance of the receiver's own surface
    // differs from its own by up to √2 texels times the slope tan θ0 (μ0 floored at 0.05 against ∞), plus
    // frame.shadow.z·d for f32 rounding and curvature (shadow.rs derives both).
    let cosine = max(mu0, 0.05);
    let slope = sqrt(max(1.0 - cosine * cosine, 0.0)) / cosine;
    let limit = distance - distance * (frame.shadow.y * slope + frame.shadow.z);
    let resolution = frame.shadow.x;
    let position_in_texels = vec2<f32>(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y) * resolution - 0.5;
    let base = floor(position_in_texels);
    let f = position_in_texels - base;
    let texel = vec2<i32>(base);
    let top = shadow_lerp(shadow_texel(texel, limit), shadow_texel(texel + vec2<i32>(1, 0), limit), f.x);
    let bottom = shadow_lerp(shadow_texel(texel + vec2<i32>(0, 1), limit),
        shadow_texel(texel + vec2<i32>(1, 1), limit), f.x);
    return shadow_lerp(top, bottom, f.y);
}

// The light's transmission at a vertex, with the receiver's cosine from the lit-side rule.
fn light_transmission_at_vertex(position: vec3<f32>, normal: vec3<f32>) -> LightTransmission {
    let side = lit_side_cosines(normal, frame.light.xyz - position, frame.eye.xyz - position);
    return light_transmission(position, max(side.mu0, COSINE_FLOOR));
}

// ---- building the map: one pass per layer, each keeping the nearest surface behind the previous layer ----

// Set per peel pipeline: true for layer 0 (no previous layer to peel behind).
override first_layer: bool = false;
// Set per peel pipeline: true when the layers carry the diffuse part D (the all-orders model is on).
override diffuse_through: bool = false;

// The previous layer (group 1 of the peel passes; binding 2, clear of the compute passes' group 1).
@group(1) @binding(2) var previous_layer: texture_2d<u32>;

struct PeelVarying {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    // t and D at the vertex, interpolated: both vary slowly over a triangle, and the map's passes then
    // cost the rasteriser almost nothing per texel.
    @location(1) transmission: vec3<f32>,
    @location(2) scattered: vec3<f32>,
}

@vertex
fn vs_peel_cloth(input: VertexInput) -> PeelVarying {
    let length_squared = dot(input.normal, input.normal);
    let n = input.normal * inverseSqrt(select(1.0, length_squared, length_squared > 0.0));
    let mu0 = clamp(abs(dot(n, normalize(frame.light.xyz - input.position))), COSINE_FLOOR, 1.0);
    let tau = optical_thickness_at_vertex(input.uv);
    var d = vec3<f32>(0.0);
    if diffuse_through {
        let nodes = all_orders_channels(tau);
        let albedo = albedo_at_vertex(input.uv);
        let albedos = all_orders_channel_albedos(nodes, albedo);
        let red = diffuse_log_values(nodes.red, albedos.red, mu0);
        let green = diffuse_log_values(nodes.green, albedos.green, mu0);
        let blue = diffuse_log_values(nodes.blue, albedos.blue, mu0);
        // T_d = Λ·e^{ln(T_d/Λ)}; D = T_d/π.
        d = albedo * exp(vec3<f32>(red.y, green.y, blue.y)) / PI;
    }
    return PeelVarying(frame.shadow_view_projection * vec4<f32>(input.position, 1.0), input.position,
        exp(-tau / mu0), d);
}

@vertex
fn vs_peel_opaque(input: OpaqueInput) -> PeelVarying {
    // t = 0, D = 0: nothing of the beam passes.
    return PeelVarying(frame.shadow_view_projection * vec4<f32>(input.position, 1.0), input.position,
        vec3<f32>(0.0), vec3<f32>(0.0));
}

// Distance from the light, or discard when this surface is not behind the previous layer. Equal distances
// are the same surface again (the same triangle at the same texel computes the same value).
fn peel_distance(input: PeelVarying) -> f32 {
    let distance = length(input.world_position - frame.light.xyz);
    if !first_layer {
        let previous = bitcast<f32>(textureLoad(previous_layer, vec2<i32>(input.clip_position.xy), 0).x);
        if distance <= previous {
            discard;
        }
    }
    return distance;
}

@fragment
fn fs_peel_cloth(input: PeelVarying) -> @location(0) vec4<u32> {
    let t = input.transmission;
    let d = input.scattered;
    return vec4<u32>(bitcast<u32>(peel_distance(input)), pack2x16float(t.rg),
        pack2x16float(vec2<f32>(t.b, d.r)), pack2x16float(d.gb));
}

@fragment
fn fs_peel_opaque(input: PeelVarying) -> @location(0) vec4<u32> {
    // t = 0, D = 0: nothing of the beam passes.
    return vec4<u32>(bitcast<u32>(peel_distance(input)), 0u, 0u, 0u);
}
