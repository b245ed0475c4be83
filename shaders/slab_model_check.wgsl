// slab_model_check.wgsl — compute entry points that evaluate `slab_shapes` of thin_slab.wgsl on a list
// of (τ1, μ0, μ) samples, and its all-orders table lookup on (τ1, Λ, μ0, μ) samples, so that the WGSL
// model can be compared with sheer-slab's f64 reference over the whole domain
// (HeadlessRenderer::evaluate_shader_model, evaluate_shader_all_orders). Appended after thin_slab.wgsl;
// group 1 keeps its bindings apart from the renderer's group 0 (which holds the table).

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

@compute @workgroup_size(64)
fn cs_all_orders_check(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= arrayLength(&model_inputs) {
        return;
    }
    let sample = model_inputs[index];
    // τ1 = x, Λ = y, μ0 = z, μ = w: (L_m reflected, L_m transmitted, ln f reflected, ln f transmitted),
    // L_m = Λ² μ0 e^{ln f} per unit irradiance normal to the beam.
    let tau = all_orders_tau(sample.x);
    let reflected = all_orders_log_value(tau, sample.y, all_orders_cosines(sample.z, sample.w), true);
    let transmitted = all_orders_log_value(tau, sample.y, all_orders_cosines(sample.z, sample.w), false);
    let scale = sample.y * sample.y * sample.z;
    model_outputs[index] = vec4<f32>(scale * exp(reflected), scale * exp(transmitted), reflected,
        transmitted);
}
