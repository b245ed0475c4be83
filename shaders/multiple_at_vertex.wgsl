// multiple_at_vertex.wgsl — one compute pass per frame that looks the all-orders table up once per mesh
// vertex, for both faces, for the per-fragment path's `vs_multiple_at_vertex` / `fs_multiple_at_vertex`
// (thin_slab.wgsl). A vertex shader would repeat the lookup for every triangle corner that misses the
// post-transform cache, and the back-to-front sort breaks most reuse; a compute pass does each vertex
// exactly once. Appended to the render module's source after thin_slab.wgsl (it uses `slab_point`,
// `optical_thickness_at_vertex`, `albedo_at_vertex`, `all_orders_reduced_both_faces`).

// The mesh's vertex buffer as the render pass reads it: 8 floats per vertex (position, normal, uv).
@group(1) @binding(0) var<storage, read> mesh_vertices: array<f32>;
// Per vertex: f = L_m/(Λ²·μ0·E) (sr⁻¹) on the lit face (3 floats), then on the far face (3 floats); bound as
// vertex buffer 1 of the render pass.
@group(1) @binding(1) var<storage, read_write> vertex_multiple: array<f32>;

const MESH_VERTEX_FLOATS: u32 = 8u;
const MULTIPLE_FLOATS: u32 = 6u;

@compute @workgroup_size(64)
fn cs_multiple_at_vertex(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= arrayLength(&vertex_multiple) / MULTIPLE_FLOATS {
        return;
    }
    let base = index * MESH_VERTEX_FLOATS;
    let position = vec3<f32>(mesh_vertices[base], mesh_vertices[base + 1u], mesh_vertices[base + 2u]);
    let normal = vec3<f32>(mesh_vertices[base + 3u], mesh_vertices[base + 4u], mesh_vertices[base + 5u]);
    let uv = vec2<f32>(mesh_vertices[base + 6u], mesh_vertices[base + 7u]);
    let point = slab_point(position, normal);
    let multiple = all_orders_reduced_both_faces(optical_thickness_at_vertex(uv),
        albedo_at_vertex(uv), point.mu0, point.mu);
    let out = index * MULTIPLE_FLOATS;
    vertex_multiple[out] = multiple.lit.r;
    vertex_multiple[out + 1u] = multiple.lit.g;
    vertex_multiple[out + 2u] = multiple.lit.b;
    vertex_multiple[out + 3u] = multiple.far.r;
    vertex_multiple[out + 4u] = multiple.far.g;
    vertex_multiple[out + 5u] = multiple.far.b;
}
