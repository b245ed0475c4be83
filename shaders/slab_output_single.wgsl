// slab_output_single.wgsl — fragment output of sheer-slab's thin-slab pipelines when τ1 is the same in all
// channels: one colour attachment, blended by fixed function as eq. (9) of Frisvad et al. (2005),
// L_dst·α_src + L_src (colour: source factor One, destination factor SrcAlpha; alpha: Zero, SrcAlpha, so
// the target's alpha keeps the product of α over the layers). Prepended before thin_slab.wgsl.

struct SlabOutput {
    @location(0) color: vec4<f32>,
}

// radiance: L_source (W/(m²·sr)); transmittance: α_source (grey, so its red channel is used).
fn slab_output(radiance: vec3<f32>, transmittance: vec3<f32>) -> SlabOutput {
    return SlabOutput(vec4<f32>(radiance * frame.output.z, transmittance.r));
}

