// thin_slab.wgsl — the thin-slab shading model of Frisvad, Christensen & Falster (2005), eqs. (4)–(9),
// for sheer-slab's headless renderer (crates/sheer-slab/src/render/mod.rs), plus the traditional baseline
// (diffuse BRDF, constant alpha 0.2) and the background pass. With the override `all_orders`, the
// diffuse radiance also carries the multiply-scattered part of an isotropically scattering slab, looked
// up in the table sheer-transport precomputes (assets/all_orders_table.bin; layout in render/mod.rs).
//
// The Rust side prepends, in this order: one of `slab_output_single.wgsl` / `slab_output_dual.wgsl`
// (which declare `SlabOutput` and `slab_output`, and for dual-source blending the `enable` directive that
// must come first), then `lit_side.wgsl` (the lit-side rule: `LitSide`, `lit_side_cosines`).
//
// Units: positions in m, light flux in W, irradiance in W/m², radiance in W/(m²·sr). All radiance here is
// linear; a display target gets it times the exposure (`frame.output.z`), a radiance target as it is.
//
// Blending (fixed-function, eq. 9): L_blended = L_dst · α_src + L_src, i.e. colour source factor One and
// destination factor SrcAlpha (grey τ1) or Src1 (per-channel τ1 with dual-source blending).

