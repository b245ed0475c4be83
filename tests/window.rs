//! Workspace-level: the window under Xvfb. `sheer --frames N --screenshot F` opens the window, runs N
//! frames, saves a screenshot of the whole window and exits; the screenshot must show the panel and the
//! flag.

use std::process::Command;

#[test]
fn the_window_runs_frames_and_saves_a_screenshot_of_panel_and_flag() {
    let dir = std::env::temp_dir().join(format!("sheer-window-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let shot = dir.join("window.png");
    let status = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x800x24"])
        .arg(env!("CARGO_BIN_EXE_sheer"))
        .args(["--frames", "20", "--screenshot"])
        .arg(&shot)
        .status()
        .expect("xvfb-run must be installed (Debian package xvfb; .ci/run installs it)");
    assert!(status.success(), "the window exited with {status}");
    let image = image::open(&shot)
        .expect("a screenshot was written")
        .to_rgb8();
    let (w, h) = image.dimensions();
    assert!(w >= 800 && h >= 500, "window is {w}×{h}");
    // The side panel: the left 200 px hold text (light pixels) on egui's dark panel.
    let panel_text = (0..200.min(w))
        .flat_map(|x| (0..h).map(move |y| (x, y)))
        .filter(|&(x, y)| image.get_pixel(x, y).0.iter().all(|&c| c > 160))
        .count();
    assert!(panel_text > 500, "no panel text: {panel_text} light pixels");
    // The flag: the Faroe flag's red cross appears right of the panel (nothing else in the scene is
    // red: the painting is sky, sea and green cliffs). It is dim where the flag is back- or side-lit,
    // so "red" means clearly redder than green and blue, not bright.
    let red = image
        .enumerate_pixels()
        .filter(|(x, _, p)| {
            let [r, g, b] = p.0.map(f32::from);
            *x >= 250 && r > 60.0 && r > 1.8 * g && r > 1.5 * b
        })
        .count();
    assert!(red > 300, "no red cross in the window: {red} red pixels");
}
