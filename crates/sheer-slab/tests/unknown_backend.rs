//! A `WGPU_BACKEND` that names no backend is refused with the name, before any adapter is searched
//! (own test binary: it sets `WGPU_BACKEND` for the whole process). The list's parsing has unit tests
//! in `render/mod.rs`; this checks that `HeadlessRenderer::new` reads the variable through it.

use sheer_slab::render::{HeadlessRenderer, RenderError};

#[test]
// `set_var` is unsafe since edition 2024: another thread may read the environment meanwhile.
#[allow(unsafe_code)]
fn a_backend_name_wgpu_does_not_know_is_a_clear_error() {
    // SAFETY: this test binary has a single test, so no other thread reads the environment meanwhile.
    unsafe { std::env::set_var("WGPU_BACKEND", "vulkan, vulcan") };
    match HeadlessRenderer::new(64, 64) {
        Err(error @ RenderError::UnknownBackend { .. }) => {
            let message = error.to_string();
            assert!(
                message.starts_with("WGPU_BACKEND = \"vulkan, vulcan\": \"vulcan\" is no graphics"),
                "{message}"
            );
        }
        Err(other) => panic!("expected UnknownBackend, got {other}"),
        Ok(renderer) => panic!(
            "expected UnknownBackend, got {}",
            renderer.adapter_description()
        ),
    }
}