struct Frame {
    view_projection: mat4x4<f32>,
    // xyz: eye position (m).
    eye: vec4<f32>,
    // xyz: light position (m); w: flux Φ (W) of the isotropic point light.
    light: vec4<f32>,
    // rgb: optical thickness τ1 per channel; w: 1 if the thickness texture multiplies τ1, else 0
    // (informative; the shader uses the override constant `has_thickness_texture`).
    optical_thickness: vec4<f32>,
    // rgb: single-scattering albedo scale (multiplies the albedo texture); w: convention
    // (0 = irradiance normal to the beam, 1 = paper-literal surface irradiance of eq. 6).
    albedo_scale: vec4<f32>,
    // rgb: uniform background radiance; w: 1 if the background texture is used instead.
    background: vec4<f32>,
    // x: the baseline's constant transmittance α (0.2 in the paper's figure 2).
    baseline: vec4<f32>,
    // Sky light (crates/sheer-slab/src/sky.rs): rgb of the nine spherical-harmonic coefficients of E/π, the
    // environment's irradiance over π (W/(m²·sr)), in the order of `spherical_harmonics`.
    sky: array<vec4<f32>, 9>,
    // x, y: the target's size (pixels); z: output scale (1 for a radiance target, the exposure for a display
    // target); w: the light marker's radius (pixels).
    output: vec4<f32>,
    // rgb: the light marker's radiance (W/(m²·sr)).
    marker: vec4<f32>,
    // The shadow map's view and projection from the light (shadow.wgsl).
    shadow_view_projection: mat4x4<f32>,
    // x: the shadow map's resolution (texels); y: a texel's width per metre of distance from the light;
    // z: the bias per metre of distance for rounding and curvature.
    shadow: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var albedo_texture: texture_2d<f32>;
@group(0) @binding(2) var thickness_texture: texture_2d<f32>;
@group(0) @binding(3) var linear_sampler: sampler;
@group(0) @binding(4) var background_texture: texture_2d<f32>;
// The all-orders table (render/mod.rs): texel (a·C + j, (face·T + t)·C + k) holds ln f = ln(L_m/(Λ²μ0))
// at the (μ0, μ) nodes (k, j), (k, j+1), (k+1, j), (k+1, j+1) of τ1 node t, albedo node a.
@group(0) @binding(5) var all_orders_table: texture_2d<f32>;
// Texel (t, 0): the albedo warps (e^β − 1, 1/β) of τ1 nodes t (xy) and t + 1 (zw).
@group(0) @binding(6) var all_orders_warp: texture_2d<f32>;

struct AllOrdersAxes {
    // x: c0 = ln τmin + τmin; y: 1/(c1 − c0) (τ1 nodes are uniform in c = ln τ1 + τ1); z: τ1 cells;
    // w: albedo cells.
    tau: vec4<f32>,
    // x: cosine cells C (μ0 and μ nodes are uniform in √μ); y: texture rows per face.
    cosine: vec4<f32>,
}

@group(0) @binding(7) var<uniform> all_orders_axes: AllOrdersAxes;
// The diffuse (sky light) table, on the all-orders table's axes: texel (a·C + j, t) holds
// (ln(R_d/Λ) at μ nodes j, j+1, ln(T_d/Λ) at μ nodes j, j+1) of τ1 node t, albedo node a.
@group(0) @binding(8) var diffuse_table: texture_2d<f32>;

const PI: f32 = 3.14159265358979;
// Cosines below this are treated as this (grazing guard): WGSL may assume no infinities at run time, so
// τ1/μ must stay finite. At μ = 1e-6 the model equals its μ → 0 limit to f32 precision for μ0 ≫ 1e-6.
const COSINE_FLOOR: f32 = 1e-6;

// Set per pipeline: true when τ1 differs between channels (then the model runs three times).
override per_channel_thickness: bool = false;
// Set per pipeline: true when a thickness texture multiplies τ1.
override has_thickness_texture: bool = false;
// Set per pipeline: true for the all-orders model (single scattering + the table's multiple part).
override all_orders: bool = false;
// Set per pipeline: true when sky light lights both faces (the diffuse table and `frame.sky`).
override sky_light: bool = false;

// φ(d) = (1 − e^{−d})/d = Σ (−d)^k/(k+1)! for 0 ≤ d ≤ 1/2, by Horner with the coefficients
// (−1)^k/(k+1)! (multiplications only: divisions by constants stay divisions without fast-math); stopping
// after d^8/9! leaves an error below (1/2)^9/10! < 6e-10, far under f32 precision. φ(0) = 1 exactly.
fn phi_series(d: f32) -> f32 {
    return 1.0 + d * (-0.5 + d * (0.166666667 + d * (-0.0416666667 + d * (0.00833333333
        + d * (-0.00138888889 + d * (0.000198412698 + d * (-2.48015873e-05 + d * 2.75573192e-06)))))));
}

// Below this argument the series is used; above it, differences of exponentials lose at most
// log2(1/(1 − e^{−1/2})) = 1.35 bits.
const SERIES_LIMIT: f32 = 0.5;

// The model for one channel without Λ/(4π)·E: (eq. 4 shape, eq. 5 shape, α). Branch-free (selects: a
// software rasteriser runs both sides of a branch anyway), with two exponentials shared by all three.
// Differences of exponentials are taken only where they lose at most 1.35 bits (argument ≥ 1/2), the
// Taylor series of φ covers the rest, so nothing cancels catastrophically and μ = μ0 is exact:
//   α = e^{−τ1/μ}, e0 = e^{−τ1/μ0};
//   eq. (4): μ0/(μ+μ0)·(1 − e^{−x}), x = τ1/μ + τ1/μ0; 1 − e^{−x} = 1 − α·e0 (x ≥ 1/2), else x·φ(x);
//   eq. (5): with M, m = max, min of μ, μ0, e_M = e^{−τ1/M}, e_m = e^{−τ1/m}, d = τ1|1/μ − 1/μ0|,
//     d < 1/2: (τ1/μ)·e_M·φ(d)  (at μ = μ0 the exact limit (τ1/μ)·e^{−τ1/μ});
//     d ≥ 1/2: μ0/(M−m)·(e_M − e_m)  (the paper's form, where it is well conditioned).
fn slab_shapes(tau: f32, mu0: f32, mu: f32) -> vec3<f32> {
    let tau_over_mu = tau / mu;
    let tau_over_mu0 = tau / mu0;
    let alpha = exp(-tau_over_mu);
    let lit_attenuation = exp(-tau_over_mu0);
    let x = tau_over_mu + tau_over_mu0;
    let series_x = x * phi_series(min(x, SERIES_LIMIT));
    let one_minus_exp = select(1.0 - alpha * lit_attenuation, series_x, x < SERIES_LIMIT);
    let reflected = mu0 / (mu + mu0) * one_minus_exp;
    let larger = max(mu, mu0);
    let smaller = min(mu, mu0);
    let eye_larger = mu >= mu0;
    let e_larger = select(lit_attenuation, alpha, eye_larger);
    let e_smaller = select(alpha, lit_attenuation, eye_larger);
    // d = |τ1/μ − τ1/μ0|: near μ = μ0 its absolute error is ≤ ε·τ1/m, which moves φ(d) ≈ 1 − d/2 by
    // ≤ ε·τ1/(2m) relative: harmless (no division needed, unlike the f64 reference's (τ1/m)(1 − m/M)).
    let d = abs(tau_over_mu - tau_over_mu0);
    let near_diagonal = tau_over_mu * e_larger * phi_series(min(d, SERIES_LIMIT));
    // max(): keeps the unused select operand finite at μ = μ0.
    let off_diagonal = mu0 / max(larger - smaller, 1e-30) * (e_larger - e_smaller);
    let transmitted = select(off_diagonal, near_diagonal, d < SERIES_LIMIT);
    return vec3<f32>(reflected, transmitted, alpha);
}

// ---- the all-orders table lookup: the CPU sampler of sheer-transport (table.rs) in f32 -----------------

// Position on a uniform axis of `cells` cells over [0, 1]: (lower node, weight), the last cell taking
// unit = 1 with weight 1, as the CPU's `axis_position`.
fn all_orders_axis(unit: f32, cells: f32) -> vec2<f32> {
    let scaled = unit * cells;
    let lower = min(floor(scaled), cells - 1.0);
    return vec2<f32>(lower, scaled - lower);
}

// ln(1 + x) for x ≥ 0 without the rounding of 1 + x for small x: 2·atanh(u), u = x/(2 + x) ≤ 1/5 for
// x < 1/2, by its series to u⁹ (truncation < 2·u¹¹/11 ≤ 4e-9 relative); log(1 + x) above.
fn all_orders_log_one_plus(x: f32) -> f32 {
    let u = x / (2.0 + x);
    let u2 = u * u;
    let series = 2.0 * u * (1.0 + u2 * (0.333333333 + u2 * (0.2 + u2 * (0.142857143 + u2 * 0.111111111))));
    return select(log(1.0 + x), series, x < 0.5);
}

struct AllOrdersTau {
    // Lower τ1 node and the weight of the upper one.
    node: vec2<f32>,
    // Albedo warps (e^β − 1, 1/β) of the lower (xy) and the upper (zw) τ1 node.
    warps: vec4<f32>,
}

fn all_orders_tau(tau: f32) -> AllOrdersTau {
    // The clamp only absorbs rounding: the renderer validates τ1 against the table's range.
    let unit = clamp((log(tau) + tau - all_orders_axes.tau.x) * all_orders_axes.tau.y, 0.0, 1.0);
    let node = all_orders_axis(unit, all_orders_axes.tau.z);
    return AllOrdersTau(node, textureLoad(all_orders_warp, vec2<i32>(i32(node.x), 0), 0));
}

struct AllOrdersCosines {
    // Texel offset of the (μ0, μ) cell within a face's τ1 node: (j, k).
    texel: vec2<i32>,
    // Bilinear weights of the cell's four nodes, in the texel's channel order.
    weights: vec4<f32>,
}

fn all_orders_cosines(mu0: f32, mu: f32) -> AllOrdersCosines {
    let cells = all_orders_axes.cosine.x;
    // min(): normalised dot products may exceed 1 by rounding.
    let k = all_orders_axis(sqrt(min(mu0, 1.0)), cells);
    let j = all_orders_axis(sqrt(min(mu, 1.0)), cells);
    let weights = vec4<f32>(1.0 - k.y, 1.0 - k.y, k.y, k.y) * vec4<f32>(1.0 - j.y, j.y, 1.0 - j.y, j.y);
    return AllOrdersCosines(vec2<i32>(i32(j.x), i32(k.x)), weights);
}

// Albedo node and weight at τ1 node with warp (e^β − 1, 1/β), s = √(1−Λ): w = ln(1 + s(e^β − 1))/β.
fn all_orders_albedo_axis(s: f32, warp: vec2<f32>) -> vec2<f32> {
    return all_orders_axis(clamp(all_orders_log_one_plus(s * warp.x) * warp.y, 0.0, 1.0),
        all_orders_axes.tau.w);
}

// Where Λ falls on the albedo axes of the lower and the upper τ1 node: (node, weight) for each.
struct AllOrdersAlbedo {
    lower: vec2<f32>,
    upper: vec2<f32>,
}

fn all_orders_albedo(tau: AllOrdersTau, albedo: f32) -> AllOrdersAlbedo {
    // max(): Λ from half-float texels times the scale may exceed 1 by rounding.
    let s = sqrt(max(1.0 - albedo, 0.0));
    return AllOrdersAlbedo(all_orders_albedo_axis(s, tau.warps.xy), all_orders_albedo_axis(s, tau.warps.zw));
}

// ln f interpolated quadrilinearly (four texel loads, each a whole (μ0, μ) cell) on the face whose rows
// start at `face_rows` (0: eye on the lit side; the axes' rows per face: the far side).
fn all_orders_log_value_at(tau: AllOrdersTau, albedo: AllOrdersAlbedo, cosines: AllOrdersCosines,
        face_rows: i32) -> f32 {
    let cells = i32(all_orders_axes.cosine.x);
    let row_lower = cosines.texel.y + face_rows + i32(tau.node.x) * cells;
    let column_lower = cosines.texel.x + i32(albedo.lower.x) * cells;
    let column_upper = cosines.texel.x + i32(albedo.upper.x) * cells;
    let w = cosines.weights;
    let at_lower = mix(dot(textureLoad(all_orders_table, vec2<i32>(column_lower, row_lower), 0), w),
        dot(textureLoad(all_orders_table, vec2<i32>(column_lower + cells, row_lower), 0), w),
        albedo.lower.y);
    let at_upper = mix(dot(textureLoad(all_orders_table, vec2<i32>(column_upper, row_lower + cells), 0), w),
        dot(textureLoad(all_orders_table, vec2<i32>(column_upper + cells, row_lower + cells), 0), w),
        albedo.upper.y);
    return mix(at_lower, at_upper, tau.node.y);
}

fn all_orders_face_rows(eye_on_lit_side: bool) -> i32 {
    return i32(select(all_orders_axes.cosine.y, 0.0, eye_on_lit_side));
}

// ln f on one face (the lookup `evaluate_shader_all_orders` checks against the CPU sampler).
fn all_orders_log_value(tau: AllOrdersTau, albedo: f32, cosines: AllOrdersCosines, eye_on_lit_side: bool)
        -> f32 {
    return all_orders_log_value_at(tau, all_orders_albedo(tau, albedo), cosines,
        all_orders_face_rows(eye_on_lit_side));
}

// τ1 node per channel: one lookup of the τ1 axis when τ1 is grey.
struct AllOrdersChannels {
    red: AllOrdersTau,
    green: AllOrdersTau,
    blue: AllOrdersTau,
}

fn all_orders_channels(tau: vec3<f32>) -> AllOrdersChannels {
    if per_channel_thickness {
        return AllOrdersChannels(all_orders_tau(tau.r), all_orders_tau(tau.g), all_orders_tau(tau.b));
    }
    let grey = all_orders_tau(tau.r);
    return AllOrdersChannels(grey, grey, grey);
}

// Where each channel's Λ falls on the albedo axes of its τ1 nodes.
struct AllOrdersChannelAlbedos {
    red: AllOrdersAlbedo,
    green: AllOrdersAlbedo,
    blue: AllOrdersAlbedo,
}

fn all_orders_channel_albedos(nodes: AllOrdersChannels, albedo: vec3<f32>) -> AllOrdersChannelAlbedos {
    return AllOrdersChannelAlbedos(all_orders_albedo(nodes.red, albedo.r),
        all_orders_albedo(nodes.green, albedo.g), all_orders_albedo(nodes.blue, albedo.b));
}

// ln f per channel on the face whose rows start at `face_rows` (`all_orders_face_rows`).
fn all_orders_log_face(nodes: AllOrdersChannels, albedos: AllOrdersChannelAlbedos, cosines: AllOrdersCosines,
        face_rows: i32) -> vec3<f32> {
    return vec3<f32>(all_orders_log_value_at(nodes.red, albedos.red, cosines, face_rows),
        all_orders_log_value_at(nodes.green, albedos.green, cosines, face_rows),
        all_orders_log_value_at(nodes.blue, albedos.blue, cosines, face_rows));
}

// f = L_m/(Λ²·μ0) per unit irradiance normal to the beam (sr⁻¹), the table's interpolated e^{ln f}, per
// channel on both faces at once: the axes are shared, only the loads double.
struct AllOrdersBothFaces {
    // Eye on the lit side (reflected).
    lit: vec3<f32>,
    // Eye on the far side (transmitted).
    far: vec3<f32>,
}

fn all_orders_reduced_both_faces(tau: vec3<f32>, albedo: vec3<f32>, mu0: f32, mu: f32)
        -> AllOrdersBothFaces {
    let cosines = all_orders_cosines(mu0, mu);
    let nodes = all_orders_channels(tau);
    let albedos = all_orders_channel_albedos(nodes, albedo);
    return AllOrdersBothFaces(exp(all_orders_log_face(nodes, albedos, cosines, all_orders_face_rows(true))),
        exp(all_orders_log_face(nodes, albedos, cosines, all_orders_face_rows(false))));
}

// ---- sky light (crates/sheer-slab/src/sky.rs): the slab's all-orders response to diffuse light -------

// (ln(R_d/Λ), ln(T_d/Λ)) at cosine μ, trilinear on the all-orders table's axes: τ1 nodes, each with its own
// albedo position, and the μ cell whose two nodes each texel holds.
fn diffuse_log_values(tau: AllOrdersTau, albedo: AllOrdersAlbedo, mu: f32) -> vec2<f32> {
    let cells = all_orders_axes.cosine.x;
    let j = all_orders_axis(sqrt(min(mu, 1.0)), cells);
    let w = vec2<f32>(1.0 - j.y, j.y);
    let step = i32(cells);
    let row = i32(tau.node.x);
    let lower = i32(albedo.lower.x) * step + i32(j.x);
    let upper = i32(albedo.upper.x) * step + i32(j.x);
    let a = textureLoad(diffuse_table, vec2<i32>(lower, row), 0);
    let b = textureLoad(diffuse_table, vec2<i32>(lower + step, row), 0);
    let c = textureLoad(diffuse_table, vec2<i32>(upper, row + 1), 0);
    let d = textureLoad(diffuse_table, vec2<i32>(upper + step, row + 1), 0);
    let at_lower = mix(vec2<f32>(dot(a.xy, w), dot(a.zw, w)), vec2<f32>(dot(b.xy, w), dot(b.zw, w)),
        albedo.lower.y);
    let at_upper = mix(vec2<f32>(dot(c.xy, w), dot(c.zw, w)), vec2<f32>(dot(d.xy, w), dot(d.zw, w)),
        albedo.upper.y);
    return mix(at_lower, at_upper, tau.node.y);
}

// L_in(m) = E(m)/π: the uniform radiance that lights a face of outward unit normal m (W/(m²·sr)), from the
// nine coefficients; never negative.
fn sky_radiance_on_face(m: vec3<f32>) -> vec3<f32> {
    let basis_1 = 0.488602512 * m;
    var sum = frame.sky[0].rgb * 0.282094792 + frame.sky[1].rgb * basis_1.y + frame.sky[2].rgb * basis_1.z
        + frame.sky[3].rgb * basis_1.x;
    sum += frame.sky[4].rgb * (1.09254843 * m.x * m.y) + frame.sky[5].rgb * (1.09254843 * m.y * m.z)
        + frame.sky[6].rgb * (0.315391565 * (3.0 * m.z * m.z - 1.0))
        + frame.sky[7].rgb * (1.09254843 * m.x * m.z)
        + frame.sky[8].rgb * (0.546274215 * (m.x * m.x - m.y * m.y));
    return max(sum, vec3<f32>(0.0));
}

// The face the eye sees (outward unit normal m) and μ = |n·e| floored, for the diffuse responses.
struct DiffuseView {
    face: vec3<f32>,
    mu: f32,
    // False for a zero normal: no diffuse light.
    valid: bool,
}

fn diffuse_view(normal: vec3<f32>, to_eye: vec3<f32>) -> DiffuseView {
    let length_squared = dot(normal, normal);
    let n = normal * inverseSqrt(select(1.0, length_squared, length_squared > 0.0));
    let s = dot(n, normalize(to_eye));
    return DiffuseView(select(-n, n, s >= 0.0), clamp(abs(s), COSINE_FLOOR, 1.0), length_squared > 0.0);
}

// (R_d/Λ, T_d/Λ) per channel at μ: the slab's response to uniform diffuse light on one face.
struct DiffuseResponse {
    reflected: vec3<f32>,
    transmitted: vec3<f32>,
}

fn diffuse_response(nodes: AllOrdersChannels, albedos: AllOrdersChannelAlbedos, mu: f32) -> DiffuseResponse {
    let red = diffuse_log_values(nodes.red, albedos.red, mu);
    let green = diffuse_log_values(nodes.green, albedos.green, mu);
    let blue = diffuse_log_values(nodes.blue, albedos.blue, mu);
    return DiffuseResponse(exp(vec3<f32>(red.x, green.x, blue.x)), exp(vec3<f32>(red.y, green.y, blue.y)));
}

// The sky's radiance toward the eye per unit albedo: L_in(m)·R_d/Λ + L_in(−m)·T_d/Λ per channel, m the
// face the eye sees, the response at μ = |n·e| floored as the point light's is. A zero normal gets none.
fn sky_radiance_with(view: DiffuseView, response: DiffuseResponse) -> vec3<f32> {
    let sky = sky_radiance_on_face(view.face) * response.reflected
        + sky_radiance_on_face(-view.face) * response.transmitted;
    return select(vec3<f32>(0.0), sky, view.valid);
}

struct SlabValues {
    // L/Λ (W/(m²·sr)): the single-scattered radiance for Λ = 1, plus with `all_orders` the multiple part
    // per unit albedo for the given Λ.
    radiance_per_albedo: vec3<f32>,
    // α = e^{−τ1/μ} per channel.
    transmittance: vec3<f32>,
}

// Where one point of the slab sees the light and the eye: the lit-side rule, its cosines with the grazing
// floor, and the irradiance that eqs. (4)–(5) multiply.
struct SlabPoint {
    mu0: f32,
    mu: f32,
    eye_on_lit_side: bool,
    // Irradiance normal to the beam Φ/(4πr²), or eq. (6)'s surface irradiance Φμ0/(4πr²) (W/m²).
    irradiance: f32,
    // Irradiance normal to the beam Φ/(4πr²) whatever the convention (W/m²); 0 where no light arrives.
    normal_irradiance: f32,
}

fn slab_point(position: vec3<f32>, normal: vec3<f32>) -> SlabPoint {
    let to_light = frame.light.xyz - position;
    let side = lit_side_cosines(normal, to_light, frame.eye.xyz - position);
    let mu = max(side.mu, COSINE_FLOOR);
    let mu0 = max(side.mu0, COSINE_FLOOR);
    // Irradiance normal to the beam Φ/(4πr²); eq. (6)'s surface irradiance multiplies it by μ0. A light
    // grazing the surface (μ0 = 0) delivers nothing: the μ0 → 0 limit of eqs. (4)–(5) is 0. Nor does a
    // light exactly at the point (r = 0, no direction; lit_side gives μ0 = 0): the divisor is replaced
    // there so that 0/0 cannot make a NaN pixel.
    let distance_squared = dot(to_light, to_light);
    let received = select(0.0, 1.0, side.mu0 > 0.0 && distance_squared > 0.0);
    let convention_factor = select(1.0, mu0, frame.albedo_scale.w > 0.5);
    let normal_irradiance = received * frame.light.w
        / (4.0 * PI * select(1.0, distance_squared, distance_squared > 0.0));
    return SlabPoint(mu0, mu, side.eye_on_lit_side, convention_factor * normal_irradiance, normal_irradiance);
}

// Single scattering at one point: eqs. (4)/(5) per channel per unit albedo, and α.
fn single_values(point: SlabPoint, tau: vec3<f32>) -> SlabValues {
    var reflected: vec3<f32>;
    var transmitted: vec3<f32>;
    var transmittance: vec3<f32>;
    if per_channel_thickness {
        let red = slab_shapes(tau.r, point.mu0, point.mu);
        let green = slab_shapes(tau.g, point.mu0, point.mu);
        let blue = slab_shapes(tau.b, point.mu0, point.mu);
        reflected = vec3<f32>(red.x, green.x, blue.x);
        transmitted = vec3<f32>(red.y, green.y, blue.y);
        transmittance = vec3<f32>(red.z, green.z, blue.z);
    } else {
        let grey = slab_shapes(tau.r, point.mu0, point.mu);
        reflected = vec3<f32>(grey.x);
        transmitted = vec3<f32>(grey.y);
        transmittance = vec3<f32>(grey.z);
    }
    let shape = select(transmitted, reflected, point.eye_on_lit_side);
    return SlabValues(shape * (point.irradiance / (4.0 * PI)), transmittance);
}

// The model at one point: lit-side rule, point-light irradiance, eqs. (4)/(5) per channel and α; with
// `all_orders` plus the table's multiple part, for which `albedo` (Λ per channel) is needed.
fn slab_values(position: vec3<f32>, normal: vec3<f32>, tau: vec3<f32>, albedo: vec3<f32>,
        light: LightTransmission) -> SlabValues {
    let point = slab_point(position, normal);
    var values = single_values(point, tau);
    if all_orders || sky_light {
        let nodes = all_orders_channels(tau);
        let albedos = all_orders_channel_albedos(nodes, albedo);
        if all_orders {
            // The multiply-scattered radiance per unit albedo, L_m/Λ = Λ·μ0·e^{ln f} per unit irradiance.
            let log_value = all_orders_log_face(nodes, albedos, all_orders_cosines(point.mu0, point.mu),
                all_orders_face_rows(point.eye_on_lit_side));
            values.radiance_per_albedo += albedo * (point.mu0 * exp(log_value)) * point.irradiance;
        }
        values.radiance_per_albedo *= light.direct;
        if sky_light || (all_orders && shadows) {
            // One lookup of the diffuse responses serves the sky and the light through a layer in front.
            let view = diffuse_view(normal, frame.eye.xyz - position);
            let response = diffuse_response(nodes, albedos, view.mu);
            if all_orders && shadows {
                values.radiance_per_albedo += diffuse_through_per_albedo(point, light, response);
            }
            if sky_light {
                values.radiance_per_albedo += sky_radiance_with(view, response);
            }
        }
    } else {
        values.radiance_per_albedo *= light.direct;
    }
    return values;
}

// The light a layer in front scatters through itself, arriving isotropically on this point's lit face with
// radiance μ0·E⊥·D (shadow.wgsl), and this slab's all-orders response to it per unit albedo: R_d/Λ toward
// an eye on the lit side, T_d/Λ toward one on the far side (the diffuse table, as for the sky).
fn diffuse_through_per_albedo(point: SlabPoint, light: LightTransmission, response: DiffuseResponse)
        -> vec3<f32> {
    let toward_eye = select(response.transmitted, response.reflected, point.eye_on_lit_side);
    return toward_eye * light.diffuse * (point.mu0 * point.normal_irradiance);
}

// τ1 per channel at uv; the thickness texture is only sampled when present (fixed per pipeline).
fn optical_thickness_at(uv: vec2<f32>) -> vec3<f32> {
    if has_thickness_texture {
        return frame.optical_thickness.rgb * textureSample(thickness_texture, linear_sampler, uv).r;
    }
    return frame.optical_thickness.rgb;
}

// As `optical_thickness_at`, for the vertex stage (explicit level 0).
fn optical_thickness_at_vertex(uv: vec2<f32>) -> vec3<f32> {
    if has_thickness_texture {
        return frame.optical_thickness.rgb * textureSampleLevel(thickness_texture, linear_sampler, uv, 0.0).r;
    }
    return frame.optical_thickness.rgb;
}

fn albedo_at(uv: vec2<f32>) -> vec3<f32> {
    return frame.albedo_scale.rgb * textureSample(albedo_texture, linear_sampler, uv).rgb;
}

// Λ at a vertex, needed there only by the all-orders model and the sky (not linear in Λ).
fn albedo_at_vertex(uv: vec2<f32>) -> vec3<f32> {
    if all_orders || sky_light {
        return frame.albedo_scale.rgb * textureSampleLevel(albedo_texture, linear_sampler, uv, 0.0).rgb;
    }
    return vec3<f32>(1.0);
}

struct VertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

// ---- per fragment -------------------------------------------------------------------------------------

// The shadow map is looked up per vertex on every path (shadow.wgsl) and interpolated: sixteen loads per
// vertex instead of per fragment, at the cost of shadow edges as soft as a triangle.
struct FragmentPathVarying {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) shadow_direct: vec3<f32>,
    @location(4) shadow_diffuse: vec3<f32>,
}

