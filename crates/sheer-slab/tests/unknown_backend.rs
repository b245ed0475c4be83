//! A `WGPU_BACKEND` that names no backend is refused with the name, before any adapter is searched
//! (own test binary: it sets `WGPU_BACKEND` for the whole process).

use sheer_slab::render::{HeadlessRenderer, RenderError};

#[test]
fn a_backend_name_wgpu_does_not_know_is_a_clear_error() {
    // Each value in turn; this binary has a single test, so no other thread reads the environment.
    for (value, name) in [
        ("garbage", "garbage"),
        ("vulkan, vulcan", "vulcan"),
        ("", ""),
    ] {
        // SAFETY: see above.
        unsafe { std::env::set_var("WGPU_BACKEND", value) };
        match HeadlessRenderer::new(64, 64) {
            Err(RenderError::UnknownBackend {
                value: reported,
                name: unknown,
            }) => {
                assert_eq!((reported.as_str(), unknown.as_str()), (value, name));
            }
            Err(other) => panic!("{value:?}: expected UnknownBackend, got {other}"),
            Ok(renderer) => panic!(
                "{value:?}: expected UnknownBackend, got {}",
                renderer.adapter_description()
            ),
        }
    }
    let message = RenderError::UnknownBackend {
        value: "vulkan,vulcan".into(),
        name: "vulcan".into(),
    }
    .to_string();
    assert!(
        message.starts_with("WGPU_BACKEND = \"vulkan,vulcan\": \"vulcan\""),
        "{message}"
    );
}
