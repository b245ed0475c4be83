//! Without any usable adapter, `HeadlessRenderer::new` returns `RenderError::NoAdapter` with a clear
//! message (own test binary: it sets `WGPU_BACKEND` for the whole process).

use sheer_slab::render::{HeadlessRenderer, RenderError};

#[test]
// `set_var` is unsafe since edition 2024: another thread may read the environment meanwhile.
#[allow(unsafe_code)]
fn no_adapter_is_a_clear_error() {
    // Metal is not compiled into this build, so restricting wgpu to it leaves no adapter at all.
    // SAFETY: this test binary has a single test, so no other thread reads the environment meanwhile.
    unsafe { std::env::set_var("WGPU_BACKEND", "metal") };
    match HeadlessRenderer::new(64, 64) {
        Err(error @ RenderError::NoAdapter { .. }) => {
            let message = error.to_string();
            assert!(message.contains("no graphics adapter found"), "{message}");
            assert!(message.contains("lavapipe"), "{message}");
        }
        Err(other) => panic!("expected NoAdapter, got {other}"),
        Ok(renderer) => panic!("expected NoAdapter, got {}", renderer.adapter_description()),
    }
}