@vertex
fn vs_per_fragment(input: VertexInput) -> FragmentPathVarying {
    let light = light_transmission_at_vertex(input.position, input.normal);
    return FragmentPathVarying(frame.view_projection * vec4<f32>(input.position, 1.0), input.position,
        input.normal, input.uv, light.direct, light.diffuse);
}

@fragment
fn fs_per_fragment(input: FragmentPathVarying) -> SlabOutput {
    let tau = optical_thickness_at(input.uv);
    let albedo = albedo_at(input.uv);
    let values = slab_values(input.world_position, input.normal, tau, albedo,
        LightTransmission(input.shadow_direct, input.shadow_diffuse));
    return slab_output(albedo * values.radiance_per_albedo, values.transmittance);
}

// ---- per fragment, the multiple part per vertex -------------------------------------------------------
// The all-orders model with eqs. (4)–(5), α and the irradiance per fragment, as `fs_per_fragment`, but the
// table's reduced value f = L_m/(Λ²·μ0·E), for both faces, computed once per vertex by
// `cs_multiple_at_vertex` (multiple_at_vertex.wgsl) and interpolated: the fragment picks the face its own
// lit-side rule gives and multiplies by its own Λ², μ0 and irradiance. Multiple scattering varies slowly with
// μ0 and μ, so this costs little accuracy (measured in tests/gpu_vs_cpu.rs) and keeps the table's loads
// out of the fragment shader.

