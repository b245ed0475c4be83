enable dual_source_blending;

// slab_output_dual.wgsl — fragment output of sheer-slab's thin-slab pipelines when τ1 differs between
// channels: dual-source blending gives eq. (9) of Frisvad et al. (2005) per channel,
// L_dst·α_src + L_src with α_src = e^{−τ1/μ} per channel (colour: source factor One, destination factor
// Src1; alpha: Zero, Src1Alpha, where the second source's alpha is the mean of the three α).
// Prepended before thin_slab.wgsl (the `enable` directive must come first in the module).

struct SlabOutput {
    @location(0) @blend_src(0) color: vec4<f32>,
    @location(0) @blend_src(1) transmittance: vec4<f32>,
}

// radiance: L_source (W/(m²·sr)); transmittance: α_source per channel.
fn slab_output(radiance: vec3<f32>, transmittance: vec3<f32>) -> SlabOutput {
    let mean = (transmittance.r + transmittance.g + transmittance.b) / 3.0;
    return SlabOutput(vec4<f32>(radiance * frame.output.z, 1.0), vec4<f32>(transmittance, mean));
}

