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
