// lit_side.wgsl — the per-fragment lit-side rule of sheer-normals (Frisvad, Christensen & Falster
// 2005, §3–4): the same rule and defined cases as `sheer_normals::lit_side_cosines` in Rust (results
// agree up to f32 rounding).
//
// Prepend this file to a shader's source; it declares only `LitSide`, `lit_side_unit` and
// `lit_side_cosines` (no entry points, no bindings). Vertex normals from sheer-normals point toward
// the light at each vertex; the interpolated normal is turned toward the light again here, because
// interpolation can carry it across the terminator. Then, with mu = n . to_eye:
//   mu >= 0: eye on the lit side, front-lit: eq. (7) with L+ of eq. (4);
//   mu <  0: eye on the far side, back-lit: eq. (8) with L- of eq. (5), and mu := -mu.
// Defined cases: a zero interpolated normal gives mu0 = 0, mu = 0, lit side ("grazing");
// a zero to_light gives mu0 = 0; a zero to_eye gives mu = 0. mu0 and mu are >= 0.

struct LitSide {
    // cos(theta0) = n . omega0' with n turned toward the light, >= 0 (eq. 4-6).
    mu0: f32,
    // |n . omega|, the cosine on the eye's side of the slab, >= 0.
    mu: f32,
    // true: evaluate eq. (7) with L+ (eq. 4); false: eq. (8) with L- (eq. 5).
    eye_on_lit_side: bool,
}

// Unit vector along v, or zero for a zero v. Dividing by the largest component first keeps the
// squared length in [1, 3], so tiny or huge inputs neither underflow nor overflow.
fn lit_side_unit(v: vec3<f32>) -> vec3<f32> {
    let largest = max(max(abs(v.x), abs(v.y)), abs(v.z));
    if largest <= 0.0 {
        return vec3<f32>(0.0);
    }
    let scaled = v / largest;
    return scaled / length(scaled);
}

// normal: interpolated vertex normal; to_light: fragment -> light; to_eye: fragment -> eye.
// None needs unit length.
fn lit_side_cosines(normal: vec3<f32>, to_light: vec3<f32>, to_eye: vec3<f32>) -> LitSide {
    let light = lit_side_unit(to_light);
    let eye = lit_side_unit(to_eye);
    var n = lit_side_unit(normal);
    if all(n == vec3<f32>(0.0)) {
        return LitSide(0.0, 0.0, true);
    }
    if dot(n, light) < 0.0 {
        n = -n;
    }
    let signed_mu = dot(n, eye);
    return LitSide(abs(dot(n, light)), abs(signed_mu), signed_mu >= 0.0);
}
