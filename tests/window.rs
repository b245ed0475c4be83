//! Workspace-level: the window under Xvfb. `sheer --frames N --screenshot F` opens the window, runs N
//! frames, saves a screenshot of the whole window and exits; the screenshot must show the panel and the
//! flag.

mod scratch;
use scratch::Scratch;

use std::process::Command;
use std::sync::Mutex;

/// One window at a time: two `xvfb-run -a` started together may pick the same display.
static DISPLAY: Mutex<()> = Mutex::new(());

#[test]
fn the_window_runs_frames_and_saves_a_screenshot_of_panel_and_flag() {
    let _display = DISPLAY.lock().unwrap_or_else(|e| e.into_inner());
    let dir = Scratch::new("window");
    let shot = dir.join("window.png");
    let output = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x800x24"])
        .arg(env!("CARGO_BIN_EXE_sheer"))
        .args(["--frames", "20", "--screenshot"])
        .arg(&shot)
        .output()
        .expect("xvfb-run must be installed (Debian package xvfb; .ci/run installs it)");
    assert!(
        output.status.success(),
        "the window exited with {}",
        output.status
    );
    // One summary line: `window: N frames, median M ms, p95 P ms, F frames/s, adapter A`.
    let stdout = String::from_utf8_lossy(&output.stdout);
    let line = stdout
        .lines()
        .find(|l| l.starts_with("window: "))
        .unwrap_or_else(|| panic!("no summary line in {stdout:?}"));
    let numbers: Vec<f64> = line
        .split([' ', ','])
        .filter_map(|word| word.parse().ok())
        .collect();
    let [frames, median, p95, fps] = numbers[..4] else {
        panic!("summary line {line:?}");
    };
    assert!(frames >= 19.0, "{line}");
    assert!(0.0 < median && median <= p95 && fps > 0.0, "{line}");
    assert!(line.contains(", adapter "), "{line}");
    let image = image::open(&shot)
        .expect("a screenshot was written")
        .to_rgb8();
    let (w, h) = image.dimensions();
    assert!(w >= 800 && h >= 500, "window is {w}×{h}");
    // The side panel, in egui's dark theme (colours measured on a screenshot: `xvfb-run -a -s
    // "-screen 0 1280x800x24" target/release/sheer --frames 30 --screenshot w.png`). Light pixels
    // alone would not do: the painting's paper border is light too, and without the panel the
    // centred frame leaves the same grey as the panel on either side. So the panel is: mostly the
    // panel grey (27) on the left, the near-black (10) of its text fields, the blue (0, 92, 128) of
    // its selected toggles, light text, and its right edge, a full-height line of grey 60.
    let near = |x: u32, y: u32, colour: [u8; 3], tolerance: u8| {
        let p = image.get_pixel(x, y).0;
        (0..3).all(|c| p[c].abs_diff(colour[c]) <= tolerance)
    };
    let left: Vec<(u32, u32)> = (0..200.min(w))
        .flat_map(|x| (0..h).map(move |y| (x, y)))
        .collect();
    let count = |colour: [u8; 3], tolerance: u8| {
        left.iter()
            .filter(|&&(x, y)| near(x, y, colour, tolerance))
            .count()
    };
    let fill = count([27; 3], 3);
    assert!(
        fill > left.len() / 2,
        "the left 200 px are not the panel's grey: {fill} of {}",
        left.len()
    );
    let fields = count([10; 3], 3);
    assert!(
        fields > 1000,
        "no text fields in the panel: {fields} pixels"
    );
    let toggles = count([0, 92, 128], 10);
    assert!(
        toggles > 500,
        "no selected toggles in the panel: {toggles} pixels"
    );
    let panel_text = left
        .iter()
        .filter(|&&(x, y)| image.get_pixel(x, y).0.iter().all(|&c| c > 160))
        .count();
    assert!(panel_text > 500, "no panel text: {panel_text} light pixels");
    let edge = (100..w / 2)
        .find(|&x| (0..h).filter(|&y| near(x, y, [60; 3], 3)).count() > h as usize * 9 / 10);
    assert!(
        edge.is_some(),
        "no panel edge in the left half of the window"
    );
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

#[test]
fn a_screenshot_that_cannot_be_written_fails_the_scripted_run() {
    let _display = DISPLAY.lock().unwrap_or_else(|e| e.into_inner());
    let run = |shot: &str| {
        Command::new("xvfb-run")
            .args(["-a", "-s", "-screen 0 1280x800x24"])
            .arg(env!("CARGO_BIN_EXE_sheer"))
            .args(["--frames", "2", "--screenshot", shot])
            .output()
            .expect("xvfb-run must be installed (Debian package xvfb; .ci/run installs it)")
    };
    // Refused before the window opens: not a PNG name, or no such directory.
    let dir = Scratch::new("window-bad");
    let jpg = dir.join("window.jpg");
    let missing = dir.join("absent").join("window.png");
    for (shot, needle) in [
        (jpg.to_str().unwrap(), "must end in .png"),
        (missing.to_str().unwrap(), "does not exist"),
        // Only found when the window writes it (these exited 0 with nothing said).
        (
            "/proc/sheer-window.png",
            "cannot write /proc/sheer-window.png",
        ),
    ] {
        let out = run(shot);
        let stderr = String::from_utf8_lossy(&out.stderr);
        // sheer's own message is its last line (Xvfb and Mesa may print lines of their own before it).
        let last = stderr.lines().last().unwrap_or("");
        assert_eq!(out.status.code(), Some(1), "{shot}: {stderr}");
        assert!(
            last.starts_with("error: ") && last.contains(needle),
            "{shot}: {stderr}"
        );
    }
    assert!(!jpg.exists(), "a refused screenshot left a file");
}

/// On a screen too small to leave room for the image beside the panel, a scripted screenshot is
/// refused with a message that says so (it saved the panel alone, and exited 0).
#[test]
fn a_window_too_small_for_the_image_says_so() {
    let _display = DISPLAY.lock().unwrap_or_else(|e| e.into_inner());
    let dir = Scratch::new("window-small");
    let shot = dir.join("small.png");
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 200x150x24"])
        .arg(env!("CARGO_BIN_EXE_sheer"))
        .args(["--frames", "3", "--screenshot"])
        .arg(&shot)
        .output()
        .expect("xvfb-run must be installed (Debian package xvfb; .ci/run installs it)");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let last = stderr.lines().last().unwrap_or("");
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        last.starts_with("error: --screenshot: the window leaves ") && last.contains("too small"),
        "{stderr}"
    );
    assert!(!shot.exists(), "a screenshot without the image was saved");
}