struct MultipleAtVertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    // f = L_m/(Λ²·μ0·E) (sr⁻¹) with the eye on the lit side (reflected) and on the far side (transmitted).
    @location(3) multiple_lit: vec3<f32>,
    @location(4) multiple_far: vec3<f32>,
}

struct MultipleAtVertexVarying {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) multiple_lit: vec3<f32>,
    @location(4) multiple_far: vec3<f32>,
    @location(5) shadow_direct: vec3<f32>,
    @location(6) shadow_diffuse: vec3<f32>,
}

@vertex
fn vs_multiple_at_vertex(input: MultipleAtVertexInput) -> MultipleAtVertexVarying {
    let light = light_transmission_at_vertex(input.position, input.normal);
    return MultipleAtVertexVarying(frame.view_projection * vec4<f32>(input.position, 1.0),
        input.position, input.normal, input.uv, input.multiple_lit, input.multiple_far, light.direct,
        light.diffuse);
}

@fragment
fn fs_multiple_at_vertex(input: MultipleAtVertexVarying) -> SlabOutput {
    let tau = optical_thickness_at(input.uv);
    let albedo = albedo_at(input.uv);
    let point = slab_point(input.world_position, input.normal);
    var values = single_values(point, tau);
    // L_m/Λ = Λ·μ0·f with the fragment's own Λ and μ0: only f, which varies more slowly, is interpolated.
    let reduced = select(input.multiple_far, input.multiple_lit, point.eye_on_lit_side);
    values.radiance_per_albedo += albedo * (point.mu0 * point.irradiance) * reduced;
    let light = LightTransmission(input.shadow_direct, input.shadow_diffuse);
    values.radiance_per_albedo *= light.direct;
    if sky_light || shadows {
        let nodes = all_orders_channels(tau);
        let albedos = all_orders_channel_albedos(nodes, albedo);
        let view = diffuse_view(input.normal, frame.eye.xyz - input.world_position);
        let response = diffuse_response(nodes, albedos, view.mu);
        if shadows {
            values.radiance_per_albedo += diffuse_through_per_albedo(point, light, response);
        }
        if sky_light {
            values.radiance_per_albedo += sky_radiance_with(view, response);
        }
    }
    return slab_output(albedo * values.radiance_per_albedo, values.transmittance);
}

