// slab_model_check.wgsl — a compute entry point that evaluates `slab_shapes` of thin_slab.wgsl on a list
// of (τ1, μ0, μ) samples, so that the WGSL model can be compared with sheer-slab's f64 reference over the
// whole domain (HeadlessRenderer::evaluate_shader_model). Appended after thin_slab.wgsl; group 1 keeps
// its bindings apart from the renderer's group 0.

@group(1) @binding(0) var<storage, read> model_inputs: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> model_outputs: array<vec4<f32>>;

@compute @workgroup_size(64)
fn cs_model_check(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= arrayLength(&model_inputs) {
        return;
    }
    let sample = model_inputs[index];
    // (eq. 4 shape, eq. 5 shape, α) for τ1 = x, μ0 = y, μ = z.
    model_outputs[index] = vec4<f32>(slab_shapes(sample.x, sample.y, sample.z), 0.0);
}
