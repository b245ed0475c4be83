//! Workspace-level tests: the `sheer` binary run as a user runs it.

mod scratch;
use scratch::Scratch;

use std::process::Command;

fn sheer(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_sheer"))
        .args(args)
        .output()
        .expect("the sheer binary runs")
}

/// `sheer` with `args`, after checking that it succeeded: its stdout and its stderr.
fn sheer_ok(args: &[&str]) -> (String, String) {
    let out = sheer(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    (
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

/// `sheer` with `args`, after checking that it failed as the CLI promises: status 1 and one line that
/// starts `error: `. Its stderr.
fn sheer_error(args: &[&str]) -> String {
    let out = sheer(args);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
    assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
    stderr
}

/// `sheer bench sim --csv` on the 16 × 11 flag, one thread, one frame per case, with `options`: its
/// output, after checking that it succeeded.
fn bench_sim_csv(options: &[&str]) -> String {
    let mut args = vec![
        "bench",
        "sim",
        "--csv",
        "--grid",
        "16x11",
        "--threads",
        "1",
        "--seconds",
        "0",
    ];
    args.extend_from_slice(options);
    sheer_ok(&args).0
}

#[test]
fn bench_sim_prints_the_documented_csv() {
    let text = bench_sim_csv(&["--method", "small_steps_xpbd,symplectic_euler"]);
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

/// A grid below the library's parallel threshold ran on one thread at `--threads 2`: the benchmark says
/// so on stderr (the CSV on stdout stays CSV), and follows a given threshold.
#[test]
fn bench_sim_says_when_a_two_thread_row_ran_on_one_thread() {
    let run = |threads: &str| {
        let (stdout, stderr) = sheer_ok(&[
            "bench",
            "sim",
            "--csv",
            "--grid",
            "16x11",
            "--method",
            "pbd",
            "--threads",
            threads,
            "--seconds",
            "0",
        ]);
        assert!(
            stdout.lines().skip(1).all(|l| l.starts_with("pbd,16,11,")),
            "{stdout}"
        );
        stderr
    };
    if std::thread::available_parallelism().map_or(1, |n| n.get()) < 2 {
        return; // two threads are refused on one core
    }
    let two = run("1,2");
    // 16 × 11 lies below the library's threshold, so its two-thread row ran on one thread: said so.
    assert!(
        two.contains(
            "note: 16x11 (176 particles) ran on one thread at --threads 2: below \
             parallel_min_particles, 16384"
        ),
        "{two}"
    );
    assert!(!run("1").contains("note:"));
    // Given a threshold, the note follows it: 176 particles reach 100.
    let (_, stderr) = sheer_ok(&[
        "bench",
        "sim",
        "--grid",
        "16x11",
        "--method",
        "pbd",
        "--threads",
        "1,2",
        "--seconds",
        "0",
        "--parallel-min-particles",
        "100",
    ]);
    assert!(!stderr.contains("note:"), "{stderr}");
}

#[test]
fn bench_sim_reports_a_diverging_method_instead_of_timing_garbage() {
    let text = bench_sim_csv(&["--method", "symplectic_euler", "--substeps", "1"]);
    assert!(
        text.lines().nth(1).unwrap().ends_with("diverged,diverged"),
        "{text}"
    );
}

#[test]
fn bench_sim_times_the_flag_without_spring_damping() {
    let text = bench_sim_csv(&["--method", "small_steps_xpbd", "--spring-damping", "off"]);
    let row = text.lines().nth(1).unwrap();
    assert!(row.starts_with("small_steps_xpbd,16,11,"), "{text}");
    let ms: f64 = row.split(',').nth(6).unwrap().parse().unwrap();
    assert!(ms > 0.0 && ms.is_finite(), "{text}");
}

#[test]
fn bad_arguments_are_one_line_errors_with_a_failing_status() {
    for args in [
        &["bench", "sim", "--method", "rk4"][..],
        &["bench", "sim", "--grid", "64by46"],
        &["bench", "sim", "--grid", "1x46"],
        &["bench", "sim", "--grid", "99999999999999999999x2"],
        &["bench", "sim", "--threads", "0"],
        &["bench", "sim", "--threads", "1,100000"],
        &["bench", "sim", "--substeps", "0"],
    ] {
        sheer_error(args);
    }
}

#[test]
fn simulate_writes_one_obj_per_frame() {
    let dir = Scratch::new("simulate");
    sheer_ok(&[
        "simulate",
        "--frames",
        "3",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
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
    let dir = Scratch::new("badscene");
    let scene = dir.join("bad.toml");
    for (text, needle) in [
        ("[light]\nflux = -3.0\n", "light.flux"),
        ("[flag]\ncolumnz = 3\n", "columnz"),
        ("this is not toml", "line 1"),
        (
            "[simulation.collisions]\nthickness = -0.001",
            "simulation.collisions.thickness",
        ),
        (
            "[simulation.collisions]\ncolliders = [{ kind = \"sphere\", center = [0.0, 0.0, 0.0], radius = 0.1 }, { kind = \"sphere\", center = [0.0, 0.0, 0.0], radius = nan }]",
            "simulation.collisions.colliders[1].radius",
        ),
        (
            "[simulation.collisions]\nself_collision = true\n[simulation.method]\nkind = \"verlet\"\nsubsteps = 200",
            "position-based",
        ),
    ] {
        std::fs::write(&scene, text).unwrap();
        let stderr = sheer_error(&[
            "simulate",
            "--scene",
            scene.to_str().unwrap(),
            "--frames",
            "1",
            "--out-dir",
            dir.to_str().unwrap(),
        ]);
        assert!(stderr.contains(needle), "{text}: {stderr}");
    }
    let stderr = sheer_error(&[
        "simulate",
        "--scene",
        "/nonexistent/scene.toml",
        "--out-dir",
        "/tmp",
    ]);
    assert!(stderr.contains("cannot read scene"), "{stderr}");
}

/// A flag in its failure region (1 024 columns at the default ×40 in the default wind diverges at frame
/// 45: crates/sheer-cloth/README.md, "Known failure regions") ends `sheer simulate` with one line that
/// names the frame and says what keeps the divergence away.
#[test]
fn a_diverging_flag_is_one_line_naming_the_frame_and_the_remedy() {
    let dir = Scratch::new("wide");
    let scene = dir.join("wide.scene.toml");
    std::fs::write(&scene, "[flag]\ncolumns = 1024\n").unwrap();
    let stderr = sheer_error(&[
        "simulate",
        "--scene",
        scene.to_str().unwrap(),
        "--frames",
        "60",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    // Frame 0 is the flag at rest, so step N − 1 would have made frame N. The message names the
    // limit that tripped, its key, the remedies for it, and the frames that are complete. (Without
    // the pole's contacts the library's flag diverges at step 45; the pole moves that by a frame or so.)
    let frame: usize = stderr
        .strip_prefix("error: frame ")
        .and_then(|rest| rest.split(':').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{stderr}"));
    assert!((40..55).contains(&frame), "{stderr}");
    assert!(
        stderr.contains(&format!("simulation: step {} diverged: ", frame - 1))
            && stderr.contains("`simulation.divergence.max_strain` = 10")
            && stderr.contains("More sub-steps (`simulation.method.substeps`, now 40)")
            && stderr.contains(&format!(
                "frame_0000.obj … frame_{:04}.obj ({frame} of 60 frames)",
                frame - 1
            )),
        "{stderr}"
    );
    assert!(!stderr.contains("last good state"), "{stderr}");
}

/// A flag in a 60 m/s wind trips the speed limit: more sub-steps cannot help there (100 to 1000 of them
/// all failed the same way), so the message names `simulation.divergence.max_speed` and the wind, and
/// does not advise sub-steps.
#[test]
fn a_flag_too_fast_for_the_speed_limit_is_told_about_the_speed_limit() {
    let dir = Scratch::new("cli-storm");
    let scene = dir.join("storm.scene.toml");
    std::fs::write(&scene, "[simulation.wind]\nvelocity = [60.0, 0.0, 0.0]\n").unwrap();
    let stderr = sheer_error(&[
        "simulate",
        "--scene",
        scene.to_str().unwrap(),
        "--frames",
        "300",
        "--out-dir",
        dir.join("frames").to_str().unwrap(),
    ]);
    assert!(
        stderr.contains("`simulation.divergence.max_speed` = 200 m/s")
            && stderr.contains("raise `simulation.divergence.max_speed`")
            && stderr.contains("lower the wind")
            && !stderr.contains("sub-steps"),
        "{stderr}"
    );
}

/// The names in `dir`, sorted.
fn names_in(dir: &std::path::Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    names
}

/// The vertex lines of an OBJ frame of the default flag, after checking that the frame is whole: a
/// header, 64 × 46 vertices and texture coordinates, 2 × 63 × 45 faces, a final newline.
fn whole_obj_vertices(path: &std::path::Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(
        text.starts_with("# sheer frame ") && text.ends_with('\n'),
        "{path:?}"
    );
    let count = |prefix: &str| text.lines().filter(|l| l.starts_with(prefix)).count();
    assert_eq!(
        (count("v "), count("vt "), count("f ")),
        (64 * 46, 64 * 46, 2 * 63 * 45),
        "{path:?} is not a whole frame"
    );
    text.lines()
        .filter(|l| l.starts_with("v "))
        .map(str::to_string)
        .collect()
}

/// Starts a long `sheer simulate` into `dir` and waits until it has written at least three frames.
fn long_simulation(dir: &std::path::Path) -> std::process::Child {
    let child = Command::new(env!("CARGO_BIN_EXE_sheer"))
        .args(["simulate", "--frames", "1000000", "--out-dir"])
        .arg(dir)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the sheer binary runs");
    let start = std::time::Instant::now();
    while names_in(dir)
        .iter()
        .filter(|n| n.starts_with("frame_"))
        .count()
        < 3
    {
        assert!(start.elapsed().as_secs() < 120, "no frames after 2 minutes");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child
}

/// Ctrl-C during `sheer simulate` ends it after the frame being written: every file under a frame's
/// name is whole, no partial file is left, and the one-line error says how far it got. Killed outright
/// (SIGKILL, no chance to finish), a run still leaves only whole files under frame names.
#[test]
fn an_interrupted_sequence_leaves_only_whole_frames_and_says_how_far_it_got() {
    for trial in 0..3 {
        let dir = Scratch::new(&format!("cli-interrupt-{trial}"));
        let child = long_simulation(&dir);
        let status = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        let names = names_in(&dir);
        let last = names.last().unwrap();
        assert!(
            stderr.starts_with("error: interrupted: frame_000000.obj … ")
                && stderr.contains(&format!("{last} ({} of 1000000 frames)", names.len())),
            "{stderr} / {names:?}"
        );
        for (frame, name) in names.iter().enumerate() {
            assert_eq!(name, &format!("frame_{frame:06}.obj"));
            whole_obj_vertices(&dir.join(name));
        }
    }
    let dir = Scratch::new("cli-killed");
    let mut child = long_simulation(&dir);
    child.kill().unwrap();
    child.wait().unwrap();
    for name in names_in(&dir) {
        if name.starts_with("frame_") {
            whole_obj_vertices(&dir.join(&name));
        } else {
            assert!(
                name.starts_with(".frame_") && name.contains(".obj.part-"),
                "{name}"
            );
        }
    }
    // --overwrite clears the killed run's frames and its partial file.
    sheer_ok(&[
        "simulate",
        "--frames",
        "2",
        "--overwrite",
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(names_in(&dir), ["frame_0000.obj", "frame_0001.obj"]);
}

/// A second sequence into a folder of frames is refused, naming --overwrite, and changes nothing;
/// with --overwrite the old frames go first, so no stale frame sits beside the new ones.
#[test]
fn a_sequence_into_a_folder_of_frames_is_refused_unless_overwritten() {
    let dir = Scratch::new("cli-overwrite");
    let out = dir.to_str().unwrap();
    sheer_ok(&["simulate", "--frames", "20", "--out-dir", out]);
    std::fs::write(dir.join("notes.txt"), "mine").unwrap();
    let stderr = sheer_error(&["simulate", "--frames", "5", "--out-dir", out]);
    assert!(
        stderr.contains("already holds 20 frame file(s)") && stderr.contains("--overwrite"),
        "{stderr}"
    );
    assert_eq!(names_in(&dir).len(), 21);
    sheer_ok(&["simulate", "--frames", "5", "--overwrite", "--out-dir", out]);
    let expected: Vec<String> = (0..5)
        .map(|f| format!("frame_{f:04}.obj"))
        .chain(["notes.txt".to_string()])
        .collect();
    assert_eq!(names_in(&dir), expected);
}

/// One clock: frame k of a sequence is the scene after round(T·fps) + k frames of 1/fps, whatever
/// the sequence's start: `--time 0.5` of 3 frames gives the same particles, bit for bit (positions
/// are written in their shortest round-trip form), as frames 30–32 of a run from 0.
#[test]
fn a_sequence_from_a_later_time_continues_the_same_flag_bit_for_bit() {
    let dir = Scratch::new("cli-clock");
    let (from_zero, from_half) = (dir.join("zero"), dir.join("half"));
    sheer_ok(&[
        "simulate",
        "--frames",
        "33",
        "--out-dir",
        from_zero.to_str().unwrap(),
    ]);
    sheer_ok(&[
        "simulate",
        "--frames",
        "3",
        "--time",
        "0.5",
        "--out-dir",
        from_half.to_str().unwrap(),
    ]);
    for k in 0..3 {
        assert_eq!(
            whole_obj_vertices(&from_half.join(format!("frame_{k:04}.obj"))),
            whole_obj_vertices(&from_zero.join(format!("frame_{:04}.obj", 30 + k))),
            "frame {k}"
        );
    }
    // Frame 0 is the flag at rest, the hoist pinned at the top.
    let rest = whole_obj_vertices(&from_zero.join("frame_0000.obj"));
    assert_eq!(rest[0], "v 0.0 0.8 0.0");
}

#[test]
fn study_choose_quick_writes_the_choice_and_its_sweep() {
    // The quick study (12 × 9 flag, coverage over 0.25–0.5 s) end to end through the binary: a few
    // seconds. A generous coverage budget so some setting meets it and the choice file is written.
    let dir = Scratch::new("study");
    // A folder holding a full study's choice (as the committed docs/ does) is refused by --quick, and
    // left as it was; --force overrides.
    std::fs::create_dir_all(&dir).unwrap();
    let full = "quick = false\n";
    std::fs::write(dir.join("choice.toml"), full).unwrap();
    let mut args = vec![
        "study",
        "choose",
        "--quick",
        "--max-coverage-difference",
        "10",
        "--out",
        dir.to_str().unwrap(),
    ];
    let stderr = sheer_error(&args);
    assert!(stderr.contains("--force"), "{stderr}");
    assert_eq!(
        std::fs::read_to_string(dir.join("choice.toml")).unwrap(),
        full
    );
    // A file that is no choice at all is refused for what it is (this said "a full study's choice").
    for (text, reason) in [
        ("quick = [", "is not TOML"),
        ("seed = 3\n", "has no `quick` flag"),
    ] {
        std::fs::write(dir.join("choice.toml"), text).unwrap();
        let stderr = sheer_error(&args);
        assert!(
            stderr.contains("is not a study's choice file") && stderr.contains(reason),
            "{stderr}"
        );
        assert_eq!(
            std::fs::read_to_string(dir.join("choice.toml")).unwrap(),
            text
        );
    }
    args.push("--force");
    sheer_ok(&args);
    let choice = std::fs::read_to_string(dir.join("choice.toml")).unwrap();
    let table: toml::Table = toml::from_str(&choice).unwrap();
    assert_eq!(table["quick"].as_bool(), Some(true));
    assert_eq!(table["budget"]["kind"].as_str(), Some("coverage"));
    assert_eq!(table["budget"]["max"].as_float(), Some(10.0));
    let method = table["choice"]["method"].as_str().unwrap();
    assert!(
        sheer_cloth::Method::NAMES.contains(&method),
        "unknown method {method}"
    );
    assert!(
        table["choice"]["cpu_ms_per_simulated_second"]
            .as_float()
            .unwrap()
            > 0.0
    );
    assert_eq!(
        table["scene"]["simulation"]["method"]["kind"].as_str(),
        Some(method)
    );
    // The sweep behind it: every row of the default flag in the CSV, with its coverage difference.
    let csv = std::fs::read_to_string(dir.join("work-precision.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let coverage = header
        .iter()
        .position(|c| *c == "coverage_difference")
        .unwrap();
    let rows: Vec<&str> = csv
        .lines()
        .filter(|l| l.starts_with("default_flag,"))
        .collect();
    assert!(rows.len() > 10, "{csv}");
    assert!(rows.iter().any(|r| {
        r.split(',')
            .nth(coverage)
            .and_then(|v| v.parse::<f64>().ok())
            .is_some_and(|v| v > 0.0)
    }));
    let md = std::fs::read_to_string(dir.join("work-precision.md")).unwrap();
    assert!(md.contains("## Budget, choice and why"));
}

#[test]
fn study_help_and_bad_budgets() {
    let help = sheer(&["study", "--help"]);
    assert!(help.status.success());
    let text = String::from_utf8(help.stdout).unwrap();
    for command in ["work-precision", "stability", "ablation", "choose", "all"] {
        assert!(text.contains(command), "{text}");
    }
    for args in [
        &["study", "choose", "--quick", "--max-coverage-difference=-1"][..],
        // A negative number as its own word is a value, checked like any other (it was an "unexpected
        // argument", status 2).
        &[
            "study",
            "choose",
            "--quick",
            "--max-coverage-difference",
            "-1",
        ],
        &["study", "choose", "--budget", "rms", "--budget-mm", "-3"],
        &[
            "study",
            "choose",
            "--quick",
            "--max-coverage-difference",
            "NaN",
        ],
        &["study", "choose", "--budget", "rms", "--budget-mm", "0"],
        &["study", "choose", "--budget", "rms", "--at", "0.3"],
        // Never silently replaced: --at under --quick must be a quick sample time; NaN is none.
        &["study", "choose", "--quick", "--budget", "rms", "--at", "1"],
        &[
            "study", "choose", "--quick", "--budget", "rms", "--at", "NaN",
        ],
        // Options the budget kind does not use are errors, not silently ignored.
        &["study", "choose", "--budget-mm", "3"],
        &["study", "choose", "--at", "0.25"],
        &[
            "study",
            "choose",
            "--budget",
            "rms",
            "--max-coverage-difference",
            "0.1",
        ],
    ] {
        sheer_error(args);
    }
}

/// Parses `sheer slab` output: the rows after the header, as numbers.
fn slab_rows(out: &std::process::Output) -> Vec<Vec<f64>> {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("tau1,albedo,mu0,mu,alpha,l_plus,l_minus")
    );
    lines
        .map(|line| line.split(',').map(|v| v.parse().unwrap()).collect())
        .collect()
}

#[test]
fn slab_all_orders_matches_the_solver_within_the_tables_error() {
    let dir = Scratch::new("slab-all");
    let input = dir.join("rows.csv");
    let rows = [
        [2.0, 1.0, 0.5, 0.5],
        [0.5, 0.9, 1.0, 0.3],
        [7.0, 0.97, 0.2, 0.8],
    ];
    let text: String = rows
        .iter()
        .map(|r| format!("{},{},{},{}\n", r[0], r[1], r[2], r[3]))
        .collect();
    std::fs::write(&input, format!("tau1,albedo,mu0,mu\n{text}")).unwrap();
    let path = input.to_str().unwrap();
    let single = slab_rows(&sheer(&["slab", path]));
    let all = slab_rows(&sheer(&["slab", "--model", "all-orders", path]));
    let explicit_single = slab_rows(&sheer(&["slab", "--model", "single", path]));
    assert_eq!(single, explicit_single);
    assert_eq!(all.len(), rows.len());
    for ((row, single), all) in rows.iter().zip(&single).zip(&all) {
        let [tau, albedo, mu0, mu] = *row;
        assert_eq!(&all[..5], &single[..5], "inputs and alpha are the model's");
        // Against the all-orders solver: within the table's stated interpolation error (sheer-transport
        // README: 4.3e-3 reflected, 3.2e-2 transmitted, rounded up as its tests do).
        let solution = sheer_transport::SlabSolver::new(tau, albedo)
            .unwrap()
            .solve(mu0)
            .unwrap();
        let reflected = solution.reflected_radiance(mu).unwrap();
        let transmitted = solution.transmitted_radiance(mu).unwrap();
        assert!(
            ((all[5] - reflected) / reflected).abs() < 5e-3,
            "{row:?}: {} vs {reflected}",
            all[5]
        );
        assert!(
            ((all[6] - transmitted) / transmitted).abs() < 3.5e-2,
            "{row:?}: {} vs {transmitted}",
            all[6]
        );
        // Multiple scattering adds light on both faces, noticeably at these optical thicknesses.
        assert!(
            all[5] > 1.05 * single[5] && all[6] > 1.05 * single[6],
            "{row:?}"
        );
    }
    // The paper-literal convention multiplies the whole diffuse radiance by μ0 (0.5 is exact).
    let literal = slab_rows(&sheer(&[
        "slab",
        "--model",
        "all-orders",
        "--paper-literal",
        path,
    ]));
    assert_eq!(literal[0][5], all[0][5] * 0.5);
    assert_eq!(literal[0][6], all[0][6] * 0.5);
}

#[test]
fn slab_refuses_a_bad_model_a_bad_table_and_rows_outside_the_table() {
    let dir = Scratch::new("slab-bad");
    let input = dir.join("rows.csv");
    std::fs::write(&input, "2,1,0.5,0.5\n").unwrap();
    let path = input.to_str().unwrap();
    let one_line = |out: &std::process::Output, status: i32, needles: &[&str]| {
        assert_eq!(out.status.code(), Some(status), "{needles:?}");
        let stderr = String::from_utf8(out.stderr.clone()).unwrap();
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        for needle in needles {
            assert!(stderr.contains(needle), "{needle}: {stderr}");
        }
    };
    // A usage error (clap's status 2), naming the value and the choices.
    one_line(
        &sheer(&["slab", "--model", "double", path]),
        2,
        &["double", "single", "all-orders"],
    );
    let missing = dir.join("missing.bin");
    one_line(
        &sheer(&[
            "slab",
            "--model",
            "all-orders",
            "--table",
            missing.to_str().unwrap(),
            path,
        ]),
        1,
        &["cannot read the all-orders table", "missing.bin"],
    );
    let corrupt = dir.join("corrupt.bin");
    std::fs::write(&corrupt, b"SHEERAOT but not really").unwrap();
    one_line(
        &sheer(&[
            "slab",
            "--model",
            "all-orders",
            "--table",
            corrupt.to_str().unwrap(),
            path,
        ]),
        1,
        &["not a valid all-orders table"],
    );
    one_line(
        &sheer(&["slab", "--table", corrupt.to_str().unwrap(), path]),
        1,
        &["--table", "all-orders"],
    );
    // τ1 outside the table is a bad row, named by its line, not a silent clamp.
    std::fs::write(&input, "2,1,0.5,0.5\n20,1,0.5,0.5\n").unwrap();
    one_line(
        &sheer(&["slab", "--model", "all-orders", path]),
        1,
        &["row 2", "tau1 = 20", "[0.01, 10]"],
    );
    // Read errors name the input (they said only "I/O error: Is a directory").
    let dir_name = dir.to_str().unwrap();
    one_line(
        &sheer(&["slab", dir_name]),
        1,
        &[&format!("reading {dir_name}")],
    );
    let binary = dir.join("binary.csv");
    std::fs::write(&binary, [0x32, 0x2c, 0xff, 0xfe, 0x0a]).unwrap();
    one_line(
        &sheer(&["slab", binary.to_str().unwrap()]),
        1,
        &["reading", "binary.csv", "UTF-8"],
    );
    // Output numbers in their shortest round-trip form: 1e308 as such, not with 309 digits.
    std::fs::write(&input, "1e308,1,0.5,0.5\n").unwrap();
    let (rows, _) = sheer_ok(&["slab", path]);
    assert!(
        rows.lines()
            .nth(1)
            .unwrap()
            .starts_with("1e308,1.0,0.5,0.5,"),
        "{rows}"
    );
    // A huge τ1 is echoed in its shortest form.
    std::fs::write(&input, "1e308,1,0.5,0.5\n").unwrap();
    one_line(
        &sheer(&["slab", "--model", "all-orders", path]),
        1,
        &["tau1 = 1e308"],
    );
}

#[test]
fn the_wrap_scene_wraps_the_flag_round_the_pole_without_passing_through() {
    use sheer_cloth::glam::DVec3;
    let dir = Scratch::new("cli-wrap");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/wrap.scene.toml");
    let frames = 240;
    sheer_ok(&[
        "simulate",
        "--scene",
        scene,
        "--frames",
        &frames.to_string(),
        "--out-dir",
        dir.to_str().unwrap(),
    ]);
    // The default pole: 15 mm in radius, its axis 17 mm behind the hoist (x = 0, z = 0) so that the
    // pinned hoist lies at the contact distance; free particles keep half the 4 mm thickness from its
    // surface (OBJ coordinates are written in full: no rounding allowance).
    let (radius, gap) = (0.015, 0.002);
    let axis_x = -(radius + gap);
    let mut touching_frames = 0;
    for frame in 0..frames {
        let text = std::fs::read_to_string(dir.join(format!("frame_{frame:04}.obj"))).unwrap();
        let positions: Vec<DVec3> = text
            .lines()
            .filter_map(|l| l.strip_prefix("v "))
            .map(|l| {
                let c: Vec<f64> = l.split(' ').map(|c| c.parse().unwrap()).collect();
                DVec3::new(c[0], c[1], c[2])
            })
            .collect();
        let triangles: Vec<[u32; 3]> = text
            .lines()
            .filter_map(|l| l.strip_prefix("f "))
            .map(|l| {
                let v: Vec<u32> = l
                    .split(' ')
                    .map(|c| c.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                [v[0], v[1], v[2]]
            })
            .collect();
        let pairs = sheer_cloth::intersecting_triangle_pairs(&positions, &triangles);
        assert_eq!(pairs, 0, "frame {frame}: the flag passes through itself");
        // Column 0 is pinned at the contact distance; every other particle keeps the gap.
        let from_axis: Vec<f64> = positions
            .iter()
            .enumerate()
            .filter(|(i, _)| i % 64 != 0)
            .map(|(_, x)| (x.x - axis_x).hypot(x.z))
            .collect();
        let nearest = from_axis.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(
            nearest >= (radius + gap) * (1.0 - 1e-12),
            "frame {frame}: {nearest} m"
        );
        touching_frames += usize::from(nearest < radius + gap + 0.001);
    }
    // The flag does wrap: it lies against the pole in most frames.
    assert!(touching_frames > frames / 2, "{touching_frames} frames");
}