// ---- per vertex (vertex shader) and on the CPU (per vertex, uploaded) ---------------------------------

struct InterpolatedVarying {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) radiance_per_albedo: vec3<f32>,
    @location(1) transmittance: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

@vertex
fn vs_per_vertex(input: VertexInput) -> InterpolatedVarying {
    let tau = optical_thickness_at_vertex(input.uv);
    let values = slab_values(input.position, input.normal, tau, albedo_at_vertex(input.uv),
        light_transmission_at_vertex(input.position, input.normal));
    return InterpolatedVarying(frame.view_projection * vec4<f32>(input.position, 1.0),
        values.radiance_per_albedo, values.transmittance, input.uv);
}

struct CpuVertexInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) radiance_per_albedo: vec3<f32>,
    @location(4) transmittance: vec3<f32>,
}

@vertex
fn vs_cpu(input: CpuVertexInput) -> InterpolatedVarying {
    return InterpolatedVarying(frame.view_projection * vec4<f32>(input.position, 1.0),
        input.radiance_per_albedo, input.transmittance, input.uv);
}

// Λ enters eqs. (4)–(5) linearly, so the albedo texture is applied per fragment in both per-vertex paths
// (all orders: the multiple part per unit albedo was evaluated with the vertex's Λ).
@fragment
fn fs_interpolated(input: InterpolatedVarying) -> SlabOutput {
    return slab_output(albedo_at(input.uv) * input.radiance_per_albedo, input.transmittance);
}

