//! `shaders/lit_side.wgsl` parses and validates with naga (the major version wgpu 30 uses), both
//! alone and prepended to a fragment shader that calls it, and declares no entry point or binding.

use naga::valid::{Capabilities, ValidationFlags, Validator};
use sheer_normals::LIT_SIDE_WGSL;

fn validate(source: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|error| panic!("{}", error.emit_to_string(source)));
    Validator::new(ValidationFlags::all(), Capabilities::default())
        .validate(&module)
        .unwrap_or_else(|error| panic!("{error:?}"));
    module
}

#[test]
fn the_snippet_alone_validates_and_has_no_entry_points_or_bindings() {
    let module = validate(LIT_SIDE_WGSL);
    assert!(module.entry_points.is_empty());
    assert!(module.global_variables.is_empty());
    let function = module
        .functions
        .iter()
        .map(|(_, f)| f)
        .find(|f| f.name.as_deref() == Some("lit_side_cosines"))
        .expect("lit_side_cosines is declared");
    assert_eq!(function.arguments.len(), 3);
    assert!(function.result.is_some());
}

#[test]
fn the_snippet_prepended_to_a_fragment_shader_validates() {
    let shader = format!(
        "{LIT_SIDE_WGSL}
struct FragmentInput {{
    @location(0) world_position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}}

@group(0) @binding(0) var<uniform> light_and_eye: array<vec4<f32>, 2>;

@fragment
fn fs_main(input: FragmentInput) -> @location(0) vec4<f32> {{
    let side = lit_side_cosines(
        input.normal,
        light_and_eye[0].xyz - input.world_position,
        light_and_eye[1].xyz - input.world_position,
    );
    let front = select(0.0, 1.0, side.eye_on_lit_side);
    return vec4<f32>(side.mu0, side.mu, front, 1.0);
}}
"
    );
    let module = validate(&shader);
    assert_eq!(module.entry_points.len(), 1);
}
