//! Workspace-level: bad input given to the `sheer` binary is refused at once, on one line, with a
//! failing status — scene files (out-of-range values, images that cannot be read) and arguments
//! (times, frame counts, options that do not go together). Nothing here may hang or abort: every
//! run is given a deadline.

mod scratch;
use scratch::Scratch;

use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs `sheer` with `args`; kills it and fails the test if it has not exited within `seconds`.
fn sheer_within(args: &[&str], seconds: u64) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_sheer"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the sheer binary runs");
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(seconds) {
            child.kill().ok();
            panic!("sheer {args:?} still ran after {seconds} s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// Asserts a one-line error (`error: …`) with status `code` that contains every needle.
fn assert_one_line_error(args: &[&str], code: i32, needles: &[&str]) {
    let out = sheer_within(args, 60);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(code), "{args:?}: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
    assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
    for needle in needles {
        assert!(
            stderr.contains(needle),
            "{args:?}: `{stderr}` lacks `{needle}`"
        );
    }
}

#[test]
fn times_out_of_range_are_refused_before_any_simulation() {
    let scratch = Scratch::new("bad-times");
    let out = scratch.join("frame.png");
    let out = out.to_str().unwrap();
    // 1e9 s at 60 Hz was a loop of 4·10⁹ steps; −5 and NaN silently rendered t = 0.
    for time in ["1e9", "3601", "-1", "-5", "NaN", "inf", "1e300"] {
        assert_one_line_error(
            &["render", "--out", out, "--time", time],
            1,
            &["--time must lie in [0, 3600] s"],
        );
        assert_one_line_error(
            &["figure2", "--out", out, &format!("--time={time}")],
            1,
            &["--time must lie in [0, 3600] s"],
        );
    }
    // Past f32's range: echoed as given, not as `inf`.
    assert_one_line_error(
        &["render", "--out", out, "--time", "1e300"],
        1,
        &["--time must lie in [0, 3600] s, got 1e300"],
    );
}

#[test]
fn benchmark_sizes_beyond_the_scene_limits_are_refused_before_any_work() {
    // Each of these panicked (capacity overflow, a float too large for a `Duration`), aborted on a
    // failed allocation, or ran for hours.
    let sim = |extra: &[&'static str]| {
        let mut args = vec!["bench", "sim", "--method", "pbd", "--threads", "1"];
        args.extend_from_slice(extra);
        args
    };
    for grid in [
        "99999999999x99999999999",
        "100000x100000",
        "4294967296x2",
        "1025x2",
        "2x1025",
    ] {
        assert_one_line_error(
            &sim(&["--grid", grid]),
            1,
            &["--grid", "must lie in [2, 1024]"],
        );
    }
    // The value is echoed in its shortest form (not 309 digits for 1e308).
    for (seconds, echoed) in [
        ("1e20", "got 1e20"),
        ("1e308", "got 1e308"),
        ("3601", "got 3601.0"),
    ] {
        assert_one_line_error(
            &sim(&["--grid", "16x11", "--seconds", seconds]),
            1,
            &["--seconds must lie in [0, 3600]", echoed],
        );
        assert_one_line_error(
            &["bench", "render", "--seconds", seconds],
            1,
            &["--seconds must lie in [0, 3600]", echoed],
        );
    }
    for substeps in ["4294967295", "100001"] {
        assert_one_line_error(
            &sim(&["--grid", "16x11", "--substeps", substeps]),
            1,
            &["--substeps must lie in [1, 100000]"],
        );
    }
    assert_one_line_error(
        &sim(&["--grid", "16x11", "--iterations", "10001"]),
        1,
        &["--iterations must lie in [1, 10000]"],
    );
    // Silently unused before: small-steps XPBD and the explicit integrators have no iterations.
    assert_one_line_error(
        &[
            "bench",
            "sim",
            "--method",
            "small_steps_xpbd,verlet",
            "--grid",
            "16x11",
            "--iterations",
            "5",
        ],
        1,
        &["--iterations: none of the methods measured (small_steps_xpbd, verlet)"],
    );
}

#[test]
fn options_that_do_not_go_together_are_one_line_usage_errors() {
    let scratch = Scratch::new("bad-usage");
    let out = scratch.join("frame.png");
    let out = out.to_str().unwrap();
    // --frames and --format describe a sequence; with --out they were silently ignored.
    assert_one_line_error(
        &["render", "--out", out, "--frames", "3"],
        2,
        &["--frames", "--out"],
    );
    assert_one_line_error(
        &["render", "--out", out, "--format", "exr"],
        2,
        &["--format", "--out"],
    );
    // The window with --frames 0 never reached its screenshot and never exited.
    assert_one_line_error(
        &["--frames", "0", "--screenshot", out],
        2,
        &["--frames", "0"],
    );
    assert_one_line_error(&["--frames", "-3"], 2, &["--frames", "-3"]);
    assert_one_line_error(&["render", "--bogus"], 2, &["--bogus"]);
    assert_one_line_error(&["render", "--time"], 2, &["--time"]);
    assert_one_line_error(&["simulate", "--frames", "-1"], 2, &["--frames", "-1"]);
    assert_one_line_error(&["bench", "sim", "--threads", "-2"], 2, &["--threads"]);
    assert_one_line_error(
        &["bench", "sim", "--wind-renewal-interval", "-0.001"],
        1,
        &["--wind-renewal-interval", "-0.001"],
    );
    assert_one_line_error(
        &["bench", "sim", "--wind-renewal-interval", "NaN"],
        1,
        &["--wind-renewal-interval", "NaN"],
    );
    for thickness in ["-0.001", "0", "NaN"] {
        assert_one_line_error(
            &[
                "bench",
                "sim",
                "--contacts",
                "self",
                "--thickness",
                thickness,
            ],
            1,
            &["--thickness", thickness],
        );
    }
    assert_one_line_error(
        &["bench", "sim", "--thickness", "0.001"],
        1,
        &["--thickness", "--contacts"],
    );
    assert_one_line_error(
        &["bench", "sim", "--spring-damping", "maybe"],
        2,
        &["--spring-damping", "maybe"],
    );
    // Missing required arguments are listed on the same line.
    assert_one_line_error(&["figure2"], 2, &["--out"]);
    // Refused before rendering (an .exr name failed after four renders, in the image crate's words).
    for name in ["fig.exr", "fig"] {
        assert_one_line_error(&["figure2", "--out", name], 1, &["must end in .png"]);
    }
}

#[test]
fn bad_scene_values_are_refused_at_once_naming_the_key() {
    let dir = Scratch::new("bad-scenes");
    let scene = dir.join("scene.toml");
    let out = dir.join("frame.png");
    for (text, key) in [
        // Aborted with an allocation failure (status 134) building the cloth.
        ("[flag]\ncolumns = 100000\nrows = 100000\n", "flag.columns"),
        // Hung for minutes building it.
        ("[flag]\ncolumns = 5000\nrows = 5000\n", "flag.columns"),
        // Stepped 1/1e30 s at a time towards the frame's time: billions of steps.
        ("[render]\nfps = 1e30\n", "render.fps"),
        // Wrote infinite pixels into the EXR.
        ("[light]\nflux = 3e38\n", "light.flux"),
        // Looked straight down: nothing drawn, no error.
        (
            "[camera]\nposition = [0.5, 4.0, 0.0]\ntarget = [0.5, 0.0, 0.0]\n",
            "camera.target",
        ),
        // Named only `stretch`.
        (
            "[simulation.stretch]\ndamping = -1.0\n",
            "simulation.stretch.damping",
        ),
        // The fourth component was dropped without a word.
        (
            "[simulation.wind]\nvelocity = [1.0, 0.0, 2.0, 5.0]\n",
            "simulation.wind.velocity",
        ),
    ] {
        std::fs::write(&scene, text).unwrap();
        for command in ["render", "simulate"] {
            let mut args = vec![command, "--scene", scene.to_str().unwrap()];
            args.extend(match command {
                "render" => ["--out", out.to_str().unwrap()],
                _ => ["--out-dir", dir.to_str().unwrap()],
            });
            assert_one_line_error(&args, 1, &[key]);
        }
    }
}

#[test]
fn images_that_cannot_be_read_are_errors_naming_their_key() {
    let dir = Scratch::new("bad-images");
    std::fs::write(
        dir.join("corrupt.png"),
        b"\x89PNG\r\n\x1a\n but no image follows",
    )
    .unwrap();
    let scene = dir.join("scene.toml");
    let out = dir.join("frame.png");
    for (section, key) in [
        ("[shading]\nalbedo_texture", "shading.albedo_texture"),
        (
            "[shading]\nalbedo_texture = \"\"\nthickness_texture",
            "shading.thickness_texture",
        ),
        (
            "[shading]\nalbedo_texture = \"\"\n[background]\nimage",
            "background.image",
        ),
    ] {
        for (image, why) in [
            ("missing.png", "cannot read"),
            ("corrupt.png", "cannot decode"),
        ] {
            std::fs::write(&scene, format!("{section} = \"{image}\"\n")).unwrap();
            assert_one_line_error(
                &[
                    "render",
                    "--scene",
                    scene.to_str().unwrap(),
                    "--out",
                    out.to_str().unwrap(),
                ],
                1,
                &[key, image, why],
            );
        }
    }
}

#[test]
fn a_backend_name_that_is_no_backend_is_one_line() {
    // wgpu skipped the name and searched nothing: "no graphics adapter found for backends
    // Backends(0x0)".
    let scratch = Scratch::new("bad-backend");
    let out = scratch.join("frame.png");
    let run = Command::new(env!("CARGO_BIN_EXE_sheer"))
        .args(["render", "--out", out.to_str().unwrap()])
        .env("WGPU_BACKEND", "garbage")
        .output()
        .expect("the sheer binary runs");
    let stderr = String::from_utf8(run.stderr).unwrap();
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("error: renderer: WGPU_BACKEND = \"garbage\": \"garbage\" is no"),
        "{stderr}"
    );
}

#[test]
fn a_black_pixel_in_the_thickness_texture_is_named_by_file_and_place() {
    // It multiplies τ1: black would be a hole of zero thickness. The message said only "texel 6".
    let dir = Scratch::new("bad-black-thickness");
    let mut weave = image::RgbImage::from_pixel(4, 3, image::Rgb([255, 255, 255]));
    weave.put_pixel(2, 1, image::Rgb([0, 0, 0]));
    weave.save(dir.join("weave.png")).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "[shading]\nalbedo_texture = \"\"\nthickness_texture = \"weave.png\"\n[background]\nimage = \"\"\n",
    )
    .unwrap();
    let out = dir.join("frame.png");
    assert_one_line_error(
        &[
            "render",
            "--scene",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        1,
        &[
            "shading.thickness_texture",
            "weave.png",
            "column 2, row 1",
            "red 0.0",
        ],
    );
}

#[test]
fn a_study_into_a_folder_it_cannot_write_is_refused_before_it_runs() {
    // This ran the whole sweep and then failed on its first file.
    for out in ["/proc/sheer-study", "/proc"] {
        assert_one_line_error(
            &[
                "study",
                "choose",
                "--quick",
                "--max-coverage-difference",
                "10",
                "--out",
                out,
            ],
            1,
            &["cannot read or write", out],
        );
    }
}

#[test]
fn an_output_that_cannot_be_written_is_refused_before_the_scene_is_simulated() {
    // An hour of simulated flag takes far longer than the deadline: each of these ran it all before
    // failing (`.jpg` is no type `render` writes), or said "File exists" of a file given as a folder.
    let dir = Scratch::new("bad-outputs");
    let file = dir.join("a-file");
    std::fs::write(&file, "not a folder").unwrap();
    let file = file.to_str().unwrap();
    let figure = dir.join("figure.png");
    let figure = figure.to_str().unwrap();
    assert_one_line_error(
        &["render", "--time", "3600", "--out", "frame.jpg"],
        1,
        &["frame.jpg", "unknown image type (use .png or .exr)"],
    );
    for args in [
        &["render", "--time", "3600", "--out-dir", file][..],
        &["simulate", "--frames", "216000", "--out-dir", file],
        &["assets", "--out", file],
        &[
            "figure2",
            "--time",
            "3600",
            "--out",
            figure,
            "--linear-dir",
            file,
        ],
    ] {
        assert_one_line_error(args, 1, &[file, "it is a file"]);
    }
    assert_one_line_error(
        &["study", "choose", "--quick", "--out", file],
        1,
        &[file, "it is a file, not a folder"],
    );
    // An image into a folder that is not there, or one that takes no file (`/proc`): refused before
    // the hour is simulated.
    let missing = dir.join("missing").join("frame.png");
    let missing = missing.to_str().unwrap();
    for (args, needle) in [
        (
            &["render", "--time", "3600", "--out", missing][..],
            "there is no folder",
        ),
        (
            &["render", "--time", "3600", "--out", "/proc/frame.png"],
            "/proc",
        ),
        (
            &["figure2", "--time", "3600", "--out", missing],
            "there is no folder",
        ),
        (
            &["render", "--time", "3600", "--out", dir.to_str().unwrap()],
            "unknown image type",
        ),
    ] {
        assert_one_line_error(args, 1, &[needle]);
    }
    // The check leaves an existing file as it was, when the run then fails (a bad scene here).
    let kept = dir.join("kept.png");
    std::fs::write(&kept, "earlier frame").unwrap();
    let scene = dir.join("bad.toml");
    std::fs::write(&scene, "[flag]\ncolumns = 0\n").unwrap();
    assert_one_line_error(
        &[
            "render",
            "--scene",
            scene.to_str().unwrap(),
            "--out",
            kept.to_str().unwrap(),
        ],
        1,
        &["columns"],
    );
    assert_eq!(std::fs::read_to_string(&kept).unwrap(), "earlier frame");
}