// ---- baseline: diffuse BRDF ρ/π and constant α; the back-lit side is black ----------------------------

@fragment
fn fs_baseline(input: FragmentPathVarying) -> SlabOutput {
    let to_light = frame.light.xyz - input.world_position;
    let side = lit_side_cosines(input.normal, to_light, frame.eye.xyz - input.world_position);
    var radiance = vec3<f32>(0.0);
    if side.eye_on_lit_side {
        // Lambertian: L = (ρ/π)·E_surface, E_surface = Φμ0/(4πr²) (eq. 6).
        let irradiance = frame.light.w * side.mu0 / (4.0 * PI * dot(to_light, to_light));
        radiance = albedo_at(input.uv) * (irradiance / PI);
    }
    return slab_output(radiance, vec3<f32>(frame.baseline.x));
}

// ---- background: a full-screen triangle, uniform colour or an image of the target's size -------------

@vertex
fn vs_background(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let x = f32(i32(index & 1u) * 4 - 1);
    let y = f32(i32(index >> 1u) * 4 - 1);
    return vec4<f32>(x, y, 0.0, 1.0);
}

@fragment
fn fs_background(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    if frame.background.w > 0.5 {
        // Alpha 1: the target's alpha channel accumulates the product of α over the layers drawn on top.
        return vec4<f32>(textureLoad(background_texture, vec2<i32>(pixel.xy), 0).rgb * frame.output.z, 1.0);
    }
    return vec4<f32>(frame.background.rgb * frame.output.z, 1.0);
}

