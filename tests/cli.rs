//! Workspace-level tests: the `sheer` binary run as a user runs it.

use std::process::Command;

fn sheer(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_sheer"))
        .args(args)
        .output()
        .expect("the sheer binary runs")
}

#[test]
fn bench_sim_prints_the_documented_csv() {
    let out = sheer(&[
        "bench",
        "sim",
        "--csv",
        "--method",
        "small_steps_xpbd,symplectic_euler",
        "--grid",
        "16x11",
        "--threads",
        "1",
        "--seconds",
        "0",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some(
            "method,width,height,substeps,iterations,threads,ms_per_frame,particle_substeps_per_s"
        )
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2);
    assert_eq!(
        rows[0][..6],
        ["small_steps_xpbd", "16", "11", "20", "1", "1"]
    );
    assert_eq!(
        rows[1][..6],
        ["symplectic_euler", "16", "11", "200", "1", "1"]
    );
    for row in &rows {
        let ms: f64 = row[6].parse().expect("a measured time");
        let rate: f64 = row[7].parse().expect("a measured rate");
        assert!(ms > 0.0 && rate > 0.0);
        // The two columns are consistent: particles × sub-steps / seconds per frame.
        let substeps: f64 = row[3].parse().unwrap();
        assert!((rate * ms * 1e-3 / (16.0 * 11.0 * substeps) - 1.0).abs() < 1e-3);
    }
}

#[test]
fn bench_sim_reports_a_diverging_method_instead_of_timing_garbage() {
    let out = sheer(&[
        "bench",
        "sim",
        "--csv",
        "--method",
        "symplectic_euler",
        "--substeps",
        "1",
        "--grid",
        "16x11",
        "--threads",
        "1",
        "--seconds",
        "0",
    ]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.lines().nth(1).unwrap().ends_with("diverged,diverged"),
        "{text}"
    );
}

#[test]
fn bad_arguments_are_one_line_errors_with_a_failing_status() {
    for args in [
        &["bench", "sim", "--method", "rk4"][..],
        &["bench", "sim", "--grid", "64by46"],
        &["bench", "sim", "--grid", "1x46"],
        &["bench", "sim", "--threads", "0"],
        &["bench", "sim", "--substeps", "0"],
    ] {
        let out = sheer(args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
    }
}

#[test]
fn simulate_writes_one_obj_per_frame() {
    let dir = std::env::temp_dir().join(format!("sheer-simulate-{}", std::process::id()));
    let out = sheer(&[
        "simulate",
        "--frames",
        "3",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for frame in 0..3 {
        let text = std::fs::read_to_string(dir.join(format!("frame_{frame:04}.obj"))).unwrap();
        // The default flag: 64 × 46 particles, 2 × 63 × 45 triangles, every vertex finite.
        let vertices: Vec<[f64; 3]> = text
            .lines()
            .filter_map(|l| l.strip_prefix("v "))
            .map(|l| {
                let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
                [v[0], v[1], v[2]]
            })
            .collect();
        assert_eq!(vertices.len(), 64 * 46);
        assert!(vertices.iter().flatten().all(|x| x.is_finite()));
        assert_eq!(
            text.lines().filter(|l| l.starts_with("vt ")).count(),
            64 * 46
        );
        assert_eq!(
            text.lines().filter(|l| l.starts_with("f ")).count(),
            2 * 63 * 45
        );
        // The hoist stays on the pole: vertex 0 is pinned at the top of the hoist.
        assert_eq!(vertices[0], [0.0, 0.8, 0.0]);
    }
    assert!(!dir.join("frame_0003.obj").exists());
}

#[test]
fn bad_scene_files_are_one_line_errors_naming_the_problem() {
    let dir = std::env::temp_dir().join(format!("sheer-badscene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("bad.toml");
    for (text, needle) in [
        ("[light]\nflux = -3.0\n", "light.flux"),
        ("[flag]\ncolumnz = 3\n", "columnz"),
        ("this is not toml", "line 1"),
    ] {
        std::fs::write(&scene, text).unwrap();
        let out = sheer(&[
            "simulate",
            "--scene",
            scene.to_str().unwrap(),
            "--frames",
            "1",
            "--out-dir",
            dir.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(1), "{text}");
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains(needle), "{text}: {stderr}");
    }
    let out = sheer(&[
        "simulate",
        "--scene",
        "/nonexistent/scene.toml",
        "--out-dir",
        "/tmp",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        String::from_utf8(out.stderr)
            .unwrap()
            .contains("cannot read scene")
    );
}