// ---- opaque surfaces (a flag pole): Lambertian, lit by the point light and the sky --------------------
// Drawn after the background and before the cloth; with a depth attachment they write depth, so cloth behind
// them is hidden and cloth in front blends over them by eq. (9). Alpha 0: nothing behind them is seen.

struct OpaqueInput {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
}

struct OpaqueVarying {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
}

@vertex
fn vs_opaque(input: OpaqueInput) -> OpaqueVarying {
    return OpaqueVarying(frame.view_projection * vec4<f32>(input.position, 1.0), input.position,
        input.normal, input.albedo);
}

@fragment
fn fs_opaque(input: OpaqueVarying) -> @location(0) vec4<f32> {
    let n = normalize(input.normal);
    let to_light = frame.light.xyz - input.world_position;
    let r2 = dot(to_light, to_light);
    // E = Φ/(4πr²)·max(n·ω, 0) (W/m²), Lambertian L = ρE/π; the sky adds ρ·E_sky(n)/π (zero without sky).
    let irradiance = frame.light.w / (4.0 * PI * r2) * max(dot(n, to_light * inverseSqrt(r2)), 0.0);
    let radiance = input.albedo * (irradiance / PI + sky_radiance_on_face(n));
    return vec4<f32>(radiance * frame.output.z, 0.0);
}

// ---- the light marker: a disc of constant radiance with a black rim, at the light's depth ---------------

struct MarkerVarying {
    @builtin(position) clip_position: vec4<f32>,
    // Offset from the disc's centre, pixels.
    @location(0) offset: vec2<f32>,
}

// A quad (triangle strip, 4 vertices) around the light, sized in pixels: radius plus a 2-pixel rim.
@vertex
fn vs_marker(@builtin(vertex_index) index: u32) -> MarkerVarying {
    let corner = vec2<f32>(f32(index & 1u) * 2.0 - 1.0, f32(index >> 1u) * 2.0 - 1.0);
    let centre = frame.view_projection * vec4<f32>(frame.light.xyz, 1.0);
    let offset = corner * (frame.output.w + 2.0);
    // Normalised device coordinates span 2 over the target's pixels.
    let clip = centre + vec4<f32>(offset * 2.0 / frame.output.xy * centre.w, 0.0, 0.0);
    return MarkerVarying(clip, offset);
}

@fragment
fn fs_marker(input: MarkerVarying) -> @location(0) vec4<f32> {
    let d = length(input.offset);
    if d > frame.output.w + 1.5 {
        discard;
    }
    let radiance = select(vec3<f32>(0.0), frame.marker.rgb, d <= frame.output.w);
    return vec4<f32>(radiance * frame.output.z, 0.0);
}
